"""Connected parts: a mesh's faces or edges keep its parts apart.

Eyes, teeth, hair cards and clothing layers are separate parts of one mesh. A point-based fit
blends parts that lie closer than its kernel, so with connectivity `decompose` decomposes each
part alone and joins the results into one Decomposition: no part's points weigh in another's
fits, clusters or normals, and an edit of one part's base leaves the others as they were.

A part too small for the levels asked keeps the levels its own resolution supports: its
coarser levels repeat its smoothest one (its bands there are zero), and a warning names it.
"""
from __future__ import annotations

import warnings

import numpy as np

from . import _core

#: A part other than the leading one (decompose_parts) keeps a level only if it has this many
#: support points there.
#: Measured on boxes, the worst case for a coarse level (tests/test_parts.py holds the bound):
#: a box's level 0 strays from the input by about 1.6 / sqrt(support points) of its diagonal,
#: 7% with 384 points, 12% with 216; 320 keeps it near 9%.
PART_COARSE_POINTS = 320
_TOO_FEW = "too few points for the coarser levels"
#: How many parts a warning names before it says "and N more".
_NAMED_IN_WARNING = 5


def connectivity_pairs(n: int, faces=None, edges=None) -> np.ndarray | None:
    """The vertex pairs that faces and edges join, (m, 2) int32, or None when neither is given.

    faces  (f, k) integer array (k >= 2), or a list of index sequences of any lengths (polygons)
    edges  (e, 2) integer array
    Every index must be a vertex of the n points.
    """
    pieces = []
    if faces is not None:
        pieces.append(_face_pairs(faces))
    if edges is not None:
        e = _integers(edges, "edges")
        if e.ndim != 2 or e.shape[1] != 2:
            raise ValueError(f"edges must have shape (m, 2), got {e.shape}")
        pieces.append(e)
    if not pieces:
        return None
    pairs = np.concatenate(pieces) if len(pieces) > 1 else pieces[0]
    if pairs.size and (pairs.min() < 0 or pairs.max() >= n):
        what = "faces and edges" if len(pieces) > 1 else ("faces" if faces is not None else "edges")
        raise ValueError(f"{what} must hold vertex indices in [0, {n - 1}], got [{pairs.min()}, {pairs.max()}]")
    return np.ascontiguousarray(pairs, dtype=np.int32)


def connected_parts(points, faces=None, edges=None, *, threads: int = 0) -> tuple[np.ndarray, int]:
    """The parts that faces or edges connect: (labels (n,) int32, count).

    Vertices at one position are one vertex here: a mesh split along its UV seams or hard edges
    (as glTF, FBX and game assets are), whose copies of a vertex lie in different faces, is one
    part (see COINCIDENT for how close counts as one position).
    Parts are numbered in the order of their lowest vertex in a face or edge. A vertex in no
    face or edge (a scan's untriangulated point) joins the part of its nearest vertex that is
    in one; with no faces and no edges everything is one part. threads: as decompose's.
    """
    from ._checks import as_points, thread_option
    p = as_points(points)
    pairs = connectivity_pairs(len(p), faces, edges)
    if pairs is None:
        return np.zeros(len(p), dtype=np.int32), 1
    if len(pairs):
        pairs = np.concatenate([pairs, coincident_pairs(p, np.unique(pairs))]).astype(np.int32, copy=False)
    labels, count = _core.connected_parts(p, np.ascontiguousarray(pairs), threads=thread_option(threads))
    return labels, int(count)


#: Vertices this close, as a fraction of the bounding-box diagonal of the vertices in faces and
#: edges, are at one position for connected_parts. The copies of a split vertex are written from
#: one value, so they are usually exactly equal; after single-precision storage and arithmetic
#: they may differ by a unit or two in the last place of a float32 coordinate, which is at most
#: 2**-23 of a coordinate of the diagonal's size. 2**-22 covers that and stays far below any
#: mesh's vertex spacing (a million-vertex surface has a spacing near 1e-3 of its diagonal).
#: Vertices up to 2 * sqrt(3) times this apart may be joined (coincident_pairs), still below the
#: mirror's default seam: a point off a mirror plane and its reflection are at least 2.02e-6 of
#: the half's diagonal apart (pointscale.mirror), so they are not joined unless the whole model
#: is over 4 times the half's size or the seam was set smaller; joined, they would only be one
#: part, as a part that crosses the plane is.
COINCIDENT = 2.0 ** -22


