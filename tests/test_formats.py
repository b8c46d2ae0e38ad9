"""pointscale.io: every format round-trips what it stores, and damaged input is a clear ValueError."""
import os
import pickle
import struct
import warnings

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

import pointscale as ps
from helpers import diagonal, shared_model
from pointscale import io
from pointscale.io import Scan, atomic_write


# -- shapes made in code (a user's clone has no data folder) -------------------------------------

def triangle_mesh(subdivisions: int = 3):
    """(points (n, 3) float64, faces (m, 3)) of an icosphere: 642 vertices, 1280 faces at 3."""
    import trimesh
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


def coloured_scan(n: int = 800, offset: float = 0.0) -> Scan:
    points = ps.shapes.bumpy_sphere(n) + offset
    normals = points - points.mean(axis=0)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    rgb = (np.arange(n) * 7 % 256).astype(np.uint8)
    return Scan(points=points, normals=normals,
                vertex_attributes={"red": rgb, "green": rgb[::-1].copy(), "blue": (rgb // 2).astype(np.uint8),
                                   "intensity": (np.arange(n) % 4000).astype(np.uint16)})


def assert_same_attributes(a: dict, b: dict):
    assert list(a) == list(b)
    for name in a:
        assert b[name].dtype == a[name].dtype, name
        assert np.array_equal(b[name], a[name]), name


def same_faces(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and np.array_equal(a, b)
    return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b))


# -- PLY ------------------------------------------------------------------------------------------

def test_float64_ply_far_from_the_origin_round_trips(tmp_path):
    points = ps.shapes.bumpy_sphere(3000) + np.array([1e7, -2e7, 3e6])
    io.write(tmp_path / "far.ply", Scan(points=points, precision=np.float64))
    back = io.read(tmp_path / "far.ply")
    assert back.precision == np.float64
    assert np.abs(back.points - points).max() <= 1e-9 * diagonal(points)
    # The old entry point stores float64 too when given float64 (it used to write float32).
    io.write_ply(tmp_path / "old.ply", points)
    old = io.read_ply(tmp_path / "old.ply")
    assert old.precision == np.float64 and np.abs(old.points - points).max() <= 1e-9 * diagonal(points)


def test_float32_ply_stays_float32(tmp_path):
    points = ps.shapes.sphere(500).astype(np.float32)
    io.write_ply(tmp_path / "a.ply", points)
    assert PlyData.read(str(tmp_path / "a.ply"))["vertex"].properties[0].val_dtype == "f4"
    assert io.read(tmp_path / "a.ply").precision == np.float32


def _plyfile_mesh(path, text: bool):
    """A PLY written by plyfile with RGBA uchar colours, float quality, int scan_id, UVs s/t,
    float64 normals, face colours and per-corner texcoords; returns the arrays written."""
    points, faces = triangle_mesh(2)
    n, m = len(points), len(faces)
    rng = np.random.default_rng(1)
    vertex = np.empty(n, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("nx", "f8"), ("ny", "f8"), ("nz", "f8"),
                                ("red", "u1"), ("green", "u1"), ("blue", "u1"), ("alpha", "u1"),
                                ("quality", "f4"), ("scan_id", "i4"), ("s", "f4"), ("t", "f4")])
    for i, c in enumerate("xyz"):
        vertex[c] = points[:, i]
        vertex["n" + c] = points[:, i] / np.linalg.norm(points, axis=1)
    for c in ("red", "green", "blue", "alpha"):
        vertex[c] = rng.integers(0, 256, n)
    vertex["quality"] = rng.random(n)
    vertex["scan_id"] = rng.integers(-5, 100000, n)
    vertex["s"], vertex["t"] = rng.random(n), rng.random(n)
    face = np.empty(m, dtype=[("vertex_indices", "i4", (3,)), ("red", "u1"), ("green", "u1"), ("blue", "u1"),
                              ("texcoord", "f4", (6,))])
    face["vertex_indices"] = faces
    for c in ("red", "green", "blue"):
        face[c] = rng.integers(0, 256, m)
    face["texcoord"] = rng.random((m, 6))
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")], text=text,
            comments=["made by test_formats", "second comment"]).write(str(path))
    return vertex, face


def _header_properties(path):
    ply = PlyData.read(str(path))
    return [(e.name, [(p.name, str(p)) for p in e.properties]) for e in ply.elements], list(ply.comments)


@pytest.mark.parametrize("text", [False, True], ids=["binary", "ascii"])
def test_every_ply_property_survives_plyfile_file(tmp_path, text):
    vertex, face = _plyfile_mesh(tmp_path / "in.ply", text)
    scan = io.read(tmp_path / "in.ply")
    assert scan.precision == np.float32 and scan.normals is not None
    assert list(scan.vertex_attributes) == ["red", "green", "blue", "alpha", "quality", "scan_id", "s", "t"]
    for name, values in scan.vertex_attributes.items():
        assert values.dtype == vertex.dtype[name] and np.array_equal(values, vertex[name]), name
    assert np.array_equal(scan.faces, face["vertex_indices"])
    assert scan.face_attributes["texcoord"].shape == (len(face), 6)
    assert np.array_equal(scan.face_attributes["texcoord"], face["texcoord"])
    assert np.array_equal(scan.face_attributes["red"], face["red"])
    io.write(tmp_path / "out.ply", scan)
    again = io.read(tmp_path / "out.ply")
    assert np.array_equal(again.points, scan.points) and np.array_equal(again.normals, scan.normals)
    assert_same_attributes(scan.vertex_attributes, again.vertex_attributes)
    assert_same_attributes(scan.face_attributes, again.face_attributes)
    assert np.array_equal(again.faces, scan.faces)
    # Same header: property order and types, encoding, comments.
    assert _header_properties(tmp_path / "out.ply") == _header_properties(tmp_path / "in.ply")
    assert PlyData.read(str(tmp_path / "out.ply")).text == text


