"""Main-thread writes of computed results onto a mesh object, and the cached engine object."""

from __future__ import annotations

import uuid
from dataclasses import dataclass

import numpy as np

from . import group_weights, keys, logic, mesh_io, preferences, recipe, storage

_cache: dict = {}
# A Reconstructor per decomposition that Rebuild Detail or Bake Filter used last, under the same
# keys: the solver finds what an edited base needs once, as reconstruct() does, and also keeps
# the model in a spatial order with each level's grouping and its working arrays. It copies
# the model, so only the last two.
_solvers: dict = {}
_SOLVERS_KEPT = 2


@dataclass
class KeyData:
    """The key arrays as Blender stores them (float32), made off the main thread."""

    levels: np.ndarray  # (k, n, 3) Level keys
    bands: np.ndarray  # (k, n, 3) Band keys
    recipe: dict | None  # see recipe.py; None: store the whole model
    sheet_normals: np.ndarray | None = None  # the vertex normals Keep Thin Sheets Apart gave the engine
    base_fingerprint: str | None = None  # of levels[0]: tells an edited 'Level 0' at the next Decompose


def key_data(layout, basis, kwargs=None, version="") -> KeyData:
    """NumPy only, safe in the worker thread: at 1M vertices this is 0.3-0.7 s that the modal
    Decompose would otherwise block the UI for."""
    basis = np.asarray(basis, dtype=np.float64)
    bands = logic.band_key_data(basis, layout.levels).astype(np.float32)
    made = recipe.make(kwargs, basis, version) if kwargs is not None else None
    sheet_normals = (kwargs or {}).get("normals")
    levels = layout.levels.astype(np.float32)
    return KeyData(levels, bands, made, None if sheet_normals is None else np.asarray(sheet_normals, dtype=np.float32),
                   recipe.fingerprint(np.ascontiguousarray(levels[0])))


def apply_layout(obj, layout, basis=None, kwargs=None, version="", data=None) -> list:
    """Keys, attributes and settings of a fresh decomposition (object mode). ``kwargs``: what
    the engine was given (then the .blend keeps only the recipe, see storage.py); ``data``:
    key_data() made beforehand. Returns the earlier result keys it kept under a "(previous)" name."""
    mesh = obj.data
    settings = mesh.multiscale
    # The Basis the decomposition was computed from (the caller's snapshot), else the current one.
    basis = mesh_io.read_basis(mesh) if basis is None else basis
    data = key_data(layout, basis, kwargs, version) if data is None else data
    made = data.recipe
    normals = layout.normals if preferences.get().normal_attributes else None
    try:
        storage.store(mesh, layout.dec, normals=normals, recipe=made,
                      sheet_normals=data.sheet_normals)
    except Exception:
        storage.clear(mesh)  # never leave half-written data
        raise
    # Show Details' colours and the Folds marks belong to the decomposition being replaced.
    drop_detail_colors(mesh)
    keys.clear_fold_marks(obj)
    kept = keys.write_layout(obj, data.levels, data.bands, settings.n_bands, data.base_fingerprint)
    release_levels(layout.dec)
    token = uuid.uuid4().hex
    mesh[storage.PROP]["token"] = token
    _remember(mesh, token, layout.dec)
    k = layout.k
    settings.n_vertices = len(mesh.vertices)
    settings.n_bands = k
    settings.bands.clear()
    for l in range(k):
        settings.bands.add().index = l
    settings.detail_band = min(settings.detail_band, k - 1)
    settings.scale = float(k)  # show the original
    mesh.update()
    return kept


def clear_problem(obj) -> str | None:
    """Why Clear cannot go ahead without losing something: an edited 'Level 0' or a result to
    keep as "(previous)" where the artist has a key of that name of their own. Checked before
    anything is removed."""
    mesh = obj.data
    mine = keys.owned(mesh, max(mesh.multiscale.n_bands, 0))
    return keys.copies_problem(mesh, keys.to_keep(mesh, mine), mine)


