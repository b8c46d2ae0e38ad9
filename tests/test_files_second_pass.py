"""Scan files, after a second reader's pass (2026-12-06): float face indices, 64-bit integers
in untyped text columns, OBJ and OFF content with no place in a Scan, text that is not pure
UTF-8, decompression bombs in a decomposition folder, and an empty -o."""
import io as pyio
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

import pointscale as ps
from helpers import one_line_error, run_cli as run


def points(n=400, seed=5):
    return np.random.default_rng(seed).normal(size=(n, 3))


def test_ply_faces_with_float_indices_are_refused(tmp_path):
    p = points()
    vertex = np.array([tuple(r) for r in p], dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    face = np.empty(2, dtype=[("vertex_indices", "O")])
    face["vertex_indices"] = [np.array([0, 12.7, 3], "f4"), np.array([1, 2, 3], "f4")]
    path = tmp_path / "float_faces.ply"
    PlyData([PlyElement.describe(vertex, "vertex"),
             PlyElement.describe(face, "face", val_types={"vertex_indices": "f4"})]).write(str(path))
    with pytest.raises(ValueError, match="vertex indices must be integers"):
        ps.io.read(path)


@pytest.mark.parametrize("header", ["", "//X Y Z R G B ID T\n", "# made by a scanner\n"])
def test_untyped_xyz_columns_of_64_bit_integers_are_read_exactly(tmp_path, header):
    p = points()
    ids = np.arange(len(p), dtype=np.int64) * 7 + (2**60 + 1)  # past 2**53: float64 would round them
    path = tmp_path / "ids.xyz"
    with open(path, "w") as f:
        f.write(header)
        for row, i in zip(p, ids):
            middle = " 10 20 30" if "ID" in header else ""
            f.write(f"{row[0]!r} {row[1]!r} {row[2]!r}{middle} {i} 1.5\n" if "ID" in header
                    else f"{row[0]!r} {row[1]!r} {row[2]!r} {i}\n")
    scan = ps.io.read(path)
    name = "ID" if "ID" in header else "column_3"
    assert scan.vertex_attributes[name].dtype == np.int64
    assert np.array_equal(scan.vertex_attributes[name], ids)
    assert np.array_equal(scan.points, p)
    ps.io.write(tmp_path / "again.xyz", scan)  # the header now declares it: exact again
    assert np.array_equal(ps.io.read(tmp_path / "again.xyz").vertex_attributes[name], ids)


def test_a_column_of_ordinary_numbers_stays_float(tmp_path):
    p = points()
    path = tmp_path / "plain.xyz"
    np.savetxt(path, np.column_stack([p, np.arange(len(p)) * 3.0]))
    assert ps.io.read(path).vertex_attributes["column_3"].dtype == np.float64


def test_obj_content_a_scan_does_not_keep_is_named_in_a_warning(tmp_path):
    p = points(6)
    path = tmp_path / "textured.obj"
    path.write_text("mtllib wood.mtl\no Board\n" + "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in p)
                    + "g top\nusemtl Oak\ns 1\nf 1 2 3\nf 4 5 6\nl 1 2\n")
    with pytest.warns(UserWarning, match="not kept") as caught:
        scan = ps.io.read(path)
    message = str(caught[0].message)
    for keyword in ("mtllib", "usemtl", "g", "o", "s", "l"):
        assert f" {keyword}" in message
    assert scan.n_points == 6 and scan.n_faces == 2


def test_an_off_colour_index_on_face_lines_is_named_in_a_warning(tmp_path):
    p = points(5)
    path = tmp_path / "indexed.off"
    path.write_text("OFF\n5 2 0\n" + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in p) + "3 0 1 2 7\n3 2 3 4 7\n")
    with pytest.warns(UserWarning, match="face lines carry 1 values"):
        scan = ps.io.read(path)
    assert scan.n_faces == 2 and scan.face_attributes == {}


