"""PLY through plyfile, binary and ASCII: every vertex and face property kept with its dtype.

Speed: plyfile parses variable-length lists row by row in Python (2.4 s for the dragon's 871k
faces). Triangle meshes are read with known_list_len, which memory-maps the face element as a
fixed-size record, and written as one packed array with the same layout; the general path is
kept for mixed polygons.
"""
from __future__ import annotations

import os
import warnings

import numpy as np
from plyfile import PlyData, PlyElement, PlyListProperty

from .atomic import atomic_write
from .ply_ascii import read_ascii, write_ascii
from .ply_header_text import HeaderAsAscii, ascii_stand_in, non_ascii_header, write_true_header
from .text_tables import IntegerOutOfRange
from .scan import Scan

COORDINATES = ("x", "y", "z")
NORMALS = ("nx", "ny", "nz")
FACE_INDEX_NAMES = ("vertex_indices", "vertex_index")
# Tried in turn: triangles (with the per-corner UVs MeshLab writes with them), then quads. A file
# that does not match fails an attempt cheaply, at its first face of another length.
_FIXED_LISTS = ({"face": {"vertex_indices": 3, "vertex_index": 3, "texcoord": 6}},
                {"face": {"vertex_indices": 4, "vertex_index": 4, "texcoord": 8}})
# The property types PLY has; an attribute in any other dtype is converted on writing.
_PLY_DTYPES = {np.dtype(t) for t in ("i1", "u1", "i2", "u2", "i4", "u4", "f4", "f8")}


def read_ply(path) -> Scan:
    """Reads a binary or ASCII PLY file into a Scan; ValueError naming the file if it is
    missing, damaged, or has no usable vertices."""
    path = os.fspath(path)
    ply, text = _parse(path)
    try:
        scan = _scan_of(ply, path)
    except (KeyError, TypeError, IndexError) as exc:
        raise ValueError(f"{path}: malformed PLY ({exc})") from None
    if text is not None:  # comments beyond ASCII, which plyfile held as stand-ins
        scan.format_info["comments"], scan.format_info["obj_info"] = text[1], text[2]
    return scan


def write_ply(path, scan: Scan, binary: bool | None = None) -> None:
    """Writes a Scan as PLY: coordinates in scan.precision (float32 or float64), every attribute
    with its dtype, triangles as a fixed-size list. binary=None keeps the file's own encoding
    (binary for scans that came from other formats)."""
    path = os.fspath(path)
    info = scan.format_info if scan.format_info.get("format") == "ply" else {}
    text = (not binary) if binary is not None else bool(info.get("text", False))
    byte_order = "=" if text else info.get("byte_order", "<")
    elements = [_vertex_element(scan, info)]
    if scan.n_faces:
        elements.append(_face_element(scan, info))
    comments, obj_info = list(info.get("comments", [])), list(info.get("obj_info", []))
    if scan.format_info.get("format") in ("xyz", "pts", "obj"):  # a text file's comment lines (a CRS, the scanner)
        comments = list(scan.format_info.get("comments", []))
    elif scan.format_info.get("format") in ("las", "laz"):  # its coordinate system, as a comment
        from .text import kept_comments
        comments = kept_comments(scan)
    ply = PlyData([e for e, _, _ in elements], text=text, byte_order=byte_order,
                  comments=[ascii_stand_in(c) for c in comments], obj_info=[ascii_stand_in(c) for c in obj_info])
    with atomic_write(path) as temporary:
        if text:
            write_ascii(temporary, ply, [columns for _, _, columns in elements])
        elif any(packed is None for _, packed, _ in elements):
            ply.write(str(temporary))  # binary with ragged polygons: plyfile's own row-by-row writer
        else:
            with open(temporary, "wb") as f:
                f.write(ply.header.encode("ascii") + b"\n")
                for _, packed, _ in elements:
                    f.write(packed(byte_order).data)
        write_true_header(temporary, ply, comments, obj_info)


# -- reading ----------------------------------------------------------------------------------

