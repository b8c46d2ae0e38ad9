"""Renders the whole paper gallery into docs/gallery/ (or --out), one figure at a time.

    python examples/render_all.py            # default quality, about 800 px wide
    python examples/render_all.py --quick    # tiny images, few samples (what the test runs)
    python examples/render_all.py --only fig05_handles fig07_spectral_filter

Each figure runs as its own process (a fresh Blender scene and memory) and prints one progress
line; its numbers go to <name>.json next to its PNG. Figures whose model is missing from
../shared/data (or $POINTSCALE_DATA) are reported as skipped. Exit status 1 if any figure failed.
"""
import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
FIGURES = [
    "fig02_detail_colors",
    "fig03_blend",
    "fig05_handles",
    "fig06_emboss",
    "fig07_spectral_filter",
    "fig08_ellipsoid",
    "fig09_morph",
    "fig10a_blend",
    "fig10b_paint",
    "buddha_scans",
]
SKIPPED = 3  # exit status of a figure whose model is absent


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    p.add_argument("--quick", action="store_true", help="tiny images at low sample counts")
    p.add_argument("--out", type=Path, default=HERE.parent / "docs" / "gallery")
    p.add_argument("--only", nargs="*", default=None, help="figure names to render (default: all)")
    p.add_argument("--timeout", type=float, default=600.0, help="seconds allowed per figure")
    p.add_argument("--verbose", action="store_true", help="show each figure's own output")
    args = p.parse_args(argv)
    names = args.only or FIGURES
    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        p.error(f"unknown figures {unknown}; choose from {FIGURES}")
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    results = {}
    for i, name in enumerate(names, 1):
        t = time.perf_counter()
        cmd = [sys.executable, str(HERE / f"{name}.py"), "--out", str(args.out)] + (["--quick"] if args.quick else [])
        try:
            run = subprocess.run(cmd, cwd=HERE, capture_output=True, text=True, timeout=args.timeout)
            code, out, err = run.returncode, run.stdout, run.stderr
        except subprocess.TimeoutExpired as exc:
            code, out, err = "timeout", exc.stdout or "", exc.stderr or ""
            out = out.decode() if isinstance(out, bytes) else out
            err = err.decode() if isinstance(err, bytes) else err
        seconds = time.perf_counter() - t
        if code == 0:
            status = "ok"
            png = args.out / f"{name}.png"
            detail = f"{png.name} {png.stat().st_size / 1024:.0f} KB"
        elif code == SKIPPED:
            status, detail = "skipped", out.strip().splitlines()[-1] if out.strip() else "model absent"
        else:
            status, detail = "FAILED", f"exit {code}"
        results[name] = {"status": status, "seconds": round(seconds, 1)}
        print(f"[{i}/{len(names)}] {name:24s} {status:7s} {seconds:6.1f} s  {detail}", flush=True)
        if args.verbose or status == "FAILED":
            print(_figure_output(out), flush=True)
            if status == "FAILED":
                print(err[-4000:], flush=True)
    total = time.perf_counter() - start
    print(f"gallery: {sum(r['status'] == 'ok' for r in results.values())} rendered, "
          f"{sum(r['status'] == 'skipped' for r in results.values())} skipped, "
          f"{sum(r['status'] == 'FAILED' for r in results.values())} failed in {total:.1f} s -> {args.out}", flush=True)
    (args.out / "render_all.json").write_text(json.dumps({"quick": args.quick, "total_seconds": round(total, 1),
                                                          "figures": results}, indent=1) + "\n")
    return 1 if any(r["status"] == "FAILED" for r in results.values()) else 0


def _figure_output(out: str) -> str:
    keep = [l for l in out.splitlines() if l.startswith("  ") or l.endswith("numbers:") or l.startswith("SKIP")]
    return "\n".join(keep)


if __name__ == "__main__":
    sys.exit(main())