@pytest.mark.parametrize("suffix", [".obj", ".off", ".xyz", ".pts"])
@pytest.mark.parametrize("start", [b"", b"\xef\xbb\xbf"])  # plain, or a UTF-8 byte-order mark
def test_a_comment_in_latin_1_does_not_refuse_a_text_file(tmp_path, suffix, start):
    p = points(30)
    rows = "".join(f"{'v ' if suffix == '.obj' else ''}{x!r} {y!r} {z!r}\n" for x, y, z in p).encode()
    head = {".obj": b"# cr\xe9\xe9 par Ren\xe9\n", ".off": b"OFF\n# cr\xe9\xe9\n30 0 0\n",
            ".xyz": b"# cr\xe9\xe9\n", ".pts": b"30\n"}[suffix]
    path = tmp_path / f"accent{suffix}"
    path.write_bytes(start + head + rows)
    assert np.array_equal(ps.io.read(path).points, p)


def test_binary_bytes_are_still_not_text(tmp_path):
    path = tmp_path / "binary.xyz"
    path.write_bytes(b"\x00\x01\x02\x03" * 64)
    with pytest.raises(ValueError, match="not a text file"):
        ps.io.read(path)
    (tmp_path / "number.xyz").write_bytes(b"1 2 3\n4 \xe95 6\n")
    with pytest.raises(ValueError, match="unreadable row"):
        ps.io.read(tmp_path / "number.xyz")


@pytest.fixture()
def folder(tmp_path):
    p = ps.shapes.bumpy_sphere(3000)
    ps.io.write(tmp_path / "in.ply", ps.io.Scan(points=p, precision=np.float64,
                                                vertex_attributes={"quality": np.arange(3000, dtype=np.float32)}))
    assert run("decompose", str(tmp_path / "in.ply"), "-o", str(tmp_path / "out"), "--levels", "3").returncode == 0
    return tmp_path / "out"


def zeros_entry(count: int) -> bytes:
    buffer = pyio.BytesIO()
    np.save(buffer, np.zeros(count))
    return buffer.getvalue()


def rewrite(source: Path, replace: dict, add: dict = {}) -> None:
    original = source.read_bytes()
    with zipfile.ZipFile(pyio.BytesIO(original)) as zin, zipfile.ZipFile(source, "w", zipfile.ZIP_DEFLATED) as zout:
        for name in zin.namelist():
            zout.writestr(name, replace.get(name, zin.read(name)))
        for name, data in add.items():
            zout.writestr(name, data)


@pytest.mark.parametrize("how", ["an entry of its own", "a known entry"])
def test_a_decompression_bomb_in_source_npz_is_refused_unread(folder, how):
    source = folder / "source.npz"
    bomb = zeros_entry(40_000_000)  # 320 MB of zeros: about 300 KB deflated
    if how == "a known entry":
        rewrite(source, {"vertex_attributes/0.npy": bomb})
    else:
        rewrite(source, {}, {"extra.npy": bomb})
    assert source.stat().st_size < 2_000_000
    start = time.perf_counter()
    done = run("reconstruct", str(folder), "-o", str(folder / "r.ply"))
    line = one_line_error(done)
    assert "source.npz" in line and ("unexpected entries" in line or "refused unread" in line), line
    assert time.perf_counter() - start < 20  # refused, not decompressed (that takes seconds and 320 MB)


def test_a_decomposition_that_declares_more_than_memory_names_its_file(folder):
    header = pyio.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (10**15, 3)})
    rewrite(folder / "decomposition.npz", {"base.npy": header.getvalue() + b"\0" * 64})
    with pytest.raises(ValueError, match="decomposition.npz"):
        ps.load(folder / "decomposition.npz")


def test_an_empty_output_is_refused_before_any_work(tmp_path):
    ps.io.write(tmp_path / "in.ply", ps.io.Scan(points=ps.shapes.bumpy_sphere(2000), precision=np.float64))
    for command in (["decompose", str(tmp_path / "in.ply")], ["reconstruct", str(tmp_path)]):
        done = run(*command, "-o", "")
        assert done.returncode == 2 and "-o/--output: is empty" in done.stderr, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.ply"]


