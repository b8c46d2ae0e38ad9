"""Folds: where a reconstruction turns the surface over itself (the paper's future work, Sec. 9).

The base is the detail's parameter domain; a point folds when, on its ring (its 12 nearest base
points), the map from the base to the result stops being one to one: its ring's plane turns
against the base's there, or along a ring edge the order of the two points reverses (their
offsets cross). native/include/pointscale/folds.h has the exact tests.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _core

#: What folds are measured against. "input": only what a filter or an edit adds; an edge or a
#: ring plane that already folds in the input (its unedited reconstruction) is not counted, so
#: an unedited reconstruction has none. "base": every fold over the base, the input's own too
#: (Max Planck's scan folds over its 4-level base at 2.4% of its points, the dragon at 4.7%).
FOLD_REFERENCES = ("input", "base")
#: reconstruct(folds=...): "ignore" (the plain result), "report" (the result and its Folds),
#: "prevent" (the result with the gain limited where it folds, and its Folds).
FOLD_MODES = ("ignore", "report", "prevent")
#: Rounds of detect-and-lower that prevention runs at most; Folds.capped says when it stopped there.
MAX_FOLD_ROUNDS = 40

TURNED = 1   # Folds.kind bit: the ring's plane faces against the base's
CROSSED = 2  # Folds.kind bit: along a ring edge the two points' order reverses


@dataclass(frozen=True)
class Folds:
    """The folds of a result, and what prevention did.

    kind      (n,) uint8 bits per point of the returned points: TURNED (1), CROSSED (2)
    before    (n,) uint8, the same for the result as reconstructed (before any prevention)
    limiter   (n,) float64 in [0, 1]: the share of every band's gain kept at each point (all 1
              unless prevented); points where it is 1 are returned bit for bit as reconstructed
    rounds    rounds of prevention run; capped: it stopped at MAX_FOLD_ROUNDS with folds left
    """

    kind: np.ndarray
    before: np.ndarray
    limiter: np.ndarray
    rounds: int = 0
    capped: bool = False

    @property
    def mask(self) -> np.ndarray:
        """(n,) bool: the points that fold."""
        return self.kind != 0

    @property
    def count(self) -> int:
        return int(np.count_nonzero(self.kind))

    @property
    def count_before(self) -> int:
        return int(np.count_nonzero(self.before))

    @property
    def changed(self) -> np.ndarray:
        """(n,) bool: the points prevention moved (limiter below 1)."""
        return self.limiter < 1.0


def _reference_option(reference) -> str:
    if reference not in FOLD_REFERENCES:
        raise ValueError(f"fold_reference must be one of {', '.join(map(repr, FOLD_REFERENCES))}, got {reference!r}")
    return reference


def reference_for(dec, reference: str = "input"):
    """The core's reference for `dec` (kept with the decomposition once made): "input" costs one
    unedited reconstruction, the first time."""
    from .multiscale import reconstruct
    key = "fold_reference_" + _reference_option(reference)

    def make():  # the core checks the model and the input
        input_points = dec._full(reconstruct(dec)) if reference == "input" else None
        if dec._mirror is None:
            return _core.fold_reference(dec._model, input=input_points)
        # A mirrored model's stored whole base is symmetric only to about its rounding and its
        # levels' fits: measured on its exact reflection (the half's base, reflected), a point
        # and its reflection take the same rings, tests and limiter.
        base = dec._full(dec.base) - dec.origin
        normals = dec._mirror.full_vectors(dec.normals(0))
        return _core.fold_reference(dec._model, input=input_points, base=base, base_normals=normals)

    return dec._kept(key, make)


def find_folds(dec, points, base=None, *, fold_reference: str = "input") -> Folds:
    """The folds of `points`, a reconstruction (n, 3) of `dec` on `base` (the stored one when None)."""
    from ._checks import as_points
    from .multiscale import _base_array, _check_decomposition
    _check_decomposition(dec)
    ref = reference_for(dec, fold_reference)
    p = as_points(points, "points")  # its count the core checks (validation.h)
    if dec._mirror is not None and p.shape[0] != dec.n_points:  # the half's, which only this package knows
        raise ValueError(f"points must have the decomposition's {dec.n_points} points, got {p.shape[0]}")
    b = _whole_symmetric_base(dec, _base_array(dec, base, "find_folds"))
    kind = _core.find_folds(dec._model, ref, dec._full(p), base=b)
    return _of_half(dec, Folds(kind=kind, before=kind.copy(), limiter=np.ones(len(kind))))


def _whole_symmetric_base(dec, base):
    """A mirrored decomposition's edited whole base (as _base_array gives it: the half's edit
    on the whole model's own base) made exactly symmetric, as the reference's stored base and
    the half's points are (reference_for); unchanged without a mirror or an edit. Measured
    against the whole model's own base, which is symmetric only to its levels' fits, any
    edited base, even the stored one handed back, found hundreds of false folds, and Prevent
    Folds moved the whole model by up to 15% of its size."""
    if base is None or dec._mirror is None:
        return base
    return np.ascontiguousarray(dec._full(dec._symmetric(np.asarray(base))))


def _fold_mode_option(folds) -> str:
    if folds not in FOLD_MODES:
        raise ValueError(f"folds must be one of {', '.join(map(repr, FOLD_MODES))}, got {folds!r}")
    return folds


def with_folds(dec, points: np.ndarray, base, mode: str, reference: str):
    """(points, Folds) for reconstruct(folds="report" or "prevent"): `points` is its result,
    limited in place when preventing. For a mirrored decomposition `points` and `base` are the
    whole model's, and the Folds the half's."""
    ref = reference_for(dec, reference)
    if mode == "report":
        kind = _core.find_folds(dec._model, ref, points, base=base)
        return points, _of_half(dec, Folds(kind=kind, before=kind.copy(), limiter=np.ones(len(kind))))
    points = np.require(points, np.float64, ("C", "W"))
    rep = _core.limit_folds(dec._model, ref, points, base=base, origin=dec.origin, max_rounds=MAX_FOLD_ROUNDS)
    limiter = rep["limiter"] if rep["limiter"] is not None else np.ones(len(points))
    return points, _of_half(dec, Folds(kind=rep["after"], before=rep["before"], limiter=limiter,
                                       rounds=int(rep["rounds"]), capped=bool(rep["capped"])))


#: Passes of prevention on a mirrored model at most (each one limits what the last left folding).
MIRRORED_PASSES = 4


def with_folds_of_half(dec, out: np.ndarray, base, mode: str, reference: str):
    """(the half's points, Folds) for reconstruct(folds=...) on a mirrored decomposition: `out`
    and `base` are the whole model's. The folds are those of the half's result as returned
    (its orbit averages, reflected: what find_folds sees), and prevention limits the half, one
    limiter for a point and all its reflections. Limited on the whole model and averaged after,
    a point and its reflection kept different gains and their average folded again (2 to 95
    points on a mirrored handles plane at gains (3, 3, 3), while the Folds said none)."""
    m = dec._mirror
    ref = reference_for(dec, reference)
    half = dec._symmetric(out)
    base = _whole_symmetric_base(dec, base)
    if mode == "report":
        kind = _core.find_folds(dec._model, ref, dec._full(half), base=base)
        return half, _of_half(dec, Folds(kind=kind, before=kind.copy(), limiter=np.ones(len(kind))))
    # Where the limiter pulls each point: the half's base, as symmetric() makes the half's points.
    base_half = dec.base if base is None else dec._symmetric(np.asarray(base))
    n = half.shape[0]
    limiter = np.ones(n)
    before, rounds = None, 0
    for _ in range(MIRRORED_PASSES):
        whole = np.require(dec._full(half), np.float64, ("C", "W"))
        rep = _core.limit_folds(dec._model, ref, whole, base=base, origin=dec.origin, max_rounds=MAX_FOLD_ROUNDS)
        before = rep["before"] if before is None else before
        rounds += int(rep["rounds"])
        if rep["folded_before"] == 0:
            after = rep["before"]
            break
        step = m.least_of_orbit(rep["limiter"])
        moved = step < 1.0  # the others stay as reconstructed, bit for bit
        half = half.copy()
        half[moved] = base_half[moved] + step[moved, None] * (half[moved] - base_half[moved])
        limiter *= step
    else:
        after = _core.find_folds(dec._model, ref, dec._full(half), base=base)
    return half, Folds(kind=m.any_of_orbit(after), before=m.any_of_orbit(before), limiter=limiter, rounds=rounds,
                       capped=bool(after.any()))


def _of_half(dec, folds: Folds) -> Folds:
    """The folds of a mirrored decomposition's whole model as its half's: a point folds when
    any of its reflections does, and keeps the least gain any of them kept."""
    m = dec._mirror
    if m is None:
        return folds
    return Folds(kind=m.any_of_orbit(folds.kind), before=m.any_of_orbit(folds.before),
                 limiter=m.least_of_orbit(folds.limiter), rounds=folds.rounds, capped=folds.capped)
