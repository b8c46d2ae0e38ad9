"""Morphing two models through a common base (Sec. 8.3, Eq. 22), aligned first if asked."""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from . import _core
from ._checks import (MAX_GAIN, MIN_COARSE_POINTS, as_array, as_callback, as_points, centre, finite_result,
                      mls_options, number, require_surface, thread_option)

#: Below this overlap of A's and B's bounding boxes (intersection over union) morph warns:
#: the base lies far from one of them, and beta = 1 would land away from B.
OVERLAP_WARNING = 0.25


@dataclass
class Morph:
    """Both models over a common base (Sec. 8.3), on A's samples: p(alpha, beta) of Eq. 22."""

    base: np.ndarray       #: (n_a, 3) A's samples projected onto the base
    normals: np.ndarray    #: (n_a, 3) oriented base normals there
    detail_a: np.ndarray   #: (n_a,) A's normal offsets: base + detail_a * normals == A
    detail_b: np.ndarray   #: (n_a,) B's offsets, interpolated onto A's samples
    report: dict           #: projections that did not converge or had no plane; the models' overlap
    #: With alignment, the similarity that carries the aligned B back to where B is
    #: (pointscale.alignment.Similarity); None when B was morphed where it lies.
    placement: object = field(default=None)

    def evaluate(self, alpha: float = 1.0, beta: float = 0.0) -> np.ndarray:
        """p_i + (alpha d_i^A + beta d_i^B) n_i: (1, 0) is A, (0, 1) is B on A's samples; any
        real alpha and beta, not only convex combinations (Fig. 10a). With alignment, beta also
        moves the shape from A's place to B's, linearly: (0, 1) is B where B lies, so Blender's
        relative shape keys, which blend linearly, give the same result. Returns (n_a, 3)."""
        try:
            alpha, beta = float(alpha), float(beta)
        except (TypeError, ValueError):
            raise ValueError(f"alpha and beta must be numbers, got {alpha!r}, {beta!r}") from None
        if not (np.isfinite(alpha) and np.isfinite(beta)):
            raise ValueError(f"alpha and beta must be finite, got {alpha}, {beta}")
        if max(abs(alpha), abs(beta)) > MAX_GAIN:
            raise ValueError(f"alpha and beta must be within +-{MAX_GAIN:.0e}, got {alpha}, {beta}")
        out = self.base + (alpha * self.detail_a + beta * self.detail_b)[:, None] * self.normals
        if self.placement is not None:
            b_here = self.base + self.detail_b[:, None] * self.normals
            out = out + beta * (self.placement.apply(b_here) - b_here)
        return finite_result(out, "the morph")


def morph(points_a, points_b, base_points=None, *, align: str = "none", base_samples: int = 20000,
          base_normals=None, kernel: float = 1.0,
          neighbors: int = 24, interpolation_neighbors: int = 8, tolerance: float = 1e-9, max_iterations: int = 50,
          threads: int = 0, progress=None, faces_a=None, edges_a=None, faces_b=None, edges_b=None) -> Morph:
    """Morph between two models through a common base surface (Sec. 8.3, Eq. 22).

    points_a, points_b  (n_a, 3), (n_b, 3); the counts may differ, each at least 8 points that
                        span a surface (not all on a line). They must overlap: a warning
                        says when their bounding boxes share less than OVERLAP_WARNING.
    base_points         samples of a base close to both, e.g. ellipsoid_base(points_a, points_b);
                        None takes that ellipsoid (of A and the aligned B), base_samples points
    align               "none", or how to carry B onto A first (pointscale.alignment): "bbox"
                        (bounding boxes), "pca" (principal axes) or "icp" (principal axes, then
                        iterative closest points). The morph is then computed on the aligned B,
                        and evaluate(0, 1) puts B back where it lies.
    Both are projected onto the base; B's offsets are carried onto A's samples by Gaussian-weighted
    interpolation over the interpolation_neighbors nearest projected B samples. Where B folds over
    the base (ears over an ellipsoid), those samples come from several sheets of B (one sheet:
    joined by a chain of samples whose offsets differ by at most twice the distance of their
    feet). Where A folds there too, into as many sheets, each A sample takes B's sheet of the same
    rank along the normal; into another number, the sheet of the B sample whose offset is nearest
    its own; where A does not fold, all.
    faces_a, edges_a, faces_b, edges_b  optional connectivity of both models: part i of A is then
                        morphed into part i of B alone (parts numbered by their lowest vertex, so
                        two versions of one mesh match), and B's offsets never cross from one
                        part to another (pointscale.parts_onto_base).
    Where evaluate(0, 1) misses B (over B_MISS_SHARE of A's samples land farther from B than 1%
    of B's diagonal), a warning says so.
    """
    from .alignment import METHODS, overlap, similarity
    if align not in METHODS:
        raise ValueError(f"align must be one of {', '.join(METHODS)}, got {align!r}")
    # A model of a few points, or of points on a line, has no shape to morph to or from.
    a = as_points(points_a, "points_a", min_count=MIN_COARSE_POINTS)
    b = as_points(points_b, "points_b", min_count=MIN_COARSE_POINTS)
    require_surface(a, "points_a", allow_planar=True)
    require_surface(b, "points_b", allow_planar=True)
    threads = thread_option(threads)
    placement = None
    if align != "none":
        carry = similarity(b, a, align, threads=threads)
        b, placement = carry.apply(b), carry.inverse()
    if base_points is None:
        from .operators import ellipsoid_base
        try:
            base_points = ellipsoid_base(a, b, n=base_samples)
        except ValueError as exc:  # its n is this function's base_samples
            if str(exc).startswith("n "):
                raise ValueError("base_samples" + str(exc)[1:]) from None
            raise
    share = overlap(a, b)
    if share < OVERLAP_WARNING:
        warnings.warn(f"A and B barely overlap (their bounding boxes share {share:.0%}), so the base lies far from "
                      "one of them and the morph will not reach B; align them first, e.g. morph(..., align='bbox'), "
                      "'pca' or 'icp'", stacklevel=2)
    options = dict(base_normals=base_normals, kernel=kernel, neighbors=neighbors,
                   interpolation_neighbors=interpolation_neighbors, tolerance=tolerance,
                   max_iterations=max_iterations, threads=threads)
    result = None
    if any(c is not None for c in (faces_a, edges_a, faces_b, edges_b)):
        from .parts_onto_base import matched_parts, morph_by_part
        labels_a, labels_b, count = matched_parts(a, b, faces_a, edges_a, faces_b, edges_b, threads)
        if count > 1:
            def morph_one(ia, ib, part_progress):
                return _morph_where_they_lie(a[ia], b[ib], base_points, progress=part_progress, **options)
            result = Morph(*morph_by_part(labels_a, labels_b, count, morph_one, as_callback(progress)))
    if result is None:
        result = _morph_where_they_lie(a, b, base_points, progress=progress, **options)
    message = _b_missed_warning(result, b, threads)
    if message:
        warnings.warn(message, stacklevel=2)
    result.report["overlap"] = share
    result.placement = placement
    return result


