#!/usr/bin/env python3
"""One smoothing pass at matched smoothing: pointscale.project against PCL's and Open3D's MLS.

    python bench/projection_bench.py                   # 1M noisy sphere + 300k noisy torus
    python bench/projection_bench.py --quick           # 100k sphere, 50k torus, one repeat
    python bench/projection_bench.py --inputs sphere --sizes 1M --repeat 3

Inputs (made here, float32-exact, so that PCL reads the very points the others get):
  sphere  n points uniform on the unit sphere (normalised Gaussian vectors), each moved along
          the radius by Gaussian noise of sigma = 0.001 (about 0.28 of the mean spacing at 1M)
  torus   n points uniform by area on a torus of radii 1 and 0.35, each moved along its normal
          by Gaussian noise of sigma = 0.002 (about 0.29 of the mean spacing at 300k)
Each in two orders: coherent (a Morton order: neighbours in space are neighbours in memory,
as in scan-line or file order, every peer's best case) and shuffled (a random permutation).

Competitors, each call in a fresh process that builds its own index, timed around the call
only (loading the points is not timed); called in turn, repeat times, so that the machine's
load falls on all of them alike; the table gives medians:
  pointscale   project(P, P) at its defaults (iterated to convergence), and with
               single_pass=True at the kernels given by --kernels and at the kernel that
               matches each peer's RMS on that input (found first by bisection, untimed); all
               cores
  PCL          MovingLeastSquares, polynomial order 1, one pass, radius calibrated so that the
               mean neighbour count is K (bench/peers/pcl_mls, built as bench/run.py builds it);
               process() only, its kd-tree included; --threads 2
  Open3D       PointCloud.smooth_mls(KDTreeSearchParamHybrid(radius = PCL's radius, max_nn = K)):
               the same Gaussian weights exp(-d^2 / r^2) on at most the K nearest; its own
               threads (OpenMP, all cores)
Smoothing is the RMS distance of the result to the true surface divided by sigma (the input
scores about 1). "Matched" is within 5% of the faster peer's figure on the same input.
Timed code never runs in a test; this script only prints.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from run import morton_order  # bench/run.py's coherent order, the same curve for both benches

HERE = Path(__file__).resolve().parent
PEER_SRC = HERE / "peers" / "pcl_mls"
PEER_BUILD = HERE / "peers" / "build" / "pcl_mls"
PEER_BIN = PEER_BUILD / "pcl_mls_bench"
K = 24
MATCH = 0.05          # matched smoothing: RMS within 5% of the faster peer's
TARGET = 0.7          # the single pass's time against the faster peer's
SPHERE_SIGMA, TORUS_SIGMA = 0.001, 0.002
TORUS_R, TORUS_MINOR = 1.0, 0.35


# --------------------------------------------------------------------------- inputs

def noisy_sphere(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    d = rng.standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return (d * (1.0 + SPHERE_SIGMA * rng.standard_normal(n))[:, None]).astype(np.float32).astype(np.float64)


def noisy_torus(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 2 * np.pi, n)
    # The area element is proportional to R + r cos v: rejection sampling keeps v uniform by area.
    v = np.empty(0)
    while len(v) < n:
        c = rng.uniform(0, 2 * np.pi, 2 * n)
        keep = rng.uniform(0, TORUS_R + TORUS_MINOR, 2 * n) < TORUS_R + TORUS_MINOR * np.cos(c)
        v = np.concatenate([v, c[keep]])
    v = v[:n]
    r = TORUS_MINOR + TORUS_SIGMA * rng.standard_normal(n)
    ring = TORUS_R + r * np.cos(v)
    p = np.column_stack([ring * np.cos(u), ring * np.sin(u), r * np.sin(v)])
    return p.astype(np.float32).astype(np.float64)


def sphere_error(q: np.ndarray) -> np.ndarray:
    return np.linalg.norm(q, axis=1) - 1.0


def torus_error(q: np.ndarray) -> np.ndarray:
    ring = np.hypot(q[:, 0], q[:, 1]) - TORUS_R
    return np.hypot(ring, q[:, 2]) - TORUS_MINOR


SHAPES = {"sphere": (noisy_sphere, sphere_error, SPHERE_SIGMA), "torus": (noisy_torus, torus_error, TORUS_SIGMA)}


def parse_size(text: str) -> int:
    t = text.strip().lower()
    scale = {"k": 1_000, "m": 1_000_000}.get(t[-1:], 1)
    return int(float(t[:-1] if scale > 1 else t) * scale)


# --------------------------------------------------------------------------- workers (fresh processes)

def worker(args: argparse.Namespace) -> int:
    """Runs one timed call on the points in args.input and prints one JSON line."""
    points = np.load(args.input)
    out: dict = {}
    if args.worker == "open3d":
        import open3d as o3d
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        search = o3d.geometry.KDTreeSearchParamHybrid(radius=args.radius, max_nn=K)
        if not hasattr(cloud, "smooth_mls"):
            print(json.dumps({"error": f"open3d {o3d.__version__} has no PointCloud.smooth_mls"}))
            return 0
        t = time.perf_counter()
        result = cloud.smooth_mls(search)
        out["seconds"] = time.perf_counter() - t
        out["version"] = o3d.__version__
        positions = np.asarray(result.points)
    else:
        import pointscale as ps
        options = json.loads(args.options)
        t = time.perf_counter()
        positions, _ = ps.project(points, points, **options)
        out["seconds"] = time.perf_counter() - t
        if args.report:  # untimed: the report may cost a fit more per point
            out["report"] = ps.project(points, points, return_report=True, **options)[2]
    if args.output:
        np.save(args.output, positions)
    print(json.dumps(out))
    return 0


def run_json(cmd: list[str]) -> dict:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    for line in reversed(proc.stdout.strip().splitlines()):
        if line.startswith("{"):
            return json.loads(line)
    tail = (proc.stderr or proc.stdout).strip().splitlines()[-4:]
    raise RuntimeError(f"{' '.join(cmd[:3])}...: exit {proc.returncode}: " + " | ".join(tail))


def build_pcl() -> Path | None:
    """The PCL harness, configured and built as bench/run.py does; None (with a message) if PCL is missing."""
    PEER_BUILD.mkdir(parents=True, exist_ok=True)
    if not (PEER_BUILD / "CMakeCache.txt").exists():
        cfg = subprocess.run(["cmake", "-S", str(PEER_SRC), "-B", str(PEER_BUILD), "-DCMAKE_BUILD_TYPE=Release"],
                             capture_output=True, text=True)
        if cfg.returncode != 0:
            (PEER_BUILD / "CMakeCache.txt").unlink(missing_ok=True)
            print("PCL peer unavailable (apt-get install -y libpcl-dev):", cfg.stderr.strip().splitlines()[-1:])
            return None
    b = subprocess.run(["cmake", "--build", str(PEER_BUILD), "-j", str(os.cpu_count() or 2)], capture_output=True, text=True)
    if b.returncode != 0 or not PEER_BIN.exists():
        print("PCL harness build failed:", (b.stderr or b.stdout).strip().splitlines()[-2:])
        return None
    return PEER_BIN


# --------------------------------------------------------------------------- the run

def competitors(kernels: list[float], matched: dict[str, float]) -> list[tuple[str, dict | None]]:
    rows = [("PCL MLS (one pass)", None), ("Open3D smooth_mls (one pass)", None),
            ("pointscale project (defaults, iterated)", {})]
    rows += [(f"pointscale project single_pass, kernel {k:g}", {"single_pass": True, "kernel": k}) for k in kernels]
    rows += [(f"pointscale project single_pass, kernel {k:.3g} (matched to {peer})", {"single_pass": True, "kernel": k})
             for peer, k in matched.items() if k not in kernels]
    return rows


def rms_of(q: np.ndarray, error, sigma: float) -> float:
    return float(np.sqrt(np.mean(error(q) ** 2)) / sigma)


def matching_kernel(points: np.ndarray, error, sigma: float, target: float) -> float:
    """The single-pass kernel whose RMS is the target's, by bisection on log(kernel) (untimed;
    the RMS falls as the kernel grows, towards the floor that K equal weights set)."""
    import pointscale as ps
    lo, hi = 1.0, 6.0
    for _ in range(10):
        mid = float(np.sqrt(lo * hi))
        rms = rms_of(ps.project(points, points, kernel=mid, single_pass=True)[0], error, sigma)
        lo, hi = (mid, hi) if rms > target else (lo, mid)
    return round(float(np.sqrt(lo * hi)), 3)


def peer_rms(points: np.ndarray, error, sigma: float, pcl: Path | None, tmp: Path) -> tuple[dict[str, float], float | None]:
    """Each peer's RMS on these points (untimed), and PCL's radius, which Open3D is given too."""
    out: dict[str, float] = {}
    if pcl is None:
        return out, None
    points.astype(np.float32).tofile(tmp / "points.f32")
    res = run_json([str(pcl), str(tmp / "points.f32"), str(K), "--threads", "2", "--out", str(tmp / "pcl.out")])
    q = np.fromfile(tmp / "pcl.out", dtype=np.float32).reshape(-1, 6)[:, :3].astype(np.float64)
    out["PCL"] = rms_of(q[np.isfinite(q).all(1)], error, sigma)
    try:
        import open3d as o3d
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        if hasattr(cloud, "smooth_mls"):
            q = np.asarray(cloud.smooth_mls(o3d.geometry.KDTreeSearchParamHybrid(radius=res["radius"], max_nn=K)).points)
            out["Open3D"] = rms_of(q, error, sigma)
    except ImportError:
        pass
    return out, res["radius"]


def measure(name: str, points: np.ndarray, error, sigma: float, args, pcl: Path | None, tmp: Path,
            matched: dict[str, float]) -> list[dict]:
    src = tmp / "points.npy"
    np.save(src, points)
    points.astype(np.float32).tofile(tmp / "points.f32")
    rows = [{"name": c, "options": o, "times": [], "load": []} for c, o in competitors(args.kernels, matched)]
    radius = None
    for rep in range(args.repeat):
        for row in rows:
            out = tmp / "out.npy"
            load = os.getloadavg()[0]
            first = rep == 0
            if row["name"].startswith("PCL"):
                if pcl is None:
                    continue
                cmd = [str(pcl), str(tmp / "points.f32"), str(K), "--threads", "2"]
                if first:
                    cmd += ["--out", str(tmp / "pcl.out")]
                res = run_json(cmd)
                radius = res["radius"]
                row["times"].append(res["process_s"])
                row["extra"] = f"radius {radius:.4g}, mean {res['mean_neighbors']:.1f} neighbours"
                if first:
                    q = np.fromfile(tmp / "pcl.out", dtype=np.float32).reshape(-1, 6)[:, :3].astype(np.float64)
                    row["rms"] = float(np.sqrt(np.mean(error(q[np.isfinite(q).all(1)]) ** 2)) / sigma)
                    row["count"] = len(q)
            else:
                cmd = [sys.executable, __file__, "--worker", "open3d" if row["options"] is None else "pointscale",
                       "--input", str(src)]
                if row["options"] is None:
                    if radius is None:
                        continue  # Open3D takes PCL's radius
                    cmd += ["--radius", repr(radius)]
                else:
                    cmd += ["--options", json.dumps(row["options"])]
                    if first and row["options"].get("single_pass"):
                        cmd += ["--report"]
                if first:
                    cmd += ["--output", str(out)]
                res = run_json(cmd)
                if "error" in res:
                    row["extra"] = res["error"]
                    continue
                row["times"].append(res["seconds"])
                if "version" in res:
                    row["extra"] = f"open3d {res['version']}, radius {radius:.4g}, max_nn {K}"
                if "report" in res:
                    r = res["report"]
                    row["extra"] = (f"next step / h: mean {r['next_step_mean']:.2g}, max {r['next_step_max']:.2g}; "
                                    f"moved / h: mean {r['moved_mean']:.2g}")
                if first:
                    q = np.load(out)
                    row["rms"] = float(np.sqrt(np.mean(error(q) ** 2)) / sigma)
                    row["count"] = len(q)
            row["load"].append(load)
            print(f"  {name} rep {rep + 1}: {row['name']}: {row['times'][-1]:.3f} s (load {load:.1f})", flush=True)
    return rows


def render(name: str, input_rms: float, rows: list[dict]) -> str:
    timed = [r for r in rows if r["times"]]
    for r in timed:
        r["median"] = statistics.median(r["times"])
    peers = [r for r in timed if r["options"] is None]
    fastest = min(peers, key=lambda r: r["median"]) if peers else None
    lines = [f"\n{name} (input RMS error / sigma {input_rms:.3f}; "
             f"load average at the end {os.getloadavg()[0]:.1f})",
             "| competitor | RMS error / sigma | median s (runs) | vs faster peer: time, RMS | load avg | notes |",
             "|---|---|---|---|---|---|"]
    for r in timed:
        ratio = rms_off = ""
        if fastest is not None and r is not fastest and r["options"] is not None:
            ratio = f"{r['median'] / fastest['median']:.2f}x"
            off = r["rms"] / fastest["rms"] - 1.0
            rms_off = f"{off:+.1%}" + (" matched" if abs(off) <= MATCH else "")
        elif r is fastest:
            ratio = "faster peer"
        runs = ", ".join(f"{t:.2f}" for t in r["times"])
        load = f"{min(r['load']):.1f}-{max(r['load']):.1f}"
        lines.append(f"| {r['name']} | {r.get('rms', float('nan')):.3f} | {r['median']:.3f} ({runs}) | "
                     f"{ratio} {rms_off} | {load} | {r.get('extra', '')} |")
    matched = [r for r in timed if fastest and r["options"] and r["options"].get("single_pass")
               and abs(r["rms"] / fastest["rms"] - 1.0) <= MATCH]
    for r in matched:
        ok = r["median"] <= TARGET * fastest["median"]
        lines.append(f"{'MET' if ok else 'NOT MET'}: {r['name']} at {r['median'] / fastest['median']:.2f}x of "
                     f"{fastest['name']} (target <= {TARGET}x), RMS {r['rms']:.3f} vs {fastest['rms']:.3f}")
    if fastest and not matched:
        lines.append("no single-pass kernel matched the faster peer's RMS within 5%: try other --kernels")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--inputs", default="sphere,torus", help="comma-separated: sphere, torus")
    p.add_argument("--sizes", default=None, help="one size per input, e.g. 1M,300k (default 1M,300k)")
    p.add_argument("--orders", default="coherent,shuffled")
    p.add_argument("--kernels", default="2.5,3", help="single-pass kernels to time")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--quick", action="store_true", help="100k sphere, 50k torus, one repeat")
    p.add_argument("--seed", type=int, default=7)
    p.add_argument("--no-match", action="store_true", help="skip the search for the kernels matching each peer")
    # worker mode (internal)
    p.add_argument("--worker", choices=("pointscale", "open3d"), help=argparse.SUPPRESS)
    p.add_argument("--input", help=argparse.SUPPRESS)
    p.add_argument("--output", help=argparse.SUPPRESS)
    p.add_argument("--options", default="{}", help=argparse.SUPPRESS)
    p.add_argument("--radius", type=float, help=argparse.SUPPRESS)
    p.add_argument("--report", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        return worker(args)
    args.kernels = [float(k) for k in args.kernels.split(",")]
    inputs = args.inputs.split(",")
    if args.quick:
        sizes, args.repeat = {"sphere": 100_000, "torus": 50_000}, 1
    else:
        given = args.sizes.split(",") if args.sizes else ["1M", "300k"][:len(inputs)]
        sizes = {name: parse_size(s) for name, s in zip(inputs, given)}
    pcl = build_pcl()
    print(f"machine: {platform.node()}, {os.cpu_count()} cores, {platform.platform()}; "
          f"load average at start {os.getloadavg()[0]:.1f} (shared machine: other jobs run too)", flush=True)
    tables = []
    with tempfile.TemporaryDirectory(prefix="projection_bench_") as tmp:
        for name in inputs:
            make, error, sigma = SHAPES[name]
            base = make(sizes[name], args.seed)
            # The matched kernels, once per input: neither side's result depends on the order.
            matched = {}
            if not args.no_match:
                rms, _ = peer_rms(base[morton_order(base)], error, sigma, pcl, Path(tmp))
                matched = {peer: matching_kernel(base, error, sigma, r) for peer, r in rms.items()}
                print(f"{name}: peers' RMS / sigma {rms}; single-pass kernels matching them {matched}", flush=True)
            for order in args.orders.split(","):
                pts = base[morton_order(base)] if order == "coherent" else base[np.random.default_rng(1).permutation(len(base))]
                label = f"{name} {sizes[name]:,} points, sigma {sigma:g}, {order} order"
                print(label, flush=True)
                rows = measure(label, pts, error, sigma, args, pcl, Path(tmp), matched)
                input_rms = float(np.sqrt(np.mean(error(pts) ** 2)) / sigma)
                tables.append(render(label, input_rms, rows))
                print(tables[-1], flush=True)
    print("\n".join(["\n=== summary ==="] + tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())
