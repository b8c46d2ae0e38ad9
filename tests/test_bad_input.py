"""Every bad input raises ValueError with a clear message: no crash, no hang."""
import numpy as np
import pytest

import pointscale as ps

GOOD = ps.shapes.bumpy_sphere(3000)


@pytest.mark.parametrize("points, message", [
    (np.full((3000, 3), np.nan), "NaN"),
    (np.where(np.arange(9000).reshape(3000, 3) == 7, np.inf, GOOD), "NaN or infinite"),
    (np.zeros((0, 3)), "empty"),
    (GOOD[:100], "at least"),
    (np.ones((3000, 3)), "identical"),
    (np.outer(np.linspace(0, 1, 3000), [1.0, 2.0, 3.0]), "collinear"),
    (np.column_stack([np.random.default_rng(0).uniform(size=(3000, 2)), np.zeros(3000)]), "one plane"),
    (GOOD.astype(np.complex128), "real numbers"),
    (GOOD.astype(str), "real numbers"),
    (GOOD[:, :2], "shape"),
    (GOOD.reshape(-1), "shape"),
    ([[1, 2, 3], [4, 5]], "array"),
])
def test_decompose_rejects(points, message):
    with pytest.raises(ValueError, match=message):
        ps.decompose(points)


@pytest.mark.parametrize("kwargs, message", [
    (dict(levels=1), "levels"), (dict(levels=2.5), "whole"), (dict(decimation=1.5), "decimation"),
    (dict(decimation=0), "decimation"), (dict(kernel=-1), "kernel"), (dict(neighbors=2), "neighbors"),
    (dict(normals=np.ones((5, 3))), "normals"), (dict(progress=3), "progress"),
])
def test_decompose_rejects_options(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ps.decompose(GOOD, **kwargs)


@pytest.fixture(scope="module")
def dec():
    return ps.decompose(GOOD, levels=3)


@pytest.mark.parametrize("gains", [[1, 1, 1], np.ones((2, 5)), [1, np.nan], "ab"])
def test_reconstruct_rejects_gains_of_the_wrong_shape(dec, gains):
    with pytest.raises(ValueError, match="gains"):
        ps.reconstruct(dec, gains=gains)


def test_reconstruct_rejects_a_base_of_the_wrong_length(dec):
    with pytest.raises(ValueError, match="base"):
        ps.reconstruct(dec, base=GOOD[:-1])
    with pytest.raises(ValueError, match="NaN"):
        ps.reconstruct(dec, base=np.full_like(GOOD, np.nan))


def test_reconstructor_rejects_what_reconstruct_rejects(dec):
    solver = ps.Reconstructor(dec)
    for gains in ([1, 1, 1], np.ones((2, 5)), [1, np.nan]):
        with pytest.raises(ValueError, match="gains"):
            solver.reconstruct(gains=gains)
    with pytest.raises(ValueError, match="base"):
        solver.reconstruct(base=GOOD[:-1])
    with pytest.raises(ValueError, match="Decomposition"):
        ps.Reconstructor(GOOD)


def test_other_functions_reject_bad_input(dec):
    with pytest.raises(ValueError, match="t must be"):
        ps.blend(dec, 5)
    with pytest.raises(ValueError, match="level"):
        dec.level(7)
    with pytest.raises(ValueError, match="Decomposition"):
        ps.reconstruct(GOOD)
    with pytest.raises(ValueError, match="onto"):
        ps.project(GOOD, GOOD[:2])
    for near, message in [(np.zeros(5, int), "near must be"), (np.full(3000, 0.5), "integers"),
                          (np.full(3000, 100), r"\[0, 99\]"), (np.full(3000, -1), "index onto")]:
        with pytest.raises(ValueError, match=message):
            ps.project(GOOD, GOOD[:100], near=near)
    with pytest.raises(ValueError, match="target"):
        ps.decimate(GOOD, 10**6)
    with pytest.raises(ValueError, match="collinear"):
        ps.estimate_normals(np.outer(np.arange(100.0), [1, 0, 0]))


def test_load_rejects_a_file_that_is_not_a_decomposition(tmp_path):
    np.savez(tmp_path / "x.npz", a=np.zeros(3))
    with pytest.raises(ValueError, match="not a pointscale decomposition"):
        ps.load(tmp_path / "x.npz")
    (tmp_path / "y.npz").write_bytes(b"garbage")
    with pytest.raises(ValueError, match="cannot read"):
        ps.load(tmp_path / "y.npz")


def test_a_very_coarse_base_is_warned_about():
    with pytest.warns(UserWarning, match="62 support points at level 0"):
        ps.decompose(ps.shapes.bumpy_sphere(4000), levels=4)
