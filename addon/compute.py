"""Engine calls on plain arrays (no bpy): what each operator computes.

Operators read arrays from Blender, call one of these, and write the result.
bpy scripts can call them directly; they are safe to run in a worker thread.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from . import logic


@dataclass
class Layout:
    """Everything Decompose writes: the engine object, levels P^0..P^{k-1} and their normals."""

    dec: object
    levels: np.ndarray  # (k, n, 3)
    normals: np.ndarray  # (k, n, 3)
    warnings: tuple = ()  # what the engine warned about, for the operator's report

    @property
    def k(self) -> int:
        return self.levels.shape[0]


# The panel's names of the smoother and the encoding, which .blend recipes keep, and the engine's.
SMOOTHERS = {"MLS": "mls", "DIFFUSION": "diffusion"}
ENCODINGS = {"PROJECTION": "projection", "RAY": "rayshoot"}


def decompose_kwargs(levels=4, decimation=0.25, kernel=1.0, neighbors=24, threads=0,
                     smoother="MLS", encoding="PROJECTION") -> dict:
    """Keyword arguments for :func:`decompose` from the panel's settings."""
    if smoother not in SMOOTHERS or encoding not in ENCODINGS:
        raise ValueError(f"unknown smoother {smoother!r} or encoding {encoding!r}")
    return dict(levels=int(levels), decimation=as_typed(decimation), kernel=as_typed(kernel),
                neighbors=int(neighbors), threads=int(threads), smoother=smoother, encoding=encoding)


def as_typed(value: float) -> float:
    """A float property's value as the artist typed it: Blender keeps 0.3 as float32
    0.30000001192092896, which the engine's messages would print; the shortest decimal that
    float32 reads back as the same value (0.3) is what was typed."""
    return float(str(np.float32(value)))


def run_decompose(ps, points: np.ndarray, smoother="MLS", encoding="PROJECTION", **kwargs):
    """``ps.decompose`` with the panel's smoother (MLS, DIFFUSION) and encoding (PROJECTION:
    Sec. 7; RAY: ray shooting, Sec. 6.1)."""
    return ps.decompose(np.asarray(points, dtype=np.float64), smoother=SMOOTHERS[smoother],
                        encoding=ENCODINGS[encoding], **kwargs)


def decompose(ps, points: np.ndarray, progress=None, smoother="MLS", encoding="PROJECTION", **kwargs) -> Layout:
    """Decompose (n,3) points and extract the levels and normals the keys need."""
    problem = logic.check_points(points)
    if problem:
        raise ValueError(problem)
    # The engine's warning as data: catching warnings is not thread-safe, and this runs on a
    # worker thread while the UI (and other jobs) go on.
    levels_asked, decimation = kwargs.get("levels", 4), kwargs.get("decimation", 0.25)
    dec = run_decompose(ps, points, smoother, encoding, progress=progress, **kwargs)
    parts = dec.parts or []
    leading = ps.parts.leading_points(parts) if parts else len(points)  # a larger flat part keeps no levels
    messages = [ps.coarse_base_warning(leading, levels_asked, decimation)]
    if parts:
        messages.append(ps.parts.parts_warning(parts, levels_asked))
    missed = ps.rays_missed_warning(dec, where=False)
    if missed:
        messages.append(f"{missed}. Projection encoding shoots no rays")
    k = dec.n_bands
    levels = np.stack([dec.level(l) for l in range(k)])
    normals = np.stack([dec.normals(l) for l in range(k)])
    return Layout(dec, levels, normals, tuple(m for m in messages if m))


def edited_base(dec, base: np.ndarray) -> np.ndarray | None:
    """``base`` (the 'Level 0' key) in double precision, or None while the key still holds the
    decomposition's own base (as a key stores it, in single precision): the engine then starts
    from its exact base and reads level 0's normals instead of fitting them (a third faster).
    Vertices the edit did not move get the exact base back, so the engine sees them unmoved
    (it turns no detail there) rather than rounded to single precision."""
    if np.shape(base) != (dec.n_points, 3):
        return np.array(base, dtype=np.float64)  # the engine says what is wrong with it
    exact, exact32 = _exact_base(dec)
    key = np.asarray(base, dtype=np.float32)
    if np.array_equal(key, exact32):
        return None
    b = np.array(base, dtype=np.float64)
    same = key == exact32
    unmoved = same[:, 0] & same[:, 1] & same[:, 2]
    b[unmoved] = exact[unmoved]
    return b


# The exact base of the decompositions seen last, and as a key stores it: a decomposition never
# changes, and at a million vertices fetching and rounding its base costs more than the compare.
_exact_bases: dict = {}


def _exact_base(dec):
    held = _exact_bases.get(id(dec))
    if held is not None and held[0]() is dec:
        return held[1], held[2]
    exact = dec.base
    exact.setflags(write=False)
    if len(_exact_bases) >= 4:
        _exact_bases.pop(next(iter(_exact_bases)))
    _exact_bases[id(dec)] = (weakref.ref(dec), exact, exact.astype(np.float32))
    return exact, _exact_bases[id(dec)][2]


