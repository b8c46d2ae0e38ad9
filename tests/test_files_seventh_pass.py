"""Files, seventh pass: a scan technician's findings on float colours and intensities in LAS,
coordinate systems written to other formats, empty vertex lists in ASCII PLY, OBJ faces of
different corner forms, and source.npz from another decomposition."""
import warnings

import numpy as np
import pytest

from pointscale import io
from pointscale.io.scan import Scan
from helpers import run_cli, one_line_error


def _cloud(n=1000, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0, 10, (n, 3)) + [500000.0, 5000000.0, 100.0]


def test_float_colours_and_intensity_of_0_to_1_fill_las_16_bit_fields(tmp_path):
    """Float colours 0..1 went black (red and green to extra bytes, blue 1.0 silently to 1 of
    65535), and an E57's float intensity to extra bytes `intensity_value`, leaving `intensity` 0."""
    laspy = pytest.importorskip("laspy")
    n = 1000
    red, green, blue = np.linspace(0, 1, n).astype("f4"), np.full(n, 0.5, "f4"), np.ones(n, "f4")
    intensity = np.linspace(0, 1, n)
    scan = Scan(points=_cloud(n), vertex_attributes={"red": red, "green": green, "blue": blue, "intensity": intensity})
    with pytest.warns(UserWarning) as said:
        io.write(tmp_path / "c.las", scan)
    text = " / ".join(str(w.message) for w in said)
    assert "colours red, green, blue of 0..1" in text and "65535 * value" in text and "intensity of 0..1" in text
    las = laspy.read(tmp_path / "c.las")
    names = list(las.point_format.dimension_names)
    assert not any(name.endswith("_value") for name in names), names
    for name, v in (("red", red), ("green", green), ("blue", blue), ("intensity", intensity)):
        stored = np.asarray(las[name])
        assert stored.dtype == np.uint16
        assert np.abs(stored / 65535.0 - v).max() <= 0.5 / 65535 + 1e-9, name
    assert las.blue.min() == 65535 and las.red.max() == 65535 and las.green[0] == 32768
    # read back and written again: the 16-bit values are kept as they are
    back = io.read(tmp_path / "c.las")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        io.write(tmp_path / "c.ply", back)
    again = io.read(tmp_path / "c.ply")
    for name in ("red", "green", "blue", "intensity"):
        assert np.array_equal(again.vertex_attributes[name], np.asarray(las[name])), name


def test_float_colours_exactly_on_16_bit_steps_are_written_without_a_warning(tmp_path):
    n = 200
    ones = np.ones(n)
    scan = Scan(points=_cloud(n), vertex_attributes={"red": np.r_[np.zeros(100), ones[:100]], "green": ones, "blue": ones})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        io.write(tmp_path / "c.las", scan)
    back = io.read(tmp_path / "c.las")
    assert back.vertex_attributes["red"][:100].max() == 0 and back.vertex_attributes["red"][100:].min() == 65535
    assert back.vertex_attributes["blue"].min() == 65535


def test_float_colours_outside_0_to_1_keep_the_extra_bytes_path(tmp_path):
    n = 300
    red = np.linspace(0, 2.5, n)  # neither 0..1 nor whole numbers
    scan = Scan(points=_cloud(n), vertex_attributes={"red": red, "green": np.full(n, 0.5), "blue": np.ones(n)})
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        io.write(tmp_path / "c.las", scan)
    text = " / ".join(str(w.message) for w in said)
    assert "'red' (float64) does not fit the LAS field; kept as extra bytes 'red_value'" in text, text
    back = io.read(tmp_path / "c.las")
    assert np.array_equal(back.vertex_attributes["red_value"], red)


_WKT = 'PROJCS["ETRS89 / UTM zone 32N",\n  GEOGCS["ETRS89",DATUM["European_Terrestrial_Reference_System_1989"]],\n  UNIT["metre",1]]'


def _georeferenced_las(path, records):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales, header.offsets = np.full(3, 0.001), np.array([500000.0, 5000000.0, 100.0])
    for record_id, data in records:
        header.vlrs.append(laspy.VLR(user_id="LASF_Projection", record_id=record_id, description="crs",
                                     record_data=data))
    las = laspy.LasData(header)
    points = _cloud(500)
    las.x, las.y, las.z = points.T
    las.write(str(path))
    return points


def _geokeys(*entries):
    keys = [1, 1, 0, len(entries)]
    for key, value in entries:
        keys += [key, 0, 1, value]
    return np.array(keys, dtype="<u2").tobytes()


