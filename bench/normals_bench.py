"""Oriented normals, side by side (issue 19, requirement 4): pointscale.estimate_normals against
the build it replaced (a spanning tree grown by Prim's algorithm over the full k-neighbour
graph), Open3D's orient_normals_consistent_tangent_plane and MeshLab's point-cloud normals.

Every call runs in a fresh subprocess that loads one cloud, resets its peak RSS (VmHWM) and
times one estimate_normals; the sides alternate within each repetition, and the table shows
medians. Figures only, nothing is asserted. Inputs: a 1M bumpy sphere in the generator's order
(a spiral: coherent) and shuffled, the dragon and the Buddha scans in file order.

    python bench/normals_bench.py --old-python ../wt-old/.venv/bin/python --peer-python /path/to/python

--old-python: a Python whose `pointscale` is the old build (e.g. a git worktree of the commit
before, installed in its own venv); without it the old column reads n/a. --peer-python: a
Python with open3d and/or pymeshlab (default: this one); missing peers read n/a.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve()


# --------------------------------------------------------------------------- worker

def status_kib(field: str) -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise KeyError(field)


def worker(args) -> None:
    side = args.worker
    if side in ("pointscale", "old"):
        import pointscale

        def run(p):
            return pointscale.estimate_normals(p, neighbors=args.neighbors, orient=True, threads=args.threads)
    elif side == "open3d":
        import open3d as o3d

        def run(p):
            pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))
            pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(args.neighbors))
            pc.orient_normals_consistent_tangent_plane(args.neighbors)
            return np.asarray(pc.normals)
    elif side == "meshlab":
        import pymeshlab

        def run(p):
            ms = pymeshlab.MeshSet()
            ms.add_mesh(pymeshlab.Mesh(vertex_matrix=p))
            ms.compute_normal_for_point_clouds(k=args.neighbors, smoothiter=0)
            return ms.current_mesh().vertex_normal_matrix()
    else:
        raise SystemExit(f"unknown side {side}")
    points = np.load(args.input)
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # VmHWM := VmRSS, so that the peak counts this call only
    except OSError:
        pass
    base = status_kib("VmRSS")
    cpu, t = time.process_time(), time.perf_counter()
    normals = run(points)
    wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    peak = status_kib("VmHWM")
    if args.save:
        np.save(args.save, np.asarray(normals, dtype=np.float64))
    print(json.dumps({"wall": wall, "cpu": cpu, "bytes_per_point": (peak - base) * 1024.0 / len(points)}))


# --------------------------------------------------------------------------- driver

def run_one(python, side, input_path, args, save=None, timeout=900):
    cmd = [python, str(HERE), "--worker", side, "--input", str(input_path), "--neighbors", str(args.neighbors),
           "--threads", str(args.threads)] + (["--save", str(save)] if save else [])
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout {timeout} s"}
    if out.returncode != 0:
        return {"error": (out.stderr.strip().splitlines() or ["failed"])[-1][:120]}
    return json.loads(out.stdout.strip().splitlines()[-1])


def importable(python, module):
    return subprocess.run([python, "-c", f"import {module}"], capture_output=True).returncode == 0


def flipped_edges(points, normals, k=8):
    """Share of 8-NN pairs with nearly antiparallel normals (n_i . n_j < -0.9): a patch
    oriented against its surroundings shows as such pairs along its border."""
    from scipy.spatial import cKDTree

    _, idx = cKDTree(points).query(points, k + 1, workers=-1)
    return float((np.einsum("ij,ikj->ik", normals, normals[idx[:, 1:]]) < -0.9).mean())


def load_ply(path):
    from plyfile import PlyData

    v = PlyData.read(str(path))["vertex"].data
    return np.column_stack([v["x"], v["y"], v["z"]]).astype(np.float64)


def load_average():
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "n/a"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--input", help=argparse.SUPPRESS)
    ap.add_argument("--save", help=argparse.SUPPRESS)
    ap.add_argument("--neighbors", type=int, default=24, help="k on every side (default 24)")
    ap.add_argument("--threads", type=int, default=2, help="pointscale's threads (default 2)")
    ap.add_argument("--reps", type=int, default=3, help="runs per input of pointscale and the old build")
    ap.add_argument("--peer-reps", type=int, default=1, help="runs per input of Open3D and MeshLab (slow)")
    ap.add_argument("--old-python", help="a Python whose pointscale is the old build")
    ap.add_argument("--peer-python", default=sys.executable, help="a Python with open3d / pymeshlab")
    ap.add_argument("--size", type=float, default=1e6, help="points of the synthetic sphere (default 1M)")
    ap.add_argument("--data-dir", default=str(HERE.parents[1] / ".." / "shared" / "data"))
    ap.add_argument("--no-data", action="store_true", help="synthetic inputs only")
    ap.add_argument("--no-peers", action="store_true")
    args = ap.parse_args()
    if args.worker:
        return worker(args)

    import pointscale

    sides = {"pointscale": sys.executable}
    if args.old_python:
        sides["old"] = args.old_python
    if not args.no_peers:
        for side, module in (("open3d", "open3d"), ("meshlab", "pymeshlab")):
            if importable(args.peer_python, module):
                sides[side] = args.peer_python
            else:
                print(f"{side}: n/a ({module} does not import in {args.peer_python})")
    n = int(args.size)
    sphere = pointscale.shapes.bumpy_sphere(n)
    inputs = {f"{n / 1e6:g}M bumpy sphere, generator's order": sphere,
              f"{n / 1e6:g}M bumpy sphere, shuffled": sphere[np.random.default_rng(0).permutation(n)]}
    if not args.no_data:
        for name in ("dragon.ply", "happy_buddha_scans.ply"):
            path = Path(args.data_dir) / name
            if path.exists():
                inputs[f"{name[:-4]}, file order"] = load_ply(path)
            else:
                print(f"{name}: skipped (not in {args.data_dir})")

    print(f"k = {args.neighbors}, pointscale threads = {args.threads}, load average at start {load_average()} "
          f"on {os.cpu_count()} cores")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, points in inputs.items():
            path = Path(tmp) / "points.npy"
            np.save(path, points)
            runs = {s: [] for s in sides}
            saved = {}
            for rep in range(max(args.reps, args.peer_reps)):
                for side, python in sides.items():
                    if rep >= (args.peer_reps if side in ("open3d", "meshlab") else args.reps):
                        continue
                    save = Path(tmp) / f"{side}.npy" if rep == 0 else None
                    r = run_one(python, side, path, args, save)
                    runs[side].append(r)
                    if save and "error" not in r:
                        saved[side] = np.load(save)
            row = {"input": label, "n": len(points)}
            for side, rs in runs.items():
                ok = [r for r in rs if "error" not in r]
                if not ok:
                    row[side] = {"error": rs[0]["error"] if rs else "not run"}
                    continue
                row[side] = {"wall": statistics.median(r["wall"] for r in ok),
                             "cpu": statistics.median(r["cpu"] for r in ok),
                             "bytes_per_point": statistics.median(r["bytes_per_point"] for r in ok),
                             "runs": len(ok)}
                nrm = saved.get(side)
                if nrm is not None:
                    row[side]["flipped"] = flipped_edges(points, nrm)
                    if "sphere" in label:
                        row[side]["outward"] = float((np.einsum("ij,ij->i", nrm, points) > 0).mean())
                    if side != "pointscale" and "pointscale" in saved:
                        row[side]["same_sign_as_pointscale"] = float(
                            (np.einsum("ij,ij->i", nrm, saved["pointscale"]) > 0).mean())
            rows.append(row)
            print(json.dumps(row), flush=True)

    print(f"\nload average at end {load_average()} (a shared machine: other jobs ran at the same time)\n")
    cols = list(sides)
    print("| input | " + " | ".join(f"{c} s (CPU s), B/pt" for c in cols) + " | new / old |")
    print("|---|" + "---|" * (len(cols) + 1))
    for row in rows:
        cells = []
        for c in cols:
            r = row[c]
            cells.append(r["error"] if "error" in r else f"{r['wall']:.2f} ({r['cpu']:.2f}), {r['bytes_per_point']:.0f}")
        ratio = "n/a"
        if "old" in row and "wall" in row.get("old", {}) and "wall" in row["pointscale"]:
            ratio = f"{row['pointscale']['wall'] / row['old']['wall']:.3f}"
        print(f"| {row['input']} | " + " | ".join(cells) + f" | {ratio} |")
    print("\nOrientation: share of flipped 8-NN edges (n_i . n_j < -0.9); outward share on the sphere; "
          "same sign as pointscale's new normals")
    for row in rows:
        parts = []
        for c in cols:
            r = row[c]
            if "flipped" not in r:
                continue
            s = f"{c}: flipped {r['flipped']:.2e}"
            if "outward" in r:
                s += f", outward {r['outward']:.6f}"
            if "same_sign_as_pointscale" in r:
                s += f", same sign {r['same_sign_as_pointscale']:.5f}"
            parts.append(s)
        print(f"- {row['input']}: " + "; ".join(parts))


if __name__ == "__main__":
    main()
