"""What a level file holds: the level's points, its own normals, its detail, the input's attributes."""
from __future__ import annotations

import numpy as np

from .. import _core
from .._checks import centre, thread_option

# Neighbours of the PCA normals of the finest level, the one level the model stores no normals for.
FINEST_NORMAL_NEIGHBORS = 16


def finest_normals(points: np.ndarray, reference: np.ndarray, threads: int) -> np.ndarray:
    """Unit normals of the finest level (n, 3): PCA normals of its own points, each turned to the
    side of `reference`, the normals (n, 3) of the level below at the same point. For a result
    other than the input itself: after a filter or an edit the input's normals no longer
    describe the surface (the input itself carries its own, commands.py)."""
    normals = _core.estimate_normals(points - centre(points), neighbors=FINEST_NORMAL_NEIGHBORS, orient=False,
                                     threads=thread_option(threads))
    flip = np.einsum("ij,ij->i", normals, reference) < 0
    normals[flip] *= -1.0
    return normals


class ResultOverflow(ValueError):
    """Gains so large that the result has infinite coordinates."""


def reconstruct_with_normals(dec, gains, base, threads: int, progress, folds: str = "ignore",
                             fold_reference: str = "input"):
    """(finest level (n, 3), normals (n, 3) of the level below it, Folds or None) of
    reconstruct(dec, gains, base, folds=..., fold_reference=...): the same points, plus what
    finest_normals() orients the result's normals by. Of a mirrored decomposition, the half's
    (the core rebuilds the whole model). ResultOverflow when the gains overflow."""
    from ..multiscale import _base_array, _gains_array, _result_with_folds
    b = _base_array(dec, base)
    levels, normals = dec._reconstruct(_gains_array(dec, gains), b, keep_levels=True, progress=progress,
                                       threads=thread_option(threads))
    if not np.isfinite(levels[-1]).all():
        raise ResultOverflow("the result has infinite coordinates")
    result = _result_with_folds(dec, levels[-1], b, folds, fold_reference)
    points, found = (result, None) if folds == "ignore" else result
    below = normals[-1] if dec._mirror is None else dec._mirror.symmetric_normals(normals[-1])
    return points, below, found


def free_names(scan, names: tuple[str, ...]) -> tuple[str, ...]:
    """`names` when the input has no vertex attribute of any of them; else the first of
    pointscale_<names>, pointscale_<names>_2, ... it has none of, so that the input's own
    attributes keep their names and values."""
    candidates, number = names, 1
    while any(name in scan.vertex_attributes for name in candidates):
        candidates = tuple(f"pointscale_{name}" + ("" if number == 1 else f"_{number}") for name in names)
        number += 1
    return candidates


def detail_attribute_name(scan) -> str:
    """'detail', or the first of pointscale_detail, pointscale_detail_2, ... the input lacks."""
    return free_names(scan, ("detail",))[0]


NORMAL_NAMES = ("nx", "ny", "nz")


# Formats with room for a vertex scalar of our own; decompose warns that the others leave the detail out.
FORMATS_WITH_VERTEX_SCALARS = (".ply", ".las", ".laz", ".xyz", ".txt", ".asc")
# Formats that store normals as vertex properties named nx, ny, nz (the others, OBJ's vn or
# OFF's NOFF columns, keep them apart from the attributes, which cannot clash with them).
FORMATS_NAMING_NORMALS = (".ply", ".las", ".laz", ".xyz", ".txt", ".asc")


def level_scan(template, points: np.ndarray, normals: np.ndarray, detail, extension: str):
    """`template`'s faces and attributes on new geometry, plus the band's detail as a vertex
    scalar when given (the finest level has none) and the format `extension` can hold it. The
    input's own attributes keep their names and values: the level's normals and detail go under
    other names where the input already uses nx, ny, nz or detail."""
    dtype = np.float64 if np.dtype(template.precision) == np.float64 else np.float32
    names = free_names(template, NORMAL_NAMES) if extension in FORMATS_NAMING_NORMALS else NORMAL_NAMES
    renamed = names != NORMAL_NAMES  # the input keeps its own nx, ny or nz (not a float triple)
    scan = template.with_geometry(points, None if renamed else normals)
    if renamed:
        for axis, name in enumerate(names):
            scan.vertex_attributes[name] = np.asarray(normals[:, axis], dtype=dtype)
    if detail is not None and extension in FORMATS_WITH_VERTEX_SCALARS:
        scan.vertex_attributes[detail_attribute_name(template)] = np.asarray(detail, dtype=dtype)
    return scan
