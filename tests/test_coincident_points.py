"""Points that coincide in the input stay one point at every level and every gain: a scan's
repeated returns, a mesh vertex split along a UV seam or a hard edge. Before, each copy was
projected on its own and the level's anchor iterated apart from its copies, so copies had bases
up to 1.7% of the diagonal apart (the bunny, every point twice) and a seam cracked open under
gains."""
import numpy as np
import pytest

import pointscale as ps
from helpers import diagonal, shared_model


def with_copies(points, which):
    """points, then a second copy of points[which] (bit for bit)."""
    return np.concatenate([points, points[which]])


def assert_copies_coincide(dec, n, which, gains_list=((0, 0, 0), (2, 2, 1), (1, 1, 3), (3, 3, 3))):
    copy = n + np.arange(len(which))
    assert np.array_equal(dec.base[which], dec.base[copy])  # one base position, bit for bit
    assert np.array_equal(dec.details[:, which], dec.details[:, copy])
    diag = diagonal(dec.base)
    for gains in gains_list:
        result = ps.reconstruct(dec, gains=gains[:dec.n_bands])
        # their normals are fitted in batches, one to rounding: measured up to 2e-16 of the diagonal
        assert np.abs(result[which] - result[copy]).max() < 1e-13 * diag, gains


@pytest.mark.parametrize("share,levels,decimation", [(1.0, 4, 0.25), (0.05, 4, 0.25), (0.3, 3, 0.1)])
def test_coincident_points_keep_one_place_at_every_level_and_gain(share, levels, decimation):
    points = ps.shapes.bumpy_sphere(12000, noise=0.002, seed=3)
    which = np.sort(np.random.default_rng(5).choice(len(points), int(share * len(points)), replace=False))
    cloud = with_copies(points, which)
    dec = ps.decompose(cloud, levels=levels, decimation=decimation)
    assert_copies_coincide(dec, len(points), which)
    assert np.abs(ps.reconstruct(dec) - cloud).max() < 1e-12 * diagonal(cloud)  # the round trip stays exact


def test_a_scan_with_repeated_returns_keeps_them_together_under_band_gains():
    """Three copies of some points, in an order that puts the copies far apart in the input."""
    points = ps.shapes.wavy_patch(20000, coarse=0.1, fine=0.01)
    which = np.arange(0, len(points), 17)
    cloud = np.concatenate([points[which], points, points[which]])
    dec = ps.decompose(cloud, levels=3)
    first, second, third = np.arange(len(which)), len(which) + which, len(which) + len(points) + np.arange(len(which))
    for other in (second, third):
        assert np.array_equal(dec.base[first], dec.base[other])
        for gains in ((0, 0), (2, 3)):
            result = ps.reconstruct(dec, gains=gains)
            assert np.abs(result[first] - result[other]).max() < 1e-13 * diagonal(cloud)


def test_a_mesh_split_along_a_seam_stays_closed():
    """A sphere's vertices along one meridian split in two, as glTF and FBX exporters write a UV
    seam: the faces on either side hold separate vertices at one place."""
    points = ps.shapes.bumpy_sphere(8000, noise=0.0, seed=1)
    seam = np.flatnonzero((np.abs(points[:, 1]) < 0.02) & (points[:, 0] > 0))
    cloud = with_copies(points, seam)
    dec = ps.decompose(cloud, levels=3)
    assert_copies_coincide(dec, len(points), seam, gains_list=((0, 0), (2, 2), (1, 3)))


def test_copies_facing_one_way_stay_one_point_with_thin_sheets():
    """With thin sheets, copies are one point when they face the same way (points at one place
    facing opposite ways are the two faces of a sheet of no thickness, and stay two)."""
    points = ps.shapes.bumpy_sphere(8000, noise=0.0, seed=2)
    normals = points / np.linalg.norm(points, axis=1)[:, None]
    which = np.arange(0, len(points), 5)
    dec = ps.decompose(with_copies(points, which), levels=3, normals=with_copies(normals, which), sheets=True)
    assert_copies_coincide(dec, len(points), which, gains_list=((0, 0), (2, 2)))


def test_the_bunny_with_every_point_twice_has_one_base():
    """A real scan, where the old decomposition put copies' bases up to 1.7% of the diagonal apart
    (1224 of 35947 pairs) and gains (2, 2, 2) up to 1.8%."""
    points = ps.io.read(shared_model("bunny.ply")).points
    which = np.arange(len(points))
    dec = ps.decompose(with_copies(points, which), levels=4)
    assert_copies_coincide(dec, len(points), which, gains_list=((0, 0, 0), (2, 2, 2), (1, 1, 2)))
