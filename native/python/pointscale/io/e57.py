"""E57 (ASTM E2807 laser scans) through pye57, an optional dependency: pip install pye57
(or pip install "pointscale[e57]").

Every scan of the file is read with its pose applied (world coordinates) and concatenated; when
the file has more than one scan, vertex attribute scan_id (uint16) says which each point came
from. Intensity (float64) and colours (colorRed/Green/Blue as red, green, blue uint8) are kept.
Written: one scan, intensity and colours; pye57 stores coordinates as float32, so they are
written relative to the bounding-box centre, which becomes the scan's pose translation (error
about 1e-7 of the extent, however far the scan is from the origin). Other attributes and normals
are dropped with a warning. Spherical-coordinate scans are read through pye57's
conversion when it offers one, else refused.
"""
from __future__ import annotations

import os
import warnings

import numpy as np

from .atomic import atomic_write
from .scan import Scan

_COLOURS = (("colorRed", "red"), ("colorGreen", "green"), ("colorBlue", "blue"))


def _pye57(action: str):
    try:
        import pye57
    except ImportError:
        raise ValueError(f"{action} .e57 needs pye57: pip install pye57") from None
    return pye57


def read_e57(path) -> Scan:
    path = os.fspath(path)
    pye57 = _pye57("reading")
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    try:
        e57 = pye57.E57(path)
        try:
            scans = [e57.read_scan(i, intensity=True, colors=True, transform=True, ignore_missing_fields=True)
                     for i in range(e57.scan_count)]
        finally:
            e57.close()
    except Exception as exc:  # libE57 raises E57Exception on damaged files
        raise ValueError(f"{path}: not a readable E57 file ({type(exc).__name__}: {_first_line(exc)})") from None
    if not scans:
        raise ValueError(f"{path}: no scans")
    if any("cartesianX" not in s for s in scans):
        raise ValueError(f"{path}: spherical-coordinate E57 scans are not supported")
    points = np.concatenate([np.column_stack([s["cartesianX"], s["cartesianY"], s["cartesianZ"]]) for s in scans])
    if len(points) == 0:
        raise ValueError(f"{path}: no points")
    if not np.isfinite(points).all():
        raise ValueError(f"{path}: non-finite coordinates")
    attributes = {}
    if all("intensity" in s for s in scans):
        attributes["intensity"] = np.concatenate([s["intensity"] for s in scans]).astype(np.float64)
    if all(field in s for s in scans for field, _ in _COLOURS):
        for field, name in _COLOURS:
            attributes[name] = np.concatenate([s[field] for s in scans]).astype(np.uint8)
    if len(scans) > 1:
        attributes["scan_id"] = np.repeat(np.arange(len(scans), dtype=np.uint16), [len(s["cartesianX"]) for s in scans])
    return Scan(points=points, precision=np.float64, vertex_attributes=attributes,
                format_info={"format": "e57", "scans": len(scans)})


def write_e57(path, scan: Scan) -> None:
    path = os.fspath(path)
    pye57 = _pye57("writing")
    # pye57 stores coordinates as float32: store them around the bounding-box centre and put the
    # centre in the scan's pose, so that coordinates far from the origin keep their precision.
    centre = (scan.points.min(axis=0) + scan.points.max(axis=0)) / 2
    local = scan.points - centre
    _warn_if_single_precision_loses(path, local)
    data = {"cartesianX": local[:, 0].copy(), "cartesianY": local[:, 1].copy(), "cartesianZ": local[:, 2].copy()}
    kept = set()
    if "intensity" in scan.vertex_attributes:
        data["intensity"] = np.asarray(scan.vertex_attributes["intensity"], dtype=np.float64)
        kept.add("intensity")
    if all(name in scan.vertex_attributes for _, name in _COLOURS):
        for field, name in _COLOURS:
            data[field] = _eight_bit(scan.vertex_attributes[name])
        kept |= {name for _, name in _COLOURS}
    dropped = [n for n in scan.vertex_attributes if n not in kept] + (["normals"] if scan.normals is not None else [])
    if dropped:
        warnings.warn(f"{path}: E57 writing keeps intensity and colours only; {', '.join(dropped)} not written",
                      stacklevel=3)
    with atomic_write(path) as temporary:
        os.unlink(temporary)  # libE57 refuses to open an existing file for writing
        try:
            e57 = pye57.E57(str(temporary), mode="w")
            try:
                e57.write_scan_raw(data, rotation=np.array([1.0, 0, 0, 0]), translation=centre)
            finally:
                e57.close()
        except Exception as exc:
            raise ValueError(f"{path}: cannot write E57 ({type(exc).__name__}: {_first_line(exc)})") from None


def _warn_if_single_precision_loses(path, local: np.ndarray) -> None:
    """Single precision keeps about 1e-7 of the whole range: fine for a scan, not for one whose
    range a few far points (outliers, a stray survey mark) stretch. Warns, with the error, when
    the rounding exceeds 1e-6 of the range that 98% of the points span."""
    if len(local) == 0:
        return
    error = float(np.abs(local.astype(np.float32).astype(np.float64) - local).max())
    lo, hi = np.percentile(local, [1, 99], axis=0)
    bulk = float(np.linalg.norm(hi - lo))
    if error > 1e-6 * bulk:
        warnings.warn(f"{path}: E57 stores coordinates in single precision, and far points stretch the range: "
                      f"points are written to within {error:.3g} ({error / bulk:.2g} of the extent of 98% of them); "
                      "PLY or LAS keep them exactly", stacklevel=4)


def _eight_bit(values) -> np.ndarray:
    values = np.asarray(values)
    if values.dtype == np.uint16:
        return (values // 257).astype(np.uint8)
    if values.dtype.kind == "f" and values.max(initial=0) <= 1.0:
        return np.round(values * 255).astype(np.uint8)
    return values.astype(np.uint8)


def _first_line(exc: Exception) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
