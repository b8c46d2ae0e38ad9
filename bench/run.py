#!/usr/bin/env python3
"""Pointscale speed benchmark against PCL's MovingLeastSquares, side by side in ONE run.

    python bench/run.py                 # 100k + 1M synthetic, dragon, happy_buddha_scans
    python bench/run.py --quick         # small smoke test (20k synthetic only)
    python bench/run.py --sizes 100k,1M --no-pcl
    python bench/run.py --huge          # also a 10M-point synthetic cloud

For every input cloud the same float32-exact points are fed to both sides:
  (a) pointscale.decompose(points, levels=4, neighbors=K) wall time,
  (b) one PCL MLS pass (order 1, radius calibrated so the mean neighbour count is K,
      same thread count), wall time of process() only, from bench/peers/pcl_mls,
  (c) ratio (a)/(b)                                  target < 1.0 (at 1M),
  (d) pointscale.reconstruct(dec, base=base), median of several runs, with base = dec.base
      taken once before them, as an editor holds its edited base (through the edited-base
      path; handed back unchanged, so no point turns), and the same through
      pointscale.Reconstructor(dec), the solver an editing session keeps (its one-off setup
      timed apart; the two are called alternately and must give identical points); then both
      again on a base a broad wave moved everywhere, so that every point's turn is measured
                                                      target < 20 ms at 100k x 4 levels,
  (e) peak memory per point while decomposing: peak RSS (VmHWM, reset after the data
      is loaded) minus the RSS after loading, in a fresh subprocess per cloud (not
      ru_maxrss: a child inherits its parent's peak through fork/exec)
                                                      target < 300 bytes/point.
Timed code never runs in a test; this script only prints.

Every measurement runs in its own subprocess (one per cloud per side) so that peak
RSS is per-cloud and a crash on one input does not lose the others.
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
        # point's turn is measured: base=dec.base above turns nothing.
        lifted = base + (0.05 * diag) * np.sin(3.0 * base[:, [0]] / diag) * np.array([0.0, 0.0, 1.0])
        edited, solver_edited = [], []
        for _ in range(args.recon_reps):
            t0 = time.perf_counter()
            pointscale.reconstruct(dec, base=lifted)
            edited.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            solver.reconstruct(base=lifted)
            solver_edited.append(time.perf_counter() - t0)
        res.update({
            "reconstruct_moved_median_ms": statistics.median(edited) * 1e3,
            "reconstructor_moved_median_ms": statistics.median(solver_edited) * 1e3,
        })
    print(json.dumps(res), flush=True)
    return 0


def run_json_subprocess(cmd: list[str], timeout: float | None) -> tuple[dict | None, str]:
    """Run cmd, return (last JSON line on stdout, error text)."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
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

def fmt(x, spec, missing="n/a"):
    return missing if x is None else format(x, spec)


