"""File formats: read(path) -> Scan and write(path, scan), the format chosen by the extension.

    scan = pointscale.io.read("site.laz")            # Scan: points (n, 3) float64, attributes...
    pointscale.io.write("site_smooth.laz", scan.with_geometry(new_points, scan.normals))

PLY (plyfile; ASCII and triangle/quad meshes without its row-by-row loops), LAS/LAZ (laspy +
lazrs, with the file's counts checked first), STL (trimesh), OBJ/OFF/XYZ/PTS (numpy), E57 (pye57,
optional: pip install pye57). Every reader raises ValueError with one line naming the file for anything missing or
damaged; every writer writes through atomic_write, so a failed write leaves no partial file.
"""
from __future__ import annotations

import dataclasses
import os
import warnings
from pathlib import Path

import numpy as np

from . import e57, las, mesh_formats, ply, text
from .atomic import atomic_write
from .scan import Scan, require_regular_file

# extension -> (reader, writer)
_FORMATS = {
    ".ply": (ply.read_ply, ply.write_ply),
    ".las": (las.read_las, las.write_las),
    ".laz": (las.read_las, las.write_las),
    ".obj": (mesh_formats.read_obj, mesh_formats.write_obj),
    ".off": (mesh_formats.read_off, mesh_formats.write_off),
    ".stl": (mesh_formats.read_stl, mesh_formats.write_stl),
    ".xyz": (text.read_xyz, text.write_xyz),
    ".txt": (text.read_xyz, text.write_cloudcompare),  # CloudCompare's ASCII clouds
    ".asc": (text.read_xyz, text.write_cloudcompare),
    ".pts": (text.read_pts, text.write_pts),
    ".e57": (e57.read_e57, e57.write_e57),
}
SUPPORTED_EXTENSIONS = tuple(_FORMATS)
# Point-cloud formats: a mesh written to them keeps its points and loses its faces.
_FORMATS_WITHOUT_FACES = (".las", ".laz", ".xyz", ".txt", ".asc", ".pts", ".e57")

__all__ = ["Scan", "SUPPORTED_EXTENSIONS", "atomic_write", "read", "read_ply", "write", "write_ply"]


def read(path) -> Scan:
    """The Scan in the file at path, the format chosen by its extension (case-insensitive)."""
    if os.path.isdir(os.fspath(path)):
        raise ValueError(f"{os.fspath(path)} is a folder, not a file")
    if os.path.exists(os.fspath(path)):  # a missing file: each reader says "no such file"
        try:
            require_regular_file(os.fspath(path))  # a named pipe would block, a device never end
        except ValueError as exc:
            raise ValueError(f"{os.fspath(path)}: {exc}") from None
    return _format(path)[0](os.fspath(path))


def write(path, scan: Scan) -> None:
    """Writes scan to path in the format of its extension (case-insensitive), atomically."""
    if not isinstance(scan, Scan):
        raise ValueError(f"write needs a Scan, got {type(scan).__name__}")
    try:
        scan = dataclasses.replace(scan)  # checks again what may have been edited in place (attributes, faces)
    except ValueError as exc:
        raise ValueError(f"{os.fspath(path)}: {exc}") from None
    if scan.n_points == 0:
        raise ValueError(f"{os.fspath(path)}: the scan has no points; nothing to write")
    if not np.isfinite(scan.points).all():
        raise ValueError(f"{os.fspath(path)}: the scan has non-finite points (did you call with_geometry?)")
    writer = _format(path)[1]
    suffix = Path(os.fspath(path)).suffix.lower()
    if scan.n_faces and suffix in _FORMATS_WITHOUT_FACES:
        warnings.warn(f"{os.fspath(path)}: {suffix} has no place for faces; {scan.n_faces} faces"
                      f"{' and their attributes' if scan.face_attributes else ''} not written", stacklevel=2)
    if suffix not in (".ply", ".xyz", ".txt", ".asc", ".obj") and scan.format_info.get("format") in ("ply", "xyz", "pts", "obj"):
        from .text import kept_comments
        lines = kept_comments(scan)
        if lines:  # a CRS in a comment is the kind of thing that must not vanish unsaid
            warnings.warn(f"{os.fspath(path)}: {suffix} has no place for the input's comment lines; {len(lines)} not "
                          f"written (the first: {lines[0][:60]!r}); .ply, .xyz, .txt, .asc and .obj keep them",
                          stacklevel=2)
    if suffix not in (".las", ".laz"):
        _warn_of_the_coordinate_system(os.fspath(path), suffix, scan)
    try:
        writer(os.fspath(path), scan)
    except OSError as exc:  # a folder that cannot be created or written, a full disk
        raise ValueError(f"{os.fspath(path)}: cannot write ({exc.strerror or exc})") from None
    except ValueError as exc:
        if os.fspath(path) in str(exc):
            raise
        raise ValueError(f"{os.fspath(path)}: {exc}") from None


def _warn_of_the_coordinate_system(path: str, suffix: str, scan: Scan) -> None:
    """A LAS file's coordinate system (its LASF_Projection records) has no field in the other
    formats: where they keep comment lines it is written as one, else it is not written; either
    is said, so that a georeferenced survey does not lose its CRS unsaid."""
    crs = las.coordinate_system(scan.format_info)
    if crs is None:
        return
    name, line = crs
    if line is not None and suffix in (".ply", ".xyz", ".txt", ".asc", ".obj"):
        warnings.warn(f"{path}: {suffix} has no field for the LAS coordinate system {name!r}; written as the "
                      f"comment line {line[:60] + ('...' if len(line) > 60 else '')!r}", stacklevel=3)
    else:
        keeps = "; .ply, .xyz, .txt, .asc and .obj keep it as a comment line" if line is not None else ""
        warnings.warn(f"{path}: {suffix} has no place for the LAS coordinate system {name!r}; not written{keeps}",
                      stacklevel=3)


def read_ply(path) -> Scan:
    """A PLY file as a Scan (.points (n, 3) float64, .normals, .faces): kept for existing callers."""
    return ply.read_ply(path)


def write_ply(path, points, normals=None, faces=None, scalars: dict | None = None, binary: bool = True) -> None:
    """Writes points (n, 3) with optional normals (n, 3), faces (index lists) and per-point scalar
    fields {name: (n,)}. Coordinates are stored as float64 when given float64, float32 when
    given float32; scalars keep their dtype."""
    points = np.asarray(points)
    precision = points.dtype if points.dtype in (np.float32, np.float64) else np.dtype(np.float64)
    scan = Scan(points=points, precision=precision, normals=normals, faces=faces,
                vertex_attributes=dict(scalars or {}))
    try:
        ply.write_ply(path, scan, binary=binary)
    except OSError as exc:
        raise ValueError(f"{os.fspath(path)}: cannot write ({exc.strerror or exc})") from None


def _format(path):
    suffix = Path(os.fspath(path)).suffix.lower()
    if suffix not in _FORMATS:
        raise ValueError(f"{os.fspath(path)}: unknown file extension {suffix or '(none)'!r}; "
                         f"supported: {', '.join(SUPPORTED_EXTENSIONS)}")
    return _FORMATS[suffix]
