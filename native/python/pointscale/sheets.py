"""Thin sheets: which way each point faces, so that decompose keeps the two sides of a wall apart.

decompose(..., sheets=True) tells the sides of a wall thinner than its kernel (a leaf, sheet
metal, a wall scanned from both sides) by the points' outward normals: every fit, cluster and
level normal takes only points whose normals make an acute angle with the point's own
(native/include/pointscale/thin_sheets.h).
"""

from __future__ import annotations

import warnings

import numpy as np


def check_sheet_normals(normals: np.ndarray) -> None:
    """Given outward normals tell the sides apart; a zero normal faces neither, so it is refused
    (ValueError). Without normals, the core estimates and orients them itself (16 neighbours, as
    estimate_normals), so that a decomposition does not hold them twice."""
    lengths = np.sqrt(np.einsum("ij,ij->i", normals, normals))
    zero = np.flatnonzero(~(lengths > 0.0))
    if zero.size:
        raise ValueError(f"sheets=True tells the sides of a wall by the normals, and {zero.size} of them are zero "
                         f"(the first at point {zero[0]}); give outward normals, or none to estimate them")


#: How many nearest points estimated_sides_warning looks among for another surface stacked along
#: a point's normal: 48 reach about 4 point spacings, across any wall the estimate can orient.
STACKED_NEIGHBOURS = 48
#: At most this many points, evenly spread over the input, are looked at.
SIDES_SAMPLE = 20000


def estimated_sides_warning(points: np.ndarray, threads: int = 0) -> str | None:
    """The warning for sheets=True without normals when the normals the core would estimate
    (those of estimate_normals) do not tell the sides of walls apart, or None.

    A point has another surface stacked on it when one of its STACKED_NEIGHBOURS nearest points
    lies within 45 degrees of its normal's line. With sides told apart, such a point faces away
    (their normals more than 120 degrees apart, as sheets=True separates them); the estimate,
    which orients by propagation, gives both sides of a wall thinner than about two spacings,
    and the inside of a closed hollow shape, one direction instead. Warns unless more points
    have a stacked point facing away than facing the same way. Measured on plates 0.5 to 4 and
    closed boxes 0.5 to 3 spacings thick: every case whose sides the estimate oriented alike (the
    sides then blend as without sheets) warns, none whose sides it told apart; a one-sided
    surface warns too (nothing is kept apart), as sheets=True does nothing there."""
    from . import _core
    from ._checks import thread_option
    from .surface import estimate_normals
    with warnings.catch_warnings():  # points without a normal just do not vote
        warnings.simplefilter("ignore")
        normals = estimate_normals(points, threads=threads)
    rows = _core.knn_within_parts(points, np.zeros(len(points), dtype=np.int32),
                                  k=min(STACKED_NEIGHBOURS, len(points)), threads=thread_option(threads))
    # Single precision is plenty for these angles, and halves the work.
    q = (points - 0.5 * (points.min(axis=0) + points.max(axis=0))).astype(np.float32)
    n32 = normals.astype(np.float32)
    # The verdict is a majority: every point, up to SIDES_SAMPLE of them evenly spread over the input.
    sample = np.unique(np.linspace(0, len(q) - 1, min(len(q), SIDES_SAMPLE)).astype(np.int64))
    same = away = 0
    for start in range(0, len(sample), 32768):  # a block at a time: (rows, k, 3) arrays
        at = sample[start:start + 32768]
        r = rows[at, 1:]
        offset = q[r] - q[at, None, :]
        along = np.einsum("ijk,ik->ij", offset, n32[at])
        point, j = np.nonzero(2.0 * along * along > np.einsum("ijk,ijk->ij", offset, offset))  # within 45 degrees
        facing = np.einsum("ij,ij->i", n32[r[point, j]], n32[at[point]])
        same += np.unique(point[facing > 0.5]).size
        away += np.unique(point[facing < -0.5]).size
    if away > same:
        return None
    return (f"sheets=True keeps the sides of a wall apart by which way their normals face, and the normals estimated "
            f"here tell no sides apart: of the points looked at with another surface stacked along their normal, "
            f"{same} face the same way as it and {away} face away. Either there is no wall thinner than the kernel (sheets=True "
            "then changes nothing), or the estimate oriented both sides of such walls alike, as it does for walls "
            "thinner than about two point spacings and the inside of closed hollow shapes: they blend as without "
            "sheets. To keep them apart, give outward normals (normals=..., e.g. a mesh's vertex normals) or the "
            "mesh's consistently wound faces (faces=...)")


