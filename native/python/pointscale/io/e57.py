"""E57 (ASTM E2807 laser scans) through pye57, an optional dependency: pip install pye57
(or pip install "pointscale[e57]").

Every scan of the file is read with its pose applied (world coordinates) and concatenated; when
the file has more than one scan, vertex attribute scan_id (uint16) says which each point came
from. Every point field pye57 reads is kept: intensity (float64), colours (colorRed/Green/Blue
as red, green, blue uint8) and a structured scan's rowIndex and columnIndex (uint16). A field
that only some scans have is kept for all, filled with 0 in the scans without it, and a warning
names the field and those scans.
Written: intensity, colours, and rowIndex/columnIndex when the scan has both; one E57 scan per
scan_id (several scans read, or a PTS file's blocks), each with the name and pose it was read
with (format_info["stations"]), else named "Scan k" and placed at its centre.
pye57 writes colours as 0..255: 8-bit values are written as they are, also from 16-bit fields
when every value is at most 255 (as many photogrammetry exporters store them in LAS); 16-bit
colours are scaled to 8 bits with a warning. Coordinates are float32 in pye57, so they are
written in the station's own frame, or relative to the bounding-box centre, which becomes the
scan's pose translation (error about 1e-7 of the extent, however far the scan is from the origin). Other attributes and normals
are dropped with a warning. Spherical-coordinate scans are read through pye57's
conversion when it offers one, else refused.
"""
from __future__ import annotations

import os
import warnings

import numpy as np

from .atomic import atomic_write
from .scan import Scan
from .text_tables import eight_bit_colours

_COLOURS = (("colorRed", "red"), ("colorGreen", "green"), ("colorBlue", "blue"))
# The point fields besides coordinates that pye57 reads, by E57 name: (attribute name, dtype).
_FIELDS = {"intensity": ("intensity", np.float64), "colorRed": ("red", np.uint8), "colorGreen": ("green", np.uint8),
           "colorBlue": ("blue", np.uint8), "rowIndex": ("rowIndex", np.uint16),
           "columnIndex": ("columnIndex", np.uint16)}
_GRID = ("rowIndex", "columnIndex")
# What the reader uses: coordinates (spherical ones converted), the fields above, and the
# invalid-state flags, by which pye57 leaves out the points without a return.
_READ = {"cartesianX", "cartesianY", "cartesianZ", "sphericalRange", "sphericalAzimuth", "sphericalElevation",
         "cartesianInvalidState", "sphericalInvalidState", *_FIELDS}


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
            scans = [e57.read_scan(i, intensity=True, colors=True, row_column=True, transform=True,
                                   ignore_missing_fields=True)
                     for i in range(e57.scan_count)]
            unread = sorted({f for i in range(e57.scan_count) for f in e57.get_header(i).point_fields} - _READ)
            stations = [_station(e57.get_header(i), i) for i in range(e57.scan_count)]
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
    if unread:  # timeStamp, the is...Invalid flags: fields pye57's reader does not offer
        warnings.warn(f"{path}: E57 point fields {', '.join(unread)} are not read (pye57 does not read them)",
                      stacklevel=3)
    attributes = _fields_of_every_scan(path, scans)
    if len(scans) > 1:
        attributes["scan_id"] = np.repeat(np.arange(len(scans), dtype=np.uint16), [len(s["cartesianX"]) for s in scans])
    return Scan(points=points, precision=np.float64, vertex_attributes=attributes,
                format_info={"format": "e57", "scans": len(scans), "stations": stations})