def _parse(path: str):
    """(PlyData, non_ascii_header(path)) of the file."""
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    try:
        fast = read_ascii(path)
    except IntegerOutOfRange as exc:
        raise ValueError(f"{path}: {exc}") from None
    text = non_ascii_header(path)  # comments beyond ASCII (ply_header_text.py), or None
    if fast is not None:
        return fast, text
    try:
        for fixed in [*_FIXED_LISTS, None]:
            # Mixed polygons are read by the general parser (fixed None); a damaged file fails
            # there again, and this time its error is reported.
            try:
                with warnings.catch_warnings():
                    # plyfile reads an ASCII list of length 0 with NumPy's loadtxt, which warns of
                    # "no data": an empty list is valid PLY, and the user needs no NumPy words
                    warnings.filterwarnings("ignore", message="loadtxt: input contained no data")
                    if text is None:
                        return PlyData.read(path, known_list_len=fixed or {}), None
                    with HeaderAsAscii(path, text[0]) as stream:
                        return PlyData.read(stream, known_list_len=fixed or {}), text
            except Exception:
                if fixed is None:
                    raise
                # not all triangles (quads), or a damaged file: try the next reading
    except MemoryError:
        raise ValueError(f"{path}: damaged PLY header (element counts too large)") from None
    except Exception as exc:  # plyfile raises PlyParseError, ValueError, struct/IndexError...
        raise ValueError(f"{path}: not a readable PLY file ({type(exc).__name__}: {_first_line(exc)})") from None


def _scan_of(ply: PlyData, path: str) -> Scan:
    names = [e.name for e in ply.elements]
    if "vertex" not in names:
        raise ValueError(f"{path}: no vertex element")
    dropped = [n for n in names if n not in ("vertex", "face")]
    if dropped:
        warnings.warn(f"{path}: PLY elements {', '.join(dropped)} are not kept (only vertex and face)",
                      stacklevel=3)
    vertex = ply["vertex"]
    props = {p.name: p for p in vertex.properties}
    if not set(COORDINATES) <= set(props):
        raise ValueError(f"{path}: vertices have no x, y, z properties")
    listed = [c for c in COORDINATES if isinstance(props[c], PlyListProperty)]
    if listed:
        raise ValueError(f"{path}: vertex property {listed[0]} is a list; x, y and z must be one number each")
    if vertex.count == 0:
        raise ValueError(f"{path}: no vertices")
    data = vertex.data
    precision = np.result_type(*(data[c].dtype for c in COORDINATES))
    precision = precision if precision in (np.float32, np.float64) else np.dtype(np.float64)
    points = np.column_stack([data[c] for c in COORDINATES]).astype(np.float64)
    if not np.isfinite(points).all():
        raise ValueError(f"{path}: {int((~np.isfinite(points).all(axis=1)).sum())} vertices have "
                         "non-finite coordinates")
    normals = None
    info = {"format": "ply", "text": bool(ply.text), "byte_order": ply.byte_order,
            "comments": list(ply.comments), "obj_info": list(ply.obj_info),
            "vertex_properties": [p.name for p in vertex.properties], "list_lengths": {}}
    if _float_triple(data, props, NORMALS):
        normals = np.column_stack([data[c] for c in NORMALS]).astype(np.float64)
        info["normal_dtype"] = _code(np.result_type(*(data[c].dtype for c in NORMALS)))
    skip = set(COORDINATES) | (set(NORMALS) if normals is not None else set())
    vertex_attributes = _properties(vertex, skip, info["list_lengths"], path)

    faces, face_attributes = None, {}
    if "face" in names and ply["face"].count:
        face = ply["face"]
        fprops = {p.name: p for p in face.properties}
        index = next((n for n in FACE_INDEX_NAMES if n in fprops), None)
        if index is None:
            raise ValueError(f"{path}: face element has no vertex_indices list "
                             f"(properties: {', '.join(fprops) or 'none'})")
        if not isinstance(fprops[index], PlyListProperty):
            raise ValueError(f"{path}: face property {index} is not a list")
        if np.dtype(fprops[index].val_dtype).kind not in "iu":
            # Read as integers, 2102.7 would silently become vertex 2102.
            raise ValueError(f"{path}: face property {index} holds {np.dtype(fprops[index].val_dtype).name} "
                             "values; vertex indices must be integers")
        faces = _lists(face.data[index], np.int64)
        info["face_index"] = {"name": index, "len_dtype": _code(fprops[index].len_dtype),
                              "val_dtype": _code(fprops[index].val_dtype)}
        info["face_properties"] = [p.name for p in face.properties]
        face_attributes = _properties(face, {index}, info["list_lengths"], path, prefix="face.")
    try:
        return Scan(points=points, precision=precision, normals=normals, vertex_attributes=vertex_attributes,
                    faces=faces, face_attributes=face_attributes, format_info=info)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def _float_triple(data: np.ndarray, props: dict, names: tuple) -> bool:
    """Whether the vertices have all three of names as float scalars: only then are nx, ny, nz
    the normals. Anything else under those names (a lone nx, int16 quantised normals) is the
    user's data, kept unchanged as vertex attributes; unit normals written into int16 would be 0."""
    return all(n in props and not isinstance(props[n], PlyListProperty) and data[n].dtype.kind == "f"
               for n in names)


