"""OFF (Object File Format, text), parsed with numpy: OFF, COFF, NOFF, CNOFF headers, vertex
normals and colours, polygons of any size and face colours.

trimesh's OFF loader was not used: it drops colours and normals and splits quads into triangles.
Colours are kept as the file has them (integers 0..255 become uint8, floats stay float64) under
red, green, blue[, alpha]. Binary OFF is not supported.
"""
from __future__ import annotations

import io
import os
import warnings

import numpy as np

from .atomic import atomic_write
from .scan import Scan
from .text_tables import face_rows, numbers, polygons, read_text, write_rows

_COLOUR_NAMES = ("red", "green", "blue", "alpha")


def read_off(path) -> Scan:
    path = os.fspath(path)
    keyword, counts, body = _header(path)
    if "BINARY" in body[:1]:
        raise ValueError(f"{path}: binary OFF is not supported")
    nv, nf = counts[0], counts[1]
    if nv <= 0:
        raise ValueError(f"{path}: no vertices")
    if len(body) < nv + nf:
        raise ValueError(f"{path}: the header says {nv} vertices and {nf} faces, the file has {len(body)} lines "
                         "(truncated?)")
    rows = numbers(body[:nv], "vertex", path)
    with_normals = "N" in keyword.replace("OFF", "")
    first_colour = 6 if with_normals else 3
    if rows.shape[1] < first_colour:
        raise ValueError(f"{path}: {keyword} vertex lines need {first_colour} values, got {rows.shape[1]}")
    points = rows[:, :3]
    if not np.isfinite(points).all():
        raise ValueError(f"{path}: non-finite coordinates")
    normals = rows[:, 3:6] if with_normals else None
    attributes = _colours(rows[:, first_colour:], path, "vertex")
    faces, face_attributes = _faces(body[nv:nv + nf], nv, path)
    try:
        return Scan(points=points, precision=np.float64, normals=normals, vertex_attributes=attributes,
                    faces=faces, face_attributes=face_attributes, format_info={"format": "off"})
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def write_off(path, scan: Scan) -> None:
    """Writes [C][N]OFF with %.17g coordinates, vertex and face colours (red, green, blue[, alpha])."""
    path = os.fspath(path)
    columns, formats = [scan.points], ["%.17g"] * 3
    keyword = "OFF"
    if scan.normals is not None:
        columns.append(scan.normals)
        formats += ["%.17g"] * 3
        keyword = "N" + keyword
    colours = _colour_columns(scan.vertex_attributes)
    kept = set(_COLOUR_NAMES) if colours is not None else set()
    dropped = [n for n in scan.vertex_attributes if n not in kept]
    dropped += [n for n in scan.face_attributes if _colour_columns(scan.face_attributes) is None or n not in _COLOUR_NAMES]
    if dropped:
        warnings.warn(f"{path}: OFF has no place for {', '.join(dropped)}; not written", stacklevel=3)
    if colours is not None:
        columns.append(colours)
        formats += ["%d" if colours.dtype.kind in "iu" else "%.17g"] * colours.shape[1]
        keyword = "C" + keyword
    buffer = io.StringIO()
    buffer.write(f"{keyword}\n{scan.n_points} {scan.n_faces} 0\n")
    write_rows(buffer, np.column_stack(columns), " ".join(formats))
    if scan.n_faces:
        lengths, flat = face_rows(scan.faces)
        face_colours = _colour_columns(scan.face_attributes)
        colour_fmt = "" if face_colours is None else \
            " " + " ".join(["%d" if face_colours.dtype.kind in "iu" else "%.17g"] * face_colours.shape[1])
        if isinstance(scan.faces, np.ndarray):
            rows = [np.full((len(lengths), 1), scan.faces.shape[1]), scan.faces]
            if face_colours is not None:
                rows.append(face_colours)
            fmt = " ".join(["%d"] * (1 + scan.faces.shape[1])) + colour_fmt
            write_rows(buffer, np.column_stack(rows), fmt)
        else:
            for i, face in enumerate(scan.faces):
                line = f"{len(face)} " + " ".join(str(int(j)) for j in face)
                if face_colours is not None:
                    line += colour_fmt % tuple(face_colours[i])
                buffer.write(line + "\n")
    with atomic_write(path) as temporary:
        with open(temporary, "w", encoding="utf-8") as f:
            f.write(buffer.getvalue())


