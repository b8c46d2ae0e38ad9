"""Real scans from ../shared/data (skipped where that folder is absent): the round trip stays
exact, and an unedited explicit base gives the same result, on CAD edges, busts, fine scales and
1.1M raw range scans with their outliers and overlaps."""
import numpy as np
import pytest

import pointscale as ps
from helpers import diagonal, shared_model

pytestmark = pytest.mark.data


# Share of anchors pinned over all bands (measured 2026-11-22: fandisk 14%, Max Planck 1.1%,
# Igea 0%, dragon 1.0%, Buddha 0.35%). The CAD part's sharp edges stall many anchors at the
# coarse bands; the bound guards against that spreading to smooth scans.
PINNED_AT_MOST = {"fandisk.ply": 0.2, "max_planck.ply": 0.03, "igea.ply": 0.03, "dragon.ply": 0.03,
                  "happy_buddha_scans.ply": 0.03}


@pytest.mark.parametrize("name", list(PINNED_AT_MOST))
def test_scan_round_trip_is_exact(name):
    points = ps.io.read_ply(shared_model(name)).points
    dec = ps.decompose(points, levels=4)
    assert dec.details.shape == (3, len(points))
    exact = ps.reconstruct(dec)
    assert np.abs(exact - points).max() <= 1e-6 * diagonal(points)
    again = ps.reconstruct(dec, base=dec.base.copy())
    assert np.abs(again - exact).max() <= 1e-9 * diagonal(points)
    pinned = sum(r["pinned"] for r in dec.stats) / sum(r["support_points"] for r in dec.stats)
    assert pinned <= PINNED_AT_MOST[name]
