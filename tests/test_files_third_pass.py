"""Files, after a third reader's pass (2026-12-07): a decompose that fails while putting its
files in place, format details of a decomposition folder that no longer fit its values, a PLY
whose coordinates are lists, and two calls whose errors were not ValueErrors."""
import json
import os

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

import pointscale as ps
from pointscale.cli import staged_output
from helpers import one_line_error, run_cli as run


def cloud_ply(path, seed, red):
    p = np.random.default_rng(seed).normal(size=(8000, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    v = np.empty(len(p), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("red", "u1")])
    v["x"], v["y"], v["z"] = p.T
    v["red"] = red
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))


def snapshot(folder):
    return {name: (folder / name).read_bytes() for name in sorted(os.listdir(folder)) if (folder / name).is_file()}


def test_a_folder_in_the_way_of_an_output_file_leaves_the_old_result_whole(tmp_path):
    """Before, the files renamed into place before the one that failed stayed: a --force run
    replaced the old decomposition but not its source.npz, and reconstruct then paired the new
    geometry with the old colours."""
    cloud_ply(tmp_path / "a.ply", 1, 100)
    cloud_ply(tmp_path / "b.ply", 2, 200)
    out = tmp_path / "out"
    assert run("decompose", str(tmp_path / "a.ply"), "-o", str(out), "--levels", "3").returncode == 0
    (out / "level_3.ply").mkdir()  # where a 4-level decompose puts its finest level
    before = snapshot(out)
    error = one_line_error(run("decompose", str(tmp_path / "b.ply"), "-o", str(out), "--levels", "4", "--force"))
    assert "level_3.ply is a folder" in error and ".part" not in error
    assert snapshot(out) == before                                   # every old file as it was
    assert sorted(os.listdir(out)) == sorted([*before, "level_3.ply"])  # and nothing else left behind
    fresh = tmp_path / "fresh"
    (fresh / "level_2.ply").mkdir(parents=True)
    one_line_error(run("decompose", str(tmp_path / "a.ply"), "-o", str(fresh), "--levels", "3"))
    assert os.listdir(fresh) == ["level_2.ply"]


def test_a_rename_that_fails_midway_puts_back_what_the_ones_before_it_replaced(tmp_path, monkeypatch):
    names = ["decomposition.npz", "source.npz", "level_0.ply", "level_1.ply"]
    for name in names:
        (tmp_path / name).write_text("old " + name)
    stage = staged_output.StagedOutput()
    for name in names:
        stage.temporary(tmp_path / name).write_text("new " + name)
    real, calls = os.replace, []

    def replace(src, dst):
        calls.append(dst)
        if str(src).endswith(".ply") and "level_1" in str(dst) and ".part" in str(src):
            raise PermissionError(13, "Permission denied")
        return real(src, dst)

    monkeypatch.setattr(staged_output.os, "replace", replace)
    with pytest.raises(OSError, match="could not write .*level_1.ply"):
        with stage:
            stage.commit()
    assert sorted(os.listdir(tmp_path)) == sorted(names)  # no temporary or set-aside file left
    for name in names:
        assert (tmp_path / name).read_text() == "old " + name


