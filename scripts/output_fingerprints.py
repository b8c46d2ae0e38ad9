#!/usr/bin/env python3
"""Fingerprints of every public operation's outputs, to check that a change leaves them bit for bit.

    python scripts/output_fingerprints.py --out before.json [--quick] [--data DIR] [--only CASE,...]
    (change the code, rebuild)
    python scripts/output_fingerprints.py --out after.json  [same options]
    python scripts/output_fingerprints.py --compare before.json after.json

--out runs every operation of the `pointscale` package on fixed inputs (the benchmark's clouds,
procedural shapes, the scans in ../shared/data when present) and writes, per output array, the
SHA-256 of its raw bytes with its dtype and shape. Non-array outputs (reports, counts, stats)
are recorded as canonical JSON. --compare lists the entries that differ or exist in one file
only and exits 1 if there are any, 0 when all match. --arrays DIR also keeps every array as .npy,
so that --compare can say by how much a float array moved (relative to its input's bounding-box
diagonal) and how many of its values changed.

Two runs of one build on one machine give the same fingerprints, at --threads 1 and 2 alike. The
CPU matters (the engine's SIMD clones round differently): compare runs made on one machine.
"""
from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import platform
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FORMAT = 1

sys.path.insert(0, str(REPO / "bench"))
# The benchmark's own inputs, so that "unchanged on the benchmark inputs" means these clouds.
from run import DEFAULT_DATA, bumpy_sphere, in_order, read_ply_xyz  # noqa: E402


