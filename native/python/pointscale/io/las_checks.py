"""Checks of a LAS/LAZ file's counts and offsets before laspy and lazrs trust them.

laspy reads as many VLRs as the header's count says (a damaged count of 4 billion makes it build
billions of empty records: 10 GB and minutes before a MemoryError) and reads an EVLR of whatever
length its header gives; lazrs sizes its chunk table by the count stored in the file, and each
layer of a layered chunk by the byte count stored before it, and aborts the process when such an
allocation fails. Each count and length is checked here against the
bytes the file actually has, so a damaged file is a ValueError and nothing larger than the file
is ever allocated.
"""
from __future__ import annotations

import os
import struct

_VLR_HEADER = 54    # reserved u16, user id 16 bytes, record id u16, length u16, description 32 bytes
_EVLR_HEADER = 60   # the same with a u64 length
_CHUNKED_COMPRESSORS = (2, 3)  # LASzip: 1 point-wise (no chunk table), 2 chunked, 3 layered chunked
_LAYERED = 3


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
    if _laszip_compressor(header) == _LAYERED:
        _check_layers(path, header, start, size)


def _check_layers(path: str, header, start: int, size: int) -> None:
    """Layered LAZ (point formats 6-10): each chunk is the raw first point, a u32 point count
    and one u32 byte count per layer, then the layers. lazrs allocates each layer's byte count
    as read, so a damaged one (3 GB, found by corruption) is refused unless the chunk holds it."""
    import lazrs

    data = _laszip_vlr(header)
    layers = _layer_count(data)
    if layers is None:
        return  # items this check does not know: leave them to lazrs
    point_size = int(header.point_format.size)
    with open(path, "rb") as f:
        f.seek(start)
        try:
            table = lazrs.read_chunk_table(f, lazrs.LazVlr(data))
        except Exception as exc:
            raise ValueError(f"damaged LAZ chunk table ({exc})") from None
        position = start + 8
        for i, (_points, length) in enumerate(table or []):
            if position + length > size:
                raise ValueError(f"LAZ chunk {i} runs past the end of the file (truncated?)")
            fixed = point_size + 4 + 4 * layers
            if length >= fixed:
                f.seek(position + point_size)
                count = struct.unpack("<I", f.read(4))[0]
                sizes = struct.unpack(f"<{layers}I", f.read(4 * layers))
                if count > 1 and sum(sizes) > length - fixed:
                    raise ValueError(f"damaged LAZ chunk {i}: its layers claim {sum(sizes)} bytes, "
                                     f"the chunk has {length - fixed}")
            position += length


def _layer_count(data: bytes) -> int | None:
    """Layers per chunk from the LASzip VLR's items: point14 9, RGB14 1, RGBNIR14 2,
    wavepacket14 1, byte14 one per byte; None for any other item."""
    if len(data) < 34:
        return None
    count = struct.unpack_from("<H", data, 32)[0]
    if len(data) < 34 + 6 * count:
        return None
    layers = 0
    for i in range(count):
        kind, item_size, _version = struct.unpack_from("<HHH", data, 34 + 6 * i)
        per_item = {10: 9, 11: 1, 12: 2, 13: 1}.get(kind, item_size if kind == 14 else None)
        if per_item is None:
            return None
        layers += per_item
    return layers


def _laszip_vlr(header) -> bytes:
    for v in header.vlrs:
        if (v.user_id, v.record_id) == ("laszip encoded", 22204):
            return bytes(v.record_data_bytes() if hasattr(v, "record_data_bytes") else v.record_data)
    return b""


def _laszip_compressor(header) -> int | None:
    data = _laszip_vlr(header)
    return struct.unpack("<H", data[:2])[0] if len(data) >= 2 else None
