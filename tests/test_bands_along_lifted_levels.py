"""Issue 16, requirement 2, read literally on detail that is not gentle: after a lift of the base,
band l is applied along the normal of level l's own lifted surface.

Band l moves level l's points along level l's normal (Eq. 9), and a level with detail of its own
is not parallel to the base: on a rippled patch its normal is off the base's by several degrees
before any edit. So the reference here is each rebuilt level's own surface, lifted: an independent
plane fit to the level's points (Gaussian weights at that level's kernel width, in NumPy), not
the lifted base's normal and nothing the engine computes. The same fit with no edit shows how far
the two estimators differ anyway, and the lift must add little to that.
"""
import numpy as np
import pytest
from scipy.spatial import cKDTree

import pointscale as ps
from helpers import diagonal
from test_edits_at_any_scale import gaussian_lift

LIFTS = (((0.1, 0.3), 0.6, 0.6), ((-0.4, -0.2), 0.3, 0.15), ((0.3, 0.3), 1.0, 0.8), ((0.2, -0.1), 0.5, 0.3))


def ripples(n, fine, frequency, coarse=0.0, seed=0):
    """A square 2 units wide sampled at random (as a scan is, not on a grid): a broad wave of
    height `coarse` plus ripples of height `fine`."""
    xy = np.random.default_rng(seed).uniform(-1.0, 1.0, (n, 2))
    x, y = xy.T
    z = coarse * np.sin(1.5 * x) * np.cos(1.2 * y) + fine * np.sin(frequency * x) * np.sin(frequency * y)
    return np.column_stack([x, y, z])


def weighted_plane_normals(points, at, width, reference, k=300):
    """Unit normals at points[at]: the smallest eigenvector of the covariance of the k nearest
    points weighted by exp(-(d / width)^2), on reference's side."""
    distance, neighbours = cKDTree(points).query(points[at], k)
    w = np.exp(-((distance / width) ** 2))
    q = points[neighbours]
    q = q - (np.einsum("nk,nki->ni", w, q) / w.sum(axis=1)[:, None])[:, None]
    normal = np.linalg.eigh(np.einsum("nk,nki,nkj->nij", w, q, q))[1][:, :, 0]
    return normal * np.where(np.einsum("ij,ij->i", normal, reference) < 0, -1.0, 1.0)[:, None]


def band_angles(dec, levels, at):
    """Per band: degrees between the direction band l moved the points at `at` and the fitted
    normal of level l there (only points whose band is not zero)."""
    out = []
    for l in range(dec.n_bands):
        d = dec.details[l][at]
        use = np.abs(d) > 1e-6 * diagonal(dec.base)
        direction = (levels[l + 1][at] - levels[l][at]) / np.where(use, d, 1.0)[:, None]
        normal = weighted_plane_normals(levels[l], at, dec.stats[l]["kernel_width"], direction)
        cosine = np.abs(np.einsum("ij,ij->i", direction, normal))[use]
        out.append(np.degrees(np.arccos(np.clip(cosine, 0.0, 1.0))))
    return out


# (points, levels, kernel): ripples 0.5-6% of the patch's width high, 3-12 per unit, on grids
# and sampled at random, with and without a broad wave under them.
CASES = {
    "grid, ripples 0.01 at 6, kernel 1": (lambda: ps.shapes.wavy_patch(30000, coarse=0.0, fine=0.01, fine_frequency=6.0), 3, 1.0),
    "grid, ripples 0.01 at 6, kernel 2": (lambda: ps.shapes.wavy_patch(30000, coarse=0.0, fine=0.01, fine_frequency=6.0), 3, 2.0),
    "grid, ripples 0.03 at 3, kernel 1.5": (lambda: ps.shapes.wavy_patch(20000, coarse=0.0, fine=0.03, fine_frequency=3.0), 3, 1.5),
    "grid, wave and ripples, 4 levels": (lambda: ps.shapes.wavy_patch(40000, coarse=0.05, fine=0.005, fine_frequency=12.0), 4, 1.0),
    "random, ripples 0.015 at 9, 4 levels": (lambda: ripples(60000, 0.015, 9.0), 4, 1.0),
    "random, wave and ripples 0.02 at 5": (lambda: ripples(35000, 0.02, 5.0, coarse=0.1, seed=3), 3, 1.0),
}


@pytest.mark.parametrize("name", list(CASES))
def test_each_band_is_applied_along_its_own_lifted_levels_normal(name):
    """The issue's bounds (median under 1 degree, 99th percentile under 3) at every band, under
    four lifts with slopes up to 40 degrees, away from the patch's rim. Measured 2026-12-08
    (/tmp script over these cases): at most 0.79 degrees at the median and 1.83 at the 99th
    percentile. With no edit the two normals already differ by up to 0.72 and 1.65 (level 0 of
    4 levels, where the fit's weights and the engine's anchors see a nearly flat base
    differently), and the lifts add at most 0.27 to the median. Not asserted: the random ripples
    at 4 levels with kernel 2, where level 0's two normals differ by 1.07 degrees at the median
    with no edit at all (1.10 under the lifts, 0.20 added)."""
    make, levels, kernel = CASES[name]
    points = make()
    dec = ps.decompose(points, levels=levels, kernel=kernel)
    inner = np.flatnonzero(np.abs(dec.base[:, :2]).max(axis=1) < 0.75)
    at = np.random.default_rng(1).choice(inner, 3000, replace=False)
    unedited = [np.median(a) for a in band_angles(dec, ps.reconstruct_levels(dec), at)]
    for centre, radius, height in LIFTS:
        lifted = ps.reconstruct_levels(dec, base=gaussian_lift(dec.base, np.array(centre), radius, height))
        for l, angle in enumerate(band_angles(dec, lifted, at)):
            median, p99 = np.median(angle), np.percentile(angle, 99)
            assert median < 1.0 and p99 < 3.0, (name, centre, l, median, p99)
            assert median < unedited[l] + 0.35, (name, centre, l, median, unedited[l])
