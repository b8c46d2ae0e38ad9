"""LAS and LAZ through laspy (LAZ with the lazrs backend).

A LAS file keeps its header's scales, offsets, point format and version, every point record
field (as vertex attributes named as laspy names them: intensity, return_number, classification,
gps_time, red, ...), its extra bytes and its VLRs/EVLRs (the CRS lives there), so that writing
the Scan back gives the same kind of file. Normals, which LAS has no field for, are stored as
extra bytes nx, ny, nz (float32 unless the file had float64). Only float extra bytes nx, ny, nz
are read as normals; others of those names (a lone nx, uint8 nx, ny, nz) are the user's fields.

A Scan from another format is written as LAS 1.4, point format 7 when it has red/green/blue
(8-bit colours are scaled by 257 to LAS's 16 bits, float colours and a float intensity within
0..1 by 65535, rounded) and 6 otherwise; the offset is the bounding
box minimum and the scale the power of ten at or below 1e-6 of the bounding box diagonal, so
coordinates are kept to half of that (e.g. 1e-7 m for a 0.3 m scan, 1 mm for a 2 km site).
Attributes named as a standard field but for case, spaces or underscores (CloudCompare's
Intensity, Classification, ReturnNumber) fill that field, and are read back under its name.
Other attributes become extra bytes with their own dtype.
"""
from __future__ import annotations

import math
import os
import uuid
import warnings

import numpy as np

from .atomic import atomic_write
from .las_checks import check_chunk_table, check_layout
from .optional import optional_module
from .scan import Scan
from .text_tables import FRACTION_SLACK

COORDINATE_FIELDS = ("X", "Y", "Z")
NORMAL_NAMES = ("nx", "ny", "nz")
# Written by laspy itself from the point format and the compression: never copied.
_MANAGED_VLRS = {("LASF_Spec", 4), ("laszip encoded", 22204)}
_COLOURS = ("red", "green", "blue")
_CHUNK_POINTS = 1 << 20


def _laspy():
    return optional_module("laspy", ".las/.laz", "'laspy[lazrs]'")


def read_las(path) -> Scan:
    """Reads a .las or .laz file into a Scan (points in float64 from the scaled integers)."""
    path = os.fspath(path)
    laspy = _laspy()
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    try:
        las = _read_records(laspy, path)
        count = len(las.points)
        points = np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)]).astype(np.float64)
        extra = {d.name: d for d in las.point_format.extra_dimensions}
        attributes = {name: np.array(las[name]) for name in las.point_format.dimension_names
                      if name not in COORDINATE_FIELDS}
        info = _header_info(las, path)
    except ValueError as exc:
        raise ValueError(f"{path}: {_first_line(exc)}") from None
    except Exception as exc:  # laspy, lazrs and numpy errors from damaged files
        hint = " (LAZ needs lazrs: pip install 'laspy[lazrs]')" if "LazBackend" in str(exc) else ""
        raise ValueError(f"{path}: not a readable LAS/LAZ file ({type(exc).__name__}: {_first_line(exc)}){hint}") \
            from None
    if count == 0:
        raise ValueError(f"{path}: no points")
    if not np.isfinite(points).all():
        raise ValueError(f"{path}: non-finite coordinates")
    normals = None
    # Only float extra bytes nx, ny, nz are normals; a lone nx or uint8 nx, ny, nz are the user's
    # own fields, kept unchanged as attributes.
    if all(n in extra and _is_float_scalar(extra[n]) for n in NORMAL_NAMES):
        normals = np.column_stack([attributes.pop(n) for n in NORMAL_NAMES]).astype(np.float64)
        info["normal_type"] = np.dtype(extra["nx"].dtype).str[1:]
    try:
        return Scan(points=points, precision=np.float64, normals=normals, vertex_attributes=attributes,
                    format_info=info)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def _is_float_scalar(dimension) -> bool:
    dtype = np.dtype(dimension.dtype)
    return dtype.kind == "f" and dtype.shape == () and dimension.scales is None and dimension.offsets is None


