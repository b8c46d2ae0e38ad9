"""Main-thread writes of computed results onto a mesh object, and the cached engine object."""

from __future__ import annotations

import uuid

import numpy as np

from . import keys, mesh_io, storage

_cache: dict = {}


def apply_layout(obj, layout, basis=None) -> list:
    """Keys, masks, attributes and settings of a fresh decomposition (object mode). Returns the
    earlier result keys it kept under a "(previous)" name."""
    mesh = obj.data
    settings = mesh.multiscale
    # The Basis the decomposition was computed from (the caller's snapshot), else the current one.
    basis = (mesh_io.read_basis(mesh) if basis is None else np.asarray(basis)).astype(np.float64)
    try:
        storage.store(mesh, layout.dec, normals=layout.normals)
    except Exception:
        storage.clear(mesh)  # never leave half-written data
        raise
    kept = keys.write_layout(obj, basis, layout.levels, settings.n_bands)
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


def clear(obj) -> list:
    """Removes everything a decompose made: its keys (and the Basis when the add-on made it and
    nothing else needs it), the stored decomposition, the detail colours (restoring the colour
    attributes that were active and rendered before Show Details), the Folds group and the band
    masks nobody painted. Returns notes on what it kept for the artist: painted masks, a Basis
    that other keys need."""
    mesh = obj.data
    settings = mesh.multiscale
    k = max(settings.n_bands, 0)
    keys.remove_layout(obj, k)
    storage.clear(mesh)
    restore_colors(mesh)
    mesh_io.remove_attributes(mesh, storage.COLOR)
    notes = []
    folds = obj.vertex_groups.get(keys.FOLDS)
    if folds is not None:
        obj.vertex_groups.remove(folds)
    masks = [keys.mask_name(l) for l in range(k) if obj.vertex_groups.get(keys.mask_name(l)) is not None]
    weights = mesh_io.read_group_weights(obj, masks, len(mesh.vertices)) if masks else []
    painted = []
    for name, w in zip(masks, weights):
        if w is not None and np.all(w == 1.0):
            obj.vertex_groups.remove(obj.vertex_groups[name])  # as Decompose made it
        else:
            painted.append(name)
    if painted:
        notes.append(f"kept the painted {', '.join(painted)} (delete them under Vertex Groups if unwanted)")
    if keys.remove_created_basis(obj) is False:
        notes.append("kept the Basis key: other shape keys need it")
    settings.n_vertices = 0
    settings.n_bands = 0
    settings.bands.clear()
    settings.scale_store = 0.0
    mesh.update()
    return notes


SHOWN_COLORS = "pointscale_colors"  # mesh ID property: the colour attributes before Show Details


def remember_colors(mesh) -> None:
    """The active and render colour attributes' names, before Show Details first replaces them."""
    if SHOWN_COLORS in mesh.keys():
        return
    colors = mesh.color_attributes
    active = colors.active_color.name if colors.active_color is not None else ""
    render = colors[colors.render_color_index].name if 0 <= colors.render_color_index < len(colors) else ""
    mesh[SHOWN_COLORS] = {"active": active, "render": render}


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


def decomposition(mesh, ps):
    """The engine object for ``mesh``, rebuilt from its attributes at most once per token."""
    token = mesh[storage.PROP].get("token", "") if storage.has_data(mesh) else ""
    key = (mesh.session_uid, token)
    dec = _cache.get(key)
    if dec is None:
        dec = storage.load(mesh, ps)
        _remember(mesh, token, dec)
    return dec


def _remember(mesh, token, dec) -> None:
    if len(_cache) >= 4:
        _cache.pop(next(iter(_cache)))
    _cache[(mesh.session_uid, token)] = dec


def forget_all() -> None:
    _cache.clear()


def show_result(obj, name: str, co: np.ndarray) -> None:
    """Write an absolute result key and show it alone over the original (Scale = k)."""
    mesh = obj.data
    kb = keys.ensure_key(obj, name, co)
    keys.add_owned(mesh, name)
    kb.value = 1.0
    for other in (keys.EDIT, keys.FILTER):
        if other != name:
            ok = keys.get(mesh, other)
            if ok is not None:
                ok.value = 0.0
    mesh.multiscale.scale = float(mesh.multiscale.n_bands)
    mesh.update()
