"""Files the user put beside or inside pointscale's: never removed, never overwritten, never
silently changed, and refused with one clear line when they cannot be kept."""
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

import pointscale as ps
from pointscale import cli, io


def wavy_torus(n: int = 3000, seed: int = 1) -> np.ndarray:
    """A closed surface of this file's own (not the bumpy sphere other tests use)."""
    rng = np.random.default_rng(seed)
    u, v = rng.random(n) * 2 * np.pi, rng.random(n) * 2 * np.pi
    r = 0.7 + 0.05 * np.sin(5 * u) * np.cos(3 * v)
    return np.column_stack([(2 + r * np.cos(v)) * np.cos(u), (2 + r * np.cos(v)) * np.sin(u), 1.3 * r * np.sin(v)])


def decompose(source: Path, out: Path, *extra) -> int:
    return cli.main(["decompose", str(source), "-o", str(out), "--levels", "3", "--threads", "1", *extra])


def write_plyfile(path: Path, points: np.ndarray, **columns) -> None:
    vertex = np.empty(len(points), [("x", "f8"), ("y", "f8"), ("z", "f8")] + [(k, v.dtype) for k, v in columns.items()])
    vertex["x"], vertex["y"], vertex["z"] = points.T
    for name, values in columns.items():
        vertex[name] = values
    PlyData([PlyElement.describe(vertex, "vertex")]).write(str(path))


def vertex_data(path: Path) -> np.ndarray:
    return PlyData.read(str(path))["vertex"].data


# -- 1. --force removes only pointscale's own files ---------------------------------------------

def test_a_folder_of_the_users_lookalike_files_is_not_a_decomposition(tmp_path, capsys):
    io.write_ply(tmp_path / "in.ply", wavy_torus())
    out = tmp_path / "out"
    out.mkdir()
    (out / "level_1.txt").write_text("my notes")
    (out / "level_12.png").write_bytes(b"png bytes")
    assert decompose(tmp_path / "in.ply", out) == 0, capsys.readouterr().err
    assert (out / "level_1.txt").read_text() == "my notes"
    assert (out / "level_12.png").read_bytes() == b"png bytes"


def test_force_removes_old_levels_but_not_the_users_files(tmp_path, capsys):
    io.write_ply(tmp_path / "in.ply", wavy_torus())
    out = tmp_path / "out"
    assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(out), "--levels", "4", "--threads", "1"]) == 0
    users = {"level_1.txt": "notes", "level_12.png": "png", "level_03.ply": "zero-padded", "level_3.PLY": "caps",
             "level_3.ply.bak": "backup", "level_x.ply": "not a number"}
    for name, text in users.items():
        (out / name).write_text(text)
    assert decompose(tmp_path / "in.ply", out) == 2
    assert "already holds a decomposition" in capsys.readouterr().err
    assert decompose(tmp_path / "in.ply", out, "--force") == 0
    assert not (out / "level_3.ply").exists()  # the earlier run's own finest level, replaced
    for name, text in users.items():
        assert (out / name).read_text() == text, name
    assert sorted(p.name for p in out.iterdir() if p.name not in users) == [
        "decomposition.npz", "level_0.ply", "level_1.ply", "level_2.ply", "source.npz"]


# -- 2. the user's nx, ny, nz that are not float normals are kept -------------------------------

