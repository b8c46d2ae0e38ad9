#!/usr/bin/env python3
"""Every point's k nearest among the points themselves: the grid of self_knn.h against a
kd-tree query per point (nanoflann), on the same points, side by side (figures only).

    python bench/knn_bench.py [--threads 2] [--reps 3]

The synthetic set is what a 1M decomposition's first step asks about: the 250k centroids of
the decimated 1M bumpy sphere, in their cluster (spatial) order. The dragon's 437k raw points
follow, Morton-sorted, when ../shared/data has them. Both sides include their setup (the
tree's build; the grid's sample, build and fallback tree). Rows are checked equal in distance.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pointscale  # noqa: E402
from pointscale import _testing  # noqa: E402
from run import bumpy_sphere, morton_order, read_ply_xyz  # noqa: E402


def best(fn, reps):
    times, out = [], None
    for _ in range(reps):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--data-dir", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    args = ap.parse_args()

    sets = []
    sphere = bumpy_sphere(1_000_000)
    centroids, _ = pointscale.decimate(sphere - sphere.mean(0), 250_000)
    sets.append(("250k centroids of the 1M sphere", np.ascontiguousarray(centroids)))
    dragon = Path(args.data_dir) / "dragon.ply"
    if dragon.exists():
        scan = read_ply_xyz(str(dragon))
        sets.append(("dragon 437k, Morton order", np.ascontiguousarray(scan[morton_order(scan)])))
    else:
        print(f"({dragon} not found: the dragon row is skipped)")

    print(f"threads {args.threads}, best of {args.reps}")
    print("| points | k | grid (s) | kd-tree (s) | speed-up | rows equal in distance |")
    print("|---|---|---|---|---|---|")
    for name, pts in sets:
        for k in (24, 40):
            g, (gi, gd) = best(lambda: _testing.self_knn(pts, k, threads=args.threads), args.reps)
            t, (ti, td) = best(lambda: _testing.kdtree_knn(pts, k, threads=args.threads), args.reps)
            same = bool(np.array_equal(gd, td))
            print(f"| {name} | {k} | {g:.3f} | {t:.3f} | {t / g:.2f}x | {same} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
