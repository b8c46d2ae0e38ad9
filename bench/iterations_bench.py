#!/usr/bin/env python3
"""How much of decompose is the MLS iteration: decompose(levels=4) at the default iteration cap
(30) and at 3 and 1 plane fits per point and level (1 is the peers' single pass), in one warm
process, medians of 3. The round trip stays exact at any cap (the offsets are made normal
after the projection); what a lower cap changes is how far each level is from the MLS surface.

    python bench/iterations_bench.py [--data-dir DIR]

Inputs: the dragon in file order (skipped without it) and a 1M bumpy sphere in Morton order.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import pointscale as ps  # noqa: E402
from median_time import median_time  # noqa: E402
from run import bumpy_sphere, morton_order  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data-dir", default=str(HERE.parent.parent / "shared" / "data"))
    args = p.parse_args()
    inputs = []
    dragon = Path(args.data_dir) / "dragon.ply"
    if dragon.exists():
        inputs.append(("dragon.ply, file order", ps.io.read(dragon).points))
    else:
        print(f"dragon: skipped, not in {args.data_dir}")
    sphere = bumpy_sphere(1_000_000)
    inputs.append(("bumpy sphere 1M, Morton order", sphere[morton_order(sphere)]))
    print("| input | max_iterations | decompose (s) | points at the cap, level 0 / 1 / 2 | round trip / diagonal |")
    print("|---|---|---|---|---|")
    for label, points in inputs:
        diagonal = np.linalg.norm(np.ptp(points, axis=0))
        for cap in (30, 3, 1):
            def call():
                return ps.decompose(points, levels=4, neighbors=24, threads=2, max_iterations=cap)
            dec = call()  # warm-up, and the model to report on
            seconds = median_time(call, 3)
            capped = " / ".join(str(s["not_converged"]) for s in dec.stats)
            error = np.abs(ps.reconstruct(dec) - points).max() / diagonal
            print(f"| {label} | {cap} | {seconds:.2f} | {capped} | {error:.1e} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
