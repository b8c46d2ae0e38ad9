"""Multiscale deformation, the paper's Fig. 5: handles stay normal to a deformed base."""
import numpy as np
import pytest

import pointscale as ps


def bump(xy, height=0.8, width=1.0):
    return height * np.exp(-(xy**2).sum(axis=1) / width**2)


@pytest.fixture(scope="module")
def handles():
    points, handle, centres = ps.shapes.handles_plane()
    dec = ps.decompose(points, levels=4, decimation=0.2, kernel=2.0)
    return points, handle, centres, dec


def test_base_is_nearly_flat(handles):
    points, handle, centres, dec = handles
    assert np.ptp(dec.base[:, 2]) < 0.2 * points[:, 2].max()


def test_multiscale_handles_follow_the_lifted_base(handles):
    points, handle, centres, dec = handles
    lifted = dec.base.copy()
    lifted[:, 2] += bump(lifted[:, :2])
    result = ps.reconstruct(dec, base=lifted)
    angles = ps.shapes.handle_angles(result, points, handle, centres, lifted)
    assert angles.max() < 3.0, angles


def test_single_scale_deformation_tilts_flank_handles(handles):
    points, handle, centres, dec = handles
    moved = points.copy()
    moved[:, 2] += bump(points[:, :2])
    angles = ps.shapes.handle_angles(moved, points, handle, centres, moved)
    assert angles.max() > 10.0, angles


def test_turning_the_base_over_keeps_detail_on_the_outside():
    """An edit that turns part of the base by more than 90 degrees must not flip the detail."""
    points = ps.shapes.wavy_patch(20000, coarse=0.0, fine=0.01)
    dec = ps.decompose(points, levels=3, kernel=2.0)
    # Roll the patch around the y axis into a half cylinder: the ends turn by 90 degrees.
    x, y, z = dec.base.T
    radius = 2.0 / np.pi
    theta = x / radius
    rolled = np.column_stack([(radius + z) * np.sin(theta), y, (radius + z) * np.cos(theta)])
    result = ps.reconstruct(dec, base=rolled)
    # Detail stays a thin normal displacement of the rolled base: a point's distance from the
    # cylinder axis is radius + its base's height (rolled in) + its detail (the input's height
    # over its base, outward), that is radius + the input's height.
    height = np.linalg.norm(result[:, [0, 2]], axis=1) - radius
    assert np.abs(height - points[:, 2]).max() < 0.003
    # ... a bound the detail exceeds twice over, so that detail turned inward (off by twice
    # the detail) fails it.
    assert np.abs(points[:, 2] - dec.base[:, 2]).max() > 2 * 0.003


@pytest.mark.parametrize("n", [3000, 40000])
def test_an_unedited_explicit_base_gives_the_default_reconstruction(n):
    """Sparse levels have clusters whose mean normal is far from their points' normals; the
    orientation carried to an explicit base must still agree with the stored one."""
    points = ps.shapes.bumpy_sphere(n)
    dec = ps.decompose(points, levels=4)
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    # Near, not equal: the base given back is rounded by the centring (measured 6.4e-17).
    assert np.abs(ps.reconstruct(dec, base=dec.base.copy()) - ps.reconstruct(dec)).max() <= 1e-13 * diagonal
