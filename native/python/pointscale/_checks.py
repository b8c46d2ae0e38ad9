"""Input checks shared by the public functions: every bad input becomes a clear ValueError.

Supported coordinates. The core's plane fits square covariances, which makes fourth powers of
the local sample spacing; in double precision those stay in range for spacings between about
1e-76 and 1e76 (measured on a sphere: 1e78 gives NaN). The checks keep a wide margin:

* every coordinate within +-MAX_COORDINATE (1e150);
* a surface (the points of decompose, the `onto` of project, ...) spans at most MAX_EXTENT
  (1e50) and at least MIN_EXTENT (1e-50) about its bounding-box centre (half the largest side
  of its bounding box); sets of points used with it lie within MAX_EXTENT of that centre.

The shape checks (identical, collinear, planar) are made in a frame scaled to the set's size,
so a set is judged by its shape, whatever its size; a set outside the range is then refused by
its size.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

MAX_COORDINATE = 1e150
MAX_EXTENT = 1e50
MIN_EXTENT = 1e-50
MAX_THREADS = 1024
MAX_LEVELS = 64
MAX_NEIGHBORS = 1024
MAX_ITERATIONS = 1000               # MLS and ray iterations per point
MAX_DIFFUSION_ITERATIONS = 10000    # diffusion steps in one call
MAX_DIFFUSION_GROWTH = 4.0          # the most a diffusion may amplify any frequency, in total
MIN_KERNEL, MAX_KERNEL = 1e-3, 1e3  # kernel widths, as multiples of the local spacing
MAX_GAIN = 1e6                      # band gains, Morph's alpha and beta


def as_points(points, name: str = "points", min_count: int = 1) -> np.ndarray:
    """Returns `points` as a C-contiguous float64 (n, 3) array, or raises ValueError."""
    try:
        a = np.asarray(points)
    except Exception as exc:  # ragged lists and the like
        raise ValueError(f"{name} must be an (n, 3) array of numbers: {exc}") from None
    if a.dtype == object or not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise ValueError(f"{name} must hold real numbers, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {a.shape}")
    if a.shape[0] == 0:
        raise ValueError(f"{name} is empty")
    if a.shape[0] < min_count:
        raise ValueError(f"{name} has {a.shape[0]} points; at least {min_count} are needed here")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.isfinite(a).all():
        bad = int((~np.isfinite(a)).any(axis=1).sum())
        raise ValueError(f"{name} contains NaN or infinite coordinates ({bad} points)")
    largest = max(float(np.abs(column_reduce(a, np.min)).max()), float(np.abs(column_reduce(a, np.max)).max()))
    if largest > MAX_COORDINATE:
        raise ValueError(f"{name} has a coordinate of {largest:.3g}; coordinates beyond +-{MAX_COORDINATE:.0e} "
                         "are not supported")
    return a


def as_normals_of(normals, points: np.ndarray, name: str = "normals", points_name: str = "points"):
    """Optional per-point normals: None, or a checked (n, 3) array of the shape of points."""
    if normals is None:
        return None
    n = as_points(normals, name)
    if n.shape != points.shape:
        raise ValueError(f"{name} must have the shape of {points_name} {points.shape}, got {n.shape}")
    return n


def column_reduce(points: np.ndarray, reduce) -> np.ndarray:
    """reduce (np.min, np.max, np.mean) of each column of an (n, 3) array: column by column,
    since NumPy's axis-0 reductions over three columns are about fifteen times slower."""
    return np.array([reduce(points[:, a]) for a in range(points.shape[1])])


def centre(points: np.ndarray) -> np.ndarray:
    """The bounding-box centre: subtracting it keeps precision for data far from the origin."""
    return 0.5 * (column_reduce(points, np.min) + column_reduce(points, np.max))


def half_width(points: np.ndarray) -> float:
    """Half the largest side of the bounding box: the set's extent about its centre."""
    return float((0.5 * (column_reduce(points, np.max) - column_reduce(points, np.min))).max())


def _scaled_spread(points: np.ndarray) -> np.ndarray:
    """extent_eigenvalues in a frame scaled to the set by a power of two (its largest deviation
    from the mean is in [0.5, 1)), so that sets of any size in the float range, 1e-320 to
    1e300, are measured alike: their squares neither overflow nor underflow."""
    c = points - column_reduce(points, np.mean)
    w = max(float(c.max()), -float(c.min()))
    if w > 0.0:
        np.ldexp(c, -math.frexp(w)[1], out=c)  # in place: no second copy of a large set
    ev = np.linalg.eigvalsh(c.T @ c / len(points))
    return np.sqrt(np.clip(ev[::-1], 0.0, None)), (math.frexp(w)[1] if w > 0.0 else 0)


def extent_eigenvalues(points: np.ndarray) -> np.ndarray:
    """Square roots of the covariance eigenvalues, largest first: the spread along 3 axes."""
    spread, exponent = _scaled_spread(points)
    return np.ldexp(spread, exponent)


def require_extent(points: np.ndarray, name: str = "points", minimum: bool = True) -> float:
    """Refuses a set larger than MAX_EXTENT (or, with minimum, smaller than MIN_EXTENT but not
    a single point) about its centre. Returns the half width."""
    w = half_width(points)
    if w > MAX_EXTENT:
        raise ValueError(f"{name} span {2 * w:.3g}; sets wider than {2 * MAX_EXTENT:.0e} are not supported "
                         "(scale them down first)")
    if minimum and 0.0 < w < MIN_EXTENT:
        raise ValueError(f"{name} span only {2 * w:.3g}; sets narrower than {2 * MIN_EXTENT:.0e} are not "
                         "supported (scale them up first)")
    return w