def test_a_lone_nx_is_kept_and_the_normals_go_beside_it(tmp_path, capsys):
    points = wavy_torus()
    nx = np.random.default_rng(2).random(len(points)).astype("f4")
    write_plyfile(tmp_path / "in.ply", points, nx=nx)
    assert decompose(tmp_path / "in.ply", tmp_path / "out") == 0, capsys.readouterr().err
    assert cli.main(["reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "result.ply")]) == 0
    for file in ["out/level_0.ply", "out/level_1.ply", "out/level_2.ply", "result.ply"]:
        data = vertex_data(tmp_path / file)
        assert data["nx"].dtype == np.float32 and np.array_equal(data["nx"], nx), file
        normals = np.column_stack([data[f"pointscale_n{a}"] for a in "xyz"])
        assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6), file


def test_int16_normals_are_kept_as_the_users_values(tmp_path, capsys):
    points = wavy_torus()
    quantised = (points / np.linalg.norm(points, axis=1, keepdims=True) * 32767).astype("i2")
    write_plyfile(tmp_path / "in.ply", points, nx=quantised[:, 0], ny=quantised[:, 1], nz=quantised[:, 2],
                  pointscale_nx=np.arange(len(points), dtype="u4"))  # the first choice of name is taken too
    scan = io.read(tmp_path / "in.ply")
    assert scan.normals is None and scan.vertex_attributes["ny"].dtype == np.int16
    assert decompose(tmp_path / "in.ply", tmp_path / "out") == 0, capsys.readouterr().err
    dec = ps.load(tmp_path / "out" / "decomposition.npz")
    data = vertex_data(tmp_path / "out" / "level_1.ply")
    for axis, name in enumerate(("nx", "ny", "nz")):
        assert data[name].dtype == np.int16 and np.array_equal(data[name], quantised[:, axis])
    assert np.array_equal(data["pointscale_nx"], np.arange(len(points)))
    normals = np.column_stack([data[f"pointscale_n{a}_2"] for a in "xyz"])
    assert np.abs(normals - dec.normals(1)).max() < 1e-12


@pytest.mark.parametrize("dims", [[("nx", "f4")], [("nx", "u1"), ("ny", "u1"), ("nz", "u1")]],
                         ids=["lone float nx", "uint8 nx ny nz"])
def test_las_extra_bytes_named_like_normals_are_kept(tmp_path, capsys, dims):
    laspy = pytest.importorskip("laspy")
    points = wavy_torus()
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales, header.offsets = [0.001] * 3, [0, 0, 0]
    for name, kind in dims:
        header.add_extra_dim(laspy.ExtraBytesParams(name=name, type=kind))
    las = laspy.LasData(header)
    las.x, las.y, las.z = points.T
    rng = np.random.default_rng(4)
    values = {name: rng.integers(0, 200, len(points)).astype(kind) if kind == "u1"
              else (rng.random(len(points)) * 50).astype(kind) for name, kind in dims}
    for name, column in values.items():
        las[name] = column
    las.write(str(tmp_path / "in.las"))
    assert decompose(tmp_path / "in.las", tmp_path / "out") == 0, capsys.readouterr().err
    for level in range(3):
        written = laspy.read(str(tmp_path / "out" / f"level_{level}.las"))
        for name, column in values.items():
            assert np.array_equal(np.asarray(written[name]), column), (level, name)
        normals = np.column_stack([np.asarray(written[f"pointscale_n{a}"]) for a in "xyz"])
        assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)


def test_an_xyz_header_with_integer_normals_keeps_them(tmp_path, capsys):
    points = wavy_torus()
    quantised = (points / np.linalg.norm(points, axis=1, keepdims=True) * 127).astype("i1")
    rows = "\n".join(f"{x!r} {y!r} {z!r} {a} {b} {c}" for (x, y, z), (a, b, c) in zip(points.tolist(), quantised))
    (tmp_path / "in.xyz").write_text("# x y z nx:i1 ny:i1 nz:i1\n" + rows + "\n")
    assert decompose(tmp_path / "in.xyz", tmp_path / "out") == 0, capsys.readouterr().err
    level = io.read(tmp_path / "out" / "level_2.xyz")
    assert level.vertex_attributes["nz"].dtype == np.int8
    assert np.array_equal(level.vertex_attributes["nz"], quantised[:, 2])
    assert np.allclose(np.linalg.norm(np.column_stack([level.vertex_attributes[f"pointscale_n{a}"] for a in "xyz"]),
                                      axis=1), 1.0)


