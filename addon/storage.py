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
BAKED = HIDDEN + "baked_"  # + band: the painted gains the Multiscale Filter key holds (baked_gains)
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
    written = []  # removed again if a write fails: never leave half-written data

    def write(name, kind, values):
        written.append(name)
        mesh_io.write_attribute(mesh, name, kind, values)

    try:
        if recipe is None:
            _store_model(mesh, dec, n, write)
        elif recipe.get("normals"):
            write(SHEET_NORMALS, "FLOAT_VECTOR", sheet_normals)
        # Vertex indices as data: Blender reorders attributes with the vertices, so a sort shows here.
        write(ORDER, "INT", np.arange(n, dtype=np.int32))
        k = dec.n_bands
        details = dec.details if details is None else details
        for l in range(k):
            write(f"{DETAIL}{l}", "FLOAT", details[l])
            if normals is not None:
                write(f"{NORMAL}{l}", "FLOAT_VECTOR", normals[l])
        if recipe is not None:
            mesh[PROP] = {"format": FORMAT, "n": n, "k": k, "recipe": recipes.dumps(recipe)}
        mesh[PROP]["normals"] = normals is not None  # whether the ms_normal_ columns are the add-on's
    except Exception:
        _remove(mesh, written)
        raise


def attribute_names(mesh) -> list:
    """The attributes the stored decomposition consists of (all of them the add-on's own)."""
    if not has_data(mesh):
        return []
    info = mesh[PROP]
    k = int(info.get("k", 0))
    names = [ORDER, SHEET_NORMALS] + [f"{DETAIL}{l}" for l in range(k)] + [f"{BAKED}{l}" for l in range(k)]
    if info.get("normals", True):  # stores that do not say are taken to have written them, as before
        names += [f"{NORMAL}{l}" for l in range(k)]
    if "meta" in info:  # format 1: the model's columns
        names += [HIDDEN + name for name in logic.column_names(json.loads(info["meta"]))]
    return names


def attributes_problem(mesh, k: int, normals: bool) -> str | None:
    """Why a decompose into k bands cannot write its attributes: an attribute of the artist's
    with one of their names (``ms_detail_<l>``, with normals ``ms_normal_<l>``)."""
    mine = set(attribute_names(mesh))
    wanted = [f"{DETAIL}{l}" for l in range(k)] + ([f"{NORMAL}{l}" for l in range(k)] if normals else [])
    for name in wanted:
        if mesh.attributes.get(name) is not None and name not in mine:
            return f"it has an attribute '{name}' of its own: rename it first, the decomposition writes that name"
    return None


def baked_gains(mesh, key_fingerprint: str | None) -> np.ndarray | None:
    """The gains the 'Multiscale Filter' key was baked with, (k,) or (k, n) per painted point,
    or None when nothing is baked on this decomposition or the key (of that fingerprint now) is
    not the one they made. Kept in the .blend, so that a bake after a reload goes on from the
    same gains."""
    if not has_data(mesh) or "baked" not in mesh[PROP]:
        return None
    if key_fingerprint is None or mesh[PROP].get("baked_key") != key_fingerprint:
        return None
    baked = mesh[PROP]["baked"]
    if isinstance(baked, str):  # "painted": one column a band
        k = int(mesh[PROP]["k"])
        columns = [mesh.attributes.get(f"{BAKED}{l}") for l in range(k)]
        if any(column is None for column in columns):
            return None
        return np.stack([mesh_io.read_attribute(mesh, f"{BAKED}{l}", "FLOAT") for l in range(k)]).astype(np.float64)
    return np.asarray(list(baked), dtype=np.float64)


def store_baked_gains(mesh, gains, key_fingerprint: str) -> None:
    """Records the gains a bake used (see baked_gains), with a fingerprint of the key it wrote:
    an undo in Edit Mode restores the key but not these properties, and a bake must build only
    on gains that made the key as it is. Gains per band as they are; painted ones in single
    precision, as attributes store them: the next bake reads them back rounded, so that it gives
    the same bits in this session and after a reload."""
    drop_baked_gains(mesh)
    mesh[PROP]["baked_key"] = key_fingerprint
    gains = np.asarray(gains, dtype=np.float64)
    if gains.ndim == 1:
        mesh[PROP]["baked"] = gains.tolist()
        return
    for l, column in enumerate(gains):
        mesh_io.write_attribute(mesh, f"{BAKED}{l}", "FLOAT", column.astype(np.float32))
    mesh[PROP]["baked"] = "painted"


def drop_baked_gains(mesh) -> None:
    if not has_data(mesh):
        return
    _remove(mesh, [f"{BAKED}{l}" for l in range(int(mesh[PROP].get("k", 0)))])
    for name in ("baked", "baked_key"):
        if name in mesh[PROP]:
            del mesh[PROP][name]


def _remove(mesh, names) -> None:
    for name in names:
        attr = mesh.attributes.get(name)
        if attr is not None:
            mesh.attributes.remove(attr)


def _store_model(mesh, dec, n: int, write) -> None:
    columns, extras, meta = logic.pack_decomposition(dec.to_dict(), n)
    for name, (kind, values) in columns.items():
        write(HIDDEN + name, kind, values)
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
    """Removes the stored decomposition: its own attributes by their exact names (an artist's
    ``ms_detail_sculpt`` is not the add-on's), and the ID property."""
    _remove(mesh, attribute_names(mesh))
    if PROP in mesh.keys():
        del mesh[PROP]


AGAIN = "Decompose again to start from the mesh as it is now"


def basis_problem(mesh) -> str | None:
    """Why the kept engine object no longer belongs to the mesh: its Basis changed since the
    Decompose. The same report as the reload gives (_decompose_again), so that an edited Basis
    is refused in the session too instead of being thrown away by a result key. Format 2 only
    (format 1 keeps the model, and loads it whatever the Basis). 12-20 ms at 1M vertices."""
    if not has_data(mesh) or "recipe" not in mesh[PROP]:
        return None
    recipe = recipes.loads(mesh[PROP]["recipe"])
    problem = recipes.problem({"points": recipe["points"]}, mesh_io.read_basis(mesh))  # the Basis alone
    return f"the mesh '{mesh.name}': {problem}. {AGAIN}" if problem else None


def _decompose_again(mesh, engine, recipe: dict, threads: int):
    """Format 2: the Basis decomposed again with the saved settings, checked to be the saved one."""
    again = AGAIN
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
