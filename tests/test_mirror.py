"""Mirror symmetry (issue 17, requirement 4): decompose(points, mirror=...) of a half model is
exactly symmetric, and points on the mirror plane stay on it at every level and with any edit."""
import warnings

import numpy as np
import pytest

import pointscale as ps
from helpers import diagonal

# Off the origin, so that the planes' origin matters: the plane x = 0.3.
CENTRE = np.array([0.3, -0.2, 0.5])


def bumpy_half(axes="x", segments=160, rings=80):
    """The x >= 0 half (or the quarter for "xy") of a bumpy UV sphere about CENTRE, its faces
    and its seam points (those on a plane). The bumps differ across every plane within the half."""
    v, f = ps.meshes.uv_sphere(1.0, segments, rings)
    for axis in axes:
        a = "xyz".index(axis)
        v[np.abs(v[:, a]) < 1e-12, a] = 0.0  # the sphere's own rounding: cos(pi / 2) is 6e-17
    v = ps.meshes.bumpy(v, 0.08, 5.0) + 0.01 * np.sin(9.0 * v[:, [1, 2, 0]] + 0.4).sum(axis=1, keepdims=True) * v
    keep = np.ones(len(v), bool)
    for axis in axes:
        keep &= v[:, "xyz".index(axis)] >= 0.0
    renumber = np.cumsum(keep) - 1
    faces = renumber[f[keep[f].all(axis=1)]]
    half = v[keep] + CENTRE
    seam = np.zeros(len(half), bool)
    for axis in axes:
        seam |= half[:, "xyz".index(axis)] == CENTRE["xyz".index(axis)]
    return half, faces, seam


@pytest.fixture(scope="module")
def half():
    return bumpy_half()


@pytest.fixture(scope="module")
def mirrored(half):
    points, faces, _ = half
    return ps.decompose(points, levels=4, mirror=ps.Mirror("x", origin=CENTRE), faces=faces)


def whole_base_and_partners(dec):
    """A decomposition about one mirror plane (x), read through its saved arrays (to_dict): the
    whole model's base (the half's points first, then the reflections of the half's points off
    the seam, in order) and, per half point, the whole model's point that is its reflection."""
    arrays = dec.to_dict()
    whole = arrays["base"] + arrays["origin"]
    seam = arrays["mirror_seam"][:, 0].astype(bool)
    n = len(seam)
    partner = np.arange(n)
    partner[~seam] = n + np.arange(int((~seam).sum()))
    return whole, partner


def plain_average(whole, partner):
    """Each half point's mean with its partner's reflection across x = CENTRE[0]."""
    reflected = whole[partner] - CENTRE
    reflected[:, 0] *= -1.0
    return 0.5 * ((whole[: len(partner)] - CENTRE) + reflected) + CENTRE


def plane_offsets(points, seam, axis=0):
    return np.abs(points[seam, axis] - CENTRE[axis])


def test_without_the_mirror_the_seam_drifts_off_the_plane(half):
    points, _, seam = half
    dec = ps.decompose(points, levels=4)
    drift = plane_offsets(dec.level(0), seam).max() / diagonal(points)
    assert drift > 2e-3, drift  # measured 4.2e-3: the half's base shrinks away from its open edge


def test_seam_points_stay_on_the_plane_at_every_level(half, mirrored):
    points, _, seam = half
    assert seam.sum() > 90 and mirrored.n_points == len(points)
    # Asked: within 1e-12 of the diagonal. Measured: on the plane exactly, (a - a) / 2 + origin.
    for l in range(mirrored.n_levels):
        assert plane_offsets(mirrored.level(l), seam).max() == 0.0, l
    assert plane_offsets(mirrored.base, seam).max() == 0.0
    assert plane_offsets(ps.blend(mirrored, 1.5), seam).max() == 0.0
    for l in range(mirrored.n_bands):
        assert np.abs(mirrored.normals(l)[seam, 0]).max() == 0.0  # the normals lie in the plane
    # A part that crosses the plane is one part with its reflection.
    assert mirrored.parts is None


def test_the_half_is_the_symmetric_average_of_the_whole_model(half, mirrored):
    # The whole model (the half and its reflection) is decomposed by the ordinary path; each
    # point of the half is the mean of its own result and its partner's, reflected back.
    points, _, seam = half
    whole, partner = whole_base_and_partners(mirrored)
    assert len(whole) == 2 * len(points) - seam.sum()
    expected = plain_average(whole, partner)
    assert np.abs(mirrored.base - expected).max() <= 1e-15 * diagonal(points)
    # And the whole model alone is not symmetric: the average does something.
    asymmetry = np.abs(whole[: len(points)] - expected).max() / diagonal(points)
    assert asymmetry > 1e-3, asymmetry  # measured 7.3e-3
    # (So the partners are right too: a wrong one would be off by the asymmetry, not 1e-15.)