def test_every_ply_property_survives_trimesh_file(tmp_path):
    import trimesh
    points, faces = triangle_mesh(2)
    mesh = trimesh.Trimesh(points, faces, process=False)
    n, m = len(points), len(faces)
    rng = np.random.default_rng(2)
    mesh.visual.vertex_colors = rng.integers(0, 256, (n, 4)).astype(np.uint8)
    mesh.vertex_attributes["quality"] = rng.random(n).astype(np.float32)
    mesh.vertex_attributes["scan_id"] = rng.integers(0, 7, n).astype(np.int32)
    mesh.vertex_attributes["texture_u"] = rng.random(n).astype(np.float32)
    mesh.vertex_attributes["texture_v"] = rng.random(n).astype(np.float32)
    mesh.face_attributes["face_quality"] = rng.random(m).astype(np.float32)
    (tmp_path / "tm.ply").write_bytes(trimesh.exchange.ply.export_ply(mesh, encoding="binary"))
    scan = io.read(tmp_path / "tm.ply")
    colours = mesh.visual.vertex_colors
    for i, c in enumerate(("red", "green", "blue", "alpha")):
        assert scan.vertex_attributes[c].dtype == np.uint8 and np.array_equal(scan.vertex_attributes[c], colours[:, i])
    for name in ("quality", "scan_id", "texture_u", "texture_v"):
        assert np.array_equal(scan.vertex_attributes[name], mesh.vertex_attributes[name]), name
        assert scan.vertex_attributes[name].dtype == mesh.vertex_attributes[name].dtype
    assert np.array_equal(scan.face_attributes["face_quality"], mesh.face_attributes["face_quality"])
    assert np.array_equal(scan.faces, faces)
    io.write(tmp_path / "out.ply", scan)
    again = io.read(tmp_path / "out.ply")
    assert_same_attributes(scan.vertex_attributes, again.vertex_attributes)
    assert_same_attributes(scan.face_attributes, again.face_attributes)
    assert np.array_equal(again.points, scan.points) and np.array_equal(again.faces, faces)
    assert _header_properties(tmp_path / "out.ply") == _header_properties(tmp_path / "tm.ply")
    # and trimesh reads our file back with the same vertices and faces
    back = trimesh.load(tmp_path / "out.ply", process=False)
    assert np.array_equal(back.faces, faces) and np.array_equal(back.vertices, scan.points)


def test_mixed_polygons_round_trip(tmp_path):
    points = ps.shapes.sphere(10)
    faces = [[0, 1, 2], [2, 3, 4, 5], [5, 6, 7, 8, 9]]
    colours = np.array([10, 20, 30], dtype=np.uint8)
    scan = Scan(points=points, faces=faces, face_attributes={"red": colours})
    for name in ("m.ply", "m.off", "m.obj"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # OFF and OBJ have no place for a lone red face channel
            io.write(tmp_path / name, scan)
        back = io.read(tmp_path / name)
        assert isinstance(back.faces, list) and [f.tolist() for f in back.faces] == faces, name
    assert np.array_equal(io.read(tmp_path / "m.ply").face_attributes["red"], colours)


def test_face_index_list_found_by_name(tmp_path):
    points = ps.shapes.sphere(6).astype(np.float32)
    vertex = np.array([tuple(p) for p in points], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    face = np.array([(7, [0, 1, 2]), (9, [3, 4, 5])], dtype=[("quality", "u1"), ("vertex_index", "i4", (3,))])
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(str(tmp_path / "a.ply"))
    scan = io.read(tmp_path / "a.ply")
    assert scan.faces.tolist() == [[0, 1, 2], [3, 4, 5]] and scan.face_attributes["quality"].tolist() == [7, 9]
    io.write(tmp_path / "b.ply", scan)
    assert [p.name for p in PlyData.read(str(tmp_path / "b.ply"))["face"].properties] == ["quality", "vertex_index"]


def test_face_element_without_an_index_list_is_refused(tmp_path):
    vertex = np.zeros(3, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    no_list = np.zeros(2, dtype=[("quality", "f4")])
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(no_list, "face")]).write(str(tmp_path / "a.ply"))
    with pytest.raises(ValueError, match="a.ply: face element has no vertex_indices"):
        io.read(tmp_path / "a.ply")
    scalar = np.zeros(2, dtype=[("vertex_indices", "i4")])
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(scalar, "face")]).write(str(tmp_path / "b.ply"))
    with pytest.raises(ValueError, match="b.ply: face property vertex_indices is not a list"):
        io.read(tmp_path / "b.ply")


