"""XYZ and PTS: text, one point a line.

.xyz  x y z [nx ny nz] [more columns], parted by spaces or tabs, or by commas or semicolons as
      the first row is; a line with a single whole number right below the comment lines is
      CloudCompare's point count, checked against the rows. CloudCompare's ASCII clouds (.txt,
      .asc) are read the same way, and written with a header line that starts with "//", the one
      comment mark CloudCompare's reader knows. A comment line "# x y z nx ny nz red:u1 ..." at the top
      (what write_xyz puts first when the scan has attributes; "//X Y Z R G B" from CloudCompare
      works too, also below other comment lines such as a CRS) names the columns and gives their
      dtypes; without it (or when no comment names every column, starting with x y z), columns 4-6 are normals when every row of them has unit length, and other
      columns are kept as float64 attributes column_3, column_4, ... Columns declared as 64-bit
      integers (id:u8, id:i8) are read and written exactly, not through float64; a header that
      names a column twice is refused. Only float (or undeclared) nx ny nz are normals, wherever
      the header puts them (CloudCompare puts them last); they are written as columns 4-6.
      Colours: three columns the header names R G B or red green blue (any case), holding whole
      numbers within 0..255 (or 0..65535), become the attributes red, green, blue as uint8 (or
      uint16), as the PLY and LAS readers give them, so that every writer writes them as colours
      (a header's integer dtype, red:u2, is kept). Colours in a file without a header are not
      guessed: they stay float64 column_3 ... (add the header line to read them as colours).
      The other comment lines at the top (# or //: a CRS, the scanner) are kept in
      format_info["comments"] and written back after the header line, also from a PLY's comments.
.pts  a first line with the point count, then x y z [intensity] [r g b] (Leica/Faro style):
      4 columns are intensity, 6 are colour, 7 are both. Colours are written as 0..255: 16-bit
      ones (above 255, as LAS stores them) are scaled to 8 bits with a warning; intensities are
      written as they are, with a warning when outside Leica's -2048..2047. A file of several scans, each block
      after its own count line, is read whole with vertex attribute scan_id (uint16), and a scan
      whose scan_id is in increasing order is written that way. Comment lines (# or //) above
      the first count line are kept in format_info["comments"] and written into XYZ and PLY
      (not into a .pts: Leica's readers take none).
Coordinates are written with %.17g, which float64 reads back exactly.
"""
from __future__ import annotations

import io
import os
import re
import warnings
from typing import NamedTuple

import numpy as np

from .atomic import atomic_write
from .scan import Scan
from .text_tables import IntegerOutOfRange, check_integer_range, eight_bit_colours, numbers, open_text, write_rows

_HEADER_MARK = "#"
_PTS_COLUMNS = {3: (), 4: ("intensity",), 6: ("red", "green", "blue"), 7: ("intensity", "red", "green", "blue")}


def read_xyz(path) -> Scan:
    path = os.fspath(path)
    comments, rows, layout = _load_xyz(path)
    # The header is the comment line that names the columns, wherever it stands among the
    # comments at the top (a CRS line above it, as some exports write); else the first one.
    naming = [c for c in comments if _names_columns(c, rows.shape[1])]
    header = naming[0] if naming else comments[0] if comments else None
    names_given = header is not None and _names_columns(header, rows.shape[1])
    if names_given:
        names, dtypes = _parse_header(header, rows.shape[1], path)
    else:  # no header, or no comment that names the columns
        for comment in comments:
            _warn_if_header_unread(path, comment, rows.shape[1])
        names, dtypes = _guess_xyz_columns(rows)
    exact = _wide_integer_columns(path, names, dtypes, layout) if names_given else {}
    declared = _declared_columns(header, rows.shape[1]) if names_given else set()
    exact.update(_undeclared_wide_integers(path, rows, names, declared, layout))
    for i, values in exact.items():
        dtypes[i] = values.dtype.str
    if names_given:
        _name_colour_columns(names, dtypes, rows, declared)
    info = {"format": "xyz", "header": bool(names_given)}
    if layout.cloudcompare:  # its levels and results are written for CloudCompare to read too
        info["header_mark"] = "//"
    kept = [c for c in comments if c and not (names_given and c is header)]
    if kept:  # a CRS, the scanner, the date: written back as comment lines (write_xyz), and into PLY
        info["comments"] = kept
    return _scan(path, rows, names, dtypes, info, exact)