def coincident_pairs(p: np.ndarray, among: np.ndarray) -> np.ndarray:
    """(m, 2) pairs of the vertices `among` (indices into p) that are at one position: every two
    within COINCIDENT * diagonal of each other along each axis are joined (through others of
    their group), and none farther apart than 2 * sqrt(3) of that."""
    q = p[among]
    if len(q) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    lo = q.min(axis=0)
    diagonal = float(np.linalg.norm(q.max(axis=0) - lo))
    if not diagonal > 0.0:  # all at one position
        return np.stack([np.full(len(among) - 1, among[0]), among[1:]], axis=1).astype(np.int64)
    cell = 2.0 * COINCIDENT * diagonal
    scaled = (q - lo) / cell  # at most 2**21 cells along an axis
    # One int64 key per cell: the cell counts' product is below 2**61, since the extents'
    # product is at most (diagonal / sqrt(3))**3.
    counts = np.floor(scaled.max(axis=0)).astype(np.int64) + 2
    found = []
    # Two grids along each axis, the second shifted by half a cell: two vertices closer than half
    # a cell along an axis share a cell of one of them, so of one of the 8 combinations.
    for shift in range(8):
        cells = np.floor(scaled + [0.5 * ((shift >> a) & 1) for a in range(3)]).astype(np.int64)
        key = (cells[:, 0] * counts[1] + cells[:, 1]) * counts[2] + cells[:, 2]
        order = np.argsort(key)  # any order of equal keys joins the same vertices
        same = np.flatnonzero(key[order[1:]] == key[order[:-1]])
        if same.size:
            found.append(np.stack([order[same], order[same + 1]], axis=1))
    if not found:
        return np.zeros((0, 2), dtype=np.int64)
    return among[np.concatenate(found)].astype(np.int64)


def _integers(a, what: str) -> np.ndarray:
    try:
        arr = np.asarray(a)
    except Exception:
        raise ValueError(f"{what} must be an array of vertex indices") from None
    if arr.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if arr.dtype.kind not in "iu":
        raise ValueError(f"{what} must hold integer vertex indices, got dtype {arr.dtype}")
    if arr.dtype.kind == "u" and arr.max() > np.iinfo(np.int64).max:  # would wrap to a negative index
        raise ValueError(f"{what} must hold vertex indices, got {arr.max()}")
    return arr.astype(np.int64, copy=False)


def _face_pairs(faces) -> np.ndarray:
    """Each face's first corner paired with each of its others: enough to join its corners."""
    if isinstance(faces, np.ndarray) and faces.dtype != object:
        f = _integers(faces, "faces")
        if f.size == 0:
            return np.zeros((0, 2), dtype=np.int64)
        if f.ndim != 2 or f.shape[1] < 2:
            raise ValueError(f"faces must have shape (m, k) with k >= 2 corners, or be a list of polygons, "
                             f"got {f.shape}")
        first = np.repeat(f[:, :1], f.shape[1] - 1, axis=1)
        return np.stack([first.ravel(), f[:, 1:].ravel()], axis=1)
    try:
        polygons = [np.asarray(face) for face in faces]
    except TypeError:
        raise ValueError("faces must be an (m, k) array or a list of index sequences") from None
    if not polygons:
        return np.zeros((0, 2), dtype=np.int64)
    if any(poly.ndim != 1 for poly in polygons):
        raise ValueError("each face must be a flat sequence of vertex indices")
    empty = [i for i, poly in enumerate(polygons) if poly.size == 0]
    if empty:
        raise ValueError(f"{len(empty)} of the {len(polygons)} faces {'is' if len(empty) == 1 else 'are'} empty "
                         f"(no vertex indices; the first is face {empty[0]}): a face joins at least one vertex")
    flat = _integers(np.concatenate(polygons), "faces")
    lengths = np.array([len(poly) for poly in polygons])
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    first = np.repeat(flat[starts[lengths > 0]], lengths[lengths > 0])
    return np.stack([first, flat], axis=1)


