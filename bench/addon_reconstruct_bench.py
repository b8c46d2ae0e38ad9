#!/usr/bin/env python3
"""Rebuild Detail and Bake Filter through bpy.ops, as an artist calls them (figures, no assertions).

    python bench/addon_reconstruct_bench.py [--n 100000 1000000] [--repeat 7]

Each size runs in its own process. A bumpy sphere in the generator's order is decomposed
through the add-on (4 levels), every band's mask painted with random weights and the band
sliders set. Then, as a session goes:
1. Bake Filter, first call after the decompose, then the median of --repeat more;
2. a lift of Level 0, then Rebuild Detail: first call, then the median of --repeat more;
3. brushing: Level 0 lifted a little further before each Rebuild Detail (median of --repeat);
4. Bake Filter on the edited base (median of --repeat);
and the process's resident memory after all of it, against after the decompose.
--without-solver runs the same with the operators calling pointscale.reconstruct with nothing
kept between calls instead of the Reconstructor the add-on keeps per mesh, for comparison.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

import numpy as np

from blender_bench import key, load_addon, mesh_object, paint_masks, rss


def timed(call) -> float:
    t = time.perf_counter()
    assert call() == {"FINISHED"}
    return time.perf_counter() - t


class Stateless:
    """What the operators would call without a kept solver: reconstruct() itself, with nothing
    kept between calls (the edit support it keeps with the decomposition dropped after each)."""

    def __init__(self, ps, dec):
        self.ps, self.dec = ps, dec

    def reconstruct(self, gains=None, base=None, **kwargs):
        try:
            return self.ps.reconstruct(self.dec, gains, base, **kwargs)
        finally:
            self.dec._cache.pop("edit", None)


def run(n: int, repeat: int, without_solver: bool) -> None:
    import bpy
    import pointscale as ps

    addon = load_addon()
    addon.register()
    if without_solver:
        writeback = sys.modules["pointscale_addon.writeback"]
        writeback.reconstructor = lambda mesh, ps: Stateless(ps, writeback.decomposition(mesh, ps))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    obj = mesh_object(bpy, ps.shapes.bumpy_sphere(n))
    me = obj.data
    me.multiscale.levels = 4
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    k = me.multiscale.n_bands
    paint_masks(bpy, obj, k, np.random.default_rng(0))
    for l in range(k):
        me.shape_keys.key_blocks[f"Band {l}"].value = (0.5, -0.3, 1.0, 0.2)[l % 4]
    after_decompose = rss()

    def bake():
        return bpy.ops.pointscale.bake_filter(reset_bands=False)

    first_bake = timed(bake)
    warm_bake = statistics.median(timed(bake) for _ in range(repeat))

    base = key(me, "Level 0")
    block = me.shape_keys.key_blocks["Level 0"]

    def lift(height):
        b = base.copy()
        b[:, 2] += height * np.exp(-(b[:, :2] ** 2).sum(axis=1) / 0.2)
        block.points.foreach_set("co", b.reshape(-1))

    lift(0.05)
    first_rebuild = timed(bpy.ops.pointscale.rebuild_detail)
    warm_rebuild = statistics.median(timed(bpy.ops.pointscale.rebuild_detail) for _ in range(repeat))
    brushing = []
    for i in range(repeat):
        lift(0.05 + 0.01 * (i + 1))
        brushing.append(timed(bpy.ops.pointscale.rebuild_detail))
    edited_bake = statistics.median(timed(bake) for _ in range(repeat))
    grown = rss() - after_decompose
    print(f"n = {n}, {'stateless reconstruct' if without_solver else 'kept Reconstructor'}, Blender {bpy.app.version_string}, {k} bands, medians of {repeat} (ms): "
          f"Bake Filter first {first_bake * 1e3:.0f}, warm {warm_bake * 1e3:.0f}; "
          f"Rebuild Detail first {first_rebuild * 1e3:.0f}, warm {warm_rebuild * 1e3:.0f}, "
          f"brushing {statistics.median(brushing) * 1e3:.0f}; Bake Filter on the edited base "
          f"{edited_bake * 1e3:.0f}; memory grown since the decompose {grown / n:.0f} B/vertex", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--without-solver", action="store_true")
    args = ap.parse_args()
    if len(args.n) > 1:
        for n in args.n:
            code = subprocess.call([sys.executable, __file__, "--n", str(n), "--repeat", str(args.repeat)]
                                   + (["--without-solver"] if args.without_solver else []))
            if code:
                return code
        return 0
    run(args.n[0], args.repeat, args.without_solver)
    sys.stdout.flush()
    import os
    os._exit(0)  # bpy can hang in its exit handlers


if __name__ == "__main__":
    sys.exit(main())
