"""The command line and PLY input/output."""
import subprocess
import sys

import numpy as np
import pytest

import pointscale as ps
from helpers import diagonal, shared_model
from pointscale.io import read_ply, write_ply


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "pointscale", *args], capture_output=True, text=True, cwd=cwd)


def test_ply_round_trip_keeps_points_normals_and_faces(tmp_path):
    points = ps.shapes.sphere(500)
    faces = [[0, 1, 2], [2, 3, 4]]
    write_ply(tmp_path / "a.ply", points, normals=points, faces=faces, scalars={"detail": points[:, 0]})
    back = read_ply(tmp_path / "a.ply")
    assert np.allclose(back.points, points, atol=1e-6) and np.allclose(back.normals, points, atol=1e-6)
    assert [list(f) for f in back.faces] == faces


def test_decompose_then_reconstruct_from_the_command_line(tmp_path):
    points = ps.shapes.bumpy_sphere(6000)
    write_ply(tmp_path / "in.ply", points)
    done = run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    assert "2 detail bands" in done.stdout
    for name in ("decomposition.npz", "level_0.ply", "level_1.ply", "level_2.ply"):
        assert (tmp_path / "out" / name).exists()
    done = run("reconstruct", str(tmp_path / "out"), "--gains", "1,1", "-o", str(tmp_path / "same.ply"))
    assert done.returncode == 0, done.stderr
    same = read_ply(tmp_path / "same.ply").points
    assert np.abs(same - points).max() < 1e-5 * diagonal(points)  # float32 file precision
    done = run("reconstruct", str(tmp_path / "out"), "--gains", "1,0", "-o", str(tmp_path / "smooth.ply"))
    smooth = read_ply(tmp_path / "smooth.ply").points
    assert np.abs(smooth - points).max() > 1e-3


def test_command_line_errors_are_reported_not_raised(tmp_path):
    done = run("decompose", str(tmp_path / "missing.ply"), "-o", str(tmp_path / "o"))
    assert done.returncode == 2 and "no such file" in done.stderr and "Traceback" not in done.stderr
    points = ps.shapes.bumpy_sphere(3000)
    write_ply(tmp_path / "in.ply", points)
    run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3")
    done = run("reconstruct", str(tmp_path / "out"), "--gains", "1,2,3", "-o", str(tmp_path / "x.ply"))
    assert done.returncode == 2 and "needs 2 values" in done.stderr


def test_demo_runs_and_writes_its_files(tmp_path):
    done = run("demo", "-o", str(tmp_path / "demo"), "--points", "20000")
    assert done.returncode == 0, done.stderr
    assert "exact reconstruction" in done.stdout
    assert (tmp_path / "demo" / "handles_multiscale.ply").exists()


def test_scanned_bunny_round_trips():
    model = read_ply(shared_model("bunny.ply"))
    dec = ps.decompose(model.points, levels=4)
    assert np.abs(ps.reconstruct(dec) - model.points).max() <= 1e-6 * diagonal(model.points)
