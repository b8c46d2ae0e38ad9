"""Command line: pointscale decompose | reconstruct | info | demo."""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from . import Cancelled, decompose, load, reconstruct, shapes
from .io import read_ply, write_ply

DECOMPOSITION_FILE = "decomposition.npz"
FACES_FILE = "faces.npy"


def _progress_printer(label: str):
    last = [-1]

    def report(fraction: float) -> bool:
        percent = int(fraction * 100)
        if percent != last[0] and sys.stderr.isatty():
            print(f"\r{label}: {percent:3d}%", end="", file=sys.stderr, flush=True)
            last[0] = percent
        return True

    return report


def _parse_gains(text: str, bands: int) -> np.ndarray:
    try:
        gains = np.array([float(g) for g in text.split(",")])
    except ValueError:
        raise ValueError(f"--gains must be comma-separated numbers, got {text!r}") from None
    if len(gains) != bands:
        raise ValueError(f"--gains needs {bands} values (one per band), got {len(gains)}")
    return gains


def _describe(dec) -> str:
    lines = [f"{dec.n_points} points, {dec.n_levels} levels (P^0..P^{dec.n_bands}), {dec.n_bands} detail bands"]
    for l, s in enumerate(dec.stats):
        rms = float(np.sqrt(np.mean(dec.details[l] ** 2)))
        lines.append(f"  band {l}: support {s['support_points']} points, kernel width {s['kernel_width']:.4g}, "
                     f"detail rms {rms:.4g}, not converged {s['not_converged']}, pinned {s['pinned']}")
    return "\n".join(lines)


def _write_levels(dec, out: Path, faces) -> None:
    for l in range(dec.n_levels):
        normals = dec.normals(l) if l < dec.n_bands else None
        scalars = {"detail": dec.details[l]} if l < dec.n_bands else None
        write_ply(out / f"level_{l}.ply", dec.level(l), normals=normals, faces=faces, scalars=scalars)


def cmd_decompose(args) -> None:
    model = read_ply(args.input)
    start = time.perf_counter()
    dec = decompose(model.points, levels=args.levels, decimation=args.decimation, kernel=args.kernel,
                    neighbors=args.neighbors, normals=model.normals, threads=args.threads,
                    progress=_progress_printer("decompose"))
    elapsed = time.perf_counter() - start
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    dec.save(out / DECOMPOSITION_FILE)
    if model.faces is not None:
        np.save(out / FACES_FILE, np.asarray(model.faces, dtype=object), allow_pickle=True)
    _write_levels(dec, out, model.faces)
    print(f"\ndecomposed {args.input} in {elapsed:.2f} s")
    print(_describe(dec))
    print(f"wrote {out / DECOMPOSITION_FILE} and level_0.ply .. level_{dec.n_bands}.ply")


def _load_dir(path: str):
    p = Path(path)
    file = p / DECOMPOSITION_FILE if p.is_dir() else p
    dec = load(file)
    faces_file = file.parent / FACES_FILE
    faces = list(np.load(faces_file, allow_pickle=True)) if faces_file.exists() else None
    return dec, faces


def cmd_reconstruct(args) -> None:
    dec, faces = _load_dir(args.decomposition)
    gains = _parse_gains(args.gains, dec.n_bands) if args.gains else None
    base = read_ply(args.base).points if args.base else None
    out = reconstruct(dec, gains=gains, base=base)
    write_ply(args.output, out, faces=faces)
    print(f"wrote {args.output} ({dec.n_points} points, gains {args.gains or 'all 1'}"
          f"{', edited base ' + args.base if args.base else ''})")


def cmd_info(args) -> None:
    dec, _ = _load_dir(args.decomposition)
    print(_describe(dec))
    print("settings:", dec.settings)


def cmd_demo(args) -> None:
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    print("Pointscale demo: a bumpy sphere with a coarse and a fine pattern plus scanner-like noise")
    points = shapes.bumpy_sphere(args.points, coarse=0.08, fine=0.012, fine_frequency=28.0, noise=0.002)
    start = time.perf_counter()
    dec = decompose(points, levels=4, progress=_progress_printer("decompose"))
    print(f"\ndecomposed {len(points)} points in {time.perf_counter() - start:.2f} s")
    print(_describe(dec))
    _write_levels(dec, out, None)
    error = np.abs(reconstruct(dec) - points).max() / np.linalg.norm(np.ptp(points, axis=0))
    print(f"exact reconstruction: max error {error:.2e} of the bounding-box diagonal")
    for gains in ((1, 1, 0), (1, 1, 2), (0, 0, 1)):
        name = "filtered_" + "_".join(str(g) for g in gains) + ".ply"
        write_ply(out / name, reconstruct(dec, gains=gains))
        print(f"band filter {gains}: wrote {out / name}")

    print("\nMultiscale deformation (paper Fig. 5): a plane with 16 box handles, base lifted by a bump")
    plane, handle, centres = shapes.handles_plane()
    dp = decompose(plane, levels=4, decimation=0.2, kernel=2.0)
    lifted = dp.base.copy()
    lifted[:, 2] += 0.8 * np.exp(-(lifted[:, :2] ** 2).sum(axis=1))
    multi = reconstruct(dp, base=lifted)
    single = plane.copy()
    single[:, 2] += 0.8 * np.exp(-(plane[:, :2] ** 2).sum(axis=1))
    write_ply(out / "handles_original.ply", plane)
    write_ply(out / "handles_multiscale.ply", multi)
    write_ply(out / "handles_single_scale.ply", single)
    print(f"wrote {out}/handles_original.ply, handles_multiscale.ply, handles_single_scale.ply")
    print(f"all files are in {out.resolve()}")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pointscale", description="Multiscale point-sampled surfaces (Pauly, Kobbelt, Gross 2006).")
    sub = parser.add_subparsers(dest="command", required=True)

    d = sub.add_parser("decompose", help="split a PLY model into a smooth base and detail bands")
    d.add_argument("input")
    d.add_argument("-o", "--output", required=True, help="output folder")
    d.add_argument("--levels", type=int, default=4, help="point clouds P^0..P^k (bands = levels - 1)")
    d.add_argument("--decimation", type=float, default=0.25)
    d.add_argument("--kernel", type=float, default=1.0)
    d.add_argument("--neighbors", type=int, default=24)
    d.add_argument("--threads", type=int, default=0)
    d.set_defaults(func=cmd_decompose)

    r = sub.add_parser("reconstruct", help="rebuild a model from a decomposition, with band gains")
    r.add_argument("decomposition", help="folder written by decompose (or its .npz)")
    r.add_argument("--gains", help="comma-separated gain per band, e.g. 2,2,1")
    r.add_argument("--base", help="PLY with an edited level 0 (same vertex count)")
    r.add_argument("-o", "--output", required=True)
    r.set_defaults(func=cmd_reconstruct)

    i = sub.add_parser("info", help="describe a decomposition")
    i.add_argument("decomposition")
    i.set_defaults(func=cmd_info)

    m = sub.add_parser("demo", help="run the whole pipeline on procedural shapes (no download)")
    m.add_argument("-o", "--output", default="pointscale-demo")
    m.add_argument("--points", type=int, default=100000)
    m.set_defaults(func=cmd_demo)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.func(args)
    except (ValueError, Cancelled) as exc:
        print(f"pointscale: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