# The names a header may give colour columns (CloudCompare writes R G B), lower-cased.
_COLOUR_NAMES = {"r": "red", "red": "red", "g": "green", "green": "green", "b": "blue", "blue": "blue"}
# CloudCompare's float colours (its export's "float colours" option: Rf Gf Bf, 0..1), lower-cased.
_FLOAT_COLOUR_NAMES = {"rf": "red", "gf": "green", "bf": "blue"}


def _name_colour_columns(names: list, dtypes: list, rows: np.ndarray, declared: set) -> None:
    """In place: the three columns a header names R G B or red green blue (any case) become
    red, green, blue, as uint8 when their whole numbers are within 0..255, else uint16 within
    0..65535 (a dtype the header declares stays). Without this, "//X Y Z R G B" gave float64
    attributes R, G, B that no writer knows for colours (LAS wrote a point format without RGB,
    PLY 'property double R'). Colours that are not whole numbers, or a name given twice, stay
    as they are."""
    if _name_float_colour_columns(names, dtypes, rows):
        return
    order = _colour_columns(names, _COLOUR_NAMES)
    if order is None:
        return
    if any(i in declared and np.dtype(dtypes[i]).kind not in "iu" for i in order):
        return  # declared floats (0..1 colours, or anything else): the header's word
    values = rows[:, order]
    if not (np.array_equal(values, np.round(values)) and values.min() >= 0 and values.max() <= 65535):
        return
    width = np.dtype(np.uint8 if values.max() <= 255 else np.uint16).str
    for i, colour in zip(order, ("red", "green", "blue")):
        names[i] = colour
        if i not in declared:
            dtypes[i] = width


def _colour_columns(names: list, colour_names: dict) -> list | None:
    """The columns (red, green, blue) that `colour_names` (lower-case name -> colour) finds after
    x y z, each once; None unless all three are there, once each."""
    columns = {}
    for i, name in enumerate(names[3:], start=3):
        colour = colour_names.get(name.lower())
        if colour is not None:
            columns.setdefault(colour, []).append(i)
    if sorted(columns) != ["blue", "green", "red"] or any(len(c) != 1 for c in columns.values()):
        return None
    return [columns[c][0] for c in ("red", "green", "blue")]


def _name_float_colour_columns(names: list, dtypes: list, rows: np.ndarray) -> bool:
    """In place: CloudCompare's float colour columns Rf Gf Bf (within 0..1) become red, green,
    blue as float64, which the LAS writer scales to its 16 bits like any float colour. Whether
    it named them."""
    order = _colour_columns(names, _FLOAT_COLOUR_NAMES)
    if order is None:
        return False
    values = rows[:, order]
    if any(np.dtype(dtypes[i]).kind != "f" for i in order) or not (values.min() >= 0.0 and values.max() <= 1.0):
        return False
    if any(c in names for c in ("red", "green", "blue")):  # the file has those names already
        return False
    for i, colour in zip(order, ("red", "green", "blue")):
        names[i] = colour
    return True


def _declared_columns(header: str, ncols: int) -> set:
    """The columns whose dtype the header gives (name:dtype)."""
    return {i for i, token in enumerate(_header_tokens(header, ncols) or []) if ":" in token}


