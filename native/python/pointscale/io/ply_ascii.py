"""ASCII PLY without plyfile's row-by-row loops (38k rows: 0.3 s to read and 3 s to write through
plyfile; 1M rows take minutes). Reading: every element whose rows all have the same number of
values (scalars, or lists of one length, such as triangles) is parsed with one numpy call;
anything else returns None and plyfile's general parser reads the file, and reports its faults.
Writing: one % per chunk of rows; floats with 9 significant digits for float32 and 17 for
float64, which read back to the same value."""
from __future__ import annotations

import io
import io as _io
import warnings

import numpy as np
from plyfile import PlyData, PlyElement, PlyListProperty, PlyProperty

from .ply_header_text import ascii_stand_in, header_line_text
from .text_tables import IntegerOutOfRange, check_integer_range, write_rows

_MAX_HEADER_LINES, _MAX_HEADER_LINE = 100_000, 100_000
_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
          "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
          "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def read_ascii(path: str) -> PlyData | None:
    """The PlyData of an ASCII PLY file, or None when the fast path does not apply."""
    try:
        with open(path, "rb") as f:
            header = []
            while len(header) < _MAX_HEADER_LINES:
                line = f.readline(_MAX_HEADER_LINE)
                if not line or line.strip() == b"end_header":
                    break
                header.append(header_line_text(line, len(header) + 1, path))
                if len(header) == 2 and not line.startswith(b"format ascii"):
                    return None  # binary: plyfile memory-maps it
            else:
                return None
            parsed = _header(header) if line else None
            if parsed is None:
                return None
            body = f.read()
        elements, comments, obj_info = parsed
        line_starts = np.concatenate([[0], np.flatnonzero(np.frombuffer(body, dtype=np.uint8) == 10) + 1])
        out, row = [], 0
        for name, count, properties in elements:
            if count and row >= len(line_starts):
                return None  # fewer lines than the header's counts: plyfile says where it ends
            stop = line_starts[row + count] if row + count < len(line_starts) else len(body)
            block = body[line_starts[row]:stop] if count else b""
            row += count  # a block of fewer rows than count fails the shape check below
            first = block.split(b"\n", 1)[0].decode("ascii").split() if count else []
            layout = _layout(first, properties)
            if layout is None:
                return None
            fields, width = layout
            # All-integer elements (faces) parse as int64, 4x faster than as floats.
            kind = np.int64 if all(np.dtype(t).kind in "iu" for _, t, _, _ in fields) else np.float64
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # "input contained no data": an empty element
                table = np.loadtxt(_io.BytesIO(block), dtype=kind, ndmin=2, comments=None).reshape(-1, width) \
                    if count else np.zeros((0, width))
            if table.shape != (count, width):
                return None
            data = _element_data(table, fields, count)
            if data is None:
                return None
            element = PlyElement(name, [_ply_property(p) for p in properties], count)
            element.data = data
            out.append(element)
    except IntegerOutOfRange:
        raise  # plyfile's parser would wrap the value into its type
    except (OSError, UnicodeDecodeError, ValueError):
        return None  # a malformed row: plyfile's parser names it
    # plyfile holds ASCII comments only: the text beyond it is read apart (ply_header_text.py)
    return PlyData(out, text=True, byte_order="=", comments=[ascii_stand_in(c) for c in comments],
                   obj_info=[ascii_stand_in(c) for c in obj_info])


