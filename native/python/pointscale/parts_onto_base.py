"""Connected parts for encode and morph: each part of a model goes onto the base alone.

encode(..., faces=, edges=) encodes every connected part of the model onto the base by itself
and joins the results as decompose does (pointscale.parts): no part's projections weigh in
another's clusters or normals, so an edit of one part's base leaves the others as they were.
morph(..., faces_a=, faces_b=, ...) morphs part i of A into part i of B (parts are numbered by
their lowest vertex, so two versions of one character's mesh match), each pair alone, so that
B's offsets are never carried from one part onto another.
"""
from __future__ import annotations

import warnings

import numpy as np

from .parts import connected_parts, decompose_parts, parts_warning

#: encode keeps no decimation of the model: a part needs its own support points at full size.
_NO_DECIMATION = 1.0
#: morph warns when two paired parts' sizes (bounding-box diagonals, each as a share of its
#: model's) differ by more than this factor: a morph may grow a part, but not by this much
#: without a reason to check, and a head paired with an eye differs by 5.
PAIRED_SIZE_RATIO = 2.0


def encode_by_part(p: np.ndarray, labels: np.ndarray, count: int, encode_one, neighbors: int, minimum: int,
                   progress, origin: np.ndarray, threads: int = 0):
    """(model arrays, stats, part reports, warning) of encode_one(points, progress) for each part."""
    def one(points, _normals, _levels, part_progress):
        return encode_one(points, part_progress)

    arrays, stats, reports = decompose_parts(p, None, labels, count, 2, _NO_DECIMATION, neighbors, minimum, one,
                                             progress, origin, threads=threads)
    return arrays, stats, reports, parts_warning(reports, 2)


def matched_parts(a: np.ndarray, b: np.ndarray, faces_a, edges_a, faces_b, edges_b, threads: int = 0):
    """The parts of A and of B, matched by number: (labels_a, labels_b, count). Raises ValueError
    when only one model has connectivity, or when their part counts differ."""
    given_a = faces_a is not None or edges_a is not None
    given_b = faces_b is not None or edges_b is not None
    if given_a != given_b:
        raise ValueError("morph keeps parts apart only with the connectivity of both models: give faces or edges "
                         "for A and for B, or for neither")
    labels_a, count_a = connected_parts(a, faces_a, edges_a, threads=threads)
    labels_b, count_b = connected_parts(b, faces_b, edges_b, threads=threads)
    if count_a != count_b:
        raise ValueError(f"A has {count_a} connected parts and B has {count_b}: morph matches part i of A with part "
                         "i of B, so both need the same parts (or morph them without faces and edges)")
    if count_a > 1:
        message = pairing_warning(a, labels_a, b, labels_b, count_a)
        if message:
            warnings.warn(message, stacklevel=3)
    return labels_a, labels_b, count_a


def _part_sizes(p: np.ndarray, labels: np.ndarray, count: int):
    """Each part's (points, first vertex, bounding-box diagonal as a share of the model's), in one
    pass over the points (a model may hold thousands of parts)."""
    whole = max(float(np.linalg.norm(p.max(axis=0) - p.min(axis=0))), np.finfo(float).tiny)
    order = np.argsort(labels, kind="stable")
    sizes = np.bincount(labels, minlength=count)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    q = p[order]
    lo, hi = np.minimum.reduceat(q, starts, axis=0), np.maximum.reduceat(q, starts, axis=0)
    diagonals = np.linalg.norm(hi - lo, axis=1) / whole
    return [(int(sizes[i]), int(order[starts[i]]), float(diagonals[i])) for i in range(count)]


def pairing_warning(a, labels_a, b, labels_b, count: int) -> str | None:
    """The warning for parts that morph pairs by number (by lowest vertex) although their sizes
    differ by more than PAIRED_SIZE_RATIO, as when B lists its parts in another order; or None.
    It names the pairs and the pairing by size where that differs."""
    sa, sb = _part_sizes(a, labels_a, count), _part_sizes(b, labels_b, count)
    tiny = 1e-12  # a part of one point has no size
    ratio = [max(x[2], tiny) / max(y[2], tiny) for x, y in zip(sa, sb)]
    bad = [i for i, r in enumerate(ratio) if max(r, 1.0 / r) > PAIRED_SIZE_RATIO]
    if not bad:
        return None

    def said(model, part, size):
        return f"{model}'s part {part} ({size[0]} points from vertex {size[1]}, {size[2]:.2g} of {model}'s size)"

    named = "; ".join(f"{said('A', i, sa[i])} with {said('B', i, sb[i])}" for i in bad[:5])
    more = f"; and {len(bad) - 5} more" if len(bad) > 5 else ""
    # The pairing by size compares every part of A with every part of B: said up to 2000 parts.
    ra, rb = (np.maximum([x[2] for x in s], tiny) for s in (sa, sb))
    by_size = np.abs(np.log(ra[:, None] / rb[None, :])).argmin(axis=1).tolist() if count <= 2000 else []
    hint = ""
    if len(set(by_size)) == count and by_size != list(range(count)):
        pairs = ", ".join(f"A's {i} with B's {j}" for i, j in enumerate(by_size) if i != j)
        hint = f" By size, the pairs would be {pairs}."
    return (f"morph pairs part i of A with part i of B (parts numbered by their lowest vertex), and {len(bad)} "
            f"pair{'s differ' if len(bad) > 1 else ' differs'} in size by more than {PAIRED_SIZE_RATIO:g} times: "
            f"{named}{more}.{hint} If B lists its parts in another order than A, each is morphed into the wrong "
            "one: give B's vertices with its parts in A's order (or morph without faces and edges)")


def morph_by_part(labels_a: np.ndarray, labels_b: np.ndarray, count: int, morph_one, progress):
    """Each part of A morphed into the same part of B by morph_one(index_a, index_b, progress):
    the (base, normals, detail_a, detail_b, report) of A's points, in A's order."""
    n = len(labels_a)
    base, normals = np.empty((n, 3)), np.empty((n, 3))
    detail_a, detail_b = np.empty(n), np.empty(n)
    report = dict(not_converged=0, degenerate=0)
    for part in range(count):
        ia, ib = np.flatnonzero(labels_a == part), np.flatnonzero(labels_b == part)
        sub = None
        if progress is not None:
            sub = (lambda f, s=part: progress((s + f) / count))
        try:
            m = morph_one(ia, ib, sub)
        except ValueError as exc:
            raise ValueError(f"part {part} (A: {len(ia)} points from vertex {ia[0]}, B: {len(ib)} points from "
                             f"vertex {ib[0]}): {exc}") from None
        base[ia], normals[ia], detail_a[ia], detail_b[ia] = m.base, m.normals, m.detail_a, m.detail_b
        for key in report:
            report[key] += int(m.report[key])
    return base, normals, detail_a, detail_b, report
