"""A fourth reader's findings in the package and the command line: each test failed before its fix."""
import subprocess
import sys

import numpy as np
import pytest

import pointscale as ps
from pointscale import io
from pointscale.multiscale import _missed_rays_of_parts


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "pointscale", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True)


@pytest.fixture(scope="module")
def sphere():
    points = ps.shapes.bumpy_sphere(6000, noise=0.0)
    return points, points / np.linalg.norm(points, axis=1)[:, None]


@pytest.mark.parametrize("zero_share", [1.0, 0.1, 1 / 6000])
def test_zero_normals_are_refused_everywhere_they_orient(sphere, zero_share):
    """A zero normal faces neither way: orientation took the sign of a dot product with it, and
    about half of those points came out turned inward, silently."""
    points, outward = sphere
    normals = outward.copy()
    zero = np.random.default_rng(0).random(len(points)) < zero_share
    zero[-1] = True
    normals[zero] = 0.0
    first = int(np.flatnonzero(zero)[0])
    message = f"normals: {zero.sum()} of them are zero \\(the first at point {first}\\)"
    with pytest.raises(ValueError, match=message):
        ps.decompose(points, 3, normals=normals)
    n = len(points)  # two parts, decomposed apart
    with pytest.raises(ValueError, match="normals: .* of them are zero"):
        ps.decompose(np.vstack([points, points + [4.0, 0.0, 0.0]]), 3, normals=np.vstack([normals, normals]),
                     edges=np.array([[0, 1], [n, n + 1]]))
    base = ps.ellipsoid_base(points, n=len(points))
    for call in (lambda: ps.morph(points, points * 1.05, base, base_normals=normals),
                 lambda: ps.encode(points, base, base_normals=normals)):
        with pytest.raises(ValueError, match="base_normals: .* of them are zero"):
            call()
    with pytest.raises(ValueError, match="onto_normals: .* of them are zero"):
        ps.project_sheets(points[:100], points, onto_normals=normals)


def test_normals_that_are_tiny_but_not_zero_still_orient(sphere):
    points, outward = sphere
    dec = ps.decompose(points, 3, normals=outward * 1e-100)
    assert (np.einsum("ij,ij->i", dec.normals(0), outward) > 0).all()


def test_the_command_line_estimates_normals_a_file_holds_as_zeros(tmp_path, sphere):
    points, outward = sphere
    io.write(tmp_path / "zeros.ply", io.Scan(points=points, normals=np.zeros_like(points)))
    r = _cli("decompose", "zeros.ply", "-o", "out", "--levels", "3", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "every normal in the file is zero; decomposing with estimated normals" in r.stderr
    level0 = io.read(tmp_path / "out" / "level_0.ply")
    assert (np.einsum("ij,ij->i", level0.normals, outward) > 0).mean() > 0.999

    partly = outward.copy()
    partly[::7] = 0.0
    io.write(tmp_path / "partly.ply", io.Scan(points=points, normals=partly))
    r = _cli("decompose", "partly.ply", "-o", "out2", "--levels", "3", cwd=tmp_path)
    assert r.returncode != 0
    assert "partly.ply: normals: 858 of them are zero" in r.stderr and "--estimate-normals" in r.stderr
    r = _cli("decompose", "partly.ply", "-o", "out2", "--levels", "3", "--estimate-normals", cwd=tmp_path)
    assert r.returncode == 0, r.stderr


def _two_spheres():
    a = ps.shapes.bumpy_sphere(3000, noise=0.0)
    return np.vstack([a, a + [4.0, 0.0, 0.0]])


def test_parts_record_the_diffusion_settings_as_one_part_does():
    points = _two_spheres()
    edges = np.array([[0, 1], [3000, 3001]])
    options = dict(smoother="diffusion", diffusion_iterations=7, lam=0.3)
    alone = ps.decompose(points[:3000], 3, **options)
    parts = ps.decompose(points, 3, edges=edges, **options)
    assert len(parts.settings["parts"]) == 2
    assert parts.settings["diffusion"] == alone.settings["diffusion"]
    assert parts.settings["diffusion"]["iterations"] == 7 and parts.settings["diffusion"]["lam"] == 0.3


def test_parts_record_the_rays_that_missed():
    points = _two_spheres()
    parts = ps.decompose(points, 3, edges=np.array([[0, 1], [3000, 3001]]), encoding="rayshoot")
    alone = [ps.decompose(points[:3000], 3, encoding="rayshoot"), ps.decompose(points[3000:], 3, encoding="rayshoot")]
    assert parts.settings["rays_missed"] == [sum(d.settings["rays_missed"][b] for d in alone) for b in range(2)]
    assert [len(m) for m in ps.rays_missed_points(parts)] == parts.settings["rays_missed"]


class _Part:
    def __init__(self, missed):
        self._missed = missed
        self.n_bands = len(missed)


def test_missed_rays_of_parts_are_numbered_in_the_whole_and_aligned_to_its_finest_bands(monkeypatch):
    """A part with fewer bands has them at the whole's finest (pointscale.parts)."""
    monkeypatch.setattr("pointscale.multiscale.rays_missed_points", lambda part: part._missed)
    parts = [(np.array([10, 11, 12]), _Part([np.array([0]), np.array([2])]), None),
             (np.array([3, 4, 5, 6]), _Part([np.array([1, 3]), np.array([], int), np.array([0])]), None),
             (np.array([7]), None, "too small")]
    missed = _missed_rays_of_parts(parts, 3)
    assert [m.tolist() for m in missed] == [[4, 6], [10], [3, 12]]


def test_a_las_attribute_named_like_a_coordinate_is_a_clear_error(tmp_path):
    points = np.random.default_rng(0).random((100, 3))
    for name in ("x", "y", "Z"):
        with pytest.raises(ValueError, match=f"vertex attribute '{name}' clashes with the coordinates"):
            io.write(tmp_path / "clash.las", io.Scan(points=points, vertex_attributes={name: np.ones(100)}))
        assert not (tmp_path / "clash.las").exists()


def test_complex_gains_are_refused_rather_than_cut_to_their_real_part():
    dec = ps.decompose(ps.shapes.bumpy_sphere(3000, noise=0.0), 3)
    for gains in ([1 + 2j, 1.0], np.ones((2, dec.n_points), complex)):
        with pytest.raises(ValueError, match="gains must be real numbers"):
            ps.reconstruct(dec, gains)
        with pytest.raises(ValueError, match="gains must be real numbers"):
            ps.Reconstructor(dec).reconstruct(gains)


def test_a_mirrored_decomposition_takes_per_band_gains_of_shape_k_by_1_as_any_other():
    points = ps.shapes.bumpy_sphere(3000, noise=0.0)
    for dec in (ps.decompose(points, 3), ps.decompose(points[points[:, 0] >= 0], 3, mirror="x")):
        np.testing.assert_array_equal(ps.reconstruct(dec, np.array([[1.0], [2.0]])), ps.reconstruct(dec, [1.0, 2.0]))


def test_morph_names_its_base_samples_option():
    a = ps.shapes.bumpy_sphere(3000, noise=0.0)
    with pytest.raises(ValueError, match="base_samples must be >= 8, got 0"):
        ps.morph(a, a * 1.02, base_samples=0)


def test_the_gain_limit_names_the_gain_as_given():
    """It said 'got 1e+06' of 1000000.5, which reads as within the limit."""
    dec = ps.decompose(ps.shapes.bumpy_sphere(3000, noise=0.0), 3)
    with pytest.raises(ValueError, match=r"gains must be within \+-1e\+06, got 1000000.5$"):
        ps.reconstruct(dec, [1000000.5, 1.0])


def test_demo_replaces_an_earlier_demo_but_not_a_file_of_its_names_it_did_not_write(tmp_path):
    assert _cli("demo", "-o", "d", "--points", "2000", cwd=tmp_path).returncode == 0
    r = _cli("demo", "-o", "d", "--points", "2000", cwd=tmp_path)  # the main job, run again
    assert r.returncode == 0, r.stderr
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "level_0.ply").write_bytes(b"my scan")
    r = _cli("demo", "-o", "mine", "--points", "2000", cwd=tmp_path)
    assert r.returncode != 0 and "already holds level_0.ply, a name the demo writes" in r.stderr and "--force" in r.stderr
    assert (tmp_path / "mine" / "level_0.ply").read_bytes() == b"my scan"
    assert _cli("demo", "-o", "mine", "--points", "2000", "--force", cwd=tmp_path).returncode == 0