def test_other_ply_elements_are_dropped_with_a_warning(tmp_path):
    vertex = np.zeros(3, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    edge = np.array([(0, 1), (1, 2)], dtype=[("vertex1", "i4"), ("vertex2", "i4")])
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(edge, "edge")]).write(str(tmp_path / "a.ply"))
    with pytest.warns(UserWarning, match="edge"):
        scan = io.read(tmp_path / "a.ply")
    assert scan.n_points == 3 and scan.faces is None


def test_shared_scans_keep_scan_id(tmp_path):
    scan = io.read(shared_model("bunny_scans.ply"))
    ids = scan.vertex_attributes["scan_id"]
    assert ids.dtype == np.uint8 and len(ids) == scan.n_points == 362272
    assert set(np.unique(ids).tolist()) == set(range(10))
    io.write(tmp_path / "b.ply", scan)
    assert (tmp_path / "b.ply").read_bytes() == shared_model("bunny_scans.ply").read_bytes()
    io.write(tmp_path / "b.laz", scan)
    assert np.array_equal(io.read(tmp_path / "b.laz").vertex_attributes["scan_id"], ids)


# -- LAS / LAZ ------------------------------------------------------------------------------------

# A GeoTIFF key directory with one key (GTModelTypeGeoKey = projected): where a LAS file's CRS lives.
GEOKEYS = struct.pack("<8H", 1, 1, 0, 1, 1024, 0, 1, 1)


def _laspy_file(path, n=500):
    """A LAS 1.2 point format 3 file written by laspy: scale 1e-3, offsets near UTM, every field
    set, two extra dimensions and a VLR; returns the LasData written."""
    import laspy
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = [0.001, 0.001, 0.0005]
    header.offsets = [500000.0, 4200000.0, 100.0]
    header.add_extra_dim(laspy.ExtraBytesParams(name="quality", type=np.float32))
    header.add_extra_dim(laspy.ExtraBytesParams(name="scan_id", type=np.uint16))
    header.vlrs.append(laspy.VLR(user_id="pointscale", record_id=7, description="test vlr",
                                 record_data=b"\x00\x01CRS lives here\xff"))
    header.vlrs.append(laspy.VLR(user_id="LASF_Projection", record_id=34735, description="GeoKeyDirectoryTag",
                                 record_data=GEOKEYS))
    las = laspy.LasData(header)
    rng = np.random.default_rng(3)
    las.x = 500000 + rng.random(n) * 300
    las.y = 4200000 + rng.random(n) * 200
    las.z = 100 + rng.random(n) * 30
    las.intensity = rng.integers(0, 65535, n)
    las.return_number = rng.integers(1, 5, n)
    las.number_of_returns = rng.integers(1, 7, n)
    las.classification = rng.integers(0, 31, n)
    las.scan_angle_rank = rng.integers(-90, 90, n)
    las.user_data = rng.integers(0, 255, n)
    las.point_source_id = rng.integers(0, 65535, n)
    las.gps_time = rng.random(n) * 1e5
    las.red, las.green, las.blue = (rng.integers(0, 65535, n) for _ in range(3))
    las.quality = rng.random(n).astype(np.float32)
    las.scan_id = rng.integers(0, 9, n)
    las.write(str(path))
    return laspy.read(str(path))


@pytest.mark.parametrize("ext", [".las", ".laz"])
def test_las_round_trip_keeps_header_fields_and_vlrs(tmp_path, ext):
    import laspy
    original = _laspy_file(tmp_path / f"in{ext}")
    scan = io.read(tmp_path / f"in{ext}")
    assert scan.precision == np.float64
    assert np.array_equal(scan.points[:, 0], np.asarray(original.x))
    io.write(tmp_path / f"out{ext}", scan)
    written = laspy.read(str(tmp_path / f"out{ext}"))
    assert written.header.point_format.id == 3 and str(written.header.version) == "1.2"
    assert np.array_equal(written.header.scales, original.header.scales)
    assert np.array_equal(written.header.offsets, original.header.offsets)
    for name in original.point_format.dimension_names:  # X, Y, Z and every other field, unchanged
        assert np.array_equal(np.asarray(written[name]), np.asarray(original[name])), name
    vlrs = [v for v in written.header.vlrs if v.user_id == "pointscale"]
    assert len(vlrs) == 1 and vlrs[0].record_id == 7 and vlrs[0].record_data == b"\x00\x01CRS lives here\xff"
    crs = [v for v in written.header.vlrs if v.record_id == 34735]
    assert len(crs) == 1 and crs[0].record_data_bytes() == GEOKEYS
    assert list(written.point_format.extra_dimension_names) == ["quality", "scan_id"]
    again = io.read(tmp_path / f"out{ext}")
    assert_same_attributes(scan.vertex_attributes, again.vertex_attributes)
    # LAS to LAZ keeps the same records
    other = ".laz" if ext == ".las" else ".las"
    io.write(tmp_path / f"swap{other}", scan)
    assert np.array_equal(np.asarray(laspy.read(str(tmp_path / f"swap{other}")).X), np.asarray(original.X))


