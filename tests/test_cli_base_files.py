"""What a scan technician's --base and -o can get wrong on the command line, and what a batch
scheduler's stop does (found by a trial on georeferenced LAS and float32 PLY files).

- A level 0 read back from a file that rounds coordinates (LAS's scaled integers, float32) was
  taken as an edit wherever the file rounded it: an unedited LAS level 0 given back moved a tenth
  of a 60k scan by up to 3.7 mm, and a local edit moved points metres from it.
- A level file other than level 0 given as --base added its detail again (points 1 m off).
- reconstruct -o could overwrite the decomposition's own level files, --force or not.
- SIGTERM and SIGHUP (`timeout`, a scheduler's time limit, a closed terminal) ended decompose at
  once and left its hidden .part files in the folder.
"""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import pointscale as ps
from helpers import one_line_error, run_cli as run
from pointscale import io
from pointscale.io import write_ply


def georeferenced(n: int = 12000, seed: int = 4) -> np.ndarray:
    """A bumpy ellipsoid 30 m long, in metres, half a million metres from the origin (UTM-like)."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    r = 1.0 + 0.04 * np.sin(7 * d[:, 0]) * np.cos(5 * d[:, 1])
    return d * r[:, None] * np.array([15.0, 9.0, 6.0]) + np.array([500123.0, 5000789.0, 250.0])


def write_las(path: Path, points: np.ndarray, scale: float = 0.001) -> np.ndarray:
    """points in a LAS 1.4 file at `scale` (a survey's millimetres); returns them as stored."""
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales = np.full(3, scale)
    header.offsets = np.floor(points.min(axis=0))
    las = laspy.LasData(header)
    las.x, las.y, las.z = points[:, 0], points[:, 1], points[:, 2]
    las.write(str(path))
    return io.read(path).points


def decomposed(tmp_path: Path, name: str, points: np.ndarray, writer) -> tuple[Path, np.ndarray, str]:
    """(folder, the input as stored, level files' extension) of `points` written by `writer` and decomposed."""
    source = tmp_path / name
    writer(source, points)
    done = run("decompose", str(source), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    return tmp_path / "out", io.read(source).points, source.suffix


def write_float32_ply(path: Path, points: np.ndarray) -> None:
    """A float32 PLY, as MeshLab and CloudCompare write them (near the origin: float32 holds it)."""
    write_ply(path, points.astype(np.float32))


INPUTS = {  # a file that rounds coordinates, with its writer
    "LAS at 1 mm, georeferenced": ("in.las", lambda p, x: write_las(p, x), georeferenced),
    "float32 PLY": ("in.ply", write_float32_ply, lambda: georeferenced() - np.array([500123.0, 5000789.0, 250.0])),
}


@pytest.mark.parametrize("kind", list(INPUTS))
def test_an_unedited_level_0_given_back_returns_the_input_exactly(tmp_path, kind):
    name, writer, shape = INPUTS[kind]
    folder, stored_input, extension = decomposed(tmp_path, name, shape(), writer)
    done = run("reconstruct", str(folder), "--base", str(folder / f"level_0{extension}"), "-o",
               str(tmp_path / f"result{extension}"))
    assert done.returncode == 0, done.stderr
    assert np.array_equal(io.read(tmp_path / f"result{extension}").points, stored_input)


@pytest.mark.parametrize("kind", list(INPUTS))
def test_a_local_edit_through_a_rounding_file_leaves_the_rest_as_it_was(tmp_path, kind):
    """A lift of the points within 2 m of one end: every point farther than 6 m from it comes
    back exactly as the input (before: thousands of them moved by up to a few mm)."""
    name, writer, shape = INPUTS[kind]
    folder, stored_input, extension = decomposed(tmp_path, name, shape(), writer)
    level0 = io.read(folder / f"level_0{extension}")
    points = level0.points.copy()
    end = points[np.argmax(points[:, 0])]
    near = np.linalg.norm(points - end, axis=1) < 2.0
    points[near, 2] += 0.3
    io.write(tmp_path / f"edited{extension}", level0.with_geometry(points, level0.normals))
    done = run("reconstruct", str(folder), "--base", str(tmp_path / f"edited{extension}"), "-o",
               str(tmp_path / f"result{extension}"))
    assert done.returncode == 0, done.stderr
    result = io.read(tmp_path / f"result{extension}").points
    far = np.linalg.norm(stored_input - end, axis=1) > 6.0
    assert near.sum() > 50 and far.sum() > 0.5 * len(far)
    assert np.array_equal(result[far], stored_input[far])
    assert np.abs(result[near] - stored_input[near]).max() > 0.1  # the edit itself is there


def test_another_level_given_as_base_is_refused(tmp_path):
    folder, _, _ = decomposed(tmp_path, "in.ply", georeferenced(8000) - 5e5, write_ply)
    for level in (1, 2):
        msg = one_line_error(run("reconstruct", str(folder), "--base", str(folder / f"level_{level}.ply"), "-o",
                                 str(tmp_path / "r.ply")))
        assert f"lies where level {level}" in msg and "level_0" in msg and "another decomposition" in msg
        assert not (tmp_path / "r.ply").exists()
    # Level 0 itself, and level 0 edited everywhere (moved off every level), are taken.
    level0 = io.read(folder / "level_0.ply")
    io.write(tmp_path / "moved.ply", level0.with_geometry(level0.points * 1.01, None))
    for base in (folder / "level_0.ply", tmp_path / "moved.ply"):
        done = run("reconstruct", str(folder), "--base", str(base), "-o", str(tmp_path / "r.ply"), "--force")
        assert done.returncode == 0, done.stderr


def test_the_decompositions_own_files_and_the_base_are_not_overwritten(tmp_path):
    folder, _, _ = decomposed(tmp_path, "in.ply", georeferenced(6000) - 5e5, write_ply)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    edited = tmp_path / "edited.ply"
    edited.write_bytes((folder / "level_0.ply").read_bytes())
    for out, base in ((folder / "level_0.ply", folder / "level_0.ply"), (folder / "level_2.ply", None),
                      (folder / "level_9.ply", None), (folder / "level_1.ply", edited), (edited, edited)):
        extra = ["--base", str(base)] if base else []
        # The decomposition given as its folder, or as its decomposition.npz (a reviewer found
        # the second one overwrote level_0.ply).
        for given in (folder, folder / "decomposition.npz"):
            msg = one_line_error(run("reconstruct", str(given), "-o", str(out), "--force", *extra))
            assert "decomposition's own files" in msg or "--base file" in msg, msg
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    assert edited.read_bytes() == before["level_0.ply"]


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads a process's CPU time from /proc")
@pytest.mark.parametrize("name", ["SIGTERM", "SIGHUP"])
def test_a_stop_signal_ends_decompose_cleanly(tmp_path, name):
    """As Ctrl-C does: exit 128 + the signal's number, one line, no file left in the folder."""
    write_ply(tmp_path / "in.ply", ps.shapes.bumpy_sphere(600000, noise=0.001, seed=9))
    proc = subprocess.Popen([sys.executable, "-m", "pointscale", "decompose", str(tmp_path / "in.ply"), "-o",
                             str(tmp_path / "out"), "--levels", "4"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    for _ in range(600):  # until it is computing (the imports and the read take less than a second)
        if cpu_seconds(proc.pid) > 1.0:
            break
        time.sleep(0.02)
    assert proc.poll() is None, "decompose ended before the signal"
    signum = getattr(signal, name)
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signum, (proc.returncode, err)
    assert len(err.strip().splitlines()) == 1 and name in err, err
    assert not (tmp_path / "out").exists() or list((tmp_path / "out").iterdir()) == []


@pytest.mark.parametrize("resave", ["offsets moved 0.4 mm", "scale 0.1 mm", "scale 0.5 mm"])
def test_a_las_level_0_resaved_by_another_tool_returns_the_input_exactly(tmp_path, resave):
    """Another tool re-saving level_0.las with its own offsets or scale rounds it a second time:
    taken with the base file's rounding alone, up to 9342 of 12000 points moved by up to 1 mm
    (a reviewer's script)."""
    laspy = pytest.importorskip("laspy")
    folder, stored_input, _ = decomposed(tmp_path, "in.las", georeferenced(), lambda p, x: write_las(p, x))
    level0 = laspy.read(str(folder / "level_0.las"))
    points = np.column_stack([level0.x, level0.y, level0.z])
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales = np.full(3, {"scale 0.1 mm": 1e-4, "scale 0.5 mm": 5e-4}.get(resave, 1e-3))
    header.offsets = level0.header.offsets + (4e-4 if resave == "offsets moved 0.4 mm" else 0.0)
    las = laspy.LasData(header)
    las.x, las.y, las.z = points[:, 0], points[:, 1], points[:, 2]
    las.write(str(tmp_path / "resaved.las"))
    done = run("reconstruct", str(folder), "--base", str(tmp_path / "resaved.las"), "-o", str(tmp_path / "r.las"))
    assert done.returncode == 0, done.stderr
    assert np.array_equal(io.read(tmp_path / "r.las").points, stored_input)


def test_a_stop_while_the_files_are_put_in_place_waits_and_says_they_were_written(tmp_path, monkeypatch, capsys):
    """SIGTERM after the renames of a decompose --force over an earlier run (simulated: sent as
    the earlier files' second names are removed). Held only in the main thread, it reached the
    command in the middle, left those second names behind and said no files were written."""
    from pointscale import cli
    from pointscale.cli import staged_output
    write_ply(tmp_path / "in.ply", ps.shapes.bumpy_sphere(8000, seed=1))
    out = tmp_path / "out"
    assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(out), "--levels", "3"]) == 0
    real_suppress, sent = staged_output.contextlib.suppress, []

    def suppress(*exceptions):
        if not sent:
            sent.append(1)
            os.kill(os.getpid(), signal.SIGTERM)
        return real_suppress(*exceptions)
    monkeypatch.setattr(staged_output.contextlib, "suppress", suppress)
    capsys.readouterr()
    assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(out), "--levels", "3", "--force"]) == 143
    assert sent and "files were written" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["decomposition.npz", "level_0.ply", "level_1.ply", "level_2.ply",
                                                     "source.npz"]