def write_ascii(path, ply: PlyData, columns: list[dict]) -> None:
    """Writes ply's header, then each element's columns (name -> (count,) or (count, k) array, or
    an object array of index arrays for ragged lists) one row a line."""
    buffer = io.StringIO()
    buffer.write(ply.header + "\n")
    for element in columns:
        if not element:
            continue
        if any(v.dtype == object for v in element.values()):
            _write_ragged(buffer, element)
            continue
        parts, formats = [], []
        for values in element.values():
            if values.ndim == 2:  # a list of fixed length: its length, then its values
                parts.append(np.full((len(values), 1), values.shape[1]))
                formats.append("%d")
            parts.append(values.reshape(len(values), -1))
            formats += [_format(values.dtype)] * parts[-1].shape[1]
        write_rows(buffer, np.column_stack(parts) if len(parts) > 1 else parts[0], " ".join(formats))
    with open(path, "w", encoding="utf-8", newline="\n") as f:  # the rows are ASCII; comments may not be
        f.write(buffer.getvalue())


def _write_ragged(buffer, element: dict) -> None:
    count = len(next(iter(element.values())))
    formats = {k: _format(v.dtype) if v.dtype != object else _format(v[0].dtype if len(v) else np.dtype("i4"))
               for k, v in element.items()}
    for i in range(count):
        fields = []
        for k, v in element.items():
            value = v[i]
            if v.dtype == object or v.ndim == 2:
                value = np.asarray(value)
                fields.append(str(len(value)))
                fields += [formats[k] % x for x in value.tolist()]
            else:
                fields.append(formats[k] % value)
        buffer.write(" ".join(fields) + "\n")


def _format(dtype) -> str:
    dtype = np.dtype(dtype)
    if dtype.kind == "f":
        return "%.9g" if dtype.itemsize <= 4 else "%.17g"
    return "%d"


def _header(lines: list[str]):
    """([(element name, count, [(name, type) or (name, len type, value type)])], comments,
    obj_info), or None for anything plyfile should look at."""
    if len(lines) < 2 or lines[0].strip() != "ply" or lines[1].split()[:2] != ["format", "ascii"]:
        return None
    elements, comments, obj_info = [], [], []
    for line in lines[2:]:
        words = line.split()
        if not words:
            continue
        if words[0] == "comment":
            comments.append(line.strip()[len("comment"):].strip())
        elif words[0] == "obj_info":
            obj_info.append(line.strip()[len("obj_info"):].strip())
        elif words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements and len(words) == 3 and words[1] in _TYPES:
            elements[-1][2].append((words[2], _TYPES[words[1]]))
        elif words[0] == "property" and elements and len(words) == 5 and words[1] == "list" \
                and words[2] in _TYPES and words[3] in _TYPES:
            elements[-1][2].append((words[4], _TYPES[words[2]], _TYPES[words[3]]))
        else:
            return None
    return elements, comments, obj_info


def _layout(first: list, properties: list):
    """([(name, dtype, first column, list length or None)], values a row) from the element's first
    row, or None when it cannot be the row of these properties."""
    fields, position = [], 0
    for p in properties:
        if len(p) == 2:
            fields.append((p[0], p[1], position, None))
            position += 1
            continue
        if not first:  # an empty element: lists of length 0
            fields.append((p[0], p[2], position + 1, 0))
            position += 1
            continue
        try:
            length = int(first[position])
        except (ValueError, IndexError):
            return None
        fields.append((p[0], p[2], position + 1, length))
        position += 1 + length
    if first and position != len(first):
        return None
    return fields, position


def _element_data(table: np.ndarray, fields: list, count: int):
    """The element's rows as plyfile's structured array (lists as fixed-size fields), or None."""
    dtype = [(name, t) if length is None else (name, t, (length,)) for name, t, _, length in fields]
    data = np.empty(count, dtype=dtype)
    for name, t, start, length in fields:
        if length is None:
            values = table[:, start]
        else:
            if not (table[:, start - 1] == length).all():
                return None  # lists of differing lengths
            values = table[:, start:start + length]
        if np.dtype(t).kind in "iu":
            if not np.array_equal(values, np.round(values)):
                return None
            check_integer_range(values, np.dtype(t), name)
        data[name] = values
    return data


def _ply_property(p):
    return PlyProperty(p[0], p[1]) if len(p) == 2 else PlyListProperty(p[0], p[1], p[2])
