"""Scan: the contents of one point-cloud or mesh file, format-neutral, and its flat-array form."""
from __future__ import annotations

import dataclasses
import json
import os
import stat
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .format_info import check_format_info

# Attribute arrays may hold booleans, integers and floats of any width: nothing a file format
# needs is a string or an object, and refusing those keeps pickles out of the flat-array form.
_PLAIN_KINDS = "biuf"
_VERTEX_PREFIX = "vertex_attributes/"
_FACE_PREFIX = "face_attributes/"
_BYTES_PREFIX = "format_bytes/"
_META_KEY = "meta_json"
_OFFSETS = ".offsets"  # beside a face attribute of lists of varying length


@dataclass(eq=False)
class Scan:
    """One file's contents.

    points             (n, 3) float64, always float64 in memory whatever the file stored.
    precision          numpy dtype the file stored coordinates in (float32 or float64); writers
                       store coordinates in it, so float64 in gives float64 out. LAS stores scaled
                       int32: its Scan says float64 and format_info["coordinates"] tells the rest.
    normals            (n, 3) float64 or None.
    vertex_attributes  name -> array of length n, shape (n,) or (n, c), any numeric dtype: every
                       other per-vertex property, with the file's own names and dtypes.
    faces              None, (m, k) int64 when every face has k corners, or a list of m int64
                       arrays for mixed polygons.
    face_attributes    name -> array of length m (face colours ...), or a list of m 1-D arrays of
                       one dtype when their lengths differ (MeshLab's per-corner texcoord on a mesh
                       of triangles and quads).
    format_info        what a writer needs to write the same kind of file back (format, comments,
                       text/binary, LAS version, scales, ...). JSON-serialisable, except that
                       values may be `bytes` (LAS VLR payloads), which to_arrays stores raw.
    """

    points: np.ndarray
    precision: np.dtype = np.dtype(np.float64)
    normals: np.ndarray | None = None
    vertex_attributes: dict = field(default_factory=dict)
    faces: np.ndarray | list | None = None
    face_attributes: dict = field(default_factory=dict)
    format_info: dict = field(default_factory=dict)

    def __post_init__(self):
        self.points = _coordinates(self.points, "points")
        n = len(self.points)
        self.precision = np.dtype(self.precision)
        if self.normals is not None:
            self.normals = _coordinates(self.normals, "normals")
            if len(self.normals) != n:
                raise ValueError(f"normals has {len(self.normals)} rows for {n} points")
        self.vertex_attributes = _attributes(self.vertex_attributes, n, "vertex attribute")
        self.faces = _faces(self.faces, n)
        self.face_attributes = _attributes(self.face_attributes, self.n_faces, "face attribute", lists=True)
        if not isinstance(self.format_info, dict):
            raise ValueError("format_info must be a dict")

    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_faces(self) -> int:
        return 0 if self.faces is None else len(self.faces)

    def with_geometry(self, points, normals=None) -> "Scan":
        """A new Scan with the same attributes, faces and format_info, and these points (n, 3)
        and normals (n, 3) or None. The number of points must not change."""
        points = _coordinates(points, "points")
        if len(points) != self.n_points:
            raise ValueError(f"with_geometry needs {self.n_points} points (the scan's attributes are per point), "
                             f"got {len(points)}")
        return dataclasses.replace(self, points=points, normals=normals,
                                   vertex_attributes=dict(self.vertex_attributes),
                                   face_attributes=dict(self.face_attributes),
                                   format_info=_copy_info(self.format_info))

    # -- flat-array form, for np.savez / np.load(allow_pickle=False) ------------------------------

    def to_arrays(self, source_id: str | None = None) -> dict:
        """Everything but the points as name -> plain numpy array (numeric, or uint8 for JSON
        text and raw bytes; never an object array), for `np.savez(file, **scan.to_arrays())`.
        The normals, where the scan has them, are kept too: they are the input's own, which no
        computed normals replace. source_id, when given, is kept in the meta text (the command
        line's source.npz names the decomposition it belongs to; read with stored_source_id)."""
        blobs: list[bytes] = []
        meta = {"n_points": self.n_points, "precision": self.precision.str,
                "format_info": _bytes_to_refs(self.format_info, blobs),
                "vertex_attributes": list(self.vertex_attributes), "face_attributes": list(self.face_attributes)}
        if source_id is not None:
            meta["source_id"] = str(source_id)
        try:
            text = json.dumps(meta)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"format_info is not JSON-serialisable: {exc}") from None
        arrays = {_META_KEY: np.frombuffer(text.encode("utf-8"), dtype=np.uint8).copy()}
        for i, blob in enumerate(blobs):
            arrays[f"{_BYTES_PREFIX}{i}"] = np.frombuffer(blob, dtype=np.uint8).copy()
        for i, (name, values) in enumerate(self.vertex_attributes.items()):
            arrays[f"{_VERTEX_PREFIX}{i}"] = values
        for i, (name, values) in enumerate(self.face_attributes.items()):
            if isinstance(values, list):  # lists of varying length: their values and where each starts
                arrays[f"{_FACE_PREFIX}{i}"] = np.concatenate(values) if values else np.zeros(0)
                arrays[f"{_FACE_PREFIX}{i}{_OFFSETS}"] = np.cumsum([0] + [len(v) for v in values]).astype(np.int64)
            else:
                arrays[f"{_FACE_PREFIX}{i}"] = values
        if self.normals is not None:
            arrays["normals"] = np.asarray(self.normals, dtype=np.float64)
        # Indices as int32 when they fit: half the size on disk; from_arrays widens them again.
        index = np.int32 if self.n_points <= np.iinfo(np.int32).max else np.int64
        if isinstance(self.faces, np.ndarray):
            arrays["faces"] = self.faces.astype(index)
        elif self.faces is not None:
            arrays["faces_flat"] = np.concatenate(self.faces).astype(index) if self.faces else np.zeros(0, index)
            arrays["faces_offsets"] = np.concatenate([[0], np.cumsum([len(f) for f in self.faces])]).astype(np.int64)
        return arrays

    @classmethod
    def from_arrays(cls, arrays, points=None, normals=None, *, n_points: int | None = None) -> "Scan":
        """The Scan that to_arrays gave, from that dict or from an .npz file (a path, opened with
        allow_pickle=False). Points are (n, 3) NaN unless given: call with_geometry before writing.
        Normals are the ones given, else those the arrays keep, else None.
        n_points: the number of points the caller knows the scan has (a decomposition's); a file
        that says otherwise is refused unread, and its size budget comes from this count, not
        from the count the file declares about itself. Defaults to len(points) when given.
        Raises ValueError for anything missing, damaged or not plain numbers."""
        if n_points is None and points is not None:
            n_points = len(np.asarray(points))
        if isinstance(arrays, (str, os.PathLike)):
            try:
                require_regular_file(arrays)
                with np.load(arrays, allow_pickle=False) as loaded:
                    if not isinstance(loaded, Mapping):
                        raise ValueError("not an .npz archive")
                    _check_archive(loaded, n_points)
                    return cls.from_arrays({k: _plain(loaded, k) for k in loaded.files}, points, normals)
            except (OSError, ValueError, EOFError) as exc:
                raise ValueError(f"cannot read scan attributes from {os.fspath(arrays)}: {exc}") from None
        if not isinstance(arrays, Mapping):
            raise ValueError(f"Scan.from_arrays needs a dict of arrays or an .npz path, got {type(arrays).__name__}")
        return _from_arrays(cls, {k: _plain(arrays, k) for k in arrays}, points, normals)