def _undeclared_wide_integers(path: str, rows: np.ndarray, names: list, declared: set, layout: "_Layout") -> dict:
    """Column index -> exact values of undeclared columns of whole numbers beyond 2**53 (ids,
    timestamps in ns), which the float64 rows hold only rounded: read again as text and kept as
    int64 (uint64 past its range). A column written with a decimal point or an exponent stays
    float64, as written."""
    wide = [i for i in range(3, rows.shape[1]) if i not in declared and names[i] not in ("nx", "ny", "nz")
            and np.all(rows[:, i] == np.round(rows[:, i])) and np.abs(rows[:, i]).max() >= 2.0 ** 53]
    if not wide:
        return {}
    texts = _text_columns(path, wide, layout)
    out = {}
    for j, i in enumerate(wide):
        try:
            values = [int(text) for text in texts[:, j].tolist()]
        except ValueError:
            continue
        low, high = min(values), max(values)
        dtype = np.int64 if low >= -2 ** 63 and high < 2 ** 63 else np.uint64 if low >= 0 and high < 2 ** 64 else None
        if dtype is not None:
            out[i] = np.array(values, dtype=dtype)
    return out


def read_pts(path) -> Scan:
    path = os.fspath(path)
    rows, blocks, comments = _pts_rows(path)
    extra = _PTS_COLUMNS.get(rows.shape[1])
    if extra is None:
        raise ValueError(f"{path}: .pts rows have 3, 4, 6 or 7 columns, got {rows.shape[1]}")
    names = ["x", "y", "z", *extra]
    dtypes = ["f8"] * 3 + [_integer_dtype(rows[:, 3 + i], name) for i, name in enumerate(extra)]
    comments = [c for c in comments if c]
    info = {"format": "pts"}
    if comments:  # written back into XYZ and PLY; Leica's readers take none in a .pts
        info["comments"] = comments
    scan = _scan(path, rows, names, dtypes, info)
    if len(blocks) > 1:  # several scans, each after its own count line
        scan.vertex_attributes["scan_id"] = np.repeat(np.arange(len(blocks), dtype=np.uint16), blocks)
    return scan


def _pts_rows(path: str):
    """(rows (n, c) float64, points per block): one count line and its rows, or several in turn."""
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    comments = []
    try:
        first, rows = _load_pts(path, leading=comments)
    except ValueError as exc:
        single = exc  # a second count line makes loadtxt fail: try blocks
    else:
        try:
            count = int(first.split()[0])
        except (ValueError, IndexError, AttributeError):
            raise ValueError(f"{path}: a .pts file starts with its point count, got {first.strip()[:40]!r}") from None
        if count != len(rows):
            raise ValueError(f"{path}: the count line says {count} points, the file has {len(rows)} (truncated?)")
        return rows, [count], comments
    try:
        with open_text(path, "a text file") as f:
            lines = [line for line in f.read().splitlines() if line.strip()]
    except (OSError, ValueError):
        raise single from None
    lines = lines[len(comments):]  # the comment lines above the first count line
    parts, blocks, i = [], [], 0
    while i < len(lines):
        if lines[i].lstrip().startswith(("#", "//")):  # a comment above a later block's count line
            comment = lines[i].lstrip().lstrip("#/").strip()
            if comment:
                comments.append(comment)
            i += 1
            continue
        words = lines[i].split()
        if len(words) != 1 or not words[0].isdigit():
            raise single
        count = int(words[0])
        block = lines[i + 1:i + 1 + count]
        if len(block) < count:
            raise ValueError(f"{path}: block {len(blocks)} says {count} points, the file has {len(block)} (truncated?)")
        parts.append(numbers(block, f"block {len(blocks)}", path))
        blocks.append(count)
        i += 1 + count
    if len({p.shape[1] for p in parts if len(p)}) > 1:
        raise ValueError(f"{path}: the blocks have different numbers of columns")
    rows = np.concatenate([p for p in parts if len(p)]) if any(len(p) for p in parts) else np.zeros((0, 3))
    if len(rows) == 0:
        raise ValueError(f"{path}: no vertices")
    return rows, blocks, comments


