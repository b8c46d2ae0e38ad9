"""The commands: decompose, reconstruct, info, demo."""
from __future__ import annotations

import sys
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .. import Mirror, decompose, io, reconstruct, shapes
from .folder import (DECOMPOSITION_FILE, LEVEL_EXTENSIONS, SOURCE_FILE, TEXT_CLOUD_EXTENSIONS, folder_signature,
                     level_extension, level_name, read_decomposition, source_identifier)
from .level_files import (FORMATS_WITH_VERTEX_SCALARS, ResultOverflow, finest_normals, level_scan,
                          reconstruct_with_normals)
from .output_checks import (check_format_holds, check_input_kept, check_output_file, check_output_folder, read_base,
                            require_writable_folder, writable_extension)
from .progress import CommandProgress
from .staged_output import StagedOutput


def normals_to_use(scan, args):
    """The file's normals for decompose, or None to estimate them: when asked, or when every one
    is zero, as some exporters write for a scan without normals (said on stderr)."""
    if scan.normals is None or args.estimate_normals:
        return None
    if not np.any(scan.normals):
        print(f"{args.input}: every normal in the file is zero; decomposing with estimated normals",
              file=sys.stderr)
        return None
    return scan.normals


def normals_for_sheets(scan, args, used_normals):
    """The normals decompose takes: with --sheets on a mesh file without them, and --parts none
    (which passes no faces), those of the faces' winding, as decompose takes them from the faces
    it is given (sheets.winding_normals); a warning says when the faces cannot give them."""
    if not args.sheets or used_normals is not None or not scan.n_faces or args.parts != "none":
        return used_normals
    from ..sheets import winding_normals
    normals, why_not = winding_normals(scan.points, scan.faces)
    if why_not:
        warnings.warn(why_not, stacklevel=2)
    return normals


