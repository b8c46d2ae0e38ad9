#!/usr/bin/env python3
"""Ray shooting (encoding="rayshoot"): how far its finest level lies from the input, per scan.

    python bench/rayshoot_bench.py [--data ../shared/data]

Ray shooting's finest level resamples the input's MLS surface, so it is not the input; a ray
that meets the wrong sheet (through a small or thin part, to its other side) puts a point far
off. Per scan (file order, levels=4) and neighbours 24 and 12: the points of the finest level
farther from their input point than 1% and 5% of the bounding-box diagonal, the 99.9th
percentile and the largest of that distance, and the rays that missed per band (they fall
back to the orthogonal projection).
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

import pointscale as ps

SCANS = ["bunny.ply", "max_planck.ply", "fandisk.ply", "lucy_50k.ply", "nefertiti.ply"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(Path(__file__).resolve().parents[1] / ".." / "shared" / "data"))
    args = parser.parse_args()
    print("| scan | neighbours | > 1% | > 5% | 99.9th pct | largest | rays missed per band |")
    print("|---|---|---|---|---|---|---|")
    for name in SCANS:
        points = ps.io.read(Path(args.data) / name).points
        diag = np.linalg.norm(np.ptp(points, axis=0))
        for neighbors in (24, 12):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                dec = ps.decompose(points, encoding="rayshoot", neighbors=neighbors)
            off = np.linalg.norm(ps.reconstruct(dec) - points, axis=1) / diag
            print(f"| {name} | {neighbors} | {(off > 0.01).sum()} | {(off > 0.05).sum()} | "
                  f"{np.percentile(off, 99.9):.3f} | {off.max():.3f} | {dec.settings['rays_missed']} |")


if __name__ == "__main__":
    main()