def _properties(element, skip: set, list_lengths: dict, path: str, prefix: str = "") -> dict:
    """Every property of the element not in skip, as name -> (count,) or (count, c) array."""
    out = {}
    for p in element.properties:
        if p.name in skip:
            continue
        values = element.data[p.name]
        if isinstance(p, PlyListProperty):
            values = _lists(values, np.dtype(p.val_dtype))
            list_lengths[prefix + p.name] = _code(p.len_dtype)
            if isinstance(values, list):
                if element.name == "face":  # kept as lists (per-corner texcoord on triangles and quads)
                    out[p.name] = [np.array(v, dtype=np.dtype(p.val_dtype).newbyteorder("=")) for v in values]
                    continue
                del list_lengths[prefix + p.name]
                warnings.warn(f"{path}: {element.name} property {p.name} has lists of varying length; not kept",
                              stacklevel=4)
                continue
        # A copy in native byte order: the element may be a memory map of a big-endian file.
        out[p.name] = np.array(values, dtype=np.asarray(values).dtype.newbyteorder("="))
    return out


def _lists(values: np.ndarray, dtype):
    """A list property as (count, k) when every list has k entries, else a list of arrays."""
    if values.dtype != object:
        return np.array(values, dtype=dtype)  # already (count, k): read through known_list_len
    lengths = np.fromiter((len(v) for v in values), dtype=np.int64, count=len(values))
    if len(values) and (lengths == lengths[0]).all():
        return np.stack(values).astype(dtype, copy=False).reshape(len(values), lengths[0])
    return [np.asarray(v, dtype=dtype) for v in values]


# -- writing ----------------------------------------------------------------------------------

def _vertex_element(scan: Scan, info: dict):
    coordinate = scan.precision if scan.precision in (np.float32, np.float64) else np.dtype(np.float64)
    columns = {c: scan.points[:, i].astype(coordinate) for i, c in enumerate(COORDINATES)}
    if scan.normals is not None:
        normal = np.dtype(info.get("normal_dtype", coordinate))
        columns.update({c: scan.normals[:, i].astype(normal) for i, c in enumerate(NORMALS)})
    for name, values in scan.vertex_attributes.items():
        if name in columns:
            raise ValueError(f"vertex attribute {name!r} clashes with the coordinates or normals")
        columns[name] = _ply_values(name, values)
    order = _ordered(columns, info.get("vertex_properties", []))
    return _element("vertex", order, info.get("list_lengths", {}))


def _face_element(scan: Scan, info: dict):
    index = info.get("face_index", {})
    name = index.get("name", "vertex_indices")
    val = np.dtype(index.get("val_dtype", "i4"))
    # The file's own index type (uchar for a small mesh) may not reach this scan's vertices:
    # widen it rather than let astype wrap index 300 to 44.
    if np.iinfo(val).max < scan.n_points - 1:
        val = np.dtype(np.int32 if scan.n_points - 1 <= np.iinfo(np.int32).max else np.uint32)
    if isinstance(scan.faces, np.ndarray):
        faces = scan.faces.astype(val)
    else:
        faces = np.empty(len(scan.faces), dtype=object)
        faces[:] = [f.astype(val) for f in scan.faces]
    columns = {name: faces}
    value_types = {name: val}
    for attr, values in scan.face_attributes.items():
        if attr == name:
            raise ValueError(f"face attribute {attr!r} clashes with the face index list")
        if isinstance(values, list):  # lists of varying length, in one PLY type for all of them
            flat = _ply_values(attr, np.concatenate(values) if values else np.zeros(0, np.float32))
            lists = np.empty(len(values), dtype=object)
            lists[:] = np.split(flat, np.cumsum([len(v) for v in values])[:-1])
            columns[attr] = lists
            value_types[attr] = flat.dtype
        else:
            columns[attr] = _ply_values(attr, values)
    lengths = {name: index.get("len_dtype", "u1")}
    lengths.update({k[len("face."):]: v for k, v in info.get("list_lengths", {}).items() if k.startswith("face.")})
    return _element("face", _ordered(columns, info.get("face_properties", [])), lengths, val_types=value_types)