def _station(header, index: int) -> dict:
    """A scan's name and pose (rotation quaternion w x y z, translation), as write_e57 puts them
    back; a scan without a pose gets the identity."""
    try:
        name = str(header["name"].value())
    except Exception:  # an unnamed scan
        name = f"Scan {index}"
    rotation, translation = [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    if header.has_pose():
        rotation = [float(v) for v in np.asarray(header.rotation, dtype=np.float64).ravel()]
        translation = [float(v) for v in np.asarray(header.translation, dtype=np.float64).ravel()]
    return {"name": name.splitlines()[0] if name.strip() else f"Scan {index}", "rotation": rotation,
            "translation": translation}


def _fields_of_every_scan(path: str, scans: list) -> dict:
    """Attribute name -> values over all scans, for every field any scan has. A scan without a
    field gets 0 there (no return, black, row 0), said in one warning per set of such scans:
    dropping the field would lose it for the scans that have it, silently."""
    attributes, missing = {}, {}
    for field, (name, dtype) in _FIELDS.items():
        if not any(field in s for s in scans):
            continue
        lacking = tuple(i for i, s in enumerate(scans) if field not in s)
        attributes[name] = np.concatenate([np.asarray(s[field]).astype(dtype) if field in s
                                           else np.zeros(len(s["cartesianX"]), dtype) for s in scans])
        if lacking:
            missing.setdefault(lacking, []).append(name)
    for lacking, names in missing.items():
        which = ", ".join(str(i) for i in lacking)
        warnings.warn(f"{path}: scan{'s' if len(lacking) > 1 else ''} {which} of {len(scans)} "
                      f"{'have' if len(lacking) > 1 else 'has'} no {', '.join(names)}, which the other scans have; "
                      f"filled with 0 there (scan_id tells the scans apart)", stacklevel=4)
    return attributes


def write_e57(path, scan: Scan) -> None:
    path = os.fspath(path)
    pye57 = _pye57("writing")
    fields, kept = _point_fields(path, scan)
    stations = _stations_to_write(scan)
    if stations is not None:
        kept.add("scan_id")
    dropped = [n for n in scan.vertex_attributes if n not in kept] + (["normals"] if scan.normals is not None else [])
    if dropped:
        warnings.warn(f"{path}: E57 writing keeps intensity, colours, rowIndex, columnIndex and the scans (scan_id) "
                      f"only; {', '.join(dropped)} not written", stacklevel=3)
    if stations is None:
        stations = [(np.arange(scan.n_points), None)]
    elif np.any(np.diff(np.concatenate([which for which, _ in stations])) != 1):
        warnings.warn(f"{path}: E57 holds each scan's points together, and here the scans' points (scan_id) are "
                      "interleaved or out of order: the file lists them scan by scan, in another order than the "
                      "scan's (pointscale reconstruct --base puts a level file of this kind back in its "
                      "decomposition's order; other tools pair points by their order)", stacklevel=3)
    with atomic_write(path) as temporary:
        os.unlink(temporary)  # libE57 refuses to open an existing file for writing
        try:
            e57 = pye57.E57(str(temporary), mode="w")
            try:
                for which, station in stations:
                    data, rotation, translation = _scan_in_its_frame(path, scan.points[which], station)
                    data.update({name: values[which] for name, values in fields.items()})
                    e57.write_scan_raw(data, name=station["name"] if station else None, rotation=rotation,
                                       translation=translation)
            finally:
                e57.close()
        except Exception as exc:
            raise ValueError(f"{path}: cannot write E57 ({type(exc).__name__}: {_first_line(exc)})") from None


def _point_fields(path: str, scan: Scan):
    """(E57 field name -> values of every point, the attributes they keep)."""
    fields, kept = {}, set()
    if "intensity" in scan.vertex_attributes:
        fields["intensity"] = np.asarray(scan.vertex_attributes["intensity"], dtype=np.float64)
        kept.add("intensity")
    if all(name in scan.vertex_attributes for _, name in _COLOURS):
        colours, loss = eight_bit_colours({name: scan.vertex_attributes[name] for _, name in _COLOURS}, path)
        for field, name in _COLOURS:
            fields[field] = colours[name]
        kept |= {name for _, name in _COLOURS}
        if loss:
            warnings.warn(f"{path}: E57 (as pye57 writes it) holds 8-bit colours: {loss}", stacklevel=4)
    if _grid_fits(scan):  # a structured scan's row and column, which pye57 stores as uint16
        for name in _GRID:
            fields[name] = np.asarray(scan.vertex_attributes[name]).astype(np.uint16)
        kept |= set(_GRID)
    return fields, kept


def _stations_to_write(scan: Scan):
    """[(point indices, station or None)] for a scan read from several E57 scans (or PTS
    blocks): one scan each, by scan_id, with the name and pose it was read with when the file
    had them; None for a single scan."""
    ids = scan.vertex_attributes.get("scan_id")
    if ids is None or np.asarray(ids).ndim != 1 or np.asarray(ids).dtype.kind not in "iu":
        return None
    ids = np.asarray(ids)
    values = np.unique(ids)
    read = scan.format_info.get("stations") if scan.format_info.get("format") == "e57" else None
    known = isinstance(read, list) and len(read) == len(values) and np.array_equal(values, np.arange(len(values)))
    out = []
    for v in values:
        station = read[int(v)] if known else {"name": f"Scan {int(v)}", "rotation": None, "translation": None}
        out.append((np.flatnonzero(ids == v), station))
    return out


def _scan_in_its_frame(path: str, points: np.ndarray, station):
    """(coordinate fields, rotation, translation): the points in the station's own frame when
    it has a pose, else around their bounding-box centre with that centre as the pose. pye57
    stores coordinates as float32, so either keeps coordinates far from the origin precise."""
    if station is not None and station.get("rotation") is not None:
        rotation = np.asarray(station["rotation"], dtype=np.float64)
        translation = np.asarray(station["translation"], dtype=np.float64)
        local = (points - translation) @ _rotation_matrix(rotation)  # R^T (p - t), row by row
    else:
        translation = (points.min(axis=0) + points.max(axis=0)) / 2
        rotation = np.array([1.0, 0, 0, 0])
        local = points - translation
    _warn_if_single_precision_loses(path, local)
    data = {"cartesianX": local[:, 0].copy(), "cartesianY": local[:, 1].copy(), "cartesianZ": local[:, 2].copy()}
    return data, rotation, translation


def _rotation_matrix(q: np.ndarray) -> np.ndarray:
    """The rotation of the unit quaternion w x y z (E57's pose)."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


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


def _grid_fits(scan: Scan) -> bool:
    """Whether the scan has rowIndex and columnIndex that pye57's uint16 fields hold unchanged."""
    columns = [scan.vertex_attributes.get(name) for name in _GRID]
    if any(c is None or np.asarray(c).ndim != 1 or np.asarray(c).dtype.kind not in "iub" for c in columns):
        return False
    return all(c.size == 0 or (int(c.min()) >= 0 and int(c.max()) <= 65535) for c in map(np.asarray, columns))


def _first_line(exc: Exception) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