def levels_kept(sizes: np.ndarray, levels: int, decimation: float, neighbors: int, minimum: int,
                leading: int | None = None) -> np.ndarray:
    """Per part, how many of the levels asked its own resolution supports (1: the part itself
    only, with no bands). The leading part (the largest that spans a surface; by default the
    largest), and any as large, keeps them all: it is decomposed exactly as it would be alone,
    whatever other parts come with it (decompose_parts refuses the call, as decompose refuses
    that part alone, when it is too small for them). Any other part needs PART_COARSE_POINTS
    support points at its coarsest level."""
    kept = np.ones(len(sizes), dtype=np.int64)
    for count in range(2, levels + 1):
        coarse = np.floor(decimation ** (count - 1) * sizes.astype(np.float64))
        kept[coarse >= max(minimum, neighbors, PART_COARSE_POINTS)] = count
    if len(sizes):
        kept[sizes >= (sizes.max() if leading is None else sizes[leading])] = max(levels, 1)
    return kept


def decompose_parts(p: np.ndarray, normals, labels: np.ndarray, count: int, levels: int, decimation: float,
                    neighbors: int, minimum: int, decompose_one, progress, origin: np.ndarray, threads: int = 0,
                    parts_out: list | None = None):
    """Decomposes each part alone and joins them: (model arrays, stats, part reports).
    threads: for the parts too small to decompose, which are joined here.

    decompose_one(points, normals, levels, progress) -> Decomposition decomposes one part.
    The leading part (the largest that spans a surface) is decomposed first and exactly as it
    would be alone: with every level asked, or not at all (ValueError) when it is too small for
    them.
    """
    order = np.argsort(labels, kind="stable")
    sizes = np.bincount(labels, minlength=count)
    bounds = np.concatenate([[0], np.cumsum(sizes)])
    need = _core.points_needed(_core.DecomposeOptions(levels=levels, decimation=decimation))
    by_size = sorted(range(count), key=lambda q: (-sizes[q], q))
    leading, flat = _leading_part(p, order, bounds, by_size, need)
    if leading is None:
        if flat:
            raise ValueError("no connected part large enough to decompose spans a surface (each is flat or on a "
                             f"line): there is no detail to separate from a base. With levels={levels}, a part "
                             f"needs at least {need} points (as it would alone): use fewer levels, or decompose "
                             "without faces and edges to treat the parts as one surface")
        raise ValueError(f"every connected part is too small to decompose with levels={levels}: the largest has "
                         f"{sizes.max()} points, and levels={levels} needs at least {need} (as it would alone). "
                         "Use fewer levels, or decompose without faces and edges to treat the parts as one surface")
    kept = levels_kept(sizes, levels, decimation, neighbors, minimum, leading)
    n, k = len(p), levels - 1
    total = float(n)
    done = 0
    parts = [None] * count
    # Each joined level holds one neighbourhood width: the first decomposed part's (the
    # leading one's, as it has them alone). A coarse level of it with fewer clusters than
    # `neighbors` has narrower neighbourhoods, which a smaller part's levels cannot share.
    widths = None
    for part in [leading] + [q for q in by_size if q != leading]:  # the leading part first
        idx = order[bounds[part]:bounds[part + 1]]  # ascending: argsort is stable
        points = p[idx]
        reason = None
        if kept[part] >= 2 and part != leading and (part in flat or not _spans_surface(points)):
            reason = "it spans no surface (its points are on a line or a plane)"
            kept[part] = 1
        if kept[part] >= 2 and widths is not None and kept[part] < levels and min(widths) < neighbors:
            reason = (f"levels={levels} leave the leading part only {min(widths)} support points at its coarsest "
                      f"level, fewer than neighbors={neighbors}, which the other parts' levels would need; "
                      "use fewer levels")
            kept[part] = 1
        dec = None
        if kept[part] >= 2:
            sub = None
            if progress is not None:
                start, weight = done / total, len(idx) / total
                sub = (lambda f, s=start, w=weight: progress(s + w * f))
            try:
                dec = decompose_one(points, None if normals is None else normals[idx], int(kept[part]), sub)
            except ValueError as exc:
                raise ValueError(f"part {part} ({len(idx)} points, first vertex {idx[0]}): {exc}") from None
            if widths is None:
                a = dec._model.to_arrays()
                widths = [int(a[f"neighborhoods_{max(l - (k - dec.n_bands), 0)}"].shape[1]) for l in range(k)]
        parts[part] = (idx, dec, reason)
        done += len(idx)
        if progress is not None and progress(done / total) is False:
            raise _core.Cancelled("cancelled")
    if all(dec is None for _, dec, _ in parts):
        raise ValueError("no connected part large enough to decompose spans a surface (each is flat or on a line): "
                         "there is no detail to separate from a base")
    arrays = _joined(p, normals, parts, k, widths, origin, threads)
    arrays["parts"] = np.ascontiguousarray(labels, dtype=np.int32)
    reports = [_part_report(part, idx, dec, reason, levels, p) for part, (idx, dec, reason) in enumerate(parts)]
    stats = _joined_stats(parts, k, leading)
    if parts_out is not None:  # (point indices, Decomposition or None, reason) per part
        parts_out.extend(parts)
    return arrays, stats, reports