def test_unit_gains_return_the_input(half, mirrored):
    points, _, _ = half
    assert np.abs(ps.reconstruct(mirrored) - points).max() <= 1e-11 * diagonal(points)  # measured 2.6e-15
    assert np.abs(mirrored.level(3) - points).max() <= 2e-14 * diagonal(points)  # measured 2.6e-15


def test_gains_and_an_edited_base_keep_the_seam_on_the_plane(half, mirrored):
    points, _, seam = half
    bound = 0.0  # asked: 1e-12 of the diagonal; measured: exactly on the plane
    for gains in ([2.0, 2.0, 2.0], [0.0, -1.0, 3.0]):
        assert plane_offsets(ps.reconstruct(mirrored, gains), seam).max() <= bound
    lifted = mirrored.base.copy()
    bump = np.exp(-np.sum((lifted - (CENTRE + [0.0, 0.0, 1.0])) ** 2, axis=1) / 0.3)
    lifted += 0.2 * bump[:, None] * np.array([0.1, 0.3, 1.0])  # a lift that also pushes the seam off the plane
    assert plane_offsets(lifted, seam).max() > 0.01
    out, folds = ps.reconstruct(mirrored, base=lifted, folds="report")
    assert plane_offsets(out, seam).max() <= bound
    assert folds.kind.shape == (len(points),)
    assert out[:, 2].max() > points[:, 2].max() + 0.1  # the lift carried the detail up
    painted = np.random.default_rng(1).uniform(0.0, 2.0, (3, len(points)))
    solver = ps.Reconstructor(mirrored)
    same = solver.reconstruct(painted, lifted)
    assert np.array_equal(same, ps.reconstruct(mirrored, painted, lifted))
    assert plane_offsets(same, seam).max() <= bound
    prevented, _ = ps.reconstruct(mirrored, [4.0, 4.0, 4.0], folds="prevent")
    assert plane_offsets(prevented, seam).max() <= bound
    levels = ps.reconstruct_levels(mirrored, [2.0, 2.0, 2.0], lifted)
    assert max(plane_offsets(level, seam).max() for level in levels) <= bound


def test_save_and_load_keep_the_mirror(half, mirrored, tmp_path):
    points, _, seam = half
    path = tmp_path / "mirrored.npz"
    mirrored.save(path)
    back = ps.load(path)
    assert back.mirror == mirrored.mirror and back.mirror.axes == "x"
    assert back.n_points == len(points)
    assert np.array_equal(back.level(0), mirrored.level(0))
    assert np.array_equal(ps.reconstruct(back, [2.0, 0.5, 1.0]), ps.reconstruct(mirrored, [2.0, 0.5, 1.0]))
    arrays = mirrored.to_dict()
    wrong = dict(arrays, mirror_seam=arrays["mirror_seam"][:-1])
    with pytest.raises(ValueError, match="mirror_seam makes a whole model"):
        ps.Decomposition.from_dict(wrong)
    without = {key: value for key, value in arrays.items() if key != "mirror_seam"}
    with pytest.raises(ValueError, match="needs both"):
        ps.Decomposition.from_dict(without)
    floats = dict(arrays, mirror_seam=arrays["mirror_seam"].astype(np.float64))
    with pytest.raises(ValueError, match="uint8"):
        ps.Decomposition.from_dict(floats)


def test_two_planes():
    points, faces, _ = bumpy_half("xy", 96, 48)
    dec = ps.decompose(points, levels=3, mirror=ps.Mirror("yx", origin=CENTRE), faces=faces)
    assert dec.mirror.axes == "xy" and len(dec.to_dict()["base"]) > 3.8 * len(points)  # the whole model
    bound = 0.0  # asked: 1e-12 of the diagonal; measured: exactly on the plane
    for axis in (0, 1):
        on = points[:, axis] == CENTRE[axis]
        assert on.sum() > 40
        for l in range(dec.n_levels):
            assert plane_offsets(dec.level(l), on, axis).max() <= bound, (axis, l)
        assert plane_offsets(ps.reconstruct(dec, [2.0, 2.0]), on, axis).max() <= bound
    assert np.abs(ps.reconstruct(dec) - points).max() <= 1e-11 * diagonal(points)  # measured 2.6e-15


def test_points_near_the_plane_are_snapped_onto_it(half):
    points, _, seam = half
    nudged = points.copy()
    nudged[seam, 0] += 1e-5 * np.sin(np.arange(seam.sum()))
    dec = ps.decompose(nudged, levels=3, mirror=ps.Mirror("x", CENTRE, seam=2e-5))
    assert plane_offsets(dec.level(dec.n_levels - 1), seam).max() == 0.0
    assert dec.settings["mirror"]["seam"] == 2e-5


@pytest.mark.parametrize("mirror, match", [
    ("w", "distinct letters"), ("xx", "distinct letters"), ("", "distinct letters"), (3, "pointscale.Mirror"),
])
def test_bad_mirror_arguments(half, mirror, match):
    with pytest.raises(ValueError, match=match):
        ps.decompose(half[0], levels=3, mirror=mirror)


