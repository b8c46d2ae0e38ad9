"""Folds (issue 16, item 5): how many points fold without and with prevention, how far the
points that did not fold move, and the time prevention adds to reconstruct.

    python bench/folds_bench.py [--data ../shared/data] [--repeat 3]

Max Planck at gains (2, 2, 1) and (1, 1, 3), the dragon at (1, 1, 3), each decomposed with
levels=4 and the defaults. Times are medians of --repeat runs; the fold reference (one unedited
reconstruction and the reversed rings, made once per decomposition) is timed apart.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import pointscale as ps
from pointscale.folds import reference_for

CASES = [("max_planck.ply", (2, 2, 1)), ("max_planck.ply", (1, 1, 3)), ("dragon.ply", (1, 1, 3))]


def median_time(call, repeat: int):
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = call()
        times.append(time.perf_counter() - t)
    return float(np.median(times)), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(Path(__file__).resolve().parents[1] / ".." / "shared" / "data"))
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    decs = {}
    print(f"{'model':<12} {'gains':<10} {'ref':<6} {'folds':>6} {'after':>6} {'moved':>7} {'rounds':>6} "
          f"{'max move, non-fold points':>26} {'out of reach':>12} {'recon ms':>9} {'report':>7} {'prevent':>8} "
          f"{'reference ms':>12}")
    for name, gains in CASES:
        if name not in decs:
            decs[name] = ps.decompose(ps.io.read(Path(args.data) / name).points, levels=4)
        dec = decs[name]
        ps.reconstruct(dec, gains)  # the working arrays, once
        for against in ("input", "base"):
            dec._cache.pop("fold_reference_" + against, None)
            t_ref, _ = median_time(lambda: reference_for(dec, against), 1)
            t_plain, plain = median_time(lambda: ps.reconstruct(dec, gains), args.repeat)
            t_report, _ = median_time(lambda: ps.reconstruct(dec, gains, folds="report", fold_reference=against),
                                      args.repeat)
            t_prevent, (points, folds) = median_time(
                lambda: ps.reconstruct(dec, gains, folds="prevent", fold_reference=against), args.repeat)
            diag = float(np.linalg.norm(np.ptp(plain, axis=0)))
            move = np.linalg.norm(points - plain, axis=1) / diag
            not_folding = folds.before == 0
            reach = folds.limiter == 1.0
            print(f"{name.split('.')[0]:<12} {str(gains):<10} {against:<6} {folds.count_before:>6} {folds.count:>6} "
                  f"{int(folds.changed.sum()):>7} {folds.rounds:>5}{'!' if folds.capped else ' '} "
                  f"{move[not_folding].max():>26.3g} {move[reach].max():>12.3g} {1e3 * t_plain:>9.1f} "
                  f"{t_report / t_plain - 1:>+7.0%} {t_prevent / t_plain - 1:>+8.0%} {1e3 * t_ref:>12.1f}")
    print("folds: points that fold as reconstructed; after: with prevention; moved: points whose gain it "
          "limits; max move: over the points that did not fold, as a fraction of the diagonal; out of reach: "
          "the same over the points the limiter does not reach; report/prevent: time added to reconstruct "
          "(the reference apart); rounds ending in '!' hit the cap with folds left")


if __name__ == "__main__":
    main()
