"""The multiscale representation: decompose, reconstruct, blend, save and load (paper Sec. 4-7)."""
from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from . import _core
from ._checks import as_callback, as_points, centre, positive, require_surface

#: The coarsest level keeps gamma**(levels-1) * n points; fewer than this cannot carry a surface.
MIN_COARSE_POINTS = 8
# Below this many support points a closed base has too few clusters to keep its shape: the
# kernels then span a large part of it, and an edit of the base reaches far across it.
FEW_COARSE_POINTS = 100
_FORMAT_VERSION = 1


@dataclass
class Decomposition:
    """P^0 plus k signed normal-displacement bands D^0..D^{k-1} (Eq. 11), for n points.

    Every level keeps all n points, indexed like the input. Coordinates are the caller's.
    """

    _model: object
    origin: np.ndarray
    settings: dict
    _cache: dict = field(default_factory=dict, repr=False)
    # reconstruct()'s working arrays, kept between calls: two (n, 3) arrays, 48 bytes per point,
    # which at 100k points saves 2-3 ms a call of faulting fresh pages in.
    _buffers: object = field(default_factory=_core.ReconstructionBuffers, repr=False, compare=False)

    @property
    def base(self) -> np.ndarray:
        """P^0, the smoothest level: (n, 3)."""
        return self._model.base + self.origin

    @property
    def details(self) -> np.ndarray:
        """D^0..D^{k-1}, signed along the outward normals of each level: (k, n)."""
        return self._model.details

    @property
    def n_levels(self) -> int:
        """Number of point clouds P^0..P^k (k + 1)."""
        return self._model.bands + 1

    @property
    def n_bands(self) -> int:
        return self._model.bands

    @property
    def n_points(self) -> int:
        return self._model.base.shape[0]

    @property
    def stats(self) -> list[dict]:
        """Per level (0 first): support points, kernel width, projections that did not converge."""
        return self._model.reports

    def _levels(self):
        if "levels" not in self._cache:
            # The core adds the origin in place (a NumPy sum would allocate every level again).
            levels, normals = self._model.reconstruct(np.ones(self.n_bands), None, True, -1, None, self.origin)
            self._cache["levels"] = list(levels)
            self._cache["normals"] = list(normals)
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
        arrays["origin"] = np.asarray(self.origin, dtype=np.float64)
        arrays["settings"] = np.frombuffer(json.dumps(self.settings).encode(), dtype=np.uint8)
        arrays["format_version"] = np.array([_FORMAT_VERSION])
        return arrays

    @classmethod
    def from_dict(cls, arrays) -> "Decomposition":
        try:
            version = int(np.asarray(arrays["format_version"])[0])
            if version != _FORMAT_VERSION:
                raise ValueError(f"unsupported decomposition format version {version}")
            settings = json.loads(bytes(np.asarray(arrays["settings"], dtype=np.uint8)).decode())
            core_arrays = {k: np.asarray(v) for k, v in arrays.items() if k not in ("origin", "settings", "format_version")}
            model = _core.Model.from_arrays(core_arrays)
        except KeyError as exc:
            raise ValueError(f"not a pointscale decomposition: missing {exc}") from None
        return cls(model, np.asarray(arrays["origin"], dtype=np.float64).reshape(3), settings)

    def save(self, path) -> None:
        """Writes one .npz file."""
        path = os.fspath(path)
        tmp = path + ".part.npz"
        np.savez_compressed(tmp, **self.to_dict())
        os.replace(tmp, path)  # never leave a half-written file under the real name


def load(path) -> Decomposition:
    """Reads a file written by Decomposition.save."""
    try:
        with np.load(os.fspath(path), allow_pickle=False) as f:
            arrays = dict(f)
    except (OSError, EOFError, ValueError) as exc:
        raise ValueError(f"cannot read decomposition {path!s}: {exc}") from None
    return Decomposition.from_dict(arrays)


def _level_index(l, count: int) -> int:
    if not isinstance(l, (int, np.integer)) or not 0 <= l < count:
        raise ValueError(f"level must be an integer in [0, {count - 1}], got {l!r}")
    return int(l)


