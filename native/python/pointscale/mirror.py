"""Mirror symmetry: a half model and its reflections decomposed as one, exactly symmetric.

decompose(points, mirror=Mirror("x")) takes one half of a model that is symmetric about one or
more axis-aligned planes through a common origin (a half-mesh with Blender's Mirror modifier).
It builds the whole model, the half and its reflections (the orbit of every point under the
group the planes generate, 2, 4 or 8 copies), decomposes that with the ordinary path, and
returns every output for the half's points symmetrised: the average over the group of each
partner's result, reflected back. Reflection is an exact sign flip in coordinates centred on
the planes, and the average is taken one plane at a time, so a point on a plane (a seam point)
has its plane coordinate exactly 0 there at every level, with any gains or edited base, and
the partners of a point are its exact reflections. A round trip with unit gains gives the half
back exactly, its seam points snapped onto their planes.

Seam points (within `seam` of a plane) are kept once, not doubled across their plane. Every
other point stays on its side, farther than the seam from the plane (by OFF_SEAM): a level that
pulls it towards the plane would otherwise make it a seam point, and Blender's Mirror modifier
would merge it with its reflection.
"""
from __future__ import annotations

import json
import re
import warnings
from dataclasses import dataclass

import numpy as np

from ._checks import MAX_COORDINATE, as_normals_of, as_points

AXES = "xyz"
#: The seam tolerance when none is given, as a fraction of the half's bounding-box diagonal.
DEFAULT_SEAM = 1e-6
#: A point off the planes is kept at least this many seams away from them: just beyond the seam,
#: with room for single-precision rounding of the result (a mesh's coordinates).
OFF_SEAM = 1.01


@dataclass(frozen=True)
class Mirror:
    """Mirror planes: one per axis in `axes` ("x", "xy", "xyz", ...), each through `origin`
    (the points' coordinates) and perpendicular to its axis. Points within `seam` of a plane
    are on it; None takes DEFAULT_SEAM times the half's bounding-box diagonal."""

    axes: str = "x"
    origin: tuple = (0.0, 0.0, 0.0)
    seam: float | None = None

    def __post_init__(self):
        axes = self.axes
        if not isinstance(axes, str) or not axes or any(a not in AXES for a in axes.lower()) \
                or len(set(axes.lower())) != len(axes):
            raise ValueError(f"mirror axes must be distinct letters of 'xyz', e.g. 'x' or 'xy', got {axes!r}")
        try:
            origin = np.asarray(self.origin, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"mirror origin must be 3 numbers, got {self.origin!r}") from None
        if origin.shape != (3,) or not np.isfinite(origin).all() or np.abs(origin).max() > MAX_COORDINATE:
            raise ValueError(f"mirror origin must be 3 finite numbers within +-{MAX_COORDINATE:.0e}, "
                             f"got {self.origin!r}")
        seam = self.seam
        if seam is not None:
            if isinstance(seam, bool) or not isinstance(seam, (int, float, np.integer, np.floating)) \
                    or not np.isfinite(seam) or seam < 0:
                raise ValueError(f"mirror seam must be a finite distance >= 0 or None, got {seam!r}")
            seam = float(seam)
        object.__setattr__(self, "axes", "".join(a for a in AXES if a in axes.lower()))
        object.__setattr__(self, "origin", tuple(float(v) for v in origin))
        object.__setattr__(self, "seam", seam)

    @property
    def axis_indices(self) -> list[int]:
        return [AXES.index(a) for a in self.axes]


def as_mirror(value) -> Mirror:
    """A Mirror, from a Mirror or an axes string ("x": the plane x = 0)."""
    if isinstance(value, Mirror):
        return value
    if isinstance(value, str):
        return Mirror(value)
    raise ValueError(f"mirror must be a pointscale.Mirror or axes such as 'x', got {type(value).__name__}")


