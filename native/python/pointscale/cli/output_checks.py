"""Checks of -o made before any computing, so that a bad path fails in a second, not after the work."""
from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np

from .. import io
from .folder import is_level_file, owned_files
from .level_files import level_scan


def writable_extension(path: Path | str, what: str, shown: str | None = None,
                       supported: tuple = io.SUPPORTED_EXTENSIONS) -> str:
    """path's extension, if one of `supported`; `what` and `shown` (default: path) name it."""
    extension = Path(path).suffix.lower()
    if what == "input" and not str(path):
        raise ValueError("the input file name is empty")
    if what == "input" and Path(path).is_dir():  # the reader would say so, after this check
        raise ValueError(f"input {path} is a folder, not a file")
    if extension not in supported:
        raise ValueError(f"{what} {shown if shown is not None else path}: unknown extension {extension or '(none)'!r}; "
                         f"supported: {', '.join(supported)}")
    return extension


def _nearest_existing(path: Path) -> Path:
    p = path.absolute()
    while not p.exists():
        p = p.parent
    return p


def _require_writable_folder(folder: Path, shown: Path) -> None:
    if not folder.is_dir():
        raise ValueError(f"cannot write {shown}: {folder} is a file, not a folder")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise ValueError(f"cannot write {shown}: {folder} is not writable ({exc.strerror})") from None


def require_writable_folder(out: Path) -> None:
    """Refuses a folder -o that cannot be written (or made), before any computing."""
    _require_writable_folder(_nearest_existing(out), out)


def check_output_folder(out: Path, force: bool) -> list[Path]:
    """Checks that decompose can write the folder `out`; returns an earlier run's files there,
    which the new run replaces (only with force)."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"-o {out} is a file; decompose writes a folder")
    _require_writable_folder(_nearest_existing(out), out)
    earlier = owned_files(out)
    if earlier and not force:
        raise ValueError(f"{out} already holds a decomposition ({len(earlier)} file{'s' * (len(earlier) != 1)}, "
                         f"e.g. {earlier[0].name}); "
                         "pass --force to replace it, or choose another folder")
    return earlier


def check_input_kept(source: Path, out: Path) -> None:
    """Refuses, --force or not, to decompose a file that the run would overwrite or remove: a
    level file of `out` (level_0.ply of an earlier run, taken as a new input) or one of its
    earlier decomposition's files. The scan would be lost once the new files are in place."""
    try:
        source_real = source.resolve(strict=True)
    except OSError:
        return  # a missing input is io.read's to report
    inside = source_real.parent == out.resolve()
    replaced = any(_same_file(source_real, p) for p in owned_files(out))
    if replaced or (inside and is_level_file(source_real.name)):
        raise ValueError(f"the input {source} is one of the files decompose writes or replaces in {out}, and would be "
                         "lost; copy it out of that folder first, or choose another -o")


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.samefile(b)
    except OSError:
        return False


def check_output_file(out: Path, force: bool, decomposition: Path | None = None, base: str | None = None) -> None:
    """Refuses an -o that cannot be written, or that exists (without --force). With --force or
    not, it refuses the decomposition's own files and the --base file: overwritten, the folder
    would no longer match its decomposition (level 0 holding a result), or the edit would be lost."""
    if out.is_dir():
        raise ValueError(f"-o {out} is a folder; reconstruct writes one file")
    writable_extension(out, "-o")
    # The decomposition's folder, given as the folder or as its decomposition.npz.
    folder = None if decomposition is None else decomposition if decomposition.is_dir() else decomposition.parent
    own = owned_files(folder) if folder is not None else []
    if decomposition is not None and decomposition.is_file():
        own.append(decomposition)
    inside = folder is not None and out.absolute().parent.resolve() == folder.resolve()
    if any(_same_file(out, p) for p in own) or (inside and is_level_file(out.name)):
        raise ValueError(f"-o {out} is one of the decomposition's own files, which the folder would then no longer "
                         "match; write the result to another file")
    if base is not None and _same_file(out, Path(base)):
        raise ValueError(f"-o {out} is the --base file, whose edit would be lost; write the result to another file")
    if out.exists() and not force:
        raise ValueError(f"{out} exists; pass --force to overwrite it")
    parent = out.absolute().parent
    if not parent.exists():
        raise ValueError(f"cannot write {out}: the folder {parent} does not exist")
    _require_writable_folder(parent, out)