def test_attributes_a_format_cannot_name_are_refused_before_computing(tmp_path, capsys, monkeypatch):
    points = wavy_torus()
    features = np.column_stack([np.arange(len(points)), -np.arange(len(points))]).astype("i4")
    scan = io.Scan(points=points, vertex_attributes={"f": features, "f_0": np.ones(len(points), "u1")})
    io.write(tmp_path / "in.ply", scan)  # (n, 2) f and a scalar f_0: XYZ would name two columns f_0
    assert decompose(tmp_path / "in.ply", tmp_path / "out") == 0
    computed = []
    monkeypatch.setattr(cli.commands, "decompose", lambda *a, **k: computed.append(1))
    monkeypatch.setattr(cli.commands, "reconstruct_with_normals", lambda *a, **k: computed.append(1))
    capsys.readouterr()
    assert decompose(tmp_path / "in.ply", tmp_path / "xyz", "--format", "xyz") == 2
    assert cli.main(["reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "result.xyz")]) == 2
    assert computed == []
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all("['f_0'] would appear twice" in line for line in err), err
    assert str(tmp_path / "xyz" / "level_0.xyz") in err[0] and str(tmp_path / "result.xyz") in err[1]
    assert not (tmp_path / "xyz").exists() and not (tmp_path / "result.xyz").exists()


def test_writers_refuse_an_attribute_that_would_overwrite_the_normals(tmp_path):
    points = wavy_torus(200)
    scan = io.Scan(points=points, normals=points / np.linalg.norm(points, axis=1, keepdims=True),
                   vertex_attributes={"nx": np.arange(200, dtype="u1")})
    for extension in (".ply", ".las", ".xyz"):
        with pytest.raises(ValueError, match="nx"):
            io.write(tmp_path / f"out{extension}", scan)
        assert not (tmp_path / f"out{extension}").exists()


# -- 3. lists longer than 255 values get a count type that holds them ---------------------------

@pytest.mark.parametrize("binary", [True, False], ids=["binary", "ascii"])
def test_a_list_attribute_longer_than_255_values_reads_back_unchanged(tmp_path, binary):
    points = wavy_torus(50)
    features = (np.arange(50 * 300, dtype=np.float32).reshape(50, 300) % 7) + 0.5
    ring = np.arange(300, dtype=np.int64)  # one polygon of 300 corners, then two triangles
    scan = io.Scan(points=np.vstack([points, wavy_torus(250, seed=3)]),
                   vertex_attributes={"features": np.vstack([features, np.zeros((250, 300), np.float32)])},
                   faces=[ring, np.array([0, 1, 2]), np.array([3, 4, 5])])
    io.ply.write_ply(tmp_path / "wide.ply", scan, binary=binary)
    header = PlyData.read(str(tmp_path / "wide.ply")).header
    assert "property list ushort float features" in header
    back = io.read(tmp_path / "wide.ply")
    assert np.array_equal(back.points, scan.points)
    assert np.array_equal(back.vertex_attributes["features"], scan.vertex_attributes["features"])
    assert [f.tolist() for f in back.faces] == [f.tolist() for f in scan.faces]


# -- 4. an edited source.npz's format_info is checked on loading --------------------------------

def icosphere_ply(path: Path) -> int:
    """A float64 PLY mesh of 642 vertices (more than uchar indices reach); returns the count."""
    import trimesh
    mesh = trimesh.creation.icosphere(subdivisions=3)
    points = mesh.vertices * (1 + 0.04 * np.sin(6 * mesh.vertices[:, :1]))
    io.write(path, io.Scan(points=points, faces=mesh.faces, format_info={}))
    return len(points)


def edit_source(folder: Path, **changes) -> None:
    import json
    arrays = dict(np.load(folder / "source.npz"))
    meta = json.loads(arrays["meta_json"].tobytes())
    meta["format_info"].update(changes)
    arrays["meta_json"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    np.savez(folder / "source.npz", **arrays)


@pytest.mark.parametrize("changes, message", [
    ({"face_index": {"name": "vertex_indices", "len_dtype": "f4", "val_dtype": "i4"}}, "face_index must"),
    ({"normal_dtype": "i1"}, "normal_dtype must be one of"),
    ({"normal_dtype": "O"}, "normal_dtype must be one of"),
    ({"byte_order": "little"}, "byte_order must be"),
    ({"comments": ["ok", "two\nelement evil 1"]}, "comments must be"),
    ({"list_lengths": {"vertex_indices": "f8"}}, "list_lengths must be"),
    ({"format": "pickle"}, "unknown format 'pickle'"),
], ids=["float count", "int8 normals", "object normals", "byte order", "header line",
        "float list count", "unknown format"])
def test_an_edited_source_format_info_is_one_clear_line(tmp_path, capsys, changes, message):
    icosphere_ply(tmp_path / "in.ply")
    assert decompose(tmp_path / "in.ply", tmp_path / "out") == 0
    edit_source(tmp_path / "out", **changes)
    capsys.readouterr()
    assert cli.main(["reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "result.ply")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and "source.npz" in err[0], err
    assert not (tmp_path / "result.ply").exists()


@pytest.mark.parametrize("changes, message", [
    ({"scales": [0.001, -1, 0.001]}, "scales must be"),
    ({"point_format": 99}, "point_format must be"),
    ({"normal_type": "u1"}, "normal_type must be"),
    ({"project_guid": "not-a-guid"}, "project_guid must be"),
    ({"extra_dimensions": [{"name": "a", "type": "object"}]}, "extra_dimensions must be"),
])
def test_an_edited_las_format_info_is_refused_on_loading(changes, message):
    scan = io.Scan(points=wavy_torus(20), format_info={
        "format": "las", "version": "1.4", "point_format": 6, "scales": [0.001] * 3, "offsets": [0.0] * 3,
        "project_guid": "00000000-0000-0000-0000-000000000000", "extra_dimensions": [], "vlrs": [], "evlrs": []})
    arrays = scan.to_arrays()
    assert io.Scan.from_arrays(arrays).format_info["point_format"] == 6
    scan.format_info.update(changes)
    with pytest.raises(ValueError, match=message):
        io.Scan.from_arrays(scan.to_arrays())


def test_uchar_face_indices_are_widened_when_the_vertices_outgrow_them(tmp_path):
    points = wavy_torus(300)
    faces = np.array([[0, 1, 299], [2, 3, 298]])
    scan = io.Scan(points=points, faces=faces, format_info={
        "format": "ply", "face_index": {"name": "vertex_indices", "len_dtype": "u1", "val_dtype": "u1"}})
    io.write(tmp_path / "out.ply", scan)
    assert np.array_equal(io.read(tmp_path / "out.ply").faces, faces)


def test_a_ply_with_uchar_face_indices_and_more_vertices_comes_back_from_its_folder(tmp_path, capsys):
    """A valid PLY: a point cloud of 2562 vertices with a few faces on its first vertices, indexed
    by uchar. Its own folder must read back (the writer widens the index type), faces intact."""
    points = ps.shapes.fibonacci_sphere(2562)
    faces = np.array([[0, 1, 2], [3, 4, 5], [250, 251, 252]])
    vertex = np.array([tuple(p) for p in points], dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    face = np.array([(f,) for f in faces.tolist()], dtype=[("vertex_indices", "u1", (3,))])
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(str(tmp_path / "in.ply"))
    assert decompose(tmp_path / "in.ply", tmp_path / "out", "--parts", "none") == 0, capsys.readouterr().err
    assert cli.main(["reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "result.ply")]) == 0, \
        capsys.readouterr().err
    result = io.read(tmp_path / "result.ply")
    assert np.array_equal(result.faces, faces)
    assert np.abs(result.points - points).max() < 1e-9 * np.linalg.norm(np.ptp(points, axis=0))


# -- 5. XYZ: 64-bit integer columns read and written exactly; no column lost to a duplicate name -

def test_xyz_64_bit_integer_columns_survive_exactly(tmp_path, capsys):
    points = wavy_torus()
    ids = 2 ** 60 + 2 * np.arange(len(points), dtype=np.uint64) + 1  # odd: float64 would round them
    offsets = -(2 ** 62) - np.arange(len(points), dtype=np.int64)
    lines = [f"{x!r} {y!r} {z!r} {int(i)} {int(o)}" for (x, y, z), i, o in zip(points.tolist(), ids, offsets)]
    (tmp_path / "in.xyz").write_text("# x y z id:u8 offset:i8\n" + "\n".join(lines) + "\n")
    scan = io.read(tmp_path / "in.xyz")
    assert scan.vertex_attributes["id"].dtype == np.uint64 and np.array_equal(scan.vertex_attributes["id"], ids)
    assert np.array_equal(scan.vertex_attributes["offset"], offsets)
    assert decompose(tmp_path / "in.xyz", tmp_path / "out") == 0, capsys.readouterr().err
    assert cli.main(["reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "result.xyz")]) == 0
    for file in ("out/level_0.xyz", "out/level_2.xyz", "result.xyz"):
        back = io.read(tmp_path / file)
        assert np.array_equal(back.vertex_attributes["id"], ids), file
        assert np.array_equal(back.vertex_attributes["offset"], offsets), file


@pytest.mark.parametrize("value", ["18446744073709551616", "-1", "1.5"])
def test_an_xyz_64_bit_integer_out_of_range_or_fractional_is_refused(tmp_path, value):
    (tmp_path / "in.xyz").write_text(f"# x y z id:u8\n0 0 0 1\n1 0 0 {value}\n0 1 0 3\n")
    with pytest.raises(ValueError, match=f"column id is declared uint64 but holds .*{value}"):
        io.read(tmp_path / "in.xyz")


@pytest.mark.parametrize("header", ["# x y z a a", "# x y z nx ny nz x:u1"])
def test_an_xyz_header_naming_a_column_twice_is_refused(tmp_path, header):
    columns = len(header.split()) - 1
    (tmp_path / "in.xyz").write_text(header + "\n" + "\n".join(" ".join(["1"] * columns) for _ in range(4)) + "\n")
    with pytest.raises(ValueError, match="more than once"):
        io.read(tmp_path / "in.xyz")


# -- 6. OBJ's w, alpha and vt w are kept and written back in their place ------------------------

def obj_lines(path: Path, prefix: str) -> list:
    return [line.split()[1:] for line in path.read_text().splitlines() if line.startswith(prefix + " ")]


@pytest.mark.parametrize("v_extra, vt_line", [("0.2 0.4 0.6 0.25", "vt 0.1 0.2 0.75"), ("0.5", None)],
                         ids=["v x y z r g b a, vt u v w", "v x y z w"])
def test_obj_values_beyond_xyz_and_uv_are_kept_in_every_level(tmp_path, capsys, v_extra, vt_line):
    import trimesh
    mesh = trimesh.creation.icosphere(subdivisions=3)
    points = mesh.vertices * (1 + 0.04 * np.sin(6 * mesh.vertices[:, :1]))
    lines = [f"v {x!r} {y!r} {z!r} {v_extra}" for x, y, z in points.tolist()]
    corner = "%d"
    if vt_line:
        lines += [vt_line] * len(points)
        corner = "%d/%d"
    lines += ["f " + " ".join(corner % ((i + 1,) * corner.count("%d")) for i in face) for face in mesh.faces]
    (tmp_path / "in.obj").write_text("\n".join(lines) + "\n")
    assert cli.main(["decompose", str(tmp_path / "in.obj"), "-o", str(tmp_path / "out"), "--levels", "2"]) == 0
    extra = [float(v) for v in v_extra.split()]
    for level in range(2):
        written = tmp_path / "out" / f"level_{level}.obj"
        assert {tuple(float(v) for v in row[3:]) for row in obj_lines(written, "v")} == {tuple(extra)}
        if vt_line:
            assert {tuple(float(v) for v in row) for row in obj_lines(written, "vt")} == {(0.1, 0.2, 0.75)}
    scan = io.read(tmp_path / "out" / "level_1.obj")
    names = ["red", "green", "blue", "alpha"] if len(extra) == 4 else ["vertex_w"]
    for name, value in zip(names, extra):
        assert np.all(scan.vertex_attributes[name] == value), name


def test_alpha_from_a_ply_is_not_put_on_obj_v_lines(tmp_path):
    points = wavy_torus(20)
    rgba = {c: np.full(20, 255, np.uint8) for c in ("red", "green", "blue", "alpha")}
    with pytest.warns(UserWarning, match="no place for alpha"):
        io.write(tmp_path / "out.obj", io.Scan(points=points, vertex_attributes=rgba))
    assert {len(row) for row in obj_lines(tmp_path / "out.obj", "v")} == {6}


# -- 7. --gains "" is refused like 1,,1 ---------------------------------------------------------

def test_empty_gains_are_refused_and_a_missing_value_is_named(tmp_path, capsys):
    io.write_ply(tmp_path / "in.ply", wavy_torus())
    assert decompose(tmp_path / "in.ply", tmp_path / "out") == 0
    capsys.readouterr()
    for gains in ("", "1,,1"):
        assert cli.main(["reconstruct", str(tmp_path / "out"), "--gains", gains, "-o", str(tmp_path / "r.ply")]) == 2
        assert f"--gains must be comma-separated numbers, got {gains!r}" in capsys.readouterr().err
        assert not (tmp_path / "r.ply").exists()
    with pytest.raises(SystemExit):
        cli.main(["reconstruct", str(tmp_path / "out"), "--gains", "--threads", "1", "-o", str(tmp_path / "r.ply")])
    assert "argument --gains: expected one argument" in capsys.readouterr().err
    assert cli.main(["reconstruct", str(tmp_path / "out"), "--gains", "-1,1", "-o", str(tmp_path / "r.ply")]) == 0


@pytest.mark.parametrize("change, message", [
    ({"kernel": "lots"}, "must be a number"),
    ({"levels": 9}, "the arrays hold 3 levels"),
    ({"neighbors": 2.5}, "whole number"),
    ({"smoother": "\x1b[31mred"}, "control character"),
    ({"note": {"\x07bell": 1}}, "control character"),
])
def test_a_shared_decompositions_settings_are_checked_on_loading(tmp_path, capsys, change, message):
    """`pointscale info` prints the settings: a shared file's escape sequences reached the
    terminal, and levels=9 was shown for a model of 3 (scan technician's trial)."""
    import json
    dec = ps.decompose(wavy_torus(), levels=3)
    arrays = dec.to_dict()
    arrays["settings"] = np.frombuffer(json.dumps({**dec.settings, **change}).encode(), dtype=np.uint8)
    np.savez(tmp_path / "decomposition.npz", **arrays)
    with pytest.raises(ValueError, match=message):
        ps.load(tmp_path / "decomposition.npz")
    assert cli.main(["info", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and "\x1b" not in err and "\x07" not in err


def test_a_ragged_xyz_and_an_empty_input_name_are_said_in_the_users_words(tmp_path, capsys):
    """NumPy's advice ("use `usecols`") named an option the user does not have; an empty input
    name was called a folder."""
    (tmp_path / "ragged.xyz").write_text("1 2 3\n4 5\n6 7 8\n")
    assert cli.main(["decompose", str(tmp_path / "ragged.xyz"), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "row 2" in err and "usecols" not in err
    assert cli.main(["decompose", "", "-o", str(tmp_path / "out")]) == 2
    assert "input file name is empty" in capsys.readouterr().err


def test_every_kind_of_decomposition_loads_back_with_its_settings_checked(tmp_path):
    """The settings check refused a decomposition of parts saved with max_iterations=30.0 (its
    settings keep the caller's own value, which decompose takes as a whole number). Found by a
    reviewer, with these kinds."""
    from scipy.spatial import cKDTree
    a = ps.shapes.bumpy_sphere(6000, seed=1)
    b = ps.shapes.bumpy_sphere(2500, seed=2) * 0.5 + [4, 0, 0]
    points = np.vstack([a, b])
    edges = np.vstack([np.array([(i + off, j + off) for i, row in enumerate(cKDTree(p).query(p, 4)[1]) for j in row[1:]])
                       for p, off in ((a, 0), (b, len(a)))])
    kinds = {"mls": lambda: ps.decompose(a, levels=3),
             "diffusion": lambda: ps.decompose(a, levels=3, smoother="diffusion"),
             "rayshoot": lambda: ps.decompose(a, levels=3, encoding="rayshoot"),
             "parts": lambda: ps.decompose(points, levels=3, edges=edges),
             "parts, max_iterations 30.0": lambda: ps.decompose(points, levels=3, edges=edges, max_iterations=30.0),
             "mirrored": lambda: ps.decompose(a[a[:, 0] >= 0], levels=3, mirror="x"),
             "encoded parts, max_iterations 30.0": lambda: ps.encode(points, ps.ellipsoid_base(points), edges=edges,
                                                                     max_iterations=30.0)}
    for name, make in kinds.items():
        dec = make()
        dec.save(tmp_path / "d.npz")
        again = ps.load(tmp_path / "d.npz")
        assert again.settings == dec.settings, name