def write_xyz(path, scan: Scan) -> None:
    """An .xyz; its header line starts with "//" where the scan was read from a CloudCompare-style
    file (a .txt or .asc, or "//" comment lines), "#" otherwise."""
    info = scan.format_info
    mark = "//" if info.get("format") == "xyz" and info.get("header_mark") == "//" else _HEADER_MARK
    _write_xyz(path, scan, mark, always_header=False)


def write_cloudcompare(path, scan: Scan) -> None:
    """A .txt or .asc: XYZ's columns under a header line that is always there and starts with
    "//", the one comment mark CloudCompare's ASCII reader knows ("#" lines it takes for rows)."""
    _write_xyz(path, scan, "//", always_header=True)


def _write_xyz(path, scan: Scan, mark: str, always_header: bool) -> None:
    names, columns, formats = _columns(scan, normals=True)
    spaced = [n for n in names if not n or any(c.isspace() or c in ",:" for c in n)]
    if spaced:  # the header is split on whitespace and commas, and ":" starts the dtype
        warnings.warn(f"{path}: column names {spaced} written with '_' for spaces, commas and colons", stacklevel=3)
        names = ["".join("_" if c.isspace() or c in ",:" else c for c in n) or "column" for n in names]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:  # read back, one of the two columns would be lost (an attribute nx beside the normals)
        raise ValueError(f"column names {twice} would appear twice in the header")
    header = None
    if always_header or len(names) > (6 if scan.normals is not None else 3):
        header = " ".join(f"{n}:{c.dtype.str.lstrip('<>=|')}" if i >= 3 else n
                          for i, (n, c) in enumerate(zip(names, columns)))
    _write(path, _rows(columns) if columns else None, formats, header=header, count=None,
           comments=kept_comments(scan), mark=mark)


def write_pts(path, scan: Scan) -> None:
    columns = [scan.points[:, i] for i in range(3)]
    formats = ["%.17g"] * 3
    if "intensity" in scan.vertex_attributes:
        intensity = scan.vertex_attributes["intensity"]
        _warn_if_outside_pts_intensity(path, intensity)
        columns.append(intensity)
        formats.append(_format(intensity))
    if all(c in scan.vertex_attributes for c in ("red", "green", "blue")):
        colours, loss = eight_bit_colours({c: scan.vertex_attributes[c] for c in ("red", "green", "blue")}, path)
        if loss:
            warnings.warn(f"{path}: .pts holds 8-bit colours: {loss}", stacklevel=3)
        for c in ("red", "green", "blue"):
            columns.append(colours[c])
            formats.append("%d")
    kept = {"intensity", "red", "green", "blue"}
    ids = scan.vertex_attributes.get("scan_id")
    counts = [scan.n_points]
    if ids is not None and ids.ndim == 1 and np.all(np.diff(ids.astype(np.int64)) >= 0):
        # Points in scan order: one block (count line and rows) per scan, as Leica/Faro write them.
        counts = np.unique(ids, return_counts=True)[1].tolist()  # sorted ids: counts in file order
        kept.add("scan_id")
    dropped = [n for n in scan.vertex_attributes if n not in kept] + (["normals"] if scan.normals is not None else [])
    if dropped:
        warnings.warn(f"{path}: .pts has no room for {', '.join(dropped)}; not written", stacklevel=3)
    _write(path, _rows(columns), formats, header=None, count=counts)


# Leica's PTS intensity range, which Cyclone and ReCap expect; other readers take any number.
_PTS_INTENSITY = (-2048, 2047)


def _warn_if_outside_pts_intensity(path: str, intensity) -> None:
    """Intensities are written as they are (a LAS file's 0..65535 too): scaling them would change
    the user's numbers for every reader, and most readers (CloudCompare, ours) take any. Says so
    when they lie outside Leica's -2048..2047, which some readers clip."""
    values = np.asarray(intensity)
    if values.size and (values.min() < _PTS_INTENSITY[0] or values.max() > _PTS_INTENSITY[1]):
        warnings.warn(f"{path}: intensity {values.min():.17g}..{values.max():.17g} written as it is, outside "
                      f"Leica's PTS range {_PTS_INTENSITY[0]}..{_PTS_INTENSITY[1]} that some readers (Cyclone, "
                      "ReCap) expect", stacklevel=4)


