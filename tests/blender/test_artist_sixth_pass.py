"""A sixth artist's pass (trial, 2026-12-07): a mesh in Edit Mode through its linked duplicate
is refused before anything is written; a mesh split along a seam (coincident vertices, as
imported assets are) reports no folds when its base moves as a whole, and Prevent Folds leaves
it as rebuilt."""

import bmesh
import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _bumpy_ico_sphere(subdivisions=4):
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions)
    obj = bpy.context.active_object
    co = h.vertices(obj.data)
    d = 1 + 0.05 * np.sin(5 * co[:, 0]) * np.sin(5 * co[:, 1]) + 0.01 * np.sin(23 * co[:, 2])
    obj.data.vertices.foreach_set("co", (co * d[:, None]).astype(np.float32).ravel())
    obj.data.update()
    return obj


def test_a_mesh_in_edit_mode_through_its_linked_duplicate_is_refused_untouched(addon):
    """Decompose through the duplicate failed half way with a traceback and wiped the stored
    decomposition (every operator then said there was none); Bake Filter wrote its key first."""
    a = _bumpy_ico_sphere()
    a.data.multiscale.levels = 3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    twin = bpy.data.objects.new("Twin", a.data)
    bpy.context.scene.collection.objects.link(twin)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.context.view_layer.objects.active = twin
    keys_before = list(a.data.shape_keys.key_blocks.keys())
    a.data.multiscale.bands[1].gain = 2.0
    for name in ("decompose", "bake_filter", "rebuild_detail", "clear"):
        operator = getattr(bpy.ops.pointscale, name)
        assert not operator.poll(), name
        with pytest.raises(RuntimeError, match="is in Edit Mode through 'Icosphere': leave Edit Mode there first"):
            operator()
    assert list(a.data.shape_keys.key_blocks.keys()) == keys_before
    bpy.context.view_layer.objects.active = a
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.context.view_layer.objects.active = twin
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}  # the decomposition is still there


def test_a_mesh_split_along_a_seam_moved_as_a_whole_folds_nowhere(addon):
    """Its coincident vertex pairs folded at the rounding of their base positions: 4 points
    marked on a UV sphere split at its equator, and Prevent Folds moved 361 points by up to
    0.0675 (3% of the model) for nothing."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48)
    obj = bpy.context.active_object
    mesh = obj.data
    co = h.vertices(mesh)
    d = 1 + 0.04 * np.sin(9 * co[:, 0]) * np.sin(9 * co[:, 1]) + 0.01 * np.sin(40 * co[:, 2])
    mesh.vertices.foreach_set("co", (co * d[:, None]).astype(np.float32).ravel())
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bmesh.ops.split_edges(bm, edges=[e for e in bm.edges if all(abs(v.co.z) < 1e-4 for v in e.verts)])
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()
    assert len(mesh.vertices) == 4514 + 96  # the equator's vertices, twice
    mesh.multiscale.levels = 3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    basis = h.key(mesh, "Basis")
    level0 = h.key(mesh, "Level 0")
    level0[:, 2] += 0.2
    h.set_key(mesh, "Level 0", level0)
    for prevent in (False, True):
        mesh.multiscale.prevent_folds = prevent
        assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
        assert np.abs(h.key(mesh, "Multiscale Edit") - basis - [0.0, 0.0, 0.2]).max() < 1e-6, prevent
        folds = obj.vertex_groups.get("Folds")
        assert folds is None or not any(g.group == folds.index for v in mesh.vertices for g in v.groups)
