"""PLY reading and writing through plyfile: points, optional normals, faces and scalar fields."""
from __future__ import annotations

import os
from typing import NamedTuple

import numpy as np
from plyfile import PlyData, PlyElement


class PlyModel(NamedTuple):
    points: np.ndarray            # (n, 3) float64
    normals: np.ndarray | None    # (n, 3) or None
    faces: list | None            # vertex index lists, kept only to write meshes back


def read_ply(path) -> PlyModel:
    """Reads a PLY file (binary or ASCII). Faces are kept as they are; the method ignores them."""
    path = os.fspath(path)
    try:
        ply = PlyData.read(path)
    except FileNotFoundError:
        raise ValueError(f"no such file: {path}") from None
    except Exception as exc:
        raise ValueError(f"cannot read PLY {path}: {exc}") from None
    if "vertex" not in ply:
        raise ValueError(f"{path} has no vertex element")
    v = ply["vertex"].data
    names = v.dtype.names or ()
    if not {"x", "y", "z"} <= set(names):
        raise ValueError(f"{path}: vertices have no x, y, z properties")
    points = np.column_stack([v["x"], v["y"], v["z"]]).astype(np.float64)
    normals = None
    if {"nx", "ny", "nz"} <= set(names):
        normals = np.column_stack([v["nx"], v["ny"], v["nz"]]).astype(np.float64)
    faces = None
    if "face" in ply and len(ply["face"].data):
        prop = "vertex_indices" if "vertex_indices" in ply["face"].data.dtype.names else ply["face"].data.dtype.names[0]
        faces = list(ply["face"].data[prop])
    return PlyModel(points, normals, faces)


def write_ply(path, points, normals=None, faces=None, scalars: dict | None = None, binary: bool = True) -> None:
    """Writes points (n, 3) with optional normals (n, 3), faces and per-point scalar fields."""
    points = np.asarray(points, dtype=np.float64)
    fields = [("x", "f4"), ("y", "f4"), ("z", "f4")]
    columns = [points[:, 0], points[:, 1], points[:, 2]]
    if normals is not None:
        fields += [("nx", "f4"), ("ny", "f4"), ("nz", "f4")]
        columns += [normals[:, 0], normals[:, 1], normals[:, 2]]
    for name, values in (scalars or {}).items():
        fields.append((name, "f4"))
        columns.append(np.asarray(values))
    vertex = np.empty(len(points), dtype=fields)
    for (name, _), col in zip(fields, columns):
        vertex[name] = col
    elements = [PlyElement.describe(vertex, "vertex")]
    if faces is not None and len(faces):
        face = np.empty(len(faces), dtype=[("vertex_indices", "i4", (3,))]) if _all_triangles(faces) else \
            np.array([(np.asarray(f, dtype=np.int32),) for f in faces], dtype=[("vertex_indices", object)])
        if face.dtype.fields["vertex_indices"][0].shape == (3,):
            face["vertex_indices"] = np.asarray(faces, dtype=np.int32).reshape(-1, 3)
        elements.append(PlyElement.describe(face, "face"))
    path = os.fspath(path)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    PlyData(elements, text=not binary).write(path)


def _all_triangles(faces) -> bool:
    return all(len(f) == 3 for f in faces)