# -- helpers ----------------------------------------------------------------------------------

def _load_pts(path: str, leading: list):
    """(the count line, rows (n, c) float64) of a PTS file of one block; the comment lines above
    the count line are put into `leading`."""
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    try:
        with open_text(path, "a text file") as f:
            leading.extend(_leading_comments(f))
            header = f.readline()
            rows = _rows_of(f, delimiter=None, comments=None)
    except ValueError as exc:
        _raise_unreadable(path, exc)
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc})") from None
    _check_rows(path, rows)
    return header, rows


class _Layout(NamedTuple):
    """How an XYZ file's rows are laid out: the lines above them (comment lines, and a count line
    where there is one), what parts their values (None: spaces or tabs), and whether the file
    comes from CloudCompare's world (a .txt or .asc, or a first line starting with "//", the one
    comment mark CloudCompare's ASCII reader knows)."""
    skip: int
    delimiter: str | None
    cloudcompare: bool


def _load_xyz(path: str):
    """(the comment lines' texts, rows (n, c) float64, _Layout). Besides spaces and tabs, the
    values may be parted by commas or semicolons, as CloudCompare's ASCII export offers (told
    from the first row, as CloudCompare's reader tells it); a line holding a single whole number
    right below the comment lines is CloudCompare's point count, checked against the rows."""
    if not os.path.isfile(path):
        raise ValueError(f"no such file: {path}")
    count = None
    try:
        with open_text(path, "a text file") as f:
            cloudcompare = (os.path.splitext(path)[1].lower() in (".txt", ".asc")
                            or f.readline().lstrip().startswith("//"))
            f.seek(0)
            comments = _leading_comments(f)
            where = f.tell()
            first = f.readline()
            words = first.split()
            if len(words) == 1 and words[0].isdigit():
                count = int(words[0])
                where = f.tell()
                first = f.readline()
            f.seek(where)
            delimiter = _delimiter(first)  # the first row's
            rows = _rows_of(f, delimiter=delimiter, comments="#")
    except ValueError as exc:
        _raise_unreadable(path, exc)
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc})") from None
    _check_rows(path, rows)
    if count is not None and count != len(rows):
        raise ValueError(f"{path}: the count line says {count} points, the file has {len(rows)}"
                         f"{' (truncated?)' if len(rows) < count else ''}")
    return comments, rows, _Layout(len(comments) + (count is not None), delimiter, cloudcompare)


def _delimiter(line: str) -> str | None:
    """What parts the values of a row: None (spaces or tabs), or "," or ";" where the row parted
    at it gives three numbers or more and parted at spaces does not. A comma as decimal mark
    ("1,5;2,25;3") is none of these: the row then stays unreadable, with the hint that says so."""
    def all_numbers(parts):
        try:
            for p in parts:
                float(p)
        except ValueError:
            return False
        return len(parts) >= 3
    if all_numbers(line.split()):
        return None
    for mark in (",", ";"):
        if all_numbers([p.strip() for p in line.split(mark)]):
            return mark
    return None


def _rows_of(f, delimiter: str | None, comments: str | None) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "input contained no data": reported below as no vertices
        return np.loadtxt(f, dtype=np.float64, ndmin=2, comments=comments, delimiter=delimiter)


def _raise_unreadable(path: str, exc: ValueError):
    if str(exc).startswith(path):  # open_text's own words
        raise exc
    # NumPy's advice names its own options (usecols), not the file's: left out.
    reason = re.sub(r";\s*use `usecols`.*$", "", _first_line(exc))
    raise ValueError(f"{path}: unreadable row ({reason}){_unreadable_hint(str(exc))}") from None