def _read_records(laspy, path: str):
    """laspy.read, made safe for damaged files: the header's counts and lengths are checked
    against the file first (las_checks), and points are read 1M at a time with lazrs's sequential
    decoder, so that no point count sizes a buffer (lazrs's parallel decoder allocates one for
    all points and aborts the process, not an exception, when that fails)."""
    check_layout(path)
    with laspy.open(path, laz_backend=laspy.LazBackend.Lazrs) as reader:
        header = reader.header
        count = int(header.point_count)
        if header.are_points_compressed:
            check_chunk_table(path, header)
        else:
            room, size = os.path.getsize(path) - int(header.offset_to_point_data), header.point_format.size
            if count * size > room:
                raise ValueError(f"the header says {count} points, the file holds {max(room, 0) // size} (truncated?)")
        arrays, done = [], 0
        while done < count:
            chunk = reader.read_points(min(_CHUNK_POINTS, count - done))
            if len(chunk) == 0:
                break
            arrays.append(chunk.array)
            done += len(chunk)
        if done != count:
            raise ValueError(f"the header says {count} points, the file holds {done} (truncated?)")
        dtype = header.point_format.dtype()
        records = np.concatenate(arrays) if arrays else np.zeros(0, dtype=dtype)
        points = laspy.ScaleAwarePointRecord(records, header.point_format, header.scales, header.offsets)
        return laspy.LasData(header=header, points=points)


def write_las(path, scan: Scan) -> None:
    """Writes a Scan as .las or .laz (by the extension): the source's header when it was LAS,
    else LAS 1.4 with the point format, scale and offset described in the module docstring."""
    path = os.fspath(path)
    laspy = _laspy()
    compress = path.lower().endswith(".laz")
    info = scan.format_info if scan.format_info.get("format") in ("las", "laz") else {}
    attributes = dict(scan.vertex_attributes)
    if info:
        point_format, version = int(info["point_format"]), str(info["version"])
        scales, offsets = np.array(info["scales"], dtype=np.float64), np.array(info["offsets"], dtype=np.float64)
    else:
        point_format = 7 if all(c in attributes for c in _COLOURS) else 6
        version = "1.4"
        scales, offsets = default_scale_offset(scan.points)
    offsets = _offsets_that_fit(scan.points, scales, offsets, path)
    try:
        header = laspy.LasHeader(point_format=point_format, version=version)
        header.scales, header.offsets = scales, offsets
        standard = {d.name: d for d in header.point_format.dimensions
                    if d.is_standard and d.name not in COORDINATE_FIELDS}
        values, extra_params = _fields(scan, attributes, standard, info, laspy, path)
        for params in extra_params:
            header.add_extra_dim(params)
        for key in ("file_source_id", "system_identifier", "generating_software"):
            if key in info:
                setattr(header, key, info[key])
        if "global_encoding" in info:
            header.global_encoding.value = int(info["global_encoding"])
        if "project_guid" in info:
            try:
                header.uuid = uuid.UUID(str(info["project_guid"]))
            except ValueError:
                raise ValueError(f"{path}: project GUID {info['project_guid']!r} is not a GUID") from None
        header.vlrs.extend(_vlr(laspy, v) for v in info.get("vlrs", []))
        from laspy.vlrs.vlrlist import VLRList
        if info.get("evlrs"):
            header.evlrs = VLRList(_vlr(laspy, v) for v in info["evlrs"])
        las = laspy.LasData(header)
        las.x, las.y, las.z = scan.points[:, 0], scan.points[:, 1], scan.points[:, 2]
        for name, column in values.items():
            las[name] = column
    except ValueError:
        raise
    except Exception as exc:
        raise ValueError(f"{path}: cannot write LAS ({type(exc).__name__}: {_first_line(exc)})") from None
    with atomic_write(path) as temporary:
        try:
            las.write(str(temporary), do_compress=compress)
        except Exception as exc:
            raise ValueError(f"{path}: cannot write LAS ({type(exc).__name__}: {_first_line(exc)})") from None


def default_scale_offset(points: np.ndarray):
    """(scales (3,), offsets (3,)) for a new file: offset at the bounding box minimum, scale the
    power of ten at or below 1e-6 of the diagonal (1e-3 for a single point)."""
    low, high = points.min(axis=0), points.max(axis=0)
    diagonal = float(np.linalg.norm(high - low))
    scale = 10.0 ** math.floor(math.log10(diagonal * 1e-6)) if diagonal > 0 else 1e-3
    return np.full(3, scale), low.astype(np.float64)


def _offsets_that_fit(points, scales, offsets, path):
    """offsets, or the bounding box minimum when edited points no longer fit int32 around them."""
    stored = np.round((points - offsets) / scales)
    if np.all(np.abs(stored) <= np.iinfo(np.int32).max):
        return offsets
    new = points.min(axis=0)
    if np.any((points.max(axis=0) - new) / scales > np.iinfo(np.int32).max):
        raise ValueError(f"{path}: the points span more than LAS's int32 range at scale {scales.tolist()}")
    warnings.warn(f"{path}: points moved outside the int32 range around the LAS offset; offset moved to "
                  f"{new.tolist()}", stacklevel=3)
    return new


