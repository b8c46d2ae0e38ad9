"""The kNN rows every decomposition step asks for (grid with a kd-tree fallback), against a
brute-force search."""
import numpy as np
import pytest

import pointscale as ps
from pointscale import _testing


def awkward_cloud() -> np.ndarray:
    """A surface with what a scan brings: a patch 100 times denser, exact duplicates, a pile
    of one point repeated (a crowded cell), and a few far, sparse points."""
    rng = np.random.default_rng(7)
    sphere = ps.shapes.bumpy_sphere(4000)
    patch = sphere[0] + rng.normal(scale=0.002, size=(800, 3))
    duplicates = sphere[rng.choice(len(sphere), 200, replace=False)]
    pile = np.repeat(sphere[1:2], 1100, axis=0)
    far = rng.uniform(5, 9, (40, 3))
    return np.concatenate([sphere, patch, duplicates, pile, far])


def brute_force_squared_distances(points: np.ndarray, rows: slice) -> np.ndarray:
    q = points[rows]
    # Summed in the order the core sums them, so that the values compare exactly.
    dx = q[:, None, 0] - points[None, :, 0]
    dy = q[:, None, 1] - points[None, :, 1]
    dz = q[:, None, 2] - points[None, :, 2]
    return dx * dx + dy * dy + dz * dz


def lattice() -> np.ndarray:
    """A 70 x 70 grid of unit spacing: every row ends among points at equal distances."""
    return np.stack(np.meshgrid(np.arange(70.0), np.arange(70.0), [0.0], indexing="ij"), -1).reshape(-1, 3)


@pytest.mark.parametrize("make", [awkward_cloud, lattice])
def test_rows_are_the_exact_nearest(make):
    points = make()
    assert len(points) > 4096  # past the size below which the tree alone answers
    ks = (1, 6, 24, 40)
    found = {k: _testing.self_knn(points, k) for k in ks}
    for start in range(0, len(points), 1000):
        rows = slice(start, min(start + 1000, len(points)))
        full = brute_force_squared_distances(points, rows)
        smallest = np.sort(np.partition(full, max(ks), axis=1)[:, :max(ks)], axis=1)
        for k in ks:
            nearest, d2 = found[k][0][rows], found[k][1][rows]
            # The k smallest distances, closest first (ties may come in any order of index).
            np.testing.assert_array_equal(d2, smallest[:, :k], err_msg=f"k = {k}")
            # Each index is a different point at the distance reported for it.
            np.testing.assert_array_equal(np.take_along_axis(full, nearest, axis=1), d2, err_msg=f"k = {k}")
            assert all(len(set(r)) == k for r in nearest), f"k = {k}"


def test_bad_k_is_a_value_error():
    with pytest.raises(ValueError, match="k must be"):
        _testing.self_knn(ps.shapes.sphere(100), 101)
