"""Thin sheets (issue 17): what decompose(..., sheets=True) costs, against the same call without.

    python bench/sheets_bench.py [--data ../shared/data] [--repeat 3]

Inputs: the benchmark's 1M bumpy sphere (generator order) and the dragon scan (file order),
with normals estimated and oriented once, outside the timing, and given to both calls; and a
thin-walled box (two-sided walls one spacing apart, generator order) with its exact normals.
Times are medians of --repeat runs in this process, levels=4 and the defaults.
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

import pointscale as ps
from median_time import median_time
from pointscale.shapes import bumpy_sphere, thin_walled_box


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(Path(__file__).resolve().parents[1] / ".." / "shared" / "data"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--points", type=int, default=1_000_000, help="size of the bumpy sphere")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    cases = []
    sphere = bumpy_sphere(args.points)
    cases.append((f"bumpy sphere {args.points:,}, generator order", sphere, ps.estimate_normals(sphere)))
    dragon = Path(args.data) / "dragon.ply"
    if dragon.exists():
        points = np.asarray(ps.io.read(dragon).points, dtype=np.float64)
        cases.append(("dragon, file order", points, ps.estimate_normals(points)))
    else:
        print(f"(no {dragon}: the dragon row is left out)")
    box, box_normals, _ = thin_walled_box((2.0, 1.6, 1.2), spacing=0.01)
    cases.append(("thin-walled box, generator order", box, box_normals))
    print(f"{'input':<40} {'points':>9} {'plain s':>8} {'sheets s':>9} {'cost':>6}")
    for name, points, normals in cases:
        plain = median_time(lambda: ps.decompose(points, 4, normals=normals), args.repeat)
        sheets = median_time(lambda: ps.decompose(points, 4, normals=normals, sheets=True), args.repeat)
        print(f"{name:<40} {len(points):>9,} {plain:>8.2f} {sheets:>9.2f} {sheets / plain - 1:>+6.0%}")


if __name__ == "__main__":
    main()
