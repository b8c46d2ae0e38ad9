"""Aligning two models before a morph (Sec. 8.3; the paper aligned Fig. 9's heads by hand).

morph() projects both models onto one base, so they must overlap. similarity(b, a, method) finds
the similarity transform x -> scale * R x + t that carries B onto A:

- "bbox": B's bounding box centre onto A's, and its diagonal scaled to A's (no rotation);
- "pca": B's centroid and principal axes onto A's, scaled by the spread; of the four proper
  sign choices of the axes, the one that leaves B nearest to A;
- "icp": "pca", then rigid iterative closest points (the scale stays the principal axes'), from
  each of the four sign choices, keeping the best.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import _core

METHODS = ("none", "bbox", "pca", "icp")
#: Points of each model that the fits use at most (a random but seeded subset).
_SAMPLE = 4000
_ICP_ROUNDS = 30


@dataclass(frozen=True)
class Similarity:
    """x -> scale * rotation @ x + translation, on (n, 3) rows."""

    scale: float = 1.0
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def apply(self, points: np.ndarray) -> np.ndarray:
        return self.scale * points @ self.rotation.T + self.translation

    def inverse(self) -> "Similarity":
        r = self.rotation.T
        return Similarity(1.0 / self.scale, r, -(r @ self.translation) / self.scale)

    def matrix(self) -> np.ndarray:
        """The 4 x 4 homogeneous matrix."""
        m = np.eye(4)
        m[:3, :3] = self.scale * self.rotation
        m[:3, 3] = self.translation
        return m


def _sample(points: np.ndarray, count: int = _SAMPLE) -> np.ndarray:
    if len(points) <= count:
        return points
    return points[np.random.default_rng(0).choice(len(points), count, replace=False)]


def nearest_indices(onto: np.ndarray, points: np.ndarray, threads: int = 0) -> np.ndarray:
    """The index of each point's nearest point of `onto`: the core's k-nearest interpolation of
    the indices themselves, with one neighbour (its weight is then the whole)."""
    values = np.arange(len(onto), dtype=np.float64)
    return np.rint(_core.knn_interpolate(onto, values, points, k=1, threads=threads)).astype(np.int64)


def _mean_distance(a: np.ndarray, b: np.ndarray, threads: int) -> float:
    """Mean distance of b's points to their nearest in a, and of a's to b (symmetric)."""
    d_ba = np.linalg.norm(b - a[nearest_indices(a, b, threads)], axis=1).mean()
    d_ab = np.linalg.norm(a - b[nearest_indices(b, a, threads)], axis=1).mean()
    return 0.5 * (d_ab + d_ba)


def _bbox(b: np.ndarray, a: np.ndarray) -> Similarity:
    lo_a, hi_a, lo_b, hi_b = a.min(0), a.max(0), b.min(0), b.max(0)
    scale = np.linalg.norm(hi_a - lo_a) / np.linalg.norm(hi_b - lo_b)
    return Similarity(scale, np.eye(3), 0.5 * (lo_a + hi_a) - scale * 0.5 * (lo_b + hi_b))


def _axes(points: np.ndarray):
    centre = points.mean(axis=0)
    values, vectors = np.linalg.eigh(np.cov((points - centre).T))
    return centre, vectors[:, ::-1], np.sqrt(np.maximum(values[::-1], 0.0).sum())


def _pca_candidates(b: np.ndarray, a: np.ndarray) -> list[Similarity]:
    ca, va, sa = _axes(a)
    cb, vb, sb = _axes(b)
    scale = sa / sb
    out = []
    for flips in ((1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)):
        r = (va * np.array(flips)) @ vb.T
        if np.linalg.det(r) < 0:  # va or vb left-handed: a proper rotation flips the last axis
            r = (va * np.array(flips[:2] + (-flips[2],))) @ vb.T
        out.append(Similarity(scale, r, ca - scale * r @ cb))
    return out


def _rigid_fit(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation that carry source rows onto target rows (Kabsch)."""
    cs, ct = source.mean(0), target.mean(0)
    u, _, vt = np.linalg.svd((source - cs).T @ (target - ct))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, ct - r @ cs


def _icp(b: np.ndarray, a: np.ndarray, start: Similarity, threads: int) -> Similarity:
    current = start
    for _ in range(_ICP_ROUNDS):
        moved = current.apply(b)
        r, t = _rigid_fit(moved, a[nearest_indices(a, moved, threads)])
        current = Similarity(current.scale, r @ current.rotation, r @ current.translation + t)
        if np.abs(r - np.eye(3)).max() < 1e-9 and np.linalg.norm(t) < 1e-9 * current.scale:
            break
    return current


def similarity(points_b: np.ndarray, points_a: np.ndarray, method: str, *, threads: int = 0) -> Similarity:
    """The similarity that carries B onto A by `method` (METHODS; "none" is the identity).
    threads: as morph's, for the nearest-point queries."""
    if method not in METHODS:
        raise ValueError(f"align must be one of {', '.join(METHODS)}, got {method!r}")
    if method == "none":
        return Similarity()
    a, b = _sample(points_a), _sample(points_b)
    if method == "bbox":
        return _bbox(b, a)
    candidates = _pca_candidates(b, a)
    if method == "icp":
        candidates = [_icp(b, a, c, threads) for c in candidates]
    return min(candidates, key=lambda s: _mean_distance(a, s.apply(b), threads))


def overlap(points_a: np.ndarray, points_b: np.ndarray) -> float:
    """How much the two models' bounding boxes overlap: intersection over union of their volumes."""
    # A flat model's box is given a sliver of thickness, so that it still has a volume.
    floor = 1e-3 * max(np.linalg.norm(np.ptp(points_a, 0)), np.linalg.norm(np.ptp(points_b, 0)))
    boxes = [(p.min(0) - floor, p.max(0) + floor) for p in (points_a, points_b)]
    lo = np.maximum(boxes[0][0], boxes[1][0])
    hi = np.minimum(boxes[0][1], boxes[1][1])
    inter = np.prod(np.clip(hi - lo, 0.0, None))
    union = sum(np.prod(h - l) for l, h in boxes) - inter
    return float(inter / union) if union > 0 else 0.0