def diagonal_of(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


class Recorder:
    """Collects the fingerprints (and, with --arrays, the arrays) of one run."""

    def __init__(self, arrays_dir: Path | None):
        self.entries: dict[str, dict] = {}
        self.inputs: dict[str, dict] = {}
        self.arrays_dir = arrays_dir
        self.prefix = ""

    def start_input(self, name: str, points: np.ndarray) -> None:
        """Entries added from now on belong to `name`; its diagonal scales --compare's differences."""
        self.prefix = name
        self.inputs[name] = {"points": int(len(points)), "diagonal": diagonal_of(points)}
        self.add("input", points)

    @contextlib.contextmanager
    def under(self, name: str):
        """Entries added inside are named name/...: one operation's outputs on a second model."""
        prefix = self.prefix
        self.prefix = f"{prefix}/{name}"
        try:
            yield
        finally:
            self.prefix = prefix

    def add(self, name: str, value) -> None:
        key = f"{self.prefix}/{name}"
        if key in self.entries:
            raise RuntimeError(f"entry {key} recorded twice")
        if isinstance(value, np.ndarray):
            a = np.ascontiguousarray(value)
            digest = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
            digest.update(a.view(np.uint8).reshape(-1) if a.size else b"")
            self.entries[key] = {"dtype": a.dtype.str, "shape": list(a.shape), "sha256": digest.hexdigest()}
            if self.arrays_dir is not None:
                path = self.arrays_dir / f"{key}.npy"
                path.parent.mkdir(parents=True, exist_ok=True)
                np.save(path, a)
        else:
            # Reports and counts: JSON keeps floats exactly (repr round-trips), and stays readable.
            text = json.dumps(value, sort_keys=True)
            self.entries[key] = {"json": text, "sha256": hashlib.sha256(text.encode()).hexdigest()}


# --------------------------------------------------------------------------- operations


def painted_gains(points: np.ndarray, bands: int) -> np.ndarray:
    """(bands, n) per-point gains that vary smoothly over the shape, as a painted mask does."""
    u = (points - points.mean(axis=0)) / diagonal_of(points)
    return np.stack([1.0 + 0.5 * np.sin(6.0 * u[:, 0] + l) for l in range(bands)])


def local_lift(base: np.ndarray) -> np.ndarray:
    """A brush-sized lift around the base's highest point: only part of the base moves."""
    diag = diagonal_of(base)
    top = base[np.argmax(base[:, 2])]
    out = base.copy()
    out[:, 2] += 0.05 * diag * np.exp(-((base - top) ** 2).sum(axis=1) / (0.2 * diag) ** 2)
    return out


def broad_wave(base: np.ndarray) -> np.ndarray:
    """bench/run.py's edit: a broad wave that moves every base point, so every point turns."""
    diag = diagonal_of(base)
    return base + (0.05 * diag) * np.sin(3.0 * base[:, [0]] / diag) * np.array([0.0, 0.0, 1.0])


def record_decomposition(rec: Recorder, name: str, dec) -> None:
    """Every array a Decomposition exposes, and every array it saves."""
    rec.add(f"{name}/base", dec.base)
    rec.add(f"{name}/details", dec.details)
    for l in range(dec.n_levels):
        rec.add(f"{name}/level_{l}", dec.level(l))
    for l in range(dec.n_bands):
        rec.add(f"{name}/normals_{l}", dec.normals(l))
    rec.add(f"{name}/stats", dec.stats)
    rec.add(f"{name}/parts", dec.parts)
    if dec.part_labels is not None:
        rec.add(f"{name}/part_labels", dec.part_labels)
    for key, array in sorted(dec.to_dict().items()):
        rec.add(f"{name}/to_dict/{key}", array)


def record_folds(rec: Recorder, name: str, folds) -> None:
    rec.add(f"{name}/kind", folds.kind)
    rec.add(f"{name}/before", folds.before)
    rec.add(f"{name}/limiter", folds.limiter)
    rec.add(f"{name}/summary", {"count": folds.count, "count_before": folds.count_before,
                                "rounds": folds.rounds, "capped": folds.capped})


def record_reconstructions(rec: Recorder, ps, dec, points: np.ndarray, fold_gains) -> None:
    """reconstruct and everything built on it, on `dec` (decomposed from `points`)."""
    k = dec.n_bands
    boost = np.ones(k)
    boost[-1] = 2.0  # the finest band doubled (Fig. 7)
    painted = painted_gains(points, k)
    lifted, wave = local_lift(dec.base), broad_wave(dec.base)
    rec.add("reconstruct/round_trip", ps.reconstruct(dec))
    rec.add("reconstruct/gains", ps.reconstruct(dec, boost))
    rec.add("reconstruct/painted", ps.reconstruct(dec, painted))
    rec.add("reconstruct/own_base", ps.reconstruct(dec, base=dec.base))  # the edited-base path, nothing turned
    rec.add("reconstruct/lift", ps.reconstruct(dec, base=lifted))
    rec.add("reconstruct/wave", ps.reconstruct(dec, base=wave))
    rec.add("reconstruct/lift_painted", ps.reconstruct(dec, painted, base=lifted))
    for mode in ("report", "prevent"):
        out, folds = ps.reconstruct(dec, fold_gains, folds=mode)
        rec.add(f"reconstruct/folds_{mode}/points", out)
        record_folds(rec, f"reconstruct/folds_{mode}", folds)
    if len(points) <= 200_000:
        # Up to 40 rounds over every fold of the input too: a minute on the Buddha scans, for a
        # path that the smaller inputs cover as well.
        out, folds = ps.reconstruct(dec, fold_gains, base=lifted, folds="prevent", fold_reference="base")
        rec.add("reconstruct/folds_prevent_lift_base_ref/points", out)
        record_folds(rec, "reconstruct/folds_prevent_lift_base_ref", folds)
    record_folds(rec, "find_folds/lift", ps.find_folds(dec, ps.reconstruct(dec, fold_gains, base=lifted),
                                                       base=lifted))
    solver = ps.Reconstructor(dec)
    rec.add("Reconstructor/gains", solver.reconstruct(boost))
    rec.add("Reconstructor/painted", solver.reconstruct(painted))
    rec.add("Reconstructor/lift", solver.reconstruct(base=lifted))
    rec.add("Reconstructor/wave_gains", solver.reconstruct(boost, base=wave))
    rec.add("reconstruct_levels/lift_gains", ps.reconstruct_levels(dec, boost, base=lifted))
    rec.add("blend/t_1.5", ps.blend(dec, 1.5))


def model_case(points_of, fold_gains=(2.0, 2.0, 1.0)):
    """A case that decomposes one cloud as bench/run.py does and runs every operation on the
    model, then estimate_normals and single-pass smoothing, which the benches time too."""
    def case(rec: Recorder, ps, threads: int, name: str) -> None:
        points = points_of()
        rec.start_input(name, points)
        dec = ps.decompose(points, levels=4, threads=threads)
        record_decomposition(rec, "decompose", dec)
        record_reconstructions(rec, ps, dec, points, fold_gains)
        rec.add("estimate_normals/oriented", ps.estimate_normals(points, threads=threads))
        rec.add("estimate_normals/unoriented", ps.estimate_normals(points, orient=False, threads=threads))
        smoothed, normals = ps.project(points, points, kernel=2.5, single_pass=True, threads=threads)
        rec.add("project_single_pass/points", smoothed)
        rec.add("project_single_pass/normals", normals)
    return case


def handles_case(rec: Recorder, ps, threads: int, name: str) -> None:
    """The paper's Fig. 5 plane with 16 handles, decomposed as the demo does, and its lift."""
    points, _, _ = ps.shapes.handles_plane()
    rec.start_input(name, points)
    dec = ps.decompose(points, levels=4, decimation=0.2, kernel=2.0, threads=threads)
    record_decomposition(rec, "decompose", dec)
    lifted = dec.base.copy()
    lifted[:, 2] += 0.8 * np.exp(-(lifted[:, :2] ** 2).sum(axis=1))
    rec.add("reconstruct/fig5_lift", ps.reconstruct(dec, base=lifted))
    record_reconstructions(rec, ps, dec, points, (1.0, 1.0, 3.0))


def operators_case(rec: Recorder, ps, threads: int, name: str) -> None:
    """The single-surface operators and the paper's further operators, on a small shape."""
    points = ps.shapes.bumpy_sphere(20_000, noise=0.002)
    rec.start_input(name, points)
    centroids, labels = ps.decimate(points, 5_000)
    rec.add("decimate/centroids", centroids)
    rec.add("decimate/labels", labels)
    for tag, kwargs in (("default", {}), ("near", {"near": labels}),
                        ("single_pass", {"kernel": 2.5, "single_pass": True})):
        pos, nrm, report = ps.project(points, centroids, threads=threads, return_report=True, **kwargs)
        rec.add(f"project/{tag}/points", pos)
        rec.add(f"project/{tag}/normals", nrm)
        rec.add(f"project/{tag}/report", report)
    rec.add("estimate_normals/oriented", ps.estimate_normals(points, threads=threads))
    rec.add("estimate_normals/unoriented", ps.estimate_normals(points, orient=False, threads=threads))
    rec.add("smooth_diffusion/laplacian", ps.smooth_diffusion(points, 10, threads=threads))
    rec.add("smooth_diffusion/taubin", ps.smooth_diffusion(points, 10, taubin=True, threads=threads))
    rec.add("diffusion_levels", ps.diffusion_levels(points, 3, threads=threads))
    rec.add("coarse_base_warning", ps.coarse_base_warning(4_000))
    hits, distances, missed = ps.shoot_rays(1.3 * points[::10], -points[::10], points, threads=threads)
    rec.add("shoot_rays/hits", hits)
    rec.add("shoot_rays/distances", distances)
    rec.add("shoot_rays/missed", missed)

    for tag, kwargs in (("diffusion", {"smoother": "diffusion"}), ("rayshoot", {"encoding": "rayshoot"}),
                        ("given_normals", {"normals": ps.estimate_normals(points, threads=threads)})):
        dec = ps.decompose(points, levels=3, threads=threads, **kwargs)
        record_decomposition(rec, f"decompose_{tag}", dec)
        rec.add(f"decompose_{tag}/reconstruct_lift", ps.reconstruct(dec, base=local_lift(dec.base)))
        if tag == "rayshoot":
            for l, missed_points in enumerate(ps.rays_missed_points(dec)):
                rec.add(f"decompose_{tag}/rays_missed_points_{l}", np.asarray(missed_points))

    ellipsoid = ps.ellipsoid_base(points, n=5_000)
    rec.add("ellipsoid_base", ellipsoid)
    dec = ps.encode(points, ellipsoid, threads=threads)
    record_decomposition(rec, "encode", dec)
    rec.add("encode/reconstruct_half", ps.reconstruct(dec, [0.5]))

    other = ps.shapes.bumpy_sphere(15_000, coarse=0.05, coarse_frequency=4.0, fine=0.02, fine_frequency=12.0)
    moved = 1.5 * other[:, [1, 2, 0]] + 0.2  # turned, scaled and shifted: alignment has work to do
    for tag, b, kwargs in (("common_base", other, {"base_points": ps.ellipsoid_base(points, other, n=5_000)}),
                           ("align_pca", moved, {"align": "pca", "base_samples": 5_000}),
                           ("align_icp", moved, {"align": "icp", "base_samples": 5_000})):
        m = ps.morph(points, b, threads=threads, **kwargs)
        for key in ("base", "normals", "detail_a", "detail_b"):
            rec.add(f"morph_{tag}/{key}", getattr(m, key))
        rec.add(f"morph_{tag}/report", m.report)
        rec.add(f"morph_{tag}/evaluate_0.5_0.5", m.evaluate(0.5, 0.5))
        rec.add(f"morph_{tag}/evaluate_0_1", m.evaluate(0.0, 1.0))


def sheets_case(rec: Recorder, ps, threads: int, name: str) -> None:
    """Thin sheets kept apart (a bent two-sided plate), and a decomposition saved and loaded."""
    plate, plate_normals, _ = ps.shapes.thin_plate(bend=0.3)
    rec.start_input(name, plate)
    dec = ps.decompose(plate, levels=4, normals=plate_normals, sheets=True, threads=threads)
    record_decomposition(rec, "decompose", dec)
    rec.add("reconstruct/lift", ps.reconstruct(dec, base=local_lift(dec.base)))
    pos, nrm = ps.project_sheets(plate, plate, onto_normals=plate_normals, threads=threads)
    rec.add("project_sheets/points", pos)
    rec.add("project_sheets/normals", nrm)
    path = Path(os.environ.get("TMPDIR", "/tmp")) / f"output_fingerprints_{os.getpid()}.npz"
    try:
        dec.save(path)
        loaded = ps.load(path)
    finally:
        path.unlink(missing_ok=True)
    record_decomposition(rec, "load", loaded)
    rec.add("load/reconstruct_lift", ps.reconstruct(loaded, base=local_lift(loaded.base)))


def parts_case(rec: Recorder, ps, threads: int, name: str) -> None:
    """A bumpy sphere with a small box beside it (tests/test_parts.py's first scene): two
    connected parts, decomposed and encoded each alone."""
    sphere, sphere_faces = ps.meshes.uv_sphere(1.0, 128, 64)
    box, box_faces = ps.meshes.box(0.3, 16)
    vertices, faces, _ = ps.meshes.joined((ps.meshes.bumpy(sphere, 0.01, 12), sphere_faces),
                                          (box + [1.2, 0.0, 0.0], ps.meshes.quads_to_triangles(box_faces)))
    rec.start_input(name, vertices)
    labels, count = ps.parts.connected_parts(vertices, faces)
    rec.add("connected_parts/labels", labels)
    rec.add("connected_parts/count", int(count))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the box is meant to keep fewer levels: that path is fingerprinted
        dec = ps.decompose(vertices, levels=4, faces=faces, threads=threads)
    record_decomposition(rec, "decompose", dec)
    rec.add("reconstruct/lift", ps.reconstruct(dec, base=local_lift(dec.base)))
    rec.add("reconstruct/gains", ps.reconstruct(dec, [1.0, 1.0, 2.0]))
    dec = ps.encode(vertices, ps.ellipsoid_base(vertices, n=5_000), faces=faces, threads=threads)
    record_decomposition(rec, "encode", dec)


def mirror_case(rec: Recorder, ps, threads: int, name: str) -> None:
    """The x >= 0 half of a bumpy UV sphere, decomposed with its mirror: every output goes
    through the symmetrising path."""
    sphere = ps.meshes.bumpy(ps.meshes.uv_sphere(1.0, 128, 64)[0], 0.08, 5.0)
    sphere[np.abs(sphere[:, 0]) < 1e-12, 0] = 0.0  # cos(pi / 2) is 6e-17: put the seam on the plane
    half = sphere[sphere[:, 0] >= 0.0]
    rec.start_input(name, half)
    dec = ps.decompose(half, levels=3, mirror=ps.Mirror("x"), threads=threads)
    record_decomposition(rec, "decompose", dec)
    record_reconstructions(rec, ps, dec, half, (8.0, 8.0))  # the least gains at which this half folds


def cases(quick: bool, data: Path) -> list[tuple[str, object]]:
    """(name, case) in the order they run; a scan that is absent is skipped with a note."""
    sizes = (100_000,) if quick else (100_000, 1_000_000)
    orders = ("coherent",) if quick else ("coherent", "shuffled")
    out = []
    for n in sizes:
        for order in orders:
            label = f"sphere_{n // 1000}k_{'morton' if order == 'coherent' else order}"
            out.append((label, model_case(lambda n=n, order=order: in_order(bumpy_sphere(n), "synthetic", order))))
    out += [("handles", handles_case), ("operators", operators_case), ("sheets", sheets_case),
            ("parts", parts_case), ("mirror", mirror_case)]
    # bench/folds_bench.py's gains: Max Planck folds at (2, 2, 1), the dragon at (1, 1, 3).
    scans = [("max_planck.ply", (2.0, 2.0, 1.0))]
    if not quick:
        scans += [("bunny.ply", (2.0, 2.0, 1.0)), ("dragon.ply", (1.0, 1.0, 3.0)),
                  ("happy_buddha_scans.ply", (1.0, 1.0, 3.0))]
    for file, gains in scans:
        path = data / file
        if path.exists():
            out.append((path.stem, model_case(lambda path=path: read_ply_xyz(path), fold_gains=gains)))
        else:
            print(f"note: {path} not found, its case is skipped")
    return out


# --------------------------------------------------------------------------- run and compare


def machine() -> dict:
    """What the results depend on beyond the code: the CPU's SIMD level picks the engine's clone."""
    flags = set()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
                break
    except OSError:
        pass
    return {"machine": platform.machine(), "simd": sorted(flags & {"avx512f", "avx2", "fma"})}


def package_commit(path: Path) -> str:
    try:
        head = subprocess.run(["git", "-C", str(path), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(path), "status", "--porcelain"], capture_output=True,
                               text=True, check=True).stdout.strip()
        return head + ("+changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def run(args) -> int:
    import pointscale as ps
    arrays_dir = Path(args.arrays).resolve() if args.arrays else None
    rec = Recorder(arrays_dir)
    chosen = cases(args.quick, Path(args.data))
    if args.only:
        wanted = set(args.only.split(","))
        unknown = wanted - {name for name, _ in chosen}
        if unknown:
            print(f"unknown case(s) {', '.join(sorted(unknown))}; cases: {', '.join(n for n, _ in chosen)}")
            return 2
        chosen = [(name, case) for name, case in chosen if name in wanted]
    start = time.perf_counter()
    for name, case in chosen:
        t = time.perf_counter()
        case(rec, ps, args.threads, name)
        print(f"{name}: {sum(k.startswith(name + '/') for k in rec.entries)} entries, {time.perf_counter() - t:.1f} s",
              flush=True)
    package = Path(ps.__file__).resolve().parent
    meta = {"format": FORMAT, "pointscale": ps.__version__, "package": str(package),
            "commit": package_commit(package), "numpy": np.__version__, "python": platform.python_version(),
            "threads": args.threads, "quick": args.quick, "cases": [name for name, _ in chosen],
            "arrays": str(arrays_dir) if arrays_dir else None, **machine()}
    Path(args.out).write_text(json.dumps({"meta": meta, "inputs": rec.inputs, "entries": rec.entries}, indent=1)
                              + "\n")
    print(f"wrote {len(rec.entries)} fingerprints to {args.out} in {time.perf_counter() - start:.0f} s")
    return 0


def difference(a_run: dict, b_run: dict, key: str) -> str:
    """How far the arrays of `key` differ, when both runs kept them (--arrays)."""
    dirs = [r["meta"].get("arrays") for r in (a_run, b_run)]
    paths = [Path(d) / f"{key}.npy" for d in dirs if d]
    if len(paths) < 2 or not all(p.exists() for p in paths):
        return "(run both with --arrays DIR to see by how much)"
    a, b = (np.load(p) for p in paths)
    if a.shape != b.shape:
        return f"shape {a.shape} against {b.shape}"
    changed = int(np.count_nonzero(a != b))
    text = f"{changed} of {a.size} values"
    if a.dtype.kind == "f" and b.dtype.kind == "f" and changed:
        diag = a_run["inputs"].get(key.split("/")[0], {}).get("diagonal", 0.0)
        largest = float(np.max(np.abs(a.astype(np.float64) - b.astype(np.float64))))
        text += f", largest difference {largest:.3g}" + (f" = {largest / diag:.3g} of the diagonal" if diag else "")
    return text


def compare(path_a: str, path_b: str) -> int:
    a_run, b_run = (json.loads(Path(p).read_text()) for p in (path_a, path_b))
    for what in ("threads", "quick", "machine", "simd", "numpy"):
        if a_run["meta"].get(what) != b_run["meta"].get(what):
            print(f"note: the runs differ in {what}: {a_run['meta'].get(what)} against {b_run['meta'].get(what)}")
    a, b = a_run["entries"], b_run["entries"]
    differ = [key for key in a if key in b and a[key] != b[key]]
    for key in differ:
        if "json" in a[key] or "json" in b[key]:
            print(f"differs: {key}: {a[key].get('json', a[key].get('shape'))} against "
                  f"{b[key].get('json', b[key].get('shape'))}")
        else:
            print(f"differs: {key} ({a[key]['dtype']} {a[key]['shape']}): {difference(a_run, b_run, key)}")
    only = [(key, path_a) for key in a if key not in b] + [(key, path_b) for key in b if key not in a]
    for key, where in only:
        print(f"only in {where}: {key}")
    same = len(a) - len(differ) - sum(where == path_a for _, where in only)
    print(f"{same} entries identical, {len(differ)} differ, {len(only)} in one file only")
    return 1 if differ or only else 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--out", metavar="FILE.json", help="compute the fingerprints and write them here")
    mode.add_argument("--compare", nargs=2, metavar=("A.json", "B.json"), help="list the entries that differ")
    parser.add_argument("--quick", action="store_true", help="of the large inputs only the 100k sphere in "
                                                             "Morton order and Max Planck (seconds, not minutes)")
    parser.add_argument("--data", default=str(DEFAULT_DATA), help="the scans' folder (default ../shared/data)")
    parser.add_argument("--only", metavar="CASE,...", help="run only these cases (names as the run prints them)")
    parser.add_argument("--threads", type=int, default=2, help="threads for every call (default 2)")
    parser.add_argument("--arrays", metavar="DIR", help="also keep every array as DIR/<entry>.npy, for --compare's "
                                                        "sizes of differences (about 4 GB for the full run)")
    args = parser.parse_args(argv)
    return compare(*args.compare) if args.compare else run(args)


if __name__ == "__main__":
    sys.exit(main())
