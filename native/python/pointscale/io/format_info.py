"""Checks of a Scan's format_info read back from a flat-array file (a decomposition folder's
source.npz), which anyone who shared the folder may have edited.

The writers take these values as the reader gave them: a face index type, a normal type, header
lines. Edited, they would make a writer wrap face indices into uint8, write unit normals as int8
zeros, or add lines to a PLY header, and still succeed. So every value a writer uses must be of
the kind the reader would have given it, and a face index type must hold every vertex index.
Keys a writer does not use are not checked: they cannot change a written file.
"""
from __future__ import annotations

import math
import re
import uuid

import numpy as np

# The integer types a PLY list's count and values may have (PLY has no 64-bit integers).
_PLY_INTEGERS = ("i1", "u1", "i2", "u2", "i4", "u4")
_PLY_FACE_INDEX_NAMES = ("vertex_indices", "vertex_index")
_FLOATS = ("f4", "f8")
_LAS_VERSIONS = ("1.0", "1.1", "1.2", "1.3", "1.4")
_LAS_EXTRA_TYPE = re.compile(r"^[1-3]?(u1|i1|u2|i2|u4|i4|u8|i8|f4|f8)$")
_FORMATS = ("ply", "las", "laz", "obj", "off", "stl", "xyz", "pts", "e57")


def check_format_info(info: dict, n_points: int) -> None:
    """Raises ValueError naming the first value a writer could not use as the reader gave it.
    An info without "format" (a Scan made in Python) is used by no writer and passes."""
    kind = info.get("format")
    if kind is None:
        return
    if kind not in _FORMATS:
        raise ValueError(f"format_info: unknown format {kind!r}")
    if kind == "ply":
        _check_ply(info, n_points)
    elif kind in ("las", "laz"):
        _check_las(info)
    elif kind in ("xyz", "pts", "obj"):
        _check(info, "comments", _single_lines, "a list of texts of one line each (they become comment lines)")
        _check(info, "header_mark", lambda v: v in ("#", "//"), "'#' or '//'")
    elif kind == "e57":
        _check(info, "stations", lambda v: _list_of(v, dict) and all(map(_station, v)),
               "a list of scans (a name of one line, a rotation of 4 numbers not all 0, a translation of 3)")


def _check_ply(info: dict, n_points: int) -> None:
    _check(info, "text", _is_bool, "true or false")
    _check(info, "byte_order", lambda v: v in ("<", ">", "="), "'<', '>' or '='")
    for key in ("comments", "obj_info"):
        _check(info, key, _single_lines, "a list of texts of one line each (they become header lines)")
    for key in ("vertex_properties", "face_properties"):
        _check(info, key, lambda v: _list_of(v, str), "a list of property names")
    _check(info, "list_lengths", lambda v: isinstance(v, dict) and all(
        isinstance(k, str) and t in _PLY_INTEGERS for k, t in v.items()), f"names mapped to one of {_PLY_INTEGERS}")
    _check(info, "normal_dtype", lambda v: v in _FLOATS, f"one of {_FLOATS}")
    index = info.get("face_index")
    if index is None:
        return
    if not isinstance(index, dict) or index.get("name") not in _PLY_FACE_INDEX_NAMES \
            or index.get("len_dtype") not in _PLY_INTEGERS or index.get("val_dtype") not in _PLY_INTEGERS:
        raise ValueError(f"format_info: face_index must name one of {_PLY_FACE_INDEX_NAMES} with count and value "
                         f"types among {_PLY_INTEGERS}, got {index!r}")
    # A type too narrow for the vertices is no error: the PLY writer widens it (io/ply.py).


def _check_las(info: dict) -> None:
    _check(info, "version", lambda v: v in _LAS_VERSIONS, f"one of {_LAS_VERSIONS}")
    _check(info, "point_format", lambda v: _integer(v, 0, 10), "a point format 0..10")
    _check(info, "scales", lambda v: _numbers(v, 3) and all(s > 0 for s in v), "three positive numbers")
    _check(info, "offsets", lambda v: _numbers(v, 3), "three numbers")
    for key in ("file_source_id", "global_encoding"):
        _check(info, key, lambda v: _integer(v, 0, 65535), "an integer 0..65535")
    for key in ("system_identifier", "generating_software"):
        _check(info, key, lambda v: isinstance(v, str) and len(v.encode("utf-8", "replace")) <= 32,
               "a text of up to 32 bytes")
    _check(info, "project_guid", _is_guid, "a GUID")
    _check(info, "normal_type", lambda v: v in _FLOATS, f"one of {_FLOATS}")
    _check(info, "extra_dimensions", lambda v: _list_of(v, dict) and all(map(_extra_dimension, v)),
           "a list of extra-bytes fields (name, type, description, scales, offsets)")
    for key in ("vlrs", "evlrs"):
        _check(info, key, lambda v: _list_of(v, dict) and all(map(_vlr, v)),
               "a list of records (user_id of up to 16 bytes, record_id, description of up to 32 bytes, data bytes)")


def _check(info: dict, key: str, test, expected: str) -> None:
    if key in info and not test(info[key]):
        shown = repr(info[key])
        raise ValueError(f"format_info: {key} must be {expected}, got {shown[:80]}{'...' if len(shown) > 80 else ''}")


def _is_bool(value) -> bool:
    return isinstance(value, bool)


def _integer(value, low: int, high: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and low <= value <= high


def _numbers(value, count: int) -> bool:
    return isinstance(value, list) and len(value) == count and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)


def _list_of(value, kind) -> bool:
    return isinstance(value, list) and all(isinstance(v, kind) for v in value)


def _single_lines(value) -> bool:
    return _list_of(value, str) and not any("\n" in v or "\r" in v for v in value)


def _is_guid(value) -> bool:
    try:
        uuid.UUID(str(value))
    except ValueError:
        return False
    return isinstance(value, str)


def _extra_dimension(d: dict) -> bool:
    scaling = all(d.get(k) is None or (isinstance(d[k], list) and 1 <= len(d[k]) <= 3 and _numbers(d[k], len(d[k])))
                  for k in ("scales", "offsets"))
    return (isinstance(d.get("name"), str) and bool(d["name"]) and isinstance(d.get("type"), str)
            and _LAS_EXTRA_TYPE.match(d["type"]) is not None and isinstance(d.get("description", ""), str) and scaling)


def _vlr(v: dict) -> bool:
    # A LAS record header holds 16 bytes of user id and 32 of description: a longer text would be cut.
    return (isinstance(v.get("user_id"), str) and len(v["user_id"].encode("utf-8", "replace")) <= 16
            and _integer(v.get("record_id"), 0, 65535) and isinstance(v.get("description", ""), str)
            and len(v.get("description", "").encode("utf-8", "replace")) <= 32 and isinstance(v.get("data"), bytes))


def _station(v: dict) -> bool:
    # An E57 scan's name and pose (io/e57.py): the writer puts the points back in this frame.
    name = v.get("name")
    rotation = v.get("rotation")
    return (isinstance(name, str) and bool(name) and "\n" not in name and "\r" not in name
            and _numbers(rotation, 4) and any(r != 0 for r in rotation) and _numbers(v.get("translation"), 3))