#: The share of A's samples that may land off B at evaluate(0, 1) before morph warns: a scan's
#: stray or duplicated samples, and B's sheets that A's samples do not reach, land off it too.
B_MISS_SHARE = 0.01


def _b_missed_warning(result: Morph, b: np.ndarray, threads: int) -> str | None:
    """The warning for a morph whose evaluate(0, 1) misses B, or None. Measured on the morph
    itself, in B's frame (with alignment, the aligned B): how far each of A's samples at (0, 1)
    lies off the plane of B at its nearest point of B (16 neighbours), as a share of B's
    diagonal. The distance to that point itself would count B's sampling: a coarse mesh's
    vertices lie farther apart than the miss.

    Where B has points with no position on the base whose normal passes through them (B reaches
    beyond the base's centres of curvature, or its projections crowd into strips, as a box's
    edges do over an ellipsoid), their offsets leave gaps on the base that A's samples fill by
    interpolation, off B: a box morphed from an ellipsoid missed B by 3.4% of its diagonal at
    13% of the samples, and bases that fit B missed it by no more than its sampling.
    """
    from .alignment import nearest_indices
    landed = result.base + result.detail_b[:, None] * result.normals
    nearest = nearest_indices(b, landed, threads)
    normals = _core.estimate_normals(b - centre(b), min(16, len(b)), False, threads)
    diagonal = float(np.linalg.norm(b.max(axis=0) - b.min(axis=0)))
    miss = np.abs(np.einsum("ij,ij->i", landed - b[nearest], normals[nearest]))
    off = miss > 0.01 * diagonal
    if not off.mean() > B_MISS_SHARE:
        return None
    return (f"morph: evaluate(0, 1) misses B (points_b) by more than 1% of its diagonal at {int(off.sum())} of "
            f"A's {len(landed)} samples (up to {miss.max() / diagonal:.2g} of it). B reaches beyond the base's "
            "centres of curvature or lies far from it, so some of B has no place on the base: a base nearer B, "
            "curving no more tightly than it, lets the morph reach B")


def _morph_where_they_lie(a, b, base_points, *, base_normals, kernel, neighbors, interpolation_neighbors,
                          tolerance, max_iterations, threads, progress) -> Morph:
    # The raw coordinates here; the core checks the rest (settings, the base's surface, the
    # models' reach, the normals) on the centred points.
    s = as_points(base_points, "base_points", min_count=MIN_COARSE_POINTS)
    bn = None if base_normals is None else as_array(base_normals, "base_normals")
    origin = centre(np.vstack([a, b, s]))
    mls = mls_options(neighbors, tolerance, max_iterations)
    options = _core.MorphOptions(
        kernel=number(kernel, "kernel"), mls=mls,
        interpolation_neighbors=number(interpolation_neighbors, "interpolation_neighbors", integer=True))
    r = _core.morph(a - origin, b - origin, s - origin, base_normals=bn, options=options,
                    progress=as_callback(progress), threads=thread_option(threads))
    for key in ("base", "normals", "detail_a", "detail_b"):
        finite_result(r[key], f"the morph's {key.replace('_', ' ')}")
    return Morph(r["base"] + origin, r["normals"], r["detail_a"], r["detail_b"],
                 {"not_converged": int(r["not_converged"]), "degenerate": int(r["degenerate"])})