def test_a_second_stop_signal_does_not_cut_the_cleanup_short(tmp_path, monkeypatch, capsys):
    """A closed terminal sends SIGHUP twice. The second, arriving as the temporary files were
    being removed, left them in the folder (simulated as in a reviewer's script)."""
    from pointscale import cli
    from pointscale.cli import commands, staged_output
    write_ply(tmp_path / "in.ply", ps.shapes.bumpy_sphere(8000, seed=1))
    real_write, real_discard, sent = io.write, staged_output.StagedOutput.discard, []

    def write(path, *args, **kwargs):
        result = real_write(path, *args, **kwargs)
        if ".part" in str(path) and not sent:
            sent.append(1)
            os.kill(os.getpid(), signal.SIGHUP)  # the first: while the levels are written
        return result

    def discard(self):
        os.kill(os.getpid(), signal.SIGHUP)  # the second: as the cleanup starts
        sum(range(1000))  # Python runs the handler at its next instructions
        return real_discard(self)
    monkeypatch.setattr(commands.io, "write", write)
    monkeypatch.setattr(staged_output.StagedOutput, "discard", discard)
    assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3"]) == 129
    assert sent and "no files were written" in capsys.readouterr().err
    assert not (tmp_path / "out").exists() or list((tmp_path / "out").iterdir()) == []
    assert signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN  # the handlers before are back


def test_an_unedited_e57_level_0_given_back_is_the_stored_base(tmp_path):
    """E57 holds float32 coordinates in each scan's own frame: an unedited level_0.e57 of a
    georeferenced scan moved every point by its rounding (5e-7 m) before (a reviewer's script).
    Now the result equals the one from the stored base, bit for bit."""
    pytest.importorskip("pye57")
    folder, _, _ = decomposed(tmp_path, "in.e57", georeferenced(), lambda p, x: io.write(p, io.Scan(points=x)))
    for name, extra in (("given.ply", ["--base", str(folder / "level_0.e57")]), ("stored.ply", [])):
        done = run("reconstruct", str(folder), *extra, "-o", str(tmp_path / name))
        assert done.returncode == 0, done.stderr
    assert np.array_equal(io.read(tmp_path / "given.ply").points, io.read(tmp_path / "stored.ply").points)