def coarse_base_warning(n: int, levels: int = 4, decimation: float = 0.25) -> str | None:
    """The warning `decompose` gives when level 0 would keep too few support points, or None.
    Callers that run decompose on a worker thread can show it without catching warnings."""
    coarse = int(np.floor(decimation ** (levels - 1) * n))
    if coarse >= FEW_COARSE_POINTS:
        return None
    return (f"levels={levels} and decimation={decimation} leave {coarse} support points at level 0 of {n}; "
            f"a base this coarse can be distorted. Use fewer levels or a larger decimation "
            f"(at least {FEW_COARSE_POINTS} is safe).")


def decompose(points, levels: int = 4, *, decimation: float = 0.25, kernel: float = 1.0, normals=None,
              neighbors: int = 24, tolerance: float = 1e-7, max_iterations: int = 30,
              max_variation: float = 0.05, smoother: str = "mls", encoding: str = "projection",
              diffusion_iterations: int = 10, lam: float = 0.5, taubin: bool = True, diffusion_neighbors: int = 10,
              threads: int = 0, progress=None) -> Decomposition:
    """Builds the multiscale representation P^0 + D^0 + ... + D^{k-1} of a point cloud (Sec. 7).

    points      (n, 3) positions; a mesh's vertices work as they are (faces are not used)
    levels      point clouds P^0..P^k, so levels - 1 detail bands (levels=4 gives the 3 bands of Fig. 7)
    decimation  gamma in (0, 1): level l-1 is projected onto gamma**(k-l+1) * n cluster centroids
    kernel      kernel width as a multiple of the local spacing of those centroids
    normals     optional (n, 3) normals: only their orientation is used, for level 0's outside
    neighbors   support points in each plane fit
    threads     worker threads, 0 for all cores
    progress    progress(fraction) -> bool; returning False stops and raises pointscale.Cancelled
    smoother    "mls" (Sec. 7) or "diffusion": each decimated level is first smoothed by
                diffusion_iterations Laplacian steps of lam over diffusion_neighbors, Taubin's
                volume-keeping variant when taubin (Sec. 5.1)
    encoding    "projection" (Sec. 6.2, exact round trip) or "rayshoot" (Sec. 6.1, see
                decompose_rayshoot: the finest level resamples the input surface)
    """
    if smoother not in ("mls", "diffusion"):
        raise ValueError(f"smoother must be 'mls' or 'diffusion', got {smoother!r}")
    if encoding not in ("projection", "rayshoot"):
        raise ValueError(f"encoding must be 'projection' or 'rayshoot', got {encoding!r}")
    from . import operators  # imports this module: import it late
    if encoding == "rayshoot":
        return operators.decompose_rayshoot(
            points, levels, smoother=smoother, decimation=decimation, kernel=kernel, normals=normals,
            neighbors=neighbors, tolerance=tolerance, max_iterations=max_iterations, max_variation=max_variation,
            diffusion_iterations=diffusion_iterations, lam=lam, taubin=taubin,
            diffusion_neighbors=diffusion_neighbors, threads=threads, progress=progress)
    diffusion = None
    if smoother == "diffusion":
        diffusion = operators._diffusion_options(diffusion_iterations, lam, taubin, diffusion_neighbors)
    levels = positive(levels, "levels", integer=True)
    if levels < 2:
        raise ValueError(f"levels must be at least 2 (a base and one band), got {levels}")
    decimation = positive(decimation, "decimation")
    if decimation >= 1.0:
        raise ValueError(f"decimation must be in (0, 1), got {decimation}")
    kernel = positive(kernel, "kernel")
    neighbors = positive(neighbors, "neighbors", integer=True, minimum=4)
    tolerance = positive(tolerance, "tolerance")
    max_iterations = positive(max_iterations, "max_iterations", integer=True)
    max_variation = positive(max_variation, "max_variation")
    need = int(np.ceil(MIN_COARSE_POINTS / decimation ** (levels - 1)))
    p = as_points(points)
    if len(p) < need:
        raise ValueError(f"decompose needs at least {need} points for levels={levels} and decimation={decimation} "
                         f"(the coarsest level keeps decimation**(levels-1) of them and needs {MIN_COARSE_POINTS}); "
                         f"got {len(p)}")
    require_surface(p)
    message = coarse_base_warning(len(p), levels, decimation)
    if message:
        warnings.warn(message, stacklevel=2)
    n_arr = None
    if normals is not None:
        n_arr = as_points(normals, "normals")
        if n_arr.shape != p.shape:
            raise ValueError(f"normals must have the shape of points {p.shape}, got {n_arr.shape}")
    progress = as_callback(progress)
    origin = centre(p)
    settings = dict(levels=levels, decimation=decimation, kernel=kernel, neighbors=neighbors,
                    tolerance=tolerance, max_iterations=max_iterations, max_variation=max_variation,
                    smoother=smoother, encoding=encoding)
    if diffusion is not None:
        settings["diffusion"] = dict(zip(("neighbors", "lam", "mu", "iterations"), diffusion))
    _core.set_threads(int(threads))
    model = _core.decompose(p, origin, n_arr, levels, decimation, kernel, neighbors, tolerance,
                            max_iterations, max_variation, diffusion, progress)
    return Decomposition(model, origin, settings)


