#!/usr/bin/env python3
"""Blender extension on heavy scenes: the operators against the bare engine (figures, no assertions).

    python bench/blender_bench.py [--n 1000000 300000] [--levels 4] [--repeat 3]

Each size runs in its own process (memory figures need a fresh one). Per size:

1. Decompose through ``bpy.ops.pointscale.decompose()`` against ``pointscale.decompose`` alone on
   the same points (interleaved, medians), and the main thread's share of the modal path: the
   operator's ``_finish`` (the write-back) on a result computed as the worker thread computes it.
   Goals (issue 18, requirement 4): write-back under 300 ms.
2. Memory retained by the first decompose, beyond Blender's own keys (2k + 1 keys of 12 bytes a
   vertex): RSS after minus before, both after gc and malloc_trim, and the engine model's share
   (freed when the cache is dropped). Goal: under 300 bytes a vertex.
3. .blend size (uncompressed) before and after the decompose against the keys' own bytes. Goal:
   growth at most 1.5x the keys.
4. Bake Filter with every band's mask painted (random weights), and the weight readers alone.
   Goal: under 300 ms.
5. Save, reload, and check nothing is lost: keys, masks, settings, and Rebuild Detail and Bake
   Filter give the results of before the save bit for bit (the first one after the reload
   decomposes the Basis again: its time is printed).
"""

from __future__ import annotations

import argparse
import ctypes
import gc
import importlib.util
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

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


def mesh_object(bpy, points, name="Bench"):
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(points))
    me.vertices.foreach_set("co", points.astype(np.float32).reshape(-1))
    me.update()
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def rss() -> int:
    """Resident bytes after giving freed memory back (glibc keeps freed blocks otherwise)."""
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except OSError:
        pass
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def key(mesh, name):
    kb = mesh.shape_keys.key_blocks[name]
    co = np.empty(len(kb.points) * 3, np.float32)
    kb.points.foreach_get("co", co)
    return co.reshape(-1, 3)


def all_keys(mesh) -> dict:
    return {kb.name: (key(mesh, kb.name), kb.value, kb.vertex_group, kb.mute) for kb in mesh.shape_keys.key_blocks}


def same_keys(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(a[k][0], b[k][0]) and a[k][1:] == b[k][1:] for k in a)


def save(bpy, path) -> int:
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=False, copy=True)
    return path.stat().st_size


def ms(seconds) -> str:
    return f"{1e3 * seconds:8.1f} ms"


def paint_masks(bpy, obj, k: int, rng) -> None:
    """Every band's mask through the panel's brush button, then random weights in 64 steps (one
    vg.add per step: a call per vertex would take minutes at 1M)."""
    n = len(obj.data.vertices)
    for l in range(k):
        assert bpy.ops.pointscale.paint_band_mask(band=l, enter_paint=False) == {"FINISHED"}
        vg = obj.vertex_groups[f"Band {l} mask"]
        step = rng.integers(0, 64, n)
        for s in range(64):
            vg.add(np.flatnonzero(step == s).tolist(), float(np.float32(s / 63.0)), "REPLACE")