@pytest.mark.parametrize("suffix", [".ply", ".xyz", ".obj", ".txt"])
def test_a_las_wkt_crs_is_written_as_a_comment_line_where_the_format_keeps_them(tmp_path, suffix):
    """A LAS file's coordinate system vanished unsaid when written to PLY, XYZ, OBJ..."""
    _georeferenced_las(tmp_path / "geo.las", [(2112, _WKT.encode() + b"\0")])
    scan = io.read(tmp_path / "geo.las")
    with pytest.warns(UserWarning, match=r"no field for the LAS coordinate system 'ETRS89 / UTM zone 32N'; "
                                         r"written as the comment line 'crs: PROJCS"):
        io.write(tmp_path / f"out{suffix}", scan)
    one_line = "crs: " + " ".join(part.strip() for part in _WKT.splitlines())
    assert io.read(tmp_path / f"out{suffix}").format_info["comments"] == [one_line]


@pytest.mark.parametrize("suffix", [".e57", ".pts", ".off"])
def test_a_las_crs_a_format_cannot_hold_is_named_in_a_warning(tmp_path, suffix):
    if suffix == ".e57":
        pytest.importorskip("pye57")
    _georeferenced_las(tmp_path / "geo.las", [(2112, _WKT.encode() + b"\0")])
    scan = io.read(tmp_path / "geo.las")
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        io.write(tmp_path / f"out{suffix}", scan)
    assert any(f"{suffix} has no place for the LAS coordinate system 'ETRS89 / UTM zone 32N'; not written"
               in str(w.message) for w in said), [str(w.message) for w in said]