def _fields(scan: Scan, attributes: dict, standard: dict, info: dict, laspy, path: str = ""):
    """(name -> values for the point records, [ExtraBytesParams] for fields the format lacks)."""
    values, params = {}, []
    declared = {d["name"]: d for d in info.get("extra_dimensions", [])}
    coordinate = [name for name in attributes if name in ("x", "y", "z", "X", "Y", "Z")]
    if coordinate:  # LAS holds the coordinates as X, Y, Z and shows them as x, y, z
        raise ValueError(f"vertex attribute {coordinate[0]!r} clashes with the coordinates (LAS X, Y, Z)")
    if scan.normals is not None:
        clash = [name for name in NORMAL_NAMES if name in attributes]
        if clash:  # the user's own values under those names would be overwritten
            raise ValueError(f"vertex attribute {clash[0]!r} clashes with the normals (extra bytes nx, ny, nz)")
        for i, name in enumerate(NORMAL_NAMES):
            attributes[name] = scan.normals[:, i].astype(info.get("normal_type", "f4"))
    foreign = not info
    if foreign:
        attributes = _standard_names(attributes, standard)
        attributes = _fractions_to_sixteen_bits(attributes, standard, path)
    for name, column in attributes.items():
        column = np.asarray(column)
        if name in standard:
            if foreign and name in _COLOURS and column.dtype == np.uint8:
                column = column.astype(np.uint16) * 257  # 8-bit to LAS's 16-bit colour, 255 -> 65535
            if _fits(column, standard[name]):
                dimension = standard[name]
                if column.dtype.kind == "f" and (dimension.dtype is None or np.dtype(dimension.dtype).kind != "f"):
                    # whole numbers read as floats (a text file's columns) into an integer or bit field
                    column = column.astype(np.uint8 if dimension.dtype is None else dimension.dtype)
                values[name] = column
                continue
            warnings.warn(f"attribute {name!r} ({column.dtype}) does not fit the LAS field; kept as extra "
                          f"bytes {name + '_value'!r}", stacklevel=4)
            name = name + "_value"
        if column.dtype.kind == "b":
            column = column.astype(np.uint8)
        elif column.dtype == np.float16:  # LAS extra bytes have no half floats
            column = column.astype(np.float32)
        if name in declared:
            d = declared[name]
            if not _declared_type_holds(column, d):
                raise ValueError(f"attribute {name!r} ({column.dtype}) does not fit the LAS extra-bytes type "
                                 f"{d['type']!r} its format details declare: its values would change. "
                                 "Write it without those format details, or to a format that keeps it (.ply)")
            params.append(laspy.ExtraBytesParams(name=name, type=d["type"], description=d.get("description", ""),
                                                 scales=d.get("scales"), offsets=d.get("offsets")))
            values[name] = column
        elif column.ndim == 1 or column.shape[1] <= 3:
            kind = column.dtype.str.lstrip("<>=|")
            params.append(laspy.ExtraBytesParams(name=name, type=kind if column.ndim == 1 else f"{column.shape[1]}{kind}"))
            values[name] = column
        else:  # LAS extra bytes hold at most 3 values per field: (n, c) becomes c fields
            for j in range(column.shape[1]):
                params.append(laspy.ExtraBytesParams(name=f"{name}_{j}", type=column.dtype.str.lstrip("<>=|")))
                values[f"{name}_{j}"] = column[:, j]
    for p in params:
        if len(p.name.encode("utf-8")) > 32:  # laspy's own words would not say which attribute
            raise ValueError(f"attribute {p.name!r} is longer than the 32 bytes a LAS extra-bytes name holds: "
                             "rename it, or write a format that keeps it (.ply)")
    return values, params