def render(rows: list[dict], args: argparse.Namespace) -> str:
    head = ("| input | points | K | pointscale decompose, 4 levels (s) | PCL MLS pass (s) "
            "| PCL radius / mean nbrs | ratio (a)/(b) | CPU-time ratio | reconstruct median / first (ms) "
            "| Reconstructor median / setup (ms) | recon max err / diag | peak mem (B/pt) | PCL peak (B/pt) |")
    sep = "|" + "|".join(["---"] * (head.count("|") - 1)) + "|"
    out = [head, sep]
    for r in rows:
        ps, pc = r.get("ps") or {}, r.get("pcl") or {}
        a = ps.get("decompose_s")
        b = pc.get("process_s")
        ratio = (a / b) if (a is not None and b) else None
        a_cell = fmt(a, ".3f", "FAILED" if r.get("ps_err") else "n/a")
        b_cell = fmt(b, ".3f", "FAILED" if r.get("pcl_err") else "n/a")
        ratio_cell = fmt(ratio, ".2f")
        cpu_ratio_cell = "n/a"
        if ps.get("decompose_cpu_s") is not None and pc.get("process_cpu_s"):
            cpu_ratio_cell = (f"{ps['decompose_cpu_s'] / pc['process_cpu_s']:.2f} "
                              f"({ps['decompose_cpu_s']:.2f} / {pc['process_cpu_s']:.2f} s)")
        if ps and ps.get("decompose_reps", 1) < args.reps:
            a_cell += f" ({ps['decompose_reps']} run{'s' if ps['decompose_reps'] > 1 else ''})"
        if r.get("ps_timeout"):
            a_cell = f"> {r['ps_timeout']:.0f} (timeout)"
            if b:
                ratio_cell = f"> {r['ps_timeout'] / b:.0f}"
        if r.get("pcl_timeout"):
            b_cell = f"> {r['pcl_timeout']:.0f} (timeout)"
        rad = (f"{pc['radius']:.4g} / {pc['mean_neighbors']:.1f}" if pc else "n/a")
        recon = ("n/a" if ps.get("reconstruct_median_ms") is None else
                 f"{ps['reconstruct_median_ms']:.1f} / {ps['reconstruct_first_ms']:.1f}")
        solver = ("n/a" if ps.get("reconstructor_median_ms") is None else
                  f"{ps['reconstructor_median_ms']:.1f} / {ps['reconstructor_setup_ms']:.1f}"
                  + ("" if ps.get("reconstructor_identical") else " (DIFFERS)"))
        pcl_mem = None
        if pc:
            pcl_mem = (pc["hwm_after_kib"] - pc["rss_before_kib"]) * 1024.0 / pc["n"]
        out.append(
            f"| {r['name']} | {r['n']:,} | {args.neighbors} | "
            f"{a_cell} | {b_cell} | {rad} | {ratio_cell} | {cpu_ratio_cell} | {recon} | {solver} | "
            f"{fmt(ps.get('reconstruct_max_err_rel'), '.1e')} | "
            f"{fmt(ps.get('peak_bytes_per_point'), '.0f')} | {fmt(pcl_mem, '.0f')} |")
    return "\n".join(out)


