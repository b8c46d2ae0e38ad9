"""Pure-NumPy logic of the Multiscale add-on.

Nothing in here imports ``bpy``: operators gather arrays from Blender, call
these functions and write the results back.  bpy scripts and tests can call
them directly.

Conventions (n points, k bands, levels P^0..P^k, P^k = the input):

* ``levels``  (k, n, 3): P^0 .. P^{k-1}, absolute positions (the ``Level l`` keys)
* ``basis``   (n, 3):    P^k, the original positions (the ``Basis`` key)
* band l offset = P^{l+1} - P^l, stored in the ``Band l`` key as Basis + offset
"""

from __future__ import annotations

import re

import numpy as np

__all__ = [
    "level_key_values",
    "band_key_data",
    "basis_from_keys",
    "evaluate_keys",
    "per_point_gains",
    "combined_gains",
    "detail_colors",
    "split_float64",
    "join_float64",
    "pack_decomposition",
    "unpack_decomposition",
    "column_names",
    "check_points",
    "levels_that_fit",
    "is_parts_refusal",
    "parts_message",
    "engine_message",
    "sheets_message",
    "faces_wound_against_neighbours",
    "winding_message",
    "morph_message",
]


# ---------------------------------------------------------------- levels / Scale

def level_key_values(t: float, k: int) -> np.ndarray:
    """Values of the ``Level 0..k-1`` keys that display the blend P(t), t in [0, k].

    Relative keys add ``v_l * (Level_l - Basis)``.  With hat weights
    ``v_l = max(0, 1 - |t - l|)`` two neighbouring keys are active, and the
    result is ``(1 - f) P^l + f P^{l+1}`` with ``l = floor(t)``, ``f = t - l``
    (``P^k`` is the Basis, whose weight is implicit).  Because
    ``P^{l+1} - P^l = D^l`` lies along the normal, this is exactly Eq. 20-21.
    """
    if k < 1:
        raise ValueError("need at least one band")
    t = float(min(max(t, 0.0), float(k)))
    l = np.arange(k, dtype=np.float64)
    return np.maximum(0.0, 1.0 - np.abs(t - l))