def _element(name: str, columns: dict, list_lengths: dict, val_types=None):
    """(PlyElement for the header, packer of the binary records or None when lists are ragged,
    the columns themselves for the ASCII writer)."""
    count = len(next(iter(columns.values())))
    ragged = any(v.dtype == object for v in columns.values())
    fields = [(k, object) if v.dtype == object else (k, v.dtype, v.shape[1:]) for k, v in columns.items()]
    data = np.empty(count, dtype=fields)
    for k, v in columns.items():
        data[k] = v
    len_types = {k: _count_type(list_lengths.get(k, "u1"), _longest_list(v))
                 for k, v in columns.items() if v.dtype == object or v.ndim == 2}
    element = PlyElement.describe(data, name, len_types=len_types,
                                  val_types={k: _code(v) for k, v in (val_types or {}).items()})

    def packed(byte_order: str) -> np.ndarray:
        # The on-disk record: each list is its length followed by its k values, with no padding.
        layout = []
        for k, v in columns.items():
            if v.ndim == 2:
                layout.append((k + "\nlen", np.dtype(len_types[k]).newbyteorder(byte_order)))
                layout.append((k, v.dtype.newbyteorder(byte_order), (v.shape[1],)))
            else:
                layout.append((k, v.dtype.newbyteorder(byte_order)))
        records = np.empty(count, dtype=layout)
        for k, v in columns.items():
            if v.ndim == 2:
                records[k + "\nlen"] = v.shape[1]
            records[k] = v
        return records

    return element, (None if ragged else packed), columns


def _count_type(preferred, longest: int) -> str:
    """The list-length type for lists of up to `longest` values: `preferred` (the file's own, or
    uchar) when it holds that count, else the narrowest unsigned type that does. A uchar count of
    300 would be written as 44 and misalign every record after it."""
    preferred = np.dtype(preferred)
    if preferred.kind in "iu" and longest <= np.iinfo(preferred).max:
        return _code(preferred)
    return next(_code(t) for t in (np.uint8, np.uint16, np.uint32) if longest <= np.iinfo(t).max)


def _longest_list(values: np.ndarray) -> int:
    """The most values in one list of a (count, k) array or an object array of ragged lists."""
    if values.dtype != object:
        return values.shape[1]
    return max((len(v) for v in values), default=0)


def _ordered(columns: dict, order: list) -> dict:
    """columns in the file's own property order first, then any new ones."""
    out = {k: columns[k] for k in order if k in columns}
    out.update({k: v for k, v in columns.items() if k not in out})
    return out


def _ply_values(name: str, values: np.ndarray) -> np.ndarray:
    """values in a dtype PLY has: bool -> uint8, 64-bit integers -> 32-bit when they fit, else
    double when exact, float16 -> float32."""
    if not name or any(c.isspace() for c in name) or not name.isascii():
        raise ValueError(f"attribute name {name!r} cannot be a PLY property name (ASCII without spaces)")
    values = np.asarray(values)
    dtype = values.dtype.newbyteorder("=")
    if dtype in _PLY_DTYPES:
        return values
    if dtype.kind == "b":
        return values.astype(np.uint8)
    if dtype.kind in "iu":
        for target in (np.int32, np.uint32) if dtype.kind == "i" else (np.uint32,):
            info = np.iinfo(target)
            if values.size == 0 or (values.min() >= info.min and values.max() <= info.max):
                return values.astype(target)
        if np.abs(values).max() <= 2 ** 53:  # whole numbers a double holds exactly
            warnings.warn(f"attribute {name!r} ({dtype}) exceeds PLY's 32-bit integers; stored as double",
                          stacklevel=5)
            return values.astype(np.float64)
        raise ValueError(f"attribute {name!r} ({dtype}) does not fit PLY's 32-bit integers or a double")
    if dtype.kind == "f":
        return values.astype(np.float64 if dtype.itemsize > 4 else np.float32)
    raise ValueError(f"attribute {name!r} has dtype {dtype}, which PLY cannot store")


def _code(dtype) -> str:
    """'u1', 'i4', 'f8': a dtype as plyfile's type codes, without byte order."""
    return np.dtype(dtype).str[1:]


def _first_line(exc: Exception) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
