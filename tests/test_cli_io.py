"""The command line: precision, attributes, formats, safe folders, clear errors, Ctrl-C."""
import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

import pointscale as ps
from helpers import diagonal, one_line_error, run_cli as run, shared_model
from pointscale import cli, io
from pointscale.io import read_ply, write_ply


def ellipsoid_with_bumps(n: int, axes=(1.3, 0.8, 0.6), seed: int = 3) -> np.ndarray:
    """A shape of this file's own: a bumpy ellipsoid, not the sphere other tests use."""
    p = ps.shapes.bumpy_sphere(n, coarse=0.05, fine=0.01, fine_frequency=19.0, noise=0.001, seed=seed)
    return p * np.asarray(axes)


def plyfile_scan(path: Path, points: np.ndarray, faces=None, dtype="f8") -> dict:
    """Writes a PLY through plyfile with colours, a quality scalar, an id, UVs and face colours;
    returns the attributes written."""
    n = len(points)
    rng = np.random.default_rng(5)
    attrs = {"red": rng.integers(0, 256, n).astype("u1"), "green": rng.integers(0, 256, n).astype("u1"),
             "blue": rng.integers(0, 256, n).astype("u1"), "alpha": rng.integers(0, 256, n).astype("u1"),
             "quality": rng.random(n).astype("f4"), "scan_id": rng.integers(0, 7, n).astype("i4"),
             "s": rng.random(n).astype("f4"), "t": rng.random(n).astype("f4")}
    vertex = np.empty(n, dtype=[("x", dtype), ("y", dtype), ("z", dtype)] + [(k, v.dtype.str) for k, v in attrs.items()])
    for a, name in enumerate("xyz"):
        vertex[name] = points[:, a]
    for k, v in attrs.items():
        vertex[k] = v
    elements = [PlyElement.describe(vertex, "vertex")]
    if faces is not None:
        face = np.empty(len(faces), dtype=[("vertex_indices", "i4", (3,)), ("red", "u1"), ("green", "u1"),
                                           ("blue", "u1")])
        face["vertex_indices"] = faces
        for c in ("red", "green", "blue"):
            face[c] = rng.integers(0, 256, len(faces)).astype("u1")
            attrs["face_" + c] = face[c].copy()
        elements.append(PlyElement.describe(face, "face", len_types={"vertex_indices": "u1"}))
    PlyData(elements).write(str(path))
    return attrs