def _check_rows(path: str, rows: np.ndarray) -> None:
    if rows.size == 0:
        raise ValueError(f"{path}: no vertices")
    if rows.shape[1] < 3:
        raise ValueError(f"{path}: rows need at least x y z, got {rows.shape[1]} columns")


def _unreadable_hint(error: str) -> str:
    """What a row NumPy could not read usually means: commas as decimal marks, or values parted
    otherwise than the first row's, or column names on a first line with no comment mark."""
    found = re.search(r"could not convert string '([^']*)'", error) or re.search(r"string '([^']*)'", error)
    text = found.group(1) if found else ""
    if "," in text or ";" in text:
        return (": values are parted by spaces, tabs, commas or semicolons, the same on every row as on the first, "
                "and need a decimal point (a decimal comma is not read)")
    if text[:1].isalpha() and re.search(r"\bat row 0\b", error):
        return ": a first line of column names must start with # or // (as '//X Y Z R G B')"
    return ""


def _leading_comments(f) -> list:
    """The texts of the comment lines (# or //) at the top of the file, marks stripped; f is left
    at the first line of numbers."""
    found = []
    while True:
        where = f.tell()
        line = f.readline()
        if not line or not line.lstrip().startswith((_HEADER_MARK, "//")):
            f.seek(where)
            return found
        found.append(line.lstrip().lstrip("#/").strip())


def _header_words(header: str) -> list:
    """A header line's words, parted by spaces, tabs, commas or semicolons."""
    return header.replace(",", " ").replace(";", " ").split()


def _header_tokens(header: str, ncols: int) -> list | None:
    """The names a first comment line gives the columns, or None: its words (split at spaces,
    tabs, commas and semicolons), or, when those are too many and commas or semicolons part them
    into as many as the columns (CloudCompare's "//X,Y,Z,R,G,B,GPS Time", which parts the names
    as it parts the values), the names so parted, spaces as "_"."""
    tokens = _header_words(header)
    if len(tokens) == ncols:
        return tokens
    for mark in (",", ";"):
        if mark in header:
            parted = [t.strip().replace(" ", "_") for t in header.split(mark)]
            if len(parted) == ncols and all(parted):
                return parted
    return None


def _starts_with_xyz(tokens: list) -> bool:
    return [t.partition(":")[0].lower() for t in tokens[:3]] == ["x", "y", "z"]


def _names_columns(header: str, ncols: int) -> bool:
    """Whether a first comment line names the columns: as many names as columns, from x y z."""
    tokens = _header_tokens(header, ncols)
    return tokens is not None and _starts_with_xyz(tokens)


def _warn_if_header_unread(path: str, header: str, ncols: int) -> None:
    """A first line that starts x y z but names more or fewer columns than the rows have (a
    name with a space in it, "GPS Time") names none of them: say so, not drop the names."""
    words = _header_words(header)
    if _starts_with_xyz(words):
        warnings.warn(f"{path}: the header line names {len(words)} columns but the rows have {ncols}, so its names "
                      f"are not used (columns after z are read as column_3 ... and no colours): a column name "
                      f"with a space in it? Write it without spaces, or part the names with commas", stacklevel=3)


def _parse_header(header: str, ncols: int, path: str):
    tokens = _header_tokens(header, ncols)
    if tokens is None:
        raise ValueError(f"{path}: the header names {len(_header_words(header))} columns, the rows have {ncols}")
    names, dtypes = [], []
    for token in tokens:
        name, _, dtype = token.partition(":")
        names.append(name.lower() if name.lower() in ("x", "y", "z", "nx", "ny", "nz") else name)
        try:
            dtypes.append(np.dtype(dtype or "f8").str)
        except TypeError:
            raise ValueError(f"{path}: header column {token!r} has an unknown dtype") from None
    if names[:3] != ["x", "y", "z"]:
        raise ValueError(f"{path}: the header must start with x y z, got {' '.join(tokens[:3])}")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:  # one name, one attribute: the second column would replace the first
        raise ValueError(f"{path}: the header names the columns {', '.join(twice)} more than once")
    return names, dtypes