def test_scan_from_elsewhere_written_as_las(tmp_path):
    import laspy
    scan = coloured_scan(2000, offset=1e6)
    io.write(tmp_path / "a.laz", scan)
    las = laspy.read(str(tmp_path / "a.laz"))
    assert las.header.point_format.id == 7 and str(las.header.version) == "1.4"
    assert np.allclose(las.header.offsets, scan.points.min(axis=0))
    assert np.array_equal(np.asarray(las.red), scan.vertex_attributes["red"].astype(np.uint16) * 257)
    assert np.array_equal(np.asarray(las.intensity), scan.vertex_attributes["intensity"])
    back = io.read(tmp_path / "a.laz")
    # scale: the power of ten at or below 1e-6 of the diagonal, so rounding is at most half of it
    assert np.abs(back.points - scan.points).max() <= 5e-7 * diagonal(scan.points)
    assert np.abs(back.normals - scan.normals).max() < 1e-6  # extra bytes nx, ny, nz in float32


def test_las14_evlr_survives(tmp_path):
    import laspy
    from laspy.vlrs.vlrlist import VLRList
    las = laspy.LasData(laspy.LasHeader(point_format=6, version="1.4"))
    las.header.scales, las.header.offsets = [1e-3] * 3, [0, 0, 0]
    las.x, las.y, las.z = np.arange(10.0), np.arange(10.0) * 2, np.arange(10.0) * 3
    las.evlrs = VLRList([laspy.VLR(user_id="pointscale", record_id=9, description="evlr",
                                   record_data=bytes(range(256)) * 300)])  # larger than a VLR may be
    las.write(str(tmp_path / "in.las"))
    io.write(tmp_path / "out.laz", io.read(tmp_path / "in.las"))
    evlrs = laspy.read(str(tmp_path / "out.laz")).header.evlrs
    assert len(evlrs) == 1 and evlrs[0].record_id == 9 and evlrs[0].record_data == bytes(range(256)) * 300


def test_big_endian_ply_round_trips_byte_for_byte(tmp_path):
    vertex = np.zeros(3, dtype=[("x", ">f4"), ("y", ">f4"), ("z", ">f4"), ("q", ">u2")])
    vertex["x"], vertex["q"] = [1.5, 2.5, -3.0], [1, 2, 300]
    PlyData([PlyElement.describe(vertex, "vertex")], byte_order=">").write(str(tmp_path / "be.ply"))
    scan = io.read(tmp_path / "be.ply")
    assert scan.vertex_attributes["q"].dtype == np.uint16 and scan.vertex_attributes["q"].tolist() == [1, 2, 300]
    io.write(tmp_path / "again.ply", scan)
    assert (tmp_path / "again.ply").read_bytes() == (tmp_path / "be.ply").read_bytes()


# -- OBJ, OFF, STL, XYZ, PTS ---------------------------------------------------------------------

def test_obj_round_trip_keeps_order_normals_colours_uvs(tmp_path):
    points, faces = triangle_mesh(2)
    n = len(points)
    extra = np.vstack([points, [[5.0, 5.0, 5.0]]])  # a vertex no face uses: still a point
    colours = np.linspace(0, 1, n + 1)
    normals = extra / np.linalg.norm(extra, axis=1, keepdims=True)
    scan = Scan(points=extra, normals=normals, faces=faces,
                vertex_attributes={"red": colours, "green": colours[::-1].copy(), "blue": colours * 0.5,
                                   "texture_u": colours, "texture_v": 1 - colours})
    io.write(tmp_path / "a.obj", scan)
    back = io.read(tmp_path / "a.obj")
    assert np.array_equal(back.points, extra) and np.array_equal(back.normals, normals)
    assert np.array_equal(back.faces, faces)
    assert_same_attributes(scan.vertex_attributes, back.vertex_attributes)


def test_obj_written_elsewhere_with_uv_seams(tmp_path):
    (tmp_path / "q.obj").write_text("mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 3 3 3\n"
                                    "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvt 0.5 0.5\n"
                                    "f 1/1 2/2 4/4 3/3\nf -3/5 -2/2 -4/1\n")
    with pytest.warns(UserWarning, match="seam"):
        scan = io.read(tmp_path / "q.obj")
    assert scan.n_points == 5 and [f.tolist() for f in scan.faces] == [[0, 1, 3, 2], [2, 3, 1]]
    assert scan.vertex_attributes["texture_u"][:4].tolist() == [0, 1, 0, 1]  # first corner's UV kept
    assert scan.normals is None


def test_off_round_trip_with_colours_and_normals(tmp_path):
    points, faces = triangle_mesh(2)
    n, m = len(points), len(faces)
    rgb = (np.arange(n) % 256).astype(np.uint8)
    face_rgb = (np.arange(m) % 200 + 20).astype(np.uint8)
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    scan = Scan(points=points, normals=normals, faces=faces,
                vertex_attributes={"red": rgb, "green": rgb, "blue": rgb, "alpha": rgb},
                face_attributes={"red": face_rgb, "green": face_rgb, "blue": face_rgb})
    io.write(tmp_path / "a.off", scan)
    assert (tmp_path / "a.off").read_text().startswith("CNOFF\n")
    back = io.read(tmp_path / "a.off")
    assert np.array_equal(back.points, points) and np.array_equal(back.normals, normals)
    assert np.array_equal(back.faces, faces)
    assert_same_attributes(scan.vertex_attributes, back.vertex_attributes)
    assert_same_attributes(scan.face_attributes, back.face_attributes)


