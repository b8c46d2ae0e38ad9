"""Points that coincide in the input (a mesh split along a seam, as imported FBX and glTF assets
are at their UV seams and hard edges; a scan's duplicates) have no order to keep: a fold test
across them read the rounding of their base positions, and a base moved as a whole reported
folds there, which Prevent Folds then flattened the detail around (issue 16, item 5)."""
import numpy as np
import pytest

import pointscale as ps


def with_duplicates(points, share, seed):
    """The points, and a copy of `share` of them appended (coincident pairs)."""
    rng = np.random.default_rng(seed)
    copies = rng.choice(len(points), int(share * len(points)), replace=False)
    return np.vstack([points, points[copies]])


@pytest.mark.parametrize("n,share,seed,levels", [(6000, 0.05, 0, 3), (12000, 0.02, 1, 4), (9000, 0.1, 2, 3)])
def test_a_base_moved_as_a_whole_folds_nowhere_at_coincident_points(n, share, seed, levels):
    points = with_duplicates(ps.shapes.bumpy_sphere(n, seed=seed), share, seed)
    dec = ps.decompose(points, levels=levels)
    # Moved as a whole, and rounded to float32 as Blender's keys keep it.
    moved = (dec.base + np.array([0.05, -0.1, 0.2])).astype(np.float32).astype(np.float64)
    plain = ps.reconstruct(dec, base=moved)
    _, folds = ps.reconstruct(dec, base=moved, folds="report")
    assert folds.count == 0, np.flatnonzero(folds.kind)
    prevented, folds = ps.reconstruct(dec, base=moved, folds="prevent")
    assert folds.count_before == 0 and not folds.changed.any()
    assert np.array_equal(prevented, plain)


@pytest.mark.parametrize("gains", [(3, 3, 3), (1, 1, 6)])
def test_scaled_up_detail_still_folds_beside_coincident_points(gains):
    """The tall handles plane holds 448 coincident pairs (where its walls meet the plane and
    the tops). Leaving only the edges between them out, its folds are those of the same points
    made unique (measured 4,999 and 4,561 at these gains), plus their copies (334 and 346 more),
    and prevention takes one round with or without the copies (it took 3 and 4 with them)."""
    points = ps.shapes.handles_plane()[0]
    unique = np.unique(points, axis=0)
    assert len(points) - len(unique) == 448
    found, rounds = [], []
    for cloud in (unique, points):
        dec = ps.decompose(cloud, levels=4)
        _, folds = ps.reconstruct(dec, gains, folds="report")
        _, prevented = ps.reconstruct(dec, gains, folds="prevent")
        assert prevented.count == 0
        found.append(folds.count)
        rounds.append(prevented.rounds)
    assert found[0] > 4000
    assert found[0] <= found[1] <= found[0] + 448, found
    assert rounds[1] <= rounds[0] + 1, rounds