def _wide_integer_columns(path: str, names: list, dtypes: list, layout: "_Layout") -> dict:
    """Column index -> exact values of the columns declared as 64-bit integers (id:u8). The rows
    are parsed as float64, which holds integers only up to 2**53: 2**60 + 1 would be read as
    2**60. These columns are read again as text and converted by Python's own integers."""
    wide = [i for i, d in enumerate(dtypes) if np.dtype(d).kind in "iu" and np.dtype(d).itemsize > 4]
    if not wide:
        return {}
    texts = _text_columns(path, wide, layout)
    return {i: _exact_integers(texts[:, j], np.dtype(dtypes[i]), f"column {names[i]}", path)
            for j, i in enumerate(wide)}


def _text_columns(path: str, columns: list, layout: "_Layout") -> np.ndarray:
    """The rows' values in `columns` as the text the file holds, past its header lines."""
    with open_text(path, "a text file") as f:
        for _ in range(layout.skip):
            f.readline()
        return np.loadtxt(f, dtype=str, comments="#", delimiter=layout.delimiter, usecols=columns, ndmin=2)


def _exact_integers(texts: np.ndarray, dtype: np.dtype, what: str, path: str) -> np.ndarray:
    """texts as dtype, exactly; a value outside dtype's range or not a whole number is refused."""
    values = []
    for text in texts.tolist():
        try:
            values.append(int(text))
        except ValueError:  # 1.0 or 1e3: whole numbers written as floats, exact up to 2**53
            number = float(text)
            if not (number.is_integer() and abs(number) <= 2 ** 53):
                raise ValueError(f"{path}: {what} is declared {dtype} but holds {text}") from None
            values.append(int(number))
    info = np.iinfo(dtype)
    low, high = min(values), max(values)
    if low < info.min or high > info.max:
        raise IntegerOutOfRange(f"{path}: {what} is declared {dtype} but holds {low}..{high}, "
                                f"outside {info.min}..{info.max}")
    return np.array(values, dtype=dtype)


def _guess_xyz_columns(rows: np.ndarray):
    ncols = rows.shape[1]
    names = ["x", "y", "z"]
    if ncols >= 6 and np.all(np.abs(np.linalg.norm(rows[:, 3:6], axis=1) - 1) < 1e-3):
        names += ["nx", "ny", "nz"]
    names += [f"column_{i}" for i in range(len(names), ncols)]
    return names, ["f8"] * ncols


def _scan(path, rows, names, dtypes, info, exact: dict | None = None) -> Scan:
    """The Scan of the rows; `exact` gives the values of columns (by index) that float64 rows
    cannot hold exactly (64-bit integers)."""
    points = rows[:, :3]
    if not np.isfinite(points).all():
        raise ValueError(f"{path}: {int((~np.isfinite(points).all(axis=1)).sum())} points have non-finite coordinates")
    # The columns named nx ny nz are the normals when declared float (or not declared), wherever
    # they stand (CloudCompare writes them after the colours and scalar fields); integer ones
    # (quantised normals) are the user's data, kept as attributes.
    normals = None
    where = [names.index(n) if n in names else -1 for n in ("nx", "ny", "nz")]
    if min(where) >= 3 and all(np.dtype(dtypes[i]).kind == "f" for i in where):
        normals = rows[:, where]
    attributes = {}
    for i, (name, dtype) in enumerate(zip(names, dtypes)):
        if name in ("x", "y", "z") or (normals is not None and name in ("nx", "ny", "nz")):
            continue
        if exact and i in exact:
            attributes[name] = exact[i]
            continue
        values = rows[:, i]
        dtype = np.dtype(dtype)
        if dtype.kind in "iub" and not np.array_equal(values, np.round(values)):
            raise ValueError(f"{path}: column {name} is declared {dtype} but holds fractions")
        if dtype.kind in "iu":
            try:
                check_integer_range(values, dtype, f"column {name}")
            except ValueError as exc:
                raise ValueError(f"{path}: {exc}") from None
        attributes[name] = values.astype(dtype)
    try:
        return Scan(points=points, precision=np.float64, normals=normals, vertex_attributes=attributes,
                    format_info=info)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def _integer_dtype(values: np.ndarray, name: str) -> str:
    """PTS intensity and colours are integers (colours 0..255) in most files; floats are kept."""
    if not np.array_equal(values, np.round(values)):
        return "f8"
    if name in ("red", "green", "blue") and values.min() >= 0 and values.max() <= 255:
        return "u1"
    return "i4"


