"""Peak memory of a decompose per input point, at several thread counts: measured, not asserted.

    python bench/memory_bench.py [--threads 1,2,4,8] [--data-dir ../shared/data]

Each cell is one decompose(points, levels=4) in a fresh process: the peak RSS (VmHWM, reset
once the points are loaded) minus the RSS after loading, over the number of points. The
inputs are bench/run.py's: the 1M bumpy sphere in Morton order and shuffled, and the dragon
and Buddha scans in file order; then the 1M sphere again with sheets=True (its normals
estimated by the call) and with levels=6 (whose model alone holds 36 bytes per point more
per band). More threads than cores still start one worker each, so a 2-core machine shows
what an 8-core one would hold. Target (issue 19): under 300 bytes per point at every thread
count.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import run  # noqa: E402  (bench/run.py: the inputs and the VmHWM helpers)


VARIANTS = {"": {}, "sheets": {"sheets": True}, "levels 6": {"levels": 6}}


def worker(source: str, order: str, threads: int, data_dir: Path, variant: str) -> None:
    import pointscale as ps

    if source.endswith(".ply"):
        points = run.in_order(run.read_ply_xyz(data_dir / source), "scan", order)
    else:
        points = run.in_order(run.bumpy_sphere(run.parse_size(source)), "synthetic", order)
    if not run.reset_peak_rss():
        raise SystemExit("this kernel does not let VmHWM be reset (/proc/self/clear_refs): no figure")
    before = run.vm_status_kib()["VmRSS"]
    ps.decompose(points, **{"levels": 4, **VARIANTS[variant]}, threads=threads)
    peak = run.vm_status_kib()["VmHWM"]
    print(json.dumps({"bytes_per_point": (peak - before) * 1024.0 / len(points)}))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--threads", default="1,2,4,8", help="thread counts (default 1,2,4,8)")
    p.add_argument("--data-dir", type=Path, default=run.DEFAULT_DATA)
    p.add_argument("--worker", nargs=4, metavar=("SOURCE", "ORDER", "THREADS", "VARIANT"), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        worker(args.worker[0], args.worker[1], int(args.worker[2]), args.data_dir, args.worker[3])
        return 0
    threads = [int(t) for t in args.threads.split(",")]
    inputs = [("1M", "coherent", ""), ("1M", "shuffled", "")]
    inputs += [(name, "coherent", "") for name in run.DATASETS if (args.data_dir / name).exists()]
    inputs += [("1M", "coherent", "sheets"), ("1M", "coherent", "levels 6")]
    print("decompose(points, levels=4): peak RSS per input point, bytes, one fresh process per cell")
    print(f"| input | order | option | " + " | ".join(f"{t} threads" for t in threads) + " |")
    print("|---|---|---|" + "---|" * len(threads))
    for source, order, variant in inputs:
        cells = []
        for t in threads:
            out = subprocess.run([sys.executable, __file__, "--data-dir", str(args.data_dir), "--worker", source, order,
                                  str(t), variant], capture_output=True, text=True, check=True)
            cells.append(f"{json.loads(out.stdout.strip().splitlines()[-1])['bytes_per_point']:.0f}")
        print(f"| {source} | {run.order_label('synthetic' if source[0].isdigit() else 'scan', order)} | "
              f"{variant or '-'} | " + " | ".join(cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