def band_key_data(basis: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """(k, n, 3) data of the ``Band l`` keys: Basis + (P^{l+1} - P^l).

    ``levels`` holds P^0..P^{k-1}; P^k is ``basis``.
    """
    basis = np.asarray(basis, dtype=np.float64)
    levels = np.asarray(levels, dtype=np.float64)
    upper = np.concatenate([levels[1:], basis[None]], axis=0)
    return basis[None] + (upper - levels)


def basis_from_keys(level: np.ndarray, band: np.ndarray) -> np.ndarray:
    """The Basis (P^k) back from the finest ``Level k-1`` and ``Band k-1`` keys, as band_key_data
    wrote them: Band k-1 = Basis + (P^k - P^{k-1}) = 2 Basis - Level k-1. Within float32 rounding
    (about 1e-7 of the coordinates; the keys keep no more), float32 like a key."""
    level = np.asarray(level, dtype=np.float64)
    band = np.asarray(band, dtype=np.float64)
    return ((band + level) / 2).astype(np.float32)


def evaluate_keys(basis, keys, values, weights=None) -> np.ndarray:
    """What Blender shows for relative keys: Basis + sum v_l w_l (key_l - Basis).

    ``keys`` (m, n, 3), ``values`` (m,), optional ``weights`` (m, n) (vertex-group
    masks, None = full).  Used by tests and previews; Blender does this itself.
    """
    basis = np.asarray(basis, dtype=np.float64)
    keys = np.asarray(keys, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    out = basis.copy()
    for m in range(keys.shape[0]):
        w = values[m] if weights is None or weights[m] is None else values[m] * np.asarray(weights[m])[:, None]
        out += w * (keys[m] - basis)
    return out


# ---------------------------------------------------------------- gains

def per_point_gains(values, weights, n: int) -> np.ndarray | None:
    """Gains of the painted-mask filter (Fig. 10b) as the core expects them.

    A band key with value ``v`` and mask weight ``w_i`` shows
    ``(a_i - 1) = v * w_i``, so the per-point gain is ``1 + v * w_i``.
    ``weights`` is a list of k arrays (n,) or None (= full mask).
    Returns (k,) when no mask is partial, else (k, n).
    """
    values = np.asarray(values, dtype=np.float64)
    k = values.shape[0]
    if weights is None or all(w is None for w in weights):
        return 1.0 + values
    g = np.empty((k, n), dtype=np.float64)
    for l in range(k):
        w = weights[l]
        g[l] = 1.0 + values[l] * (1.0 if w is None else np.asarray(w, dtype=np.float64))
    return g


def combined_gains(baked, gains):
    """The gains of a bake on top of an earlier one: the product per band, and per point when
    either is painted ((k,) or (k, n) each, as per_point_gains gives them). ``baked`` None: none."""
    if baked is None:
        return gains
    baked, gains = np.asarray(baked, dtype=np.float64), np.asarray(gains, dtype=np.float64)
    if baked.ndim != gains.ndim:  # one of them per band only: the same gain at every point
        baked, gains = (baked[:, None], gains) if baked.ndim == 1 else (baked, gains[:, None])
    return baked * gains


# ---------------------------------------------------------------- display

def detail_colors(details: np.ndarray, scale: float | None = None) -> np.ndarray:
    """(n, 4) linear RGBA: blue for negative detail, white for zero, red for positive (Fig. 2).

    ``scale`` maps to full saturation; by default the 98th percentile of |d|.
    """
    d = np.asarray(details, dtype=np.float64).reshape(-1)
    if scale is None:
        a = np.abs(d[np.isfinite(d)])
        scale = float(np.percentile(a, 98.0)) if a.size else 1.0
    if not scale > 0.0:
        scale = 1.0
    s = np.clip(d / scale, -1.0, 1.0)
    s = np.where(np.isfinite(s), s, 0.0)
    rgba = np.ones((d.shape[0], 4), dtype=np.float32)
    pos = s > 0
    # red: (1, 1-s, 1-s); blue: (1-|s|, 1-|s|, 1)
    rgba[pos, 1] = 1.0 - s[pos]
    rgba[pos, 2] = 1.0 - s[pos]
    neg = ~pos
    rgba[neg, 0] = 1.0 + s[neg]
    rgba[neg, 1] = 1.0 + s[neg]
    return rgba


# ---------------------------------------------------------------- storage

def split_float64(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """float64 -> (hi, lo) float32 with hi + lo == a to ~48 mantissa bits.

    Blender attributes are float32; the pair keeps the decomposition exact
    enough that a reloaded file reconstructs like the original.
    """
    a = np.asarray(a, dtype=np.float64)
    hi = a.astype(np.float32)
    lo = (a - hi.astype(np.float64)).astype(np.float32)
    return hi, lo


def join_float64(hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
    return np.asarray(hi, dtype=np.float64) + np.asarray(lo, dtype=np.float64)


def pack_decomposition(d: dict, n: int):
    """Split ``Decomposition.to_dict()`` into per-vertex columns and the rest.

    Returns ``(columns, extras, meta)``:

    * ``columns``: {attribute-name-suffix: (kind, (n,) array)} with kind
      ``'FLOAT'`` (float32) or ``'INT'`` (int32); float64 columns are split
      into ``.hi``/``.lo`` pairs;
    * ``extras``: {key: 1-D float64 or int array} for arrays whose leading
      dimension is not n (stored as ID properties);
    * ``meta``: {key: {"shape", "dtype", "where"}} to rebuild the dict.
    """
    columns, extras, meta = {}, {}, {}
    for key, value in d.items():
        arr = np.asarray(value)
        info = {"shape": list(arr.shape), "dtype": arr.dtype.str}
        per_point = n > 0 and arr.dtype.kind in "fiub" and arr.ndim >= 1
        transpose = per_point and arr.ndim == 2 and arr.shape[0] != n and arr.shape[1] == n
        if per_point and (arr.shape[0] == n or transpose):
            flat = arr.T if transpose else arr.reshape(n, -1)
            info["where"] = "attr"
            info["transpose"] = bool(transpose)
            for j in range(flat.shape[1]):
                col = flat[:, j]
                base = f"{key}.{j}"
                if arr.dtype.kind == "f":
                    if arr.dtype == np.float64:
                        hi, lo = split_float64(col)
                        columns[base + ".hi"] = ("FLOAT", hi)
                        columns[base + ".lo"] = ("FLOAT", lo)
                    else:
                        columns[base] = ("FLOAT", col.astype(np.float32))
                else:
                    if arr.dtype.kind == "u" and arr.dtype.itemsize >= 4 and col.size and col.max() > np.iinfo(np.int32).max:
                        raise ValueError(f"array {key!r} does not fit int32")
                    columns[base] = ("INT", col.astype(np.int32))
        else:
            info["where"] = "prop"
            if arr.dtype.kind == "f":
                extras[key] = arr.astype(np.float64).reshape(-1)
            elif arr.dtype.kind in "iub":
                extras[key] = arr.astype(np.int64).reshape(-1)
            else:
                raise ValueError(f"cannot store array {key!r} of dtype {arr.dtype}")
        meta[key] = info
    return columns, extras, meta


def unpack_decomposition(columns_get, extras: dict, meta: dict, n: int) -> dict:
    """Inverse of :func:`pack_decomposition`.

    ``columns_get(name, kind)`` returns the stored (n,) column.
    """
    out = {}
    for key, info in meta.items():
        shape = tuple(int(s) for s in info["shape"])
        dtype = np.dtype(info["dtype"])
        if info["where"] == "attr":
            transpose = bool(info.get("transpose", False))
            stored = (shape[1], shape[0]) if transpose else shape
            m = int(np.prod(stored[1:])) if len(stored) > 1 else 1
            flat = np.empty((n, m), dtype=np.float64 if dtype.kind == "f" else np.int64)
            for j in range(m):
                base = f"{key}.{j}"
                if dtype.kind == "f":
                    if dtype == np.float64:
                        flat[:, j] = join_float64(columns_get(base + ".hi", "FLOAT"), columns_get(base + ".lo", "FLOAT"))
                    else:
                        flat[:, j] = columns_get(base, "FLOAT")
                else:
                    flat[:, j] = columns_get(base, "INT")
            flat = flat.astype(dtype)
            out[key] = np.ascontiguousarray(flat.T) if transpose else flat.reshape(shape)
        else:
            out[key] = np.asarray(extras[key]).astype(dtype).reshape(shape)
    return out


def column_names(meta: dict) -> list:
    """The attribute-name suffixes that :func:`pack_decomposition` wrote for ``meta``: exactly
    its columns, so that removing them touches no other attribute."""
    names = []
    for key, info in meta.items():
        if info["where"] != "attr":
            continue
        shape = tuple(int(s) for s in info["shape"])
        stored = (shape[1], shape[0]) if info.get("transpose", False) else shape
        m = int(np.prod(stored[1:])) if len(stored) > 1 else 1
        for j in range(m):
            base = f"{key}.{j}"
            names += [base + ".hi", base + ".lo"] if np.dtype(info["dtype"]) == np.float64 else [base]
    return names


# ---------------------------------------------------------------- input

def check_points(points: np.ndarray, minimum: int = 4) -> str | None:
    """A clear message when ``points`` cannot be decomposed, else None.

    The engine validates too (ValueError); checking first lets the operator
    refuse before it starts a worker thread.
    """
    p = np.asarray(points)
    if p.ndim != 2 or p.shape[1] != 3:
        return f"expected (n, 3) points, got shape {p.shape}"
    if p.shape[0] < minimum:
        return f"the mesh has {p.shape[0]} vertices; a decomposition needs at least {minimum}"
    bad = ~np.isfinite(p).all(axis=1)
    if bad.any():
        return f"{int(bad.sum())} vertices have NaN or infinite coordinates (first: index {int(np.argmax(bad))})"
    return None


def uneven_scale_message(linear: np.ndarray, name: str) -> str | None:
    """What to tell the artist when the object is shown stretched: ``linear`` is the 3x3 part of
    its world matrix. The engine works on the mesh as stored, so under an unapplied non-uniform
    scale (or a parent's shear) Level 0 and the bands follow the unscaled shape, not the one in
    the viewport, as Blender's own UV Unwrap warns. None for a rotation with a uniform scale,
    mirrored or not."""
    m = np.asarray(linear, dtype=np.float64)
    gram = m.T @ m
    size = float(np.trace(gram)) / 3.0
    if not size > 0.0 or np.abs(gram - size * np.eye(3)).max() <= 1e-4 * size:
        return None
    axes = np.linalg.norm(m, axis=0)
    shown = ", ".join(f"{a:.3g}" for a in axes)
    return (f"'{name}' is shown with an unapplied non-uniform scale ({shown}): the decomposition works on the "
            "mesh as stored, so Level 0 and the bands follow its unscaled shape. Apply Scale (Ctrl+A) first to "
            "decompose the shape you see")


# Modifiers that leave the shape as it is, or that animate or simulate it (the shape at rest is
# the one to decompose); Geometry Nodes, which may do anything, are not guessed at.
_SHAPE_KEEPING_MODIFIERS = {"ARMATURE", "DATA_TRANSFER", "UV_PROJECT", "UV_WARP", "VERTEX_WEIGHT_EDIT",
                            "VERTEX_WEIGHT_MIX", "VERTEX_WEIGHT_PROXIMITY", "WEIGHTED_NORMAL", "NORMAL_EDIT",
                            "TRIANGULATE", "NODES", "PARTICLE_SYSTEM", "COLLISION", "SOFT_BODY", "CLOTH", "MESH_CACHE",
                            "MESH_SEQUENCE_CACHE", "SURFACE", "DYNAMIC_PAINT", "OCEAN", "EXPLODE", "FLUID",
                            "PARTICLE_INSTANCE"}


def unapplied_modifiers_message(modifiers, name: str) -> str | None:
    """What to tell the artist when modifiers shown in the viewport change the shape the
    decomposition does not see: ``modifiers`` are (name, type) pairs of the enabled ones, less
    the Mirror modifiers Decompose reads itself (Use Mirror Modifier). The engine reads the
    mesh's own vertices (the Basis), as it reads them under an unapplied scale. Animation and
    simulation modifiers and Geometry Nodes (which may do anything) are not named."""
    shaping = [f"'{m}'" for m, kind in modifiers if kind not in _SHAPE_KEEPING_MODIFIERS]
    if not shaping:
        return None
    return (f"'{name}' is shown through modifiers that change its shape ({', '.join(shaping)}): the decomposition "
            "works on the mesh's own vertices, so Level 0 and the bands follow the shape without them. Apply them "
            "first to decompose the shape you see")


def loose_vertices_message(n_vertices: int, edges: np.ndarray) -> str | None:
    """With Keep Parts Apart, vertices in no edge join the part of their nearest vertex and are
    smoothed with it (a scan's untriangulated points): say how many, since helper vertices then
    move to that surface in the base. None when there are none, or no edges at all (a point
    cloud, decomposed as one surface)."""
    e = np.asarray(edges).reshape(-1)
    if n_vertices == 0 or e.size == 0:
        return None
    used = np.zeros(n_vertices, dtype=bool)
    used[e] = True
    loose = n_vertices - int(used.sum())
    if loose == 0:
        return None
    first = int(np.argmin(used))
    return (f"{loose} vertices in no edge (first: index {first}) joined the part of their nearest vertex, as a "
            "scan's untriangulated points do: their base lies on that part's surface")


def _whole(x: float) -> int:
    """The whole number at or above ``x``, without the float noise of a power (8 / 0.02**2 is
    20000.000000000004, not 20001)."""
    return int(np.ceil(x * (1 - 1e-12)))


def count_words(count: int) -> str:
    """A vertex count as an artist reads it: exact below a million, else rounded in words."""
    if count < 1_000_000:
        return str(count)
    for size, word in ((1e12, None), (1e9, "billion"), (1e6, "million")):
        if count >= size:
            return f"about {count / size:.3g} {word}" if word else "more than a trillion"
    return str(count)  # (not reached)


def levels_that_fit(n: int, levels: int, decimation: float, min_coarse: int,
                    parts: bool = False, safe: int = 100, max_decimation: float = 0.9) -> tuple[int, str | None]:
    """The most levels (at most `levels`) whose coarsest keeps min_coarse of n points at this
    decimation, and what to tell the artist when that is fewer than asked: (levels, message).
    The message's hint gives a level 0 of at least ``safe`` points (the engine calls a coarser
    base distorted): a Decimation up to ``max_decimation`` (the panel's), else fewer levels.
    With ``parts`` (Keep Parts Apart), n is the vertex count of the largest connected part that
    is not flat: each part is decomposed alone, and a flat one keeps no bands, so that part
    bounds the levels, not the whole mesh.
    Raises ValueError when not even a base and one band fit."""
    def keeps(count: int, at: float, least: int) -> bool:
        return np.floor(at ** (count - 1) * n) >= least

    what = "the largest part of the mesh that is not flat" if parts else "the mesh"
    apart = (", or turn off Keep Parts Apart to decompose the parts as one surface" if parts else "")
    fitting = max((count for count in range(2, levels + 1) if keeps(count, decimation, min_coarse)), default=0)
    if fitting == levels:
        return levels, None
    need = count_words(_whole(min_coarse / decimation ** (levels - 1)))
    if fitting < 2:
        least = count_words(_whole(min_coarse / decimation))
        raise ValueError(f"{what} has {n} vertices, and even 2 levels at Decimation {decimation:g} need {least} vertices: "
                         f"subdivide it (a Subdivision Surface modifier, applied) or decompose a denser mesh{apart}")
    wanted = _whole(100 * (safe / n) ** (1.0 / (levels - 1))) / 100
    while wanted <= max_decimation and not keeps(levels, wanted, safe):
        wanted = round(wanted + 0.01, 2)
    safe_levels = max((count for count in range(2, levels) if keeps(count, decimation, safe)), default=0)
    if wanted <= max_decimation:
        hint = f"raise Decimation to {wanted:g} (then level 0 keeps at least {safe} points)"
    elif safe_levels:
        hint = f"use {safe_levels} levels (then level 0 keeps at least {safe} points)"
    else:
        hint = "use fewer levels"
    return fitting, (f"{what} has {n} vertices, and {levels} levels at Decimation {decimation:g} need {need} vertices: "
                     f"decomposed with {fitting} levels. For {levels}, subdivide the mesh (a Subdivision Surface "
                     f"modifier, applied) or {hint}{apart}")


PARTS_REFUSAL = "every connected part is too small"  # how the engine's refusal of too small parts begins
# ... and of parts too small where the larger ones are flat (a ground plane beside a small rock)
FLAT_PARTS_REFUSAL = "no connected part large enough to decompose spans a surface"


def is_parts_refusal(message: str) -> bool:
    return message.startswith(PARTS_REFUSAL) or message.startswith(FLAT_PARTS_REFUSAL)


def parts_message(message: str, neighbors: int, levels: int) -> str:
    """The engine's refusal of a mesh whose connected parts are all too small, in the add-on's
    terms (the Neighbours and Levels settings, the Keep Parts Apart option) rather than the
    engine's (faces and edges, levels=N); any other message as it is. Each part is decomposed
    alone, so its levels need Neighbours support points of that part, and the engine's counts
    alone can read as a contradiction (a largest part of 441 points refused where 32 are needed)."""
    if message.startswith(FLAT_PARTS_REFUSAL):
        return message.replace("decompose without faces and edges to treat the parts as one surface",
                               "turn off Keep Parts Apart to decompose the parts as one surface")
    if not is_parts_refusal(message):
        return message
    found = re.search(r"the largest has (\d+) points", message)
    largest = f" (the largest has {found.group(1)} vertices)" if found else ""
    return (f"every connected part of the mesh is too small to decompose alone{largest} with Levels {levels} "
            f"and Neighbours {neighbors}: Keep Parts Apart decomposes each part by itself. Lower Neighbours "
            "or Levels, or turn off Keep Parts Apart to decompose the parts as one surface")


PLANAR_HINT = " (use project() to work with planar data)"  # the engine's hint for Python users
# The engine's keywords for the panel's settings: (the panel's label, {engine value: the panel's item}).
PANEL_NAMES = {
    "smoother": ("Smoother", {"mls": "MLS Projection", "diffusion": "Diffusion"}),
    "encoding": ("Encoding", {"projection": "Projection", "rayshoot": "Ray Shooting"}),
}
SHEETS_REFUSAL = "sheets=True keeps thin sheets apart with"  # how the engine's refusal of other methods begins
SHEETS_METHODS = {"smoother": "mls", "encoding": "projection"}  # the methods Keep Thin Sheets Apart works with


def engine_message(message: str, neighbors: int, levels: int) -> str:
    """The engine's refusal in the add-on's terms: parts_message, thin sheets' refusals with the
    panel's names instead of Python keywords, and a flat mesh's refusal without the hint meant
    for Python users."""
    if PLANAR_HINT in message:
        return message.replace(PLANAR_HINT, ". A flat mesh is all base: give it relief (sculpt it, or apply a "
                                             "Displace modifier) to have detail to edit")
    if message.startswith(SHEETS_REFUSAL):
        return sheets_message(message)
    message = MIRROR_SEAM_HINT.sub(_mirror_seam_in_blender_words, message)
    return parts_message(message, neighbors, levels).replace("sheets=True", "Keep Thin Sheets Apart")


#: The engine's hint for a half with points across its mirror plane, in Python's terms.
MIRROR_SEAM_HINT = re.compile(r"\(or a seam of at least ([0-9.e+-]+) if those points belong on the plane\)")


def _mirror_seam_in_blender_words(match) -> str:
    """The seam a Mirror modifier gives is half its Merge distance (mirror_modifier.mirror_planes)."""
    return (f"(or, if those vertices belong on the plane, set the Mirror modifier's Merge distance to at least "
            f"{2.0 * float(match.group(1)):.3g})")


def _panel_setting(keyword: str, value: str) -> str:
    label, items = PANEL_NAMES[keyword]
    return f"{label}: {items.get(value, value)}"


def sheets_message(message: str) -> str:
    """The engine's refusal of Keep Thin Sheets Apart with another smoother or encoding, naming
    the settings as the Decompose panel shows them."""
    asked = dict(re.findall(r"(smoother|encoding)='(\w+)'", message))
    other = [_panel_setting(keyword, value) for keyword, value in asked.items() if value != SHEETS_METHODS[keyword]]
    needed = " and ".join(_panel_setting(keyword, value) for keyword, value in SHEETS_METHODS.items())
    return (f"Keep Thin Sheets Apart works with {needed} only; {' and '.join(other) or 'these settings'} would blend "
            "the two sides of a wall. Switch to them, or turn Keep Thin Sheets Apart off")


def faces_wound_against_neighbours(loops, starts, totals) -> int:
    """How many faces are wound against a neighbour: they run along a shared edge in the same
    direction as the face on its other side (consistently wound faces run it both ways). A patch
    of flipped faces counts the faces along its border. loops: each loop's vertex; starts,
    totals: each face's first loop and loop count (Blender's polygons)."""
    loops = np.asarray(loops, dtype=np.int64)
    starts = np.asarray(starts, dtype=np.int64)
    totals = np.asarray(totals, dtype=np.int64)
    if not len(starts):
        return 0
    face = np.repeat(np.arange(len(starts)), totals)
    position = np.arange(len(face)) - starts[face]
    following = loops[starts[face] + (position + 1) % totals[face]]
    keep = loops != following
    face, edges = face[keep], loops[keep] * (int(loops.max()) + 1) + following[keep]
    _, inverse, counts = np.unique(edges, return_inverse=True, return_counts=True)
    return int(np.unique(face[counts[inverse.reshape(-1)] > 1]).size)


def winding_message(count: int, total: int) -> str | None:
    """The warning for Keep Thin Sheets Apart over faces wound against their neighbours, whose
    vertex normals point the wrong way there: it tells a sheet's sides by them, and the base tears."""
    if count <= 0:
        return None
    return (f"{count} of {total} faces are wound against a neighbouring face (flipped faces): Keep Thin Sheets Apart "
            "tells a sheet's sides by the normals, so the base may tear there. In Edit Mode select all, use "
            "Mesh > Normals > Recalculate Outside, and Decompose again")


MORPH_TOO_FEW = re.compile(r"^(points_a|points_b|base_points) has (\d+) points; at least (\d+) are needed")


def morph_message(message: str, a_name: str, b_name: str, base_name: str | None = None) -> str:
    """The engine's refusal of a morph in the panel's terms: which object, in vertices, rather
    than its keyword (points_a, points_b, base_points)."""
    which = {"points_a": f"object A '{a_name}'", "points_b": f"target B '{b_name}'",
             "base_points": f"base object '{base_name}'"}
    found = MORPH_TOO_FEW.match(message)
    if found is not None:
        return f"{which[found.group(1)]} has {found.group(2)} vertices; Morph needs at least {found.group(3)}"
    empty = re.match(r"^(points_a|points_b|base_points) is empty", message)
    if empty is not None:
        return f"{which[empty.group(1)]} has no vertices" + message[empty.end():]
    # Any other refusal names the keyword too ("all points_b are identical: they define no surface").
    return re.sub(r"\b(points_a|points_b|base_points)\b", lambda m: f"the vertices of {which[m.group(1)]}", message)


def keys_in_layout_order(names: list, layout: list, new: set) -> list:
    """The shape key list ``names`` as a Decompose leaves it: the keys of ``layout`` (Level 0..k-1,
    Band 0..k-1) in layout order, each key it added (``new``, at the end of the list) right after
    the one before it in the layout (Level 2 after Level 1, Band 2 after Band 1), so that the
    artist's keys keep their places beside the add-on's. Blender adds a key at the end: a
    Decompose with more levels than the one before gave Basis, Level 0, Level 1, Band 0, Band 1,
    Level 2, Band 2."""
    out = [name for name in names if name not in new]
    for i, name in enumerate(layout):
        if name not in new:
            continue
        before = layout[i - 1] if i > 0 else None
        out.insert(out.index(before) + 1 if before in out else len(out), name)
    # The layout's keys in layout order in the places they hold (an older add-on may have left
    # them otherwise); every other key keeps its place.
    wanted = set(layout)
    slots = [i for i, name in enumerate(out) if name in wanted]
    ordered = [name for name in layout if name in out]
    for slot, name in zip(slots, ordered):
        out[slot] = name
    return out


def moves_up(names: list, target: list) -> list:
    """How to turn the list ``names`` into ``target`` (the same names) by moving one entry up one
    place at a time, as Blender's Move Shape Key does: the index of the entry to move, each time.
    The first entry (the Basis) is never moved past."""
    names, moves = list(names), []
    for p in range(1, len(target)):
        q = names.index(target[p])
        while q > p:
            moves.append(q)
            names[q - 1], names[q] = names[q], names[q - 1]
            q -= 1
    return moves