def las_with_float_extra(path):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = [0.001] * 3
    header.offsets = [5.0e5, 4.2e6, 100.0]
    header.add_extra_dim(laspy.ExtraBytesParams(name="reflectance", type=np.float64))
    header.vlrs.append(laspy.VLR(user_id="pointscale", record_id=7, description="a record", record_data=b"\x01\x02"))
    las = laspy.LasData(header)
    rng = np.random.default_rng(4)
    p = rng.normal(size=(3000, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    las.x, las.y, las.z = (5.0e5 + 20 * p[:, 0], 4.2e6 + 20 * p[:, 1], 100 + 20 * p[:, 2])
    las.reflectance = rng.normal(size=3000)
    las.write(str(path))


@pytest.mark.parametrize("edit, message", [
    (lambda m: m["format_info"]["extra_dimensions"][0].update(type="u1"), "does not fit the LAS extra-bytes type 'u1'"),
    (lambda m: m["format_info"]["vlrs"][0].update(user_id="u" * 40), "user_id of up to 16 bytes"),
])
def test_format_details_edited_to_no_longer_fit_the_values_are_refused(tmp_path, edit, message):
    """Before, reflectance 0.49, 0.02, -1.59, 1.44 came out as 0, 0, 255, 1 (a uint8 field), and a
    40-character record id was cut to 15, both with exit 0."""
    las_with_float_extra(tmp_path / "scan.las")
    assert run("decompose", str(tmp_path / "scan.las"), "-o", str(tmp_path / "d"), "--levels", "3").returncode == 0
    source = tmp_path / "d" / "source.npz"
    arrays = dict(np.load(source))
    meta = json.loads(bytes(arrays["meta_json"]))
    edit(meta)
    arrays["meta_json"] = np.frombuffer(json.dumps(meta).encode(), np.uint8).copy()
    np.savez(source, **arrays)
    error = one_line_error(run("reconstruct", str(tmp_path / "d"), "-o", str(tmp_path / "out.las")))
    assert message in error
    assert not (tmp_path / "out.las").exists()


def test_unedited_format_details_still_write_every_value(tmp_path):
    laspy = pytest.importorskip("laspy")
    las_with_float_extra(tmp_path / "scan.las")
    assert run("decompose", str(tmp_path / "scan.las"), "-o", str(tmp_path / "d"), "--levels", "3").returncode == 0
    assert run("reconstruct", str(tmp_path / "d"), "-o", str(tmp_path / "out.las")).returncode == 0
    assert np.array_equal(laspy.read(str(tmp_path / "out.las")).reflectance, laspy.read(str(tmp_path / "scan.las")).reflectance)


@pytest.mark.parametrize("text", [False, True])
def test_a_ply_whose_coordinates_are_lists_is_named_in_the_error(tmp_path, text):
    """Before: 'setting an array element with a sequence', naming neither file nor property."""
    lengths = np.full(50, 1)
    lengths[7] = 2
    x = np.empty(50, dtype=object)
    x[:] = [np.arange(k, dtype="f8") for k in lengths]
    v = np.empty(50, dtype=[("x", object), ("y", "f8"), ("z", "f8")])
    v["x"], v["y"], v["z"] = x, np.arange(50.0), np.arange(50.0) ** 2
    element = PlyElement.describe(v, "vertex", len_types={"x": "u1"}, val_types={"x": "f8"})
    PlyData([element], text=text).write(str(tmp_path / "x.ply"))
    with pytest.raises(ValueError, match="x.ply: vertex property x is a list"):
        ps.io.read(tmp_path / "x.ply")


def test_load_of_no_path_and_faces_of_huge_unsigned_indices_are_value_errors():
    with pytest.raises(ValueError, match="needs the path of a decomposition file, got NoneType"):
        ps.load(None)
    with pytest.raises(ValueError, match="faces must hold vertex indices, got 9223372036854775808"):
        ps.decompose(ps.shapes.sphere(3000), faces=np.array([[0, 1, 2**63]], dtype=np.uint64))


def ply_with_normals(path, dtype="f4"):
    p = ps.shapes.bumpy_sphere(6000)
    rng = np.random.default_rng(8)
    n = p / np.linalg.norm(p, axis=1)[:, None] + 0.3 * rng.normal(size=p.shape)  # a scanner's own, noisy
    n /= np.linalg.norm(n, axis=1)[:, None]
    v = np.empty(len(p), dtype=[(c, "f8") for c in "xyz"] + [(c, dtype) for c in ("nx", "ny", "nz")])
    for i, c in enumerate("xyz"):
        v[c] = p[:, i]
    for i, c in enumerate(("nx", "ny", "nz")):
        v[c] = n[:, i]
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))
    return n.astype(dtype)