def test_stl_corners_merge_into_shared_vertices(tmp_path):
    points, faces = triangle_mesh(3)
    first_use = np.unique(faces.ravel(), return_index=True)[1]
    order = np.unique(faces.ravel())[np.argsort(first_use)]
    # float64 is written as ASCII STL, exactly; float32 as binary STL
    for precision, bound in ((np.float64, 0.0), (np.float32, 1e-7)):
        io.write(tmp_path / "a.stl", Scan(points=points, faces=faces, precision=precision))
        back = io.read(tmp_path / "a.stl")
        assert back.precision == precision and back.format_info["binary"] == (precision == np.float32)
        assert back.n_points == len(points) and back.faces.shape == faces.shape  # 3m corners -> n vertices
        # the same triangles, in the same order
        assert np.abs(back.points[back.faces] - points[faces]).max() <= bound
        # vertices come in the order of their first corner
        assert np.abs(back.points - points[order]).max() <= bound


def test_stl_of_a_point_cloud_is_refused(tmp_path):
    with pytest.raises(ValueError, match="no faces"):
        io.write(tmp_path / "a.stl", Scan(points=ps.shapes.sphere(10)))
    assert not (tmp_path / "a.stl").exists()


def test_xyz_round_trip_keeps_normals_and_named_columns(tmp_path):
    scan = coloured_scan(700, offset=1e7)
    scan.vertex_attributes["quality"] = np.linspace(0, 1, 700)
    io.write(tmp_path / "a.xyz", scan)
    back = io.read(tmp_path / "a.xyz")
    assert np.array_equal(back.points, scan.points) and np.array_equal(back.normals, scan.normals)
    assert_same_attributes(scan.vertex_attributes, back.vertex_attributes)
    # a plain file from elsewhere: x y z nx ny nz and one more column
    rows = np.column_stack([scan.points, scan.normals, np.arange(700.0)])
    np.savetxt(tmp_path / "b.xyz", rows)
    plain = io.read(tmp_path / "b.xyz")
    assert np.array_equal(plain.points, scan.points) and plain.normals is not None
    assert np.array_equal(plain.vertex_attributes["column_6"], np.arange(700.0))
    # a first comment that does not name the columns is only a comment
    (tmp_path / "c.xyz").write_text("# exported by some scanner\n1 2 3\n4 5 6\n")
    assert io.read(tmp_path / "c.xyz").points.tolist() == [[1, 2, 3], [4, 5, 6]]


def test_pts_round_trip_keeps_intensity_and_colour(tmp_path):
    scan = coloured_scan(600, offset=-3e6)
    scan.vertex_attributes["intensity"] = (np.arange(600) - 300).astype(np.int32)
    with pytest.warns(UserWarning, match="normals"):
        io.write(tmp_path / "a.pts", scan)
    assert (tmp_path / "a.pts").read_text().split("\n", 1)[0] == "600"
    back = io.read(tmp_path / "a.pts")
    assert np.array_equal(back.points, scan.points)
    assert list(back.vertex_attributes) == ["intensity", "red", "green", "blue"]
    for name, values in back.vertex_attributes.items():
        assert np.array_equal(values, scan.vertex_attributes[name]), name
    assert back.vertex_attributes["red"].dtype == np.uint8


def test_pts_of_several_scans_keeps_them_apart(tmp_path):
    (tmp_path / "m.pts").write_text("2\n0 0 0 5\n1 0 0 6\n3\n2 0 0 7\n3 0 0 8\n4 0 0 9\n")
    scan = io.read(tmp_path / "m.pts")
    assert scan.points[:, 0].tolist() == [0, 1, 2, 3, 4]
    assert scan.vertex_attributes["scan_id"].tolist() == [0, 0, 1, 1, 1]
    io.write(tmp_path / "again.pts", scan)
    assert (tmp_path / "again.pts").read_text() == (tmp_path / "m.pts").read_text()
    (tmp_path / "cut.pts").write_text("2\n0 0 0 5\n1 0 0 6\n3\n2 0 0 7\n")
    with pytest.raises(ValueError, match="cut.pts: block 1 says 3 points, the file has 1"):
        io.read(tmp_path / "cut.pts")


def test_e57_round_trip(tmp_path):
    pytest.importorskip("pye57")
    scan = coloured_scan(900, offset=5e6)
    scan.vertex_attributes["intensity"] = np.linspace(0, 1, 900)
    with pytest.warns(UserWarning, match="normals"):
        io.write(tmp_path / "a.e57", scan)
    back = io.read(tmp_path / "a.e57")
    # pye57 stores float32 around the bounding-box centre: 1e-7 of the extent, not of 5e6
    assert np.abs(back.points - scan.points).max() < 1e-7 * diagonal(scan.points)
    for name in ("red", "green", "blue"):
        assert np.array_equal(back.vertex_attributes[name], scan.vertex_attributes[name])
    assert np.allclose(back.vertex_attributes["intensity"], scan.vertex_attributes["intensity"], atol=1e-6)


