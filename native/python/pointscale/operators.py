"""The paper's further operators: diffusion smoothing (Sec. 5.1), ray-shooting encoding (Sec. 6.1),
encoding onto a given base (Sec. 8.2, Fig. 8), morphing (Sec. 8.3, Eq. 22), and a projection that
keeps thin sheets apart.
"""
from __future__ import annotations

import math
import warnings
import numpy as np

from . import _core
from ._checks import (MAX_DIFFUSION_ITERATIONS, MAX_LEVELS, MIN_COARSE_POINTS, as_array, as_callback, as_normals_of,
                      as_points, centre, finite_result, mls_options, number, positive, require_extent, require_near,
                      require_surface, thread_option)
from ._diffusion import diffusion_options
from .multiscale import Decomposition, _require_finite_model


def smooth_diffusion(points, iterations: int = 10, *, lam: float = 0.5, taubin: bool = False, mu=None,
                     neighbors: int = 10, threads: int = 0, progress=None) -> np.ndarray:
    """Laplacian diffusion smoothing of a point cloud (Sec. 5.1, Eq. 12): p' = p + lam * L(p).

    L(p) is the mean of p's k nearest neighbours minus p, over neighbourhoods computed once on the
    input and kept (so points cannot drift into clusters).
    iterations  number of steps, at most 10000
    lam         step in [0.001, 1]
    taubin      alternate each step with a negative one, mu = 1 / (0.1 - 1/lam) (Taubin 1995),
                which keeps the volume that plain Laplacian smoothing shrinks away
    mu          Taubin's negative step, in [-1000, -lam), or 0 for plain smoothing; overrides taubin
    A lam|mu pair lifts some frequencies slightly above 1 per iteration (mu = -10 with lam = 0.5
    by 5.5x, the default Taubin pair by 1.00066x); iterations that would lift one more than 4x
    in all, which inflates the shape and ends in NaN, raise ValueError.
    neighbors   k, the point itself included
    Returns the smoothed (n, 3) points, indexed like the input.
    """
    options = diffusion_options(iterations, lam, mu, taubin, neighbors)
    options.validate()  # the core's check, before the points are counted against the neighbours
    p = as_points(points, min_count=options.neighbors)
    origin = centre(p)
    out = _core.diffuse(p - origin, options, progress=as_callback(progress), threads=thread_option(threads)) + origin
    return finite_result(out, "the smoothed points")


def diffusion_levels(points, levels: int = 4, *, iterations: int = 10, growth: float = 4.0, lam: float = 0.5,
                     taubin: bool = False, mu=None, neighbors: int = 10, threads: int = 0) -> np.ndarray:
    """A discrete scale space by diffusion: (levels, n, 3), level 0 the smoothest, the last the input.

    Level l-1 is level l smoothed by iterations * growth**(k-l) more steps, so the diffusion time
    grows geometrically towards the coarse levels, like the kernel widths of decompose(). The steps
    of all levels together are bounded like smooth_diffusion's iterations (at most 10000).
    """
    levels = positive(levels, "levels", integer=True, minimum=2, maximum=MAX_LEVELS)
    growth = positive(growth, "growth", minimum=1.0, maximum=1e3)
    first = diffusion_options(iterations, lam, mu, taubin, neighbors)
    first.validate()  # the core's checks of the first level's settings
    iterations, neighbors, lam, mu = first.iterations, first.neighbors, first.lam, first.mu
    # The steps per level grow geometrically: bound their sum, like smooth_diffusion's iterations.
    total = sum(float(np.round(iterations * growth ** step)) for step in range(levels - 1))
    if total > MAX_DIFFUSION_ITERATIONS:
        raise ValueError(f"levels={levels}, iterations={iterations} and growth={growth:g} take {total:.3g} diffusion "
                         f"steps in all; at most {MAX_DIFFUSION_ITERATIONS} are allowed (use fewer levels, "
                         "iterations or a smaller growth)")
    _core.check_stable_diffusion(lam, mu, int(total), "the total of iterations over the levels")
    p = as_points(points, min_count=neighbors)
    origin = centre(p)
    threads = thread_option(threads)
    out = [p - origin]
    for step in range(levels - 1):
        steps = int(round(iterations * growth ** step))
        options = _core.DiffusionOptions(neighbors=neighbors, lam=lam, mu=mu, iterations=steps)
        out.append(_core.diffuse(out[-1], options, threads=threads))
    levels_out = np.stack(out[::-1]) + origin
    levels_out[-1] = p  # the input itself, without a centring round trip
    return finite_result(levels_out, "the diffusion levels")


