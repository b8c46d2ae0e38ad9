"""Band filtering (paper Sec. 8.2, Fig. 7): scaling one detail band scales one frequency band.

A unit sphere carries a coarse bump pattern and a fine one. The fine pattern (about 6 sample
spacings per period) is chosen so that it lives in the last band of a default 4-level
decomposition, while the coarse one lives in P^0..P^2. Amplitudes are measured by least
squares against the two known patterns, so the other band and the sampling do not leak in.
"""
import numpy as np
import pytest

import pointscale as ps
from pointscale.shapes import bump_field

COARSE, COARSE_FREQ = 0.08, 3.0
FINE, FINE_FREQ = 0.01, 60.0


def amplitudes(points):
    """(coarse, fine) amplitude of the radial function of `points` on the unit sphere."""
    r = np.linalg.norm(points, axis=1)
    u = points / r[:, None]
    a = np.column_stack([np.ones(len(r)), bump_field(u, COARSE_FREQ), bump_field(u, FINE_FREQ)])
    c, *_ = np.linalg.lstsq(a, r, rcond=None)
    return c[1], c[2]


@pytest.fixture(scope="module")
def sphere_decomposition():
    p = ps.shapes.bumpy_sphere(40000, coarse=COARSE, coarse_frequency=COARSE_FREQ, fine=FINE,
                               fine_frequency=FINE_FREQ)
    return p, ps.decompose(p, levels=4)


def test_input_amplitudes_are_measured_exactly(sphere_decomposition):
    p, _ = sphere_decomposition
    coarse, fine = amplitudes(p)
    assert coarse == pytest.approx(COARSE, rel=1e-6)
    assert fine == pytest.approx(FINE, rel=1e-6)


def test_fine_pattern_lives_in_the_last_band(sphere_decomposition):
    _, dec = sphere_decomposition
    _, fine_below = amplitudes(dec.level(dec.n_levels - 2))
    assert abs(fine_below) < 0.2 * FINE


def test_gain_zero_on_last_band_removes_fine_keeps_coarse(sphere_decomposition):
    _, dec = sphere_decomposition
    coarse, fine = amplitudes(ps.reconstruct(dec, [1.0, 1.0, 0.0]))
    assert abs(fine) <= 0.2 * FINE, f"fine amplitude {fine:.5f} left of {FINE}"
    assert coarse >= 0.8 * COARSE, f"coarse amplitude {coarse:.5f} of {COARSE}"


def test_gain_two_on_last_band_doubles_fine(sphere_decomposition):
    _, dec = sphere_decomposition
    coarse, fine = amplitudes(ps.reconstruct(dec, [1.0, 1.0, 2.0]))
    assert fine == pytest.approx(2 * FINE, rel=0.2), f"fine amplitude {fine:.5f}, want {2 * FINE}"
    assert coarse == pytest.approx(COARSE, rel=0.2)


def test_unit_gains_keep_both_patterns(sphere_decomposition):
    p, dec = sphere_decomposition
    # A round trip, to 1e-11 of the diagonal (measured 7e-16).
    assert np.abs(ps.reconstruct(dec, [1.0, 1.0, 1.0]) - p).max() <= 1e-11 * np.linalg.norm(np.ptp(p, axis=0))
