"""The mesh's Mirror modifier as the engine's mirror planes (no bpy: plain values in).

Decompose reads the Mirror modifiers of the stack (an artist often stacks one for X and one for
Y) and passes their planes to the engine, so that the part the artist models is decomposed
together with its reflections and the seam vertices stay on the planes: the modifiers keep
merging them at every Scale and gain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AXES = "xyz"
#: The seam tolerance when the modifier neither merges nor clips, as a fraction of the mesh's
#: diagonal: vertices that are on the plane up to single-precision rounding.
SMALL_SEAM = 1e-6
#: How far from axis-aligned (relative) the mirror object's planes may be in the mesh's space.
ALIGNED = 1e-6


@dataclass(frozen=True)
class MirrorPlanes:
    """Mirror planes in the mesh's own coordinates: ps.Mirror's arguments."""

    axes: str
    origin: tuple
    seam: float

    def describe(self) -> str:
        where = ", ".join(f"{a} = {self.origin[AXES.index(a)]:.10g}" for a in self.axes)
        return f"the Mirror modifier's planes {where} (seam {self.seam:.3g})"


def mirror_modifiers(modifiers) -> list:
    """The Mirror modifiers of the stack that are on in the viewport."""
    return [m for m in modifiers if m.type == "MIRROR" and m.show_viewport]


def combined(planes: list) -> tuple[MirrorPlanes | None, str | None]:
    """The planes of several Mirror modifiers as one set (X from one, Y from the next ...), or
    (None, why) when two of them mirror along the same axis at different places. The seam is the
    widest of theirs."""
    planes = [p for p in planes if p is not None]
    if not planes:
        return None, None
    origin = [0.0, 0.0, 0.0]
    axes = {}
    for p in planes:
        for a in p.axes:
            i = AXES.index(a)
            if a in axes and abs(p.origin[i] - origin[i]) > 1e-9 * max(1.0, abs(origin[i])):
                return None, (f"two Mirror modifiers mirror along {a.upper()} at {origin[i]:.10g} and "
                              f"{p.origin[i]:.10g}; Pointscale keeps one plane per axis. Turn one off, or turn "
                              "off Use Mirror Modifier")
            axes[a] = True
            origin[i] = p.origin[i]
    return MirrorPlanes("".join(a for a in AXES if a in axes), tuple(origin), max(p.seam for p in planes)), None


def mirror_planes(use_axis, use_merge: bool, use_clip: bool, merge_threshold: float, diagonal: float,
                  to_mirror_space=None, bisect_threshold: float = 0.0) -> tuple[MirrorPlanes | None, str | None]:
    """(planes, None), or (None, why the modifier cannot be honoured), or (None, None) for a
    modifier that mirrors nothing.

    use_axis         three bools, the modifier's X, Y, Z
    merge_threshold  with merge, Blender joins a vertex with its reflection when they are closer
                     than this, that is when the vertex is within half of it of the plane: those
                     are the seam. With clipping alone, the vertices within it are held on the plane.
    bisect_threshold with Bisect on a mirrored axis, Blender also joins a vertex within this of the
                     plane with its reflection: the seam is at least that wide, or a vertex kept just
                     beyond a narrower seam at some level would be merged there (0: no bisect).
    to_mirror_space  4x4, the mesh's coordinates -> the mirror object's (None: no mirror object).
                     Its planes must be axis-aligned in the mesh's space; any translation, scale
                     along the axes, or quarter turn is, a general rotation is not.
    """
    axes = [a for a, used in zip(range(3), use_axis) if used]
    if not axes:
        return None, None
    if use_merge:
        seam = 0.5 * float(merge_threshold)
    elif use_clip:
        seam = float(merge_threshold)
    else:
        seam = SMALL_SEAM * float(diagonal)
    seam = max(seam, float(bisect_threshold))
    origin = np.zeros(3)
    mesh_axes = axes
    if to_mirror_space is not None:
        m = np.asarray(to_mirror_space, dtype=np.float64)
        linear, shift = m[:3, :3], m[:3, 3]
        mesh_axes = []
        for a in axes:
            # Plane a of the mirror object is linear[a] . p + shift[a] = 0 in the mesh's space; it
            # mirrors along one of the mesh's axes b only if that row and column b are zero elsewhere.
            b = int(np.argmax(np.abs(linear[a])))
            scale = np.abs(linear).max()
            off_row = np.abs(np.delete(linear[a], b)).max()
            off_column = np.abs(np.delete(linear[:, b], a)).max()
            if not scale > 0 or max(off_row, off_column) > ALIGNED * scale:
                return None, (f"the Mirror modifier's mirror object is rotated against the mesh, so its "
                              f"{AXES[a].upper()} plane is not along one of the mesh's axes; Pointscale mirrors "
                              "only along the mesh's axes. Align the mirror object (rotations by quarter turns "
                              "are fine) or turn off Use Mirror Modifier")
            origin[b] = -shift[a] / linear[a, b]
            mesh_axes.append(b)
    return MirrorPlanes("".join(AXES[b] for b in sorted(mesh_axes)), tuple(float(v) for v in origin), seam), None


def same_planes(then, now: MirrorPlanes | None) -> bool:
    """Whether the planes a decomposition followed (``then``: anything with axes, origin and
    seam, such as pointscale.Mirror, or None) are the Mirror modifiers' ``now``: the same axes,
    at the same places, with seams within 1e-6 of each other (relative)."""
    if then is None or now is None:
        return then is None and now is None
    if "".join(sorted(then.axes)) != now.axes:
        return False
    for a in now.axes:
        i = AXES.index(a)
        if abs(float(then.origin[i]) - now.origin[i]) > 1e-9 * max(1.0, abs(now.origin[i])):
            return False
    return abs(float(then.seam) - now.seam) <= 1e-6 * max(float(then.seam), now.seam)


def changed_message(then, now: MirrorPlanes | None, problem: str | None = None) -> str | None:
    """What Rebuild Detail and Bake Filter say where the Mirror modifiers no longer mirror as
    they did at Decompose (then: the decomposition's planes, or None; now: the modifiers'
    planes, or None with ``problem`` when their settings cannot be followed), or None where
    they do. Decompose reads them once: a modifier added, removed or moved after it mirrors a
    decomposition made for other planes, and the seam may tear."""
    if problem is None and same_planes(then, now):
        return None
    again = "Decompose again to follow the Mirror modifiers as they are now"
    if problem is not None:
        return f"the Mirror modifiers changed since Decompose, and {problem}"
    if then is None:
        return (f"{now.describe()} mirror the mesh now, but Decompose did not follow a Mirror modifier, so the "
                f"detail at the seam is not matched with its reflection and the seam may tear. {again}")
    then_text = MirrorPlanes("".join(sorted(then.axes)), tuple(float(v) for v in then.origin), float(then.seam)).describe()
    if now is None:
        return (f"Decompose followed {then_text}, but no Mirror modifier mirrors the mesh now (or Use Mirror "
                f"Modifier is off). {again}, or turn the modifier back on")
    return f"Decompose followed {then_text}, but now {now.describe()} mirror the mesh. {again}"