def project_sheets(points, onto, *, kernel: float = 1.0, sheet: float = 0.2, onto_normals=None,
                   neighbors: int = 24, tolerance: float = 1e-9, max_iterations: int = 50, threads: int = 0,
                   progress=None, return_report: bool = False):
    """MLS projection that keeps thin sheets apart (two sheets closer than the kernel width).

    Like project(), but a support point's weight also falls with its distance along its own
    normal, with width sheet * h: points of a parallel sheet 0.5 h away weigh about
    exp(-(0.5/sheet)**2) as much, so each sheet projects onto itself instead of onto their mean.
    onto_normals  (m, 3) normals of `onto` (sign ignored); None estimates them from 16 neighbours
    Returns (positions, normals) and, with return_report, a dict like project().
    """
    x = as_points(points)
    s = as_points(onto, "onto", min_count=3)
    require_surface(s, "onto", allow_planar=True)
    require_near(x, centre(s), "points", "onto")
    kernel, sheet = number(kernel, "kernel"), number(sheet, "sheet")
    mls = mls_options(neighbors, tolerance, max_iterations)
    nrm = as_normals_of(onto_normals, s, "onto_normals", "onto")
    if nrm is not None:  # unit normals for the core: turning them so is this package's conversion
        nrm = nrm / np.linalg.norm(nrm, axis=1)[:, None]
        if not np.isfinite(nrm).all():
            raise ValueError("onto_normals has vectors too short to normalise")
    origin = centre(s)
    pos, n, not_converged, degenerate = _core.project_sheets(x - origin, s - origin, onto_normals=nrm, kernel=kernel,
                                                             mls=mls, sheet=sheet, progress=as_callback(progress),
                                                             threads=thread_option(threads))
    pos = finite_result(pos + origin, "the projection")
    finite_result(n, "the projection's normals")
    if return_report:
        return pos, n, {"not_converged": int(not_converged), "degenerate": int(degenerate)}
    return pos, n


def shoot_rays(origins, directions, onto, *, kernel: float = 1.0, neighbors: int = 24, max_distance=None,
               tolerance: float = 1e-9, max_iterations: int = 50, threads: int = 0):
    """Intersects rays with the MLS surface of `onto` (Adamson and Alexa 2003).

    origins, directions  (r, 3); directions need not be unit. Rays are whole lines.
    max_distance         a hit farther than this from its origin counts as a miss (None: no limit)
    Returns (hits (r, 3), distances (r,) signed along the unit directions, missed (r,) bool).
    Missed rays keep their origin and distance 0: check `missed`, nothing is dropped.
    """
    o = as_points(origins, "origins")
    d = as_points(directions, "directions")
    # Unit directions for the core, which checks that they are: turning them so is this
    # package's conversion, and a zero vector has no direction to turn.
    length = np.linalg.norm(d, axis=1)
    if not (length > 0).all():
        raise ValueError(f"directions contains {int((length == 0).sum())} zero vectors")
    unit = d / length[:, None]
    s = as_points(onto, "onto", min_count=3)
    require_surface(s, "onto", allow_planar=True)
    origin = centre(s)
    limit = math.inf if max_distance is None else number(max_distance, "max_distance")
    rays = _core.RayOptions(neighbors=number(neighbors, "neighbors", integer=True),
                            tolerance=number(tolerance, "tolerance"),
                            max_iterations=number(max_iterations, "max_iterations", integer=True),
                            max_distance=limit, min_cosine=0.05)
    kernel = number(kernel, "kernel")
    hits, dist, missed = _core.shoot_rays(o - origin, unit, s - origin, kernel=kernel, options=rays,
                                          threads=thread_option(threads))
    return finite_result(hits + origin, "the ray hits"), finite_result(dist, "the ray distances"), missed


def encode(points, base_points, *, base_normals=None, kernel: float = 1.0, neighbors: int = 24,
           tolerance: float = 1e-9, max_iterations: int = 50, max_variation: float = 0.05, threads: int = 0,
           progress=None, faces=None, edges=None) -> Decomposition:
    """Encodes a model onto a user-given base surface (Sec. 8.2, Fig. 8): a one-band Decomposition.

    points       (n, 3) the model
    base_points  (m, 3) samples of the base, e.g. ellipsoid_base(points); the model may lie many
                 kernel widths away from it
    base_normals (m, 3) optional, orients the base (else outward by propagation)
    kernel       kernel width as a multiple of the base's local sample spacing
    reconstruct(dec, [0]) lies on the base's MLS surface, reconstruct(dec, [1]) is the model,
    other gains blend or exaggerate (Fig. 8). Where the model reaches beyond the base's centres of
    curvature, or its projections crowd into strips, a point may have no position on the base
    whose recomputed normal passes through it; it then stays at its projection, and gain 1 misses
    it by its tangential offset. stats[0]["pinned"] counts such points and
    stats[0]["consistency_residual"] is the largest such error (0 up to rounding when none).
    faces, edges  optional connectivity of the model, as for decompose: each connected part is
                 then encoded onto the base alone (pointscale.parts_onto_base); a part too small
                 for a band of its own keeps none, with a warning that names it.
    """
    if faces is not None or edges is not None:
        from .parts import connected_parts
        labels, count = connected_parts(as_points(points), faces, edges, threads=threads)
        if count > 1:
            options = dict(base_normals=base_normals, kernel=kernel, neighbors=neighbors, tolerance=tolerance,
                           max_iterations=max_iterations, max_variation=max_variation, threads=threads)
            return _encode_by_part(points, base_points, labels, count, options, progress)
    options = _encode_options(kernel, neighbors, tolerance, max_iterations, max_variation)
    # The raw coordinates here; the core checks the rest (settings, the base's surface, reach,
    # normals) on the centred points.
    p = as_points(points, min_count=MIN_COARSE_POINTS)
    b = as_points(base_points, "base_points", min_count=MIN_COARSE_POINTS)
    bn = None if base_normals is None else as_array(base_normals, "base_normals")
    origin = centre(np.vstack([p, b]))
    model = _core.encode(p - origin, b - origin, base_normals=bn, options=options, progress=as_callback(progress),
                         threads=thread_option(threads))
    mls = options.mls
    settings = dict(levels=2, encoding="base", kernel=options.kernel, neighbors=mls.neighbors,
                    tolerance=mls.tolerance, max_iterations=mls.max_iterations,
                    max_variation=options.max_variation, base_points=len(b))
    dec = Decomposition(model, origin, settings)
    _require_finite_model(dec)
    _warn_if_inexact(dec, p)
    return dec