def check_format_holds(extension: str, scan, name, points=None, shown=None) -> None:
    """Refuses, before any computing, an output format that cannot hold the model at all, or
    the input's attributes under their names and types (a LAS field 'my field' in PLY, a
    column named twice in XYZ): a few of its vertices are written as a level would be, to a
    scratch folder. `points` (n, 3) stand in for the scan's own (NaN in a source.npz); `shown`
    is the output file named in the error."""
    if extension == ".stl" and scan.n_faces == 0:
        raise ValueError(f"STL stores triangles and {name} has no faces; write .ply, .las or .xyz instead")
    trial = _few_vertices(scan, scan.points if points is None else points)
    normals = np.tile([0.0, 0.0, 1.0], (trial.n_points, 1))
    with tempfile.TemporaryDirectory() as scratch, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the real writes warn; this one must not warn twice
        path = Path(scratch) / f"trial{extension}"
        try:
            io.write(path, level_scan(trial, trial.points, normals, np.zeros(trial.n_points), extension))
        except ValueError as exc:
            raise ValueError(str(exc).replace(str(path), str(shown or f"the {extension} output"))) from None


def _few_vertices(scan, points: np.ndarray, count: int = 8):
    """The first `count` vertices of scan with their attributes, or the first face's vertices and
    that face (renumbered) with its attributes: a scan small enough to write in no time."""
    if scan.n_faces:
        face = np.asarray(scan.faces[0])
        keep = np.unique(face)
        faces = np.searchsorted(keep, face)[None, :]
        face_attributes = {k: v[:1] for k, v in scan.face_attributes.items()}
    else:
        keep, faces, face_attributes = np.arange(min(count, scan.n_points)), None, {}
    return io.Scan(points=points[keep], precision=scan.precision,
                   vertex_attributes={k: v[keep] for k, v in scan.vertex_attributes.items()},
                   faces=faces, face_attributes=face_attributes, format_info=scan.format_info)


def read_base(path: str, n_points: int, source, stored=None, threads: int = 0, dec=None):
    """The edited level 0 of `path`, (n, 3), checked against the decomposition: the same vertex
    count and, when both files have faces, the same faces (STL, say, renumbers its vertices on
    reading, which would pair each vertex with another's detail). stored: the decomposition's
    own level 0, against which a base in another vertex order is told (a warning). dec: the
    decomposition, whose other levels a base is told from (an error)."""
    base = io.read(path)
    if base.n_points != n_points:
        raise ValueError(f"--base {path} has {base.n_points} points; the decomposition has {n_points} "
                         "(edit level_0 without adding or removing vertices)")
    base = _in_input_order(base, source)
    if stored is not None:
        resolution = level_file_rounding(base, source)
        unedited = within_resolution(base.points, stored, resolution)
        # Most of level 0 left where it was, the common case, is told without rebuilding a level.
        if dec is not None and unedited.mean() <= OTHER_LEVEL_SHARE:
            _refuse_other_level(path, base, stored, dec, source, resolution)
        base = _unedited_at_full_precision(path, base, source, stored, resolution, unedited)
    if source is not None and source.n_faces and base.n_faces:
        shared = _share_of_faces_kept(base.faces, source.faces)
        if shared < FACES_KEPT:
            raise ValueError(f"--base {path}: only {shared:.0%} of its faces join the same vertices as the decomposed "
                             "input's, so its vertices look renumbered, which would pair each vertex with another's "
                             "detail (STL, for one, renumbers them on reading: edit a level file in a format that "
                             "keeps vertex order, such as PLY)")
    if stored is not None:
        _warn_if_reordered(path, base.points, stored, threads)
    return base.points


#: The share of a base's points that lie where another level's do, as the file rounds them,
#: past which the base is taken for that level: an edit of level 0 leaves its points where level
#: 0 has them, or moves them off every level.
OTHER_LEVEL_SHARE = 0.5


