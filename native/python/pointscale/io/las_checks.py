"""Checks of a LAS/LAZ file's counts and offsets before laspy and lazrs trust them.

laspy reads as many VLRs as the header's count says (a damaged count of 4 billion makes it build
billions of empty records: 10 GB and minutes before a MemoryError) and reads an EVLR of whatever
length its header gives; lazrs sizes its chunk table by the count stored in the file and aborts
the process when that allocation fails. Each count and length is checked here against the
bytes the file actually has, so a damaged file is a ValueError and nothing larger than the file
is ever allocated.
"""
from __future__ import annotations

import os
import struct

_VLR_HEADER = 54    # reserved u16, user id 16 bytes, record id u16, length u16, description 32 bytes
_EVLR_HEADER = 60   # the same with a u64 length
_CHUNKED_COMPRESSORS = (2, 3)  # LASzip: 1 point-wise (no chunk table), 2 chunked, 3 layered chunked


def check_layout(path: str) -> None:
    """The public header's VLR and EVLR counts and every record's length against the file size."""
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        head = f.read(375)
        if len(head) < 227 or head[:4] != b"LASF":
            raise ValueError("not a LAS file (no LASF signature, or shorter than a LAS header)")
        minor = head[25]
        header_size, point_data, vlr_count = struct.unpack_from("<HII", head, 94)
        if not header_size <= point_data <= size:
            raise ValueError(f"damaged header: point data at {point_data}, header {header_size} bytes, file {size}")
        _walk(f, header_size, point_data, vlr_count, _VLR_HEADER, "<H", "VLR")
        if minor >= 4 and len(head) >= 247:
            evlr_start, evlr_count = struct.unpack_from("<QI", head, 235)
            if evlr_count:
                if not point_data <= evlr_start <= size:
                    raise ValueError(f"damaged header: EVLRs at {evlr_start} in a {size}-byte file (truncated?)")
                _walk(f, evlr_start, size, evlr_count, _EVLR_HEADER, "<Q", "EVLR")


def _walk(f, start: int, end: int, count: int, record_header: int, length_format: str, what: str) -> None:
    """Steps through count records from start; each must end by end."""
    if count * record_header > end - start:
        raise ValueError(f"damaged header: {count} {what}s cannot fit in {end - start} bytes (truncated?)")
    position = start
    for i in range(count):
        f.seek(position + 20)  # the length follows reserved (2), user id (16) and record id (2)
        raw = f.read(struct.calcsize(length_format))
        if len(raw) < struct.calcsize(length_format):
            raise ValueError(f"{what} {i} is cut off (truncated?)")
        position += record_header + struct.unpack(length_format, raw)[0]
        if position > end:
            raise ValueError(f"{what} {i} runs past the end of its section (damaged or truncated)")


def check_chunk_table(path: str, header) -> None:
    """For chunked LAZ: the chunk table's offset (the first 8 bytes of the point data or, when
    those are -1, the last 8 of the file) must lie in the file, and its chunk count (after a u32
    version) cannot exceed the bytes after the point data start: every chunk takes at least one."""
    if _laszip_compressor(header) not in _CHUNKED_COMPRESSORS:
        return
    start = int(header.offset_to_point_data)
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        f.seek(start)
        raw = f.read(8)
        if len(raw) < 8:
            raise ValueError("truncated LAZ point data")
        offset = int.from_bytes(raw, "little", signed=True)
        if offset == -1:
            f.seek(max(size - 8, 0))
            offset = int.from_bytes(f.read(8), "little", signed=True)
        if not start + 8 <= offset <= size - 8:
            raise ValueError(f"damaged LAZ chunk table offset {offset} in a {size}-byte file (truncated?)")
        f.seek(offset)
        _version, chunks = struct.unpack("<II", f.read(8))
        if chunks > size - start:
            raise ValueError(f"damaged LAZ chunk table ({chunks} chunks in a {size}-byte file)")


def _laszip_compressor(header) -> int | None:
    for v in header.vlrs:
        if (v.user_id, v.record_id) == ("laszip encoded", 22204):
            data = v.record_data_bytes() if hasattr(v, "record_data_bytes") else bytes(v.record_data)
            return struct.unpack("<H", data[:2])[0] if len(data) >= 2 else None
    return None
