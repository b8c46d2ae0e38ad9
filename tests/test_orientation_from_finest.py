"""decompose without normals orients its levels from the finest level's propagated orientation
(level_turns.h, decomposition.cpp's level0_normals_from_finest), not from a spanning tree over
level 0's sparse anchors. That tree reached across thin tubes and sharp creases, and turned whole
regions in: on a torus half of every level's normals faced in, and a bump there read as a dent.
Measured 2026-12-07 (before -> now, share of the finest level's normals facing in)."""

import numpy as np
import pytest

import pointscale as ps
from helpers import SHARED_DATA


def torus(n, major, minor, seed):
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, n)
    outward = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)
    centre = np.stack([major * np.cos(u), major * np.sin(u), 0 * u], axis=1)
    return centre + minor * outward, outward


def flat_ellipsoid(n, axes, seed):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    outward = u / np.asarray(axes)
    return u * np.asarray(axes), outward / np.linalg.norm(outward, axis=1, keepdims=True)


def facing_in(dec, outward):
    return [float(((dec.normals(level) * outward).sum(axis=1) < 0).mean()) for level in range(dec.n_bands)]


# (points, outward normals), bound on the share facing in at every level: measured 1.5%, 4.7%,
# 3.2% and 2.0% (before: 52%, 41%, 75% and 49%).
SHAPES = {
    "torus 1 / 0.1, 50k": (lambda: torus(50000, 1.0, 0.1, 21), 0.025),
    "torus 1.5 / 0.3, 20k": (lambda: torus(20000, 1.5, 0.3, 22), 0.06),
    "torus 1 / 0.25, 16k": (lambda: torus(16000, 1.0, 0.25, 23), 0.045),
    "ellipsoid 8 : 3 : 1, 30k": (lambda: flat_ellipsoid(30000, (8.0, 3.0, 1.0), 13), 0.03),
}


@pytest.mark.parametrize("name", SHAPES)
def test_thin_closed_shapes_face_outward_at_every_level(name):
    make, bound = SHAPES[name]
    points, outward = make()
    shares = facing_in(ps.decompose(points, levels=4, threads=2), outward)
    assert max(shares) < bound, (name, shares)


def test_a_bump_on_a_thin_torus_is_positive_detail():
    """The issue's promise: outward normals, so positive detail is a bump. Gaussian bumps on a
    torus whose tube is a few level-0 anchors wide: on the reviewer's torus 108 of 559 bump peaks
    read as dents, 0 now; on this one, 6 of 512 (before: 331)."""
    points, outward = torus(20000, 1.0, 0.25, 5)
    rng = np.random.default_rng(6)
    centres = points[rng.choice(len(points), 40, replace=False)]
    distance = np.min(np.linalg.norm(points[:, None, :] - centres[None, :, :], axis=2), axis=1)
    height = 0.02 * np.exp(-(distance / 0.08) ** 2)
    dec = ps.decompose(points + height[:, None] * outward, levels=4, threads=2)
    peaks = height > 0.015
    assert peaks.sum() > 300
    assert (dec.details[-1][peaks] < 0).sum() <= 0.02 * peaks.sum()


def test_a_flat_base_under_tall_detail_stays_one_way_up():
    """Where a finer level turns at right angles to the level below it (the walls of tall
    handles) the orientation carried down to level 0 is a toss-up; level 0's clusters take the
    side most of their points give, so a flat base faces one way everywhere. Which way an open
    plane faces is the propagation's vote (here down, as before this change), not checked here.
    Per point instead, 4% of this base faced the other way."""
    points, _, _ = ps.shapes.handles_plane(size=2.0, count=4, width=0.1, height=0.4, spacing=0.02)
    dec = ps.decompose(points, levels=4, decimation=0.1)
    up = dec.normals(0)[:, 2]
    assert np.all(np.abs(up) > 0.9) and (np.all(up > 0) or np.all(up < 0))


# Scans, points only: the share of the finest level's normals that face against estimate_normals'
# (its own spanning tree over the dense input). Measured 2.8%, 3.2% and 1.6% (before: 12.2%, 6.4%
# and 6.1%).
SCANS = {"dragon.ply": 0.035, "bunny.ply": 0.04, "armadillo_points_normals.ply": 0.025}


@pytest.mark.parametrize("name", SCANS)
def test_scans_without_normals_have_no_flipped_regions(name):
    path = SHARED_DATA / name
    if not path.exists():
        pytest.skip(f"{name} is in ../shared/data, which a user's clone does not have")
    points = np.asarray(ps.io.read(path).points, dtype=float)
    reference = ps.estimate_normals(points, threads=2)
    dec = ps.decompose(points, levels=4, threads=2)
    share = float(((dec.normals(dec.n_bands - 1) * reference).sum(axis=1) < 0).mean())
    assert share < SCANS[name], (name, share)
