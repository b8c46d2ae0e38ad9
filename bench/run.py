#!/usr/bin/env python3
"""Pointscale speed benchmark against PCL's MovingLeastSquares and Open3D's smooth_mls, side by side in ONE run.

    python bench/run.py                 # 100k + 1M synthetic, dragon, happy_buddha_scans
    python bench/run.py --quick         # small smoke test (20k synthetic only)
    python bench/run.py --sizes 100k,1M --no-pcl --no-open3d
    python bench/run.py --huge          # also a 10M-point synthetic cloud
    python bench/run.py --results bench/RESULTS.md   # also write the table there, in markdown

Every input is timed in two orders (--orders):
  coherent  the order a real input comes in, each peer's best case: file order for the
            scans (scan lines, mesh vertex order), a Morton (Z-order) sort for the
            synthetic clouds (whose generator draws directions at random);
  shuffled  the same points under one fixed random permutation (seed 7).
PCL and Open3D do not reorder points, so a shuffled cloud slows their kd-tree walks;
pointscale sorts the points spatially itself.

For every input cloud and order the same float32-exact points are fed to every side:
  (a) pointscale.decompose(points, levels=4, neighbors=K) wall time,
  (b) one PCL MLS pass (order 1, radius calibrated so the mean neighbour count is K,
      same thread count), wall time of process() only, from bench/peers/pcl_mls,
  (b') one Open3D PointCloud.smooth_mls pass (PyPI open3d; a weighted PCA plane per point,
      the point projected onto it), wall time of that call only, twice: with
      KDTreeSearchParamRadius(PCL's radius) (Gaussian weights exp(-d^2/r^2), PCL's own)
      and with KDTreeSearchParamKNN(K) (uniform weights, pointscale's neighbourhood),
      OMP_NUM_THREADS = the same thread count,
  (c) ratio (a)/(faster of (b), (b')), per order            target < 1.0 (at 1M),
  (d) pointscale.reconstruct(dec, base=base), median of several runs, with base = dec.base
      taken once before them, as an editor holds its edited base (handed back unchanged, it
      is recognised as the stored base, and no point turns), and the same through
      pointscale.Reconstructor(dec), the solver an editing session keeps (its one-off setup
      timed apart; the two are called alternately and must give identical points); then both
      again on bases two broad waves moved everywhere, in turn, so that every point's turn is
      measured on every call.
      reconstruct's first call on an edited base finds the edit support and keeps it with
      the decomposition (its time is printed apart); both have the same
                                                      target < 20 ms at 100k x 4 levels,
  (e) peak memory per point while decomposing: peak RSS (VmHWM, reset after the data
      is loaded) minus the RSS after loading, in a fresh subprocess per cloud (not
      ru_maxrss: a child inherits its parent's peak through fork/exec)
                                                      target < 300 bytes/point.
Timed code never runs in a test; this script only prints.

Every pass runs in a fresh subprocess (one per cloud, order, side and repetition, each
building its own index), and the repetitions are interleaved: round 1 runs every side on
every order, then round 2, so that load from other processes falls on all of them alike.
Medians over the rounds are reported. (d) and (e) come from the first round's pointscale
process.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
PEER_SRC = HERE / "peers" / "pcl_mls"
PEER_BUILD = HERE / "peers" / "build" / "pcl_mls"
PEER_BIN = PEER_BUILD / "pcl_mls_bench"
DEFAULT_DATA = (REPO / ".." / "shared" / "data").resolve()
DATASETS = ("dragon.ply", "happy_buddha_scans.ply")
ORDERS = ("coherent", "shuffled")
SHUFFLE_SEED = 7

TARGET_RATIO = 1.0
TARGET_RECON_MS = 20.0
TARGET_BYTES_PER_POINT = 300.0


# --------------------------------------------------------------------------- inputs

def parse_size(text: str) -> int:
    t = text.strip().lower().replace("_", "")
    mult = 1
    if t.endswith("k"):
        mult, t = 1_000, t[:-1]
    elif t.endswith("m"):
        mult, t = 1_000_000, t[:-1]
    value = int(float(t) * mult)
    if value < 100:
        raise argparse.ArgumentTypeError(f"size {text!r} is too small (need >= 100 points)")
    return value


def size_label(n: int) -> str:
    if n >= 1_000_000 and n % 1_000_000 == 0:
        return f"{n // 1_000_000}M"
    if n >= 1_000 and n % 1_000 == 0:
        return f"{n // 1_000}k"
    return str(n)


def bumpy_sphere(n: int, seed: int = 1) -> np.ndarray:
    """A unit sphere carrying three bump frequencies plus a little noise.

    Coarse (f=3, 6% of the radius), medium (f=9, 1.5%) and fine (f=27, 0.4%) relief,
    then 0.05% Gaussian noise: a multiscale surface with detail in every band.
    Generated in chunks so the 10M cloud does not need large temporaries.
    Returned as float32-exact float64 (the PCL side reads float32).
    """
    rng = np.random.default_rng(seed)
    out = np.empty((n, 3), dtype=np.float64)
    chunk = 1_000_000
    for s in range(0, n, chunk):
        m = min(chunk, n - s)
        d = rng.standard_normal((m, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        x, y, z = d[:, 0], d[:, 1], d[:, 2]
        r = (1.0
             + 0.06 * np.sin(3 * x + 0.3) * np.sin(3 * y + 0.7) * np.sin(3 * z + 1.1)
             + 0.015 * np.sin(9 * x) * np.sin(9 * y + 0.5) * np.sin(9 * z + 0.2)
             + 0.004 * np.sin(27 * x + 0.1) * np.sin(27 * y) * np.sin(27 * z + 0.4)
             + 0.0005 * rng.standard_normal(m))
        out[s:s + m] = d * r[:, None]
    return out.astype(np.float32).astype(np.float64)


def morton_order(points: np.ndarray) -> np.ndarray:
    """Indices sorting points along a 3D Z-order curve (10 bits per axis)."""
    lo = points.min(axis=0)
    extent = float((points.max(axis=0) - lo).max()) or 1.0
    q = np.clip(((points - lo) / extent * 1023.0).astype(np.uint64), 0, 1023)

    def spread(v):
        v = (v | (v << np.uint64(16))) & np.uint64(0x30000FF)
        v = (v | (v << np.uint64(8))) & np.uint64(0x300F00F)
        v = (v | (v << np.uint64(4))) & np.uint64(0x30C30C3)
        return (v | (v << np.uint64(2))) & np.uint64(0x9249249)

    code = spread(q[:, 0]) | (spread(q[:, 1]) << np.uint64(1)) | (spread(q[:, 2]) << np.uint64(2))
    return np.argsort(code, kind="stable")


def in_order(points: np.ndarray, kind: str, order: str) -> np.ndarray:
    """The points in the named order: 'coherent' (file order for a scan, Morton order for a
    synthetic cloud) or 'shuffled' (a fixed random permutation of the coherent order)."""
    if kind == "synthetic":
        points = points[morton_order(points)]
    if order == "shuffled":
        points = points[np.random.default_rng(SHUFFLE_SEED).permutation(len(points))]
    return points


def order_label(kind: str, order: str) -> str:
    if order == "shuffled":
        return "shuffled"
    return "Morton order" if kind == "synthetic" else "file order"


def read_ply_xyz(path: Path) -> np.ndarray:
    from plyfile import PlyData

    ply = PlyData.read(str(path))
    v = ply["vertex"].data
    return np.column_stack([v["x"], v["y"], v["z"]]).astype(np.float64)


# --------------------------------------------------------------------------- workers

def vm_status_kib() -> dict:
    """VmRSS and VmHWM (peak RSS of this process image) from /proc/self/status, in KiB."""
    out = {}
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(("VmRSS:", "VmHWM:")):
                out[line.split(":")[0]] = int(line.split()[1])
    return out


def reset_peak_rss() -> bool:
    """Resets VmHWM to the current RSS (Linux >= 4.0); False when not allowed."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def maxrss_kib() -> int:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux


def jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist() if obj.size <= 16 else f"ndarray{obj.shape}"
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, (str, int, float, bool)) or obj is None:
        return obj
    return repr(obj)


def worker_pointscale(args: argparse.Namespace) -> int:
    """Runs in a fresh subprocess: decompose one cloud, print one JSON line."""
    import pointscale  # noqa: F401  (import cost stays out of the baseline delta)

    points = np.load(args.worker_pointscale)  # float64 (n, 3), exactly the array size
    n = len(points)
    # Peak memory: NOT ru_maxrss, which a child inherits from its parent's peak across
    # fork/exec on Linux (a parent that once held 10M points makes every child's
    # ru_maxrss start at that size). VmHWM belongs to this process image; reset it to
    # the current RSS after loading, then read it after the first decompose.
    was_reset = reset_peak_rss()
    base = vm_status_kib()
    base_max = maxrss_kib()

    dec_times, cpu_times = [], []
    peak = None
    for _ in range(max(1, args.reps)):
        if dec_times and sum(dec_times) > args.rep_budget:
            break  # slow input: the first run(s) already say enough
        dec = None  # free the previous result before the next run
        c0 = time.process_time()  # CPU time of the whole process, all threads
        t0 = time.perf_counter()
        dec = pointscale.decompose(points, levels=args.levels, neighbors=args.neighbors,
                                   threads=args.threads)
        dec_times.append(time.perf_counter() - t0)
        cpu_times.append(time.process_time() - c0)
        if peak is None:
            peak = vm_status_kib()["VmHWM"]  # peak of the first (cold) run
            peak_maxrss = maxrss_kib()
    t_dec = statistics.median(dec_times)

    res = {
        "side": "pointscale",
        "n": n,
        "levels": args.levels,
        "neighbors": args.neighbors,
        "threads": args.threads,
        "decompose_s": t_dec,
        "decompose_all_s": dec_times,
        "decompose_reps": len(dec_times),
        "decompose_cpu_s": statistics.median(cpu_times),
        "peak_reset": was_reset,
        "rss_baseline_kib": base["VmRSS"],
        "hwm_baseline_kib": base["VmHWM"],
        "hwm_peak_kib": peak,
        "peak_bytes_per_point": (peak - (base["VmRSS"] if was_reset else base["VmHWM"])) * 1024.0 / n,
        "abs_peak_bytes_per_point": peak * 1024.0 / n,
        "ru_maxrss_baseline_kib": base_max,
        "ru_maxrss_peak_kib": peak_maxrss,
        "details_shape": list(np.shape(dec.details)),
        "stats": jsonable(getattr(dec, "stats", {})),
    }

    if args.recon_reps > 0:
        times, solver_times = [], []
        rec = solved = None
        base = dec.base  # a property that builds the array: not part of reconstruct
        t0 = time.perf_counter()
        solver = pointscale.Reconstructor(dec)
        setup = time.perf_counter() - t0
        for _ in range(args.recon_reps):  # alternately, so that both meet the same machine
            t0 = time.perf_counter()
            rec = pointscale.reconstruct(dec, base=base)
            times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            solved = solver.reconstruct(base=base)
            solver_times.append(time.perf_counter() - t0)
        rec = np.asarray(rec)
        res.update({
            "reconstructor_setup_ms": setup * 1e3,
            "reconstructor_median_ms": statistics.median(solver_times) * 1e3,
            "reconstructor_min_ms": min(solver_times) * 1e3,
            "reconstructor_all_ms": [t * 1e3 for t in solver_times],
            "reconstructor_identical": bool(np.array_equal(solved, rec)),
        })
        diag = float(np.linalg.norm(points.max(0) - points.min(0)))
        err = np.linalg.norm(rec - points, axis=1)
        res.update({
            "reconstruct_first_ms": times[0] * 1e3,
            "reconstruct_median_ms": statistics.median(times) * 1e3,
            "reconstruct_min_ms": min(times) * 1e3,
            "reconstruct_reps": len(times),
            "reconstruct_all_ms": [t * 1e3 for t in times],
            "reconstruct_max_err_rel": float(err.max() / diag),
        })
        # The same on a base that an edit moved everywhere (a broad wave), so that every
        # point's turn is measured: base=dec.base above turns nothing. Two waves, in turn: a
        # Reconstructor redoes only what changed since its last edited call, and each call
        # must find the whole base changed.
        up = np.array([0.0, 0.0, 1.0])
        waves = [base + (0.05 * diag) * np.sin(3.0 * base[:, [0]] / diag) * up,
                 base + (0.05 * diag) * np.cos(3.0 * base[:, [1]] / diag) * up]
        edited, solver_edited = [], []
        t0 = time.perf_counter()
        pointscale.reconstruct(dec, base=waves[0])  # finds the edit support and keeps it with dec
        moved_first = time.perf_counter() - t0
        for rep in range(args.recon_reps):
            lifted = waves[rep % 2]
            t0 = time.perf_counter()
            pointscale.reconstruct(dec, base=lifted)
            edited.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            solver.reconstruct(base=lifted)
            solver_edited.append(time.perf_counter() - t0)
        res.update({
            "reconstruct_moved_first_ms": moved_first * 1e3,
            "reconstruct_moved_median_ms": statistics.median(edited) * 1e3,
            "reconstructor_moved_median_ms": statistics.median(solver_edited) * 1e3,
        })
    print(json.dumps(res), flush=True)
    return 0