# What a Scan's archive may hold, decompressed: far more than any file's attributes take (100
# float64 properties a point are 800 bytes), and far less than a crafted archive can declare: a
# megabyte of deflated zeros unpacks to a gigabyte. The points' share is counted from a point
# count the caller knows (a decomposition's), never only from the count the archive declares.
_BYTES_PER_POINT = 4096
# Besides the per-point entries: the format's own bytes (LAS VLRs and EVLRs, which may carry a
# survey's metadata) and the meta_json; .npy headers and small meshes fit in _PER_POINT_SLACK.
_BYTES_BESIDES = 256 << 20
_PER_POINT_SLACK = 1 << 20
_MAX_META = 64 << 20


def _check_archive(loaded, n_expected: int | None = None) -> None:
    """Refuses, before any entry but the small meta_json is decompressed, an .npz whose entries
    are not the ones its meta_json names, whose point count is not n_expected (when the caller
    knows it), or whose entries declare more bytes than its points can take (_BYTES_PER_POINT;
    the format bytes may add _BYTES_BESIDES). The sizes are the archive's own (ZipInfo.file_size),
    which also cap what reading an entry decompresses."""
    infos = npz_entries(loaded.zip)
    meta_info = infos.get(_META_KEY)
    if meta_info is None:
        raise ValueError(f"scan arrays lack {_META_KEY!r}")
    if meta_info.file_size > _MAX_META:
        raise ValueError(f"{_META_KEY} declares {meta_info.file_size} bytes")
    try:
        meta = json.loads(_as_bytes(_plain(loaded, _META_KEY), _META_KEY).decode("utf-8"))
        n = int(meta["n_points"])
        vertex_count, face_count = len(meta["vertex_attributes"]), len(meta["face_attributes"])
    except (KeyError, TypeError, ValueError, UnicodeDecodeError, RecursionError) as exc:
        raise ValueError(f"scan arrays: damaged {_META_KEY} ({type(exc).__name__}: {exc})") from None
    if n_expected is not None and n != n_expected:
        raise ValueError(f"its {_META_KEY} says {n} points where {n_expected} are expected (another run's file, "
                         "or a crafted one); refused unread")
    named = _entry_names(vertex_count, face_count)
    unknown = sorted(k for k in infos if k not in named and not k.startswith(_BYTES_PREFIX))
    if unknown:
        raise ValueError(f"scan arrays: unexpected entries {unknown}")
    # The attributes, normals and faces within 4 KB a point; the format bytes (a large LAS's
    # waveform EVLRs) may use what they leave, and _BYTES_BESIDES more.
    per_point = sum(info.file_size for name, info in infos.items()
                    if name != _META_KEY and not name.startswith(_BYTES_PREFIX))
    budget = max(n, 0) * _BYTES_PER_POINT + _PER_POINT_SLACK
    if per_point > budget:
        raise ValueError(f"its entries declare {per_point} bytes, more than {n} points' attributes can take "
                         f"({budget}); refused unread")
    declared = sum(info.file_size for info in infos.values())
    budget = max(n, 0) * _BYTES_PER_POINT + _BYTES_BESIDES
    if declared > budget:
        raise ValueError(f"its entries declare {declared} bytes, more than {n} points' attributes and their "
                         f"format's own bytes can take ({budget}); refused unread")