def test_the_inputs_own_normals_come_back_in_the_finest_level_and_a_unit_gain_result(tmp_path):
    """Before, the finest level and reconstruct at unit gains carried recomputed normals, up to
    60 degrees off a scanner's own, and no output kept the file's."""
    given = ply_with_normals(tmp_path / "in.ply")
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "d"), "--levels", "3").returncode == 0
    assert run("reconstruct", str(tmp_path / "d"), "-o", str(tmp_path / "same.ply")).returncode == 0
    assert run("reconstruct", str(tmp_path / "d"), "-o", str(tmp_path / "ones.ply"), "--gains", "1,1").returncode == 0
    for name in ("d/level_2.ply", "same.ply", "ones.ply"):
        assert np.array_equal(ps.io.read(tmp_path / name).normals.astype(np.float32), given), name
    # A filtered result is another surface: its normals are its own.
    assert run("reconstruct", str(tmp_path / "d"), "-o", str(tmp_path / "f.ply"), "--gains", "0,2").returncode == 0
    assert not np.array_equal(ps.io.read(tmp_path / "f.ply").normals.astype(np.float32), given)


def test_normals_set_aside_by_estimate_normals_are_not_written_back(tmp_path):
    given = ply_with_normals(tmp_path / "in.ply")
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "d"), "--levels", "3",
               "--estimate-normals").returncode == 0
    finest = ps.io.read(tmp_path / "d" / "level_2.ply").normals.astype(np.float32)
    assert not np.array_equal(finest, given)
    assert "normals" not in np.load(tmp_path / "d" / "source.npz").files


def ply_with_header_text(path, text: bool, comment: bytes, faces=None):
    """A PLY whose header has `comment` as raw bytes (plyfile itself writes ASCII only)."""
    p = ps.shapes.bumpy_sphere(500)
    v = np.empty(len(p), dtype=[(c, "f8") for c in "xyz"])
    v["x"], v["y"], v["z"] = p.T
    elements = [PlyElement.describe(v, "vertex")]
    if faces is not None:
        f = np.empty(len(faces), dtype=[("vertex_indices", object)])
        f["vertex_indices"] = [np.asarray(x, dtype="i4") for x in faces]
        elements.append(PlyElement.describe(f, "face"))
    PlyData(elements, text=text, comments=["X" * len(comment)], obj_info=["Y" * len(comment)]).write(str(path))
    raw = path.read_bytes()
    raw = raw.replace(b"comment " + b"X" * len(comment), b"comment " + comment, 1)
    path.write_bytes(raw.replace(b"obj_info " + b"Y" * len(comment), b"obj_info " + comment, 1))
    return p


@pytest.mark.parametrize("text", [False, True])
@pytest.mark.parametrize("comment, shown", [("café Zürich".encode(), "café Zürich"),
                                            ("Zürich".encode("latin-1"), "Zürich")])
@pytest.mark.parametrize("polygons", [False, True])
def test_comments_beyond_ascii_are_read_and_written_back(tmp_path, text, comment, shown, polygons):
    """MeshLab writes a texture's file name into a comment as it is. Before: 'not a readable PLY
    file (UnicodeDecodeError ...)'. Mixed triangles and quads take plyfile's own writer."""
    faces = [[0, 1, 2], [2, 3, 4, 5]] if polygons else None
    points = ply_with_header_text(tmp_path / "in.ply", text, comment, faces)
    scan = ps.io.read(tmp_path / "in.ply")
    assert scan.format_info["comments"] == [shown] and scan.format_info["obj_info"] == [shown]
    assert np.array_equal(scan.points, points)
    ps.io.write(tmp_path / "out.ply", scan)
    again = ps.io.read(tmp_path / "out.ply")
    assert again.format_info["comments"] == [shown] and np.array_equal(again.points, points)
    assert (b"comment " + shown.encode("utf-8")) in (tmp_path / "out.ply").read_bytes()[:400]
    if polygons:
        assert [list(f) for f in again.faces] == faces


def test_bytes_beyond_ascii_outside_a_comment_are_a_damaged_header(tmp_path):
    ply_with_header_text(tmp_path / "in.ply", True, b"ok")
    raw = (tmp_path / "in.ply").read_bytes().replace(b"property double z", "property double é".encode())
    (tmp_path / "in.ply").write_bytes(raw)
    with pytest.raises(ValueError, match="in.ply: PLY header line .* is not ASCII text"):
        ps.io.read(tmp_path / "in.ply")