def calibrate_radius(points: np.ndarray, k: int, tree, samples: int = 20_000) -> tuple[float, float]:
    """The radius whose mean neighbour count (the query point included) over a random sample
    of points is k, within 0.5%: bench/peers/pcl_mls's rule, for when PCL is not there.
    tree is an open3d KDTreeFlann. Returns (radius, mean count obtained)."""
    rng = np.random.default_rng(12345)
    sample = points[rng.integers(0, len(points), min(samples, len(points)))]

    def mean_count(r: float) -> float:
        return float(np.mean([tree.search_radius_vector_3d(q, r)[0] for q in sample]))

    r = float(np.mean([np.sqrt(tree.search_knn_vector_3d(q, k)[2][-1]) for q in sample]))
    lo, hi, c = 0.0, r, mean_count(r)
    while c < k:
        lo, hi = hi, hi * np.sqrt(k / max(c, 1.0)) * 1.05
        c = mean_count(hi)
    if lo == 0.0:
        lo, clo = hi, c
        while clo >= k:
            hi, c = lo, clo
            lo *= np.sqrt(k / clo) * 0.95
            clo = mean_count(lo)
    radius, got = hi, c
    for _ in range(40):
        if abs(got - k) <= 0.005 * k:
            break
        mid = 0.5 * (lo + hi)
        cm = mean_count(mid)
        if cm < k:
            lo = mid
        else:
            hi = radius = mid
            got = cm
    return radius, got


def worker_open3d(args: argparse.Namespace) -> int:
    """Runs in a fresh subprocess: one Open3D PointCloud.smooth_mls pass, one JSON line.

    The thread count comes from OMP_NUM_THREADS, which the caller sets."""
    import open3d as o3d

    pts = np.fromfile(args.worker_open3d, dtype="<f4").reshape(-1, 3).astype(np.float64)
    n = len(pts)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    res = {"side": "open3d", "version": o3d.__version__, "n": n, "search": args.o3d_search,
           "omp_num_threads": os.environ.get("OMP_NUM_THREADS")}
    if args.o3d_search == "radius":
        radius = args.radius
        if not radius:
            t0 = time.perf_counter()
            radius, got = calibrate_radius(pts, args.neighbors, o3d.geometry.KDTreeFlann(cloud))
            res.update({"calibrated": True, "mean_neighbors": got, "calib_s": time.perf_counter() - t0})
        res["radius"] = radius
        param = o3d.geometry.KDTreeSearchParamRadius(radius)
    else:
        param = o3d.geometry.KDTreeSearchParamKNN(args.neighbors)
    was_reset = reset_peak_rss()
    before = vm_status_kib()["VmRSS" if was_reset else "VmHWM"]
    c0 = time.process_time()
    t0 = time.perf_counter()
    out = cloud.smooth_mls(param)
    res["process_s"] = time.perf_counter() - t0
    res["process_cpu_s"] = time.process_time() - c0
    res["peak_bytes_per_point"] = (vm_status_kib()["VmHWM"] - before) * 1024.0 / n
    q = np.asarray(out.points)
    res["n_out"] = len(q)
    if len(q) == n:  # sanity: how far the pass moved the points, of the bbox diagonal
        diag = float(np.linalg.norm(pts.max(0) - pts.min(0)))
        res["mean_displacement_rel"] = float(np.linalg.norm(q - pts, axis=1).mean() / diag)
    print(json.dumps(res), flush=True)
    return 0