def _columns(scan: Scan, normals: bool):
    names, columns, formats = ["x", "y", "z"], [scan.points[:, i] for i in range(3)], ["%.17g"] * 3
    if normals and scan.normals is not None:
        names += ["nx", "ny", "nz"]
        columns += [scan.normals[:, i] for i in range(3)]
        formats += ["%.17g"] * 3
    for name, values in scan.vertex_attributes.items():
        values = np.asarray(values)
        if values.ndim == 2:  # (n, c): one column each, name_0 .. name_{c-1}
            for j in range(values.shape[1]):
                names.append(f"{name}_{j}")
                columns.append(values[:, j])
                formats.append(_format(values))
        else:
            names.append(name)
            columns.append(values)
            formats.append(_format(values))
    return names, columns, formats


def _rows(columns: list) -> np.ndarray:
    """The columns side by side, as float64, or as Python numbers when a 64-bit integer column
    holds values float64 would round (above 2**53): %d then writes them exactly."""
    def rounded(c) -> bool:
        c = np.asarray(c)
        return c.dtype.kind in "iu" and c.dtype.itemsize > 4 and c.size > 0 and (
            int(c.max()) > 2 ** 53 or int(c.min()) < -2 ** 53)
    if any(rounded(c) for c in columns):
        return np.column_stack([np.asarray(c).astype(object) for c in columns])
    return np.column_stack(columns)


def _format(values: np.ndarray) -> str:
    return "%d" if np.asarray(values).dtype.kind in "iub" else "%.17g"


def kept_comments(scan: Scan) -> list:
    """The comment lines a scan was read with that a text or PLY header can hold: an XYZ, PTS or
    OBJ file's comment lines, a PLY header's comments and obj_info lines (as "obj_info ..."), a
    LAS file's coordinate system ("crs: <WKT on one line>", las.coordinate_system)."""
    info = scan.format_info
    if info.get("format") in ("las", "laz"):  # its coordinate system, as one line
        from .las import coordinate_system
        crs = coordinate_system(info)
        return [crs[1]] if crs and crs[1] else []
    if info.get("format") not in ("xyz", "ply", "pts", "obj"):
        return []
    lines = list(info.get("comments", [])) + [f"obj_info {c}" for c in info.get("obj_info", [])]
    return [c for c in lines if isinstance(c, str)]


def _write(path: str, rows: np.ndarray, formats: list, header: str | None, count: list | None,
           comments: list = (), mark: str = _HEADER_MARK) -> None:
    """rows under an optional header line and comment lines (starting with `mark`); with count
    (points per block), each block of rows after a line with its count (PTS)."""
    buffer = io.StringIO()
    if header is not None:
        buffer.write(f"{mark}{' ' if mark == _HEADER_MARK else ''}{header}\n")
    for comment in comments:
        buffer.write(f"{mark} {comment}\n")
    start = 0
    for block in count if count is not None else [len(rows)]:
        if count is not None:
            buffer.write(f"{block}\n")
        write_rows(buffer, rows[start:start + block], " ".join(formats))
        start += block
    with atomic_write(path) as temporary:
        with open(temporary, "w", encoding="utf-8") as f:
            f.write(buffer.getvalue())


def _first_line(exc: Exception) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