def _fractions_to_sixteen_bits(attributes: dict, standard: dict, path: str) -> dict:
    """Float colours (judged together, as one colour) and a float intensity within 0..1, as
    renderers and E57 files hold them, scaled to LAS's 16-bit fields: 65535 * value, rounded
    (within FRACTION_SLACK of the range: clipped first), with a warning when that rounds them.
    Floats outside 0..1 are left as they are (whole numbers fill the field, others become
    extra bytes with a warning)."""
    out = dict(attributes)
    groups = [tuple(c for c in _COLOURS if c in standard)]
    if "intensity" in standard:
        groups.append(("intensity",))
    for names in groups:
        if not names or not all(n in out for n in names):
            continue
        columns = [np.asarray(out[n]) for n in names]
        if not any(c.dtype.kind == "f" for c in columns) or any(c.ndim != 1 or c.dtype.kind not in "biuf"
                                                               for c in columns):
            continue
        stacked = np.concatenate(columns).astype(np.float64)
        if stacked.size == 0 or not np.isfinite(stacked).all() or stacked.min() < -FRACTION_SLACK \
                or stacked.max() > 1 + FRACTION_SLACK:
            continue
        scaled = [np.round(np.clip(c.astype(np.float64), 0.0, 1.0) * 65535) for c in columns]
        for n, v in zip(names, scaled):
            out[n] = v.astype(np.uint16)
        if not np.array_equal(np.concatenate(scaled), stacked * 65535):
            what = "colours " + ", ".join(names) if len(names) > 1 else names[0]
            warnings.warn(f"{path}: {what} of 0..1 (float) written to LAS's 16-bit "
                          f"field{'s' if len(names) > 1 else ''} as 65535 * value, rounded (within "
                          f"{0.5 / 65535:.1e} of each value; read back as 0..65535)", stacklevel=5)
    return out


def _plain(name: str) -> str:
    return name.lower().replace("_", "").replace(" ", "")


def _standard_names(attributes: dict, standard: dict) -> dict:
    """Attributes of another format under LAS's standard field names where theirs differ only
    in case, spaces or underscores (CloudCompare's XYZ names Intensity, Classification,
    ReturnNumber...), and the field is not given under its own name too: written into the
    standard fields, as a LAS reader expects them, and read back under those names."""
    by_plain = {_plain(name): name for name in standard}
    out = {}
    for name, column in attributes.items():
        field = by_plain.get(_plain(name))
        if (field is not None and field != name and field not in attributes and field not in out
                and _fits(np.asarray(column), standard[field])):  # else kept as extra bytes of its own name
            out[field] = column
        else:
            out[name] = column
    return out


def _declared_type_holds(column: np.ndarray, declared: dict) -> bool:
    """Whether an extra-bytes field of the declared type ("u1", "3f8"...; scales and offsets
    optional) keeps column's values: unchanged by the type where unscaled, within its range
    where scaled."""
    kind = np.dtype(declared["type"].lstrip("123"))
    if column.dtype.kind not in "biuf":
        return False
    if declared.get("scales") is not None or declared.get("offsets") is not None:
        scales = np.asarray(declared.get("scales") or [1.0], float)
        offsets = np.asarray(declared.get("offsets") or [0.0], float)
        with np.errstate(all="ignore"):
            raw = (column - offsets) / scales
        if kind.kind in "iu":  # stored rounded: 2.55 at scale 0.01 is 255, not 255.00000000000003
            raw = np.rint(raw)
        limits = np.iinfo(kind) if kind.kind in "iu" else np.finfo(kind)
        return bool(np.all(np.isfinite(raw)) and raw.min(initial=0) >= limits.min and raw.max(initial=0) <= limits.max)
    with np.errstate(all="ignore"):
        back = column.astype(kind).astype(column.dtype)
    return bool(np.array_equal(back, column, equal_nan=column.dtype.kind == "f"))


def _fits(column: np.ndarray, dimension) -> bool:
    """Whether column can be stored in a standard LAS field unchanged (bit fields by range)."""
    if column.ndim != 1 or column.dtype.kind not in "biuf":
        return False
    if dimension.dtype is None:  # a bit field such as return_number (3 or 4 bits)
        low, high = 0, 2 ** int(dimension.num_bits) - 1
    else:
        dtype = np.dtype(dimension.dtype)
        if np.can_cast(column.dtype, dtype, "safe"):
            return True
        if dtype.kind == "f":
            return column.dtype.kind in "biu" or column.dtype.itemsize <= dtype.itemsize
        low, high = np.iinfo(dtype).min, np.iinfo(dtype).max
    if column.size == 0:
        return True
    whole = column.dtype.kind != "f" or np.array_equal(column, np.round(column))
    return bool(whole and column.min() >= low and column.max() <= high)