def clear(obj) -> list:
    """Removes everything a decompose made: its keys (and the Basis when the add-on made it and
    nothing else needs it), the stored decomposition, the detail colours (restoring the colour
    attributes that were active and rendered before Show Details), the Folds group and the band
    masks nobody painted. Returns notes on what it kept for the artist: painted masks, a Basis
    that other keys need."""
    mesh = obj.data
    settings = mesh.multiscale
    k = max(settings.n_bands, 0)
    groups = keys.owned_groups(mesh, k)  # only these vertex groups are the add-on's to remove
    previous, older = keys.remove_layout(obj, k)
    storage.clear(mesh)
    drop_detail_colors(mesh)
    notes = []
    folds = obj.vertex_groups.get(keys.FOLDS)
    if folds is not None and keys.FOLDS in groups:
        obj.vertex_groups.remove(folds)
    groups.discard(keys.FOLDS)
    if keys.FOLDS_MARKED in mesh.keys():
        del mesh[keys.FOLDS_MARKED]
    # Every mask the add-on recorded, also those of bands a later Decompose no longer has.
    masks = sorted(name for name in groups if obj.vertex_groups.get(name) is not None)
    weights = group_weights.read(obj, masks, len(mesh.vertices)) if masks else []
    painted = []
    for name, w in zip(masks, weights):
        if w is not None and np.all(w == 1.0):
            obj.vertex_groups.remove(obj.vertex_groups[name])  # as Paint Band Mask made it
        else:
            painted.append(name)
    # The painted masks it keeps stay recorded as the add-on's: a later Decompose uses them again.
    groups = {name for name in groups if obj.vertex_groups.get(name) is not None}
    if groups:
        keys.set_owned_groups(mesh, groups)
    elif keys.GROUPS in mesh.keys():
        del mesh[keys.GROUPS]
    if painted:
        notes.append(f"kept the painted {', '.join(painted)} (delete them under Vertex Groups if unwanted)")
    if keys.BASE_PREVIOUS in previous:
        notes.append(f"kept 'Level 0', changed since Decompose wrote it, as '{keys.BASE_PREVIOUS}' (delete it under "
                     "Shape Keys if unwanted)")
    copies = [name for name in previous if keys.is_edited_layout_copy(name)]
    if copies:
        notes.append(f"kept your edits of other levels and bands as {', '.join(repr(name) for name in copies)} "
                     "(delete them under Shape Keys if unwanted)")
    results = [name for name in previous if name != keys.BASE_PREVIOUS and name not in copies]
    if results:
        notes.append(f"kept the last results as {', '.join(repr(n) for n in results)}, switched off (delete them under "
                     "Shape Keys if unwanted)")
    if older:
        notes.append(f"kept the earlier {', '.join(repr(n) for n in older)} (delete them under Shape Keys if unwanted)")
    if keys.remove_created_basis(obj) is False:
        notes.append("kept the Basis key: other shape keys need it")
    settings.n_vertices = 0
    settings.n_bands = 0
    settings.bands.clear()
    settings.scale_store = 0.0
    mesh.update()
    return notes


SHOWN_COLORS = "pointscale_colors"  # mesh ID property: the colour attributes before Show Details
# Every mesh ID property the add-on sets, by its exact name (a copy of the mesh drops them).
ID_PROPERTIES = (storage.PROP, keys.OWNED, keys.GROUPS, keys.CREATED_BASIS, keys.FOLDS_MARKED, keys.WRITTEN_BASE,
                 keys.WRITTEN_LAYOUT, keys.WRITTEN_RESULTS,
                 SHOWN_COLORS)


def remember_colors(mesh) -> None:
    """The active and render colour attributes' names, before Show Details first replaces them."""
    if SHOWN_COLORS in mesh.keys():
        return
    colors = mesh.color_attributes
    active = colors.active_color.name if colors.active_color is not None else ""
    render = colors[colors.render_color_index].name if 0 <= colors.render_color_index < len(colors) else ""
    mesh[SHOWN_COLORS] = {"active": active, "render": render}


