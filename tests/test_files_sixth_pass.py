"""Files, sixth pass (2026-12-07): comment lines above a PTS file's count line."""
import warnings

import numpy as np
import pytest

from pointscale import io
from helpers import run_cli


def _write_pts(path, blocks, comments):
    rng = np.random.default_rng(len(blocks))
    with open(path, "w") as f:
        for c in comments:
            f.write(f"{c}\n")
        rows = []
        for count in blocks:
            block = np.c_[rng.uniform(-5, 5, (count, 3)) + [500000.0, 4000000.0, 120.0],
                          rng.integers(-2048, 2048, count), rng.integers(0, 256, (count, 3))]
            f.write(f"{count}\n")
            for r in block:
                f.write(f"{r[0]:.17g} {r[1]:.17g} {r[2]:.17g} {int(r[3])} {int(r[4])} {int(r[5])} {int(r[6])}\n")
            rows.append(block)
    return np.concatenate(rows)


@pytest.mark.parametrize("blocks", [[700], [400, 250, 90]])
def test_pts_comment_lines_are_read_and_kept_into_xyz_and_ply(tmp_path, blocks):
    """A .pts with a CRS line above its count was refused as 'the number of columns changed
    from 1 to 7' (NumPy's words, with its advice on `usecols`)."""
    comments = ["// CRS: EPSG:25832", "# scanner: P50, station 3"]
    rows = _write_pts(tmp_path / "scan.pts", blocks, comments)
    scan = io.read(tmp_path / "scan.pts")
    assert np.array_equal(scan.points, rows[:, :3])
    assert np.array_equal(scan.vertex_attributes["intensity"], rows[:, 3].astype(int))
    assert scan.format_info["comments"] == ["CRS: EPSG:25832", "scanner: P50, station 3"]
    if len(blocks) > 1:
        assert np.array_equal(np.bincount(scan.vertex_attributes["scan_id"]), blocks)
    for suffix in (".xyz", ".ply"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # nothing is said to be left out
            io.write(tmp_path / f"out{suffix}", scan)
        back = io.read(tmp_path / f"out{suffix}")
        assert back.format_info["comments"] == scan.format_info["comments"], suffix
        assert np.array_equal(back.points, scan.points)
    with pytest.warns(UserWarning, match="no place for the input's comment lines; 2 not written"):
        io.write(tmp_path / "out.pts", scan)  # Leica's readers take no comment lines
    assert "comments" not in io.read(tmp_path / "out.pts").format_info


def test_pts_comments_survive_the_command_line(tmp_path):
    _write_pts(tmp_path / "scan.pts", [3000], ["# CRS: EPSG:32633"])
    done = run_cli("decompose", str(tmp_path / "scan.pts"), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    done = run_cli("reconstruct", str(tmp_path / "out"), "--gains", "1,2", "-o", str(tmp_path / "boosted.xyz"))
    assert done.returncode == 0, done.stderr
    assert io.read(tmp_path / "boosted.xyz").format_info["comments"] == ["CRS: EPSG:32633"]


def test_a_pts_count_line_that_disagrees_is_still_refused_after_comments(tmp_path):
    _write_pts(tmp_path / "scan.pts", [500], ["# a comment"])
    text = (tmp_path / "scan.pts").read_text().replace("\n500\n", "\n600\n", 1)
    (tmp_path / "scan.pts").write_text(text)
    with pytest.raises(ValueError, match="says 600 points, the file has 500"):
        io.read(tmp_path / "scan.pts")


@pytest.mark.parametrize("above", [["# EPSG:25832"], ["// exported by a scanner", "# CRS: EPSG:32633"]])
def test_an_xyz_header_below_other_comment_lines_names_the_columns(tmp_path, above):
    """'# EPSG:25832' above '//X Y Z R G B Nx Ny Nz': the header was taken for a plain comment,
    the colours and normals became float64 column_3 .. column_8, and decompose estimated normals
    of its own."""
    rng = np.random.default_rng(7)
    points = rng.uniform(-3, 3, (900, 3)) + [300000.0, 5000000.0, 40.0]
    normals = rng.normal(size=(900, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    colours = rng.integers(0, 256, (900, 3))
    path = tmp_path / "cloud.xyz"
    with open(path, "w") as f:
        f.write("\n".join(above) + "\n//X Y Z R G B Nx Ny Nz\n")
        for p, c, n in zip(points, colours, normals):
            f.write(f"{p[0]:.17g} {p[1]:.17g} {p[2]:.17g} {c[0]} {c[1]} {c[2]} {n[0]:.17g} {n[1]:.17g} {n[2]:.17g}\n")
    scan = io.read(path)
    assert np.array_equal(scan.points, points) and np.array_equal(scan.normals, normals)
    assert sorted(scan.vertex_attributes) == ["blue", "green", "red"]
    assert scan.vertex_attributes["red"].dtype == np.uint8
    assert scan.format_info["comments"] == [line.lstrip("#/ ") for line in above]
    io.write(tmp_path / "back.xyz", scan)
    again = io.read(tmp_path / "back.xyz")
    assert again.format_info["comments"] == scan.format_info["comments"]
    assert np.array_equal(again.vertex_attributes["green"], scan.vertex_attributes["green"])


@pytest.mark.parametrize("ids", ["halves swapped", "interleaved"])
def test_e57_level_files_of_interleaved_scans_come_back_in_order_as_base(tmp_path, ids):
    """An input whose scan_id runs 1 then 0, or interleaves scans, got E57 level files listed
    scan by scan; handed back unedited as --base they paired each point with another's detail
    (median error 17 on a sphere of radius 10), without a word."""
    pytest.importorskip("pye57")
    rng = np.random.default_rng(11)
    d = rng.normal(size=(7000, 3))
    points = d / np.linalg.norm(d, axis=1)[:, None] * [8.0, 5.0, 6.0] + [1000.0, 2000.0, 30.0]
    n = len(points)
    scan_id = (np.arange(n) < n // 2).astype(np.uint16) if ids == "halves swapped" else (np.arange(n) % 3).astype(np.uint16)
    io.write(tmp_path / "scans.ply", io.Scan(points=points, vertex_attributes={"scan_id": scan_id}))
    done = run_cli("decompose", str(tmp_path / "scans.ply"), "-o", str(tmp_path / "dec"), "--levels", "3",
                   "--format", ".e57")
    assert done.returncode == 0, done.stderr
    assert "lists them scan by scan" in done.stderr
    done = run_cli("reconstruct", str(tmp_path / "dec"), "--base", str(tmp_path / "dec" / "level_0.e57"),
                   "-o", str(tmp_path / "back.ply"))
    assert done.returncode == 0, done.stderr
    back = io.read(tmp_path / "back.ply").points
    # E57 stores float32 coordinates about each scan's centre: the base comes back to ~1e-6.
    assert np.abs(back - points).max() < 1e-4


def test_obj_negative_indices_count_back_from_the_lines_above_the_face(tmp_path):
    """Relative indices (f -3 -2 -1 after each object's own v lines, as exporters writing object
    by object do) counted back from the end of the file: both triangles became [3, 4, 5]."""
    text = ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf -3/-3/-1 -2/-2/-1 -1/-1/-1\n"
            "v 5 0 0\nv 6 0 0\nv 5 1 0\nv 5 1 1\nvt 0.5 0.5\nvt 1 1\nvt 0 0.5\nvt 0.2 0.2\nvn 1 0 0\n"
            "f -4/-4/-1 -3/-3/-1 -2/-2/-1 -1/-1/-1\nf 1 2 -1\n")
    (tmp_path / "relative.obj").write_text(text.replace("f 1 2 -1\n", ""))
    scan = io.read(tmp_path / "relative.obj")
    assert [list(f) for f in scan.faces] == [[0, 1, 2], [3, 4, 5, 6]]
    assert np.array_equal(scan.normals, [[0, 0, 1]] * 3 + [[1, 0, 0]] * 4)
    assert np.array_equal(scan.vertex_attributes["texture_u"], [0, 1, 0, 0.5, 1, 0, 0.2])
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n")
    with pytest.raises(ValueError, match=r"vertex -3, outside 1..3 \(or -2..-1, counted back from the vertices above"):
        io.read(tmp_path / "bad.obj")


@pytest.mark.parametrize("offset, said", [((300000.0, 5000000.0, 40.0), True), ((0.0, 0.0, 0.0), False)])
def test_a_single_precision_base_of_a_far_off_model_is_warned_of(tmp_path, offset, said):
    """level_0 re-saved as float32 (what MeshLab and Blender write) of a georeferenced cloud was
    taken without a word, and moved the result by 0.09-0.15 on a model of radius 10."""
    rng = np.random.default_rng(2)
    d = rng.normal(size=(6000, 3))
    points = d / np.linalg.norm(d, axis=1)[:, None] * [6.0, 4.0, 3.0] + offset
    io.write(tmp_path / "cloud.ply", io.Scan(points=points))
    assert run_cli("decompose", str(tmp_path / "cloud.ply"), "-o", str(tmp_path / "dec"), "--levels", "3").returncode == 0
    level0 = io.read(tmp_path / "dec" / "level_0.ply")
    edited = level0.points.copy()
    edited[:50, 2] += 0.5
    for precision, name in ((np.float32, "single.ply"), (np.float64, "double.ply")):
        io.write(tmp_path / name, io.Scan(points=edited, precision=precision))
        done = run_cli("reconstruct", str(tmp_path / "dec"), "--base", str(tmp_path / name), "-o",
                       str(tmp_path / f"out_{name}"))
        assert done.returncode == 0, done.stderr
        warned = "its 50 edited vertices are rounded by float32" in done.stderr
        assert warned == (said and precision == np.float32), (name, done.stderr)
    # Unedited, in float32: taken at full precision, so the result is the input, and nothing is said.
    io.write(tmp_path / "unedited.ply", io.Scan(points=level0.points, precision=np.float32))
    done = run_cli("reconstruct", str(tmp_path / "dec"), "--base", str(tmp_path / "unedited.ply"), "-o",
                   str(tmp_path / "out.ply"))
    assert done.returncode == 0 and "float32" not in done.stderr, done.stderr
    assert np.abs(io.read(tmp_path / "out.ply").points - points).max() < 1e-9


def test_cloudcompare_field_names_fill_the_standard_las_fields(tmp_path):
    """'//X Y Z Intensity Classification ReturnNumber' went to extra bytes of those names, and
    the LAS intensity and classification a reader shows were all 0, without a word."""
    laspy = pytest.importorskip("laspy")
    rng = np.random.default_rng(3)
    points = rng.uniform(0, 50, (800, 3)) + [600000.0, 4500000.0, 0.0]
    intensity, classes, returns = rng.integers(0, 65536, 800), rng.integers(0, 32, 800), rng.integers(1, 6, 800)
    with open(tmp_path / "cc.xyz", "w") as f:
        f.write("//X Y Z Intensity Classification Return_Number Own_Field\n")
        for p, i, c, r in zip(points, intensity, classes, returns):
            f.write(f"{p[0]:.3f} {p[1]:.3f} {p[2]:.3f} {i} {c} {r} 0.5\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        io.write(tmp_path / "out.las", io.read(tmp_path / "cc.xyz"))
    las = laspy.read(tmp_path / "out.las")
    assert np.array_equal(las.intensity, intensity) and np.array_equal(las.classification, classes)
    assert np.array_equal(las.return_number, returns)
    assert list(las.point_format.extra_dimension_names) == ["Own_Field"]


def test_small_file_cases_after_a_review(tmp_path):
    """A header below a CRS line naming more columns than the rows have was dropped without a
    word; a comment above a later PTS block's count was refused in NumPy's words, and a bare '#'
    kept as an empty comment; an OBJ face above every v line was told '-0..-1'."""
    (tmp_path / "h.xyz").write_text("# EPSG:25832\n//X Y Z GPS Time\n0 0 0 1\n1 0 0 2\n0 1 0 3\n")
    with pytest.warns(UserWarning, match="the header line names 5 columns but the rows have 4"):
        io.read(tmp_path / "h.xyz")
    (tmp_path / "e.pts").write_text("# site A\n2\n0 0 0\n1 0 0\n#\n// station 2\n3\n0 1 0\n1 1 0\n0 0 1\n")
    scan = io.read(tmp_path / "e.pts")
    assert scan.format_info["comments"] == ["site A", "station 2"]
    assert np.array_equal(scan.vertex_attributes["scan_id"], [0, 0, 1, 1, 1])
    (tmp_path / "o.obj").write_text("f -1 -2 -3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n")
    with pytest.raises(ValueError, match="outside 1..3; no vertices stand above the face to count back from"):
        io.read(tmp_path / "o.obj")


def test_a_float_intensity_stays_extra_bytes_of_its_own_name(tmp_path):
    """A scanner's Intensity of 0..1 does not fit LAS's uint16 field: it was renamed to
    'intensity' anyway and kept as extra bytes 'intensity_value', a name the input never had."""
    laspy = pytest.importorskip("laspy")
    rng = np.random.default_rng(1)
    scan = io.Scan(points=rng.uniform(0, 10, (300, 3)), vertex_attributes={"Intensity": rng.random(300)})
    io.write(tmp_path / "out.las", scan)
    las = laspy.read(tmp_path / "out.las")
    assert list(las.point_format.extra_dimension_names) == ["Intensity"]
    assert np.array_equal(las["Intensity"], scan.vertex_attributes["Intensity"])


def test_obj_comment_lines_are_kept(tmp_path):
    """An OBJ's own '#' lines (the exporter, a unit, a CRS) were dropped without a word."""
    (tmp_path / "in.obj").write_text("# Blender 4.5 exporter\n# units: metres\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                     "# a comment between\nf 1 2 3\n")
    scan = io.read(tmp_path / "in.obj")
    assert scan.format_info["comments"] == ["Blender 4.5 exporter", "units: metres", "a comment between"]
    for suffix in (".obj", ".ply", ".xyz"):
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            io.write(tmp_path / f"out{suffix}", scan)
        assert not [w for w in said if "comment lines" in str(w.message)], suffix
        assert io.read(tmp_path / f"out{suffix}").format_info["comments"] == scan.format_info["comments"], suffix
    with pytest.warns(UserWarning, match="3 not written"):
        io.write(tmp_path / "out.stl", scan)
