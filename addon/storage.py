"""The decomposition kept on the mesh, so that it survives save and reload.

Format 2 (now): the ID property ``mesh["pointscale"]`` holds the recipe (recipe.py: the
settings the engine was given, fingerprints of the Basis and edges); the engine object is made
again from the Basis on first use after a reload, and checked bit for bit against the visible
``ms_detail_<l>`` attributes. ``ms_normal_<l>`` (12 bytes a vertex each) only when the Level
Normal Attributes preference asks for them. A setting the recipe cannot write falls back to
format 1.

Format 1 (files written before, still read): the whole engine model as hidden ``.ps.*``
columns (about 200 bytes a vertex) plus the ID property's arrays.
"""

from __future__ import annotations

import json

import numpy as np

from . import compute, logic, mesh_io, recipe as recipes

PROP = "pointscale"
HIDDEN = ".ps."
DETAIL = "ms_detail_"
NORMAL = "ms_normal_"
COLOR = "ms_detail_color"
ORDER = HIDDEN + "order"
SHEET_NORMALS = HIDDEN + "sheet_normals"  # the vertex normals Keep Thin Sheets Apart gave the engine
FORMAT = 2


def has_data(mesh) -> bool:
    return PROP in mesh.keys()


def stored_count(mesh) -> int:
    return int(mesh[PROP]["n"]) if has_data(mesh) else -1


def store(mesh, dec, details=None, normals=None, recipe=None, sheet_normals=None) -> None:
    """Write ``dec`` onto ``mesh`` (object mode). ``normals``: list of (n,3) per level, or None.
    With a ``recipe`` only the recipe is kept (format 2), else the whole model (format 1)."""
    n = dec.n_points
    clear(mesh)
    if recipe is None:
        _store_model(mesh, dec, n)
    elif recipe.get("normals"):
        mesh_io.write_attribute(mesh, SHEET_NORMALS, "FLOAT_VECTOR", sheet_normals)
    # Vertex indices as data: Blender reorders attributes with the vertices, so a sort shows here.
    mesh_io.write_attribute(mesh, ORDER, "INT", np.arange(n, dtype=np.int32))
    k = dec.n_bands
    details = dec.details if details is None else details
    for l in range(k):
        mesh_io.write_attribute(mesh, f"{DETAIL}{l}", "FLOAT", details[l])
        if normals is not None:
            mesh_io.write_attribute(mesh, f"{NORMAL}{l}", "FLOAT_VECTOR", normals[l])
    if recipe is not None:
        mesh[PROP] = {"format": FORMAT, "n": n, "k": k, "recipe": recipes.dumps(recipe)}


def _store_model(mesh, dec, n: int) -> None:
    columns, extras, meta = logic.pack_decomposition(dec.to_dict(), n)
    for name, (kind, values) in columns.items():
        mesh_io.write_attribute(mesh, HIDDEN + name, kind, values)
    mesh[PROP] = {
        "format": 1,
        "n": n,
        "k": dec.n_bands,
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


def load(mesh, engine, threads: int = 0):
    """Rebuild the engine's Decomposition from the mesh (raises ValueError if absent, damaged,
    or no longer what the mesh was decomposed from)."""
    if not has_data(mesh):
        raise ValueError(f"mesh {mesh.name!r} has no decomposition; run Decompose first")
    info = mesh[PROP]
    if "recipe" in info:
        return _decompose_again(mesh, engine, recipes.loads(info["recipe"]), threads)
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
    mesh_io.remove_attributes(mesh, HIDDEN)  # the order column and sheet normals too
    mesh_io.remove_attributes(mesh, DETAIL)
    mesh_io.remove_attributes(mesh, NORMAL)
    if PROP in mesh.keys():
        del mesh[PROP]


def _decompose_again(mesh, engine, recipe: dict, threads: int):
    """Format 2: the Basis decomposed again with the saved settings, checked to be the saved one."""
    again = "Decompose again to start from the mesh as it is now"
    points = mesh_io.read_basis(mesh)
    edges = mesh_io.read_edges(mesh) if "edges" in recipe else None
    problem = recipes.problem(recipe, points, edges)
    if problem:
        raise ValueError(f"'{mesh.name}': {problem}. {again}")
    kwargs = dict(recipe["kwargs"], threads=threads)
    if edges is not None:
        kwargs["edges"] = edges
    if "normals" in recipe:
        kwargs["normals"] = None
        if recipe["normals"]:
            if mesh.attributes.get(SHEET_NORMALS) is None:
                raise ValueError(f"'{mesh.name}': the attribute {SHEET_NORMALS} was removed. {again}")
            kwargs["normals"] = mesh_io.read_attribute(mesh, SHEET_NORMALS, "FLOAT_VECTOR").astype(np.float64)
    if "mirror" in recipe:
        kwargs["mirror"] = engine.Mirror(recipe["mirror"]["axes"], tuple(recipe["mirror"]["origin"]),
                                         recipe["mirror"]["seam"])
    dec = compute.run_decompose(engine, points, **kwargs)  # the recipe's smoother and encoding too
    saved = [mesh_io.read_attribute(mesh, f"{DETAIL}{l}", "FLOAT") if mesh.attributes.get(f"{DETAIL}{l}") is not None else None
             for l in range(dec.n_bands)]
    band = recipes.changed_band(dec.details, saved) if dec.n_bands == int(mesh[PROP]["k"]) else 0
    if band is not None:
        raise ValueError(f"'{mesh.name}': decomposing the Basis again did not give the saved band {band} back "
                         f"(saved with pointscale {recipe.get('engine') or '?'}). {again}")
    return dec