class Symmetry:
    """The orbit of n half points under the mirror group, and the maps between the half's
    points (n) and the whole model's (N). Whole point j is the reflection `element[j]` (a bit
    per plane) of half point `source[j]`; the first n are the half itself."""

    def __init__(self, mirror: Mirror, on_plane: np.ndarray, sides):
        self.mirror = mirror
        self.sides = tuple(int(side) for side in sides)  # per plane, +1 or -1: the side the half is on
        self.on_plane = np.ascontiguousarray(on_plane, dtype=bool)  # (n, planes): seam points
        n, planes = self.on_plane.shape
        self.n = n
        seam_bits = self.on_plane.astype(np.int64) @ (1 << np.arange(planes))
        group = 1 << planes
        index = np.full((group, n), -1, dtype=np.int64)
        sources, elements = [], []
        count = 0
        for g in range(group):
            own = np.flatnonzero((seam_bits & g) == 0)  # a seam point is its own image across its plane
            index[g, own] = count + np.arange(len(own))
            count += len(own)
            sources.append(own)
            elements.append(np.full(len(own), g))
        self.source = np.concatenate(sources)
        self.element = np.concatenate(elements)
        self.n_full = count
        # The whole point each whole point becomes when reflected across plane p.
        self._across = [index[(self.element ^ (1 << p)) & ~seam_bits[self.source], self.source]
                        for p in range(planes)]
        self._origin = np.array(mirror.origin)
        self._signs = np.ones((self.n_full, 3))
        for p, axis in enumerate(mirror.axis_indices):
            self._signs[(self.element >> p) & 1 == 1, axis] = -1.0

    # ---- the half -> the whole model
    def full(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) positions of the half -> (N, 3) of the whole model."""
        return (points - self._origin)[self.source] * self._signs + self._origin

    def full_vectors(self, vectors: np.ndarray) -> np.ndarray:
        """(n, 3) directions (normals) -> (N, 3), reflected."""
        return vectors[self.source] * self._signs

    def full_values(self, values: np.ndarray) -> np.ndarray:
        """(..., n) scalars per point (gains) -> (..., N)."""
        return values[..., self.source]

    def full_pairs(self, pairs: np.ndarray) -> np.ndarray:
        """(m, 2) vertex pairs (edges) of the half -> the pairs of every copy."""
        index = np.empty((1 << len(self.mirror.axes), self.n), dtype=np.int64)
        index[self.element, self.source] = np.arange(self.n_full)
        seam_bits = self.on_plane.astype(np.int64) @ (1 << np.arange(self.on_plane.shape[1]))
        copies = [index[g & ~seam_bits[pairs], pairs] for g in range(index.shape[0])]
        return np.ascontiguousarray(np.concatenate(copies), dtype=np.int32)

    # ---- the whole model -> the half, symmetrised
    def _average(self, values: np.ndarray, signs) -> np.ndarray:
        # One plane at a time: after plane p, a value and its reflection across p are exact
        # negatives in p's coordinate ((a - b) / 2 and (b - a) / 2), a seam point's is 0, and
        # the next planes keep that (they add and halve such pairs alike).
        out = values
        for p, axis in enumerate(self.mirror.axis_indices):
            partner = out[self._across[p]]
            if signs:
                partner = partner.copy()
                partner[:, axis] = -partner[:, axis]
            out = 0.5 * (out + partner)
        return out[: self.n]

    def symmetric(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) positions of the whole model -> (n, 3), averaged over each orbit."""
        out = self._average(points - self._origin, True)
        keep_off = OFF_SEAM * self.mirror.seam
        if keep_off == 0.0:
            # seam=0: only points exactly on a plane are seam points; the others are kept a few
            # single-precision steps off it, which a mesh's rounding cannot undo.
            keep_off = 4.0 * 2.0 ** -23 * (np.abs(out).max() + np.abs(self._origin).max())
        for p, axis in enumerate(self.mirror.axis_indices):
            off, side = ~self.on_plane[:, p], self.sides[p]
            # Only points that came within the seam move (to just beyond it); the input's own
            # points near it stay where they are, so the round trip stays exact.
            into_seam = off & (side * out[:, axis] <= self.mirror.seam)
            out[into_seam, axis] = side * keep_off
        return out + self._origin

    def crossings(self, half: np.ndarray) -> list:
        """Where an edited half (n, 3) reaches across a mirror plane: per plane, (axis name,
        points beyond the seam on the other side, how far the farthest lies beyond the plane,
        the points off the plane). The whole model is the half and its reflections, so a half
        moved across its plane overlaps its own mirror image, and symmetric() holds the result
        at the plane there."""
        out = []
        for p, axis in enumerate(self.mirror.axis_indices):
            off = ~self.on_plane[:, p]
            depth = -self.sides[p] * (half[:, axis] - self._origin[axis])
            across = off & (depth > self.mirror.seam)
            if across.any():
                out.append((self.mirror.axes[p], int(across.sum()), float(depth[across].max()), int(off.sum())))
        return out

    def symmetric_normals(self, normals: np.ndarray) -> np.ndarray:
        """(N, 3) unit normals -> (n, 3), averaged over each orbit and normalised again."""
        mean = self._average(normals, True)
        length = np.linalg.norm(mean, axis=1, keepdims=True)
        return np.where(length > 1e-12, mean / np.maximum(length, 1e-300), normals[: self.n])

    def symmetric_values(self, values: np.ndarray) -> np.ndarray:
        """(k, N) scalars (detail) -> (k, n), averaged over each orbit."""
        return np.ascontiguousarray(self._average(values.T, False).T)

    def any_of_orbit(self, flags: np.ndarray) -> np.ndarray:
        """(N,) bits -> (n,): a bit is set when it is set anywhere in the point's orbit."""
        out = flags
        for across in self._across:
            out = out | out[across]
        return out[: self.n]

    def least_of_orbit(self, values: np.ndarray) -> np.ndarray:
        out = values
        for across in self._across:
            out = np.minimum(out, out[across])
        return out[: self.n]

    def in_half_numbers(self, message: str) -> str:
        """A message about the whole model with each "from vertex N" said as the half's vertex
        (and whether the part is a reflection)."""
        def vertex(match):
            j = int(match.group(1))
            if j >= self.n_full:
                return match.group(0)
            mirrored = ", mirrored" if self.element[j] else ""
            return f"from vertex {int(self.source[j])}{mirrored}"
        return re.sub(r"from vertex (\d+)", vertex, message)

    # ---- saving
    def settings(self) -> dict:
        m = self.mirror
        return {"axes": m.axes, "origin": list(m.origin), "seam": m.seam, "sides": list(self.sides)}

    def to_arrays(self) -> dict:
        return {"mirror_seam": self.on_plane.astype(np.uint8)}