def _refuse_other_level(path: str, base, stored: np.ndarray, dec, source, resolution) -> None:
    """Refuses a level file other than level 0 given as --base (level_3.ply beside level_0.ply,
    one tab completion away): its detail would be added twice (a scan's points ended up 1 m off,
    without a word). Told by where its points lie: on another level's, as the file rounds them
    (resolution: level_file_rounding)."""
    from ..multiscale import reconstruct
    finest = dec.n_bands
    # Level l rebuilt with the bands above it at gain 0, one level at a time: dec.level() would
    # keep every level and its normals (160 bytes a point) for the rest of the command. Rebuilt
    # to rounding, so an exact file is compared within 1e-9 of the model's size.
    floor = 1e-9 * float(np.linalg.norm(np.ptp(stored, axis=0)))
    tolerance = np.maximum(resolution, floor) if resolution is not None else np.full(base.points.shape, floor)
    for l in range(1, finest + 1):
        if l == finest and source is not None and np.isfinite(source.points).all():
            level = source.points
        else:
            level = reconstruct(dec, np.r_[np.ones(l), np.zeros(finest - l)])
        if within_resolution(base.points, level, tolerance).mean() > OTHER_LEVEL_SHARE:
            raise ValueError(f"--base {path} lies where level {l}{' (the finest)' if l == finest else ''} of this "
                             f"decomposition lies, not level 0: its detail would be added again. Give this "
                             f"decomposition's (edited) level_0 file as --base (a level_0 of another decomposition of "
                             f"the same input, with other levels or settings, is not this one's)")


#: Rounding of a single-precision base, as a share of the model's size, beyond which it is said:
#: a model near the origin rounds by about 3e-8 of its size; one far from it (georeferenced),
#: by far more.
SINGLE_PRECISION_SAID = 1e-6


def file_resolution(scan):
    """The largest rounding, per vertex and coordinate ((n, 3), or None for none), by which a
    file like `scan`'s stores a point: half a step of a LAS file's scaled integers, half a unit in
    the last place of single precision (float32 PLY, MeshLab's and CloudCompare's files, and the
    level files of a float32 input), half a step of the fixed decimals of a text file (las2txt's
    and CloudCompare's exports). Levels written in such a file come back rounded by it."""
    info = scan.format_info
    las = _las_half_step(info, scan.points.shape)
    if las is not None:
        return las
    if info.get("format") == "e57":
        return _e57_rounding(scan)
    if info.get("format") in ("xyz", "pts"):
        return _text_half_step(scan.points)
    if np.dtype(scan.precision) == np.float32:
        return 0.5 * np.spacing(np.abs(scan.points).astype(np.float32)).astype(np.float64)
    return None


def _e57_rounding(scan):
    """E57 files hold float32 coordinates in each scan's own frame (pye57; io.e57 writes them
    around the scan's pose): a point rounds by half a float32 step at its distance from its
    scan's origin, in any direction of the world (sqrt(3) of it per coordinate). Which scan a
    point came from is not always at hand here, so the farthest origin bounds it."""
    origins = [s.get("translation") for s in scan.format_info.get("stations") or () if isinstance(s, dict)]
    origins = np.array([o for o in origins if o is not None], dtype=np.float64).reshape(-1, 3)
    if len(origins) == 0:
        origins = np.zeros((1, 3))
    reach = np.max([np.linalg.norm(scan.points - o, axis=1) for o in origins], axis=0)
    step = np.spacing(reach.astype(np.float32)).astype(np.float64)
    return np.broadcast_to((np.sqrt(3.0) * 0.5 * step)[:, None], scan.points.shape)


#: The most decimals a text file's coordinates are looked at with: beyond them a fixed number of
#: decimals is no rounding worth telling apart from float64's own.
TEXT_DECIMALS = 12


def _text_half_step(points: np.ndarray) -> np.ndarray | None:
    """Half a step of the fixed decimals a text file's coordinates were written with (las2txt,
    CloudCompare's export and many scanners' software write 2 to 8), per coordinate, as
    points' shape; None where a coordinate has no fixed number of them (our own files write
    every digit float64 holds)."""
    steps = [_fixed_decimals_half_step(column) for column in points.T]
    if any(step is None for step in steps):
        return None
    return np.broadcast_to(np.array(steps), points.shape)