def run_json_subprocess(cmd: list[str], timeout: float | None,
                        env: dict | None = None) -> tuple[dict | None, str]:
    """Run cmd, return (last JSON line on stdout, error text)."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return None, f"timed out after {timeout:.0f} s"
    for line in reversed(proc.stdout.strip().splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line), ""
            except json.JSONDecodeError:
                break
    tail = (proc.stderr or proc.stdout).strip().splitlines()[-6:]
    return None, f"exit {proc.returncode}: " + " | ".join(tail)


# --------------------------------------------------------------------------- PCL peer

def build_peer(force: bool = False) -> tuple[Path | None, str]:
    """Configure and build the PCL harness into bench/peers/build/. Returns (binary, why-not)."""
    if shutil.which("cmake") is None:
        return None, "cmake not found"
    PEER_BUILD.mkdir(parents=True, exist_ok=True)
    if force or not (PEER_BUILD / "CMakeCache.txt").exists():
        cfg = subprocess.run(
            ["cmake", "-S", str(PEER_SRC), "-B", str(PEER_BUILD), "-DCMAKE_BUILD_TYPE=Release"],
            capture_output=True, text=True)
        if cfg.returncode != 0:
            msg = cfg.stderr.strip() or cfg.stdout.strip()
            # a failed configure must not stick: drop the cache so the next run retries
            (PEER_BUILD / "CMakeCache.txt").unlink(missing_ok=True)
            if "libpcl" in msg or "PCL headers" in msg:
                return None, ("PCL is not installed: `apt-get install -y libpcl-dev` "
                              "(Debian), then re-run")
            return None, "cmake configure failed: " + " | ".join(msg.splitlines()[-4:])
    b = subprocess.run(["cmake", "--build", str(PEER_BUILD), "-j", str(os.cpu_count() or 2)],
                       capture_output=True, text=True)
    if b.returncode != 0 or not PEER_BIN.exists():
        msg = (b.stderr.strip() or b.stdout.strip()).splitlines()[-4:]
        return None, "PCL harness build failed: " + " | ".join(msg)
    return PEER_BIN, ""


# --------------------------------------------------------------------------- table

SIDES = ("ps", "pcl", "o3d_radius", "o3d_knn")
SIDE_NAMES = {"ps": "pointscale", "pcl": "PCL MLS", "o3d_radius": "Open3D smooth_mls (radius)",
              "o3d_knn": "Open3D smooth_mls (kNN)"}
PEERS = ("pcl", "o3d_radius", "o3d_knn")


def fmt(x, spec, missing="n/a"):
    return missing if x is None else format(x, spec)


def wall(r: dict, side: str):
    return (r.get(side) or {}).get("wall_s")


def faster_peer(r: dict) -> tuple[str | None, float | None]:
    """The peer pass that was fastest on this input and order (median wall time)."""
    best = [(wall(r, s), s) for s in PEERS if wall(r, s)]
    if not best:
        return None, None
    t, side = min(best)
    return side, t


def peer_ratio(r: dict) -> tuple[float | None, str | None]:
    a = wall(r, "ps")
    side, b = faster_peer(r)
    return ((a / b) if (a is not None and b) else None), side


def time_cell(r: dict, side: str, reps: int, spec: str = ".3f") -> str:
    if r.get(side + "_timeout"):
        return f"> {r[side + '_timeout']:.0f} (timeout)"
    res = r.get(side)
    if not res:
        return "FAILED" if r.get(side + "_err") else "n/a"
    cell = format(res["wall_s"], spec)
    if len(res["all_s"]) < reps:
        cell += f" ({len(res['all_s'])} run{'s' if len(res['all_s']) > 1 else ''})"
    return cell


def render(rows: list[dict], args: argparse.Namespace) -> str:
    """Three tables: the ratio per input and order, every side's time, and the rest."""
    out = ["| input | points | " + " | ".join(
        f"{o} order: pointscale / faster peer" if o == "coherent" else f"{o}: pointscale / faster peer"
        for o in args.orders) + " |"]
    out.append("|" + "|".join(["---"] * (2 + len(args.orders))) + "|")
    names = list(dict.fromkeys(r["name"] for r in rows))
    for name in names:
        cells = []
        n = None
        for o in args.orders:
            r = next((x for x in rows if x["name"] == name and x["order"] == o), None)
            if r is None:
                cells.append("n/a")
                continue
            n = r["n"]
            ratio, side = peer_ratio(r)
            cells.append("n/a" if ratio is None else
                         f"**{ratio:.2f}** ({wall(r, 'ps'):.3f} s / {wall(r, side):.3f} s "
                         f"{SIDE_NAMES[side]}; {r['order_label']})")
        out.append(f"| {name} | {n:,} | " + " | ".join(cells) + " |")

    out += ["", "| input | order | pointscale decompose, %d levels (s) | PCL MLS pass (s) "
            "| Open3D smooth_mls, radius (s) | Open3D smooth_mls, kNN (s) | faster peer "
            "| ratio pointscale / faster peer | CPU-time ratio (pointscale / that peer, s) |" % args.levels]
    out.append("|" + "|".join(["---"] * 9) + "|")
    for r in rows:
        ratio, side = peer_ratio(r)
        if r.get("ps_timeout") and faster_peer(r)[1]:
            ratio_cell = f"> {r['ps_timeout'] / faster_peer(r)[1]:.0f}"
        else:
            ratio_cell = fmt(ratio, ".2f")
        cpu_cell = "n/a"
        ps = r.get("ps") or {}
        if side and ps.get("cpu_s") is not None and r[side].get("cpu_s"):
            cpu_cell = (f"{ps['cpu_s'] / r[side]['cpu_s']:.2f} "
                        f"({ps['cpu_s']:.2f} / {r[side]['cpu_s']:.2f})")
        out.append(f"| {r['name']} | {r['order_label']} | " +
                   " | ".join(time_cell(r, sd, args.reps) for sd in SIDES) +
                   f" | {SIDE_NAMES[side] if side else 'n/a'} | {ratio_cell} | {cpu_cell} |")

    out += ["", "| input | order | K | PCL radius / mean nbrs | reconstruct median / first (ms) "
            "| Reconstructor median / setup (ms) | both on a moved base (ms) | recon max err / diag "
            "| peak mem (B/pt) | PCL peak (B/pt) | Open3D peak, radius / kNN (B/pt) |"]
    out.append("|" + "|".join(["---"] * 11) + "|")
    for r in rows:
        ps, pc = r.get("ps") or {}, r.get("pcl") or {}
        rad = (f"{pc['radius']:.4g} / {pc['mean_neighbors']:.1f}" if pc else "n/a")
        recon = ("n/a" if ps.get("reconstruct_median_ms") is None else
                 f"{ps['reconstruct_median_ms']:.1f} / {ps['reconstruct_first_ms']:.1f}")
        solver = ("n/a" if ps.get("reconstructor_median_ms") is None else
                  f"{ps['reconstructor_median_ms']:.1f} / {ps['reconstructor_setup_ms']:.1f}"
                  + ("" if ps.get("reconstructor_identical") else " (DIFFERS)"))
        moved = ("n/a" if ps.get("reconstruct_moved_median_ms") is None else
                 f"{ps['reconstruct_moved_median_ms']:.1f} / {ps['reconstructor_moved_median_ms']:.1f}")
        pcl_mem = None
        if pc:
            pcl_mem = (pc["hwm_after_kib"] - pc["rss_before_kib"]) * 1024.0 / pc["n"]
        o3d_mem = " / ".join(fmt((r.get(sd) or {}).get("peak_bytes_per_point"), ".0f")
                             for sd in ("o3d_radius", "o3d_knn"))
        out.append(
            f"| {r['name']} | {r['order_label']} | {args.neighbors} | {rad} | {recon} | {solver} | {moved} | "
            f"{fmt(ps.get('reconstruct_max_err_rel'), '.1e')} | "
            f"{fmt(ps.get('peak_bytes_per_point'), '.0f')} | {fmt(pcl_mem, '.0f')} | {o3d_mem} |")
    return "\n".join(out)


