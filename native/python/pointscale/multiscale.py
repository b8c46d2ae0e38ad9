"""The multiscale representation: decompose, reconstruct, blend, save and load (paper Sec. 4-7)."""
from __future__ import annotations

import contextvars
import json
import math
import os
import threading
import warnings
from collections.abc import Mapping
from pathlib import Path
from dataclasses import dataclass, field

import numpy as np

from . import _core
from ._checks import (MAX_COORDINATE, MAX_EXTENT, MAX_LEVELS, MAX_NEIGHBORS, MIN_COARSE_POINTS, as_array,
                      as_callback, as_normals_of, as_points, centre, finite_result, flag, mls_options, number, positive,
                      raise_not_finite, require_extent, require_near, thread_option)
from ._diffusion import settings_record, smoother_options

# MIN_COARSE_POINTS (from the core's limits): the coarsest level keeps gamma**(levels-1) * n
# points; fewer than this cannot carry a surface.
# Below this many support points a closed base has too few clusters to keep its shape: the
# kernels then span a large part of it, and an edit of the base reaches far across it.
FEW_COARSE_POINTS = 100
_FORMAT_VERSION = 1


@dataclass(eq=False)
class Decomposition:
    """P^0 plus k signed normal-displacement bands D^0..D^{k-1} (Eq. 11), for n points.

    Every level keeps all n points, indexed like the input. Coordinates are the caller's.
    Two decompositions are equal (==) when every array and setting to_dict() gives is equal,
    bit for bit: a saved and loaded one equals the one saved.
    """

    def __eq__(self, other):
        if not isinstance(other, Decomposition):
            return NotImplemented
        if self is other:
            return True
        a, b = self.to_dict(), other.to_dict()
        return a.keys() == b.keys() and all(
            a[key].dtype == b[key].dtype and np.array_equal(a[key], b[key]) for key in a)

    __hash__ = None  # mutable (settings, origin): not a dictionary key

    _model: object
    origin: np.ndarray
    settings: dict
    _cache: dict = field(default_factory=dict, repr=False)
    # The decomposition's per-level report, kept from the run that made it: a loaded model has
    # no reports of its own, so load() restores them from the file.
    _stats: list | None = field(default=None, repr=False, compare=False)
    # A decomposition of a mirrored half (pointscale.mirror): _model holds the whole model, and
    # every output for the half's points is symmetrised through this.
    _mirror: object = field(default=None, repr=False, compare=False)
    # decompose_rayshoot's rays that found no surface: per band, the points' indices. None for
    # any other decomposition, and for one loaded from a file (which keeps only the counts).
    _missed_rays: list | None = field(default=None, repr=False, compare=False)

    @property
    def mirror(self):
        """The pointscale.Mirror this decomposition is symmetric about, or None."""
        return None if self._mirror is None else self._mirror.mirror

    def _symmetric(self, points: np.ndarray) -> np.ndarray:
        """The whole model's (N, 3) positions as the half's (n, 3); unchanged without a mirror."""
        return points if self._mirror is None else self._mirror.symmetric(points)

    def _full(self, points: np.ndarray) -> np.ndarray:
        """The half's (n, 3) positions as the whole model's; unchanged without a mirror."""
        return points if self._mirror is None else self._mirror.full(points)

    @property
    def base(self) -> np.ndarray:
        """P^0, the smoothest level: (n, 3)."""
        return self._symmetric(self._model.base + self.origin)

    @property
    def details(self) -> np.ndarray:
        """D^0..D^{k-1}, signed along the outward normals of each level: (k, n). Mirrored: each
        point's orbit average, so level(l) + details[l] * normals(l) is level(l + 1) only to
        within the whole model's own asymmetry."""
        details = self._model.details
        return details if self._mirror is None else self._mirror.symmetric_values(details)

    @property
    def n_levels(self) -> int:
        """Number of point clouds P^0..P^k (k + 1)."""
        return self._model.bands + 1

    @property
    def n_bands(self) -> int:
        return self._model.bands

    @property
    def n_points(self) -> int:
        return self._model.points if self._mirror is None else self._mirror.n

    @property
    def parts(self) -> list[dict] | None:
        """The connected parts, when decompose was given faces or edges and found more than one:
        per part its points, first vertex, centre, size and the levels it kept. None otherwise."""
        return self.settings.get("parts")

    @property
    def part_labels(self) -> np.ndarray | None:
        """(n,) the part of each point, or None for one part."""
        parts = self._model.parts
        return parts if parts is None or self._mirror is None else parts[: self._mirror.n]

    @property
    def stats(self) -> list[dict]:
        """Per level (0 first): support points, kernel width, projections that did not converge."""
        return self._stats if self._stats is not None else self._model.reports

    def _reconstruct(self, gains: np.ndarray, base, *, keep_levels: bool = False, progress=None, threads: int = 0):
        """The core's reconstruction of the whole model from checked gains and base (world
        coordinates): the finest level, or with keep_levels (levels, normals) of every level.
        The core adds the origin in place (a NumPy sum would allocate every level again).
        An edited base: what every edit needs is found on the first such call and kept with
        this decomposition (the core's EditMemo), so the calls after it cost the edited pass."""
        # Gains other than 1 read the level normals at unit gains too (they orient the others'),
        # kept in the same memo.
        memo = None if base is None and (gains == 1.0).all() else self._kept("edit", _core.EditMemo)
        return self._model.reconstruct(gains, base=base, keep_levels=keep_levels, progress=progress,
                                       origin=self.origin, threads=threads, memo=memo)

    def _kept(self, key: str, make):
        """What make() returns, made once and kept with this decomposition (fold references...).
        Threads that ask at once may each make one, but all get the first kept (setdefault is
        atomic), so none keeps a value another thread has dropped."""
        value = self._cache.get(key)
        return value if value is not None else self._cache.setdefault(key, make())

    def _mirror_about(self, symmetry) -> None:
        """Makes this decomposition of the whole model one of its mirrored half (pointscale.mirror)."""
        self._mirror = symmetry
        if self._missed_rays is not None:  # ray shooting's misses, as the half's points
            self._missed_rays = [np.unique(symmetry.source[m]).astype(np.int32) for m in self._missed_rays]

    def _levels(self):
        if "levels" not in self._cache:
            levels, normals = self._reconstruct(np.ones(self.n_bands), None, keep_levels=True)
            for level in levels:
                finite_result(level, "a level of this decomposition")
            symmetric_normals = (lambda a: a) if self._mirror is None else self._mirror.symmetric_normals
            self._cache["levels"] = [self._symmetric(level) for level in levels]
            self._cache["normals"] = [symmetric_normals(normal) for normal in normals]
        return self._cache["levels"], self._cache["normals"]

    def level(self, l: int) -> np.ndarray:
        """P^l as (n, 3); level(n_levels - 1) is the input."""
        return self._levels()[0][_level_index(l, self.n_levels)].copy()

    def normals(self, l: int) -> np.ndarray:
        """Unit normals of P^l, along which band l displaces it: (n, 3), l in 0..k-1."""
        return self._levels()[1][_level_index(l, self.n_bands)].copy()

    def to_dict(self) -> dict[str, np.ndarray]:
        """Every array needed to rebuild this object with from_dict (no pickles)."""
        arrays = dict(self._model.to_arrays())
        arrays["origin"] = np.array(self.origin, dtype=np.float64)  # a copy: editing it must not move the model
        arrays["settings"] = np.frombuffer(json.dumps(self.settings).encode(), dtype=np.uint8)
        arrays["stats"] = np.frombuffer(json.dumps(self.stats).encode(), dtype=np.uint8)
        arrays["format_version"] = np.array([_FORMAT_VERSION])
        if self._mirror is not None:
            arrays.update(self._mirror.to_arrays())
        return arrays

    @classmethod
    def from_dict(cls, arrays) -> "Decomposition":
        """Rebuilds a decomposition from to_dict()'s arrays. Every array is checked first (keys,
        dtypes, shapes against n and the band count, index ranges, finiteness, the settings);
        anything wrong raises one ValueError saying what."""
        core_arrays, origin, settings = _checked_arrays(arrays)
        from .mirror import saved_symmetry
        symmetry = saved_symmetry(settings, arrays, core_arrays["base"].shape[0])
        model = _core.Model.from_arrays(core_arrays)  # checks the structure again, for C++ callers
        return cls(model, origin, settings, _stats=_checked_stats(arrays, model.bands), _mirror=symmetry)

    def save(self, path) -> None:
        """Writes one .npz file at `path`, whole or not at all: an earlier file there stays until
        the new one is complete. Raises ValueError when `path` is a folder or its folder is missing."""
        from .io.atomic import atomic_write
        if not isinstance(path, (str, os.PathLike)):
            raise ValueError(f"save needs the path of a file to write, got {type(path).__name__}")
        path = Path(os.fspath(path))
        if path.is_dir():
            raise ValueError(f"cannot save the decomposition to {path}: it is a folder; name a file, "
                             f"e.g. {path / 'decomposition.npz'}")
        folder = path.absolute().parent
        if not folder.is_dir():
            raise ValueError(f"cannot save the decomposition to {path}: the folder {folder} does not exist")
        arrays = self.to_dict()
        try:
            with atomic_write(path) as tmp, open(tmp, "wb") as f:  # a file object: savez adds no .npz
                np.savez_compressed(f, **arrays)
        except OSError as exc:
            raise ValueError(f"cannot save the decomposition to {path}: {exc.strerror or exc}") from None


