"""Text beyond ASCII in a PLY header's comments.

The PLY header is ASCII, but MeshLab and others write file names and notes into `comment` and
`obj_info` lines as they are (a texture called "café.png" in UTF-8). plyfile reads the header
as ASCII and holds only ASCII comments. Such a file is read here with those bytes shown to
plyfile as "?" (the same number of bytes, so that the data after the header stays where it is),
and the comments are then taken from the header's own bytes, as UTF-8 (else Latin-1). Written,
the file gets the same stand-ins, and then its header is written over with the comments as
UTF-8, which take the same bytes. Any other line with bytes beyond ASCII is a damaged header."""
from __future__ import annotations

import io
import os

_MAX_HEADER = 64 << 20  # no header of a real file is near this; a damaged file is read no further
_TEXT_LINES = (b"comment", b"obj_info")


def header_line_text(line: bytes, number: int, path) -> str:
    """One header line as text: ASCII, or for a comment or obj_info line UTF-8 (else Latin-1)."""
    try:
        return line.decode("ascii")
    except UnicodeDecodeError:
        if not line.lstrip().startswith(_TEXT_LINES):
            raise ValueError(f"{os.fspath(path)}: PLY header line {number} is not ASCII text") from None
        try:
            return line.decode("utf-8")
        except UnicodeDecodeError:
            return line.decode("latin-1")


def non_ascii_header(path) -> tuple[int, list[str], list[str]] | None:
    """(the header's length in bytes, its comments, its obj_info lines) of a PLY file whose header
    holds bytes beyond ASCII, or None for a header that is ASCII (or not found). Lines end as the
    first one ("ply") does, in LF, CRLF or CR, as plyfile reads them; the header ends at the
    line that is end_header."""
    with open(path, "rb") as f:
        head = f.read(1 << 16)
        if not head.startswith(b"ply"):
            return None
        newline = b"\r\n" if head[3:5] == b"\r\n" else head[3:4]
        if newline not in (b"\n", b"\r", b"\r\n"):
            return None
        end = newline + b"end_header" + newline
        while end not in head and len(head) < _MAX_HEADER:
            more = f.read(1 << 20)
            if not more:
                break
            head += more
    stop = head.find(end)
    if stop < 0:
        return None
    header = head[:stop + len(end)]
    if header.isascii():
        return None
    comments, obj_info = [], []
    for number, line in enumerate(header[:-len(newline)].split(newline), start=1):
        text = header_line_text(line, number, path)
        words = text.split(None, 1)
        if words and words[0] == "comment":
            comments.append(text.strip()[len("comment"):].strip())
        elif words and words[0] == "obj_info":
            obj_info.append(text.strip()[len("obj_info"):].strip())
    return len(header), comments, obj_info


class HeaderAsAscii(io.FileIO):
    """The file, read with the bytes beyond ASCII in its first `header` bytes shown as "?".
    A real file, so plyfile still memory-maps the data after the header."""

    def __init__(self, path, header: int):
        super().__init__(path, "rb")
        self._header = header

    def read(self, size=-1):
        start = self.tell()
        data = super().read(size)
        if start < self._header and data:
            cut = min(len(data), self._header - start)
            data = bytes(b if b < 128 else 63 for b in data[:cut]) + data[cut:]
        return data

    def readinto(self, buffer):
        data = self.read(len(buffer))
        buffer[:len(data)] = data
        return len(data)


def ascii_stand_in(text: str) -> str:
    """text with each character beyond ASCII as as many "?" as its UTF-8 bytes: a header of the
    same length in bytes, which plyfile can write."""
    return "".join(c if c.isascii() else "?" * len(c.encode("utf-8")) for c in text)


def write_true_header(path, ply, comments: list[str], obj_info: list[str]) -> None:
    """Writes over the header of the PLY file at path, which `ply` (with ascii_stand_in comments)
    wrote, the same header with the comments and obj_info as given, in UTF-8."""
    if all(c.isascii() for c in [*comments, *obj_info]):
        return
    lines, comment, info = [], iter(comments), iter(obj_info)
    for line in ply.header.split("\n"):
        if line.startswith("comment"):
            line = "comment " + next(comment) if line != "comment" else line
        elif line.startswith("obj_info"):
            line = "obj_info " + next(info) if line != "obj_info" else line
        lines.append(line)
    header = "\n".join(lines).encode("utf-8")
    if len(header) != len(ply.header.encode("ascii")):
        raise ValueError("the PLY header's comments did not keep their length")  # a stand-in is off
    with open(path, "r+b") as f:
        f.write(header)