def test_e57_scans_are_placed_by_their_poses_and_numbered(tmp_path):
    pye57 = pytest.importorskip("pye57")
    e57 = pye57.E57(str(tmp_path / "m.e57"), mode="w")
    for k in range(3):
        e57.write_scan_raw({"cartesianX": np.arange(4.0) + k, "cartesianY": np.zeros(4), "cartesianZ": np.zeros(4)},
                           translation=np.array([10.0 * k, 0, 0]), rotation=np.array([1.0, 0, 0, 0]))
    e57.close()
    scan = io.read(tmp_path / "m.e57")
    assert scan.points[:, 0].tolist() == [0, 1, 2, 3, 11, 12, 13, 14, 22, 23, 24, 25]
    assert scan.vertex_attributes["scan_id"].tolist() == [0] * 4 + [1] * 4 + [2] * 4


def test_e57_without_pye57_says_how_to_install(tmp_path, monkeypatch):
    import sys
    monkeypatch.setitem(sys.modules, "pye57", None)  # import pye57 now raises ImportError
    with pytest.raises(ValueError, match=r"reading \.e57 needs pye57: pip install pye57"):
        io.read(tmp_path / "a.e57")


# -- damaged input --------------------------------------------------------------------------------

def _write_sample(path, ascii_ply=False):
    points, faces = triangle_mesh(3)
    scan = coloured_scan(len(points))
    if path.suffix in (".ply", ".obj", ".off", ".stl"):
        scan = Scan(points=points, faces=faces, vertex_attributes=scan.vertex_attributes)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if ascii_ply:
            from pointscale.io.ply import write_ply
            write_ply(path, scan, binary=False)
        else:
            io.write(path, scan)


FORMATS = [".ply", ".las", ".laz", ".obj", ".off", ".stl", ".xyz", ".pts", ".e57"]


@pytest.mark.parametrize("ext", FORMATS + ["ascii.ply"])
def test_truncated_file_is_a_clear_error(tmp_path, ext):
    if ext == ".e57":
        pytest.importorskip("pye57")
    ascii_ply = ext == "ascii.ply"
    ext = ".ply" if ascii_ply else ext
    path = tmp_path / f"a{ext}"
    _write_sample(path, ascii_ply)
    data = path.read_bytes()
    for keep in (0.6, 0.97):
        cut = tmp_path / f"cut_{keep}{ext}"
        # Cut inside a line, dropping at least its last value. (A cut exactly at a line end is
        # undetectable in OBJ and XYZ, which have no counts; PLY, OFF, PTS, LAS, STL, E57 do.)
        chunk = data[:int(len(data) * keep)]
        cut.write_bytes(chunk[:chunk.rstrip().rfind(b" ")] if ext in (".obj", ".xyz") else chunk)
        with pytest.raises(ValueError) as error:
            io.read(cut)
        message = str(error.value)
        assert str(cut) in message and "\n" not in message


@pytest.mark.parametrize("ext", FORMATS)
def test_missing_and_garbage_files_are_clear_errors(tmp_path, ext):
    with pytest.raises(ValueError, match="no such file|needs pye57"):
        io.read(tmp_path / f"missing{ext}")
    garbage = tmp_path / f"garbage{ext}"
    garbage.write_bytes(bytes(range(256)) * 40)
    with pytest.raises(ValueError, match="garbage"):
        io.read(garbage)


def test_damaged_las_counts_are_refused_before_anything_trusts_them(tmp_path):
    _laspy_file(tmp_path / "a.las", n=50)
    data = bytearray((tmp_path / "a.las").read_bytes())
    data[100:104] = struct.pack("<I", 0xFFFFFFFF)  # the VLR count: laspy would build 4 billion VLRs
    (tmp_path / "vlrs.las").write_bytes(bytes(data))
    with pytest.raises(ValueError, match="vlrs.las: damaged header: 4294967295 VLRs"):
        io.read(tmp_path / "vlrs.las")
    # A LAZ chunk table claiming 4 billion chunks: lazrs allocates 64 GB for it and aborts the
    # process (without the check, this test ends pytest instead of failing).
    _laspy_file(tmp_path / "a.laz", n=50)
    data = bytearray((tmp_path / "a.laz").read_bytes())
    start = laspy_header(tmp_path / "a.laz").offset_to_point_data
    table = struct.unpack_from("<q", data, start)[0]  # the point data starts with the table's offset
    struct.pack_into("<I", data, table + 4, 0xFFFFFFFF)  # after the table's version: its chunk count
    (tmp_path / "chunks.laz").write_bytes(bytes(data))
    with pytest.raises(ValueError, match="chunks.laz: damaged LAZ chunk table"):
        io.read(tmp_path / "chunks.laz")
    # A layered chunk (point formats 6-10) whose first layer claims 3 GB: lazrs allocated it.
    io.write(tmp_path / "b.laz", coloured_scan(300))  # LAS 1.4, point format 7: layered chunks
    data = bytearray((tmp_path / "b.laz").read_bytes())
    header = laspy_header(tmp_path / "b.laz")
    first_layer = header.offset_to_point_data + 8 + header.point_format.size + 4
    struct.pack_into("<I", data, first_layer, 3_000_000_000)
    (tmp_path / "layer.laz").write_bytes(bytes(data))
    with pytest.raises(ValueError, match="layer.laz: damaged LAZ chunk 0: its layers claim"):
        io.read(tmp_path / "layer.laz")
    (tmp_path / "cut.laz").write_bytes((tmp_path / "a.laz").read_bytes()[:-2])
    with pytest.raises(ValueError, match="cut.laz"):
        io.read(tmp_path / "cut.laz")


