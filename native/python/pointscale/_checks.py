"""Input conversion for the public functions, and their calls into the core's checks.

The checks (shapes, finiteness, supported coordinates and extents, option ranges, gains, the
stability of a diffusion) are the core's: native/include/pointscale/validation.h says what is
supported and why, every C++ entry point makes them, and their std::invalid_argument arrives
here as ValueError. The package keeps what is Python's: turning inputs into float64
C-contiguous (n, 3) arrays and numbers (a ValueError for anything else), callbacks, string
options, the parameters only Python functions have, and the checks of saved files. Where a
function centres its points before it calls the core, it first has the core check the raw
ones (as_points, require_surface...), since centring could hide a coordinate out of range.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

from . import _core

# The core's limits (validation.h), for the few Python-side uses: file loading, messages.
MAX_COORDINATE = _core.limits["max_coordinate"]
MAX_EXTENT = _core.limits["max_extent"]
MAX_LEVELS = _core.limits["max_levels"]
MAX_NEIGHBORS = _core.limits["max_neighbors"]
MAX_DIFFUSION_ITERATIONS = _core.limits["max_diffusion_iterations"]
MAX_GAIN = _core.limits["max_gain"]
MIN_COARSE_POINTS = _core.limits["min_coarse_points"]
_INT_MAX = 2 ** 31 - 1  # the core's options are C ints


def as_array(points, name: str = "points") -> np.ndarray:
    """`points` as a C-contiguous float64 (n, 3) array, unchecked beyond its type and shape."""
    try:
        a = np.asarray(points)
    except Exception as exc:  # ragged lists and the like
        raise ValueError(f"{name} must be an (n, 3) array of numbers: {exc}") from None
    if a.dtype == object or not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise ValueError(f"{name} must hold real numbers, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def as_points(points, name: str = "points", min_count: int = 1) -> np.ndarray:
    """`points` as a C-contiguous float64 (n, 3) array that the core's check_points accepts
    (at least min_count points, finite, within +-MAX_COORDINATE), or raises ValueError."""
    a = as_array(points, name)
    _core.check_points(a, name, min_count)
    return a


def as_normals_of(normals, points: np.ndarray, name: str = "normals", points_name: str = "points"):
    """Optional per-point normals: None, or an (n, 3) array of the shape of points (checked by
    the core's check_normals)."""
    if normals is None:
        return None
    n = as_array(normals, name)
    _core.check_normals(n, points, name, points_name)
    return n


def column_reduce(points: np.ndarray, reduce) -> np.ndarray:
    """reduce (np.min, np.max, np.mean) of each column of an (n, 3) array: column by column,
    since NumPy's axis-0 reductions over three columns are about fifteen times slower."""
    return np.array([reduce(points[:, a]) for a in range(points.shape[1])])


def centre(points: np.ndarray) -> np.ndarray:
    """The bounding-box centre: subtracting it keeps precision for data far from the origin."""
    return 0.5 * (column_reduce(points, np.min) + column_reduce(points, np.max))


def require_extent(points: np.ndarray, name: str = "points", minimum: bool = True) -> float:
    """The core's check_extent: refuses a set wider than MAX_EXTENT about its centre (or, with
    minimum, narrower than MIN_EXTENT but not one point). Returns the half width."""
    return _core.check_extent(points, name, minimum)


def require_near(points: np.ndarray, origin: np.ndarray, name: str, other: str) -> None:
    """The core's check_near: refuses points farther than MAX_EXTENT from `origin`, the centre of
    the set named `other`."""
    _core.check_near(points, np.asarray(origin, dtype=np.float64), name, other)


def require_surface(points: np.ndarray, name: str = "points", allow_planar: bool = False) -> None:
    """The core's check_surface: refuses sets that span no surface (all identical, collinear,
    or, unless allowed, planar), then sets outside the supported size."""
    _core.check_surface(points, name, allow_planar)


def number(value, name: str, integer: bool = False):
    """`value` as an int (integer) or a float, or ValueError for what is not one: bools, text,
    2.5 for a whole number. The ranges are the core's to check."""
    if isinstance(value, (bool, np.bool_, str, bytes)):  # float("3") would take text for a number
        raise ValueError(f"{name} must be a number, got {value!r}")
    try:
        v = int(value) if integer else float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a {'whole ' if integer else ''}number, got {value!r}") from None
    if integer and v != value:
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    if integer and abs(v) > _INT_MAX:  # beyond what the core's int options hold
        raise ValueError(f"{name} must be a whole number within +-{_INT_MAX}, got {value!r}")
    return v


def mls_options(neighbors, tolerance, max_iterations) -> _core.MlsOptions:
    """The MLS projection's settings as the core takes them, the numbers converted."""
    return _core.MlsOptions(neighbors=number(neighbors, "neighbors", integer=True),
                            tolerance=number(tolerance, "tolerance"),
                            max_iterations=number(max_iterations, "max_iterations", integer=True))


def positive(value, name: str, integer: bool = False, minimum=None, maximum=None):
    """A number that only Python functions take (the core checks its own options): checked
    against its range here; returns it as int or float."""
    v = number(value, name, integer)
    if not (integer or math.isfinite(v)) or v <= 0 or (minimum is not None and v < minimum):
        lo = f">= {minimum}" if minimum is not None else "> 0"
        raise ValueError(f"{name} must be {lo}, got {value!r}")
    if maximum is not None and v > maximum:
        raise ValueError(f"{name} must be at most {maximum:g}, got {value!r}")
    return v


def thread_option(threads) -> int:
    """`threads` as an int for one core call, which checks it (0 for all cores, else up to
    1024) and runs on that many threads, leaving no count behind for other calls."""
    if not isinstance(threads, (numbers.Integral, float, np.floating)):
        raise ValueError(f"threads must be a whole number, 0 for all cores, got {threads!r}")
    t = number(threads, "threads", integer=True)
    _core.check_threads(t)
    return t


def finite_result(array, what: str):
    """A last guard: a result with NaN or infinite values is refused, never returned."""
    if not np.isfinite(array).all():
        raise_not_finite(what)
    return array


def raise_not_finite(what: str):
    raise ValueError(f"{what} is not finite: the input lies outside what the core can represent "
                     "(extreme coordinates, gains or a damaged decomposition)")


def as_callback(progress):
    if progress is not None and not callable(progress):
        raise ValueError("progress must be a callable taking a fraction in [0, 1], or None")
    return progress


def flag(value, name: str) -> bool:
    """A True/False option: a string such as "no" would otherwise count as True."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)