def leading_points(reports: list[dict]) -> int:
    """The point count of the leading part, from decompose's part reports (dec.parts): the
    largest of those that keep the most levels. Level 0's coarseness is its."""
    most = max(r["levels"] for r in reports)
    return max(r["points"] for r in reports if r["levels"] == most)


def leading_part(p: np.ndarray, labels: np.ndarray, count: int) -> int | None:
    """The part that decompose_parts decomposes first, with every level: the largest that spans
    a surface (None: none does). p #P by 3; labels, count from connected_parts."""
    order = np.argsort(labels, kind="stable")
    sizes = np.bincount(labels, minlength=count)
    bounds = np.concatenate([[0], np.cumsum(sizes)])
    return _leading_part(p, order, bounds, sorted(range(count), key=lambda q: (-sizes[q], q)), 4)[0]


def _leading_part(p, order, bounds, by_size, at_least: int) -> tuple[int | None, set]:
    """(the largest part of at least at_least points that spans a surface, or None; the larger
    parts found flat on the way). It keeps every level and sets the joined levels' widths. A flat
    part (a ground plane under a rock) keeps no bands, however large: leading, it left the
    surface parts only the levels their own sizes support."""
    flat = set()
    for part in by_size:
        if bounds[part + 1] - bounds[part] < at_least:
            break
        if _spans_surface(p[order[bounds[part]:bounds[part + 1]]]):
            return part, flat
        flat.add(part)
    return None, flat


def _spans_surface(points: np.ndarray) -> bool:
    from ._checks import require_surface
    try:
        require_surface(points)
    except ValueError:
        return False
    return True