def npz_entries(archive) -> dict:
    """An .npz archive's (a zipfile.ZipFile's) entries by array name (without .npy), with the
    sizes they declare: what np.load would unpack, known without unpacking it."""
    return {info.filename[:-4] if info.filename.endswith(".npy") else info.filename: info
            for info in archive.infolist()}


# numpy's own default for the largest .npy header it parses; a saved array's header is ~128 bytes.
_MAX_NPY_HEADER = 10000


def npy_shape(archive, info) -> tuple[tuple, np.dtype]:
    """(shape, dtype) of one .npz entry, from its .npy header alone: a few hundred bytes are
    decompressed, whatever size the entry declares. ValueError for a header that is damaged,
    too long, or not a plain array."""
    with archive.open(info) as fp:
        version = np.lib.format.read_magic(fp)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(fp, max_header_size=_MAX_NPY_HEADER)
        elif version == (2, 0):
            shape, _, dtype = np.lib.format.read_array_header_2_0(fp, max_header_size=_MAX_NPY_HEADER)
        else:  # 3.0 is for utf-8 field names, which no plain array needs
            raise ValueError(f"entry {info.filename!r}: unsupported .npy version {version}")
    return shape, dtype


def require_regular_file(path) -> None:
    """Refuses a path that is not a regular file before opening it: a named pipe would block the
    open until someone writes to it, and a device (/dev/zero, /dev/urandom) never ends."""
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        raise ValueError(f"cannot read it ({exc.strerror or exc})") from None
    if not stat.S_ISREG(mode):
        raise ValueError(f"it is not a regular file ({_file_kind(mode)}); refused unread")


