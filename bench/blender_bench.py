#!/usr/bin/env python3
"""Blender extension speed: the operators against the bare engine (figures only, no assertions).

    python bench/blender_bench.py [--n 100000] [--repeat 3]

1. Decompose of an n-vertex mesh through ``bpy.ops.pointscale.decompose()`` (reading the
   Basis, the engine, extracting levels and normals, writing 2k shape keys, k masks and the
   attributes) against ``pointscale.decompose`` alone on the same points.  Goal: within 1.3x.
2. Rebuild detail on n vertices, end to end (read the Level 0 key, reconstruct with normals
   recomputed, write the Multiscale Edit key): cold (first call after loading, which rebuilds
   the engine object from the attributes) and warm.  Goal: under 50 ms.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def load_addon():
    spec = importlib.util.spec_from_file_location(
        "pointscale_addon", ROOT / "addon" / "__init__.py", submodule_search_locations=[str(ROOT / "addon")]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules["pointscale_addon"] = module
    spec.loader.exec_module(module)
    return module


def mesh_object(bpy, points):
    me = bpy.data.meshes.new("Bench")
    me.vertices.add(len(points))
    me.vertices.foreach_set("co", points.astype(np.float32).reshape(-1))
    me.update()
    obj = bpy.data.objects.new("Bench", me)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def timed(fn, repeat):
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return out


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=100_000)
    ap.add_argument("--levels", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    import bpy
    import pointscale as ps

    addon = load_addon()
    addon.register()
    writeback = sys.modules["pointscale_addon.writeback"]
    bpy.ops.wm.read_factory_settings(use_empty=True)

    points = ps.shapes.bumpy_sphere(args.n)
    p32 = points.astype(np.float32).astype(np.float64)  # what the mesh holds
    print(f"Blender {bpy.app.version_string}, pointscale {getattr(ps, '__version__', '?')}, "
          f"n = {args.n}, levels = {args.levels}, best of {args.repeat}")

    engine = timed(lambda: ps.decompose(p32, levels=args.levels), args.repeat)
    obj = mesh_object(bpy, points)
    obj.data.multiscale.levels = args.levels
    op = timed(lambda: bpy.ops.pointscale.decompose(), args.repeat)
    e, o = min(engine), min(op)
    print(f"decompose  engine alone        {e * 1e3:9.1f} ms  (median {statistics.median(engine) * 1e3:.1f})")
    print(f"decompose  operator end to end {o * 1e3:9.1f} ms  (median {statistics.median(op) * 1e3:.1f})"
          f"  ratio {o / e:.2f}x  (goal <= 1.3x)")

    me = obj.data
    kb = me.shape_keys.key_blocks["Level 0"]
    base = np.empty(len(kb.points) * 3, np.float32)
    kb.points.foreach_get("co", base)
    base = base.reshape(-1, 3)
    base[:, 2] += 0.05 * np.exp(-(base[:, :2] ** 2).sum(axis=1) / 0.2)
    kb.points.foreach_set("co", base.reshape(-1))

    dec = writeback.decomposition(me, ps)
    bare = timed(lambda: ps.reconstruct(dec, base=base), args.repeat)
    writeback.forget_all()
    t = time.perf_counter()
    bpy.ops.pointscale.rebuild_detail()
    cold = time.perf_counter() - t
    warm = timed(lambda: bpy.ops.pointscale.rebuild_detail(), max(args.repeat, 5))
    print(f"rebuild    engine reconstruct  {min(bare) * 1e3:9.1f} ms")
    print(f"rebuild    operator, cold      {cold * 1e3:9.1f} ms  (engine object rebuilt from the attributes)")
    print(f"rebuild    operator, warm      {min(warm) * 1e3:9.1f} ms  (median {statistics.median(warm) * 1e3:.1f};"
          f" goal < 50 ms)")
    addon.unregister()
    return 0


if __name__ == "__main__":
    sys.exit(main())