def _fixed_decimals_half_step(column: np.ndarray) -> float | None:
    for decimals in range(TEXT_DECIMALS + 1):
        scaled = column * 10.0 ** decimals
        if np.abs(scaled).max() >= 2.0 ** 52:  # past float64's whole numbers: no decimals left to tell
            return None
        # Read back, k / 10^d times 10^d gives k to a few units in float64's last place.
        if np.all(np.abs(scaled - np.round(scaled)) <= 8.0 * np.spacing(np.maximum(np.abs(scaled), 1.0))):
            return 0.5 * 10.0 ** -decimals
    return None


def _las_half_step(info: dict, shape) -> np.ndarray | None:
    """Half a step of the scaled integers of the LAS file `info` describes, as `shape`, or None
    for a file of another format."""
    if info.get("format") not in ("las", "laz") or info.get("scales") is None:
        return None
    return np.broadcast_to(0.5 * np.abs(np.asarray(info["scales"], dtype=np.float64)), shape)


def level_file_rounding(base, source):
    """How far a level file's vertices may lie from the stored level as `base` was read: its own
    file's rounding, plus, for a LAS input, the rounding of the level file decompose wrote on the
    input's grid (a level_0.las re-saved with other offsets or a finer scale rounds twice), or
    None for none."""
    own = file_resolution(base)
    written = _las_half_step(source.format_info, base.points.shape) if source is not None else None
    if written is None:
        return own
    return written if own is None else own + written


def within_resolution(points: np.ndarray, reference: np.ndarray, resolution) -> np.ndarray:
    """(n,) whether each point is `reference`'s as the file rounded it: within `resolution` of it
    in every coordinate (exactly equal where there is none)."""
    if resolution is None:
        return np.all(points == reference, axis=1)
    # A rounding exactly halfway is the file's either way: a hair more than half a step, and the
    # few units in float64's last place by which the step's decimal is not a binary number
    # (5180000.123455 written with 5 decimals came back 5.00027e-6 away).
    slack = 4.0 * np.spacing(np.maximum(np.abs(points), np.abs(reference)))
    return np.all(np.abs(points - reference) <= resolution * (1.0 + 1e-9) + slack, axis=1)


def _unedited_at_full_precision(path: str, base, source, stored: np.ndarray, resolution, unedited: np.ndarray):
    """A base saved in a file that rounds coordinates (LAS's scaled integers; single precision,
    what MeshLab and Blender write): its vertices that the file holds as the stored level 0
    rounded are taken as the stored ones (unedited), as the Blender add-on takes them, so an
    unedited round trip stays exact and a local edit leaves the rest as it was (read back from
    a LAS file at 1 mm, an unedited level 0 moved a tenth of the points by up to 3.7 mm). The
    edited ones keep the file's rounding; where that is float32's far from the origin of a
    decomposition in double, which moves them and their detail visibly, it is said.
    resolution: level_file_rounding; unedited: within_resolution of the stored level 0."""
    if resolution is None:
        return base
    points = base.points.copy()
    points[unedited] = stored[unedited]
    double = source is None or np.dtype(source.precision) == np.float64
    if np.dtype(base.precision) != np.float32 or not double:
        return base.with_geometry(points, base.normals)
    edited = points[~unedited]
    size = float(np.linalg.norm(np.ptp(stored, axis=0)))
    rounding = float(np.abs(edited).max()) * 2.0 ** -24 if len(edited) else 0.0
    if size > 0.0 and rounding > SINGLE_PRECISION_SAID * size:
        warnings.warn(f"--base {path} holds single-precision (float32) coordinates and the decomposition double; "
                      f"its {len(edited)} edited vertices are rounded by float32 by up to {rounding:.2g} "
                      f"({rounding / size:.1e} of the model's size) this far from the origin, and their detail moves "
                      "with them (the unedited ones are taken at full precision). Save the edited level 0 in double "
                      "precision where the tool can (a PLY with double properties)")
    return base.with_geometry(points, base.normals)


