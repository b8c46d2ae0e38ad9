"""A third reader's findings on the command line and the engine: each test failed before its fix."""
import subprocess
import sys

import numpy as np
import pytest

import pointscale as ps
from pointscale import io


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "pointscale", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True)


def test_decompose_refuses_an_input_it_would_overwrite_or_remove(tmp_path):
    io.write(tmp_path / "scan.ply", io.Scan(points=ps.shapes.bumpy_sphere(3000, noise=0.0)))
    assert _cli("decompose", "scan.ply", "-o", "out", "--levels", "3", cwd=tmp_path).returncode == 0
    (tmp_path / "out" / "level_9.ply").write_bytes((tmp_path / "scan.ply").read_bytes())
    for name in ("level_0.ply", "level_9.ply"):  # rewritten, and removed as stale
        before = (tmp_path / "out" / name).read_bytes()
        r = _cli("decompose", f"out/{name}", "-o", "out", "--force", "--levels", "3", cwd=tmp_path)
        assert r.returncode != 0 and "would be lost" in r.stderr
        assert (tmp_path / "out" / name).read_bytes() == before


def test_demo_names_its_points_option(tmp_path):
    for value in ("-5", "0", "100000000000"):
        r = _cli("demo", "--points", value, "-o", "d", cwd=tmp_path)
        assert r.returncode == 2 and "argument --points: must be from 1000 to 10000000" in r.stderr
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize("b", [lambda a: a[:1], lambda a: a[:3], lambda a: np.tile(a[:1], (500, 1)),
                               lambda a: np.outer(np.linspace(-1, 1, 500), [1.0, 0.5, 0.2])])
def test_morph_refuses_a_model_with_no_surface(b):
    a = ps.shapes.bumpy_sphere(3000, noise=0.0)
    with pytest.raises(ValueError, match="points_b (has fewer than|is empty|.*identical|are collinear)|points_b"):
        ps.morph(a, b(a))


@pytest.mark.parametrize("k", [4, 6, 11])  # 3 neighbours fit a plane to a triangle: PCA alone fails there
def test_oriented_normals_with_few_neighbours_point_outward(k):
    p = ps.shapes.sphere(4000)
    n = ps.estimate_normals(p, neighbors=k)
    outward = np.einsum("ij,ij->i", n, p / np.linalg.norm(p, axis=1, keepdims=True))
    assert (outward > 0.9).mean() > 0.99


def test_far_apart_parts_are_not_called_a_line():
    p = ps.shapes.sphere(2000)
    with pytest.raises(ValueError, match="parts far apart"):
        ps.decompose(np.vstack([p, p + [3e6, 0, 0]]), levels=2)


def test_save_refuses_a_folder_or_a_missing_one_and_leaves_nothing(tmp_path):
    dec = ps.decompose(ps.shapes.bumpy_sphere(3000), levels=2)
    (tmp_path / "existing").mkdir()
    with pytest.raises(ValueError, match="it is a folder"):
        dec.save(tmp_path / "existing")
    with pytest.raises(ValueError, match="does not exist"):
        dec.save(tmp_path / "nope" / "x.npz")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["existing"]
    dec.save(tmp_path / "model")  # no extension: saved under that name, loadable
    np.testing.assert_array_equal(ps.load(tmp_path / "model").base, dec.base)


@pytest.mark.parametrize("face, named", [("f 0 1 2", "vertex 0,"), ("f -1 -2 -9", "vertex -9,")])
def test_obj_face_errors_name_the_index_as_written(tmp_path, face, named):
    (tmp_path / "a.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n" + face + "\n")
    with pytest.raises(ValueError, match=f"a face refers to {named} outside 1..4"):
        io.read(tmp_path / "a.obj")
