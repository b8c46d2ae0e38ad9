"""Input checks shared by the public functions: every bad input becomes a clear ValueError."""
from __future__ import annotations

import numpy as np


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
    return a


def column_reduce(points: np.ndarray, reduce) -> np.ndarray:
    """reduce (np.min, np.max, np.mean) of each column of an (n, 3) array: column by column,
    since NumPy's axis-0 reductions over three columns are about fifteen times slower."""
    return np.array([reduce(points[:, a]) for a in range(points.shape[1])])


def centre(points: np.ndarray) -> np.ndarray:
    """The bounding-box centre: subtracting it keeps precision for data far from the origin."""
    return 0.5 * (column_reduce(points, np.min) + column_reduce(points, np.max))


def extent_eigenvalues(points: np.ndarray) -> np.ndarray:
    """Square roots of the covariance eigenvalues, largest first: the spread along 3 axes."""
    c = points - column_reduce(points, np.mean)
    ev = np.linalg.eigvalsh(c.T @ c / len(points))
    return np.sqrt(np.clip(ev[::-1], 0.0, None))


def require_surface(points: np.ndarray, name: str = "points", allow_planar: bool = False) -> None:
    """Rejects sets that span no surface: all identical, collinear, or (unless allowed) planar."""
    spread = extent_eigenvalues(points)
    if spread[0] == 0.0:
        raise ValueError(f"all {name} are identical: they define no surface")
    # Rounding leaves eigenvalues near 1e-16 of the largest, so spreads below 1e-6 count as zero.
    if spread[1] <= 1e-6 * spread[0]:
        raise ValueError(f"{name} are collinear: they define no surface and no normals")
    if not allow_planar and spread[2] <= 1e-6 * spread[0]:
        raise ValueError(f"{name} all lie in one plane: there is no detail to separate from a base "
                         "(use project() to work with planar data)")


def positive(value, name: str, integer: bool = False, minimum=None):
    """Checks a scalar option; returns it as int or float."""
    try:
        v = int(value) if integer else float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if integer and v != value:
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    if not np.isfinite(v) or v <= 0 or (minimum is not None and v < minimum):
        lo = f">= {minimum}" if minimum is not None else "> 0"
        raise ValueError(f"{name} must be {lo}, got {value!r}")
    return v


def as_callback(progress):
    if progress is not None and not callable(progress):
        raise ValueError("progress must be a callable taking a fraction in [0, 1], or None")
    return progress