def _file_kind(mode: int) -> str:
    kinds = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe"), (stat.S_ISCHR, "a character device"),
             (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def _entry_names(vertex_count: int, face_count: int) -> set:
    """The entries a Scan's flat-array form may hold besides its format bytes."""
    names = {_META_KEY, "faces", "faces_flat", "faces_offsets", "normals"}
    names |= {f"{_VERTEX_PREFIX}{i}" for i in range(vertex_count)}
    names |= {f"{_FACE_PREFIX}{i}{suffix}" for i in range(face_count) for suffix in ("", _OFFSETS)}
    return names


def _from_arrays(cls, arrays: dict, points, normals) -> Scan:
    if _META_KEY not in arrays:
        raise ValueError(f"scan arrays lack {_META_KEY!r}")
    try:
        meta = json.loads(_as_bytes(arrays[_META_KEY], _META_KEY).decode("utf-8"))
        n = int(meta["n_points"])
        precision = np.dtype(meta["precision"])
        vertex_names = [str(s) for s in meta["vertex_attributes"]]
        face_names = [str(s) for s in meta["face_attributes"]]
        for names in (vertex_names, face_names):
            if len(set(names)) != len(names):  # one name, one attribute: the second would replace the first
                raise ValueError(f"it names {sorted({n for n in names if names.count(n) > 1})} twice")
        info = meta["format_info"]
    except (KeyError, TypeError, ValueError, UnicodeDecodeError, RecursionError) as exc:
        raise ValueError(f"scan arrays: damaged {_META_KEY} ({type(exc).__name__}: {exc})") from None
    if n < 0 or precision.kind not in "fi" or not isinstance(info, dict):
        raise ValueError(f"scan arrays: damaged {_META_KEY} (n_points {n}, precision {precision})")
    blobs = {}
    for key, value in arrays.items():
        if key.startswith(_BYTES_PREFIX):
            blobs[key[len(_BYTES_PREFIX):]] = _as_bytes(value, key)
    known = _entry_names(len(vertex_names), len(face_names)) | {_BYTES_PREFIX + k for k in blobs}
    unknown = sorted(set(arrays) - known)
    if unknown:
        raise ValueError(f"scan arrays: unexpected entries {unknown}")
    vertex = {name: _entry(arrays, f"{_VERTEX_PREFIX}{i}") for i, name in enumerate(vertex_names)}
    face = {name: _face_entry(arrays, f"{_FACE_PREFIX}{i}") for i, name in enumerate(face_names)}
    faces = None
    if "faces" in arrays:
        faces = arrays["faces"]
        if faces.ndim != 2 or faces.dtype.kind not in "iu":
            raise ValueError(f"scan arrays: faces must be an (m, k) integer array, got {faces.shape} {faces.dtype}")
    elif "faces_flat" in arrays or "faces_offsets" in arrays:
        flat, offsets = _entry(arrays, "faces_flat"), _entry(arrays, "faces_offsets")
        if flat.ndim != 1 or offsets.ndim != 1 or flat.dtype.kind not in "iu" or offsets.dtype.kind not in "iu" \
                or len(offsets) < 1 or offsets[0] != 0 or offsets[-1] != len(flat) or np.any(np.diff(offsets) < 1):
            raise ValueError("scan arrays: faces_flat / faces_offsets do not describe a list of polygons")
        faces = np.split(flat.astype(np.int64), offsets[1:-1])
    if points is None:
        points = np.full((n, 3), np.nan)
    if normals is None and "normals" in arrays:
        normals = arrays["normals"]  # checked by Scan as a normals array of n rows
        if normals.dtype.kind != "f" or not np.isfinite(normals).all():
            raise ValueError("scan arrays: normals must be finite floating-point numbers")
    try:
        info = _refs_to_bytes(info, blobs)
        check_format_info(info, n)  # anyone may have edited the file: the writers trust these values
        scan = cls(points=points, precision=precision, normals=normals, vertex_attributes=vertex, faces=faces,
                   face_attributes=face, format_info=info)
    except (KeyError, TypeError, RecursionError) as exc:
        raise ValueError(f"scan arrays: damaged format_info ({type(exc).__name__}: {exc})") from None
    except ValueError as exc:
        raise ValueError(f"scan arrays: {exc}") from None
    if scan.n_points != n:
        raise ValueError(f"scan arrays describe {n} points, got {scan.n_points}")
    return scan


def _plain(arrays, key: str) -> np.ndarray:
    """arrays[key] as a numeric array. Object arrays are refused before anything unpickles them:
    np.load(allow_pickle=False) raises on them, and an in-memory object array is refused here."""
    try:
        value = np.asarray(arrays[key])
    except ValueError as exc:  # np.load: "Object arrays cannot be loaded when allow_pickle=False"
        raise ValueError(f"entry {key!r}: {exc}") from None
    if value.dtype.kind not in _PLAIN_KINDS:
        raise ValueError(f"entry {key!r} has dtype {value.dtype}; only plain numbers are accepted")
    return value


def _entry(arrays: dict, key: str) -> np.ndarray:
    if key not in arrays:
        raise ValueError(f"scan arrays lack {key!r}")
    return arrays[key]


def _face_entry(arrays: dict, key: str):
    """A face attribute: its array, or with offsets beside it, its lists of varying length."""
    values = _entry(arrays, key)
    if key + _OFFSETS not in arrays:
        return values
    offsets = arrays[key + _OFFSETS]
    if values.ndim != 1 or offsets.ndim != 1 or offsets.dtype.kind not in "iu" or len(offsets) < 1 \
            or offsets[0] != 0 or offsets[-1] != len(values) or np.any(np.diff(offsets) < 0):
        raise ValueError(f"scan arrays: {key} and its offsets do not describe lists")
    return np.split(values, offsets[1:-1]) if len(offsets) > 1 else []


def stored_source_id(path) -> str | None:
    """The source_id that to_arrays kept in the .npz file at path, or None (none kept). Call it
    after Scan.from_arrays(path, n_points=...) has checked the file and its sizes."""
    with np.load(path, allow_pickle=False) as loaded:
        meta = json.loads(_as_bytes(_plain(loaded, _META_KEY), _META_KEY).decode("utf-8"))
    value = meta.get("source_id") if isinstance(meta, dict) else None
    if value is not None and not (isinstance(value, str) and value.isprintable() and len(value) <= 64):
        raise ValueError(f"{os.fspath(path)}: damaged {_META_KEY} (source_id {str(value)[:40]!r})")
    return value


def _as_bytes(value: np.ndarray, key: str) -> bytes:
    if value.dtype != np.uint8 or value.ndim != 1:
        raise ValueError(f"scan arrays: {key!r} must be 1-D uint8 bytes, got {value.shape} {value.dtype}")
    return value.tobytes()


def _bytes_to_refs(value, blobs: list):
    """format_info with every bytes value replaced by {"__bytes__": index into blobs}."""
    if isinstance(value, (bytes, bytearray)):
        blobs.append(bytes(value))
        return {"__bytes__": str(len(blobs) - 1)}
    if isinstance(value, dict):
        return {k: _bytes_to_refs(v, blobs) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_bytes_to_refs(v, blobs) for v in value]
    return value


def _refs_to_bytes(value, blobs: dict):
    if isinstance(value, dict):
        if set(value) == {"__bytes__"}:
            return blobs[str(value["__bytes__"])]
        return {k: _refs_to_bytes(v, blobs) for k, v in value.items()}
    if isinstance(value, list):
        return [_refs_to_bytes(v, blobs) for v in value]
    return value


def _copy_info(value):
    if isinstance(value, dict):
        return {k: _copy_info(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_copy_info(v) for v in value]
    return value


def _coordinates(values, what: str) -> np.ndarray:
    values = np.asarray(values)
    if values.dtype.kind not in "biuf":
        raise ValueError(f"{what} must be numbers, got dtype {values.dtype}")
    values = np.ascontiguousarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != 3:
        raise ValueError(f"{what} must be (n, 3), got {values.shape}")
    return values


def _attributes(attributes, count: int, what: str, lists: bool = False) -> dict:
    """Checked attributes; with `lists`, a value may also be a list of `count` 1-D arrays."""
    if not isinstance(attributes, Mapping):
        raise ValueError(f"{what}s must be a dict of arrays")
    out = {}
    for name, values in attributes.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"{what} names must be non-empty strings, got {name!r}")
        if lists and isinstance(values, list):
            arrays = [np.asarray(v) for v in values]
            if len(arrays) != count or any(a.ndim != 1 or a.dtype.kind not in _PLAIN_KINDS for a in arrays):
                raise ValueError(f"{what} {name!r}: a list must hold {count} 1-D arrays of numbers, one per face")
            dtype = np.result_type(*arrays) if arrays else np.dtype(np.float64)
            out[name] = [a.astype(dtype, copy=False) for a in arrays]
            continue
        values = np.asarray(values)
        if values.dtype.kind not in _PLAIN_KINDS:
            raise ValueError(f"{what} {name!r} has dtype {values.dtype}; only plain numbers are kept")
        if values.ndim not in (1, 2) or len(values) != count:
            raise ValueError(f"{what} {name!r} has shape {values.shape}, expected ({count},) or ({count}, c)")
        out[name] = values
    return out


def _faces(faces, n: int):
    """faces as (m, k) int64 or a list of int64 arrays (mixed polygons), every index in [0, n)."""
    if faces is None:
        return None
    if isinstance(faces, np.ndarray) and faces.dtype.kind != "O":
        if faces.ndim != 2 or (faces.size and faces.dtype.kind not in "iu") or (len(faces) and faces.shape[1] < 3):
            raise ValueError(f"faces must be an (m, k >= 3) integer array, got {faces.shape} {faces.dtype}")
        faces = faces.astype(np.int64, copy=False)
        flat = faces.ravel()
    else:
        faces = [_index_list(f) for f in faces]
        if any(f.ndim != 1 or (f.size and f.dtype.kind not in "iu") or len(f) < 3 for f in faces):
            raise ValueError("faces must be integer index lists of at least 3 vertices each")
        faces = [f.astype(np.int64, copy=False) for f in faces]
        if len({len(f) for f in faces}) <= 1:
            faces = np.array(faces, dtype=np.int64).reshape(len(faces), -1 if faces else 3)
            flat = faces.ravel()
        else:
            flat = np.concatenate(faces)
    if flat.size and (flat.min() < 0 or flat.max() >= n):
        raise ValueError(f"faces index vertices {int(flat.min())}..{int(flat.max())}, outside 0..{n - 1}")
    return faces


def _index_list(face) -> np.ndarray:
    """One face as an integer array; object arrays of integers (np.load of an old faces.npy) are
    accepted when every entry is a whole number."""
    face = np.asarray(face)
    if face.dtype == object:
        try:
            as_int = face.astype(np.int64)
        except (TypeError, ValueError):
            raise ValueError("faces must be integer index lists") from None
        if not np.array_equal(as_int, face):
            raise ValueError("faces must be integer index lists")
        face = as_int
    return face