def _joined(p, normals, parts, k, widths, origin, threads) -> dict:
    """One model's arrays from the parts' (see to_dict): each part's clusters follow the
    previous part's, and a part with fewer bands takes its smoothest level's support for the
    coarser levels, where its bands are zero. widths: each level's neighbourhood width."""
    n = len(p)
    base = np.empty((n, 3))
    details = np.zeros((k, n))
    base_normals = np.empty((n, 3))
    labels = np.empty((k, n), dtype=np.int32)
    local = [np.zeros((n, 3)) for _ in range(k)]
    per_level = [dict(neighborhoods=[], kernel=[], anchors=[], frames=[]) for _ in range(k)]
    offsets = [0] * k
    # Frozen parts' kernel widths only shape normals that displace nothing: the largest
    # decomposed part's median width at each level serves.
    main = max((dec for _, dec, _ in parts if dec is not None), key=lambda d: d.n_points)
    kernel_scale = [float(main.stats[max(l - (k - main.n_bands), 0)]["kernel_width"]) for l in range(k)]
    for idx, dec, _ in parts:
        if dec is None:
            continue
        a = dec._model.to_arrays()
        kp = dec.n_bands
        shift = k - kp
        base[idx] = a["base"] + (dec.origin - origin)
        base_normals[idx] = a["base_normals"]
        details[shift:, idx] = a["details"]
        for l in range(k):
            own = max(l - shift, 0)
            c = len(a[f"kernel_{own}"])
            if a[f"neighborhoods_{own}"].shape[1] != widths[l]:
                raise ValueError(f"a part has {a[f'neighborhoods_{own}'].shape[1]} neighbours per cluster at level "
                                 f"{l}, not {widths[l]}")  # decompose_parts should never allow it
            labels[l, idx] = a["labels"][own] + offsets[l]
            local[l][idx] = a[f"local_{own}"]
            per_level[l]["neighborhoods"].append(a[f"neighborhoods_{own}"] + offsets[l])
            per_level[l]["kernel"].append(a[f"kernel_{own}"])
            per_level[l]["anchors"].append(idx[a[f"anchors_{own}"]])
            per_level[l]["frames"].append(a[f"frames_{own}"] + offsets[l])
            offsets[l] += c
    frozen = [idx for idx, dec, _ in parts if dec is None]
    if frozen:
        _frozen_parts(p, normals, frozen, k, widths, kernel_scale, origin, base, base_normals, labels, per_level,
                      offsets, threads)
    out = dict(base=base, details=details, base_normals=base_normals, labels=labels)
    for l in range(k):
        out[f"neighborhoods_{l}"] = np.ascontiguousarray(np.concatenate(per_level[l]["neighborhoods"]), np.int32)
        out[f"kernel_{l}"] = np.concatenate(per_level[l]["kernel"])
        out[f"anchors_{l}"] = np.ascontiguousarray(np.concatenate(per_level[l]["anchors"]), np.int32)
        out[f"frames_{l}"] = np.ascontiguousarray(np.concatenate(per_level[l]["frames"]), np.int32)
        out[f"local_{l}"] = local[l]
    return out


def _frozen_parts(p, normals, frozen, k, widths, kernel_scale, origin, base, base_normals, labels, per_level,
                  offsets, threads) -> None:
    """The parts with no bands, all at once: every level is the part itself. Each point is its
    own cluster, with its nearest points of its part as neighbours, so that its normals are
    fitted on the part alone; they only orient it, since nothing is displaced along them.
    frozen: each such part's point indices. Their clusters follow all the others'; their
    neighbourhoods take each level's width (the nearest first, so a narrower one is a prefix)."""
    idx = np.concatenate(frozen)
    part = np.repeat(np.arange(len(frozen)), [len(f) for f in frozen]).astype(np.int32)
    points = np.ascontiguousarray(p[idx])
    m = len(idx)
    base[idx] = points - origin
    base_normals[idx] = _part_normals(points, part, len(frozen), None if normals is None else normals[idx])
    rows = _core.knn_within_parts(points, part, k=max(widths), threads=threads).astype(np.int64)
    own = np.arange(m)
    for l in range(k):
        labels[l, idx] = offsets[l] + own
        per_level[l]["neighborhoods"].append(rows[:, :widths[l]] + offsets[l])
        per_level[l]["kernel"].append(np.full(m, kernel_scale[l]))
        per_level[l]["anchors"].append(idx)
        per_level[l]["frames"].append(np.repeat((offsets[l] + own)[:, None], 2, axis=1))
        offsets[l] += m


