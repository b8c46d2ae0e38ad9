"""Single-surface tools: MLS projection (Sec. 2), clustering decimation (Sec. 5.2), normals."""
from __future__ import annotations

import warnings

import numpy as np

from . import _core
from ._checks import (as_callback, as_points, centre, finite_result, flag, mls_options, number,
                      require_near, require_surface, thread_option)


def project(points, onto, *, kernel: float = 1.0, neighbors: int = 24, tolerance: float = 1e-9,
            max_iterations: int = 50, threads: int = 0, progress=None, return_report: bool = False,
            near=None, single_pass: bool = False):
    """Projects points onto the MLS surface defined by the point set `onto` (the operator Psi).

    points  (n, 3) to project;  onto (m, 3) samples of the surface
    kernel  kernel width as a multiple of the local sample spacing of `onto`
    tolerance  stop once a point is within tolerance x kernel width of where its iteration
            goes: its last step is that small, or its steps shrink at a steady rate r < 0.5 and
            step x r / (1 - r) is; max_iterations caps the iterations
    near    optional (n,) index into `onto` of a sample near each point, such as the labels
            from decimate(points) when `onto` is its centroids: the points around one sample
            then share one neighbour query. Only a speed-up: a point whose iteration converges
            ends where it would without; one that does not converge (it cycles; see
            return_report) may stop elsewhere in its cycle, since its sums are taken in another
            order.
    single_pass  one plane fit at each point and one projection onto it, as PCL's and Open3D's
            MLS smoothing do, instead of iterating to the MLS surface: one neighbour query per
            point, and no iteration (tolerance and max_iterations then only set what the
            report counts as converged; near is not used). It stops where the iteration takes
            its first step; a larger kernel (about 2.5-3) smooths noise as much as the peers.
    Returns (positions (n, 3), normals (n, 3)); with return_report also a dict with the number
    of points that did not converge and of points whose neighbourhood defines no plane.
    With single_pass the report also says how far from converged the pass stops, per point
    and relative to the kernel width h there: moved_mean and moved_max, the pass's own step
    |result - point| / h, and next_step_mean and next_step_max, the step the iteration would
    take next (its second fit, at the result, on the result's own neighbours: a second query
    and fit per point, made only for the report); not_converged counts the points whose next
    step exceeds tolerance x h, and passes is 1.
    Normals are unit and unoriented. A point whose neighbourhood defines no plane (its weights
    vanish: far from `onto`) stays where it is with a zero normal; without return_report a
    warning counts such points.
    """
    x = as_points(points)
    mls = mls_options(neighbors, tolerance, max_iterations)
    mls.validate()  # the core's check; single_pass reads tolerance for its report only
    s = as_points(onto, "onto", min_count=3)
    require_surface(s, "onto", allow_planar=True)
    require_near(x, centre(s), "points", "onto")
    kernel = number(kernel, "kernel")
    if near is not None:  # its count and range the core checks
        near = np.asarray(near)
        if near.ndim != 1 or not np.issubdtype(near.dtype, np.integer):
            raise ValueError(f"near must be ({len(x)},) integers (an index into onto), got {near.dtype} {near.shape}")
        if len(near) and (near.min() < np.iinfo(np.int32).min or near.max() > np.iinfo(np.int32).max):
            raise ValueError(f"near must index onto: each in [0, {len(s) - 1}], got [{near.min()}, {near.max()}]")
        near = near.astype(np.int32)
    single_pass = flag(single_pass, "single_pass")
    origin = centre(s)
    threads = thread_option(threads)
    if single_pass:
        return _single_pass(x, s, origin, kernel, mls.neighbors, mls.tolerance, progress, return_report, threads)
    pos, nrm, not_converged, degenerate = _core.project(x - origin, s - origin, kernel=kernel, mls=mls,
                                                        progress=as_callback(progress), near=near, threads=threads)
    pos = finite_result(pos + origin, "the projection")
    finite_result(nrm, "the projection's normals")
    if return_report:
        return pos, nrm, {"not_converged": int(not_converged), "degenerate": int(degenerate)}
    _warn_unprojected(int(degenerate), len(x))
    return pos, nrm


def _warn_unprojected(degenerate: int, n: int) -> None:
    if degenerate:
        warnings.warn(f"project: {degenerate} of {n} points were left where they are, with zero normals: their "
                      "neighbourhood on `onto` defines no plane (they lie far from it); return_report=True counts "
                      "them", stacklevel=3)


def _single_pass(x, s, origin, kernel, neighbors, tolerance, progress, return_report, threads):
    # Projecting a cloud onto itself (smoothing it) lets the core take every point's
    # neighbours from one all-points query (self_knn.h) instead of a tree query each.
    same = x.shape == s.shape and np.array_equal(x, s)
    pos, nrm, moved, next_step, degenerate = _core.project_single_pass(
        None if same else x - origin, s - origin, kernel=kernel, neighbors=neighbors, self=same,
        estimate=bool(return_report), progress=as_callback(progress), threads=threads)
    pos = finite_result(pos + origin, "the projection")
    finite_result(nrm, "the projection's normals")
    if not return_report:
        _warn_unprojected(int(degenerate), len(x))
        return pos, nrm
    fitted = len(moved) > 0
    report = {"not_converged": int(np.count_nonzero(next_step > tolerance)), "degenerate": int(degenerate),
              "passes": 1,
              "moved_mean": float(moved.mean()) if fitted else 0.0,
              "moved_max": float(moved.max()) if fitted else 0.0,
              "next_step_mean": float(next_step.mean()) if fitted else 0.0,
              "next_step_max": float(next_step.max()) if fitted else 0.0}
    return pos, nrm, report


def decimate(points, target: int, *, max_variation: float = 0.05):
    """Hierarchical-clustering decimation (Pauly et al. 2002) to `target` clusters.

    Returns (centroids (target, 3), labels (n,) int32 cluster of each point). Clusters of
    identical points cannot be split, so duplicates may leave fewer clusters than asked.
    """
    p = as_points(points)  # the core checks the rest
    target, max_variation = number(target, "target", integer=True), number(max_variation, "max_variation")
    origin = centre(p)
    c, labels = _core.decimate(p - origin, target=target, max_variation=max_variation)
    return finite_result(c + origin, "the centroids"), labels


def estimate_normals(points, neighbors: int = 16, *, orient: bool = True, threads: int = 0) -> np.ndarray:
    """Unit PCA normals of each point's neighbourhood, consistently oriented (outward on closed
    shapes) by spanning-tree propagation when orient is True. The propagation follows each
    point's 12 nearest neighbours, or all `neighbors` of its fit when there are fewer. Returns (n, 3).
    A point whose neighbours span no plane (all at one position, or on a line) has no normal: its
    row is zero, and a warning counts such points and names the first."""
    neighbors = number(neighbors, "neighbors", integer=True)
    orient = flag(orient, "orient")
    p = as_points(points)  # the core checks the neighbours, the count and the surface
    normals = _core.estimate_normals(p - centre(p), neighbors=neighbors, orient=orient,
                                     threads=thread_option(threads))
    normals = finite_result(normals, "the normals")
    missing = ~normals.any(axis=1)
    if missing.any():
        warnings.warn(f"{int(missing.sum())} of {len(normals)} points have no normal (their {neighbors} neighbours "
                      f"span no plane: duplicates, or points on a line; the first is point {int(np.argmax(missing))}): "
                      "their rows are zero", stacklevel=2)
    return normals
