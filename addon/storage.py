"""The decomposition kept on the mesh, so that it survives save and reload.

* per-vertex arrays -> mesh attributes (hidden ``.ps.*`` columns that rebuild
  the engine object exactly, plus visible ``ms_detail_<l>`` / ``ms_normal_<l>``
  for artists, shaders and Geometry Nodes);
* everything else -> the ID property ``mesh["pointscale"]``.
"""

from __future__ import annotations

import json

import numpy as np

from . import logic, mesh_io

PROP = "pointscale"
HIDDEN = ".ps."
DETAIL = "ms_detail_"
NORMAL = "ms_normal_"
COLOR = "ms_detail_color"
ORDER = HIDDEN + "order"
FORMAT = 1


def has_data(mesh) -> bool:
    return PROP in mesh.keys()


def stored_count(mesh) -> int:
    return int(mesh[PROP]["n"]) if has_data(mesh) else -1


def store(mesh, dec, details=None, normals=None) -> None:
    """Write ``dec`` onto ``mesh`` (object mode). ``normals``: list of (n,3) per level."""
    n = dec.n_points
    columns, extras, meta = logic.pack_decomposition(dec.to_dict(), n)
    clear(mesh)
    for name, (kind, values) in columns.items():
        mesh_io.write_attribute(mesh, HIDDEN + name, kind, values)
    # Vertex indices as data: Blender reorders attributes with the vertices, so a sort shows here.
    mesh_io.write_attribute(mesh, ORDER, "INT", np.arange(n, dtype=np.int32))
    k = dec.n_bands
    details = dec.details if details is None else details
    for l in range(k):
        mesh_io.write_attribute(mesh, f"{DETAIL}{l}", "FLOAT", details[l])
        if normals is not None:
            mesh_io.write_attribute(mesh, f"{NORMAL}{l}", "FLOAT_VECTOR", normals[l])
    mesh[PROP] = {
        "format": FORMAT,
        "n": n,
        "k": k,
        "meta": json.dumps(meta),
        "extras": {key: _idprop_array(v) for key, v in extras.items()},
    }


def _idprop_array(v: np.ndarray):
    # Buffers (fast): float64 as is; integers as int32 when they fit, else float64 (exact to
    # 2**53).  The original dtype is in the metadata, so loading casts back.
    if v.dtype.kind in "iub":
        info = np.iinfo(np.int32)
        if v.size == 0 or (int(v.min()) >= info.min and int(v.max()) <= info.max):
            return np.ascontiguousarray(v, dtype=np.int32)
    return np.ascontiguousarray(v, dtype=np.float64)


def load(mesh, engine):
    """Rebuild the engine's Decomposition from the mesh (raises ValueError if absent or damaged)."""
    if not has_data(mesh):
        raise ValueError(f"mesh {mesh.name!r} has no decomposition; run Decompose first")
    info = mesh[PROP]
    n = int(info["n"])
    meta = json.loads(info["meta"])
    extras = {key: np.asarray(info["extras"][key]) for key in info["extras"].keys()}

    def column(name, kind):
        attr = mesh.attributes.get(HIDDEN + name)
        if attr is None:
            raise ValueError(f"the decomposition data on {mesh.name!r} is incomplete (attribute {HIDDEN + name} is missing)")
        return mesh_io.read_attribute(mesh, HIDDEN + name, kind)

    arrays = logic.unpack_decomposition(column, extras, meta, n)
    return engine.Decomposition.from_dict(arrays)


def order_intact(mesh) -> bool:
    """False when the vertices were reordered after the decompose (True for older data without
    the order column)."""
    if mesh.attributes.get(ORDER) is None:
        return True
    order = mesh_io.read_attribute(mesh, ORDER, "INT")
    return bool(np.array_equal(order, np.arange(len(order), dtype=order.dtype)))


def read_details(mesh, band: int) -> np.ndarray:
    """The band's detail coefficients (the visible attribute); ValueError if it was removed."""
    if mesh.attributes.get(f"{DETAIL}{band}") is None:
        raise ValueError(f"the attribute {DETAIL}{band} was removed: Decompose again to restore it")
    return mesh_io.read_attribute(mesh, f"{DETAIL}{band}", "FLOAT")


def clear(mesh) -> None:
    mesh_io.remove_attributes(mesh, HIDDEN)
    mesh_io.remove_attributes(mesh, DETAIL)
    mesh_io.remove_attributes(mesh, NORMAL)
    if PROP in mesh.keys():
        del mesh[PROP]