def _part_normals(points: np.ndarray, part: np.ndarray, count: int, normals) -> np.ndarray:
    """Unit normals for parts with no bands: the given ones where usable, else each part's
    least-spread direction, pointing away from its centre. part: (m,) the part of each point."""
    size = np.bincount(part, minlength=count).astype(np.float64)
    centre = np.stack([np.bincount(part, points[:, a], count) for a in range(3)], axis=1) / size[:, None]
    spread = points - centre[part]
    cov = np.zeros((count, 3, 3))
    for a in range(3):
        for b in range(a, 3):
            cov[:, a, b] = cov[:, b, a] = np.bincount(part, spread[:, a] * spread[:, b], count)
    axis = np.linalg.eigh(cov)[1][:, :, 0]  # the eigenvector of the smallest spread, per part
    out = axis[part]
    out[(spread * out).sum(axis=1) < 0] *= -1.0
    if normals is not None:
        length = np.linalg.norm(normals, axis=1)
        good = length > 0
        out[good] = normals[good] / length[good, None]
    return out


def _part_report(part: int, idx: np.ndarray, dec, reason, levels: int, p: np.ndarray) -> dict:
    kept = dec.n_levels if dec is not None else 1
    lo, hi = p[idx].min(axis=0), p[idx].max(axis=0)
    return dict(part=part, points=int(len(idx)), first_vertex=int(idx[0]), levels=int(kept),
                centre=[float(v) for v in 0.5 * (lo + hi)], size=float(np.linalg.norm(hi - lo)),
                why=reason or ("" if kept == levels else _TOO_FEW))


def _joined_stats(parts, k: int, leading: int) -> list[dict]:
    """The model's per-level report: counts summed over the parts, the kernel width of the
    leading part, the worst consistency figures."""
    stats = []
    for l in range(k):
        row = dict(support_points=0, kernel_width=0.0, not_converged=0, degenerate=0, consistency_iterations=0,
                   consistency_residual=0.0, pinned=0)
        for part, (idx, dec, _) in enumerate(parts):
            if dec is None:
                row["support_points"] += len(idx)
                continue
            own = max(l - (k - dec.n_bands), 0)
            s = dec.stats[own]
            for key in ("support_points", "not_converged", "degenerate", "pinned"):
                row[key] += int(s[key])
            row["consistency_iterations"] = max(row["consistency_iterations"], int(s["consistency_iterations"]))
            row["consistency_residual"] = max(row["consistency_residual"], float(s["consistency_residual"]))
            if part == leading:
                row["kernel_width"] = float(s["kernel_width"])
        stats.append(row)
    return stats


def parts_warning(reports: list[dict], levels: int) -> str | None:
    """The warning that names the parts keeping fewer levels than asked, or None."""
    short = [r for r in reports if r["levels"] < levels]
    if not short:
        return None
    short.sort(key=lambda r: -r["points"])
    named = "; ".join(_described(r) for r in short[:_NAMED_IN_WARNING])
    more = len(short) - _NAMED_IN_WARNING
    if more > 0:  # the rest are no larger than the last named: "smaller" only if none is as large
        smaller = all(r["points"] < short[_NAMED_IN_WARNING - 1]["points"] for r in short[_NAMED_IN_WARNING:])
        tail = f"; and {more} {'smaller' if smaller else 'more'} part{'s' if more > 1 else ''}"
    else:
        tail = ""
    verb, their, its = ("are", "Their", "their") if len(short) > 1 else ("is", "Its", "its")
    return (f"{len(short)} of {len(reports)} connected parts {verb} too small for levels={levels}: {named}{tail}. "
            f"{their} coarser levels repeat {its} smoothest one, so {its} bands there are zero.")


def _described(r: dict) -> str:
    c = ", ".join(f"{v:.4g}" for v in r["centre"])
    kept = f"keeps {r['levels']} levels" if r["levels"] > 1 else "keeps no bands"
    why = f" ({r['why']})" if r["why"] and r["why"] != _TOO_FEW else ""
    count = f"{r['points']} point{'s' if r['points'] != 1 else ''}"
    return f"part {r['part']} ({count} from vertex {r['first_vertex']}, around ({c})) {kept}{why}"
