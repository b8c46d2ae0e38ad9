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


def clear(obj) -> None:
    mesh = obj.data
    settings = mesh.multiscale
    keys.remove_layout(obj, max(settings.n_bands, 0))
    storage.clear(mesh)
    mesh_io.remove_attributes(mesh, storage.COLOR)
    settings.n_vertices = 0
    settings.n_bands = 0
    settings.bands.clear()
    settings.scale_store = 0.0
    mesh.update()


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