def rebuild(solver, dec, base: np.ndarray, gains=None, prevent_folds: bool = False, residual=None):
    """Full detail on an edited base P^0, each level's normals turned with the base (Sec. 8.1):
    (points, the Folds of the result). solver: the pointscale.Reconstructor of dec; residual:
    finest_residual()."""
    points, folds = solver.reconstruct(gains, edited_base(dec, base), folds="prevent" if prevent_folds else "report")
    return _with_residual(points, residual, gains), folds


def bake(solver, dec, base: np.ndarray, band_values, mask_weights, prevent_folds: bool = False, baked=None,
         residual=None):
    """Recursive reconstruction of the current band gains (with painted masks), on top of the
    gains ``baked`` before (logic.combined_gains): (points, the Folds of the result, the gains
    used). solver: the pointscale.Reconstructor of dec; residual: finest_residual()."""
    gains = logic.combined_gains(baked, logic.per_point_gains(band_values, mask_weights, dec.n_points))
    points, folds = solver.reconstruct(gains, edited_base(dec, base), folds="prevent" if prevent_folds else "report")
    return _with_residual(points, residual, gains), folds, gains


def _with_residual(points, residual, gains=None):
    """``points`` with the residual of finest_residual() as part of the finest band: scaled by
    that band's gain (per point when painted), as the band keys show it."""
    if residual is None:
        return points
    finest = 1.0 if gains is None else np.asarray(gains, dtype=np.float64)[-1]
    return points + (finest[:, None] if np.ndim(finest) else finest) * residual


# The residual of the decompositions seen last (see finest_residual): a decomposition never
# changes, and the residual costs a reconstruct.
_residuals: dict = {}


def finest_residual(solver, dec, read_basis) -> np.ndarray | None:
    """What the engine's finest level leaves out of the Basis, per vertex, or None when it is
    the Basis itself. Projection (Sec. 7) keeps the input as its finest level; ray shooting
    (Sec. 6.1) resamples the input's surface there, most vertices within about 1% of the
    diagonal (more where rays missed), so Rebuild Detail and Bake Filter add this difference back as part of the finest
    band (_with_residual), a fixed offset per vertex that does not turn with an edited base:
    unit gains on an unedited base then give the Basis, and other gains what the band keys show.
    read_basis: called for the Basis (n, 3) when the residual is not known yet."""
    if dec.settings.get("encoding") != "rayshoot":
        return None
    held = _residuals.get(id(dec))
    if held is not None and held[0]() is dec:
        return held[1]
    residual = np.asarray(read_basis(), dtype=np.float64) - solver.reconstruct()
    residual.setflags(write=False)
    if len(_residuals) >= 4:
        _residuals.pop(next(iter(_residuals)))
    _residuals[id(dec)] = (weakref.ref(dec), residual)
    return residual


#: The engine's words in its morph warnings, and the panel's for them.
_MORPH_WORDS = (("morph: ", ""), ("B (points_b)", "B"),
                ("evaluate(0, 1)", "'B detail' at 1"))


def _morph_words(message: str) -> str:
    """An engine warning of the morph as the panel says it (the operator adds 'Morph: ')."""
    for python, panel in _MORPH_WORDS:
        message = message.replace(python, panel)
    return message


def morph_keys(ps, a: np.ndarray, b: np.ndarray, base_points: np.ndarray | None = None, samples: int = 40000,
               align: str = "NONE", progress=None):
    """Eq. 22 as three arrays and the engine's warnings: (projected A, A + alpha detail at (1,0),
    at (0,1), warnings). progress: the engine's callback (fraction -> False to cancel), or None.

    p(alpha, beta) is linear in alpha and beta (also with alignment, whose placement follows
    beta linearly), so Blender's relative keys ``A detail`` = p(1,0) and ``B detail`` = p(0,1)
    over the Basis p(0,0) evaluate it exactly.
    """
    import warnings

    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if base_points is not None:
        base_points = np.asarray(base_points, dtype=np.float64)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = ps.morph(a, b, base_points, align=align.lower(), base_samples=samples, progress=progress)
    # The engine's overlap warning speaks Python: say it in the panel's words.
    messages = tuple(_morph_words(str(w.message)) for w in caught
                     if not str(w.message).startswith("A and B barely overlap"))
    if m.report["overlap"] < ps.morphing.OVERLAP_WARNING:
        messages += (f"A and B barely overlap (their bounding boxes share {m.report['overlap']:.0%}), so the morph "
                     "will not reach B: set Align in the Morph panel (Bounding Box, Principal Axes or Closest "
                     "Points), or move B onto A",)
    return m.evaluate(0.0, 0.0), m.evaluate(1.0, 0.0), m.evaluate(0.0, 1.0), messages