def test_geotiff_keys_give_an_epsg_comment_and_las_to_las_keeps_the_records(tmp_path):
    laspy = pytest.importorskip("laspy")
    keys = _geokeys((1024, 1), (3072, 25832), (4096, 5783))
    citation = b"ETRS89 / UTM zone 32N|\0"
    _georeferenced_las(tmp_path / "geo.las", [(34735, keys), (34737, citation)])
    scan = io.read(tmp_path / "geo.las")
    with pytest.warns(UserWarning, match=r"'ETRS89 / UTM zone 32N \(EPSG:25832 \+ EPSG:5783\)'"):
        io.write(tmp_path / "out.ply", scan)
    assert io.read(tmp_path / "out.ply").format_info["comments"] == ["crs: EPSG:25832 + EPSG:5783"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # LAS to LAS: the records as they are, nothing said
        io.write(tmp_path / "out.las", scan)
    records = [(v.user_id, v.record_id, v.record_data_bytes() if hasattr(v, "record_data_bytes") else bytes(v.record_data))
               for v in laspy.read(tmp_path / "out.las").header.vlrs]
    assert ("LASF_Projection", 34735, keys) in records and ("LASF_Projection", 34737, citation) in records


def test_the_crs_reaches_every_level_file_of_decompose_format_ply(tmp_path):
    _georeferenced_las(tmp_path / "geo.las", [(2112, _WKT.encode() + b"\0")])
    done = run_cli("decompose", str(tmp_path / "geo.las"), "-o", str(tmp_path / "out"), "--levels", "3",
                   "--format", ".ply")
    assert done.returncode == 0, done.stderr
    assert "coordinate system 'ETRS89 / UTM zone 32N'" in done.stderr
    for level in range(3):
        comments = io.read(tmp_path / "out" / f"level_{level}.ply").format_info["comments"]
        assert comments[0].startswith('crs: PROJCS["ETRS89 / UTM zone 32N", GEOGCS'), comments
    done = run_cli("reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "back.e57"))
    if done.returncode == 0:
        assert "no place for the LAS coordinate system 'ETRS89 / UTM zone 32N'" in done.stderr


def _ply_with_empty_lists(path, n=400):
    points = _cloud(n, seed=3) - [500000.0, 5000000.0, 100.0]
    with open(path, "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
                "property list uchar int tags\nend_header\n")
        for i, p in enumerate(points):
            f.write(f"{p[0]:.7g} {p[1]:.7g} {p[2]:.7g} {i % 2}{' 7' if i % 2 else ''}\n")
    return points


def test_an_ascii_ply_vertex_list_that_is_sometimes_empty_says_only_our_words(tmp_path):
    """NumPy's 'loadtxt: input contained no data' reached the user for every empty list."""
    points = _ply_with_empty_lists(tmp_path / "tags.ply")
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        scan = io.read(tmp_path / "tags.ply")
    messages = [str(w.message) for w in said]
    assert not any("loadtxt" in m for m in messages), messages
    assert any("vertex property tags has lists of varying length; not kept" in m for m in messages), messages
    assert np.allclose(scan.points, points, atol=1e-5)
    done = run_cli("decompose", str(tmp_path / "tags.ply"), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    assert "loadtxt" not in done.stderr and "varying length" in done.stderr, done.stderr


def _grid_mesh(k=12):
    u, v = np.meshgrid(np.linspace(0, 1, k), np.linspace(0, 1, k), indexing="ij")
    points = np.c_[u.ravel(), v.ravel(), 0.1 * np.sin(3 * u.ravel()) * np.cos(2 * v.ravel())]
    idx = np.arange(k * k).reshape(k, k)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return points, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


def test_an_obj_whose_faces_differ_in_corner_form_is_read_with_the_missing_uvs_filled(tmp_path):
    """'f v/vt' in one group and 'f v' in another (legal OBJ) was refused: 'face corners mix the
    forms v, v/vt, v//vn and v/vt/vn'."""
    points, faces = _grid_mesh()
    textured = faces[:60]
    with open(tmp_path / "mixed.obj", "w") as f:
        for p in points:
            f.write("v %.17g %.17g %.17g\n" % tuple(p))
        for p in points:
            f.write("vt %.17g %.17g\n" % (p[0], p[1]))
        f.write("g textured\n")
        for t in textured + 1:
            f.write("f %d/%d %d/%d %d/%d\n" % (t[0], t[0], t[1], t[1], t[2], t[2]))
        f.write("g plain\n")
        for t in faces[60:] + 1:
            f.write("f %d %d %d\n" % tuple(t))
    lacking = len(points) - len(np.unique(textured))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        scan = io.read(tmp_path / "mixed.obj")
    messages = [str(w.message) for w in said]
    assert any(f"some faces give UVs and others do not; {lacking} of {len(points)} vertices have none, filled with 0"
               in m for m in messages), messages
    assert np.array_equal(scan.faces, faces) and np.array_equal(scan.points, points)
    has = np.zeros(len(points), bool)
    has[textured] = True
    assert np.array_equal(scan.vertex_attributes["texture_u"][has], points[has, 0])
    assert np.array_equal(scan.vertex_attributes["texture_v"][has], points[has, 1])
    assert not scan.vertex_attributes["texture_u"][~has].any()
    done = run_cli("decompose", str(tmp_path / "mixed.obj"), "-o", str(tmp_path / "out"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    assert "filled with 0" in done.stderr and "mix the forms" not in done.stderr


def test_normals_given_by_some_faces_only_and_a_mix_within_one_face(tmp_path):
    points, faces = _grid_mesh(6)
    head = "".join("v %.17g %.17g %.17g\n" % tuple(p) for p in points) + "vn 0 0 1\n"
    body = "".join("f %d//1 %d//1 %d//1\n" % tuple(t) for t in faces[:4] + 1)
    body += "".join("f %d %d %d\n" % tuple(t) for t in faces[4:] + 1)
    (tmp_path / "vn.obj").write_text(head + body)
    with pytest.warns(UserWarning, match="some faces give normals and others do not.*the file's normals are left out"):
        scan = io.read(tmp_path / "vn.obj")
    assert scan.normals is None  # zero normals would be refused by decompose as orientations (a second reader)
    (tmp_path / "one_face.obj").write_text(head + "f 1//1 2 3\n" + body)
    with pytest.raises(ValueError, match="a face's corners mix the forms v, v/vt, v//vn and v/vt/vn"):
        io.read(tmp_path / "one_face.obj")
    (tmp_path / "bad_index.obj").write_text(head + "f 1//2 2//2 3//2\n" + body)
    with pytest.raises(ValueError, match="a face refers to normal 2, outside 1..1"):
        io.read(tmp_path / "bad_index.obj")


def _write_xyz(path, n=2000, seed=5):
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(-1, 1, (2, n))
    points = np.c_[u, v, 0.2 * np.sin(2 * u) * np.cos(3 * v)]
    np.savetxt(path, points, fmt="%.17g")
    return points


def test_format_lists_only_the_level_formats_and_one_file_is_singular(tmp_path):
    _write_xyz(tmp_path / "s.xyz")
    line = one_line_error(run_cli("decompose", str(tmp_path / "s.xyz"), "-o", str(tmp_path / "out"),
                                  "--format", ".ply.gz"))
    assert "unknown extension '.gz'; supported: .ply, .las, .laz, .obj, .off, .stl, .xyz, .pts, .e57" in line, line
    assert ".txt" not in line and ".asc" not in line
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "level_0.xyz").write_text("0 0 0\n")
    line = one_line_error(run_cli("decompose", str(tmp_path / "s.xyz"), "-o", str(tmp_path / "out")))
    assert "already holds a decomposition (1 file, e.g. level_0.xyz)" in line, line
    (tmp_path / "out" / "level_1.xyz").write_text("0 0 0\n")
    line = one_line_error(run_cli("decompose", str(tmp_path / "s.xyz"), "-o", str(tmp_path / "out")))
    assert "already holds a decomposition (2 files, e.g. level_0.xyz)" in line, line


def test_a_full_disk_names_the_file_being_written(tmp_path, monkeypatch, capsys):
    """'error: No space left on device' named no file when NumPy's .npz writer hit a full disk."""
    import errno
    import pointscale.cli as cli
    _write_xyz(tmp_path / "s.xyz")

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "savez", full)
    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)
    code = cli.main(["decompose", str(tmp_path / "s.xyz"), "-o", str(tmp_path / "out"), "--levels", "3"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert f"cannot write {tmp_path / 'out' / 'decomposition.npz'}: No space left on device" in err, err
    assert not (tmp_path / "out").exists()


def _without_source_id(folder):
    """The folder as a pointscale that wrote no identifier left it."""
    import json
    with np.load(folder / "decomposition.npz", allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    settings = json.loads(arrays["settings"].tobytes())
    del settings["source_id"]
    arrays["settings"] = np.frombuffer(json.dumps(settings).encode(), dtype=np.uint8)
    np.savez(folder / "decomposition.npz", **arrays)
    scan = io.Scan.from_arrays(folder / "source.npz")
    np.savez(folder / "source.npz", **scan.to_arrays())


def test_a_source_npz_of_another_decomposition_is_refused(tmp_path):
    """source.npz copied from a decomposition of another file with as many points was taken
    silently: the result had the other file's colours and attributes."""
    points = _write_xyz(tmp_path / "a.xyz")
    rng = np.random.default_rng(9)
    colours = rng.integers(0, 256, (len(points), 3))
    np.savetxt(tmp_path / "b.xyz", np.c_[points, colours], fmt=["%.17g"] * 3 + ["%d"] * 3,
               header="x y z red green blue", comments="//")
    for name in ("a", "b"):
        done = run_cli("decompose", str(tmp_path / f"{name}.xyz"), "-o", str(tmp_path / name), "--levels", "3")
        assert done.returncode == 0, done.stderr
    first = (tmp_path / "a" / "decomposition.npz").read_bytes(), (tmp_path / "a" / "source.npz").read_bytes()
    done = run_cli("decompose", str(tmp_path / "a.xyz"), "-o", str(tmp_path / "a"), "--levels", "3", "--force")
    assert done.returncode == 0, done.stderr  # the same input again: the same files, bit for bit
    assert ((tmp_path / "a" / "decomposition.npz").read_bytes(), (tmp_path / "a" / "source.npz").read_bytes()) == first
    (tmp_path / "a" / "source.npz").write_bytes((tmp_path / "b" / "source.npz").read_bytes())
    for command in (["reconstruct", str(tmp_path / "a"), "-o", str(tmp_path / "r.ply")], ["info", str(tmp_path / "a")]):
        line = one_line_error(run_cli(*command))
        assert "source.npz and " in line and "come from different decompositions" in line, line
    assert not (tmp_path / "r.ply").exists()


def test_folders_without_a_source_id_still_work_and_do_not_mix_with_new_ones(tmp_path):
    points = _write_xyz(tmp_path / "a.xyz")
    done = run_cli("decompose", str(tmp_path / "a.xyz"), "-o", str(tmp_path / "new"), "--levels", "3")
    assert done.returncode == 0, done.stderr
    (tmp_path / "old").mkdir()
    for name in ("decomposition.npz", "source.npz"):
        (tmp_path / "old" / name).write_bytes((tmp_path / "new" / name).read_bytes())
    _without_source_id(tmp_path / "old")
    done = run_cli("reconstruct", str(tmp_path / "old"), "-o", str(tmp_path / "r.xyz"))
    assert done.returncode == 0, done.stderr
    assert np.abs(io.read(tmp_path / "r.xyz").points - points).max() < 1e-13  # 1e-14 measured
    (tmp_path / "new" / "source.npz").write_bytes((tmp_path / "old" / "source.npz").read_bytes())
    line = one_line_error(run_cli("reconstruct", str(tmp_path / "new"), "-o", str(tmp_path / "r2.xyz")))
    assert "come from different decompositions (source without an identifier" in line, line