def _in_input_order(base, source):
    """An E57 level file of an input whose scans (scan_id) were interleaved or out of order
    lists the points scan by scan (io.e57, which warns when it writes one): put back in the
    input's order, which it tells by the scans it reads back; anything else as it is."""
    ids = None if source is None else source.vertex_attributes.get("scan_id")
    if base.format_info.get("format") != "e57" or ids is None:
        return base
    ids = np.asarray(ids)
    if ids.ndim != 1 or len(ids) != base.n_points or np.all(np.diff(ids.astype(np.int64)) >= 0):
        return base
    order = np.argsort(ids, kind="stable")  # the file's point r is the input's point order[r]
    read = base.vertex_attributes.get("scan_id")
    if read is None or not np.array_equal(np.asarray(read), np.unique(ids, return_inverse=True)[1][order]):
        return base  # not listed as pointscale writes it: the checks below judge it
    points = np.empty_like(base.points)
    points[order] = base.points
    return base.with_geometry(points, None)


#: The median stretch of the edges between nearest neighbours, beyond the stretch of the whole
#: model (a uniform scale: metres to centimetres), past which a base is taken for one in another
#: vertex order. A shuffled base stretches them by about half the model's size over its sample
#: spacing: 37 times on an 8000-point sphere, 12 on a 1000-point one; an edit that stretches the
#: surface itself 5 times at most of its points is no edit.
REORDERED_STRETCH = 5.0


def _warn_if_reordered(path: str, base: np.ndarray, stored: np.ndarray, threads: int) -> None:
    """A base in another vertex order (a point cloud re-saved sorted, or shuffled) has its count,
    yet pairs each point with another's detail: the result is garbage. Its points lie far from
    the points that neighbour them in the decomposition's level 0, which no edit does."""
    from .. import _core
    if len(stored) < 2:
        return
    rows = _core.knn_within_parts(stored, np.zeros(len(stored), dtype=np.int32), k=2, threads=threads).astype(np.int64)
    before = np.linalg.norm(stored[rows[:, 1]] - stored, axis=1)
    after = np.linalg.norm(base[rows[:, 1]] - base, axis=1)
    use = before > 0.0
    size_before = float(np.linalg.norm(np.ptp(stored, axis=0)))
    size_after = float(np.linalg.norm(np.ptp(base, axis=0)))
    if not use.any() or not size_before > 0.0 or not size_after > 0.0:
        return
    stretch = float(np.median(after[use] / before[use])) / (size_after / size_before)
    if stretch > REORDERED_STRETCH:
        warnings.warn(f"--base {path}: points that neighbour each other in the decomposition's level 0 lie a median "
                      f"{stretch:.0f} times farther apart in it (for its size); it looks like level 0 in another "
                      "vertex order, which pairs each vertex with another's detail (edit level_0 in a format and tool "
                      "that keep the vertex order, such as PLY)")


#: The share of an edited base's faces that must join the same vertices as the input's faces do.
#: Renumbered vertices (STL's reading) keep almost none; faces flipped, reordered, deleted or
#: added around a hole keep nearly all.
FACES_KEPT = 0.5


def _share_of_faces_kept(base_faces, source_faces) -> float:
    """The share of base_faces whose every edge joins two vertices of one source face: a face
    of the source flipped or moved, or a triangle of a source polygon split (MeshLab
    triangulates polygons on reading, Blender's exporters can), keeps them all."""
    source = np.unique(np.concatenate([k.ravel() for k in _vertex_pairs(source_faces, every=True)]))
    kept = sum(int(np.isin(k, source).all(axis=1).sum()) for k in _vertex_pairs(base_faces, every=False))
    return kept / max(len(base_faces), 1)


def _vertex_pairs(faces, every: bool) -> list:
    """Per group of faces of one size, (m, pairs) int64 keys a * 2^32 + b with a < b: each
    face's every vertex pair, or only its edges."""
    groups = [faces] if isinstance(faces, np.ndarray) else _by_size(faces)
    out = []
    for f in groups:
        f = np.asarray(f, dtype=np.int64)
        k = f.shape[1]
        pairs = [(i, j) for i in range(k) for j in range(i + 1, k)] if every else [(i, (i + 1) % k) for i in range(k)]
        a = f[:, [i for i, _ in pairs]]
        b = f[:, [j for _, j in pairs]]
        out.append(np.minimum(a, b) * 2**32 + np.maximum(a, b))
    return out


def _by_size(faces) -> list:
    """Polygons of several sizes as one (m, k) array per size."""
    sizes = {}
    for face in faces:
        sizes.setdefault(len(face), []).append(face)
    return [np.array(group, dtype=np.int64) for group in sizes.values()]