def verdicts(rows: list[dict]) -> list[str]:
    lines = []
    for r in rows:
        ps, pc = r.get("ps") or {}, r.get("pcl") or {}
        if r["kind"] == "synthetic" and r["n"] == 1_000_000 and ps and pc:
            ratio = ps["decompose_s"] / pc["process_s"]
            lines.append(f"ratio at 1M synthetic: {ratio:.2f} (target < {TARGET_RATIO}) "
                         f"-> {'MET' if ratio < TARGET_RATIO else 'NOT MET'}")
        if r["kind"] == "synthetic" and r["n"] == 100_000 and ps.get("reconstruct_median_ms") is not None:
            ms = ps["reconstruct_median_ms"]
            lines.append(f"reconstruct at 100k x 4 levels, pointscale.reconstruct: {ms:.1f} ms median (target < "
                         f"{TARGET_RECON_MS:.0f} ms) -> {'MET' if ms < TARGET_RECON_MS else 'NOT MET'}")
            if ps.get("reconstructor_median_ms") is not None:
                ms = ps["reconstructor_median_ms"]
                same = ps.get("reconstructor_identical")
                lines.append(f"reconstruct at 100k x 4 levels, pointscale.Reconstructor: {ms:.1f} ms median, "
                             f"setup {ps['reconstructor_setup_ms']:.1f} ms once, points "
                             f"{'identical' if same else 'DIFFERENT'} (target < {TARGET_RECON_MS:.0f} ms) -> "
                             f"{'MET' if same and ms < TARGET_RECON_MS else 'NOT MET'}")
            if ps.get("reconstruct_moved_median_ms") is not None:
                a, b = ps["reconstruct_moved_median_ms"], ps["reconstructor_moved_median_ms"]
                lines.append(f"reconstruct at 100k x 4 levels on a base moved everywhere: reconstruct {a:.1f} ms, "
                             f"Reconstructor {b:.1f} ms median (target < {TARGET_RECON_MS:.0f} ms) -> "
                             f"{'MET' if max(a, b) < TARGET_RECON_MS else 'NOT MET'}")
    worst = [(r["ps"]["peak_bytes_per_point"], r["name"]) for r in rows if r.get("ps")]
    if worst:
        bpp, name = max(worst)
        lines.append(f"peak memory, worst input ({name}): {bpp:.0f} B/point (target < "
                     f"{TARGET_BYTES_PER_POINT:.0f}) -> {'MET' if bpp < TARGET_BYTES_PER_POINT else 'NOT MET'}")
    huge = [r for r in rows if r["kind"] == "synthetic" and r["n"] >= 10_000_000]
    for r in huge:
        ok = bool(r.get("ps"))
        lines.append(f"{size_label(r['n'])} decompose: "
                     f"{'completed' if ok else 'FAILED: ' + str(r.get('ps_err'))}")
    return lines


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
    p.add_argument("--morton", action="store_true",
                   help="feed both sides the synthetic clouds in Morton order instead of random order")
    p.add_argument("--no-pcl", action="store_true", help="skip the PCL peer")
    p.add_argument("--no-pointscale", action="store_true", help="skip pointscale (PCL only)")
    p.add_argument("--no-data", action="store_true", help="skip the real scans")
    p.add_argument("--data-dir", type=Path, default=DEFAULT_DATA,
                   help=f"where dragon.ply etc. live (default {DEFAULT_DATA})")
    p.add_argument("--neighbors", "-k", type=int, default=24, help="K for both sides (default 24)")
    p.add_argument("--levels", type=int, default=4, help="decomposition levels (default 4)")
    p.add_argument("--threads", type=int, default=2,
                   help="threads for both sides (default 2, the issue's reference)")
    p.add_argument("--recon-reps", type=int, default=None,
                   help="reconstruct runs per cloud (default 9; 3 with --quick)")
    p.add_argument("--reps", type=int, default=None,
                   help="decompose and PCL passes per cloud, median reported (default 3; "
                        "1 with --quick and for >= 10M points)")
    p.add_argument("--timeout", type=float, default=600.0,
                   help="per-subprocess timeout in s (default 600); a timed-out cell reads '> T'")
    p.add_argument("--rep-budget", type=float, default=60.0,
                   help="stop repeating a decompose once its runs took this many s (default 60)")
    p.add_argument("--json", type=Path, help="also write all raw results to this file")
    p.add_argument("--worker-pointscale", help=argparse.SUPPRESS)
    args = p.parse_args(argv)

    if args.worker_pointscale:
        return worker_pointscale(args)

    if args.reps is None:
        args.reps = 1 if args.quick else 3
    if args.recon_reps is None:
        args.recon_reps = 3 if args.quick else 9
    sizes = args.sizes or ([20_000] if args.quick else [100_000, 1_000_000])
    if args.huge:
        sizes = sizes + [10_000_000]

    print("# pointscale vs PCL MovingLeastSquares")
    print("machine:", machine_line())
    print("command:", "python bench/run.py" + ("" if not sys.argv[1:] else " " + " ".join(sys.argv[1:])))
    print("load average at start:", open("/proc/loadavg").read().split()[:3],
          "(others' processes on this machine disturb timings)")
    print(f"K={args.neighbors} levels={args.levels} threads={args.threads} "
          f"reps={args.reps} (median) reconstruct reps={args.recon_reps}", flush=True)

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
    print(flush=True)

    order = "Morton order" if args.morton else "random order"
    inputs: list[tuple[str, str, object]] = [
        ("synthetic", f"bumpy sphere {size_label(n)} ({order})", n) for n in sizes]
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
            if kind == "synthetic" and args.morton:
                pts = pts[morton_order(pts)]
            n = len(pts)
            f32 = tmp / "cloud.f32"
            npy = tmp / "cloud.npy"
            pts.astype("<f4").tofile(f32)
            np.save(npy, np.ascontiguousarray(pts, dtype=np.float64))
            del pts
            print(f"[{name}] {n:,} points prepared in {time.perf_counter() - t0:.1f} s", flush=True)
            row = {"kind": kind, "name": name, "n": n}
            reps = 1 if n >= 10_000_000 else args.reps

            if peer is not None:
                res, err = run_json_subprocess(
                    [str(peer), str(f32), str(args.neighbors), "--threads", str(args.threads),
                     "--reps", str(reps)],
                    args.timeout)
                row["pcl"], row["pcl_err"] = res, (err or None)
                row["pcl_timeout"] = args.timeout if err.startswith("timed out") else None
                if res:
                    print(f"  PCL MLS: {res['process_s']:.3f} s {res['process_all_s']} (radius {res['radius']:.4g}, mean "
                          f"{res['mean_neighbors']:.2f} / median {res['median_neighbors']} neighbours, "
                          f"{res['n_out']:,} points out)", flush=True)
                else:
                    print("  PCL MLS FAILED:", err, flush=True)
            else:
                row["pcl"], row["pcl_err"] = None, None

            if have_ps:
                res, err = run_json_subprocess(
                    [sys.executable, str(Path(__file__).resolve()), "--worker-pointscale", str(npy),
                     "--neighbors", str(args.neighbors), "--levels", str(args.levels),
                     "--threads", str(args.threads), "--recon-reps", str(args.recon_reps),
                     "--reps", str(reps), "--rep-budget", str(args.rep_budget)],
                    args.timeout)
                row["ps"], row["ps_err"] = res, (err or None)
                row["ps_timeout"] = args.timeout if err.startswith("timed out") else None
                if res:
                    msg = (f"  pointscale decompose: {res['decompose_s']:.3f} s "
                           f"{[round(t, 3) for t in res['decompose_all_s']]}, peak "
                           f"{res['peak_bytes_per_point']:.0f} B/pt")
                    if "reconstruct_median_ms" in res:
                        msg += (f", reconstruct {res['reconstruct_median_ms']:.1f} ms median "
                                f"(max err {res['reconstruct_max_err_rel']:.1e} of diag), Reconstructor "
                                f"{res['reconstructor_median_ms']:.1f} ms median")
                    print(msg, flush=True)
                else:
                    print("  pointscale FAILED:", err, flush=True)
            else:
                row["ps"], row["ps_err"] = None, None
            rows.append(row)

    print()
    print(render(rows, args))
    print()
    print("(a) pointscale.decompose(points, levels=%d, neighbors=%d, threads=%d), wall time, "
          "median of %d (fewer where marked: runs stop after --rep-budget %.0f s);"
          % (args.levels, args.neighbors, args.threads, args.reps, args.rep_budget))
    print("(b) pcl::MovingLeastSquares<PointXYZ, PointNormal>, order 1, radius calibrated to a mean of "
          "K neighbours, %d threads, process() only, median of %d;" % (args.threads, args.reps))
    print("CPU-time ratio: user+system CPU seconds of (a) over (b), all threads; less sensitive to other load than wall time.\n"
          "reconstruct = pointscale.reconstruct(dec, base=base), base = dec.base taken once before the runs; Reconstructor = "
          "pointscale.Reconstructor(dec).reconstruct(base=base), called alternately with it (setup: building it, once); peak mem = VmHWM (peak RSS) "
          "minus RSS after loading, fresh subprocess per cloud.")
    if not have_ps:
        print("pointscale:", ps_why)
    if peer is None:
        print("PCL:", pcl_why)
    print("load average at end:", open("/proc/loadavg").read().split()[:3])
    for r in rows:
        for side in ("ps", "pcl"):
            if r.get(side + "_err"):
                print(f"{r['name']}: {'pointscale' if side == 'ps' else 'PCL'} failed: {r[side + '_err']}")
    v = verdicts(rows)
    if v:
        print()
        for line in v:
            print(" -", line)
    if args.json:
        args.json.write_text(json.dumps({"machine": machine_line(), "argv": sys.argv[1:],
                                         "rows": rows}, indent=1))
        print(f"\nraw results: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