def _header_info(las, path) -> dict:
    h = las.header
    info = {"format": "laz" if path.lower().endswith(".laz") else "las",
            "version": f"{h.version.major}.{h.version.minor}", "point_format": int(h.point_format.id),
            "scales": [float(s) for s in h.scales], "offsets": [float(o) for o in h.offsets],
            "coordinates": "int32 X, Y, Z with x = X * scale + offset",
            "file_source_id": int(h.file_source_id), "global_encoding": int(h.global_encoding.value),
            "system_identifier": str(h.system_identifier), "generating_software": str(h.generating_software),
            # The project GUID names the survey project, which a derived file still belongs to; the
            # creation date is not kept: a level file is created today (PDAL's default too).
            "project_guid": str(h.uuid)}
    info["extra_dimensions"] = [_extra_info(d) for d in las.point_format.extra_dimensions]
    info["vlrs"] = [_vlr_info(v) for v in h.vlrs if (v.user_id, v.record_id) not in _MANAGED_VLRS]
    info["evlrs"] = [_vlr_info(v) for v in (h.evlrs or []) if (v.user_id, v.record_id) not in _MANAGED_VLRS]
    return info


def _extra_info(d) -> dict:
    base = np.dtype(d.dtype).base if np.dtype(d.dtype).shape else np.dtype(d.dtype)
    kind = base.str.lstrip("<>=|")
    return {"name": d.name, "type": kind if d.num_elements == 1 else f"{d.num_elements}{kind}",
            "description": str(d.description or ""),
            "scales": None if d.scales is None else [float(s) for s in np.atleast_1d(d.scales)],
            "offsets": None if d.offsets is None else [float(o) for o in np.atleast_1d(d.offsets)]}


def _vlr_info(v) -> dict:
    data = v.record_data_bytes() if hasattr(v, "record_data_bytes") else bytes(v.record_data)
    return {"user_id": str(v.user_id), "record_id": int(v.record_id), "description": str(v.description),
            "data": bytes(data)}


def _vlr(laspy, v: dict):
    return laspy.VLR(user_id=v["user_id"], record_id=int(v["record_id"]), description=v.get("description", ""),
                     record_data=bytes(v["data"]))


_WKT_RECORD, _GEOKEY_RECORDS = 2112, (34735, 34736, 34737)
_EPSG_KEYS = {3072: "projected", 2048: "geographic", 4096: "vertical"}  # GeoTIFF keys holding an EPSG code


def coordinate_system(info: dict) -> tuple[str, str | None] | None:
    """(a name for it, the line a text or PLY header keeps of it, or None) for the coordinate
    system of a LAS file's format_info (LASF_Projection VLRs or EVLRs: OGC WKT, record 2112, or
    GeoTIFF keys, 34735-34737), or None when it has none. The line is "crs: <the WKT on one line>",
    or "crs: EPSG:<code>" from GeoTIFF keys that give one."""
    if info.get("format") not in ("las", "laz"):
        return None
    records = [v for v in [*info.get("vlrs", []), *info.get("evlrs", [])]
               if isinstance(v, dict) and v.get("user_id") == "LASF_Projection"]
    wkt = [v for v in records if v.get("record_id") == _WKT_RECORD]
    if wkt:
        text = bytes(wkt[0].get("data", b"")).split(b"\0")[0].decode("utf-8", "replace")
        text = " ".join(part.strip() for part in text.splitlines() if part.strip())
        if text:
            quoted = text.split('"')
            return (quoted[1] if len(quoted) > 2 and quoted[1] else text[:60]), f"crs: {text}"
    keys = [v for v in records if v.get("record_id") in _GEOKEY_RECORDS]
    if not keys:
        return None
    codes = _epsg_codes(next((bytes(v.get("data", b"")) for v in keys if v.get("record_id") == 34735), b""))
    citation = next((bytes(v.get("data", b"")) for v in keys if v.get("record_id") == 34737), b"")
    citation = citation.replace(b"\0", b"").decode("utf-8", "replace").strip("| ").split("|")[0].strip()
    epsg = " + ".join(f"EPSG:{c}" for c in codes)
    name = " ".join(p for p in (citation, f"({epsg})" if citation and epsg else epsg) if p) or "GeoTIFF keys"
    return name, (f"crs: {epsg}" if epsg else None)


def _epsg_codes(directory: bytes) -> list:
    """The EPSG codes a GeoKeyDirectory (uint16 header and 4-value entries) gives in place:
    projected, else geographic, and vertical."""
    values = np.frombuffer(directory[:len(directory) // 2 * 2], dtype="<u2")
    count = int(values[3]) if len(values) >= 4 else 0
    entries = values[4:4 + 4 * count]
    found = {}
    for key, location, _, value in entries[:len(entries) // 4 * 4].reshape(-1, 4).tolist():
        if key in _EPSG_KEYS and location == 0 and 0 < value < 32767:
            found[key] = value
    horizontal = found.get(3072, found.get(2048))
    return [c for c in (horizontal, found.get(4096)) if c is not None]


def _first_line(exc: Exception) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
