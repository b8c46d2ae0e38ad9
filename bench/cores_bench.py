"""How much of a second core the projection uses: CPU time over wall time, measured, not asserted.

    python bench/cores_bench.py [--points 300000] [--reps 3]

Prints, per thread count, the wall time, the process's CPU time and their ratio for
`pointscale.project(points, points[::3])`, the bulk of a decompose. On an idle 2-core machine
the ratio at threads=0 approaches 2; other load on the machine lowers it, which is why this is
a benchmark and not a test (tests/test_threads.py only checks that a second thread starts).
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

import pointscale as ps


def measure(points: np.ndarray, surface: np.ndarray, threads: int) -> tuple[float, float]:
    wall = time.perf_counter()
    cpu = time.process_time()
    ps.project(points, surface, threads=threads)
    return time.perf_counter() - wall, time.process_time() - cpu


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=300000, help="cloud size (default 300000)")
    parser.add_argument("--reps", type=int, default=3, help="runs per thread count, median reported (default 3)")
    args = parser.parse_args(argv)
    points = ps.shapes.bumpy_sphere(args.points, noise=0.001)
    surface = points[::3]
    print(f"project({args.points} points onto {len(surface)}), {os.cpu_count()} cores, median of {args.reps}")
    print(f"{'threads':>8} {'wall s':>8} {'cpu s':>8} {'cpu/wall':>9}")
    for threads in (1, 2, 0):
        runs = sorted((measure(points, surface, threads) for _ in range(args.reps)), key=lambda r: r[0])
        wall, cpu = runs[len(runs) // 2]
        print(f"{threads:>8} {wall:8.3f} {cpu:8.3f} {cpu / wall:9.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