# A residual above this share of the model's diagonal is more than the iteration's rounding
# (measured up to 1.1e-9 on models that encode well): say so.
INEXACT_ENCODING = 1e-6


def _warn_if_inexact(dec, points) -> None:
    """Warns when reconstruct(dec, [1]) does not give the model back: the residual is in the
    stats, where nobody looks until the model is wrong."""
    stats = dec.stats[0] if dec.stats else {}
    residual = float(stats.get("consistency_residual", 0.0))
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    if not residual > INEXACT_ENCODING * diagonal:
        return
    pinned = int(stats.get("pinned", 0))
    share = f"{residual / diagonal:.2g} of its diagonal" if diagonal > 0 else "its points are all at one position"
    warnings.warn(
        f"encode: reconstruct at gain 1 misses the model by up to {residual:.3g} ({share}); {pinned} points have no position on the base whose normal passes through them. The model "
        "reaches beyond the base's centres of curvature or lies far from it: a base nearer the model, curving no "
        "more tightly than it, encodes it exactly (stats[0]['consistency_residual'], stats[0]['pinned'])",
        stacklevel=3)


def _encode_options(kernel, neighbors, tolerance, max_iterations, max_variation) -> _core.EncodeOptions:
    """encode()'s settings as the core takes them, the numbers converted; the core checks them."""
    mls = mls_options(neighbors, tolerance, max_iterations)
    return _core.EncodeOptions(kernel=number(kernel, "kernel"), max_variation=number(max_variation, "max_variation"),
                               mls=mls)


def _encode_by_part(points, base_points, labels, count, options, progress) -> Decomposition:
    """encode() of each connected part alone, joined into one Decomposition."""
    from .parts_onto_base import encode_by_part
    p = as_points(points)
    b = as_points(base_points, "base_points", min_count=MIN_COARSE_POINTS)
    require_near(p, centre(b), "points", "base_points")
    checked = _encode_options(options["kernel"], options["neighbors"], options["tolerance"], options["max_iterations"],
                              options["max_variation"])
    checked.validate()  # before the parts' sizes are weighed with them
    neighbors = checked.mls.neighbors
    origin = centre(np.vstack([p, b]))
    if np.bincount(labels, minlength=count).max() < MIN_COARSE_POINTS:
        raise ValueError(f"every connected part is too small to encode (each needs {MIN_COARSE_POINTS} points); "
                         "encode without faces and edges to treat the parts as one surface")

    def encode_one(part_points, part_progress):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return encode(part_points, b, progress=part_progress, **options)

    arrays, stats, reports, message = encode_by_part(p, labels, count, encode_one, neighbors, MIN_COARSE_POINTS,
                                                     as_callback(progress), origin,
                                                     threads=thread_option(options["threads"]))
    settings = dict(levels=2, encoding="base", kernel=options["kernel"], neighbors=neighbors,
                    tolerance=options["tolerance"], max_iterations=options["max_iterations"],
                    max_variation=options["max_variation"], base_points=len(b), parts=reports)
    dec = Decomposition(_core.Model.from_arrays(arrays), origin, settings, _stats=stats)
    _require_finite_model(dec)
    if message:
        warnings.warn(message, stacklevel=3)
    _warn_if_inexact(dec, p)
    return dec


def ellipsoid_base(points_a, points_b=None, n: int = 20000) -> np.ndarray:
    """n samples of the largest axis-aligned ellipsoid inside the common bounding box of the
    models, the base the paper used for Fig. 8 and 9. Returns (n, 3)."""
    n = positive(n, "n", integer=True, minimum=MIN_COARSE_POINTS, maximum=10 ** 8)
    a = as_points(points_a, "points_a")
    pts = a if points_b is None else np.vstack([a, as_points(points_b, "points_b")])
    require_extent(pts, "the points", minimum=False)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    axes = 0.5 * (hi - lo)
    if not (axes > 1e-9 * axes.max()).all():
        raise ValueError(f"the bounding box is flat (extent {2 * axes}): it holds no ellipsoid")
    from .shapes import fibonacci_sphere
    return 0.5 * (lo + hi) + fibonacci_sphere(n) * axes