def run(n: int, levels: int, repeat: int) -> None:
    import bpy
    import pointscale as ps

    addon = load_addon()
    addon.register()
    modules = {name: sys.modules[f"pointscale_addon.{name}"] for name in
               ("writeback", "group_weights", "mesh_io", "keys", "operators.decompose")}
    writeback, decompose_op = modules["writeback"], modules["operators.decompose"]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    tmp = Path(tempfile.mkdtemp(prefix="pointscale-bench-"))
    print(f"== n = {n}: Blender {bpy.app.version_string}, pointscale {getattr(ps, '__version__', '?')}, "
          f"levels = {levels}, {os.cpu_count()} cores, medians of {repeat} interleaved runs", flush=True)

    warm = mesh_object(bpy, ps.shapes.bumpy_sphere(5000), "Warm-up")  # load every code path once
    warm.data.multiscale.levels = levels
    bpy.ops.pointscale.decompose()
    bpy.data.objects.remove(warm)
    writeback.forget_all()

    points = ps.shapes.bumpy_sphere(n)
    p32 = points.astype(np.float32)
    obj = mesh_object(bpy, points)
    me = obj.data
    me.multiscale.levels = levels
    size_before = save(bpy, tmp / "before.blend")
    k = levels - 1
    key_bytes = (2 * k + 1) * n * 12  # Basis, Level and Band keys, float32 xyz

    bpy.context.view_layer.objects.active = obj
    before = rss()
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    assert me.multiscale.n_bands == k
    after = rss()
    retained = after - before - key_bytes
    writeback.forget_all()
    model = after - rss()  # what the cached engine object (the model Rebuild Detail needs) holds
    # Blender's own share, after ours (memory it frees it reuses, which would hide ours): as many
    # keys on a copy, evaluated as the operator's view-layer update evaluates them
    control = mesh_object(bpy, points, "Control")
    start = rss()
    control.shape_key_add(name="Basis")
    for l in range(2 * k):
        control.shape_key_add(name=f"Key {l}").points.foreach_set("co", (p32 + l).reshape(-1))
    bpy.context.view_layer.update()
    blender_own = rss() - start - key_bytes
    control_mesh = control.data
    bpy.data.objects.remove(control)
    bpy.data.meshes.remove(control_mesh)
    bpy.context.view_layer.objects.active = obj
    ours = sum(a.data_type in {"FLOAT", "INT"} and 4 or 12 for a in me.attributes
               if a.name.startswith(("ms_", ".ps.")))
    size_after = save(bpy, tmp / "after.blend")
    growth = size_after - size_before

    # -- speed, interleaved
    engine, operator, finish = [], [], []
    kwargs = decompose_op.compute.decompose_kwargs(levels)
    for _ in range(repeat):
        t = time.perf_counter()
        ps.decompose(p32.astype(np.float64), levels=levels)
        engine.append(time.perf_counter() - t)
        t = time.perf_counter()
        bpy.ops.pointscale.decompose()
        operator.append(time.perf_counter() - t)
        result = decompose_op._computed(ps, p32, kwargs)  # what the worker thread hands over
        me_op = SimpleNamespace(report=lambda *a: None)
        t = time.perf_counter()
        decompose_op.POINTSCALE_OT_decompose._finish(me_op, bpy.context, obj, result, p32)
        finish.append(time.perf_counter() - t)
        del result
    e, o, f = (statistics.median(x) for x in (engine, operator, finish))
    print(f"decompose  engine alone            {ms(e)}")
    print(f"decompose  operator end to end     {ms(o)}  ({o / e:.2f}x the engine)")
    print(f"decompose  modal: main thread      {ms(f)}  (the write-back in _finish; goal < 300 ms)")
    print(f"memory     retained after decompose {retained / n:7.0f} B/vertex beyond the keys' {key_bytes / n:.0f}, "
          f"{(retained - blender_own) / n:.0f} beyond Blender's evaluated copy of them ({blender_own / n:.0f}, on a "
          f"control object; goal < 300): the engine model {model / n:.0f} B, our attributes {ours} B")
    print(f".blend     {size_before / 1e6:.1f} MB -> {size_after / 1e6:.1f} MB: +{growth / 1e6:.1f} MB, keys "
          f"{key_bytes / 1e6:.1f} MB, growth {growth / key_bytes:.2f}x the keys (goal <= 1.5x)", flush=True)

    # -- Bake Filter with painted masks
    rng = np.random.default_rng(0)
    paint_masks(bpy, obj, k, rng)
    for l in range(k):
        me.shape_keys.key_blocks[f"Band {l}"].value = (0.5, -0.3, 1.0, 0.2)[l % 4]
    masks = [f"Band {l} mask" for l in range(k)]
    t = time.perf_counter()
    slow = modules["mesh_io"].read_group_weights(obj, masks, n)
    t_slow = time.perf_counter() - t
    bulk_times, bake, engine_bake, evaluate = [], [], [], []
    dec = writeback.decomposition(me, ps)
    gains = 1.0 + np.array([kb.value for kb in me.shape_keys.key_blocks if kb.name.startswith("Band ")])[:, None] \
        * np.stack(slow)
    for _ in range(repeat):
        t = time.perf_counter()
        ps.reconstruct(dec, gains=gains, folds="report")  # the engine's share of Bake Filter
        engine_bake.append(time.perf_counter() - t)
        t = time.perf_counter()
        bulk = modules["group_weights"].read(obj, masks, n)
        bulk_times.append(time.perf_counter() - t)
        # A settled scene, as when the artist presses the button: the probe object the bulk read
        # made and removed is evaluated away first, at Blender's next redraw in the UI.
        bpy.context.view_layer.update()
        t = time.perf_counter()
        assert bpy.ops.pointscale.bake_filter(reset_bands=False) == {"FINISHED"}
        bake.append(time.perf_counter() - t)
        t = time.perf_counter()
        me.shape_keys.key_blocks["Multiscale Filter"].value = 1.0  # the same key shown again: Blender's
        bpy.context.view_layer.update()                            # own evaluation of the mesh
        evaluate.append(time.perf_counter() - t)
    exact = all(np.array_equal(a, b) for a, b in zip(slow, bulk))
    print(f"weights    Python loop             {ms(t_slow)}  ({k} masks)")
    print(f"weights    Geometry Nodes, bulk    {ms(statistics.median(bulk_times))}  (equal: {exact})")
    b, eb = statistics.median(bake), statistics.median(engine_bake)
    print(f"bake       Bake Filter             {ms(b)}  (goal < 300 ms); the engine's reconstruct with the "
          f"fold check alone {ms(eb).strip()}, the add-on's share {ms(b - eb).strip()}, of which Blender's "
          f"own evaluation of the mesh after it (through bpy.ops) about {ms(statistics.median(evaluate)).strip()}",
          flush=True)
    del dec

    # -- Rebuild Detail on an edited base, then save and reload
    base = key(me, "Level 0")
    base[:, 2] += 0.05 * np.exp(-(base[:, :2] ** 2).sum(axis=1) / 0.2)
    me.shape_keys.key_blocks["Level 0"].points.foreach_set("co", base.reshape(-1))
    warm_rebuild = []
    for _ in range(repeat):
        t = time.perf_counter()
        assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
        warm_rebuild.append(time.perf_counter() - t)
    print(f"rebuild    Rebuild Detail, warm    {ms(statistics.median(warm_rebuild))}")
    assert bpy.ops.pointscale.bake_filter(reset_bands=False) == {"FINISHED"}  # on the edited base too
    keys_before = all_keys(me)
    weights_before = modules["group_weights"].read(obj, masks, n)
    settings_before = (me.multiscale.n_bands, me.multiscale.levels, me["pointscale"]["recipe"])
    size_saved = save(bpy, tmp / "saved.blend")

    bpy.ops.wm.open_mainfile(filepath=str(tmp / "saved.blend"))
    obj = bpy.data.objects["Bench"]
    me = obj.data
    bpy.context.view_layer.objects.active = obj
    kept = (same_keys(keys_before, all_keys(me))
            and all(np.array_equal(a, b) for a, b in zip(weights_before, modules["group_weights"].read(obj, masks, n)))
            and settings_before == (me.multiscale.n_bands, me.multiscale.levels, me["pointscale"]["recipe"]))
    t = time.perf_counter()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    cold = time.perf_counter() - t
    rebuilt = np.array_equal(key(me, "Multiscale Edit"), keys_before["Multiscale Edit"][0])
    assert bpy.ops.pointscale.bake_filter(reset_bands=False) == {"FINISHED"}
    baked = np.array_equal(key(me, "Multiscale Filter"), keys_before["Multiscale Filter"][0])
    print(f"reload     .blend with masks and results {size_saved / 1e6:.1f} MB; keys, masks, settings kept: {kept}")
    print(f"reload     first Rebuild Detail    {ms(cold)}  (decomposes the Basis again); same result: {rebuilt}; "
          f"Bake Filter same: {baked}", flush=True)
    for path in tmp.iterdir():
        path.unlink()
    tmp.rmdir()


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="+", default=[1_000_000, 300_000])
    ap.add_argument("--levels", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if len(args.n) > 1:
        for n in args.n:
            code = subprocess.call([sys.executable, __file__, "--n", str(n), "--levels", str(args.levels),
                                    "--repeat", str(args.repeat)])
            if code:
                return code
        return 0
    run(args.n[0], args.levels, args.repeat)
    sys.stdout.flush()
    os._exit(0)  # bpy can hang in its exit handlers after a file was opened


if __name__ == "__main__":
    sys.exit(main())
