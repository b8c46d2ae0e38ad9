"""Small bpy helpers for the Blender tests (bulk reads only), and the add-on loader."""

import contextlib
import importlib.util
import sys
from pathlib import Path

import bmesh
import bpy
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
ADDON_NAME = "pointscale_addon"


def load_addon():
    if ADDON_NAME in sys.modules:
        return sys.modules[ADDON_NAME]
    spec = importlib.util.spec_from_file_location(
        ADDON_NAME, ROOT / "addon" / "__init__.py", submodule_search_locations=[str(ROOT / "addon")]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[ADDON_NAME] = module
    spec.loader.exec_module(module)
    return module



def diagonal(points) -> float:
    points = np.asarray(points)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))



def mesh_object(points, faces=(), name="Model"):
    """A new mesh object (vertex-only when no faces), linked, active and selected."""
    points = np.asarray(points, dtype=np.float32)
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(points))
    me.vertices.foreach_set("co", points.reshape(-1))
    if len(faces):
        faces = np.asarray(faces, dtype=np.int32)
        me.loops.add(faces.size)
        me.polygons.add(len(faces))
        me.loops.foreach_set("vertex_index", faces.reshape(-1))
        me.polygons.foreach_set("loop_start", np.arange(0, faces.size, faces.shape[1], dtype=np.int32))
        me.update(calc_edges=True)
    me.update()
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    return obj


def vertices(mesh):
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def key(mesh, name):
    kb = mesh.shape_keys.key_blocks[name]
    co = np.empty(len(kb.points) * 3, np.float32)
    kb.points.foreach_get("co", co)
    return co.reshape(-1, 3)


def set_key(mesh, name, co):
    mesh.shape_keys.key_blocks[name].points.foreach_set("co", np.asarray(co, np.float32).reshape(-1))
    mesh.update()


def evaluated(obj):
    """Positions Blender shows (shape keys with values and masks applied)."""
    bpy.context.view_layer.update()
    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    me = ev.to_mesh()
    try:
        return vertices(me).astype(np.float64)
    finally:
        ev.to_mesh_clear()


def snapshot(obj):
    """Every shape key, attribute and vertex position, for 'nothing was modified' checks."""
    me = obj.data
    out = {"co": vertices(me).copy()}
    if me.shape_keys is not None:
        for kb in me.shape_keys.key_blocks:
            out["key:" + kb.name] = key(me, kb.name).copy()
            out["value:" + kb.name] = kb.value
    for attr in me.attributes:
        if attr.domain == "POINT" and attr.data_type in {"FLOAT", "INT"}:
            buf = np.empty(len(attr.data), np.float32 if attr.data_type == "FLOAT" else np.int32)
            attr.data.foreach_get("value", buf)
            out["attr:" + attr.name] = buf
    out["groups"] = [g.name for g in obj.vertex_groups]
    return out


def same(a, b):
    if a.keys() != b.keys():
        return False
    for k in a:
        x, y = a[k], b[k]
        if isinstance(x, np.ndarray):
            if x.shape != y.shape or not np.array_equal(x, y, equal_nan=True):
                return False
        elif x != y:
            return False
    return True


def assert_refused(obj, operator: str, match: str, **kwargs):
    """bpy.ops.pointscale.<operator> raises a report matching `match` and leaves obj untouched."""
    import pytest

    before = snapshot(obj)
    with pytest.raises(RuntimeError, match=match):
        getattr(bpy.ops.pointscale, operator)(**kwargs)
    assert same(before, snapshot(obj))


def noisy_sphere(n=4000, seed=0):
    import pointscale as ps

    rng = np.random.default_rng(seed)
    p = ps.shapes.bumpy_sphere(n, coarse=0.06, fine=0.01)
    return p * (1.0 + 0.003 * rng.standard_normal(len(p)))[:, None]


def decompose(obj, **settings):
    s = obj.data.multiscale
    for name, value in settings.items():
        setattr(s, name, value)
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}


@contextlib.contextmanager
def edited_bmesh(obj):
    """obj's mesh as a BMesh with the vertex lookup table ready; written back on leaving."""
    me = obj.data
    bm = bmesh.new()
    try:
        bm.from_mesh(me)
        bm.verts.ensure_lookup_table()
        yield bm
        bm.to_mesh(me)
    finally:
        bm.free()
    me.update()


def morph_onto_bumpy_b(a, samples=3000):
    """Create Morph of `a` onto a new bumpy sphere 'B' (3000 base samples): the new object."""
    import pointscale as ps

    b = mesh_object(ps.shapes.bumpy_sphere(2000, coarse=0.1, fine=0.02), name="B")
    bpy.context.view_layer.objects.active = a
    a.data.multiscale.morph_target = b
    a.data.multiscale.morph_samples = samples
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    return bpy.context.active_object


def two_models(scale=1):
    """Objects 'A' (3000 vertices) and 'B' (2200, bumpier), B selected and A active, as
    Create Morph takes them, and their points; scale multiplies both counts."""
    import pointscale as ps

    a = ps.shapes.bumpy_sphere(3000 * scale, coarse=0.05, coarse_frequency=3.0, fine=0.0)
    b = ps.shapes.bumpy_sphere(2200 * scale, coarse=0.08, coarse_frequency=5.0, fine=0.0, seed=1) * np.array([1.0, 1.0, 1.1])
    A = mesh_object(a, name="A")
    B = mesh_object(b, name="B")
    B.select_set(True)
    A.select_set(True)
    bpy.context.view_layer.objects.active = A
    return A, B, a, b