def test_a_float64_ply_far_from_the_origin_round_trips_through_the_command_line(tmp_path):
    # UTM-like coordinates: float32 would put every point of this 3-unit shape on one value.
    points = ellipsoid_with_bumps(7000) + np.array([6.3e6, 1.2e7, 310.0])
    write_ply(tmp_path / "utm.ply", points)
    done = run("decompose", str(tmp_path / "utm.ply"), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    level = read_ply(tmp_path / "out" / "level_2.ply")
    assert level.precision == np.float64
    assert np.abs(level.points - points).max() < 1e-9 * diagonal(points)
    done = run("reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "same.ply"))
    assert done.returncode == 0, done.stderr
    same = read_ply(tmp_path / "same.ply")
    assert same.precision == np.float64
    assert np.abs(same.points - points).max() < 1e-9 * diagonal(points)


def test_every_attribute_survives_into_every_level_and_result(tmp_path):
    points = ellipsoid_with_bumps(6000, axes=(0.7, 1.0, 1.6), seed=8)
    faces = np.random.default_rng(1).integers(0, len(points), (500, 3))
    attrs = plyfile_scan(tmp_path / "in.ply", points, faces, dtype="f4")
    # Random faces join random vertices into parts too small to decompose at 4 levels (the
    # largest holds 128 points), which is refused with a message that says what to do; they
    # are here to carry attributes.
    refused = run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "4")
    assert "every connected part is too small" in one_line_error(refused) and "--parts none" in refused.stderr
    done = run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3",
               "--parts", "none")
    assert done.returncode == 0, done.stderr
    dec = ps.load(tmp_path / "out" / "decomposition.npz")
    done = run("reconstruct", str(tmp_path / "out"), "--gains", "1,2", "-o", str(tmp_path / "boost.ply"))
    assert done.returncode == 0, done.stderr
    files = [tmp_path / "out" / f"level_{l}.ply" for l in range(3)] + [tmp_path / "boost.ply"]
    for f in files:
        ply = PlyData.read(str(f))
        v = ply["vertex"].data
        assert v["x"].dtype == np.float32  # the input's precision
        for name in ("red", "green", "blue", "alpha", "quality", "scan_id", "s", "t"):
            assert v[name].dtype == attrs[name].dtype and np.array_equal(v[name], attrs[name]), (f.name, name)
        fa = ply["face"].data
        assert np.array_equal(np.stack(fa["vertex_indices"]), faces)
        for c in ("red", "green", "blue"):
            assert np.array_equal(fa[c], attrs["face_" + c]), (f.name, c)
        normals = np.column_stack([v["nx"], v["ny"], v["nz"]]).astype(np.float64)
        assert np.abs(np.linalg.norm(normals, axis=1) - 1).max() < 1e-6
    # Levels carry their own normals, not the input's (it had none) nor each other's.
    for l in range(2):
        v = PlyData.read(str(files[l]))["vertex"].data
        got = np.column_stack([v["nx"], v["ny"], v["nz"]])
        assert np.abs(got - dec.normals(l)).max() < 1e-6
    finest = read_ply(files[2])
    outward = np.einsum("ij,ij->i", finest.normals, finest.points / np.array([0.7, 1.0, 1.6]) ** 2) > 0
    assert outward.mean() > 0.999  # measured: every point