def verdicts(rows: list[dict]) -> list[str]:
    lines = []
    for r in rows:
        ps = r.get("ps") or {}
        ratio, side = peer_ratio(r)
        big = (r["kind"] == "synthetic" and r["n"] == 1_000_000) or r["kind"] == "data"
        if big and ratio is not None:
            lines.append(f"{r['name']}, {r['order_label']}: decompose / faster peer ({SIDE_NAMES[side]}) "
                         f"= {ratio:.2f} (target <= {TARGET_RATIO}) -> "
                         f"{'MET' if ratio <= TARGET_RATIO else 'NOT MET'}")
        if (r["kind"] == "synthetic" and r["n"] == 100_000 and r["order"] == "shuffled"
                and ps.get("reconstruct_median_ms") is not None):
            ms = ps["reconstruct_median_ms"]
            lines.append(f"reconstruct at 100k x 4 levels (shuffled), pointscale.reconstruct on its own base handed "
                         f"back: {ms:.1f} ms median")
            if ps.get("reconstructor_median_ms") is not None:
                ms = ps["reconstructor_median_ms"]
                same = ps.get("reconstructor_identical")
                lines.append(f"reconstruct at 100k x 4 levels (shuffled), pointscale.Reconstructor: {ms:.1f} ms "
                             f"median, setup {ps['reconstructor_setup_ms']:.1f} ms once, points "
                             f"{'identical' if same else 'DIFFERENT'} (target < {TARGET_RECON_MS:.0f} ms) -> "
                             f"{'MET' if same and ms < TARGET_RECON_MS else 'NOT MET'}")
            if ps.get("reconstruct_moved_median_ms") is not None:
                a, b = ps["reconstruct_moved_median_ms"], ps["reconstructor_moved_median_ms"]
                first = ps.get("reconstruct_moved_first_ms")
                lines.append(f"reconstruct at 100k x 4 levels (shuffled) on a base moved everywhere: reconstruct "
                             f"{a:.1f} ms median after its first call ("
                             + ("n/a" if first is None else f"{first:.1f}") + " ms, which finds the edit support), "
                             f"Reconstructor {b:.1f} ms median (target < {TARGET_RECON_MS:.0f} ms) -> "
                             f"{'MET' if max(a, b) < TARGET_RECON_MS else 'NOT MET'}")
    worst = [(r["ps"]["peak_bytes_per_point"], f"{r['name']}, {r['order_label']}") for r in rows if r.get("ps")]
    if worst:
        bpp, name = max(worst)
        lines.append(f"peak memory, worst input ({name}): {bpp:.0f} B/point (target < "
                     f"{TARGET_BYTES_PER_POINT:.0f}) -> {'MET' if bpp < TARGET_BYTES_PER_POINT else 'NOT MET'}")
    huge = [r for r in rows if r["kind"] == "synthetic" and r["n"] >= 10_000_000]
    for r in huge:
        ok = bool(r.get("ps"))
        lines.append(f"{size_label(r['n'])} decompose, {r['order_label']}: "
                     f"{'completed' if ok else 'FAILED: ' + str(r.get('ps_err'))}")
    return lines


RESULTS_BEGIN = "<!-- bench/run.py --results: begin (generated; run the command again, do not edit) -->"
RESULTS_END = "<!-- bench/run.py --results: end -->"


def results_markdown(rows: list[dict], meta: dict) -> str:
    """The one results table, in markdown, between RESULTS_BEGIN and RESULTS_END: what ran
    (command, date, machine, revision, load), the input orders, and one row per input and order.

    meta: command, date, machine, revision, load_start, load_end, neighbors, levels, threads,
    reps, recon_reps, peers (which PCL and Open3D ran), and not_run (optional: a sentence per side that did not run, saying why)."""
    m = meta
    out = [RESULTS_BEGIN,
           f"Command: `{m['command']}`  ",
           f"Date: {m['date']}  ",
           f"Machine: {m['machine']}  ",
           f"pointscale: {m['revision']}  ",
           f"Peers: {m['peers']}  ",
           f"Load average (1, 5, 15 min): {m['load_start']} at the start, {m['load_end']} at the end  ",
           "Input order: *Morton order* = the synthetic cloud sorted along a Z-order curve; *file order* = "
           "a scan as its file holds it; *shuffled* = either under one fixed random permutation "
           f"(seed {SHUFFLE_SEED}).",
           "",
           "| input | points | order | pointscale decompose (s) | PCL MLS (s) | Open3D smooth_mls, radius (s) "
           "| Open3D smooth_mls, kNN (s) | pointscale / faster peer | CPU-time ratio "
           "| reconstruct / Reconstructor (ms) | both on a moved base (ms) | peak memory (B/point) |",
           "|" + "|".join(["---"] * 12) + "|"]
    for r in rows:
        ps = r.get("ps") or {}
        ratio, side = peer_ratio(r)
        if r.get("ps_timeout") and faster_peer(r)[1]:
            ratio_cell = f"> {r['ps_timeout'] / faster_peer(r)[1]:.0f}"
        else:
            ratio_cell = "n/a" if ratio is None else f"{ratio:.2f}, {SIDE_NAMES[side]}"
        cpu_cell = "n/a"
        if side and ps.get("cpu_s") is not None and (r.get(side) or {}).get("cpu_s"):
            cpu_cell = f"{ps['cpu_s'] / r[side]['cpu_s']:.2f}"
        recon = ("n/a" if ps.get("reconstruct_median_ms") is None else
                 f"{ps['reconstruct_median_ms']:.1f} / " +
                 ("n/a" if ps.get("reconstructor_median_ms") is None else
                  f"{ps['reconstructor_median_ms']:.1f}" + ("" if ps.get("reconstructor_identical") else " (DIFFERS)")))
        moved = ("n/a" if ps.get("reconstruct_moved_median_ms") is None else
                 f"{ps['reconstruct_moved_median_ms']:.1f} / {ps['reconstructor_moved_median_ms']:.1f}")
        out.append(f"| {r['name']} | {r['n']:,} | {r['order_label']} | " +
                   " | ".join(time_cell(r, sd, m["reps"], ".2f") for sd in SIDES) +
                   f" | {ratio_cell} | {cpu_cell} | {recon} | {moved} | {fmt(ps.get('peak_bytes_per_point'), '.0f')} |")
    out += ["",
            f"Every time is the median of {m['reps']} interleaved round{'s' if m['reps'] != 1 else ''}, each pass "
            "in a fresh process that builds its own index (fewer where a cell says so). pointscale decompose: "
            f"`decompose(points, levels={m['levels']}, neighbors={m['neighbors']}, threads={m['threads']})`. "
            f"PCL: `MovingLeastSquares`, order 1, radius calibrated to a mean of {m['neighbors']} neighbours, "
            f"{m['threads']} threads, `process()` only. Open3D: `PointCloud.smooth_mls` with PCL's radius and with "
            f"KNN({m['neighbors']}), OMP_NUM_THREADS={m['threads']}. Faster peer: the smallest of the three peer "
            "times on that row. CPU-time ratio: user + system CPU seconds, all threads, pointscale over that peer. "
            f"reconstruct: `reconstruct(dec, base=dec.base)` and `Reconstructor(dec).reconstruct(base=...)`, "
            f"medians of {m['recon_reps']} alternating calls in the first round's process; moved base: both on a "
            "base one of two broad waves moved everywhere, in turn, after a first call of reconstruct that finds the edit support. "
            "Peak memory: peak RSS (VmHWM) minus the RSS after loading the "
            "points, during the first round's decompose, per input point."
            + "".join(f" {what}." for what in m.get("not_run", [])),
            RESULTS_END]
    return "\n".join(out)