def test_a_source_npz_that_is_a_folder_or_names_an_attribute_twice_is_refused(folder):
    import json

    source = folder / "source.npz"
    with np.load(source) as loaded:
        arrays = dict(loaded)
    meta = json.loads(bytes(arrays["meta_json"]).decode())
    meta["vertex_attributes"] = meta["vertex_attributes"] * 2
    arrays["meta_json"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    arrays["vertex_attributes/1"] = arrays["vertex_attributes/0"]
    np.savez(source, **arrays)
    assert "twice" in one_line_error(run("reconstruct", str(folder), "-o", str(folder / "r.ply")))
    source.unlink()
    source.mkdir()
    assert "is not a file" in one_line_error(run("reconstruct", str(folder), "-o", str(folder / "r.ply")))
    assert not (folder / "r.ply").exists()


def test_a_las_extra_bytes_name_too_long_is_named(tmp_path):
    name = "a_rather_long_attribute_name_from_a_scanner"
    scan = ps.io.Scan(points=points(), precision=np.float64, vertex_attributes={name: np.arange(400, dtype=np.float32)})
    with pytest.raises(ValueError, match=name):
        ps.io.write(tmp_path / "long.las", scan)
    ps.io.write(tmp_path / "long.ply", scan)  # and the format it names keeps it
    assert np.array_equal(ps.io.read(tmp_path / "long.ply").vertex_attributes[name], np.arange(400, dtype=np.float32))


def mixed_mesh_with_corner_uvs(path: Path):
    """Triangles and quads with MeshLab's per-corner texcoord (6 or 8 values a face) and a face
    quality; returns the face records written."""
    p = ps.shapes.bumpy_sphere(1500, seed=4)
    order = np.argsort(np.arctan2(p[:, 1], p[:, 0]))
    faces = [order[i:i + (4 if i % 3 else 3)] for i in range(0, 1200, 4)]
    rng = np.random.default_rng(8)
    vertex = np.array([tuple(r) for r in p], dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    face = np.empty(len(faces), dtype=[("vertex_indices", "O"), ("texcoord", "O"), ("quality", "f4")])
    face["vertex_indices"] = [np.asarray(f, "i4") for f in faces]
    face["texcoord"] = [rng.random(2 * len(f)).astype("f4") for f in faces]
    face["quality"] = rng.random(len(faces)).astype("f4")
    PlyData([PlyElement.describe(vertex, "vertex"),
             PlyElement.describe(face, "face", val_types={"vertex_indices": "i4", "texcoord": "f4"})]).write(str(path))
    return face


def test_face_lists_of_varying_length_survive_every_file(tmp_path):
    face = mixed_mesh_with_corner_uvs(tmp_path / "mixed.ply")
    scan = ps.io.read(tmp_path / "mixed.ply")
    assert {len(t) for t in scan.face_attributes["texcoord"]} == {6, 8}
    # These faces are a few strips, not one surface: decomposed as one point set (--parts none).
    assert run("decompose", str(tmp_path / "mixed.ply"), "-o", str(tmp_path / "out"), "--levels", "3",
               "--parts", "none").returncode == 0
    assert run("reconstruct", str(tmp_path / "out"), "-o", str(tmp_path / "r.ply"), "--gains", "2,1").returncode == 0
    for name in ("out/level_0.ply", "out/level_2.ply", "r.ply"):
        written = PlyData.read(str(tmp_path / name))["face"]
        assert all(np.array_equal(a, b) for a, b in zip(written["texcoord"], face["texcoord"])), name
        assert written["texcoord"][0].dtype == np.float32
        assert np.array_equal(written["quality"], face["quality"]), name
    scan.format_info["text"] = True  # and as ASCII
    ps.io.write(tmp_path / "ascii.ply", scan)
    again = ps.io.read(tmp_path / "ascii.ply").face_attributes["texcoord"]
    assert all(np.array_equal(a, b) for a, b in zip(again, face["texcoord"]))


def test_face_list_offsets_that_do_not_fit_are_refused(tmp_path):
    mixed_mesh_with_corner_uvs(tmp_path / "mixed.ply")
    arrays = ps.io.read(tmp_path / "mixed.ply").to_arrays()
    key = next(k for k in arrays if k.endswith(".offsets"))
    assert ps.io.Scan.from_arrays(dict(arrays)).n_faces == 300
    arrays[key] = arrays[key][::-1].copy()
    with pytest.raises(ValueError, match="offsets do not describe lists"):
        ps.io.Scan.from_arrays(arrays)
