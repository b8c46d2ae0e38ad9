"""STL through trimesh (binary and ASCII).

An STL file is a triangle soup: each triangle has its own three corners. Read, corners at exactly
equal coordinates are merged into one vertex, as MeshLab does on import, since 3 copies of every
point make a poor point cloud; vertices come in the order of their first corner. Binary STL holds
float32 coordinates (precision float32), ASCII holds decimal text (precision float64). The
per-triangle normals STL stores are not kept (they follow from the triangles; trimesh writes them
again). Vertex attributes and normals have no place in STL and are dropped with a warning.
"""
from __future__ import annotations

import os
import warnings

import numpy as np

from .atomic import atomic_write
from .optional import optional_module
from .scan import Scan


def _trimesh():
    return optional_module("trimesh", ".stl", "trimesh")


def read_stl(path) -> Scan:
    path = os.fspath(path)
    trimesh = _trimesh()
    from trimesh.exchange.stl import load_stl
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    binary = _is_binary(path)
    try:
        with open(path, "rb") as f:
            loaded = load_stl(f)
        corners = np.asarray(loaded["vertices"], dtype=np.float64)
        triangles = np.asarray(loaded["faces"], dtype=np.int64)
    except Exception as exc:  # trimesh raises HeaderError, ValueError, IndexError on damaged files
        raise ValueError(f"{path}: not a readable STL file ({type(exc).__name__}: {_first_line(exc)})") from None
    del trimesh
    if len(triangles) == 0 or len(corners) == 0:
        raise ValueError(f"{path}: no triangles")
    if not np.isfinite(corners).all():
        raise ValueError(f"{path}: non-finite coordinates")
    if triangles.min() < 0 or triangles.max() >= len(corners):
        raise ValueError(f"{path}: triangles refer to missing corners")
    # Equal corners are equal 24-byte rows (+ 0.0 turns -0.0 into 0.0 so that they match too);
    # np.unique on those bytes is 3x faster than np.unique(axis=0).
    keys = np.ascontiguousarray(corners + 0.0).view(np.dtype((np.void, 24))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")  # vertices in the order of their first corner
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    points = corners[first[order]]
    faces = rank[inverse.reshape(-1)][triangles]
    return Scan(points=points, precision=np.float32 if binary else np.float64, faces=faces,
                format_info={"format": "stl", "binary": bool(binary)})


def write_stl(path, scan: Scan) -> None:
    """Writes the scan's faces as STL, polygons split into fans of triangles: binary (float32)
    for float32 scans, ASCII (shortest exact decimals) for float64 ones, which binary would round."""
    path = os.fspath(path)
    trimesh = _trimesh()
    from trimesh.exchange.stl import export_stl, export_stl_ascii
    if scan.n_faces == 0:
        raise ValueError(f"{path}: STL stores triangles and this scan has no faces (write .ply or .xyz instead)")
    dropped = list(scan.vertex_attributes) + list(scan.face_attributes) + (["normals"] if scan.normals is not None
                                                                             else [])
    if dropped:
        warnings.warn(f"{path}: STL has no place for {', '.join(dropped)}; not written", stacklevel=3)
    mesh = trimesh.Trimesh(vertices=scan.points, faces=_triangles(scan.faces), process=False, validate=False)
    data = export_stl(mesh) if scan.precision == np.float32 else export_stl_ascii(mesh).encode("ascii")
    with atomic_write(path) as temporary:
        with open(temporary, "wb") as f:
            f.write(data)


def _triangles(faces) -> np.ndarray:
    """(t, 3) triangles: each polygon (a, b, c, d, ...) as the fan (a, b, c), (a, c, d), ..."""
    if isinstance(faces, np.ndarray) and faces.shape[1] == 3:
        return faces
    polygons = faces if isinstance(faces, list) else list(faces)
    return np.array([(p[0], p[i], p[i + 1]) for p in polygons for i in range(1, len(p) - 1)], dtype=np.int64)


def _is_binary(path: str) -> bool:
    """Binary STL: 80-byte header, uint32 count, 50 bytes a triangle; the size gives it away even
    when the header starts with "solid" as some exporters write."""
    size = os.path.getsize(path)
    if size < 84:
        return False
    with open(path, "rb") as f:
        header = f.read(84)
    count = int(np.frombuffer(header[80:84], dtype="<u4")[0])
    return size == 84 + 50 * count


def _first_line(exc: Exception) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