def require_near(points: np.ndarray, origin: np.ndarray, name: str, other: str) -> None:
    """Refuses points farther than MAX_EXTENT (along an axis) from the centre of `other`."""
    far = max(float(np.abs(column_reduce(points, np.min) - origin).max()),
              float(np.abs(column_reduce(points, np.max) - origin).max()))
    if far > MAX_EXTENT:
        raise ValueError(f"{name} reach {far:.3g} from the centre of {other}; more than {MAX_EXTENT:.0e} "
                         "is not supported")


def require_surface(points: np.ndarray, name: str = "points", allow_planar: bool = False) -> None:
    """Rejects sets that span no surface: all identical, collinear, or (unless allowed) planar;
    then sets outside the supported size (require_extent)."""
    if half_width(points) == 0.0:
        raise ValueError(f"all {name} are identical: they define no surface")
    spread, _ = _scaled_spread(points)  # judged by shape, whatever the size
    if spread[0] == 0.0:
        raise ValueError(f"all {name} are identical: they define no surface")
    # Rounding leaves eigenvalues near 1e-16 of the largest, so spreads below 1e-6 count as zero.
    if spread[1] <= 1e-6 * spread[0]:
        raise ValueError(f"{name} are collinear: they define no surface and no normals")
    if not allow_planar and spread[2] <= 1e-6 * spread[0]:
        raise ValueError(f"{name} all lie in one plane: there is no detail to separate from a base "
                         "(use project() to work with planar data)")
    require_extent(points, name)


def positive(value, name: str, integer: bool = False, minimum=None, maximum=None):
    """Checks a scalar option; returns it as int or float."""
    if isinstance(value, (bool, np.bool_)) or (integer and isinstance(value, str)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    try:
        v = int(value) if integer else float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a {'whole ' if integer else ''}number, got {value!r}") from None
    if integer and v != value:
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    if not (integer or math.isfinite(v)) or v <= 0 or (minimum is not None and v < minimum):
        lo = f">= {minimum}" if minimum is not None else "> 0"
        raise ValueError(f"{name} must be {lo}, got {value!r}")
    if maximum is not None and v > maximum:
        raise ValueError(f"{name} must be at most {maximum:g}, got {value!r}")
    return v


def kernel_option(value, name: str = "kernel") -> float:
    """A kernel width as a multiple of the local spacing, in [MIN_KERNEL, MAX_KERNEL]."""
    return positive(value, name, minimum=MIN_KERNEL, maximum=MAX_KERNEL)


def thread_option(threads) -> int:
    """Checks `threads` (0 for all cores, else 1..MAX_THREADS); returns it for one core call,
    which runs on that many threads and leaves no count behind for other calls."""
    if isinstance(threads, (bool, np.bool_)) or not isinstance(threads, (numbers.Integral, float, np.floating)):
        raise ValueError(f"threads must be a whole number in [0, {MAX_THREADS}] (0: all cores), got {threads!r}")
    if isinstance(threads, (float, np.floating)) and not (np.isfinite(threads) and threads == int(threads)):
        raise ValueError(f"threads must be a whole number in [0, {MAX_THREADS}] (0: all cores), got {threads!r}")
    t = int(threads)
    if not 0 <= t <= MAX_THREADS:
        raise ValueError(f"threads must be in [0, {MAX_THREADS}] (0: all cores), got {threads!r}")
    return t


def finite_result(array, what: str):
    """A last guard: a result with NaN or infinite values is refused, never returned."""
    if not np.isfinite(array).all():
        raise ValueError(f"{what} is not finite: the input lies outside what the core can represent "
                         "(extreme coordinates, gains or a damaged decomposition)")
    return array


def diffusion_growth(lam: float, mu: float) -> float:
    """The largest factor by which one diffusion iteration (a lam step, then a mu step when mu
    is not 0) scales a frequency k of the umbrella Laplacian, over k in [0, 2]:
    max |(1 - lam k)(1 - mu k)|. Taubin's lam|mu filter lifts the frequencies near
    k* = (lam + mu) / (2 lam mu) slightly above 1, so many iterations inflate the shape."""
    f = lambda k: abs((1.0 - lam * k) * (1.0 - mu * k))
    candidates = [f(0.0), f(2.0)]
    if mu != 0.0:
        k_star = (lam + mu) / (2.0 * lam * mu)
        if 0.0 <= k_star <= 2.0:
            candidates.append(f(k_star))
    return max(candidates)


def require_stable_diffusion(lam: float, mu: float, iterations: int, name: str = "iterations") -> None:
    """Refuses a diffusion whose iterations would amplify some frequency more than
    MAX_DIFFUSION_GROWTH times in total (it would inflate the shape, or give NaN)."""
    g = diffusion_growth(lam, mu)
    if g > 1.0 and iterations * math.log(g) > math.log(MAX_DIFFUSION_GROWTH):
        most = int(math.log(MAX_DIFFUSION_GROWTH) / math.log(g))
        raise ValueError(f"lam={lam:g}, mu={mu:g} amplify some frequencies {g:.6g} times per iteration, so "
                         f"{name}={iterations} would inflate the shape; at most {most} iterations are stable "
                         "(use fewer, or mu closer to -lam)")


def as_callback(progress):
    if progress is not None and not callable(progress):
        raise ValueError("progress must be a callable taking a fraction in [0, 1], or None")
    return progress