#: The gap between a half and its mirror plane, as a share of the half's diagonal, beyond which
#: the plane is said to be far: a half model reaches its plane (a scan's hole along the seam
#: leaves a few percent).
FAR_FROM_PLANE = 0.1


def symmetry_of(points: np.ndarray, mirror: Mirror) -> Symmetry:
    """The seam points of the half `points`, checked: every point not on a plane lies on one
    side of it."""
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    seam = DEFAULT_SEAM * diagonal if mirror.seam is None else mirror.seam
    mirror = Mirror(mirror.axes, mirror.origin, seam)
    on_plane = np.zeros((len(points), len(mirror.axes)), dtype=bool)
    sides = []
    for p, axis in enumerate(mirror.axis_indices):
        offset = points[:, axis] - mirror.origin[axis]
        on_plane[:, p] = np.abs(offset) <= seam
        below, above = int((offset < -seam).sum()), int((offset > seam).sum())
        name, at = mirror.axes[p], f"{mirror.axes[p]} = {mirror.origin[axis]:.10g}"
        if below and above:
            reach = float(min(-offset.min(), offset.max()))
            raise ValueError(f"points lie on both sides of the {name} mirror plane ({at}): {below} below and "
                             f"{above} above it beyond the seam tolerance {seam:.3g}. Give the half on one side "
                             f"(or a seam of at least {reach:.3g} if those points belong on the plane)")
        if not below and not above:
            raise ValueError(f"all points lie on the {name} mirror plane ({at}, seam tolerance {seam:.3g}): "
                             "there is no half to mirror")
        sides.append(1 if above else -1)
        gap = float(np.abs(offset).min())
        if gap > FAR_FROM_PLANE * diagonal:
            warnings.warn(f"no point lies within {gap:.6g} of the {name} mirror plane ({name} = "
                          f"{mirror.origin[axis]:.10g}), {gap / diagonal:.0%} of the half's size: a half reaches its "
                          "plane, so its reflection is a separate copy here. Is the plane where it should be (Mirror's "
                          "origin, in the points' coordinates; --mirror-origin on the command line)? A georeferenced "
                          "half's plane is far from 0", stacklevel=3)
    return Symmetry(mirror, on_plane, sides)


