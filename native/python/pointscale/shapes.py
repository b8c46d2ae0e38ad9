"""Procedural shapes with detail at several scales, for the demo, tests and benchmarks.

Every function returns float64 (n, 3) points (and, where said, extra per-point data); none needs
a download. Sampling is near-uniform so that spacing-based kernels behave as on scans.
"""
from __future__ import annotations

import numpy as np


def fibonacci_sphere(n: int) -> np.ndarray:
    """n near-uniform unit vectors (the golden-angle spiral)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def sphere(n: int = 20000, radius: float = 1.0, noise: float = 0.0, seed: int = 0) -> np.ndarray:
    """A sphere, optionally with Gaussian radial noise of standard deviation `noise`."""
    u = fibonacci_sphere(n)
    r = radius + noise * np.random.default_rng(seed).standard_normal(n)
    return u * r[:, None]


def bump_field(u: np.ndarray, frequency: float) -> np.ndarray:
    """A smooth pattern on unit vectors, about `frequency` bumps around a great circle, in [-1, 1]."""
    f = frequency
    return np.sin(f * u[:, 0]) * np.sin(f * u[:, 1] + 0.3) * np.sin(f * u[:, 2] + 0.7)


def bumpy_sphere(n: int = 40000, coarse: float = 0.08, coarse_frequency: float = 3.0, fine: float = 0.01,
                 fine_frequency: float = 25.0, noise: float = 0.0, seed: int = 0) -> np.ndarray:
    """A unit sphere with a coarse and a fine bump pattern (and optional noise) on its radius."""
    u = fibonacci_sphere(n)
    r = 1.0 + coarse * bump_field(u, coarse_frequency) + fine * bump_field(u, fine_frequency)
    if noise:
        r = r + noise * np.random.default_rng(seed).standard_normal(n)
    return u * r[:, None]


def bumpy_torus(n: int = 40000, major: float = 1.0, minor: float = 0.35, fine: float = 0.015,
                frequency: float = 12.0) -> np.ndarray:
    """A torus around z with a fine bump pattern on its tube radius."""
    side = int(np.sqrt(n * minor / major))
    nu, nv = max(8, n // max(side, 1)), max(8, side)
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, nu, endpoint=False),
                       np.linspace(0, 2 * np.pi, nv, endpoint=False), indexing="ij")
    u, v = u.ravel(), v.ravel()
    r = minor + fine * np.sin(frequency * u) * np.sin(frequency * v / 2 + 0.5)
    return np.column_stack([(major + r * np.cos(v)) * np.cos(u), (major + r * np.cos(v)) * np.sin(u), r * np.sin(v)])


def wavy_patch(n: int = 30000, size: float = 2.0, coarse: float = 0.15, fine: float = 0.01,
               fine_frequency: float = 20.0) -> np.ndarray:
    """An open height-field square with a boundary: a broad wave plus fine ripples."""
    side = int(np.sqrt(n))
    x, y = np.meshgrid(np.linspace(-size / 2, size / 2, side), np.linspace(-size / 2, size / 2, side), indexing="ij")
    x, y = x.ravel(), y.ravel()
    z = coarse * np.sin(1.5 * x) * np.cos(1.2 * y) + fine * np.sin(fine_frequency * x) * np.sin(fine_frequency * y)
    return np.column_stack([x, y, z])


def handles_plane(size: float = 4.0, spacing: float = 0.025, count: int = 4, width: float = 0.2,
                  height: float = 0.2):
    """A square plane (z = 0) with count x count box handles on it, as in the paper's Fig. 5.

    Returns (points (n, 3), handle (n,) int: -1 on the plane, else the handle's index, and
    centres (count*count, 2): each handle's (x, y) centre).
    """
    ticks = np.arange(-size / 2, size / 2 + 1e-9, spacing)
    x, y = np.meshgrid(ticks, ticks, indexing="ij")
    plane = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    step = size / count
    c1 = -size / 2 + step * (np.arange(count) + 0.5)
    centres = np.array([(cx, cy) for cx in c1 for cy in c1])
    half = width / 2
    keep = np.ones(len(plane), bool)
    parts, labels = [], []
    s = np.arange(-half, half + 1e-9, spacing)
    s = s - s.mean()
    zs = np.arange(spacing, height - 1e-9, spacing)
    for h, (cx, cy) in enumerate(centres):
        inside = (np.abs(plane[:, 0] - cx) < half) & (np.abs(plane[:, 1] - cy) < half)
        keep &= ~inside
        tx, ty = np.meshgrid(s, s, indexing="ij")
        top = np.column_stack([cx + tx.ravel(), cy + ty.ravel(), np.full(tx.size, height)])
        walls = []
        for z in zs:
            for t in s:
                walls += [(cx + t, cy - half, z), (cx + t, cy + half, z), (cx - half, cy + t, z), (cx + half, cy + t, z)]
        part = np.vstack([top, np.array(walls)])
        parts.append(part)
        labels.append(np.full(len(part), h))
    points = np.vstack([plane[keep]] + parts)
    handle = np.concatenate([np.full(int(keep.sum()), -1)] + labels)
    return points, handle, centres


def handle_angles(result, points, handle, centres, surface) -> np.ndarray:
    """How upright the handles of `handles_plane` stand after a deformation (Fig. 5).

    result   #P by 3 deformed points, indexed like `points`
    points, handle, centres   as returned by handles_plane
    surface  #P by 3 positions whose plane points around each handle give the reference normal
             (the deformed base for a multiscale edit, `result` itself for a single-scale one)
    Returns (#handles,) angles in degrees between each handle's axis (bottom ring to top face)
    and the normal of a plane fitted to the surface ring around it.
    """
    angles = []
    for i, (cx, cy) in enumerate(centres):
        mine = handle == i
        top = mine & (points[:, 2] > points[mine, 2].max() - 1e-6)
        low = mine & (points[:, 2] < points[mine, 2].min() + 1e-6)
        axis = result[top].mean(axis=0) - result[low].mean(axis=0)
        r = np.hypot(points[:, 0] - cx, points[:, 1] - cy)
        ring = surface[(handle == -1) & (r > 0.15) & (r < 0.4)]
        normal = np.linalg.svd(ring - ring.mean(axis=0), full_matrices=False)[2][2]
        angles.append(np.degrees(np.arccos(abs(axis @ normal) / np.linalg.norm(axis))))
    return np.array(angles)


def thin_plate(size_u: float = 2.0, size_v: float = 1.6, spacing: float = 0.025, gap: float | None = None,
               bend: float = 0.0):
    """A two-sided plate: two grids `gap` apart (default one spacing), bent by bend * u**2.

    Returns (points, outward normals, side): side is +1 for the upper sheet, -1 for the lower,
    and row i of the upper sheet lies over row i of the lower one.
    """
    gap = spacing if gap is None else gap
    u, v = np.meshgrid(np.arange(-size_u / 2, size_u / 2 + spacing / 2, spacing),
                       np.arange(-size_v / 2, size_v / 2 + spacing / 2, spacing))
    u, v = u.ravel(), v.ravel()
    mid = bend * u ** 2
    up = np.c_[-2.0 * bend * u, np.zeros_like(u), np.ones_like(u)]
    up /= np.linalg.norm(up, axis=1)[:, None]
    centre = np.c_[u, v, mid]
    points = np.r_[centre + 0.5 * gap * up, centre - 0.5 * gap * up]
    return points, np.r_[up, -up], np.r_[np.ones(len(u)), -np.ones(len(u))]


def _box_surface(half: np.ndarray, spacing: float):
    """Grid samples of a box's surface (half-sizes `half`), each once, with outward normals."""
    points, normals = [], []
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        ticks = [np.linspace(-half[a], half[a], max(2, int(round(2 * half[a] / spacing)) + 1)) for a in others]
        s, t = (g.ravel() for g in np.meshgrid(*ticks))
        for sign in (-1.0, 1.0):
            p = np.zeros((len(s), 3))
            p[:, axis], p[:, others[0]], p[:, others[1]] = sign * half[axis], s, t
            n = np.zeros_like(p)
            n[:, axis] = sign
            points.append(p)
            normals.append(n)
    points, normals = np.concatenate(points), np.concatenate(normals)
    _, first = np.unique(np.round(points / spacing, 6), axis=0, return_index=True)  # edges once
    first.sort()
    return points[first], normals[first]


def thin_walled_box(size=(2.0, 1.6, 1.2), spacing: float = 0.025, gap: float | None = None):
    """A closed box whose walls are `gap` thick (default one spacing), sampled on both sides.

    Returns (points, outward normals of the wall, outer): outer is True on the outside, whose
    normals point away from the box; the inside's point into the cavity.
    """
    gap = spacing if gap is None else gap
    half = np.asarray(size, dtype=float) / 2
    if half.shape != (3,) or not (half > gap).all() or not 0 < spacing < half.min():
        raise ValueError(f"thin_walled_box needs size as three lengths (x, y, z) above twice the gap {gap} and a "
                         f"spacing below half the smallest, got size={size!r}, spacing={spacing}")
    outer_p, outer_n = _box_surface(half, spacing)
    inner_p, inner_n = _box_surface(half - gap, spacing)
    outer = np.r_[np.ones(len(outer_p), bool), np.zeros(len(inner_p), bool)]
    return np.r_[outer_p, inner_p], np.r_[outer_n, -inner_n], outer