def _header(path: str):
    """(keyword such as COFF, [nv, nf, ne], the remaining non-empty lines without comments)."""
    text = read_text(path, "a text OFF file (binary OFF is not supported)")
    lines = [line.split("#", 1)[0].strip() for line in text.splitlines()]
    lines = [line for line in lines if line]
    if not lines or not lines[0].split()[0].upper().endswith("OFF"):
        raise ValueError(f"{path}: not an OFF file (no OFF keyword on the first line)")
    first = lines[0].split()
    keyword, rest = first[0].upper(), first[1:]
    if "ST" in keyword or "4" in keyword:
        raise ValueError(f"{path}: {keyword} (texture or n-dimensional OFF) is not supported")
    body = lines[1:]
    if not rest:
        if not body:
            raise ValueError(f"{path}: no vertex and face counts")
        rest, body = body[0].split(), body[1:]
    try:
        counts = [int(c) for c in rest[:3]]
    except ValueError:
        raise ValueError(f"{path}: the counts line {' '.join(rest)!r} is not integers") from None
    if len(counts) < 2:
        raise ValueError(f"{path}: the counts line needs vertex and face counts")
    return keyword, counts, body


def _faces(lines: list, nv: int, path: str):
    if not lines:
        return None, {}
    try:
        lengths, flat, colours = _uniform_faces(lines)
        if lengths is None:  # mixed polygons: one line at a time
            rows = [np.array(line.split(), dtype=np.float64) for line in lines]
            lengths = np.array([int(r[0]) for r in rows])
            if any(len(r) < 1 + k for r, k in zip(rows, lengths)):
                raise ValueError("a face line has fewer indices than its count")
            flat = np.concatenate([r[1:1 + k] for r, k in zip(rows, lengths)])
            extra = {len(r) - 1 - k for r, k in zip(rows, lengths)}
            colours = np.array([r[1 + k:] for r, k in zip(rows, lengths)]) if len(extra) == 1 \
                else np.zeros((len(rows), 0))
            if len(extra) > 1:
                warnings.warn(f"{path}: face lines carry {'/'.join(map(str, sorted(extra)))} values after their "
                              "indices; not kept (a colour is 3 or 4 values on every face line)", stacklevel=4)
    except (ValueError, OverflowError) as exc:  # OverflowError: a count of inf
        raise ValueError(f"{path}: malformed face lines ({exc})") from None
    if not np.array_equal(flat, np.round(flat)):
        raise ValueError(f"{path}: face indices are not whole numbers")
    if (lengths < 3).any():
        raise ValueError(f"{path}: a face has fewer than 3 corners")
    flat = flat.astype(np.int64)
    if flat.size and (flat.min() < 0 or flat.max() >= nv):
        raise ValueError(f"{path}: faces index vertices {int(flat.min())}..{int(flat.max())}, outside 0..{nv - 1}")
    return polygons(lengths, flat), _colours(colours, path, "face")


def _uniform_faces(lines: list):
    """(lengths, flat indices, colour columns) parsed at once when every face line has the same
    corner count and width (a triangle mesh), else (None, None, None)."""
    width = len(lines[0].split())
    tokens = " ".join(lines).split()
    if len(tokens) != width * len(lines):
        return None, None, None
    table = np.array(tokens, dtype=np.float64).reshape(len(lines), width)
    k = int(table[0, 0])
    if not (table[:, 0] == k).all() or width < 1 + k:
        return None, None, None
    return np.full(len(lines), k), table[:, 1:1 + k].ravel(), table[:, 1 + k:]


def _colours(columns: np.ndarray, path: str, element: str) -> dict:
    """Colour columns (3 or 4) as red, green, blue[, alpha]: uint8 when whole numbers 0..255.
    Any other count of values (a colour-map index) is not kept, with a warning."""
    if columns.shape[1] not in (3, 4):
        if columns.shape[1]:
            warnings.warn(f"{path}: {element} lines carry {columns.shape[1]} values beyond what OFF defines "
                          "(a colour is 3 or 4); not kept", stacklevel=4)
        return {}
    if np.array_equal(columns, np.round(columns)) and columns.min() >= 0 and columns.max() <= 255 \
            and columns.max() > 1:
        columns = columns.astype(np.uint8)
    return {name: columns[:, i].copy() for i, name in enumerate(_COLOUR_NAMES[:columns.shape[1]])}


def _colour_columns(attributes: dict):
    names = [n for n in _COLOUR_NAMES if n in attributes]
    if names[:3] != list(_COLOUR_NAMES[:3]):
        return None
    return np.column_stack([attributes[n] for n in names])