def _check_decomposition(dec) -> None:
    if not isinstance(dec, Decomposition):
        raise ValueError(f"expected a pointscale.Decomposition, got {type(dec).__name__}")


def _gains_array(dec: Decomposition, gains) -> np.ndarray:
    k, n = dec.n_bands, dec.n_points
    if gains is None:
        return np.ones(k)
    try:
        g = np.asarray(gains, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("gains must be numbers: (k,) per band or (k, n) per point") from None
    if g.shape not in ((k,), (k, n)):
        raise ValueError(f"gains must have shape ({k},) per band or ({k}, {n}) per point, got {g.shape}")
    if not np.isfinite(g).all():
        raise ValueError("gains contain NaN or infinite values")
    return np.ascontiguousarray(g)


def _base_array(dec: Decomposition, base):
    """The edited base, checked, in world coordinates (the core centres it)."""
    if base is None:
        return None
    b = as_points(base, "base")
    if b.shape[0] != dec.n_points:
        raise ValueError(f"base must have the decomposition's {dec.n_points} points, got {b.shape[0]}")
    return b


def reconstruct(dec: Decomposition, gains=None, base=None, *, progress=None) -> np.ndarray:
    """The finest level rebuilt from P^0 with each band scaled by its gain (Eq. 9-11).

    gains  (k,) per band or (k, n) per point (painted gains); None means all 1
    base   an edited P^0 (n, 3): the detail is carried along its new normals (Sec. 8.1)
    Normals of every level are recomputed from that level's current points, so with unit gains
    and the unedited base this returns the input. The decomposition keeps two (n, 3) working
    arrays from the first call on (48 bytes per point) for the calls after it.
    """
    _check_decomposition(dec)
    g = _gains_array(dec, gains)
    b = _base_array(dec, base)
    return dec._model.reconstruct(g, b, False, -1, as_callback(progress), dec.origin, dec._buffers)


class Reconstructor:
    """reconstruct() for one decomposition over and over, as an editing session calls it.

    Holds the model in a spatially coherent point order, each level's grouping by cluster and
    the working storage (about the decomposition's size again), so that a call costs the fits
    and little else. Results are bit for bit those of reconstruct(dec, gains, base). Calls on
    one Reconstructor run one at a time; use reconstruct() for a one-off call.
    """

    def __init__(self, dec: Decomposition):
        _check_decomposition(dec)
        self._dec = dec
        self._core = _core.Reconstructor(dec._model)

    def reconstruct(self, gains=None, base=None, *, progress=None) -> np.ndarray:
        """As pointscale.reconstruct(dec, gains, base): the finest level, (n, 3)."""
        g = _gains_array(self._dec, gains)
        b = _base_array(self._dec, base)
        return self._core.reconstruct(g, b, as_callback(progress), self._dec.origin)


def reconstruct_levels(dec: Decomposition, gains=None, base=None) -> np.ndarray:
    """Every level P^0..P^k rebuilt like reconstruct(): (k+1, n, 3)."""
    _check_decomposition(dec)
    levels, _ = dec._model.reconstruct(_gains_array(dec, gains), _base_array(dec, base), True, -1, None, dec.origin)
    return np.stack(levels)


def blend(dec: Decomposition, t: float) -> np.ndarray:
    """The continuous blend of Eq. 20-21: t in [0, k]; whole t gives level(t)."""
    _check_decomposition(dec)
    try:
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