@pytest.mark.parametrize("newline", [b"\r", b"\r\n"])
@pytest.mark.parametrize("comment", ["plain", "café", "not the end_header"])
def test_headers_ending_lines_in_cr_or_crlf_keep_the_data_after_them(tmp_path, newline, comment):
    """A reviewer's cases: a CR-only header was cut at the first LF in the binary data after it,
    and an end_header inside a comment cut the header short. Bytes from 200 up right after the
    header show that the data is read where it is."""
    v = np.zeros(50, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("q", "u1")])
    rng = np.random.default_rng(1)
    for c in "xyz":
        v[c] = rng.normal(size=50)
    v["q"] = 200 + np.arange(50) % 50
    path = tmp_path / "in.ply"
    PlyData([PlyElement.describe(v, "vertex")], comments=["X" * len(comment.encode())]).write(str(path))
    raw = path.read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    header = raw[:end].replace(b"X" * len(comment.encode()), comment.encode()).replace(b"\n", newline)
    path.write_bytes(header + raw[end:])
    scan = ps.io.read(path)
    assert scan.format_info["comments"] == [comment]
    assert np.array_equal(scan.vertex_attributes["q"], v["q"]) and np.array_equal(scan.points[:, 0], v["x"].astype(float))


def test_scaled_extra_bytes_at_the_limit_of_their_type_are_written(tmp_path):
    """(2.55 - 0) / 0.01 is 255.00000000000003: the range check must round as LAS stores."""
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.4")
    header.add_extra_dim(laspy.ExtraBytesParams(name="level", type=np.uint8, scales=np.array([0.01]),
                                                offsets=np.array([0.0])))
    las = laspy.LasData(header)
    p = ps.shapes.sphere(2000)
    las.x, las.y, las.z = p.T
    las.level = np.where(np.arange(2000) % 2 == 0, 0.0, 2.55)
    las.write(str(tmp_path / "in.las"))
    scan = ps.io.read(tmp_path / "in.las")
    ps.io.write(tmp_path / "out.las", scan)
    assert np.array_equal(laspy.read(str(tmp_path / "out.las")).points["level"], laspy.read(str(tmp_path / "in.las")).points["level"])


def test_an_output_replaced_keeps_its_name_until_the_new_file_takes_it(tmp_path, monkeypatch):
    """The earlier file gets a second name (a hard link) rather than being renamed away, so a
    reader, or a crash, between the two steps still finds a whole file at its name."""
    (tmp_path / "a.ply").write_text("old")
    stage = staged_output.StagedOutput()
    stage.temporary(tmp_path / "a.ply").write_text("new")
    real, seen = os.replace, []

    def replace(src, dst):
        seen.append(os.path.exists(dst))
        return real(src, dst)

    monkeypatch.setattr(staged_output.os, "replace", replace)
    stage.commit()
    assert seen == [True] and (tmp_path / "a.ply").read_text() == "new"
    assert os.listdir(tmp_path) == ["a.ply"]


def test_an_output_that_cannot_be_set_aside_leaves_nothing_behind(tmp_path, monkeypatch):
    (tmp_path / "a.ply").write_text("old")
    stage = staged_output.StagedOutput()
    stage.temporary(tmp_path / "a.ply").write_text("new")

    def refuse(*args, **kwargs):
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(staged_output.os, "link", refuse)
    monkeypatch.setattr(staged_output.os, "replace", refuse)
    with pytest.raises(PermissionError):
        with stage:
            stage.commit()
    assert os.listdir(tmp_path) == ["a.ply"] and (tmp_path / "a.ply").read_text() == "old"


def test_a_file_that_cannot_be_put_back_is_named_with_where_it_is_kept(tmp_path, monkeypatch):
    for name in ("a.ply", "b.ply"):
        (tmp_path / name).write_text("old " + name)
    stage = staged_output.StagedOutput()
    for name in ("a.ply", "b.ply"):
        stage.temporary(tmp_path / name).write_text("new " + name)
    real = os.replace

    def replace(src, dst):
        if ".part" in str(src) and str(dst).endswith("b.ply"):
            raise OSError(5, "Input/output error")      # the second output fails ...
        if ".old" in str(src):
            raise OSError(5, "Input/output error")      # ... and so does putting the first back
        return real(src, dst)

    monkeypatch.setattr(staged_output.os, "replace", replace)
    with pytest.raises(OSError, match=r"could not put back .*a.ply: .*kept as .*\.a\..*\.old\.ply"):
        with stage:
            stage.commit()
