"""A fifth pass over the package's promises (QA, 2026-12-07): what was silent now says so.

An encoding that does not give the model back, a projection or a normal estimate that leaves
points without a normal, and a reconstruction without the input's attributes now warn; a
decomposition file with zero base normals and a save to something that is not a path are
refused with a ValueError."""
import warnings

import numpy as np
import pytest

import pointscale as ps
from helpers import run_cli


def _caught(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn()
    return result, [str(w.message) for w in caught]


@pytest.mark.parametrize("offset", [0.5, 100.0])
def test_encode_onto_a_far_base_warns_that_the_model_is_not_given_back(offset):
    p = ps.shapes.bumpy_sphere(2000)
    dec, said = _caught(lambda: ps.encode(p, ps.ellipsoid_base(p) + offset))
    miss = np.linalg.norm(ps.reconstruct(dec) - p, axis=1).max()
    assert miss > 1e-3  # measured 0.62 and 172
    assert any(m.startswith("encode: reconstruct at gain 1 misses the model by up to") for m in said), said
    assert f"{miss:.3g}" in " ".join(said)


def test_encode_onto_a_near_base_is_exact_and_silent():
    p = ps.shapes.bumpy_sphere(3000, coarse=0.1, coarse_frequency=3.0, fine=0.02, seed=4)
    dec, said = _caught(lambda: ps.encode(p, ps.ellipsoid_base(p)))
    assert np.abs(ps.reconstruct(dec) - p).max() < 1e-9 * np.ptp(p, axis=0).max()
    assert not [m for m in said if m.startswith("encode:")], said


def test_encode_says_nothing_of_the_iterations_rounding():
    """A model 40 kernels off a sphere base: the residual is the iteration's rounding (7.9e-9,
    1.1e-9 of the diagonal), and no point is pinned."""
    model = 2.0 * ps.shapes.bumpy_sphere(20000, coarse=0.05, fine=0.0)
    dec, said = _caught(lambda: ps.encode(model, ps.shapes.sphere(20000)))
    assert 0 < dec.stats[0]["consistency_residual"] < 1e-8 and dec.stats[0]["pinned"] == 0
    assert not [m for m in said if m.startswith("encode:")], said


def test_a_file_with_zero_base_normals_is_refused(tmp_path):
    p = ps.shapes.bumpy_sphere(3000)
    ps.decompose(p, 3).save(tmp_path / "a.npz")
    arrays = dict(np.load(tmp_path / "a.npz"))
    arrays["base_normals"][5:9] = 0.0
    np.savez(tmp_path / "b.npz", **arrays)
    with pytest.raises(ValueError, match=r"base_normals must be unit vectors \(4 are not, first: row 5\)"):
        ps.load(tmp_path / "b.npz")


@pytest.mark.parametrize("path", [None, 3, b"dec.npz"])
def test_save_to_something_that_is_not_a_path_is_a_value_error(path):
    dec = ps.decompose(ps.shapes.bumpy_sphere(3000), 3)
    with pytest.raises(ValueError, match="save needs the path of a file"):
        dec.save(path)


def test_estimate_normals_counts_the_points_it_has_no_normal_for():
    p = ps.shapes.bumpy_sphere(3000)
    normals, said = _caught(lambda: ps.estimate_normals(np.r_[p, np.full((16, 3), 0.01)]))
    assert not normals[3000:].any() and np.allclose(np.linalg.norm(normals[:3000], axis=1), 1.0)
    assert any(m.startswith("16 of 3016 points have no normal") and "point 3000" in m for m in said), said
    _, said = _caught(lambda: ps.estimate_normals(p))
    assert not said


def test_project_counts_the_points_it_leaves_where_they_are():
    p = ps.shapes.bumpy_sphere(3000)
    (pos, nrm), said = _caught(lambda: ps.project(np.array([[100.0, 0, 0], [1.0, 0, 0]]), p))
    assert (pos[0] == [100.0, 0, 0]).all() and not nrm[0].any() and np.linalg.norm(nrm[1]) == pytest.approx(1.0)
    assert any(m.startswith("project: 1 of 2 points were left where they are") for m in said), said
    (_, _, report), said = _caught(lambda: ps.project(np.array([[100.0, 0, 0]]), p, return_report=True))
    assert report["degenerate"] == 1 and not said


def test_reconstruct_from_a_folder_without_its_source_says_what_is_missing(tmp_path):
    p = ps.shapes.bumpy_sphere(3000)
    ps.io.write(tmp_path / "in.ply", ps.io.Scan(points=p, vertex_attributes={"quality": np.arange(3000.0)}))
    assert run_cli("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "dec"), "--levels", "3").returncode == 0
    (tmp_path / "dec" / "source.npz").unlink()
    done = run_cli("reconstruct", str(tmp_path / "dec"), "-o", str(tmp_path / "out.ply"))
    assert done.returncode == 0, done.stderr
    assert "the result has points and normals only: " in done.stderr and "source.npz, which" in done.stderr, done.stderr
    done = run_cli("reconstruct", str(tmp_path / "dec" / "decomposition.npz"), "-o", str(tmp_path / "out2.ply"))
    assert done.returncode == 0 and "missing" not in done.stderr, done.stderr


def test_a_mirror_with_seam_zero_keeps_off_plane_points_off_the_plane():
    """seam=0 (only points exactly on the plane are seam points): an off-plane point a gain pulls
    across the plane was put exactly on it (4 of 6,241 at gains -2), where Blender merges it."""
    from pointscale import meshes
    v, _ = meshes.uv_sphere(1.0, 160, 80)
    v = meshes.bumpy(v, 0.05, 5.0)
    v[np.abs(v[:, 0]) < 1e-12, 0] = 0.0
    half = v[v[:, 0] >= 0]
    on = half[:, 0] == 0.0
    dec = ps.decompose(half, 4, mirror=ps.Mirror("x", seam=0.0))
    for out in [dec.level(0), ps.reconstruct(dec, gains=[-2, -2, -2]), ps.reconstruct(dec, gains=[3, 3, 3])]:
        assert (out[on, 0] == 0.0).all()
        assert (out[~on, 0] > 0.0).all() and (out[~on, 0].astype(np.float32) > 0).all()


@pytest.mark.parametrize("call", ["decompose", "estimate_normals", "project"])
def test_a_true_or_false_option_refuses_other_values(call):
    p = ps.shapes.bumpy_sphere(3000)
    run = {"decompose": lambda: ps.decompose(p, 3, sheets="yes"),
           "estimate_normals": lambda: ps.estimate_normals(p, orient="no"),
           "project": lambda: ps.project(p, p, single_pass=1)}[call]
    with pytest.raises(ValueError, match="must be True or False"):
        run()


def test_mirror_origin_without_mirror_is_refused_even_at_the_origin(tmp_path):
    from helpers import one_line_error
    p = ps.shapes.bumpy_sphere(3000)
    ps.io.write(tmp_path / "in.ply", ps.io.Scan(points=p))
    done = run_cli("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--mirror", "x",
                   "--mirror-origin", "")
    assert "--mirror-origin must be three comma-separated numbers" in one_line_error(done)
    for origin in ("0,0,0", "1,2,3"):
        line = one_line_error(run_cli("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"),
                                      "--mirror-origin", origin))
        assert "--mirror-origin and --mirror-seam need --mirror" in line


def test_e57_says_when_far_points_cost_the_others_their_precision(tmp_path):
    """E57 (through pye57) keeps single precision about the range's centre: 5e-8 on a unit
    sphere 5e5 from the origin, but one stray point at 1e9 moved every other point by 1.5."""
    pytest.importorskip("pye57")
    p = ps.shapes.bumpy_sphere(2000)
    for points, warned in [(p + [5e5, 0, 0], False), (np.r_[p, [[1e9, 0, 0]]], True)]:
        _, said = _caught(lambda: ps.io.write(tmp_path / "a.e57", ps.io.Scan(points=points)))
        error = np.abs(ps.io.read(tmp_path / "a.e57").points - points).max()
        assert (error > 1e-3) == warned, error
        assert any("single precision" in m for m in said) == warned, said


def test_writing_to_a_symlink_writes_its_target(tmp_path):
    """A replaced link left the target as it was and the link a plain file."""
    p = ps.shapes.bumpy_sphere(500)
    (tmp_path / "data").mkdir()
    target = tmp_path / "data" / "scan.ply"
    ps.io.write(target, ps.io.Scan(points=p))
    link = tmp_path / "latest.ply"
    link.symlink_to(target)
    ps.io.write(link, ps.io.Scan(points=p + 1.0))
    assert link.is_symlink()
    assert np.array_equal(ps.io.read(target).points, p + 1.0)
    assert not [f for f in (tmp_path / "data").iterdir() if f.name != "scan.ply"]


def test_an_option_error_is_one_line_too(tmp_path):
    """argparse printed its 11-line usage block before the error."""
    from helpers import one_line_error
    line = one_line_error(run_cli("decompose", str(tmp_path / "scan.laz")))
    assert "the following arguments are required: -o/--output" in line and "--help" in line
    assert "invalid choice: 'bogus'" in one_line_error(run_cli("bogus"))


def test_a_negative_mirror_origin_is_a_value(tmp_path):
    """'--mirror-origin -0.03,0,0' read the value as an option (the bunny's centre has x = -0.027)."""
    p = ps.shapes.bumpy_sphere(4000)
    half = p[p[:, 0] >= -0.03]
    ps.io.write(tmp_path / "half.ply", ps.io.Scan(points=half))
    done = run_cli("decompose", str(tmp_path / "half.ply"), "-o", str(tmp_path / "out"), "--levels", "3",
                   "--mirror", "x", "--mirror-origin", "-0.03,0,0")
    assert done.returncode == 0, done.stderr
    assert ps.load(tmp_path / "out" / "decomposition.npz").settings["mirror"]["origin"][0] == -0.03
