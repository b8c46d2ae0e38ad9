"""reconstruct --base from a text file written with fixed decimals (las2txt, CloudCompare's ASCII
export, a scanner's software): its unedited vertices are the stored level 0 as that file rounds
it, and come back at full precision, as a LAS file's do. Before, every vertex kept the file's
rounding, and the result moved by 3 to 6 times it (0.029 m at 2 decimals on a georeferenced scan)
without a word."""
import numpy as np
import pytest

import pointscale as ps
from pointscale import io
from helpers import run_cli


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("text_base")
    points = ps.shapes.bumpy_sphere(6000, noise=0.001, seed=4) * 12.0 + np.array([652000.0, 5180000.0, 240.0])
    io.write(root / "scan.ply", io.Scan(points=points))
    done = run_cli("decompose", "scan.ply", "-o", "out", "--levels", "3", cwd=root)
    assert done.returncode == 0, done.stderr
    done = run_cli("reconstruct", "out", "-o", "unedited.ply", cwd=root)
    assert done.returncode == 0, done.stderr
    return root, points, io.read(root / "out" / "level_0.ply").points, io.read(root / "unedited.ply").points


def save_text(path, points, decimals):
    if path.suffix == ".pts":
        path.write_text(f"{len(points)}\n" + "".join(" ".join(f"{v:.{decimals}f}" for v in p) + "\n" for p in points))
    else:
        np.savetxt(path, points, fmt=f"%.{decimals}f")


@pytest.mark.parametrize("name,decimals", [("base.xyz", 2), ("base.xyz", 5), ("base.txt", 3), ("base.pts", 4)])
def test_an_unedited_level_0_saved_with_fixed_decimals_comes_back_exactly(folder, name, decimals):
    root, _, level0, unedited = folder
    save_text(root / name, level0, decimals)
    done = run_cli("reconstruct", "out", "--base", name, "-o", "result.ply", "--force", cwd=root)
    assert done.returncode == 0, done.stderr
    assert np.array_equal(io.read(root / "result.ply").points, unedited)


def test_an_edit_saved_with_fixed_decimals_moves_only_what_it_edits(folder):
    root, _, level0, unedited = folder
    edited = level0.copy()
    lifted = np.linalg.norm(level0 - level0[0], axis=1) < 3.0
    edited[lifted, 2] += 0.5 * (1.0 - np.linalg.norm(level0[lifted] - level0[0], axis=1) / 3.0)
    save_text(root / "edited.xyz", edited, 3)
    done = run_cli("reconstruct", "out", "--base", "edited.xyz", "-o", "result.ply", "--force", cwd=root)
    assert done.returncode == 0, done.stderr
    result = io.read(root / "result.ply").points
    far = np.linalg.norm(level0 - level0[0], axis=1) > 8.0  # beyond the edit's reach through the levels
    assert far.sum() > 1000
    # where they were, to the rounding of coordinates this far from the origin: measured one unit
    # in the last place of 5.18e6, 9.3e-10 (the edited pass works on the base less the model's
    # centre); before, the file's rounding and more: 5.7e-4
    assert np.abs(result[far] - unedited[far]).max() <= 2.0 * np.spacing(np.abs(unedited).max())
    assert np.abs(result[lifted] - unedited[lifted]).max() > 0.1