def decompose_mirrored(points, mirror, normals=None, faces=None, edges=None, **options):
    """decompose(points, mirror=...) (see the module's docstring): the whole model decomposed
    with `options`, its outputs for the half's points symmetrised."""
    from .multiscale import decompose
    from .parts import connectivity_pairs
    p = as_points(points)
    symmetry = symmetry_of(p, as_mirror(mirror))
    axes = symmetry.mirror.axis_indices
    centred = p - symmetry._origin
    centred[:, axes] = np.where(symmetry.on_plane, 0.0, centred[:, axes])  # seam points onto their planes
    half = centred + symmetry._origin
    n_arr = as_normals_of(normals, p)
    # Connectivity as vertex pairs: that is all that parts read, and pairs mirror simply. A part
    # that crosses a plane stays one part with its reflection.
    pairs = connectivity_pairs(len(p), faces, edges)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            dec = decompose(symmetry.full(half), normals=None if n_arr is None else symmetry.full_vectors(n_arr),
                            edges=None if pairs is None else symmetry.full_pairs(pairs), **options)
        except ValueError as exc:
            raise _far_plane_error(exc, half, symmetry) from None
    for w in caught:  # the whole model's vertex numbers, said as the half's
        warnings.warn(symmetry.in_half_numbers(str(w.message)), w.category, stacklevel=3)
    for report in dec.settings.get("parts") or ():
        first = report["first_vertex"]
        report["first_vertex"], report["mirrored"] = int(symmetry.source[first]), bool(symmetry.element[first])
    dec._mirror_about(symmetry)
    dec.settings["mirror"] = symmetry.settings()
    return dec


def _far_plane_error(exc: ValueError, half: np.ndarray, symmetry: Symmetry) -> ValueError:
    """exc, or what it means when the half spans a surface but the whole model does not: a
    mirror plane so far from the half that the half and its reflection look like a line."""
    from ._checks import require_surface
    try:
        require_surface(half)
    except ValueError:
        return exc
    try:
        require_surface(symmetry.full(half))
    except ValueError:
        pass  # the half spans a surface and the whole model does not: the plane is too far
    else:
        return exc
    mirror = symmetry.mirror
    diagonal = float(np.linalg.norm(half.max(axis=0) - half.min(axis=0)))
    gaps = [float(np.abs(half[:, axis] - mirror.origin[axis]).min()) for axis in mirror.axis_indices]
    p = int(np.argmax(gaps))
    axis = mirror.axis_indices[p]
    return ValueError(f"the {mirror.axes[p]} mirror plane ({mirror.axes[p]} = {mirror.origin[axis]:.10g}) lies "
                      f"{gaps[p]:.3g} from the half, {gaps[p] / diagonal:.3g} times the half's size ({diagonal:.3g}): "
                      f"the half and its reflection, that far apart, make a whole model too thin to span a surface "
                      f"({exc}). A mirror plane usually runs through the half's seam: check Mirror's origin, "
                      "which is in the points' coordinates")


def saved_symmetry(settings: dict, arrays, n_full: int) -> Symmetry | None:
    """The Symmetry of a saved decomposition, checked, or None when it has none."""
    if "mirror" not in settings and "mirror_seam" not in arrays:
        return None

    def bad(what):
        return ValueError(f"not a valid decomposition: {what}")

    if "mirror" not in settings or "mirror_seam" not in arrays:
        raise bad("a mirrored decomposition needs both settings['mirror'] and the mirror_seam array")
    saved = settings["mirror"]
    if not isinstance(saved, dict) or set(saved) != {"axes", "origin", "seam", "sides"}:
        raise bad("settings['mirror'] must be an object with exactly axes, origin, seam and sides")
    try:
        mirror = Mirror(saved["axes"], saved["origin"], saved["seam"])
    except ValueError as exc:
        raise bad(f"settings['mirror']: {exc}") from None
    if mirror.seam is None or mirror.axes != saved["axes"]:
        raise bad(f"settings['mirror'] must give the axes in xyz order and a seam, got {json.dumps(saved)}")
    sides = saved["sides"]
    if not isinstance(sides, list) or len(sides) != len(mirror.axes) or any(
            isinstance(side, bool) or side not in (1, -1) for side in sides):
        raise bad(f"settings['mirror']['sides'] must list +1 or -1 for each of the {len(mirror.axes)} planes")
    on_plane = np.asarray(arrays["mirror_seam"])
    if on_plane.dtype != np.uint8 or on_plane.ndim != 2 or on_plane.shape[1] != len(mirror.axes) \
            or on_plane.shape[0] < 1 or on_plane.max() > 1:
        raise bad(f"mirror_seam must be (n, {len(mirror.axes)}) uint8 of 0 and 1, "
                  f"got {on_plane.dtype} {on_plane.shape}")
    symmetry = Symmetry(mirror, on_plane.astype(bool), sides)
    if symmetry.n_full != n_full:
        raise bad(f"mirror_seam makes a whole model of {symmetry.n_full} points, but the model has {n_full}")
    return symmetry