def colors_problem(mesh) -> str | None:
    """Why Show Details cannot write its colours: a colour attribute of the artist's has their name."""
    if mesh.attributes.get(storage.COLOR) is not None and SHOWN_COLORS not in mesh.keys():
        return (f"it has an attribute '{storage.COLOR}' of its own, and Show Details writes that name: "
                "rename it first; nothing was modified")
    return None


def drop_detail_colors(mesh) -> None:
    """Removes the detail colours of Show Details (only when the add-on wrote them) and gives
    back the colour attributes that were active and rendered before."""
    if SHOWN_COLORS not in mesh.keys():
        return
    restore_colors(mesh)
    attr = mesh.attributes.get(storage.COLOR)
    if attr is not None:
        mesh.attributes.remove(attr)


def restore_colors(mesh) -> None:
    if SHOWN_COLORS not in mesh.keys():
        return
    saved = mesh[SHOWN_COLORS]
    colors = mesh.color_attributes
    active, render = colors.get(saved.get("active", "")), saved.get("render", "")
    if active is not None:
        colors.active_color = active
    if colors.get(render) is not None:
        colors.render_color_index = colors.find(render)
    del mesh[SHOWN_COLORS]


def release_levels(dec) -> None:
    """Drops the levels and normals the engine object cached for the keys (about 170 bytes a
    vertex at 3 bands): the keys hold them now, and reconstruct does not read the cache."""
    for name in ("levels", "normals"):
        dec._cache.pop(name, None)


def decomposition(mesh, ps):
    """The engine object for ``mesh``, rebuilt at most once per token: from the saved model
    (format 1), or by decomposing the Basis again (format 2, as long as the engine takes)."""
    key = _key(mesh)
    dec = _cache.get(key)
    if dec is None:
        dec = storage.load(mesh, ps, threads=preferences.get().threads)  # checks the Basis itself
        _remember(mesh, key[1], dec)
    else:
        problem = storage.basis_problem(mesh)  # as the reload would refuse it
        if problem:
            raise ValueError(problem)
    return dec


def _key(mesh) -> tuple:
    """What the engine object of ``mesh`` is kept under: the mesh, and its decomposition's token."""
    return mesh.session_uid, mesh[storage.PROP].get("token", "") if storage.has_data(mesh) else ""


def reconstructor(mesh, ps):
    """The Reconstructor of ``mesh``'s engine object (decomposition()), made on first use and
    kept while that object is."""
    key = _key(mesh)
    dec = decomposition(mesh, ps)
    held = _solvers.get(key)
    if held is not None and held[0] is dec:
        return held[1]
    _solvers.pop(key, None)
    while len(_solvers) >= _SOLVERS_KEPT:
        _solvers.pop(next(iter(_solvers)))
    solver = ps.Reconstructor(dec)
    _solvers[key] = (dec, solver)
    return solver


def _remember(mesh, token, dec) -> None:
    if len(_cache) >= 4:
        gone = next(iter(_cache))
        _cache.pop(gone)
        _solvers.pop(gone, None)
    _cache[(mesh.session_uid, token)] = dec
    # A new engine object for this mesh: its solvers belong to the ones before (an undo back to
    # them makes one again, in a fraction of a decompose's time).
    for key in [key for key in _solvers if key[0] == mesh.session_uid]:
        _solvers.pop(key)


def forget_all() -> None:
    _cache.clear()
    _solvers.clear()


def show_result(obj, name: str, co: np.ndarray) -> None:
    """Write an absolute result key and show it alone over the original (Scale = k)."""
    mesh = obj.data
    kb = keys.ensure_key(obj, name, co)
    keys.add_owned(mesh, name)
    keys.record_written_result(mesh, name, co)
    kb.value = 1.0
    for other in keys.RESULTS:  # the kept "(previous)" results too: this one is shown alone
        if other != name:
            ok = keys.get(mesh, other)
            if ok is not None:
                ok.value = 0.0
    mesh.multiscale.scale = float(mesh.multiscale.n_bands)
    mesh.update()