def input_where_rebuilt(finest: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The finest level as written: the input's own coordinates, bit for bit, wherever the model
    rebuilds them to rounding (a few units in the last place: a technician who compares the file
    with the scan finds no point changed), the model's elsewhere (a mirrored half's seam snapped
    onto its plane, ray shooting's resampled surface)."""
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    same = np.abs(finest - points).max(axis=1) <= 1e-9 * diagonal
    out = finest.copy()
    out[same] = points[same]
    return out


def parse_gains(text: str, bands: int) -> np.ndarray:
    try:
        gains = np.array([float(g) for g in text.split(",")])
    except ValueError:
        raise ValueError(f"--gains must be comma-separated numbers, got {text!r}") from None
    if len(gains) != bands:
        raise ValueError(f"--gains needs {bands} values (one per band), got {len(gains)}")
    if not np.isfinite(gains).all():
        raise ValueError(f"--gains must be finite numbers, got {text!r}")
    return gains


def mirror_option(args):
    """--mirror, --mirror-origin and --mirror-seam as a pointscale.Mirror, or None."""
    if args.mirror is None:
        if args.mirror_origin is not None or args.mirror_seam is not None:
            raise ValueError("--mirror-origin and --mirror-seam need --mirror (the axes, e.g. --mirror x)")
        return None
    try:
        origin = [float(v) for v in (args.mirror_origin if args.mirror_origin is not None else "0,0,0").split(",")]
    except ValueError:
        raise ValueError(f"--mirror-origin must be three comma-separated numbers, got {args.mirror_origin!r}") from None
    try:
        return Mirror(args.mirror, origin, args.mirror_seam)
    except ValueError as exc:
        raise ValueError(f"--mirror: {exc}") from None


def describe(dec, source=None) -> str:
    lines = [f"{dec.n_points} points, {dec.n_levels} levels (P^0..P^{dec.n_bands}), {dec.n_bands} detail bands"]
    for l, s in enumerate(dec.stats):
        rms = float(np.sqrt(np.mean(dec.details[l] ** 2)))
        lines.append(f"  band {l}: support {s['support_points']} points, kernel width {s['kernel_width']:.4g}, "
                     f"detail rms {rms:.4g}, not converged {s['not_converged']}, pinned {s['pinned']}")
    if dec.parts:
        short = sum(1 for part in dec.parts if part["levels"] < dec.n_levels)
        lines.append(f"  {len(dec.parts)} connected parts, decomposed apart"
                     + (f"; {short} keep fewer levels (see the warning)" if short else ""))
    if dec.mirror is not None:
        origin = ", ".join(f"{v:.10g}" for v in dec.mirror.origin)
        lines.append(f"  mirror symmetric about {dec.mirror.axes} through ({origin}), seam {dec.mirror.seam:.3g}")
    if source is not None:
        lines.append("source: " + describe_source(source))
    return "\n".join(lines)


def describe_source(scan) -> str:
    kind = scan.format_info.get("format", "?")
    parts = [f"{kind}, {scan.n_points} vertices", f"coordinates {np.dtype(scan.precision).name}"]
    if scan.n_faces:
        parts.append(f"{scan.n_faces} faces")
    if scan.vertex_attributes:
        parts.append("vertex attributes " + ", ".join(scan.vertex_attributes))
    if scan.face_attributes:
        parts.append("face attributes " + ", ".join(scan.face_attributes))
    return "; ".join(parts)


class _Writers:
    """Runs writers (callables) on two threads, so the formats' encoders, the disk and the main
    thread's remaining computing overlap. Ctrl-C or an error cancels the writes not yet started;
    the caller's StagedOutput then discards the files."""

    def __init__(self, progress: CommandProgress, stage: str, expected: int):
        self._pool = ThreadPoolExecutor(max_workers=2)
        self._futures = []
        self._progress, self._stage, self._expected = progress, stage, expected

    def submit(self, task, temporary: Path, final: Path) -> None:
        """Runs task(), which writes `temporary`; its errors name `final`, the file the user asked for."""
        def run():
            try:
                task()
            except ValueError as exc:
                raise ValueError(str(exc).replace(str(temporary), str(final))) from None
            except OSError as exc:  # a full disk while NumPy writes an .npz: its words name no file
                raise ValueError(f"cannot write {final}: {exc.strerror or exc}") from None
        self._futures.append(self._pool.submit(run))

    def wait(self) -> None:
        report = self._progress.stage(self._stage)
        for done, future in enumerate(self._futures, 1):
            future.result()
            report(done / self._expected)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        # The running writes must end before the caller discards their files; a second Ctrl-C
        # while they finish must not cut this wait short.
        while True:
            try:
                self._pool.shutdown(wait=True, cancel_futures=True)
                break
            except KeyboardInterrupt:
                continue
        return False


def cmd_decompose(args) -> None:
    out = Path(args.output)
    if args.format:
        named = "level" + "." * (not args.format.startswith(".")) + args.format
        if Path(named).suffix.lower() in TEXT_CLOUD_EXTENSIONS:
            raise ValueError(f"--format {args.format}: level files are never {Path(named).suffix.lower()} (a file of "
                             f"that name beside them may be anyone's); a text cloud's levels are .xyz, the same columns")
        extension = writable_extension(named, "--format", shown=args.format, supported=LEVEL_EXTENSIONS)
    else:
        extension = level_extension(writable_extension(args.input, "input"))
    check_input_kept(Path(args.input), out)  # first: --force would not help
    earlier = check_output_folder(out, args.force)
    signature = folder_signature(out)
    stages = {"reading": 1.0, "decomposing": 5.0, "levels": 0.6, "writing": 1.6}
    with CommandProgress(stages) as progress, StagedOutput() as staged:
        progress.stage("reading")
        scan = io.read(args.input)
        check_format_holds(extension, scan, args.input, shown=out / level_name(0, extension))
        if extension not in FORMATS_WITH_VERTEX_SCALARS:
            warnings.warn(f"{extension} has no room for a vertex scalar: the level files leave out each band's detail, "
                          f"which {DECOMPOSITION_FILE} holds (.ply, .las, .laz and .xyz level files carry it)",
                          stacklevel=1)
        if extension == ".stl" and Path(args.input).suffix.lower() != ".stl":  # an STL input's own order comes back
            warnings.warn(".stl stores triangle corners, and reading it merges and renumbers the vertices, so an STL "
                          "level 0 cannot come back as reconstruct --base: to edit the base, write the levels with "
                          "--format .ply", stacklevel=1)
        start = time.perf_counter()
        used_normals = normals_to_use(scan, args)
        try:
            dec = decompose(scan.points, levels=args.levels, decimation=args.decimation, kernel=args.kernel,
                            neighbors=args.neighbors, normals=normals_for_sheets(scan, args, used_normals),
                            smoother=args.smoother,
                            encoding=args.encoding, threads=args.threads, progress=progress.stage("decomposing"),
                            faces=scan.faces if args.parts == "faces" and scan.n_faces else None,
                            sheets=args.sheets, mirror=mirror_option(args))
        except ValueError as exc:
            if str(exc).startswith("normals:") and "zero" in str(exc):
                raise ValueError(f"{args.input}: {exc} (on the command line, --estimate-normals)") from None
            if str(exc).startswith(("points", "normals", "all points", "sheets")):  # about the file's data: name it
                raise ValueError(f"{args.input}: {exc}") from None
            if str(exc).startswith("every connected part"):
                raise ValueError(f"{args.input}: {exc}; on the command line, --parts none") from None
            raise
        elapsed = time.perf_counter() - start
        progress.stage("levels")
        k = dec.n_bands
        levels = [dec.level(l) for l in range(k + 1)]
        levels[k] = input_where_rebuilt(levels[k], scan.points)
        normals = [dec.normals(l) for l in range(k)]

        staged.make_dir(out)
        with _Writers(progress, "writing", expected=k + 3) as writers:
            model_tmp = staged.temporary(out / DECOMPOSITION_FILE)
            source_tmp = staged.temporary(out / SOURCE_FILE)
            # The source keeps the file's normals where the decomposition used them (not where
            # they were all zero or --estimate-normals set them aside).
            source = scan if used_normals is not None else scan.with_geometry(scan.points, None)
            # Both files name the same source, so that reconstruct tells a source.npz of another
            # decomposition (of another input, or other normals) from this one's.
            source_id = source_identifier(scan.points, source.to_arrays())
            dec.settings["source_id"] = source_id
            writers.submit(lambda: np.savez(model_tmp, **dec.to_dict()), model_tmp, out / DECOMPOSITION_FILE)
            writers.submit(lambda: np.savez(source_tmp, **source.to_arrays(source_id)), source_tmp, out / SOURCE_FILE)
            level_files = [out / level_name(l, extension) for l in range(k + 1)]
            level_tmp = [staged.temporary(f) for f in level_files]
            for l in range(k):
                writers.submit(lambda l=l: io.write(level_tmp[l], level_scan(scan, levels[l], normals[l],
                                                                             dec.details[l], extension)),
                               level_tmp[l], level_files[l])
            # The finest level is the input: it carries the file's own normals where the
            # decomposition used them. Otherwise they are computed while the other files are written.
            normals.append(used_normals if used_normals is not None else finest_normals(levels[k], normals[k - 1],
                                                                                         args.threads))
            writers.submit(lambda: io.write(level_tmp[k], level_scan(scan, levels[k], normals[k], None, extension)),
                           level_tmp[k], level_files[k])
            writers.wait()
        written = {out / DECOMPOSITION_FILE, out / SOURCE_FILE, *level_files}
        if folder_signature(out) != signature:
            raise ValueError(f"another command wrote a decomposition into {out} while this one ran; this run's files "
                             "were not put in place (run it again to replace that one, with --force)")
        staged.commit(remove_after=[p for p in earlier if p not in written])
    print(f"decomposed {args.input} in {elapsed:.2f} s")
    print(describe(dec, scan))
    print(f"wrote {out / DECOMPOSITION_FILE}, {SOURCE_FILE} and {level_name(0, extension)} .. "
          f"{level_name(k, extension)}")


def cmd_reconstruct(args) -> None:
    out = Path(args.output)
    check_output_file(out, args.force, Path(args.decomposition), args.base)
    stages = {"reading": 1.0, "reconstructing": 2.0, "normals": 0.5, "writing": 1.0}
    with CommandProgress(stages) as progress, StagedOutput() as staged:
        progress.stage("reading")
        dec, source = read_decomposition(Path(args.decomposition))
        if source is None and Path(args.decomposition).is_dir():
            warnings.warn(f"the result has points and normals only: {Path(args.decomposition) / SOURCE_FILE}, which "
                          "keeps the input's faces and attributes, is missing")
        gains = parse_gains(args.gains, dec.n_bands) if args.gains is not None else None  # "" is refused
        if args.fold_reference != "input" and args.folds == "ignore":
            warnings.warn(f"--fold-reference {args.fold_reference} applies to --folds report or prevent only; "
                          "without --folds nothing is measured")
        template = source if source is not None else io.Scan(points=dec.base)
        check_format_holds(out.suffix.lower(), template, args.decomposition, points=dec.base, shown=out)
        base = read_base(args.base, dec.n_points, source, dec.base, args.threads, dec) if args.base else None
        try:
            points, reference, folds = reconstruct_with_normals(dec, gains, base, args.threads,
                                                                progress.stage("reconstructing"), args.folds,
                                                                args.fold_reference)
        except ResultOverflow:
            raise ValueError(f"--gains {args.gains} overflow: the result has infinite coordinates") from None
        progress.stage("normals")
        # Unedited at unit gains, with nothing limited, the result is the input: its own normals.
        as_input = (args.base is None and (gains is None or np.all(np.asarray(gains) == 1.0))
                    and (folds is None or not folds.changed.any()))
        if as_input and source is not None and source.normals is not None:
            normals = source.normals
        else:
            normals = finest_normals(points, reference, args.threads)
        tmp = staged.temporary(out)
        with _Writers(progress, "writing", expected=1) as writers:
            writers.submit(lambda: io.write(tmp, level_scan(template, points, normals, None, out.suffix.lower())),
                           tmp, out)
            writers.wait()
        staged.commit()
    print(f"wrote {out} ({dec.n_points} points, gains {args.gains or 'all 1'}"
          f"{', edited base ' + args.base if args.base else ''})")
    if folds is not None:
        print(describe_folds(folds, args.folds, args.fold_reference))


def describe_folds(folds, mode: str, reference: str) -> str:
    against = "over the input's own" if reference == "input" else "over the base"
    if mode == "report":
        return f"folds: {folds.count} points fold ({against})"
    text = (f"folds: {folds.count_before} points folded ({against}), {folds.count} after limiting the gain at "
            f"{int(folds.changed.sum())} points in {folds.rounds} rounds")
    if folds.capped:
        text += f" (stopped after the cap of {folds.rounds} rounds with folds left)"
    return text


def cmd_info(args) -> None:
    dec, source = read_decomposition(Path(args.decomposition))
    print(describe(dec, source))
    print("settings:", ", ".join(f"{k}={v}" for k, v in dec.settings.items()))


DEMO_GAINS = ((1, 1, 0), (1, 1, 2), (0, 0, 1))


def demo_filtered_name(gains) -> str:
    return "filtered_" + "_".join(str(g) for g in gains) + ".ply"


DEMO_FILES = ([level_name(l, ".ply") for l in range(4)] + [demo_filtered_name(gains) for gains in DEMO_GAINS] +
              ["handles_original.ply", "handles_multiscale.ply", "handles_single_scale.ply"])


def check_demo_folder(out: Path, force: bool) -> None:
    """The demo writes fixed file names, all at once: it replaces them where an earlier demo
    wrote them all, and elsewhere only with --force, since they may be the user's. Checked, as
    the folder's writability is, before any computing."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"-o {out} is a file; the demo writes a folder")
    require_writable_folder(out)
    present = [name for name in DEMO_FILES if (out / name).exists()]
    if present and len(present) < len(DEMO_FILES) and not force:
        raise ValueError(f"{out} already holds {present[0]}, a name the demo writes, but not all of the demo's files; "
                         "pass --force to replace it, or choose another folder")


def cmd_demo(args) -> None:
    out = Path(args.output)
    check_demo_folder(out, args.force)
    with StagedOutput() as staged:
        staged.make_dir(out)
        run_demo(args, out, staged)
        staged.commit()
    print(f"all files are in {out.resolve()}")


def run_demo(args, out: Path, staged) -> None:
    """The demo's work, every file written under staged's temporary names."""
    def write(name, scan_or_points):
        tmp = staged.temporary(out / name)
        if isinstance(scan_or_points, io.Scan):
            io.write(tmp, scan_or_points)
        else:
            io.write_ply(tmp, scan_or_points)

    print("Pointscale demo: a bumpy sphere with a coarse and a fine pattern plus scanner-like noise")
    points = shapes.bumpy_sphere(args.points, coarse=0.08, fine=0.012, fine_frequency=28.0, noise=0.002)
    start = time.perf_counter()
    with CommandProgress({"decomposing": 1.0}) as progress:
        dec = decompose(points, levels=4, progress=progress.stage("decomposing"))
    print(f"decomposed {len(points)} points in {time.perf_counter() - start:.2f} s")
    print(describe(dec))
    template = io.Scan(points=points)
    for l in range(dec.n_levels):
        normals = dec.normals(l) if l < dec.n_bands else finest_normals(points, dec.normals(l - 1), 0)
        detail = dec.details[l] if l < dec.n_bands else None
        write(level_name(l, ".ply"), level_scan(template, dec.level(l), normals, detail, ".ply"))
    error = np.abs(reconstruct(dec) - points).max() / np.linalg.norm(np.ptp(points, axis=0))
    print(f"exact reconstruction: max error {error:.2e} of the bounding-box diagonal")
    for gains in DEMO_GAINS:
        name = demo_filtered_name(gains)
        write(name, reconstruct(dec, gains=gains))
        print(f"band filter {gains}: writes {out / name}")

    print("\nMultiscale deformation (paper Fig. 5): a plane with 16 box handles, base lifted by a bump")
    plane, handle, centres = shapes.handles_plane()
    dp = decompose(plane, levels=4, decimation=0.2, kernel=2.0)
    lifted = dp.base.copy()
    lifted[:, 2] += 0.8 * np.exp(-(lifted[:, :2] ** 2).sum(axis=1))
    multi = reconstruct(dp, base=lifted)
    single = plane.copy()
    single[:, 2] += 0.8 * np.exp(-(plane[:, :2] ** 2).sum(axis=1))
    write("handles_original.ply", plane)
    write("handles_multiscale.ply", multi)
    write("handles_single_scale.ply", single)
    print(f"writes {out}/handles_original.ply, handles_multiscale.ply, handles_single_scale.ply")
