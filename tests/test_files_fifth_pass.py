"""Files, after a fifth reader's pass (trial, 2026-12-07): CloudCompare's XYZ with normals after
the colours, a header whose column name holds a space, and E57 files of several stations."""
import os
import stat
import warnings

import numpy as np
import pytest

import pointscale as ps
from pointscale import io


def _plane(n, seed=0):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 10, (n, 2))
    return np.c_[xy, 0.3 * np.sin(xy[:, 0]) + 0.1 * np.cos(1.7 * xy[:, 1])]


@pytest.mark.parametrize("order", [("rgb", "normals"), ("normals", "rgb"), ("rgb", "sf", "normals")])
def test_xyz_normals_are_read_wherever_the_header_puts_them(tmp_path, order):
    """CloudCompare writes normals after the colours and scalar fields: they were read as plain
    attributes nx ny nz, and decompose estimated its own normals (facing +z where the file's
    faced -z)."""
    points = _plane(1500)
    down = np.tile([0.0, 0.0, -1.0], (len(points), 1))
    rgb = np.random.default_rng(1).integers(0, 256, (len(points), 3))
    sf = np.arange(len(points)) * 0.5
    blocks = {"rgb": (rgb, "R G B"), "normals": (down, "Nx Ny Nz"), "sf": (sf[:, None], "Intensity")}
    path = tmp_path / "cloud.xyz"
    np.savetxt(path, np.c_[(points,) + tuple(blocks[b][0] for b in order)], fmt="%.6f",
               header="X Y Z " + " ".join(blocks[b][1] for b in order), comments="//")
    scan = io.read(path)
    assert scan.normals is not None and np.array_equal(scan.normals, down)
    assert not {"nx", "ny", "nz"} & set(scan.vertex_attributes)
    assert [scan.vertex_attributes[c].dtype for c in ("red", "green", "blue")] == [np.uint8] * 3
    dec = ps.decompose(scan.points, levels=3, normals=scan.normals)
    assert (dec.normals(0)[:, 2] < 0).all()  # the file's side, as with the normals first


def _coloured_with_gps_time(path, header):
    """An XYZ file of x y z, R G B and a GPS time column under the header line given."""
    points = _plane(500)
    rgb = np.random.default_rng(2).integers(0, 256, (len(points), 3))
    np.savetxt(path, np.c_[points, rgb, 3e8 + np.arange(len(points))], fmt="%.6f", header=header, comments="//")


def test_a_header_with_a_name_holding_a_space_is_said_to_be_unused(tmp_path):
    """'//X Y Z R G B GPS Time' names 8 columns for 7: every name was dropped, silently."""
    _coloured_with_gps_time(tmp_path / "spaced.xyz", "X Y Z R G B GPS Time")
    with pytest.warns(UserWarning, match="names 8 columns but the rows have 7.*a column name with a space"):
        io.read(tmp_path / "spaced.xyz")


def test_comma_parted_names_may_hold_spaces(tmp_path):
    _coloured_with_gps_time(tmp_path / "commas.xyz", "X,Y,Z,R,G,B,GPS Time")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scan = io.read(tmp_path / "commas.xyz")
    assert set(scan.vertex_attributes) == {"red", "green", "blue", "GPS_Time"}
    assert scan.vertex_attributes["red"].dtype == np.uint8