def test_demo_writes_all_of_its_files_or_none(tmp_path, monkeypatch):
    """An interrupted demo left some of its files, and a second run then refused the folder."""
    import pointscale.cli.commands as commands
    from pointscale.cli import main

    calls = []

    def failing_write(path, points):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(path, points)
    real = commands.io.write_ply
    monkeypatch.setattr(commands.io, "write_ply", failing_write)
    assert main(["demo", "-o", str(tmp_path / "d"), "--points", "2000"]) == 130  # "interrupted"
    assert not (tmp_path / "d").exists()  # nothing of it: not its files, not the folder it made
    monkeypatch.undo()
    assert _cli("demo", "-o", "d", "--points", "2000", cwd=tmp_path).returncode == 0
    assert sorted(p.name for p in (tmp_path / "d").iterdir()) == sorted(commands.DEMO_FILES)


def test_a_folder_or_a_file_of_another_kind_is_named_for_what_it_is(tmp_path):
    (tmp_path / "result.ply").mkdir()
    with pytest.raises(ValueError, match="result.ply is a folder, not a file"):
        io.read(tmp_path / "result.ply")
    io.write(tmp_path / "scan.ply", io.Scan(points=ps.shapes.bumpy_sphere(2000, noise=0.0)))
    with pytest.raises(ValueError, match="scan.ply: it is not a decomposition file"):
        ps.load(tmp_path / "scan.ply")  # np.load said 'Cannot load file containing pickled data'
    r = _cli("info", "scan.ply", cwd=tmp_path)
    assert r.returncode != 0 and "not a decomposition file" in r.stderr and "pickle" not in r.stderr
    r = _cli("decompose", "scan.ply", "-o", "out", "--format", ".png", cwd=tmp_path)
    assert r.returncode != 0 and "--format .png: unknown extension '.png'" in r.stderr


def test_the_command_line_speaks_of_its_own_options(tmp_path):
    io.write(tmp_path / "s.ply", io.Scan(points=ps.shapes.bumpy_sphere(4000, noise=0.0)))
    r = _cli("decompose", "s.ply", "-o", "o", "--levels", "3", "--sheets", "--encoding", "rayshoot", cwd=tmp_path)
    assert r.returncode != 0 and "--sheets keeps thin sheets apart" in r.stderr and "--encoding rayshoot" in r.stderr
    assert "sheets=True" not in r.stderr and "encoding=" not in r.stderr
