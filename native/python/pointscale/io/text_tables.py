"""Shared pieces of the text mesh readers and writers (OBJ, OFF): fast number parsing, faces."""
from __future__ import annotations

import io
import os

import numpy as np


def numbers(lines: list[str], what: str, path: str) -> np.ndarray:
    """The lines as (len(lines), w) float64 when they all have w numbers, else ValueError."""
    if not lines:
        return np.zeros((0, 3))
    tokens = " ".join(lines).split()
    width = len(lines[0].split())
    if width == 0 or len(tokens) != width * len(lines):
        widths = sorted({len(line.split()) for line in lines})
        raise ValueError(f"{path}: {what} lines have differing numbers of values {widths} (truncated?)")
    try:
        return np.array(tokens, dtype=np.float64).reshape(len(lines), width)
    except ValueError:
        raise ValueError(f"{path}: {what} lines hold something that is not a number") from None


def polygons(lengths: np.ndarray, flat: np.ndarray):
    """Faces as (m, k) when all have k corners, else a list of arrays (mixed polygons)."""
    if len(lengths) and (lengths == lengths[0]).all():
        return flat.reshape(len(lengths), int(lengths[0]))
    return np.split(flat, np.cumsum(lengths)[:-1])


def face_rows(faces) -> tuple[np.ndarray, np.ndarray]:
    """(lengths (m,), flat indices) of (m, k) faces or a list of index arrays."""
    if isinstance(faces, np.ndarray):
        return np.full(len(faces), faces.shape[1]), faces.ravel()
    return np.array([len(f) for f in faces]), np.concatenate(faces) if faces else np.zeros(0, np.int64)


def savetxt(buffer: io.StringIO, prefix: str, columns: np.ndarray, fmt: str) -> None:
    """Rows of columns, each line starting with prefix (e.g. "v "), formatted with fmt per value."""
    if len(columns):
        write_rows(buffer, columns, prefix + " ".join([fmt] * columns.shape[1]))


def write_rows(buffer, rows: np.ndarray, row_format: str, chunk: int = 100_000) -> None:
    """rows (n, c) as text, one row_format line each (c % placeholders). Formats a whole chunk
    with one % operation, twice as fast as np.savetxt's row-by-row loop."""
    rows = np.asarray(rows)
    if rows.ndim == 1:
        rows = rows[:, None]
    line = row_format + "\n"
    for start in range(0, len(rows), chunk):
        part = rows[start:start + chunk]
        buffer.write((line * len(part)) % tuple(part.ravel().tolist()))


def colour_for_text(values: np.ndarray) -> np.ndarray:
    """Colours as 0..1 floats for OBJ: 8- and 16-bit integers are divided by 255 or 65535."""
    values = np.asarray(values)
    if values.dtype.kind in "ui":
        return values / float(np.iinfo(values.dtype).max)
    return values.astype(np.float64)


def open_text(path: str, what: str):
    """The text file at `path`, open for reading. A binary file (a NUL byte in its first 64 KB)
    is refused as not `what`. UTF-8 with or without a byte-order mark; a byte that is not UTF-8
    (a Latin-1 accent in a comment) reads as U+FFFD rather than refusing a valid file: in a
    number it still fails to parse, with the row named. ValueError when missing or unreadable."""
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    try:
        with open(path, "rb") as f:
            if b"\0" in f.read(65536):
                raise ValueError(f"{path}: not {what}")
        return open(path, "r", encoding="utf-8-sig", errors="replace")
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc})") from None


def read_text(path: str, what: str) -> str:
    """The whole text file at `path` (open_text)."""
    try:
        with open_text(path, what) as f:
            return f.read()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc})") from None


class IntegerOutOfRange(ValueError):
    """A text value too large for its declared integer type: refused, never wrapped."""


def check_integer_range(values: np.ndarray, dtype: np.dtype, what: str) -> None:
    """Refuses text values that do not fit the declared integer type: a cast would wrap them
    (a face index 2**32 + 2 would become 2, a colour 300 would become 44)."""
    info = np.iinfo(dtype)
    if values.size and (values.min() < info.min or values.max() > info.max):
        raise IntegerOutOfRange(f"{what} is declared {dtype} but holds {values.min():.17g}..{values.max():.17g}, "
                         f"outside {info.min}..{info.max}")


#: How far past 0 or 1 float colours may round and still be read as fractions of 0..1 (clipped).
FRACTION_SLACK = 1e-3


def eight_bit_colours(channels: dict, where: str) -> tuple[dict, str | None]:
    """(name -> uint8 values, a note of what was lost or None) for a format that stores colours
    as 0..255 (PTS, and E57 as pye57 writes it). The channels are judged together, so that they
    stay one colour:
      floats all within 0..1   255 * v, rounded (within FRACTION_SLACK of it: clipped first);
                               the note says so when that changes them;
      all within 0..255        8-bit values, whatever their field's width (many photogrammetry
                               exporters put 8-bit colours in LAS's 16-bit fields): kept
                               exactly (fractions rounded, and the note says so);
      within 0..65535          16-bit colours: 255 * v / 65535, rounded; the note says so.
    Anything else (negative, beyond 16 bits, NaN) is a ValueError naming `where` and the channels."""
    values = {name: np.asarray(v) for name, v in channels.items()}
    names = ", ".join(values)
    stacked = np.concatenate([v.ravel() for v in values.values()]).astype(np.float64)
    top = float(stacked.max(initial=0))
    fractions = (any(v.dtype.kind == "f" for v in values.values()) and np.isfinite(stacked).all()
                 and float(stacked.min(initial=0)) >= -FRACTION_SLACK and top <= 1 + FRACTION_SLACK)
    if fractions:  # a renderer's 0..1 colours, a rounding past either end included
        values = {name: np.clip(v.astype(np.float64), 0.0, 1.0) for name, v in values.items()}
        stacked, top = np.clip(stacked, 0.0, 1.0), min(top, 1.0)
    if stacked.size and (not np.isfinite(stacked).all() or stacked.min() < 0 or top > 65535):
        raise ValueError(f"{where}: colours {names} hold values outside 0..65535 (or not finite); a colour is 0..1, "
                         "0..255 (8-bit) or 0..65535 (16-bit)")
    if fractions:
        scale, what = 255.0, f"colours {names} of 0..1 written as 255 * value, rounded"
    elif top <= 255:
        scale, what = 1.0, f"colours {names} with fractions written rounded to whole numbers"
    else:
        scale, what = 255 / 65535, (f"16-bit colours {names} written as 8-bit (255 * value / 65535, rounded): their "
                                    "low 8 bits are lost; .ply or .las keep them")
    scaled = {name: np.round(v.astype(np.float64) * scale).astype(np.uint8) for name, v in values.items()}
    exact = scale == 1.0 and np.array_equal(stacked, np.round(stacked)) or \
        scale == 255.0 and np.array_equal(stacked * 255, np.round(stacked * 255))
    return scaled, None if exact else what