def _quaternion(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    half = np.radians(degrees) / 2
    return np.r_[np.cos(half), np.sin(half) * axis]


STATIONS = [("north", _quaternion([0, 0, 1], 30.0), [500000.0, 4000000.0, 100.0]),
            ("south", _quaternion([1, 2, 3], 75.0), [500040.0, 3999990.0, 102.5]),
            ("roof", [1.0, 0.0, 0.0, 0.0], [500020.0, 4000020.0, 130.0])]


def _stations_file(path, pye57, sizes):
    rng = np.random.default_rng(4)
    e57 = pye57.E57(str(path), mode="w")
    local = []
    for (name, rotation, translation), n in zip(STATIONS, sizes):
        q = _plane(n, seed=len(local)) - 5.0
        local.append(q)
        e57.write_scan_raw({"cartesianX": q[:, 0], "cartesianY": q[:, 1], "cartesianZ": q[:, 2],
                            "intensity": rng.random(n), "rowIndex": np.arange(n) // 40,
                            "columnIndex": np.arange(n) % 40},
                           name=name, rotation=np.asarray(rotation, float), translation=np.asarray(translation))
    e57.close()
    return local


def test_an_e57_of_several_stations_is_written_back_station_by_station(tmp_path):
    """Three stations came back as one scan: names and poses gone, and their row and column
    indices on top of each other (one grid cell for two or three points)."""
    pye57 = pytest.importorskip("pye57")
    sizes = (1200, 900, 700)
    local = _stations_file(tmp_path / "stations.e57", pye57, sizes)
    scan = io.read(tmp_path / "stations.e57")
    assert scan.n_points == sum(sizes)
    # A filter's output: the world points moved a little, written as E57 again.
    moved = scan.with_geometry(scan.points + [0.0, 0.0, 0.01])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # scan_id is written, as the scans
        io.write(tmp_path / "out.e57", moved)
    e57 = pye57.E57(str(tmp_path / "out.e57"))
    assert e57.scan_count == 3
    for i, ((name, rotation, translation), q) in enumerate(zip(STATIONS, local)):
        header = e57.get_header(i)
        raw = e57.read_scan_raw(i)
        assert header["name"].value() == name
        assert np.allclose(header.translation, translation) and np.allclose(header.rotation, rotation)
        # In the station's own frame, as before (moved 0.01 along world z), to float32.
        got = np.c_[raw["cartesianX"], raw["cartesianY"], raw["cartesianZ"]]
        up = np.asarray(header.rotation_matrix).T @ [0.0, 0.0, 0.01]
        assert np.abs(got - (q + up)).max() < 1e-5
        assert len(np.unique(np.c_[raw["rowIndex"], raw["columnIndex"]], axis=0)) == len(q)
    e57.close()
    again = io.read(tmp_path / "out.e57")
    assert np.abs(again.points - moved.points).max() < 1e-5
    assert np.array_equal(again.vertex_attributes["scan_id"], scan.vertex_attributes["scan_id"])


def test_an_edited_station_pose_in_a_shared_folder_is_refused(tmp_path):
    """The writer puts the points back in each station's frame: a pose a shared folder's
    source.npz was edited to hold is checked before any writer uses it."""
    pytest.importorskip("pye57")
    from pointscale.io.format_info import check_format_info
    for bad in ({"name": "a", "rotation": [0, 0, 0, 0], "translation": [0, 0, 0]},
                {"name": "a\nb", "rotation": [1, 0, 0, 0], "translation": [0, 0, 0]},
                {"name": "a", "rotation": [1, 0, 0, 0], "translation": [0, float("nan"), 0]}):
        with pytest.raises(ValueError, match="stations must be a list of scans"):
            check_format_info({"format": "e57", "stations": [bad]}, 10)


def test_xyz_comment_lines_are_kept_into_xyz_and_ply_and_said_lost_elsewhere(tmp_path):
    """'# EPSG:32633 ...' at the top of an XYZ file vanished from every level file and output,
    and a PLY header's comments from XYZ and LAS outputs, unsaid."""
    path = tmp_path / "georef.xyz"
    with open(path, "w") as f:
        f.write("//X Y Z Intensity\n# EPSG:32633 WGS 84 / UTM zone 33N\n// scanner: RTC360, 2026-11-02\n")
        np.savetxt(f, np.c_[_plane(600) + [500000.0, 4000000.0, 0.0], np.arange(600)], fmt="%.6f")
    scan = io.read(path)
    lines = ["EPSG:32633 WGS 84 / UTM zone 33N", "scanner: RTC360, 2026-11-02"]
    assert scan.format_info["comments"] == lines and list(scan.vertex_attributes) == ["Intensity"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        io.write(tmp_path / "back.xyz", scan)
        io.write(tmp_path / "back.ply", scan)
    again = io.read(tmp_path / "back.xyz")
    assert again.format_info["comments"] == lines and np.array_equal(again.points, scan.points)
    ply = io.read(tmp_path / "back.ply")
    assert ply.format_info["comments"] == lines
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        io.write(tmp_path / "from_ply.xyz", ply)
    assert io.read(tmp_path / "from_ply.xyz").format_info["comments"] == lines
    with pytest.warns(UserWarning, match=r"\.pts has no place for the input's comment lines; 2 not written.*EPSG"):
        io.write(tmp_path / "out.pts", ply)


def test_an_unreadable_xyz_says_what_it_needs(tmp_path):
    path = tmp_path / "odd.xyz"
    np.savetxt(path, _plane(50), fmt="%.4f", header="X Y Z", comments="")
    with pytest.raises(ValueError, match="must start with # or //"):
        io.read(path)
    # a decimal comma, values parted by semicolons (as spreadsheets in many languages write)
    path.write_text("".join(";".join(f"{v:.4f}".replace(".", ",") for v in row) + "\n" for row in _plane(50)))
    with pytest.raises(ValueError, match="need a decimal point"):
        io.read(path)


@pytest.mark.parametrize("delimiter", [",", ";", "\t"])
def test_an_xyz_parted_by_commas_semicolons_or_tabs_reads_as_parted_by_spaces(tmp_path, delimiter):
    """CloudCompare's ASCII export offers space, comma, semicolon and tab as separators."""
    points = _plane(50)
    np.savetxt(tmp_path / "spaces.xyz", points, fmt="%.17g")
    np.savetxt(tmp_path / "other.xyz", points, delimiter=delimiter, fmt="%.17g")
    assert np.array_equal(io.read(tmp_path / "other.xyz").points, io.read(tmp_path / "spaces.xyz").points)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_pipe_or_a_link_to_one_is_never_written_over(tmp_path):
    """A write goes to a temporary file renamed over the path: a named pipe or a device there
    became a plain file (as root, save('/dev/null') replaced /dev/null)."""
    dec = ps.decompose(ps.shapes.bumpy_sphere(2000), levels=2)
    scan = io.Scan(points=_plane(300))
    pipe = tmp_path / "pipe.ply"
    os.mkfifo(pipe)
    link = tmp_path / "link.ply"
    link.symlink_to(pipe)
    for target in (pipe, link):
        with pytest.raises(ValueError, match="not a regular file"):
            dec.save(target)
        with pytest.raises(ValueError, match="not a regular file"):
            io.write(target, scan)
        assert stat.S_ISFIFO(os.stat(pipe).st_mode)
    assert link.is_symlink()


def test_a_decompositions_exported_origin_is_its_own_copy():
    """to_dict()['origin'] was the decomposition's own array: editing the export moved every
    later reconstruct; from_dict kept the caller's array the same way."""
    dec = ps.decompose(ps.shapes.bumpy_sphere(3000), levels=3)
    before = ps.reconstruct(dec)
    exported = dec.to_dict()
    exported["origin"] += 10.0
    assert np.array_equal(ps.reconstruct(dec), before)
    arrays = dec.to_dict()
    again = ps.Decomposition.from_dict(arrays)
    arrays["origin"] += 10.0
    assert np.array_equal(ps.reconstruct(again), before)
