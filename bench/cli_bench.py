"""The whole `pointscale decompose` command against the engine's own decompose, on real scans.

    python bench/cli_bench.py [--reps 3] [--data-dir ../shared/data] [--files dragon.ply,happy_buddha_scans.ply]

For each scan, in its file order: (a) the engine alone, `pointscale.decompose(points, levels=4)`
timed in a fresh process after the file is read; (b) the command `pointscale decompose FILE -o
DIR --force`, wall time from process start to exit (interpreter start, reading, decomposing, the
levels' normals, writing decomposition.npz, source.npz and every level file). Medians of --reps
runs, alternating (a) and (b). The target: (b) / (a) <= 1.5. Nothing here is asserted.
"""
from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DEFAULT_DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
ENGINE = """
import json, sys, time
import pointscale as ps
scan = ps.io.read(sys.argv[1])
start = time.perf_counter()
ps.decompose(scan.points, levels=4, normals=scan.normals)
print(json.dumps({"seconds": time.perf_counter() - start, "points": scan.n_points}))
"""


def engine_seconds(path: Path) -> tuple[float, int]:
    done = subprocess.run([sys.executable, "-c", ENGINE, str(path)], capture_output=True, text=True, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    return result["seconds"], result["points"]


def command_seconds(path: Path, out: Path) -> tuple[float, float]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "pointscale", "decompose", str(path), "-o", str(out), "--force"],
                          capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(done.stderr)
    inside = float(re.search(r"decomposed .* in ([0-9.]+) s", done.stdout).group(1))
    return wall, inside


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reps", type=int, default=3, help="runs of each, median reported (default 3)")
    parser.add_argument("--data-dir", type=Path, default=DEFAULT_DATA, help="folder of the scans")
    parser.add_argument("--files", default="dragon.ply,happy_buddha_scans.ply", help="comma-separated scan files")
    args = parser.parse_args(argv)
    print(f"{'scan':<26} {'points':>9} {'engine s':>9} {'command s':>10} {'in command':>11} {'ratio':>6}")
    for name in args.files.split(","):
        path = args.data_dir / name
        if not path.exists():
            print(f"{name:<26} skipped: not found in {args.data_dir}")
            continue
        engine, command, inside = [], [], []
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(args.reps):
                seconds, n = engine_seconds(path)
                engine.append(seconds)
                wall, decompose_part = command_seconds(path, Path(tmp) / "out")
                command.append(wall)
                inside.append(decompose_part)
        e, c, i = (statistics.median(v) for v in (engine, command, inside))
        print(f"{name:<26} {n:>9} {e:>9.2f} {c:>10.2f} {i:>11.2f} {c / e:>6.2f}")
    print("engine: decompose alone after reading; command: the whole process; in command: its decompose call")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