def laspy_header(path):
    import laspy
    with laspy.open(str(path)) as reader:
        return reader.header


def test_faces_out_of_range_are_refused(tmp_path):
    vertex = np.zeros(4, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    face = np.array([([0, 1, 4],)], dtype=[("vertex_indices", "i4", (3,))])
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(str(tmp_path / "a.ply"))
    with pytest.raises(ValueError, match="a.ply: faces index vertices 0..4, outside 0..3"):
        io.read(tmp_path / "a.ply")
    face["vertex_indices"] = [[0, -1, 2]]
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(str(tmp_path / "b.ply"))
    with pytest.raises(ValueError, match="b.ply: faces index"):
        io.read(tmp_path / "b.ply")
    (tmp_path / "a.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
    with pytest.raises(ValueError, match="a.obj: a face refers to vertex 4, outside 1..3"):
        io.read(tmp_path / "a.obj")
    (tmp_path / "a.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")
    with pytest.raises(ValueError, match="a.off: faces index"):
        io.read(tmp_path / "a.off")
    with pytest.raises(ValueError, match="outside"):
        Scan(points=np.zeros((3, 3)), faces=[[0, 1, 3]])


def test_no_vertices_and_non_finite_coordinates_are_refused(tmp_path):
    empty = np.zeros(0, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    PlyData([PlyElement.describe(empty, "vertex")]).write(str(tmp_path / "empty.ply"))
    with pytest.raises(ValueError, match="empty.ply: no vertices"):
        io.read(tmp_path / "empty.ply")
    points = ps.shapes.sphere(20)
    points[7, 1] = np.nan
    io.write_ply(tmp_path / "nan.ply", points)
    with pytest.raises(ValueError, match="nan.ply: 1 vertices have non-finite"):
        io.read(tmp_path / "nan.ply")
    (tmp_path / "inf.xyz").write_text("0 0 0\n1 inf 0\n")
    with pytest.raises(ValueError, match="inf.xyz: 1 points have non-finite"):
        io.read(tmp_path / "inf.xyz")
    (tmp_path / "empty.xyz").write_text("")
    with pytest.raises(ValueError, match="empty.xyz: no vertices"):
        io.read(tmp_path / "empty.xyz")


@pytest.mark.parametrize("ext", FORMATS)
def test_an_empty_scan_is_not_written(tmp_path, ext):
    with pytest.raises(ValueError, match="no points"):
        io.write(tmp_path / f"a{ext}", Scan(points=np.zeros((0, 3))))
    assert os.listdir(tmp_path) == []


def test_unknown_extension_names_the_supported_ones_in_one_line(tmp_path):
    with pytest.raises(ValueError) as error:
        io.read(tmp_path / "scan.dae")
    message = str(error.value)
    assert "\n" not in message and "'.dae'" in message
    assert all(ext in message for ext in io.SUPPORTED_EXTENSIONS)
    with pytest.raises(ValueError, match="unknown file extension"):
        io.write(tmp_path / "noext", Scan(points=np.zeros((1, 3))))


def test_extension_is_case_insensitive(tmp_path):
    scan = coloured_scan(300)
    for name in ("A.PLY", "B.Laz", "C.XYZ"):
        io.write(tmp_path / name, scan)
        assert np.allclose(io.read(tmp_path / name).points, scan.points, atol=1e-6)
    assert PlyData.read(str(tmp_path / "A.PLY"))["vertex"].count == 300


# -- flat arrays (the command line's decomposition folder) ----------------------------------------

def test_to_arrays_round_trips_through_npz(tmp_path):
    _laspy_file(tmp_path / "in.laz")
    scan = io.read(tmp_path / "in.laz")
    np.savez(tmp_path / "attrs.npz", **scan.to_arrays())
    back = Scan.from_arrays(tmp_path / "attrs.npz").with_geometry(scan.points)
    assert_same_attributes(scan.vertex_attributes, back.vertex_attributes)
    assert back.format_info == scan.format_info  # VLR payload bytes included
    assert back.format_info["vlrs"][0]["data"] == b"\x00\x01CRS lives here\xff"
    io.write(tmp_path / "out.laz", back)
    assert np.array_equal(io.read(tmp_path / "out.laz").points, scan.points)
    # mixed polygons and face attributes
    mixed = Scan(points=ps.shapes.sphere(6), faces=[[0, 1, 2], [2, 3, 4, 5]],
                 face_attributes={"red": np.array([1, 2], np.uint8)}, precision=np.float32)
    arrays = mixed.to_arrays()
    assert all(a.dtype != object for a in arrays.values())
    again = Scan.from_arrays(arrays)
    assert same_faces(again.faces, mixed.faces) and again.precision == np.float32
    assert np.isnan(again.points).all()  # no geometry until with_geometry
    with pytest.raises(ValueError, match="non-finite"):
        io.write(tmp_path / "x.ply", again)


def test_damaged_arrays_are_refused(tmp_path):
    points, faces = triangle_mesh(1)
    scan = Scan(points=points, faces=faces, vertex_attributes={"q": np.arange(len(points), dtype=np.float32)})
    good = scan.to_arrays()

    def damaged(**changes):
        arrays = dict(good)
        arrays.update(changes)
        return {k: v for k, v in arrays.items() if v is not None}

    with pytest.raises(ValueError, match="shape"):
        Scan.from_arrays(damaged(**{"vertex_attributes/0": np.zeros(3, np.float32)}))
    with pytest.raises(ValueError, match="outside"):
        Scan.from_arrays(damaged(faces=faces + len(points)))
    with pytest.raises(ValueError, match="integer"):
        Scan.from_arrays(damaged(faces=faces.astype(np.float64)))
    with pytest.raises(ValueError, match="meta_json"):
        Scan.from_arrays(damaged(meta_json=good["meta_json"][:-5]))
    with pytest.raises(ValueError, match="lack"):
        Scan.from_arrays(damaged(**{"vertex_attributes/0": None}))
    with pytest.raises(ValueError, match="unexpected"):
        Scan.from_arrays(damaged(stray=np.zeros(2)))
    with pytest.raises(ValueError, match="dtype"):
        Scan.from_arrays(damaged(**{"vertex_attributes/0": np.array(["a"] * len(points))}))
    with pytest.raises(ValueError, match="points"):
        Scan.from_arrays(good).with_geometry(points[:-1])


class _CreatesMarker:
    """Unpickling this creates a marker file: the sign that a pickle ran."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (open, (self.marker, "w"))


def test_pickles_are_refused_without_running(tmp_path):
    marker = tmp_path / "unpickled.marker"
    payload = np.array([_CreatesMarker(str(marker))], dtype=object)
    np.save(tmp_path / "evil.npy", payload, allow_pickle=True)
    arrays = Scan(points=np.zeros((1, 3))).to_arrays()
    np.savez(tmp_path / "evil.npz", **arrays, **{"vertex_attributes/0": payload})
    (tmp_path / "raw.npz").write_bytes(pickle.dumps(_CreatesMarker(str(marker))))
    assert not marker.exists()
    for name in ("evil.npy", "evil.npz", "raw.npz"):
        with pytest.raises(ValueError):
            Scan.from_arrays(tmp_path / name)
        assert not marker.exists(), name
    with pytest.raises(ValueError, match="dtype object"):
        Scan.from_arrays({**arrays, "faces": np.array([[0, 0, 0]], dtype=object)})
    assert not marker.exists()


# -- atomic writes --------------------------------------------------------------------------------

@pytest.mark.parametrize("exception", [RuntimeError, KeyboardInterrupt])
def test_atomic_write_leaves_nothing_on_failure(tmp_path, exception):
    target = tmp_path / "out.ply"
    target.write_text("previous")
    with pytest.raises(exception):
        with atomic_write(target) as temporary:
            temporary.write_text("half")
            raise exception()
    assert target.read_text() == "previous" and os.listdir(tmp_path) == ["out.ply"]
    with atomic_write(target) as temporary:
        temporary.write_text("new")
    assert target.read_text() == "new" and os.listdir(tmp_path) == ["out.ply"]


def test_failed_writer_leaves_no_partial_file(tmp_path):
    scan = Scan(points=ps.shapes.sphere(50), vertex_attributes={"big": np.full(50, 2 ** 60, dtype=np.int64)})
    with pytest.raises(ValueError, match="a.ply: attribute 'big'"):
        io.write(tmp_path / "a.ply", scan)
    assert os.listdir(tmp_path) == []
    (tmp_path / "file").write_text("")
    with pytest.raises(ValueError, match="cannot write"):  # a folder that is a file: OSError inside
        io.write(tmp_path / "file" / "a.ply", Scan(points=np.zeros((1, 3))))
    with pytest.warns(UserWarning, match="stored as double"):  # 2**40 fits a double exactly
        io.write(tmp_path / "b.ply", Scan(points=np.zeros((1, 3)), vertex_attributes={"t": np.array([2 ** 40])}))
    assert io.read(tmp_path / "b.ply").vertex_attributes["t"].tolist() == [2.0 ** 40]


# -- the old entry points -------------------------------------------------------------------------

def test_read_ply_and_write_ply_keep_working(tmp_path):
    points = ps.shapes.sphere(200)
    io.write_ply(tmp_path / "a.ply", points, normals=points, faces=[[0, 1, 2], [2, 3, 4]],
                 scalars={"detail": points[:, 0]}, binary=False)
    back = io.read_ply(tmp_path / "a.ply")
    assert np.array_equal(back.points, points) and np.array_equal(back.normals, points)
    assert back.faces.tolist() == [[0, 1, 2], [2, 3, 4]]
    assert np.array_equal(back.vertex_attributes["detail"], points[:, 0])
    assert PlyData.read(str(tmp_path / "a.ply")).text
