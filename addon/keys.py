"""The shape-key layout that a decompose leaves on a mesh.

``Basis`` (never written), ``Level 0..k-1`` (absolute P^l), ``Band 0..k-1``
(Basis + P^{l+1} - P^l, value = gain - 1, masked by ``Band l mask``),
``Multiscale Edit`` (Rebuild detail) and ``Multiscale Filter`` (Bake filter).
"""

from __future__ import annotations

import numpy as np

from . import logic, mesh_io

LEVEL = "Level {}"
BAND = "Band {}"
MASK = "Band {} mask"
EDIT = "Multiscale Edit"
FILTER = "Multiscale Filter"
BAND_MIN = -1.0  # gain 0
BAND_MAX = 4.0  # gain 5


def level_name(l: int) -> str:
    return LEVEL.format(l)


def band_name(l: int) -> str:
    return BAND.format(l)


def mask_name(l: int) -> str:
    return MASK.format(l)


def key_blocks(mesh):
    return None if mesh.shape_keys is None else mesh.shape_keys.key_blocks


def get(mesh, name):
    kbs = key_blocks(mesh)
    return None if kbs is None else kbs.get(name)


def ensure_basis(obj):
    if obj.data.shape_keys is None:
        obj.shape_key_add(name="Basis", from_mix=False)
    obj.data.shape_keys.use_relative = True
    return obj.data.shape_keys.reference_key


def ensure_key(obj, name: str, co: np.ndarray, slider=(0.0, 1.0)):
    """Create (from the Basis) or reuse the relative key ``name`` and fill it."""
    ref = ensure_basis(obj)
    kb = obj.data.shape_keys.key_blocks.get(name)
    if kb is None:
        kb = obj.shape_key_add(name=name, from_mix=False)
    kb.relative_key = ref
    kb.slider_min, kb.slider_max = slider
    mesh_io.write_key(kb, co)
    return kb


def remove_key(obj, name: str) -> None:
    kb = get(obj.data, name)
    if kb is not None:
        obj.shape_key_remove(kb)


def ensure_mask(obj, l: int):
    """The vertex group ``Band l mask``; a new one starts at weight 1 everywhere (full band)."""
    name = mask_name(l)
    vg = obj.vertex_groups.get(name)
    if vg is None:
        vg = obj.vertex_groups.new(name=name)
        vg.add(range(len(obj.data.vertices)), 1.0, "REPLACE")
    return vg


def write_layout(obj, basis: np.ndarray, levels: np.ndarray, old_k: int) -> None:
    """Level and Band keys and masks for k = len(levels); removes stale ones."""
    k = levels.shape[0]
    bands = logic.band_key_data(basis, levels)
    for l in range(k):
        ensure_key(obj, level_name(l), levels[l]).value = 0.0
    for l in range(k):
        kb = ensure_key(obj, band_name(l), bands[l], slider=(BAND_MIN, BAND_MAX))
        kb.value = 0.0
        kb.vertex_group = ensure_mask(obj, l).name
    for l in range(k, max(old_k, k) + 16):
        remove_key(obj, level_name(l))
        remove_key(obj, band_name(l))
    remove_key(obj, EDIT)
    remove_key(obj, FILTER)


def remove_layout(obj, k: int) -> None:
    for l in range(k + 16):
        remove_key(obj, level_name(l))
        remove_key(obj, band_name(l))
    remove_key(obj, EDIT)
    remove_key(obj, FILTER)


def set_scale(mesh, t: float, k: int) -> None:
    """Level key values that show the blend P(t) (Eq. 20-21)."""
    values = logic.level_key_values(t, k)
    for l in range(k):
        kb = get(mesh, level_name(l))
        if kb is not None:
            kb.value = float(values[l])


def band_values(mesh, k: int) -> np.ndarray:
    out = np.zeros(k)
    for l in range(k):
        kb = get(mesh, band_name(l))
        if kb is not None and not kb.mute:
            out[l] = kb.value
    return out


def band_masks(obj, k: int) -> list:
    """Mask names in use per band (None when a band key has no mask)."""
    names = []
    for l in range(k):
        kb = get(obj.data, band_name(l))
        names.append(kb.vertex_group if kb is not None and kb.vertex_group else None)
    return names