def load(path) -> Decomposition:
    """Reads a file written by Decomposition.save. A file that cannot be read, or whose arrays
    do not make a decomposition, raises ValueError."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise ValueError(f"load needs the path of a decomposition file, got {type(path).__name__}")
    from .io.scan import require_regular_file
    if os.path.isdir(os.fspath(path)):
        raise ValueError(f"cannot read decomposition {path!s}: it is a folder, not a file")
    try:  # before open(): a named pipe would block it until someone writes, a device never ends
        require_regular_file(os.fspath(path))
        with open(os.fspath(path), "rb") as head:
            magic = head.read(6)
    except ValueError as exc:
        raise ValueError(f"cannot read decomposition {path!s}: {exc}") from None
    except OSError as exc:
        raise ValueError(f"cannot read decomposition {path!s}: {exc.strerror or exc}") from None
    if not magic.startswith((b"PK\x03\x04", b"PK\x05\x06", b"\x93NUMPY")):
        # np.load would take it for a pickle, and say so
        raise ValueError(f"cannot read decomposition {path!s}: it is not a decomposition file (the .npz that "
                         "decompose or Decomposition.save writes)")
    try:
        f = np.load(os.fspath(path), allow_pickle=False)
        if not isinstance(f, np.lib.npyio.NpzFile):
            raise ValueError("it holds one array, not the arrays of a decomposition (.npz)")
        with f:
            _check_archive_sizes(f)
            arrays = dict(f)
    except MemoryError:  # a crafted header can declare any size: say which file
        raise ValueError(f"cannot read decomposition {path!s}: its arrays declare more data than fits in "
                         "memory") from None
    except Exception as exc:  # BadZipFile, zlib.error, EOFError, KeyError from a damaged archive...
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise ValueError(f"cannot read decomposition {path!s}: {detail}") from None
    return Decomposition.from_dict(arrays)


# What each entry of a decomposition file (Decomposition.to_dict) may hold for n points and k
# bands, in bytes: 8 a number (the widest the checks accept), 1 a byte of JSON text (settings,
# stats), which is generous for a part report per part and a stats row per level.
_NUMBER, _JSON_BYTES, _JSON_BYTES_PER_POINT = 8, 1 << 20, 1024
_NPY_HEADER = 10000  # the largest .npy header numpy parses by default; a saved one is ~128 bytes


def _check_archive_sizes(npz) -> None:
    """Refuses, before any array is unpacked, a decomposition file with entries it does not
    write, or an entry that declares more bytes (ZipInfo.file_size, which also caps what reading
    it decompresses) than a decomposition of its points and bands can hold. The point and band
    counts come from the .npy headers of base (n, 3) and details (k, n), a few hundred bytes
    each. Unchecked, a crafted file unpacks what it declares: 4 MB of deflated zeros are 4 GB."""
    from .io.scan import npz_entries
    entries = npz_entries(npz.zip)
    n, k = _declared_counts(npz.zip, entries)
    json_bytes = _JSON_BYTES + _JSON_BYTES_PER_POINT * n
    allowed = {"base": 3 * n * _NUMBER, "base_normals": 3 * n * _NUMBER, "details": k * n * _NUMBER,
               "labels": k * n * _NUMBER, "parts": n * _NUMBER, "mirror_seam": 3 * n, "origin": 3 * _NUMBER,
               "format_version": _NUMBER, "settings": json_bytes, "stats": json_bytes}
    for band in range(k):  # a band's clusters each own a point (its anchor): at most n of them
        allowed.update({f"neighborhoods_{band}": n * min(n, MAX_NEIGHBORS) * _NUMBER, f"kernel_{band}": n * _NUMBER,
                        f"anchors_{band}": n * _NUMBER, f"frames_{band}": 2 * n * _NUMBER,
                        f"local_{band}": 3 * n * _NUMBER})
    unknown = sorted(name for name in entries if name not in allowed)
    if unknown:
        raise ValueError(f"it holds entries a decomposition file does not: {', '.join(unknown[:5])}"
                         f"{' ...' if len(unknown) > 5 else ''}; refused unread")
    for name, info in entries.items():
        if info.file_size > _NPY_HEADER + allowed[name]:
            raise ValueError(f"its entry {name!r} declares {info.file_size} bytes, more than a decomposition of "
                             f"{n} points and {k} bands holds there ({_NPY_HEADER + allowed[name]}); refused unread")


def _declared_counts(archive, entries) -> tuple[int, int]:
    """(n, k): the points and bands the headers of base (n, 3) and details (k, n) declare."""
    from .io.scan import npy_shape
    for key in ("base", "details"):
        if key not in entries:
            raise ValueError(f"not a pointscale decomposition: missing {key!r}")
    base_shape, _ = npy_shape(archive, entries["base"])
    if len(base_shape) != 2 or base_shape[1] != 3 or base_shape[0] < 1:
        raise _bad(f"base must have shape (n, 3) with n >= 1, got {base_shape}")
    n = base_shape[0]
    details_shape, _ = npy_shape(archive, entries["details"])
    if len(details_shape) != 2 or details_shape[1] != n:  # the words of _checked_arrays, which says it later
        raise _bad(f"details must have shape (k, {n}), got {details_shape}")
    if not 1 <= details_shape[0] < MAX_LEVELS:
        raise _bad(f"details has {details_shape[0]} bands; 1 to {MAX_LEVELS - 1} are supported")
    return n, details_shape[0]


def _bad(what: str):
    return ValueError(f"not a valid decomposition: {what}")


def _checked_arrays(arrays):
    """The arrays of a saved decomposition, checked and converted for _core.Model.from_arrays:
    (core arrays, origin, settings). Raises ValueError on the first thing wrong."""
    if not isinstance(arrays, Mapping):
        raise _bad(f"expected a dict of arrays, got {type(arrays).__name__}")

    def get(key):
        if key not in arrays:
            raise ValueError(f"not a pointscale decomposition: missing {key!r}")
        try:
            return np.asarray(arrays[key])
        except Exception as exc:
            raise _bad(f"{key} is not an array ({exc})") from None

    def floats(key, shape, limit=MAX_EXTENT):
        a = get(key)
        if a.dtype.kind != "f":
            raise _bad(f"{key} must hold floating-point numbers, got dtype {a.dtype}")
        if a.shape != shape:
            raise _bad(f"{key} must have shape {shape}, got {a.shape}")
        a = np.ascontiguousarray(a, dtype=np.float64)
        if not np.isfinite(a).all():
            raise _bad(f"{key} holds NaN or infinite values")
        if a.size and np.abs(a).max() > limit:
            raise _bad(f"{key} holds values beyond +-{limit:.0e}")
        return a

    def indices(key, shape, count, what):
        a = get(key)
        if a.dtype.kind not in "iu":
            raise _bad(f"{key} must hold integers, got dtype {a.dtype}")
        if a.shape != shape:
            raise _bad(f"{key} must have shape {shape}, got {a.shape}")
        if a.size and (a.min() < 0 or a.max() >= count):
            raise _bad(f"{key} must hold indices of {what} in [0, {count - 1}], got [{a.min()}, {a.max()}]")
        return np.ascontiguousarray(a, dtype=np.int32)

    version = get("format_version")
    if version.dtype.kind not in "iu" or version.size != 1:
        raise _bad(f"format_version must be one integer, got {version.dtype} {version.shape}")
    if int(version.reshape(-1)[0]) != _FORMAT_VERSION:
        raise ValueError(f"unsupported decomposition format version {int(version.reshape(-1)[0])}")
    raw = get("settings")
    if raw.dtype != np.uint8 or raw.ndim != 1:
        raise _bad(f"settings must be (m,) uint8 (JSON text), got {raw.dtype} {raw.shape}")
    try:
        settings = json.loads(raw.tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise _bad(f"settings are not valid JSON ({exc})") from None
    if not isinstance(settings, dict):
        raise _bad(f"settings must be a JSON object, got {type(settings).__name__}")
    origin = floats("origin", (3,), MAX_COORDINATE).copy()  # the caller's array stays the caller's

    base = get("base")
    if base.ndim != 2 or base.shape[1:] != (3,) or base.shape[0] < 1:
        raise _bad(f"base must have shape (n, 3) with n >= 1, got {base.shape}")
    n = base.shape[0]
    out = {"base": floats("base", (n, 3))}
    details = get("details")
    if details.ndim != 2 or details.shape[1:] != (n,):
        raise _bad(f"details must have shape (k, {n}), got {details.shape}")
    k = details.shape[0]
    if not 1 <= k < MAX_LEVELS:
        raise _bad(f"details has {k} bands; 1 to {MAX_LEVELS - 1} are supported")
    out["details"] = floats("details", (k, n))
    normals = floats("base_normals", (n, 3))
    off_unit = np.abs(np.einsum("ij,ij->i", normals, normals) - 1.0) > 1e-6
    if off_unit.any():  # a zero row would drop that point's detail without a word
        raise _bad(f"base_normals must be unit vectors ({int(off_unit.sum())} are not, first: row "
                   f"{int(np.argmax(off_unit))})")
    out["base_normals"] = normals
    labels = get("labels")
    if labels.shape != (k, n):
        raise _bad(f"labels must have shape ({k}, {n}), got {labels.shape}")
    label_rows = []
    for l in range(k):
        nb = get(f"neighborhoods_{l}")
        if nb.ndim != 2 or nb.shape[0] < 1 or not 1 <= nb.shape[1] <= MAX_NEIGHBORS:
            raise _bad(f"neighborhoods_{l} must have shape (clusters >= 1, 1..{MAX_NEIGHBORS}), got {nb.shape}")
        c = nb.shape[0]
        out[f"neighborhoods_{l}"] = indices(f"neighborhoods_{l}", nb.shape, c, "clusters")
        h = floats(f"kernel_{l}", (c,), 1e100)
        if not (h >= 1e-100).all():
            raise _bad(f"kernel_{l} must hold kernel widths in [1e-100, 1e100]")
        out[f"kernel_{l}"] = h
        anchors = indices(f"anchors_{l}", (c,), n, "points")
        out[f"anchors_{l}"] = anchors
        out[f"frames_{l}"] = indices(f"frames_{l}", (c, 2), c, "clusters")
        row = labels[l]
        if row.dtype.kind not in "iu":
            raise _bad(f"labels must hold integers, got dtype {row.dtype}")
        if row.min() < 0 or row.max() >= c:
            raise _bad(f"labels of level {l} must be clusters in [0, {c - 1}], got [{row.min()}, {row.max()}]")
        row = row.astype(np.int32)
        if not (row[anchors] == np.arange(c)).all():
            raise _bad(f"anchors_{l} must each be a member of its own cluster")
        label_rows.append(row)
        out[f"local_{l}"] = floats(f"local_{l}", (n, 3))
    out["labels"] = np.ascontiguousarray(np.stack(label_rows))
    if "parts" in arrays:  # written for a decomposition of connected parts (pointscale.parts)
        out["parts"] = indices("parts", (n,), n, "parts")
    _check_settings(settings, k, _bad)
    return out, origin, settings


# Settings that decompose records as numbers (whole numbers: the first three).
_WHOLE_SETTINGS = ("levels", "neighbors", "max_iterations")
_NUMBER_SETTINGS = ("decimation", "kernel", "tolerance", "max_variation")


def _check_settings(settings: dict, bands: int, bad) -> None:
    """The settings a file gives, which `pointscale info` and the warnings print: numbers where
    decompose writes numbers, the level count the arrays have, and text without control
    characters (a shared file's settings printed escape sequences to the terminal)."""
    for key in _WHOLE_SETTINGS + _NUMBER_SETTINGS:
        if key not in settings:
            continue
        value = settings[key]
        whole = key in _WHOLE_SETTINGS
        # A whole number may come as 30.0: decompose by parts records the caller's own value.
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if not number or (whole and not float(value).is_integer()):
            raise bad(f"settings['{key}'] must be a {'whole ' if whole else ''}number, got {json.dumps(value)[:40]}")
    if "levels" in settings and settings["levels"] != bands + 1:
        raise bad(f"settings['levels'] is {settings['levels']}, but the arrays hold {bands + 1} levels")

    def texts(value):
        if isinstance(value, str):
            yield value
        elif isinstance(value, dict):
            for key, item in value.items():
                yield key
                yield from texts(item)
        elif isinstance(value, list):
            for item in value:
                yield from texts(item)
    for text in texts(settings):
        if not text.isprintable():
            raise bad(f"settings hold text with a control character: {text[:40]!r}")


_STATS_KEYS = ("support_points", "kernel_width", "not_converged", "degenerate", "consistency_iterations",
               "consistency_residual", "pinned")


def _checked_stats(arrays, bands: int) -> list | None:
    """The saved per-level report (JSON), or None for a file saved before reports were kept."""
    if "stats" not in arrays:
        return None
    raw = np.asarray(arrays["stats"])
    try:
        if raw.dtype != np.uint8 or raw.ndim != 1:
            raise ValueError(f"must be (m,) uint8 JSON text, got {raw.dtype} {raw.shape}")
        stats = json.loads(raw.tobytes().decode("utf-8"))
        if not isinstance(stats, list) or len(stats) != bands:
            raise ValueError(f"must list one report per band ({bands})")
        for report in stats:
            if not isinstance(report, dict) or set(report) != set(_STATS_KEYS):
                raise ValueError(f"each report must have exactly the keys {', '.join(_STATS_KEYS)}")
            for key, value in report.items():
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
                    raise ValueError(f"{key} must be a finite number, got {value!r}")
    except (ValueError, UnicodeDecodeError, RecursionError, TypeError, OverflowError) as exc:
        raise _bad(f"stats {exc}") from None
    return stats


def _level_index(l, count: int) -> int:
    # A bool is an int to Python, but True is no level number anyone means.
    if isinstance(l, (bool, np.bool_)) or not isinstance(l, (int, np.integer)) or not 0 <= l < count:
        raise ValueError(f"level must be an integer in [0, {count - 1}], got {l!r}")
    return int(l)


def coarse_base_warning(n: int, levels: int = 4, decimation: float = 0.25) -> str | None:
    """The warning `decompose` gives when level 0 would keep too few support points, or None.
    Callers that run decompose on a worker thread can show it without catching warnings."""
    n = positive(n, "n", integer=True)
    levels, decimation = number(levels, "levels", integer=True), number(decimation, "decimation")
    _core.DecomposeOptions(levels=levels, decimation=decimation).validate()
    coarse = int(np.floor(decimation ** (levels - 1) * n))
    if coarse >= FEW_COARSE_POINTS:
        return None
    return (f"levels={levels} and decimation={decimation} leave {coarse} support points at level 0 of {n}; "
            f"a base this coarse can be distorted. Use fewer levels or a larger decimation "
            f"(at least {FEW_COARSE_POINTS} is safe).")


def _scale_space(levels, decimation, kernel, neighbors, tolerance, max_iterations, max_variation,
                 thin_sheets: bool = False) -> _core.DecomposeOptions:
    """The core's settings of the scale space that decompose() and decompose_rayshoot() build
    alike, the numbers converted; the core checks their ranges."""
    mls = mls_options(neighbors, tolerance, max_iterations)
    return _core.DecomposeOptions(levels=number(levels, "levels", integer=True),
                                  decimation=number(decimation, "decimation"), kernel=number(kernel, "kernel"),
                                  max_variation=number(max_variation, "max_variation"), mls=mls,
                                  thin_sheets=thin_sheets)


def _settings_record(options: _core.DecomposeOptions) -> dict:
    """The scale space's settings as a decomposition's settings keep them."""
    return dict(levels=options.levels, decimation=options.decimation, kernel=options.kernel,
                neighbors=options.mls.neighbors, tolerance=options.mls.tolerance,
                max_iterations=options.mls.max_iterations, max_variation=options.max_variation)


def _require_round_trip(dec: "Decomposition", points: np.ndarray, why: str) -> None:
    """Refuses a decomposition that does not give its input back (a collapsed or inflated base)."""
    back = dec._reconstruct(np.ones(dec.n_bands), None)
    scale = max(float(np.abs(points - dec.origin).max()), np.finfo(float).tiny)
    error = float(np.abs(back - points).max()) if np.isfinite(back).all() else np.inf
    if not error <= 1e-6 * scale:
        raise ValueError(f"the decomposition does not give its input back (off by {error:.3g}, the input spans "
                         f"{2 * scale:.3g}): {why}")


def decompose(points, levels: int = 4, *, decimation: float = 0.25, kernel: float = 1.0, normals=None,
              neighbors: int = 24, tolerance: float = 1e-7, max_iterations: int = 30,
              max_variation: float = 0.05, smoother: str = "mls", encoding: str = "projection",
              diffusion_iterations: int = 10, lam: float = 0.5, taubin: bool = True, diffusion_neighbors: int = 10,
              threads: int = 0, progress=None, faces=None, edges=None, mirror=None, sheets: bool = False) -> Decomposition:
    """Builds the multiscale representation P^0 + D^0 + ... + D^{k-1} of a point cloud (Sec. 7).

    points      (n, 3) positions; a mesh's vertices work as they are
    levels      point clouds P^0..P^k, so levels - 1 detail bands (levels=4 gives the 3 bands of Fig. 7)
    decimation  gamma in (0, 1): level l-1 is projected onto gamma**(k-l+1) * n cluster centroids
    kernel      kernel width as a multiple of the local spacing of those centroids
    normals     optional (n, 3) normals: only their orientation is used, for level 0's outside
    neighbors   support points in each plane fit (4..1024)
    threads     worker threads, 0 for all cores, at most 1024; a thread the system cannot start
                stops the work with RuntimeError
    progress    progress(fraction) -> bool; returning False stops and raises pointscale.Cancelled
    smoother    "mls" (Sec. 7) or "diffusion": each decimated level is first smoothed by
                diffusion_iterations Laplacian steps of lam over diffusion_neighbors, Taubin's
                volume-keeping variant when taubin (Sec. 5.1)
    encoding    "projection" (Sec. 6.2, exact round trip) or "rayshoot" (Sec. 6.1, see
                decompose_rayshoot: the finest level resamples the input surface)
    faces, edges  optional mesh connectivity: faces (m, k) or a list of polygons, edges (m, 2).
                Each connected part is then decomposed alone (pointscale.parts), so parts that
                lie close together neither blend nor move with each other's edits; a part too
                small for `levels` keeps the levels it supports, with a warning that names it.
                dec.parts lists the parts. A vertex in no face or edge joins its nearest part.
    sheets      keep two-sided thin sheets apart (a leaf, sheet metal, a wall scanned from both
                sides, thinner than the kernel): the sides are told apart by the normals, which
                must then face outward: given; when None, those of the faces' winding when faces
                are given and wound consistently (sheets.winding_normals; a warning says when they
                are not), else estimated and oriented. A point's
                fits, clusters and level normals then take only points whose normals turn less
                than 120 degrees from its own, so a surface that turns further within a kernel
                (a wire, a sharp rim) is not smoothed across either. Off by default: it costs
                time (README, "Thin sheets").
    mirror      optional pointscale.Mirror (or axes such as "x"): `points` are one half of a model
                symmetric about those planes; the whole model is decomposed and every output is
                exactly symmetric, points on a plane stay on it (pointscale.mirror)
    Supported input: coordinates within +-1e150, spanning 1e-50 to 1e50 about their centre
    (the core's validation.h says why); levels up to 64, kernel 0.001..1000, max_iterations up to 1000,
    diffusion_iterations up to 10000 and below what Taubin's lam|mu pair keeps stable. Anything
    else raises ValueError, as does a diffusion that would not give the input back.
    """
    sheets = flag(sheets, "sheets")
    if sheets and normals is None and faces is not None:
        normals = _normals_from_winding(points, faces)  # a mesh without normals still faces a way
    if mirror is not None:
        arguments = dict(locals())  # every argument, so options added later pass through too
        from .mirror import decompose_mirrored
        return decompose_mirrored(**arguments)
    if smoother not in ("mls", "diffusion"):
        raise ValueError(f"smoother must be 'mls' or 'diffusion', got {smoother!r}")
    if encoding not in ("projection", "rayshoot"):
        raise ValueError(f"encoding must be 'projection' or 'rayshoot', got {encoding!r}")
    if sheets and (encoding != "projection" or smoother != "mls"):
        raise ValueError("sheets=True keeps thin sheets apart with the MLS smoother and projection encoding; "
                         f"smoother={smoother!r} and encoding={encoding!r} would blend the two sides")
    if faces is not None or edges is not None:
        from .parts import connected_parts
        p = as_points(points)
        labels, count = connected_parts(p, faces, edges, threads=threads)
        if count > 1:
            if sheets and normals is None:  # the parts' own warnings are not shown: said of the whole
                _warn_estimated_sides(p, threads)
            options = dict(decimation=decimation, kernel=kernel, neighbors=neighbors, tolerance=tolerance,
                           max_iterations=max_iterations, max_variation=max_variation, smoother=smoother,
                           encoding=encoding, diffusion_iterations=diffusion_iterations, lam=lam, taubin=taubin,
                           diffusion_neighbors=diffusion_neighbors, threads=threads, sheets=sheets)
            dec = _decompose_by_part(p, labels, count, levels, normals, options, as_callback(progress))
            message = _rays_missed_warning(dec.settings.get("rays_missed", []))  # the parts' are not shown
            if message:
                warnings.warn(message, stacklevel=2)
            return dec
    if encoding == "rayshoot":
        return decompose_rayshoot(
            points, levels, smoother=smoother, decimation=decimation, kernel=kernel, normals=normals,
            neighbors=neighbors, tolerance=tolerance, max_iterations=max_iterations, max_variation=max_variation,
            diffusion_iterations=diffusion_iterations, lam=lam, taubin=taubin,
            diffusion_neighbors=diffusion_neighbors, threads=threads, progress=progress)
    diffusion = None
    if smoother == "diffusion":
        diffusion = smoother_options(diffusion_iterations, lam, taubin, diffusion_neighbors)
    options = _scale_space(levels, decimation, kernel, neighbors, tolerance, max_iterations, max_variation,
                           thin_sheets=bool(sheets))
    levels, decimation = options.levels, options.decimation
    p = as_array(points)
    n_arr = None if normals is None else as_array(normals, "normals")
    # The core checks the settings, the points (count, surface, coordinates) and the normals;
    # here on the raw points, before they are centred and their sides estimated.
    _core.check_decompose_input(p, n_arr, options, diffusion=diffusion)
    message = coarse_base_warning(len(p), levels, decimation)
    if message:
        warnings.warn(message, stacklevel=2)
    if sheets and n_arr is not None:
        from .sheets import check_sheet_normals
        check_sheet_normals(n_arr)
    elif sheets:
        _warn_estimated_sides(p, threads)
    progress = as_callback(progress)
    origin = centre(p)
    settings = dict(_settings_record(options), smoother=smoother, encoding=encoding)
    if sheets:
        settings["sheets"] = True
    if diffusion is not None:
        settings["diffusion"] = settings_record(diffusion)
    model = _core.decompose(p, origin, n_arr, options=options, diffusion=diffusion, progress=progress,
                            threads=thread_option(threads), estimate_sides=bool(sheets) and n_arr is None)
    dec = Decomposition(model, origin, settings)
    _require_finite_model(dec)
    if diffusion is not None:
        _require_round_trip(dec, p, f"diffusion_iterations={diffusion.iterations} smoothed the support too far; "
                                    "use fewer iterations")
    return dec


def _normals_from_winding(points, faces):
    """sheets=True on a mesh given without normals: outward normals from its faces' winding
    (sheets.winding_normals), or None, with a warning that says why, to estimate them."""
    from .parts import connectivity_pairs
    from .sheets import winding_normals
    p = as_points(points)
    connectivity_pairs(len(p), faces)  # the faces' shape and indices, refused as decompose refuses them
    normals, why_not = winding_normals(p, faces)
    if why_not:
        warnings.warn(why_not, stacklevel=3)
    return normals


# Set while a part is decomposed alone: the sides were checked on the whole model, and a part's
# warnings are not shown.
_SIDES_CHECKED = contextvars.ContextVar("pointscale_sides_checked", default=False)


def _warn_estimated_sides(p, threads) -> None:
    if _SIDES_CHECKED.get():
        return
    from .sheets import estimated_sides_warning
    message = estimated_sides_warning(p, threads)
    if message:
        warnings.warn(message, stacklevel=3)


def _missed_rays_of_parts(parts, bands: int) -> list:
    """Per band of the whole, the points (whole-model indices) whose ray missed in any part; a
    part with fewer bands has them at the finest of the whole's (pointscale.parts)."""
    missed = [[] for _ in range(bands)]
    for idx, part, _ in parts:
        if part is None:
            continue
        for b, m in enumerate(rays_missed_points(part)):
            missed[bands - part.n_bands + b].append(idx[np.asarray(m, dtype=np.int64)])
    return [np.sort(np.concatenate(m)).astype(np.int32) if m else np.zeros(0, np.int32) for m in missed]


def _decompose_by_part(p, labels, count, levels, normals, options, progress) -> Decomposition:
    """decompose() of each connected part alone, joined into one Decomposition (pointscale.parts)."""
    from .parts import decompose_parts, leading_points, parts_warning
    scale_space = _scale_space(levels, options["decimation"], options["kernel"], options["neighbors"],
                               options["tolerance"], options["max_iterations"], options["max_variation"])
    scale_space.validate()  # before the parts' sizes are weighed with them
    levels, decimation, neighbors = scale_space.levels, scale_space.decimation, scale_space.mls.neighbors
    # decompose_parts refuses a leading part too small for the levels, as decompose refuses it alone
    require_extent(p)
    n_arr = as_normals_of(normals, p)
    origin = centre(p)

    def decompose_one(points, part_normals, part_levels, part_progress):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the parts' warnings are summed up below
            checked = _SIDES_CHECKED.set(True)  # decompose() checked the whole model's sides
            try:
                return decompose(points, part_levels, normals=part_normals, progress=part_progress, **options)
            finally:
                _SIDES_CHECKED.reset(checked)

    parts = []
    arrays, stats, reports = decompose_parts(p, n_arr, labels, count, levels, decimation, neighbors,
                                             MIN_COARSE_POINTS, decompose_one, progress, origin,
                                             threads=thread_option(options["threads"]), parts_out=parts)
    model = _core.Model.from_arrays(arrays)
    dec_settings = dict(levels=levels, decimation=decimation, kernel=options["kernel"], neighbors=neighbors,
                        tolerance=options["tolerance"], max_iterations=options["max_iterations"],
                        max_variation=options["max_variation"], smoother=options["smoother"],
                        encoding=options["encoding"], parts=reports)
    if options["smoother"] == "diffusion":  # as one part records it
        dec_settings["diffusion"] = settings_record(smoother_options(
            options["diffusion_iterations"], options["lam"], options["taubin"], options["diffusion_neighbors"]))
    missed = None
    if options["encoding"] == "rayshoot":
        missed = _missed_rays_of_parts(parts, levels - 1)
        dec_settings["rays_missed"] = [int(len(m)) for m in missed]
    if options.get("sheets"):
        dec_settings["sheets"] = True
    dec = Decomposition(model, origin, dec_settings, _stats=stats, _missed_rays=missed)
    _require_finite_model(dec)
    for message in (coarse_base_warning(leading_points(reports), levels, decimation), parts_warning(reports, levels)):
        if message:
            warnings.warn(message, stacklevel=3)
    return dec


def _require_finite_model(dec: "Decomposition") -> None:
    for finite, what in ((dec._model.base_finite, "base"), (dec._model.details_finite, "detail")):
        if not finite:
            raise_not_finite(f"the decomposition's {what}")


def _check_decomposition(dec) -> None:
    if not isinstance(dec, Decomposition):
        raise ValueError(f"expected a pointscale.Decomposition, got {type(dec).__name__}")


def _gains_array(dec: Decomposition, gains) -> np.ndarray:
    k, n = dec.n_bands, dec.n_points
    if gains is None:
        return np.ones(k)
    try:
        g = np.asarray(gains)
        if g.dtype == object or not (np.issubdtype(g.dtype, np.floating) or np.issubdtype(g.dtype, np.integer)
                                     or g.dtype == bool):
            raise TypeError(g.dtype)  # complex ones would lose their imaginary part
        g = g.astype(np.float64)
    except (TypeError, ValueError):
        raise ValueError("gains must be real numbers: (k,) per band or (k, n) per point") from None
    # The core checks the shape, finiteness and size (validation.h); a mirrored decomposition's
    # gains are first the half's, which only this package knows. (k, 1) is per band, as the
    # core takes it.
    per_point = g.ndim == 2 and g.shape != (k, 1)
    if g.ndim not in (1, 2) or (dec._mirror is not None and per_point and g.shape != (k, n)):
        raise ValueError(f"gains must have shape ({k},) per band or ({k}, {n}) per point, got {g.shape}")
    if per_point and dec._mirror is not None:
        g = dec._mirror.full_values(g)  # a point's reflections take its gains
    return np.ascontiguousarray(g)


def _base_array(dec: Decomposition, base, caller: str = "reconstruct"):
    """The edited base, checked, in world coordinates (the core centres it); of a mirrored
    decomposition, the half's edit (its move from dec.base) mirrored onto the whole model's own
    base, so that every point the edit leaves alone keeps its base bit for bit (the whole model
    is symmetric only to rounding and its clusters' asymmetry, which an edit must not add)."""
    if base is None:
        return None
    if dec._mirror is None:
        return as_array(base, "base")  # its count, values and reach the core checks (validation.h)
    b = as_points(base, "base")  # checked before the mirror's arithmetic reads it
    if b.shape[0] != dec.n_points:  # the half's, which only this package knows
        raise ValueError(f"base must have the decomposition's {dec.n_points} points, got {b.shape[0]}")
    require_near(b, dec.origin, "base", "the decomposition")
    _check_mirror_crossings(dec._mirror, b, caller)
    return (dec._model.base + dec.origin) + dec._mirror.full_vectors(b - dec.base)


def _check_mirror_crossings(symmetry, b: np.ndarray, caller: str) -> None:
    """An edited half of a mirrored model that reaches across its plane: the result is held at
    the plane there, as Blender's Mirror modifier with Clipping holds vertices, so a few points
    pushed over by a brush are said in a warning; a half moved or flipped across the plane as a
    whole would come back flattened onto it, and is refused."""
    for name, count, depth, off in symmetry.crossings(b):
        plane = f"the {name} mirror plane"
        if count > off // 2:
            raise ValueError(f"base: {count} of the half's {off} points off {plane} lie across it (up to {depth:.3g} "
                             "beyond): a mirrored model is one half and its reflection, so a half moved or flipped "
                             "across its plane overlaps its own mirror image. Keep the half on its side (flip the "
                             "whole model, or decompose the flipped half again)")
        warnings.warn(f"{caller}: {count} points of the edited base lie across {plane} (up to {depth:.3g} "
                      "beyond); a mirrored model's half stays on its side, so their results are held at the "
                      "plane, as the Mirror modifier's Clipping holds vertices", stacklevel=4)


def reconstruct(dec: Decomposition, gains=None, base=None, *, progress=None, folds: str = "ignore",
                fold_reference: str = "input"):
    """The finest level rebuilt from P^0 with each band scaled by its gain (Eq. 9-11).

    gains  (k,) per band or (k, n) per point (painted gains); None means all 1
    base   an edited P^0 (n, 3): the detail is carried along its new normals (Sec. 8.1); it
           must still span a surface (a plane will do; a point or a line is refused)
    folds  "ignore": the points (n, 3); "report": (points, Folds), the points unchanged and
           which of them fold over the base; "prevent": (points, Folds) with the gain limited,
           point by point and smoothly, where the surface would fold (pointscale.folds)
    fold_reference  "input" (default): count only the folds that the gains or the edit add to
           the input's own; "base": every fold over the base
    Normals of every level are recomputed from that level's current points, so with unit gains
    and the unedited base this returns the input; dec.base handed back is the unedited base.
    The first call on an edited base finds what every edit needs (each base point's ring, plane
    and foot, and the stored base's level normals at unit gains) and keeps it with dec, about
    250 bytes a point at 4 levels: the calls after it, on any thread, cost the edited pass
    alone. Results are the same bit for bit whichever call came first.
    """
    _check_decomposition(dec)
    g = _gains_array(dec, gains)
    b = _base_array(dec, base)
    from .folds import _fold_mode_option, _reference_option
    mode = _fold_mode_option(folds)
    _reference_option(fold_reference)
    out = dec._reconstruct(g, b, progress=as_callback(progress))
    return _result_with_folds(dec, out, b, mode, fold_reference)


def _result_with_folds(dec: Decomposition, out: np.ndarray, b, mode: str, fold_reference: str):
    """A reconstruction of the whole model as reconstruct() returns it: the half's points, and
    their Folds unless mode is "ignore"."""
    from .folds import with_folds, with_folds_of_half
    out = finite_result(out, "the reconstruction")
    if mode == "ignore":
        return dec._symmetric(out)
    if dec._mirror is not None:
        return with_folds_of_half(dec, out, b, mode, fold_reference)
    out, found = with_folds(dec, out, b, mode, fold_reference)
    return dec._symmetric(out), found


class Reconstructor:
    """reconstruct() for one decomposition over and over, as an editing session calls it.

    Holds the model in a spatially coherent point order, each level's grouping by cluster and
    the working storage (about the decomposition's size again); its first call on an edited
    base finds what every edit needs (each base point's ring, plane and foot) and keeps it, and
    it keeps the stored base's level normals for the gains last used. So a call costs the fits
    and little else; an edited call with the gains of the edited call before it, on a base that
    changed at fewer than a quarter of its points since then (a brush dab), redoes only what
    those changes reach. Results are bit for bit those of reconstruct(dec, gains, base). Calls on
    one Reconstructor run one at a time; use reconstruct() for a one-off call.
    """

    def __init__(self, dec: Decomposition):
        _check_decomposition(dec)
        self._dec = dec
        self._core = _core.Reconstructor(dec._model)
        self._calling = threading.local()  # set while this thread is inside reconstruct()

    def reconstruct(self, gains=None, base=None, *, progress=None, folds: str = "ignore",
                    fold_reference: str = "input"):
        """As pointscale.reconstruct(dec, gains, base, folds=..., fold_reference=...): the finest
        level (n, 3), or (points, Folds) with folds "report" or "prevent"."""
        from .folds import _fold_mode_option, _reference_option
        g = _gains_array(self._dec, gains)
        b = _base_array(self._dec, base, "Reconstructor.reconstruct")
        mode = _fold_mode_option(folds)
        _reference_option(fold_reference)
        if getattr(self._calling, "active", False):
            # Calls run one at a time: this thread would wait on itself, for ever, deaf to Ctrl-C.
            raise ValueError("Reconstructor.reconstruct was called again from within its own call (from its "
                             "progress callback?): calls on one Reconstructor run one at a time. Use another "
                             "Reconstructor, or pointscale.reconstruct(), there")
        self._calling.active = True
        try:
            out = self._core.reconstruct(g, base=b, progress=as_callback(progress), origin=self._dec.origin)
            return _result_with_folds(self._dec, out, b, mode, fold_reference)
        finally:
            self._calling.active = False


def reconstruct_levels(dec: Decomposition, gains=None, base=None) -> np.ndarray:
    """Every level P^0..P^k rebuilt like reconstruct(): (k+1, n, 3)."""
    _check_decomposition(dec)
    levels, _ = dec._reconstruct(_gains_array(dec, gains), _base_array(dec, base, "reconstruct_levels"),
                                 keep_levels=True)
    return finite_result(np.stack([dec._symmetric(level) for level in levels]), "the reconstruction")


def blend(dec: Decomposition, t: float) -> np.ndarray:
    """The continuous blend of Eq. 20-21: t in [0, k]; whole t gives level(t)."""
    _check_decomposition(dec)
    try:
        if isinstance(t, (str, bytes, bool, np.bool_)):  # float("1") and float(True) would pass
            raise TypeError
        t = float(t)
    except (TypeError, ValueError):
        raise ValueError(f"t must be a number in [0, {dec.n_bands}], got {t!r}") from None
    if not (0.0 <= t <= dec.n_bands):
        raise ValueError(f"t must be in [0, {dec.n_bands}], got {t}")
    l = min(int(np.floor(t)), dec.n_bands)
    alpha = t - l
    lower = dec.level(l)
    if alpha == 0.0:
        return lower
    return lower + alpha * (dec.level(l + 1) - lower)


def decompose_rayshoot(points, levels: int = 4, *, smoother: str = "mls", decimation: float = 0.25,
                       kernel: float = 1.0, normals=None, neighbors: int = 24, tolerance: float = 1e-7,
                       max_iterations: int = 30, max_variation: float = 0.05, diffusion_iterations: int = 10,
                       lam: float = 0.5, taubin: bool = True, diffusion_neighbors: int = 10,
                       fine_kernel: float = 0.5, max_distance=None, threads: int = 0,
                       progress=None) -> Decomposition:
    """Multiscale decomposition with bottom-up ray-shooting encoding (Sec. 6.1).

    The scale space is built as in decompose() (smoother "mls": decimate and project, Sec. 7;
    "diffusion": the decimated support is diffused first, Sec. 5.1, with diffusion_iterations,
    lam, taubin and diffusion_neighbors). Then P^0 is kept and every finer level is where rays from
    the level below, along its normals, meet the next finer surface. The finest level therefore
    resamples the input's MLS surface: reconstruct() gives it back exactly, not the input points.
    settings["rays_missed"] counts, per band, rays that found no surface (these fall back to the
    orthogonal projection of their origin, so those points of the finest level may lie off the
    input surface); rays_missed_points(dec) lists them, and stats[l]["not_converged"] repeats
    the count per level.
    fine_kernel  kernel of the input's own MLS surface, which the finest level resamples, as a
                 multiple of the input's spacing: small, so that it stays close to the samples
    """
    if smoother not in ("mls", "diffusion"):
        raise ValueError(f"smoother must be 'mls' or 'diffusion', got {smoother!r}")
    options = _scale_space(levels, decimation, kernel, neighbors, tolerance, max_iterations, max_variation)
    diffusion = None
    if smoother == "diffusion":
        diffusion = smoother_options(diffusion_iterations, lam, taubin, diffusion_neighbors)
    p = as_points(points)  # the core checks the rest, once centred
    n_arr = None if normals is None else as_array(normals, "normals")
    limit = math.inf if max_distance is None else number(max_distance, "max_distance")
    fine_kernel = number(fine_kernel, "fine_kernel")
    origin = centre(p)
    # The rays take more iterations than the projections: a ray's first plane can lie far off.
    rays = _core.RayOptions(neighbors=options.mls.neighbors, max_iterations=max(options.mls.max_iterations, 50),
                            max_distance=limit)
    model, missed = _core.decompose_rayshoot(p - origin, n_arr, options=options, diffusion=diffusion, rays=rays,
                                             fine_kernel=fine_kernel, progress=as_callback(progress),
                                             threads=thread_option(threads))
    settings = dict(_settings_record(options), smoother=smoother, encoding="rayshoot",
                    rays_missed=[int(len(m)) for m in missed])
    dec = Decomposition(model, origin, settings, _missed_rays=[np.asarray(m) for m in missed])
    _require_finite_model(dec)
    # The same coarse-base warning as the projection encoding: the scale space is built alike.
    for message in (coarse_base_warning(len(p), options.levels, options.decimation),
                    _rays_missed_warning(settings["rays_missed"])):
        if message:
            warnings.warn(message, stacklevel=2)
    return dec


def _rays_missed_warning(missed: list, where: bool = True) -> str | None:
    """The warning for rays that found no surface, or None: their points sit off the surface,
    which the counts in settings alone do not tell anyone."""
    total = int(sum(missed))
    if not total:
        return None
    return (f"ray shooting: {total} rays found no surface (per band, coarsest first: "
            f"{', '.join(str(int(m)) for m in missed)}); those points stay at their origin's orthogonal projection, "
            "so the finer levels may leave the surface there"
            + (" (settings['rays_missed'], rays_missed_points(dec))" if where else ""))


def rays_missed_warning(dec: Decomposition, where: bool = True) -> str | None:
    """What decompose_rayshoot warns of when rays found no surface, from a decomposition's
    settings, or None: for callers that cannot catch warnings (a worker thread). where: end
    with where the package keeps the counts and the points."""
    if not isinstance(dec, Decomposition):
        raise ValueError(f"rays_missed_warning needs a Decomposition, got {type(dec).__name__}")
    return _rays_missed_warning(dec.settings.get("rays_missed") or [], where)


def rays_missed_points(dec: Decomposition) -> list:
    """Per band, the indices of points whose ray missed in decompose_rayshoot (empty lists
    for a decomposition loaded from a file, which keeps only the counts in settings)."""
    if not isinstance(dec, Decomposition):
        raise ValueError(f"expected a pointscale.Decomposition, got {type(dec).__name__}")
    if dec._missed_rays is None:
        return [np.zeros(0, np.int32)] * dec.n_bands
    return list(dec._missed_rays)
