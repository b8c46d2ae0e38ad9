"""CloudCompare's ASCII clouds (.txt, .asc): read as XYZ, whatever separator and header options
its export dialog was given, and written back with the header it reads."""
import numpy as np
import pytest

import pointscale as ps
from pointscale import io
from helpers import one_line_error, run_cli


def cloudcompare_file(path, points, colours, intensity, normals, separator=",", header=True, count=True):
    """What CloudCompare's "Save as ASCII cloud" writes: coordinates with 8 decimals, colours as
    whole numbers, scalar fields with 6 decimals, normals last, and at the top, when asked, a
    "//" line naming the columns and a line with the point count."""
    lines = []
    if header:
        lines.append("//" + separator.join(["X", "Y", "Z", "R", "G", "B", "Intensity", "Nx", "Ny", "Nz"]))
    if count:
        lines.append(str(len(points)))
    for p, c, i, n in zip(points, colours, intensity, normals):
        values = [f"{v:.8f}" for v in p] + [str(v) for v in c] + [f"{i:.6f}"] + [f"{v:.6f}" for v in n]
        lines.append(separator.join(values))
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def georeferenced():
    rng = np.random.default_rng(4)
    points = ps.shapes.bumpy_sphere(3000, noise=0.0) * 20.0 + np.array([500123.0, 5400987.0, 312.0])
    normals = rng.normal(size=(len(points), 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    colours = rng.integers(0, 256, (len(points), 3))
    intensity = rng.uniform(0, 2000, len(points))
    return np.round(points, 8), colours, np.round(intensity, 6), np.round(normals, 6)


@pytest.mark.parametrize("separator", [",", ";", " ", "\t"])
@pytest.mark.parametrize("header,count", [(True, True), (True, False), (False, False)])
def test_every_export_option_of_cloudcompare_reads(tmp_path, georeferenced, separator, header, count):
    points, colours, intensity, normals = georeferenced
    path = tmp_path / "scan.txt"
    cloudcompare_file(path, points, colours, intensity, normals, separator, header, count)
    scan = io.read(path)
    assert np.array_equal(scan.points, points)  # every digit of the 8 decimals
    if header:
        assert np.array_equal(scan.normals, normals)
        assert all(scan.vertex_attributes[c].dtype == np.uint8 for c in ("red", "green", "blue"))
        assert np.array_equal(np.column_stack([scan.vertex_attributes[c] for c in ("red", "green", "blue")]), colours)
        assert np.array_equal(scan.vertex_attributes["Intensity"], intensity)
    else:  # no names: colours are not guessed (README), the columns are kept as they are
        assert len(scan.vertex_attributes) + 3 * (scan.normals is not None) == 7


def test_a_count_line_that_does_not_match_the_rows_is_refused(tmp_path, georeferenced):
    points, colours, intensity, normals = georeferenced
    path = tmp_path / "cut.asc"
    cloudcompare_file(path, points, colours, intensity, normals)
    path.write_text("".join(path.read_text().splitlines(keepends=True)[:-10]))  # a copy cut short
    with pytest.raises(ValueError, match=f"count line says {len(points)} points, the file has {len(points) - 10}"):
        io.read(path)


def test_a_written_txt_has_the_header_cloudcompare_reads_and_reads_back_the_same(tmp_path, georeferenced):
    points, colours, intensity, normals = georeferenced
    source = tmp_path / "scan.txt"
    cloudcompare_file(source, points, colours, intensity, normals)
    scan = io.read(source)
    for name in ("out.txt", "out.asc"):
        io.write(tmp_path / name, scan)
        first = (tmp_path / name).read_text().splitlines()[0]
        assert first.startswith("//x y z nx")  # "#" lines CloudCompare would take for rows
        again = io.read(tmp_path / name)
        assert np.array_equal(again.points, scan.points) and np.array_equal(again.normals, scan.normals)
        for key, values in scan.vertex_attributes.items():
            assert again.vertex_attributes[key].dtype == values.dtype
            assert np.array_equal(again.vertex_attributes[key], values)
    io.write(tmp_path / "plain.txt", io.Scan(points=points))  # a header even with nothing but x y z
    assert (tmp_path / "plain.txt").read_text().splitlines()[0] == "//x y z"


def test_the_command_line_decomposes_a_text_cloud_into_xyz_levels_and_leaves_txt_files_alone(tmp_path,
                                                                                             georeferenced):
    """A text cloud's level files are .xyz (the same columns, which CloudCompare reads), never
    .txt: a user's level_1.txt beside them stays theirs, --force or not."""
    points, colours, intensity, normals = georeferenced
    cloudcompare_file(tmp_path / "scan.txt", points, colours, intensity, normals)
    out = tmp_path / "out"
    out.mkdir()
    (out / "level_1.txt").write_text("my notes on level 1\n")
    for extra in ([], ["--force"]):
        done = run_cli("decompose", "scan.txt", "-o", "out", "--levels", "3", *extra, cwd=tmp_path)
        assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in out.iterdir()) == ["decomposition.npz", "level_0.xyz", "level_1.txt", "level_1.xyz",
                                                     "level_2.xyz", "source.npz"]
    assert (out / "level_1.txt").read_text() == "my notes on level 1\n"
    for level in range(3):  # with the header line CloudCompare reads ("#" lines it takes for rows)
        assert (out / f"level_{level}.xyz").read_text().startswith("//x y z nx:f8 ny:f8 nz:f8 red:u1")
    finest = io.read(out / "level_2.xyz")
    assert np.array_equal(finest.points, points)
    assert np.array_equal(finest.vertex_attributes["Intensity"], intensity)
    # reconstruct writes a .txt where asked, and takes one as --base
    done = run_cli("reconstruct", "out", "--base", "out/level_0.xyz", "-o", "result.txt", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    result = io.read(tmp_path / "result.txt")
    assert np.abs(result.points - points).max() < 1e-9  # unedited: the input, to rounding (3.4e-13 measured)
    assert np.array_equal(result.vertex_attributes["red"], colours[:, 0].astype(np.uint8))
    io.write(tmp_path / "base.txt", io.read(out / "level_0.xyz"))
    done = run_cli("reconstruct", "out", "--base", "base.txt", "-o", "again.ply", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert np.abs(io.read(tmp_path / "again.ply").points - points).max() < 1e-9


def test_levels_are_never_written_as_txt(tmp_path):
    io.write(tmp_path / "scan.ply", io.Scan(points=ps.shapes.bumpy_sphere(3000)))
    message = one_line_error(run_cli("decompose", "scan.ply", "-o", "out", "--format", "txt", cwd=tmp_path))
    assert "level files are never .txt" in message and ".xyz" in message


def test_an_xyz_keeps_its_own_comment_mark(tmp_path):
    """An .xyz read with "#" lines is written back with "#", one read with CloudCompare's "//"
    with "//"."""
    points = ps.shapes.bumpy_sphere(500)
    for mark in ("#", "//"):
        text = f"{mark} x y z intensity\n" + "".join(f"{p[0]:.6f} {p[1]:.6f} {p[2]:.6f} 7\n" for p in points)
        (tmp_path / "in.xyz").write_text(text)
        io.write(tmp_path / "out.xyz", io.read(tmp_path / "in.xyz"))
        assert (tmp_path / "out.xyz").read_text().startswith(f"{mark}{' ' if mark == '#' else ''}x y z intensity")


@pytest.mark.parametrize("text", ["1.5,2.5,3.5\n", "//X;Y;Z\n1.5;2.5;3.5\n", "1,2,3\n# a note\n4,5,6\n"])
def test_the_separator_is_told_from_the_first_row(tmp_path, text):
    (tmp_path / "a.xyz").write_text(text)
    assert io.read(tmp_path / "a.xyz").points[0].tolist() == ([1.5, 2.5, 3.5] if "." in text else [1.0, 2.0, 3.0])


def test_cloudcompare_float_colours_are_colours_and_fill_las_16_bit_fields(tmp_path):
    """CloudCompare's export can write colours as floats 0..1 (Rf Gf Bf): read as the colours
    red, green, blue, which the LAS writer scales to its 16 bits, not as three unknown columns
    that LAS would keep as extra bytes."""
    points = ps.shapes.bumpy_sphere(800)
    colours = np.random.default_rng(2).uniform(0, 1, (len(points), 3)).round(6)
    rows = np.column_stack([points, colours])
    (tmp_path / "c.txt").write_text("//X,Y,Z,Rf,Gf,Bf\n" + "".join(",".join(f"{v:.6f}" for v in r) + "\n" for r in rows))
    scan = io.read(tmp_path / "c.txt")
    assert [k for k in scan.vertex_attributes] == ["red", "green", "blue"]
    assert np.array_equal(scan.vertex_attributes["green"], rows[:, 4])
    pytest.importorskip("laspy")
    with pytest.warns(UserWarning):
        io.write(tmp_path / "c.las", scan)
    back = io.read(tmp_path / "c.las")
    assert np.abs(back.vertex_attributes["red"] / 65535.0 - colours[:, 0]).max() < 1e-5
