"""Bulk reads and writes between Blender meshes and NumPy (foreach_get/foreach_set only)."""

from __future__ import annotations

import numpy as np


def read_vertices(mesh) -> np.ndarray:
    n = len(mesh.vertices)
    co = np.empty(n * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(n, 3)


def write_vertices(mesh, co: np.ndarray) -> None:
    mesh.vertices.foreach_set("co", np.ascontiguousarray(co, dtype=np.float32).reshape(-1))
    mesh.update()


def read_edges(mesh) -> np.ndarray:
    """(e, 2) vertex indices of the mesh's edges: they say which vertices form one part."""
    e = np.empty(2 * len(mesh.edges), dtype=np.int32)
    mesh.edges.foreach_get("vertices", e)
    return e.reshape(-1, 2)


def read_faces(mesh) -> tuple:
    """(loop vertex indices, each face's first loop, each face's loop count): the faces' windings."""
    loops = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", loops)
    starts = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    totals = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", totals)
    return loops, starts, totals


def read_vertex_normals(mesh) -> np.ndarray | None:
    """(n, 3) Blender's vertex normals, outward where the faces are wound consistently; None for
    a mesh without faces, whose vertex normals say nothing."""
    if not len(mesh.polygons):
        return None
    n = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertex_normals.foreach_get("vector", n)
    return n.reshape(-1, 3).astype(np.float64)


def read_imported_normals(mesh) -> np.ndarray | None:
    """(n, 3) the per-vertex `normal` attribute that Blender's PLY importer gives a point cloud,
    or None when the mesh has none."""
    attr = mesh.attributes.get("normal")
    if attr is None or attr.domain != "POINT" or attr.data_type != "FLOAT_VECTOR":
        return None
    n = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    attr.data.foreach_get("vector", n)
    return n.reshape(-1, 3).astype(np.float64)


def read_key(kb) -> np.ndarray:
    # ShapeKey.points (Blender 4.1+): the lightweight accessor, without .data's per-point extras.
    n = len(kb.points)
    co = np.empty(n * 3, dtype=np.float32)
    kb.points.foreach_get("co", co)
    return co.reshape(n, 3)


def write_key(kb, co: np.ndarray) -> None:
    kb.points.foreach_set("co", np.ascontiguousarray(co, dtype=np.float32).reshape(-1))


def read_basis(mesh) -> np.ndarray:
    """The reference (Basis) positions: the reference key if any, else the vertices."""
    if mesh.shape_keys is not None and mesh.shape_keys.reference_key is not None:
        return read_key(mesh.shape_keys.reference_key)
    return read_vertices(mesh)


def read_group_weights(obj, group_names, n: int) -> list:
    """Weights (n,) per named vertex group, None where the group does not exist.

    Vertex groups have no bulk reader, so this walks the vertices once; call
    it once per operator, never per frame.
    """
    wanted = {}
    out = []
    for name in group_names:
        vg = obj.vertex_groups.get(name) if name else None
        if vg is None:
            out.append(None)
        else:
            w = np.zeros(n, dtype=np.float64)
            wanted[vg.index] = w
            out.append(w)
    if wanted:
        for v in obj.data.vertices:
            for g in v.groups:
                w = wanted.get(g.group)
                if w is not None:
                    w[v.index] = g.weight
    return out


def write_attribute(mesh, name: str, kind: str, values: np.ndarray, domain: str = "POINT"):
    """Create or replace a mesh attribute and fill it in one call.

    kind: 'FLOAT' (n,), 'INT' (n,), 'FLOAT_VECTOR' (n,3), 'FLOAT_COLOR' (n,4).
    """
    attr = mesh.attributes.get(name)
    if attr is not None and (attr.data_type != kind or attr.domain != domain):
        mesh.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = mesh.attributes.new(name, kind, domain)
    prop = {"FLOAT": "value", "INT": "value", "FLOAT_VECTOR": "vector", "FLOAT_COLOR": "color"}[kind]
    dtype = np.int32 if kind == "INT" else np.float32
    attr.data.foreach_set(prop, np.ascontiguousarray(values, dtype=dtype).reshape(-1))
    return attr


def read_attribute(mesh, name: str, kind: str) -> np.ndarray:
    attr = mesh.attributes[name]
    n = len(attr.data)
    width = {"FLOAT": 1, "INT": 1, "FLOAT_VECTOR": 3, "FLOAT_COLOR": 4}[kind]
    prop = {"FLOAT": "value", "INT": "value", "FLOAT_VECTOR": "vector", "FLOAT_COLOR": "color"}[kind]
    buf = np.empty(n * width, dtype=np.int32 if kind == "INT" else np.float32)
    attr.data.foreach_get(prop, buf)
    return buf if width == 1 else buf.reshape(n, width)