def check_results_file(path: Path) -> str | None:
    """Why --results cannot write to path (None when it can): an existing file must hold the
    markers, so that only the table between them is replaced and the rest is kept."""
    if not path.exists():
        return None
    text = path.read_text()
    if RESULTS_BEGIN not in text or RESULTS_END not in text:
        return (f"{path} exists without the markers {RESULTS_BEGIN!r} and {RESULTS_END!r}: "
                "add them where the table goes, or give a new file")
    return None


def write_results(path: Path, block: str) -> None:
    """Writes the table into path: between the markers of an existing file (the rest kept), or a
    new file holding only a title and the table."""
    if path.exists():
        text = path.read_text()
        head, rest = text.split(RESULTS_BEGIN, 1)
        tail = rest.split(RESULTS_END, 1)[1]
        path.write_text(head + block + tail)
    else:
        path.write_text("# Benchmark results\n\n" + block + "\n")


def core_revision() -> str:
    """HEAD of the repo and whether native/ differs from it (the core being measured)."""
    try:
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--", "native",
                                "CMakeLists.txt", "pyproject.toml"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + (" (native/ has uncommitted changes)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def machine_line() -> str:
    model = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = "?"
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                mem = f"{int(line.split()[1]) / 1024**2:.1f} GiB"
                break
    except OSError:
        pass
    return f"nproc={os.cpu_count()}, CPU: {model}, RAM: {mem}, {platform.platform()}, Python {platform.python_version()}"


# --------------------------------------------------------------------------- main

def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true",
                   help="smoke test: 20k synthetic points, no data sets, 3 reconstruct runs")
    p.add_argument("--sizes", type=lambda s: [parse_size(x) for x in s.split(",") if x.strip()],
                   help="comma-separated synthetic sizes, e.g. 100k,1M (default 100k,1M)")
    p.add_argument("--huge", action="store_true", help="also decompose a 10M-point synthetic cloud")
    p.add_argument("--orders", type=lambda s: [x.strip() for x in s.split(",") if x.strip()],
                   default=list(ORDERS),
                   help="input orders to time, of coherent,shuffled (default both): coherent = file "
                        "order for scans, Morton order for synthetic clouds; shuffled = a fixed "
                        "random permutation")
    p.add_argument("--morton", action="store_true",
                   help="the coherent order only (same as --orders coherent; kept for old commands)")
    p.add_argument("--no-pcl", action="store_true", help="skip the PCL peer")
    p.add_argument("--no-open3d", action="store_true", help="skip the Open3D peer")
    p.add_argument("--open3d-search", choices=("radius", "knn", "both"), default="both",
                   help="Open3D smooth_mls neighbourhoods: PCL's radius, K nearest, or both (default)")
    p.add_argument("--no-pointscale", action="store_true", help="skip pointscale (peers only)")
    p.add_argument("--no-data", action="store_true", help="skip the real scans")
    p.add_argument("--data-dir", type=Path, default=DEFAULT_DATA,
                   help=f"where dragon.ply etc. live (default {DEFAULT_DATA})")
    p.add_argument("--neighbors", "-k", type=int, default=24, help="K for every side (default 24)")
    p.add_argument("--levels", type=int, default=4, help="decomposition levels (default 4)")
    p.add_argument("--threads", type=int, default=2,
                   help="threads for every side (default 2, the issue's reference)")
    p.add_argument("--recon-reps", type=int, default=None,
                   help="reconstruct runs per cloud and order (default 9; 3 with --quick)")
    p.add_argument("--reps", type=int, default=None,
                   help="interleaved rounds (a fresh process per pass), median reported (default 3; "
                        "1 with --quick and for >= 10M points)")
    p.add_argument("--timeout", type=float, default=600.0,
                   help="per-subprocess timeout in s (default 600); a timed-out cell reads '> T'")
    p.add_argument("--rep-budget", type=float, default=60.0,
                   help="stop repeating a side on an input once its passes took this many s (default 60)")
    p.add_argument("--json", type=Path, help="also write all raw results to this file")
    p.add_argument("--results", type=Path, metavar="FILE.md",
                   help="also write the results table in markdown, with the command, date, machine and "
                        "input orders: between the markers of an existing file (bench/RESULTS.md), or "
                        "into a new one")
    p.add_argument("--worker-pointscale", help=argparse.SUPPRESS)
    p.add_argument("--worker-open3d", help=argparse.SUPPRESS)
    p.add_argument("--o3d-search", default="knn", help=argparse.SUPPRESS)
    p.add_argument("--radius", type=float, default=0.0, help=argparse.SUPPRESS)
    args = p.parse_args(argv)

    if args.worker_pointscale:
        return worker_pointscale(args)
    if args.worker_open3d:
        return worker_open3d(args)

    if args.results:
        why = check_results_file(args.results)
        if why:
            p.error(why)
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    load_start = ", ".join(open("/proc/loadavg").read().split()[:3])

    if args.morton:
        args.orders = ["coherent"]
    bad = [o for o in args.orders if o not in ORDERS]
    if bad or not args.orders:
        p.error(f"--orders takes {','.join(ORDERS)}, not {','.join(bad) or 'nothing'}")
    if args.reps is None:
        args.reps = 1 if args.quick else 3
    if args.recon_reps is None:
        args.recon_reps = 3 if args.quick else 9
    sizes = args.sizes or ([20_000] if args.quick else [100_000, 1_000_000])
    if args.huge:
        sizes = sizes + [10_000_000]

    print("# pointscale vs PCL MovingLeastSquares and Open3D smooth_mls")
    print("machine:", machine_line())
    print("command:", "python bench/run.py" + ("" if not sys.argv[1:] else " " + " ".join(sys.argv[1:])))
    print("load average at start:", open("/proc/loadavg").read().split()[:3],
          "(others' processes on this machine disturb timings)")
    print(f"K={args.neighbors} levels={args.levels} threads={args.threads} orders={','.join(args.orders)} "
          f"rounds={args.reps} (median, interleaved, a fresh process per pass) "
          f"reconstruct reps={args.recon_reps}", flush=True)

    # --- which sides can run
    have_ps = False
    ps_why = "skipped (--no-pointscale)"
    if not args.no_pointscale:
        chk = subprocess.run([sys.executable, "-c",
                              "import pointscale, os, time; from pointscale import _core; "
                              "print(getattr(pointscale, '__version__', '?'), pointscale.__file__, "
                              "'| _core built', time.strftime('%Y-%m-%d %H:%M:%S UTC', "
                              "time.gmtime(os.path.getmtime(_core.__file__))))"],
                             capture_output=True, text=True)
        if chk.returncode == 0:
            have_ps = True
            print("pointscale:", chk.stdout.strip(), "| repo HEAD", core_revision())
        else:
            ps_why = "pointscale not importable (pip install -e . in the repo root)"
            print("pointscale: NOT IMPORTABLE -", (chk.stderr.strip().splitlines() or ["?"])[-1])
            print("  -> pointscale columns will read n/a; run `pip install -e .` first")
    peer = None
    pcl_why = "skipped (--no-pcl)"
    if not args.no_pcl:
        peer, pcl_why = build_peer()
        if peer is None:
            print("PCL peer: UNAVAILABLE -", pcl_why)
            print("  -> PCL columns will read n/a")
        else:
            print("PCL peer:", peer.relative_to(REPO))
    o3d_modes: list[str] = []
    o3d_version = "?"
    o3d_why = "skipped (--no-open3d)"
    if not args.no_open3d:
        chk = subprocess.run([sys.executable, "-c",
                              "import open3d; print(open3d.__version__, "
                              "hasattr(open3d.geometry.PointCloud, 'smooth_mls'))"],
                             capture_output=True, text=True)
        words = chk.stdout.split()
        if chk.returncode != 0:
            last = (chk.stderr.strip().splitlines() or ["?"])[-1]
            o3d_why = f"open3d not importable ({last}): `pip install open3d`"
            if "libusb" in last:
                o3d_why += " and `apt-get install -y libusb-1.0-0`"
        elif words[-1:] != ["True"]:
            o3d_why = f"open3d {words[0] if words else '?'} has no PointCloud.smooth_mls"
        else:
            o3d_modes = ["radius", "knn"] if args.open3d_search == "both" else [args.open3d_search]
            o3d_version = words[0]
            print(f"Open3D peer: open3d {words[0]}, PointCloud.smooth_mls ({' and '.join(o3d_modes)} search), "
                  f"OMP_NUM_THREADS={args.threads}")
        if not o3d_modes:
            print("Open3D peer: UNAVAILABLE -", o3d_why)
            print("  -> Open3D columns will read n/a")
    o3d_env = dict(os.environ, OMP_NUM_THREADS=str(args.threads))
    print(flush=True)

    inputs: list[tuple[str, str, object]] = [
        ("synthetic", f"bumpy sphere {size_label(n)}", n) for n in sizes]
    if not (args.no_data or args.quick):
        for name in DATASETS:
            path = args.data_dir / name
            if path.exists():
                inputs.append(("data", name, path))
            else:
                print(f"skip {name}: not found in {args.data_dir}")

    rows = []
    with tempfile.TemporaryDirectory(prefix="pointscale-bench-") as tmp:
        tmp = Path(tmp)
        for kind, name, src in inputs:
            t0 = time.perf_counter()
            pts = bumpy_sphere(src) if kind == "synthetic" else read_ply_xyz(src)
            n = len(pts)
            files, by_order = {}, {}
            for order in args.orders:
                f32, npy = tmp / f"cloud-{order}.f32", tmp / f"cloud-{order}.npy"
                ordered = in_order(pts, kind, order)
                ordered.astype("<f4").tofile(f32)
                np.save(npy, np.ascontiguousarray(ordered, dtype=np.float64))
                del ordered
                files[order] = (f32, npy)
                by_order[order] = {"kind": kind, "name": name, "order": order,
                                   "order_label": order_label(kind, order), "n": n}
            del pts
            print(f"[{name}] {n:,} points prepared in {len(args.orders)} orders in "
                  f"{time.perf_counter() - t0:.1f} s", flush=True)
            rounds = 1 if n >= 10_000_000 else args.reps
            radius = None  # PCL's calibrated radius, shared by every later pass on this cloud

            def record(row: dict, side: str, res: dict | None, err: str, wall_key: str, cpu_key: str):
                if not res:
                    row[side + "_err"] = err
                    if err.startswith("timed out"):
                        row[side + "_timeout"] = args.timeout
                    return None
                agg = row.get(side)
                if agg is None:
                    agg = row[side] = dict(res, all_s=[], all_cpu_s=[])
                agg["all_s"].append(res[wall_key])
                agg["all_cpu_s"].append(res[cpu_key])
                agg["wall_s"] = statistics.median(agg["all_s"])
                agg["cpu_s"] = statistics.median(agg["all_cpu_s"])
                return res[wall_key]

            def wanted(row: dict, side: str) -> bool:  # not failed, not over its time budget
                if row.get(side + "_err"):
                    return False
                done = (row.get(side) or {}).get("all_s", [])
                return sum(done) <= args.rep_budget or not done

            for rnd in range(rounds):
                for order in args.orders:
                    row = by_order[order]
                    f32, npy = files[order]
                    said = []
                    if peer is not None and wanted(row, "pcl"):
                        cmd = [str(peer), str(f32), str(args.neighbors), "--threads", str(args.threads),
                               "--reps", "1"]
                        if radius:
                            cmd += ["--radius", repr(radius)]
                        res, err = run_json_subprocess(cmd, args.timeout)
                        t = record(row, "pcl", res, err, "process_s", "process_cpu_s")
                        if res and radius is None:
                            radius = res["radius"]
                        said.append(f"PCL {t:.3f} s" if t is not None else f"PCL FAILED: {err}")
                    for mode in o3d_modes:
                        side = "o3d_" + mode
                        if not wanted(row, side):
                            continue
                        cmd = [sys.executable, str(Path(__file__).resolve()), "--worker-open3d", str(f32),
                               "--o3d-search", mode, "--neighbors", str(args.neighbors)]
                        if mode == "radius" and radius:
                            cmd += ["--radius", repr(radius)]
                        res, err = run_json_subprocess(cmd, args.timeout, env=o3d_env)
                        t = record(row, side, res, err, "process_s", "process_cpu_s")
                        if res and mode == "radius" and radius is None:
                            radius = res["radius"]
                        said.append(f"Open3D {mode} {t:.3f} s" if t is not None else
                                    f"Open3D {mode} FAILED: {err}")
                    if have_ps and wanted(row, "ps"):
                        res, err = run_json_subprocess(
                            [sys.executable, str(Path(__file__).resolve()), "--worker-pointscale", str(npy),
                             "--neighbors", str(args.neighbors), "--levels", str(args.levels),
                             "--threads", str(args.threads),
                             "--recon-reps", str(args.recon_reps if rnd == 0 else 0),
                             "--reps", "1", "--rep-budget", str(args.rep_budget)],
                            args.timeout)
                        t = record(row, "ps", res, err, "decompose_s", "decompose_cpu_s")
                        if t is None:
                            said.append(f"pointscale FAILED: {err}")
                        else:
                            msg = f"pointscale {t:.3f} s"
                            if rnd == 0:
                                msg += f" (peak {res['peak_bytes_per_point']:.0f} B/pt"
                                if "reconstruct_median_ms" in res:
                                    msg += (f", reconstruct {res['reconstruct_median_ms']:.1f} ms median, max err "
                                            f"{res['reconstruct_max_err_rel']:.1e} of diag, Reconstructor "
                                            f"{res['reconstructor_median_ms']:.1f} ms median")
                                msg += ")"
                            said.append(msg)
                    print(f"  round {rnd + 1}, {row['order_label']}: " + " | ".join(said), flush=True)
            for order in args.orders:
                row = by_order[order]
                if row.get("ps"):  # the names the rest of this file and older JSON readers use
                    row["ps"]["decompose_s"] = row["ps"]["wall_s"]
                    row["ps"]["decompose_all_s"] = row["ps"]["all_s"]
                    row["ps"]["decompose_reps"] = len(row["ps"]["all_s"])
                for side in PEERS:
                    if row.get(side):
                        row[side]["process_s"] = row[side]["wall_s"]
                        row[side]["process_all_s"] = row[side]["all_s"]
                if row.get("pcl"):
                    row["pcl"]["radius"] = radius or row["pcl"]["radius"]
                rows.append(row)

    print()
    print(render(rows, args))
    print()
    print("order: coherent = file order for a scan, Morton (Z-order) sort for a synthetic cloud; shuffled = "
          f"that order under a fixed random permutation (seed {SHUFFLE_SEED}).")
    print("(a) pointscale.decompose(points, levels=%d, neighbors=%d, threads=%d), wall time, "
          "median of %d fresh processes (fewer where marked: a side stops repeating after --rep-budget %.0f s);"
          % (args.levels, args.neighbors, args.threads, args.reps, args.rep_budget))
    print("(b) pcl::MovingLeastSquares<PointXYZ, PointNormal>, order 1, radius calibrated to a mean of "
          "K neighbours, %d threads, process() only (its kd-tree build included);" % args.threads)
    print("(b') open3d PointCloud.smooth_mls, KDTreeSearchParamRadius(PCL's radius) and KDTreeSearchParamKNN(K), "
          "OMP_NUM_THREADS=%d, that call only (its kd-tree build included); every pass interleaved with the "
          "others, round by round, median of %d." % (args.threads, args.reps))
    print("faster peer = the peer pass with the smallest median wall time on that input and order.")
    print("CPU-time ratio: user+system CPU seconds of (a) over the faster peer's, all threads; less sensitive to other load than wall time.\n"
          "reconstruct = pointscale.reconstruct(dec, base=base), base = dec.base taken once before the runs; Reconstructor = "
          "pointscale.Reconstructor(dec).reconstruct(base=base), called alternately with it (setup: building it, once); moved base = "
          "both on bases two broad waves moved everywhere, in turn; peak mem = VmHWM (peak RSS) minus RSS after loading, first round's "
          "process (the peers: around their pass).")
    if not have_ps:
        print("pointscale:", ps_why)
    if peer is None:
        print("PCL:", pcl_why)
    if not o3d_modes:
        print("Open3D:", o3d_why)
    print("load average at end:", open("/proc/loadavg").read().split()[:3])
    for r in rows:
        for side in SIDES:
            if r.get(side + "_err"):
                print(f"{r['name']}, {r['order_label']}: {SIDE_NAMES[side]} failed: {r[side + '_err']}")
    v = verdicts(rows)
    if v:
        print()
        for line in v:
            print(" -", line)
    if args.json:
        args.json.write_text(json.dumps({"machine": machine_line(), "argv": sys.argv[1:],
                                         "rows": rows}, indent=1))
        print(f"\nraw results: {args.json}")
    if args.results:
        write_results(args.results, results_markdown(rows, {
            "command": "python bench/run.py" + ("" if not sys.argv[1:] else " " + " ".join(sys.argv[1:])),
            "date": started, "machine": machine_line(),
            "revision": f"the repository at {core_revision()}" if have_ps else ps_why,
            "load_start": load_start, "load_end": ", ".join(open("/proc/loadavg").read().split()[:3]),
            "neighbors": args.neighbors, "levels": args.levels, "threads": args.threads,
            "reps": args.reps, "recon_reps": args.recon_reps,
            "peers": ", ".join((["PCL MovingLeastSquares (bench/peers/pcl_mls)"] if peer is not None else []) +
                               ([f"Open3D {o3d_version} ({' and '.join(o3d_modes)} search)"] if o3d_modes else []))
                     or "none",
            "not_run": ([f"pointscale did not run: {ps_why}"] if not have_ps else []) +
                       ([f"PCL did not run: {pcl_why}"] if peer is None else []) +
                       ([f"Open3D did not run: {o3d_why}"] if not o3d_modes else [])}))
        print(f"results table: {args.results}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