def test_bad_mirror_values(half):
    points = half[0]
    with pytest.raises(ValueError, match="origin"):
        ps.Mirror("x", origin=(0.0, np.nan, 0.0))
    with pytest.raises(ValueError, match="origin"):
        ps.Mirror("x", origin=(0.0, 1.0))
    with pytest.raises(ValueError, match="seam"):
        ps.Mirror("x", seam=-1.0)
    with pytest.raises(ValueError, match="both sides of the x mirror plane"):
        ps.decompose(points, levels=3, mirror=ps.Mirror("x", origin=CENTRE + [0.5, 0.0, 0.0]))
    with pytest.raises(ValueError, match="both sides of the y mirror plane"):
        ps.decompose(points, levels=3, mirror=ps.Mirror("xy", origin=CENTRE))
    flat = points.copy()
    flat[:, 0] = CENTRE[0]
    with pytest.raises(ValueError, match="all points lie on the x mirror plane"):
        ps.decompose(flat, levels=3, mirror=ps.Mirror("x", origin=CENTRE))


def test_points_off_the_plane_stay_off_the_seam(half):
    # A level that pulls a point towards the plane must not make it a seam point: Blender's Mirror
    # modifier would merge it with its reflection. Near the poles level 0 pulls points this close.
    points, _, _ = half
    seam = 2e-3
    dec = ps.decompose(points, levels=4, mirror=ps.Mirror("x", CENTRE, seam=seam))
    off = np.abs(points[:, 0] - CENTRE[0]) > seam
    averaged = plain_average(*whole_base_and_partners(dec)) - CENTRE
    assert (np.abs(averaged[off, 0]) <= seam).sum() > 0  # without the rule some would be on the seam
    for l in range(dec.n_levels):
        side = dec.level(l)[off, 0] - CENTRE[0]
        assert side.min() > seam, l
    assert (ps.reconstruct(dec, [2.0, 2.0, 2.0])[off, 0] - CENTRE[0]).min() > seam


def test_the_command_line_mirror_option(half, tmp_path):
    import subprocess
    import sys
    points, faces, seam = half
    ps.io.write(tmp_path / "half.ply", ps.io.Scan(points=points, faces=faces))
    origin = ",".join(repr(float(v)) for v in CENTRE)
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "pointscale", "decompose", str(tmp_path / "half.ply"), "-o", str(out),
                           "--levels", "3", "--mirror", "x", "--mirror-origin", origin],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "mirror symmetric about x" in done.stdout
    dec = ps.load(out / "decomposition.npz")
    assert dec.mirror.axes == "x" and dec.mirror.origin == tuple(CENTRE)
    level0 = ps.io.read(out / "level_0.ply").points
    assert np.abs(level0[seam, 0] - CENTRE[0]).max() <= 1e-7  # the file's single precision
    bad = subprocess.run([sys.executable, "-m", "pointscale", "decompose", str(tmp_path / "half.ply"), "-o",
                          str(tmp_path / "bad"), "--mirror", "y"], capture_output=True, text=True)
    assert bad.returncode == 2 and "both sides of the y mirror plane" in bad.stderr, bad.stderr
    assert "Traceback" not in bad.stderr


def test_a_mirror_plane_far_from_the_half_is_said_so():
    """A plane 1e6 from a half of size 3 (a wrong origin) made the whole model a line, and the
    error blamed collinear points; it now names the plane and its distance."""
    from pointscale import meshes
    v, _ = meshes.uv_sphere(1.0, 48, 24)
    half = meshes.bumpy(v, 0.02, 5)
    half = half[half[:, 0] >= 0]
    with pytest.raises(ValueError) as refused:
        ps.decompose(half, 3, mirror=ps.Mirror("x", origin=(-1e6, 0, 0)), threads=1)
    message = str(refused.value)
    assert message.startswith("the x mirror plane (x = -1000000) lies 1e+06 from the half"), message
    assert "check Mirror's origin" in message
    with pytest.raises(ValueError, match="^points are collinear"):  # a half that is a line is still said so
        ps.decompose(np.c_[np.linspace(1, 2, 50), np.zeros(50), np.zeros(50)], 2, mirror="x", threads=1)


def test_a_half_far_from_its_mirror_plane_is_warned_of():
    """A georeferenced half mirrored about x = 0 (its origin forgotten) was decomposed as two
    copies a million units apart without a word."""
    rng = np.random.default_rng(8)
    d = rng.normal(size=(4000, 3))
    half = d / np.linalg.norm(d, axis=1)[:, None] * [20.0, 30.0, 10.0]
    half = half[half[:, 0] >= 0] + [512000.125, 4100000.5, 80.0]
    with pytest.warns(UserWarning, match=r"no point lies within 512000 of the x mirror plane \(x = 0\)"):
        ps.decompose(half, 3, mirror="x")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the plane through the seam: nothing to say
        dec = ps.decompose(half, 3, mirror=ps.Mirror("x", origin=(512000.125, 0.0, 0.0)))
    assert dec.mirror.origin[0] == 512000.125