def winding_normals(points: np.ndarray, faces) -> tuple[np.ndarray | None, str | None]:
    """Outward vertex normals from a mesh's faces, for sheets=True when no normals are given:
    (normals, None), or (None, why not) when the faces cannot give them.

    A mesh file without normals (an STL, a PLY or OBJ with faces only) still says which way
    each face looks, by the order of its corners; each vertex takes the area-weighted normals of
    its faces, summed (each polygon as the triangles of a fan from its first corner, as
    meshes.vertex_normals does). That only tells the sides of a wall apart when neighbouring
    faces agree: where two faces wind their shared edge the same way, one of them is flipped,
    and normals taken from them would face either way. So the normals are refused as a whole
    when any shared edge is wound alike by two faces, or any vertex's normal is zero (a vertex
    in no face, or faces that cancel there).
    points (n, 3); faces (m, k) or a list of polygons, indices already checked against n.
    """
    polygons = _polygons_by_corner_count(faces)
    n = len(points)
    summed = np.zeros((n, 3), dtype=np.float64)
    directed, triangles = [], []
    for corners in polygons:
        for triangle in _fan_triangles(corners):
            triangles.append(triangle)
            a, b, c = (points[triangle[:, i]] for i in range(3))
            normal = np.cross(b - a, c - a)  # twice the triangle's area, along its normal
            for i in range(3):
                for axis in range(3):  # bincount sums repeated indices, as np.add.at does, far faster
                    summed[:, axis] += np.bincount(triangle[:, i], weights=normal[:, axis], minlength=n)
        directed.append(np.stack([corners.ravel(), np.roll(corners, -1, axis=1).ravel()], axis=1))
    if not directed:
        return None, None  # no faces: nothing to take the normals from
    alike = _edges_wound_alike(np.concatenate(directed), n)
    if alike.size:
        return None, (f"sheets=True: the faces wind {len(alike)} shared edges "
                      f"the same way on both sides (the first joins vertices {alike[0, 0]} and {alike[0, 1]}), so "
                      "their winding does not say which way the surface faces; the normals are estimated from "
                      "the points instead. Recalculate the mesh's normals outside (Blender: Mesh > Normals > "
                      "Recalculate Outside) or give outward normals")
    length = np.sqrt(np.einsum("ij,ij->i", summed, summed))
    zero = np.flatnonzero(~(length > 0.0))
    if zero.size:
        return None, (f"sheets=True: {zero.size} vertices have no normal from the faces (the first is vertex "
                      f"{zero[0]}: in no face, or between faces that cancel), so the normals are estimated from "
                      "the points instead. Give outward normals, or a mesh whose every vertex is in a face")
    normals = summed / length[:, None]
    inside_out, labels = _closed_parts_wound_inside_out(points, np.concatenate(triangles), np.concatenate(directed), n)
    if not inside_out.any():
        return normals, None
    flip = inside_out[labels]
    normals[flip] *= -1.0
    warnings.warn(f"sheets=True: the faces of {int(inside_out.sum())} closed part(s) are wound inside out (their "
                  f"normals faced in, at {int(flip.sum())} vertices); they are taken turned outward", stacklevel=3)
    return normals, None


def _closed_parts_wound_inside_out(points: np.ndarray, triangles: np.ndarray, directed: np.ndarray,
                                   n: int) -> tuple[np.ndarray, np.ndarray]:
    """Per connected part, whether it is closed (every edge run by two faces) and encloses a
    negative volume: wound so that its normals face in; and each vertex's part
    (parts.connected_parts). An open part's winding is the mesh's choice and is kept."""
    from .parts import connected_parts
    labels, count = connected_parts(points, faces=triangles)
    a, b, c = (points[triangles[:, i]] for i in range(3))
    centre = points.mean(axis=0)  # the volume of a closed part does not depend on it; rounding does
    volume = np.einsum("ij,ij->i", a - centre, np.cross(b - centre, c - centre))
    enclosed = np.bincount(labels[triangles[:, 0]], weights=volume, minlength=count)
    edges = directed[directed[:, 0] != directed[:, 1]]
    undirected = np.sort(edges, axis=1)
    keys, runs = np.unique(undirected[:, 0] * np.int64(n) + undirected[:, 1], return_counts=True)
    open_edge = keys[runs == 1]
    open_part = np.zeros(count, dtype=bool)
    open_part[labels[open_edge // n]] = True
    return ~open_part & (enclosed < 0.0), labels


def _polygons_by_corner_count(faces) -> list:
    """faces as a list of (m, k) int64 arrays, one per corner count k >= 3 (fewer corners make
    no area)."""
    if isinstance(faces, np.ndarray) and faces.dtype != object:
        grouped = [np.asarray(faces, dtype=np.int64).reshape(len(faces), -1)] if len(faces) else []
    else:
        polygons = [np.asarray(face, dtype=np.int64).reshape(-1) for face in faces]
        sizes = np.array([len(p) for p in polygons], dtype=np.int64)
        grouped = [np.stack([p for p, s in zip(polygons, sizes) if s == k]) for k in np.unique(sizes)]
    return [g for g in grouped if g.shape[1] >= 3]


def _fan_triangles(corners: np.ndarray) -> list:
    """(m, k) polygons as k - 2 (m, 3) triangle arrays, fanned from each polygon's first corner:
    for quads, the triangles meshes.quads_to_triangles makes."""
    return [corners[:, [0, c, c + 1]] for c in range(1, corners.shape[1] - 1)]


def _edges_wound_alike(directed: np.ndarray, n: int) -> np.ndarray:
    """(e, 2) the edges that two faces run through in the same direction, once each: in a
    consistently wound mesh each face runs a shared edge the other way."""
    directed = directed[directed[:, 0] != directed[:, 1]]  # a repeated corner makes no edge
    keys = directed[:, 0] * np.int64(n) + directed[:, 1]
    unique, counts = np.unique(keys, return_counts=True)
    twice = unique[counts > 1]
    return np.stack([twice // n, twice % n], axis=1)
