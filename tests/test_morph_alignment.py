"""Morph with B away from A (issue 18, req. 5): the overlap is checked, and an alignment carries B
onto A for the morph and puts it back at beta = 1."""
import warnings

import numpy as np
import pytest
from scipy.spatial import cKDTree

import pointscale as ps
from pointscale.alignment import similarity


def lumpy(n, amplitude, seed):
    """An asymmetric blob: a stretched bumpy sphere with a lobe on one side."""
    p = ps.shapes.bumpy_sphere(n, coarse=amplitude, seed=seed) * np.array([1.2, 0.9, 0.7])
    lobe = np.exp(-np.sum((p - [0.9, 0.4, 0.2]) ** 2, axis=1) / 0.2)
    return p * (1.0 + 0.25 * lobe)[:, None]


def rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    t = np.radians(degrees)
    return np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * k @ k


def landing(m, b):
    """How far beta = 1 lands from B: the 99th percentile of the distance to B's nearest point, over B's diagonal."""
    d, _ = cKDTree(b).query(m.evaluate(0.0, 1.0))
    return np.percentile(d, 99) / np.linalg.norm(np.ptp(b, axis=0))


A = lumpy(20000, 0.06, 1)
B_SHAPE = lumpy(16000, 0.10, 2)


@pytest.mark.parametrize("align, turn, scale, shift", [
    ("bbox", 0.0, 1.0, (3.0, 0.0, 0.0)),
    ("bbox", 0.0, 0.6, (0.0, -2.5, 1.0)),
    ("pca", 35.0, 1.3, (3.0, 1.0, 0.0)),
    ("icp", 35.0, 1.3, (3.0, 1.0, 0.0)),
    ("icp", 120.0, 0.8, (-1.0, 3.0, 2.0)),
])
def test_aligned_morph_lands_on_b_where_it_lies(align, turn, scale, shift):
    b = scale * B_SHAPE @ rotation([0.3, 1.0, 0.2], turn).T + np.asarray(shift)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # aligned, they overlap: no warning
        m = ps.morph(A, b, align=align)
    assert landing(m, b) < 0.01, landing(m, b)
    assert np.abs(m.evaluate(1.0, 0.0) - A).max() < 1e-9  # alpha = 1 is still A where it lies
    assert m.report["overlap"] > 0.5


def test_a_morph_of_models_apart_warns_and_misses_b():
    b = B_SHAPE + np.array([3.0, 0.0, 0.0])
    with pytest.warns(UserWarning, match="barely overlap.*align"):
        m = ps.morph(A, b)
    assert m.report["overlap"] == 0.0
    assert landing(m, b) > 0.3  # measured: beta = 1 lands a diagonal or more away


def test_alignment_recovers_a_known_similarity():
    turn = rotation([1.0, 0.2, -0.4], 50.0)
    b = 1.7 * A @ turn.T + np.array([2.0, -1.0, 0.5])
    s = similarity(b, A, "icp")
    assert np.abs(s.apply(b) - A).max() < 1e-6 * np.linalg.norm(np.ptp(A, axis=0))
    assert abs(s.scale * 1.7 - 1.0) < 1e-3


def test_unknown_alignment_is_refused():
    with pytest.raises(ValueError, match="align must be one of"):
        ps.morph(A, B_SHAPE, align="magic")