def test_a_trimesh_file_keeps_its_colours(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    mesh = trimesh.creation.icosphere(subdivisions=5, radius=2.0)
    mesh.vertices += 0.02 * np.sin(9 * mesh.vertices)
    colours = np.random.default_rng(2).integers(0, 256, (len(mesh.vertices), 4)).astype(np.uint8)
    mesh.visual.vertex_colors = colours
    mesh.export(tmp_path / "ico.ply")
    done = run("decompose", str(tmp_path / "ico.ply"), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    for l in range(3):
        back = trimesh.load(tmp_path / "out" / f"level_{l}.ply", process=False)
        assert np.array_equal(np.asarray(back.visual.vertex_colors), colours), l
        assert np.array_equal(np.asarray(back.faces), np.asarray(mesh.faces))


def test_the_bunny_scans_keep_their_scan_id(tmp_path):
    path = shared_model("bunny_scans.ply")
    source = PlyData.read(str(path))["vertex"].data["scan_id"]
    done = run("decompose", str(path), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    for l in (0, 2):
        v = PlyData.read(str(tmp_path / "out" / f"level_{l}.ply"))["vertex"].data
        assert v["scan_id"].dtype == source.dtype and np.array_equal(v["scan_id"], source)


def test_formats_are_chosen_by_extension_in_both_directions(tmp_path):
    laspy = pytest.importorskip("laspy")
    points = ellipsoid_with_bumps(6000, axes=(40.0, 25.0, 12.0), seed=4) + np.array([4.5e5, 5.2e6, 100.0])
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.array([450000.0, 5200000.0, 0.0])
    header.uuid = uuid.UUID("0f1e2d3c-4b5a-6978-8796-a5b4c3d2e1f0")  # the survey project's GUID
    las = laspy.LasData(header)
    las.x, las.y, las.z = points[:, 0], points[:, 1], points[:, 2]
    las.intensity = np.arange(len(points), dtype=np.uint16)
    las.classification = np.full(len(points), 2, dtype=np.uint8)
    las.write(tmp_path / "site.las")
    done = run("decompose", str(tmp_path / "site.las"), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    level = laspy.read(tmp_path / "out" / "level_0.las")
    assert np.allclose(level.header.scales, 0.001) and np.allclose(level.header.offsets, header.offsets)
    assert level.header.uuid == header.uuid
    assert np.array_equal(level.intensity, np.arange(len(points))) and (np.asarray(level.classification) == 2).all()
    done = run("reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "same.obj"))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "same.obj").read_text()[:4000].count("\nv ") > 10  # OBJ text, not PLY bytes
    done = run("reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "same.xyz"))
    assert done.returncode == 0, done.stderr
    back = io.read(tmp_path / "same.xyz").points
    las_points = np.column_stack([level.x, level.y, level.z])
    assert back.shape == points.shape and np.abs(back - points).max() < 1e-3  # the LAS grid of 1 mm
    assert las_points.shape == points.shape
    done = run("decompose", str(tmp_path / "site.las"), "-o", str(tmp_path / "as_ply"), "--levels", "3",
               "--format", "ply")
    assert done.returncode == 0, done.stderr
    as_ply = read_ply(tmp_path / "as_ply" / "level_0.ply")
    # The same level 0, unquantised: within half the LAS file's 1 mm grid of what it stored.
    assert np.abs(as_ply.points - np.column_stack([level.x, level.y, level.z])).max() <= 0.0005 + 1e-9
    assert np.array_equal(as_ply.vertex_attributes["intensity"], np.arange(len(points)))
    msg = one_line_error(run("reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "same.dwg")))
    assert ".dwg" in msg and ".ply" in msg and ".laz" in msg


def test_nothing_loads_a_pickle(tmp_path):
    points = ellipsoid_with_bumps(6000)
    write_ply(tmp_path / "in.ply", points)
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3").returncode == 0
    marker = tmp_path / "pwned"

    class Payload:
        def __reduce__(self):
            return (os.system, (f"touch {marker}",))

    bad = np.empty(1, dtype=object)
    bad[0] = Payload()
    np.save(tmp_path / "out" / "faces.npy", bad, allow_pickle=True)
    (tmp_path / "out" / "source.npz").unlink()
    msg = one_line_error(run("info", str(tmp_path / "out")))
    assert "pickle" in msg and not marker.exists()
    np.savez(tmp_path / "out" / "source.npz", meta_json=bad)
    msg = one_line_error(run("reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "r.ply")))
    assert not marker.exists() and "source.npz" in msg


@pytest.mark.parametrize("victim", ["decomposition.npz", "source.npz"])
def test_a_truncated_folder_file_is_one_clear_line(tmp_path, victim):
    write_ply(tmp_path / "in.ply", ellipsoid_with_bumps(6000))
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3").returncode == 0
    f = tmp_path / "out" / victim
    f.write_bytes(f.read_bytes()[: f.stat().st_size // 2])
    msg = one_line_error(run("info", str(tmp_path / "out")))
    assert victim in msg or "decomposition" in msg


def test_faces_out_of_range_are_refused_before_computing(tmp_path):
    points = ellipsoid_with_bumps(6000)
    vertex = np.empty(len(points), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    for a, name in enumerate("xyz"):
        vertex[name] = points[:, a]
    face = np.empty(2, dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = [[0, 1, 2], [5, 6, 6000]]
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(str(tmp_path / "in.ply"))
    msg = one_line_error(run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out")))
    assert "6000" in msg or "range" in msg
    assert not (tmp_path / "out").exists()


def test_bad_outputs_are_refused_before_computing(tmp_path, monkeypatch, capsys):
    write_ply(tmp_path / "in.ply", ellipsoid_with_bumps(6000))
    calls = []
    monkeypatch.setattr(cli.commands, "decompose", lambda *a, **k: calls.append(1))
    (tmp_path / "file").write_text("x")
    locked = tmp_path / "locked"
    locked.mkdir()
    for out in (tmp_path / "file", Path("/proc/pointscale-out")):
        assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(out)]) == 2
    assert calls == []
    err = capsys.readouterr().err
    assert "is a file" in err and "/proc" in err
    # reconstruct: a folder, an existing file without --force, a missing folder
    monkeypatch.undo()
    assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "d"), "--levels", "3"]) == 0
    capsys.readouterr()
    for out in (locked, tmp_path / "file.ply", tmp_path / "nowhere" / "x.ply"):
        (tmp_path / "file.ply").write_text("keep me")
        assert cli.main(["reconstruct", str(tmp_path / "d"), "-o", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 3 and "folder" in err[0] and "--force" in err[1] and "does not exist" in err[2]
    assert (tmp_path / "file.ply").read_text() == "keep me"
    assert cli.main(["reconstruct", str(tmp_path / "d"), "-o", str(tmp_path / "file.ply"), "--force"]) == 0
    assert len(read_ply(tmp_path / "file.ply").points) == 6000


def test_decomposing_again_into_a_folder_needs_force_and_removes_old_levels(tmp_path):
    write_ply(tmp_path / "in.ply", ellipsoid_with_bumps(8000))
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "4").returncode == 0
    assert (tmp_path / "out" / "level_3.ply").exists()
    msg = one_line_error(run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3"))
    assert "--force" in msg and (tmp_path / "out" / "level_3.ply").exists()
    done = run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3", "--force")
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["decomposition.npz", "level_0.ply", "level_1.ply", "level_2.ply", "source.npz"]


def test_ctrl_c_exits_130_with_one_line_and_no_files(tmp_path):
    write_ply(tmp_path / "in.ply", ps.shapes.bumpy_sphere(600000, noise=0.001, seed=9))
    proc = subprocess.Popen([sys.executable, "-m", "pointscale", "decompose", str(tmp_path / "in.ply"), "-o",
                             str(tmp_path / "out"), "--levels", "4"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    # Wait until it is computing (CPU time past a second: the imports and the read take less).
    ticks = os.sysconf("SC_CLK_TCK")
    for _ in range(600):
        fields = Path(f"/proc/{proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        if (int(fields[11]) + int(fields[12])) / ticks > 1.0:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, (proc.returncode, err)
    assert len(err.strip().splitlines()) == 1 and "interrupted" in err
    assert not (tmp_path / "out").exists() or list((tmp_path / "out").iterdir()) == []


def test_gains_may_be_negative_and_must_be_finite(tmp_path):
    points = ellipsoid_with_bumps(6000)
    write_ply(tmp_path / "in.ply", points)
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3").returncode == 0
    dec = ps.load(tmp_path / "out" / "decomposition.npz")
    done = run("reconstruct", str(tmp_path / "out"), "--gains", "-1,1", "-o", str(tmp_path / "neg.ply"))
    assert done.returncode == 0, done.stderr
    assert np.abs(read_ply(tmp_path / "neg.ply").points - ps.reconstruct(dec, gains=[-1, 1])).max() < 1e-12
    for gains in ("1e300,1", "nan,1", "1,inf", "1e308,1e308"):
        msg = one_line_error(run("reconstruct", str(tmp_path / "out"), "--gains", gains, "-o", str(tmp_path / "g.ply")))
        assert "gains" in msg
        assert not (tmp_path / "g.ply").exists()
    msg = one_line_error(run("reconstruct", str(tmp_path / "out"), "--gains", "1,2,3", "-o", str(tmp_path / "x.ply")))
    assert "needs 2 values" in msg


def test_info_shows_the_real_stats(tmp_path):
    points = ellipsoid_with_bumps(9000)
    write_ply(tmp_path / "in.ply", points)
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3").returncode == 0
    done = run("info", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    saved = ps.load(tmp_path / "out" / "decomposition.npz")
    fresh = ps.decompose(points, levels=3)
    assert saved.stats == fresh.stats  # kept in the file, not recomputed
    for l, s in enumerate(fresh.stats):
        rms = float(np.sqrt(np.mean(fresh.details[l] ** 2)))
        assert (f"band {l}: support {s['support_points']} points, kernel width {s['kernel_width']:.4g}, "
                f"detail rms {rms:.4g}, not converged {s['not_converged']}, pinned {s['pinned']}") in done.stdout
        assert s["kernel_width"] > 0 and s["not_converged"] + s["pinned"] > 0
    assert "ply, 9000 vertices" in done.stdout


def test_help_version_and_the_smoother_and_encoding_options(tmp_path):
    done = run("decompose", "--help")
    assert done.returncode == 0
    for option, default in (("--levels", "4"), ("--decimation", "0.25"), ("--kernel", "1.0"), ("--neighbors", "24"),
                            ("--smoother", "mls"), ("--encoding", "projection"), ("--threads", "0")):
        assert option in done.stdout and f"(default: {default})" in done.stdout, option
    done = run("--version")
    assert done.returncode == 0 and done.stdout.strip() == f"pointscale {ps.__version__}"
    write_ply(tmp_path / "in.ply", ellipsoid_with_bumps(6000))
    done = run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3",
               "--smoother", "diffusion")
    assert done.returncode == 0, done.stderr
    assert ps.load(tmp_path / "out" / "decomposition.npz").settings["smoother"] == "diffusion"


@pytest.mark.parametrize("command", ["decompose", "reconstruct", "info", "demo"])
def test_every_command_says_what_it_does_in_its_help(command):
    """`pointscale demo --help` listed its options and nothing of what it does."""
    from pointscale.cli.parser import build_parser
    sub = next(a for a in build_parser("ply")._actions if a.dest == "command").choices[command]
    assert sub.description and len(sub.description) > 40
    done = run(command, "--help")
    assert done.returncode == 0 and sub.description.split()[0] in done.stdout


def test_command_line_errors_are_reported_not_raised(tmp_path):
    msg = one_line_error(run("decompose", str(tmp_path / "missing.ply"), "-o", str(tmp_path / "o")))
    assert "missing.ply" in msg


def test_demo_runs_and_writes_its_files(tmp_path):
    done = run("demo", "-o", str(tmp_path / "demo"), "--points", "20000")
    assert done.returncode == 0, done.stderr
    assert "exact reconstruction" in done.stdout
    assert (tmp_path / "demo" / "handles_multiscale.ply").exists()


def test_scanned_bunny_round_trips():
    model = read_ply(shared_model("bunny.ply"))
    dec = ps.decompose(model.points, levels=4)
    assert np.abs(ps.reconstruct(dec) - model.points).max() <= 1e-11 * diagonal(model.points)  # measured 2.7e-13


@pytest.mark.parametrize("extension", [".ply", ".las", ".laz", ".obj", ".off", ".stl", ".xyz", ".pts", ".e57"])
def test_a_truncated_input_of_any_format_is_one_clear_line(tmp_path, extension):
    if extension == ".e57":
        pytest.importorskip("pye57", reason="E57 needs pye57 (pip install pye57)")
    mesh = extension in (".ply", ".obj", ".off", ".stl")
    points = ellipsoid_with_bumps(3000, seed=11)
    faces = np.random.default_rng(4).integers(0, len(points), (2000, 3)) if mesh else None
    io.write(tmp_path / f"in{extension}", io.Scan(points=points, faces=faces))
    data = (tmp_path / f"in{extension}").read_bytes()
    cut = len(data) * 2 // 5
    if extension in (".obj", ".xyz"):
        # A text file cut between two lines is a valid, shorter file; cut inside a line, after
        # its first number, as a copy that stopped half-way does.
        line = data.rindex(b"\n", 0, cut) + 1
        cut = data.index(b" ", line + 2) if extension == ".obj" else data.index(b" ", line)
    (tmp_path / f"cut{extension}").write_bytes(data[:cut])
    msg = one_line_error(run("decompose", str(tmp_path / f"cut{extension}"), "-o", str(tmp_path / "out")))
    assert f"cut{extension}" in msg
    assert not (tmp_path / "out").exists()


def test_a_base_whose_vertices_were_renumbered_is_refused(tmp_path):
    # STL renumbers vertices on reading (it stores triangle corners); a level edited in it and
    # given back as --base would pair each vertex with another's detail.
    trimesh = pytest.importorskip("trimesh")
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=1.5)
    mesh.vertices += 0.01 * np.sin(7 * mesh.vertices)
    order = np.random.default_rng(3).permutation(len(mesh.vertices))
    inverse = np.argsort(order)
    io.write(tmp_path / "ico.ply", io.Scan(points=mesh.vertices[order], faces=inverse[mesh.faces]))
    assert run("decompose", str(tmp_path / "ico.ply"), "-o", str(tmp_path / "out"), "--levels", "3").returncode == 0
    level0 = io.read(tmp_path / "out" / "level_0.ply")
    io.write(tmp_path / "edited.stl", level0)
    msg = one_line_error(run("reconstruct", str(tmp_path / "out"), "--base", str(tmp_path / "edited.stl"), "-o",
                             str(tmp_path / "r.ply")))
    assert "its vertices look renumbered" in msg and not (tmp_path / "r.ply").exists()
    # The same level in a format that keeps the order is taken, and gives back the input; so is
    # one whose faces were flipped, reordered or partly deleted (MeshLab's Invert Faces
    # Orientation, a cleanup): refused before as "its vertices are not in the input's order".
    faces = level0.faces[np.random.default_rng(5).permutation(len(level0.faces))[:-40], ::-1]
    io.write(tmp_path / "flipped.ply", io.Scan(points=level0.points, faces=faces))
    done = run("reconstruct", str(tmp_path / "out"), "--base", str(tmp_path / "flipped.ply"), "-o",
               str(tmp_path / "f.ply"))
    assert done.returncode == 0, done.stderr
    assert np.abs(read_ply(tmp_path / "f.ply").points - mesh.vertices[order]).max() < 1e-9
    done = run("reconstruct", str(tmp_path / "out"), "--base", str(tmp_path / "out" / "level_0.ply"), "-o",
               str(tmp_path / "r.ply"))
    assert done.returncode == 0, done.stderr
    assert np.abs(read_ply(tmp_path / "r.ply").points - mesh.vertices[order]).max() < 1e-9


def test_a_mesh_written_to_a_point_format_says_its_faces_are_dropped(tmp_path):
    points = ellipsoid_with_bumps(6000)
    faces = np.random.default_rng(6).integers(0, len(points), (300, 3))
    write_ply(tmp_path / "in.ply", points, faces=faces)
    done = run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3", "--format", "xyz",
               "--parts", "none")  # its random faces only test that they are dropped
    assert done.returncode == 0, done.stderr
    warnings = [l for l in done.stderr.splitlines() if "warning" in l]
    assert len(warnings) == 1 and "300 faces" in warnings[0] and ".part" not in warnings[0], done.stderr


def test_an_output_format_that_cannot_hold_the_model_is_refused_before_computing(tmp_path, monkeypatch, capsys):
    io.write(tmp_path / "cloud.xyz", io.Scan(points=ellipsoid_with_bumps(6000)))
    calls = []
    monkeypatch.setattr(cli.commands, "decompose", lambda *a, **k: calls.append(1))
    assert cli.main(["decompose", str(tmp_path / "cloud.xyz"), "-o", str(tmp_path / "o"), "--format", "stl"]) == 2
    assert calls == [] and "no faces" in capsys.readouterr().err and not (tmp_path / "o").exists()


@pytest.mark.parametrize("name, text", [
    ("inf.off", "OFF\n3 inf 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
    ("big.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n"),
    ("wrap.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                 "3 0 1 4294967298\n"),
    ("colour.xyz", "# x y z red:u1\n0 0 0 300\n1 0 0 -1\n0 1 0 5\n"),
])
def test_numbers_too_large_for_their_type_are_refused_not_wrapped(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    msg = one_line_error(run("decompose", str(tmp_path / name), "-o", str(tmp_path / "out")))
    assert name in msg


def test_a_mesh_of_two_parts_is_decomposed_part_by_part(tmp_path):
    """The command line passes the PLY's faces: a torus-like ring of bumps and a box beside it stay apart."""
    sv, sf = ps.meshes.uv_sphere(0.9, 80, 40)
    sv = ps.meshes.bumpy(sv, 0.02, 7) * np.array([1.2, 1.0, 0.8])
    bv, bf = ps.meshes.box((0.2, 0.35, 0.25), 30)
    bv = bv + np.array([1.08 + 0.03 + 0.1, 0.0, 0.0])
    points, faces, part = ps.meshes.joined((sv, sf), (bv, ps.meshes.quads_to_triangles(bf)))
    plyfile_scan(tmp_path / "two.ply", points, faces)
    for mode, expect in (("faces", 2), ("none", None)):
        out = tmp_path / mode
        done = run("decompose", str(tmp_path / "two.ply"), "-o", str(out), "--parts", mode)
        assert done.returncode == 0, done.stderr
        dec = ps.load(out / "decomposition.npz")
        if expect is None:
            assert dec.parts is None
            continue
        assert len(dec.parts) == expect and np.array_equal(dec.part_labels, part)
        assert "2 connected parts" in done.stdout
        assert "part 1 (" in done.stderr  # the box keeps fewer levels, and the warning says so
        level0 = read_ply(out / "level_0.ply").points
        box_diag = diagonal(bv)
        assert np.linalg.norm(level0[part == 1] - bv, axis=1).max() < 0.10 * box_diag


def test_sheets_keep_a_thin_plate_apart_from_the_files_normals(tmp_path):
    """--sheets tells a two-sided plate's sides by the normals the PLY carries."""
    points, normals, side = ps.shapes.thin_plate(1.8, 1.3, spacing=0.02, gap=0.016)
    io.write(tmp_path / "plate.ply", io.Scan(points=points, normals=normals))
    for flag, apart in (("--sheets", True), (None, False)):
        out = tmp_path / ("sheets" if flag else "plain")
        done = run("decompose", str(tmp_path / "plate.ply"), "-o", str(out), *([flag] if flag else []))
        assert done.returncode == 0, done.stderr
        level0 = read_ply(out / "level_0.ply").points
        drift = np.abs(np.einsum("ij,ij->i", level0 - points, normals)).max() / 0.016
        assert (drift < 0.1) == apart, drift  # measured 0 with --sheets, 0.53 without


def test_reconstruct_rebuilds_a_mirrored_half(tmp_path):
    """Every `pointscale reconstruct` of a decomposition made with --mirror failed: 'with_geometry
    needs 6000 points ..., got 12000' (the command line took the whole mirrored model's points
    for the half's)."""
    rng = np.random.default_rng(4)
    d = rng.normal(size=(16000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    p = d * [1.5, 0.7, 1.0] * (1 + 0.03 * np.sin(6 * d[:, 0]) * np.sin(5 * d[:, 2]))[:, None] + [0.0, 2.0, 0.0]
    half = p[p[:, 1] >= 2.0]
    write_ply(tmp_path / "half.ply", half)
    done = run("decompose", str(tmp_path / "half.ply"), "-o", str(tmp_path / "dec"), "--levels", "3",
               "--mirror", "y", "--mirror-origin", "0,2,0")
    assert done.returncode == 0, done.stderr
    dec = ps.load(tmp_path / "dec" / "decomposition.npz")
    assert dec.mirror is not None and dec.n_points == len(half)
    base = io.read(tmp_path / "dec" / "level_0.ply").points
    base[:, 2] += 0.1 * np.exp(-np.sum((base - base[np.argmax(base[:, 2])]) ** 2, axis=1) / 0.2)
    io.write(tmp_path / "edited.ply", io.read(tmp_path / "dec" / "level_0.ply").with_geometry(base))
    cases = {"plain": ([], ps.reconstruct(dec)),
             "gains": (["--gains", "1,3"], ps.reconstruct(dec, (1, 3))),
             "base": (["--base", str(tmp_path / "edited.ply")], ps.reconstruct(dec, None, base)),
             "prevent": (["--gains", "1,6", "--folds", "prevent"], ps.reconstruct(dec, (1, 6), folds="prevent")[0])}
    for name, (options, expected) in cases.items():
        out = tmp_path / f"{name}.ply"
        done = run("reconstruct", str(tmp_path / "dec"), "-o", str(out), *options)
        assert done.returncode == 0, (name, done.stderr)
        assert np.array_equal(io.read(out).points, expected), name
    assert np.abs(io.read(tmp_path / "plain.ply").points - half).max() < 1e-12


def test_small_command_line_notes(tmp_path):
    """A folder as input said "unknown extension '(none)'"; --fold-reference without --folds was
    ignored without a word; STL level files, which --base can never take back, were written
    without one."""
    (tmp_path / "scans").mkdir()
    assert one_line_error(run("decompose", str(tmp_path / "scans"), "-o", str(tmp_path / "o"))).endswith(
        "is a folder, not a file")
    from pointscale import meshes
    v, f = meshes.uv_sphere(1.0, 72, 36)
    io.write(tmp_path / "in.ply", io.Scan(points=meshes.bumpy(v, 0.03, 6), faces=f))
    done = run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "dec"), "--levels", "3", "--format", ".stl")
    assert done.returncode == 0 and "cannot come back as reconstruct --base" in done.stderr, done.stderr
    done = run("reconstruct", str(tmp_path / "dec"), "--fold-reference", "base", "-o", str(tmp_path / "r.ply"))
    assert done.returncode == 0 and "--fold-reference base applies to --folds report or prevent only" in done.stderr
    done = run("reconstruct", str(tmp_path / "dec"), "--fold-reference", "base", "--folds", "report",
               "-o", str(tmp_path / "r2.ply"))
    assert done.returncode == 0 and "applies to --folds" not in done.stderr


def test_a_triangulated_base_of_a_quad_mesh_is_taken(tmp_path):
    """MeshLab triangulates polygons on reading: a quad grid's level 0 came back as triangles,
    and --base refused it as renumbered (0% of its faces matched)."""
    n = 48
    u, v = np.meshgrid(np.linspace(0, 3, n), np.linspace(0, 2, n))
    points = np.c_[u.ravel(), v.ravel(), (0.1 * np.sin(3 * u) * np.cos(4 * v)).ravel()]
    idx = np.arange(n * n).reshape(n, n)
    quads = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], axis=-1).reshape(-1, 4)
    io.write(tmp_path / "grid.ply", io.Scan(points=points, faces=quads))
    assert run("decompose", str(tmp_path / "grid.ply"), "-o", str(tmp_path / "dec"), "--levels", "3").returncode == 0
    level0 = io.read(tmp_path / "dec" / "level_0.ply").points
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    io.write(tmp_path / "tri.ply", io.Scan(points=level0, faces=triangles))
    done = run("reconstruct", str(tmp_path / "dec"), "--base", str(tmp_path / "tri.ply"), "-o", str(tmp_path / "r.ply"))
    assert done.returncode == 0, done.stderr
    assert np.abs(io.read(tmp_path / "r.ply").points - points).max() < 1e-9


def test_an_stl_input_takes_its_own_stl_level_back(tmp_path):
    """Decompose of an STL said its STL level 0 could not come back as --base: it can (an STL's
    vertices are numbered as they are read, and its levels are written in that order)."""
    from pointscale import meshes
    v, f = meshes.uv_sphere(1.0, 64, 32)
    io.write(tmp_path / "in.stl", io.Scan(points=meshes.bumpy(v, 0.03, 5), faces=f))
    done = run("decompose", str(tmp_path / "in.stl"), "-o", str(tmp_path / "dec"), "--levels", "3")
    assert done.returncode == 0 and "cannot come back" not in done.stderr, done.stderr
    done = run("reconstruct", str(tmp_path / "dec"), "--base", str(tmp_path / "dec" / "level_0.stl"),
               "-o", str(tmp_path / "r.ply"))
    assert done.returncode == 0, done.stderr
    assert np.abs(io.read(tmp_path / "r.ply").points - io.read(tmp_path / "in.stl").points).max() < 1e-6
