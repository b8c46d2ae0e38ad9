"""Files, after a fourth reader's pass (2026-12-07): decompression bombs in a shared
decomposition folder, a named pipe given to load, colours that E57, PTS and XYZ lost or
mislabelled, and E57 fields that some scans lack."""
import io as bytes_io
import json
import os
import subprocess
import sys
import tracemalloc
import warnings
import zipfile

import numpy as np
import pytest
from plyfile import PlyData

import pointscale as ps
from pointscale import io
from pointscale.cli.folder import read_decomposition
from helpers import one_line_error, run_cli as run

# A bomb entry of this many bytes of deflated zeros (64 KB on disk). The old checks let it
# unpack: every assertion below bounds the peak well under it.
BOMB = 64 << 20
# Reading the small folder below peaks at 0.5 MB traced (tracemalloc), refusing a bomb at 0.5 MB;
# the old checks peaked at 68-91 MB, the bomb unpacked.
PEAK_BOUND = 4 << 20


def write_zero_entry(archive: zipfile.ZipFile, name: str, nbytes: int, shape=None, descr="|u1") -> None:
    """name.npy holding nbytes of zeros, streamed so that the test itself stays small."""
    header = bytes_io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": descr, "fortran_order": False,
                                                  "shape": shape or (nbytes // np.dtype(descr).itemsize,)})
    with archive.open(name + ".npy", "w", force_zip64=True) as f:
        f.write(header.getvalue())
        chunk = bytes(1 << 22)
        for start in range(0, nbytes, len(chunk)):
            f.write(chunk[:min(len(chunk), nbytes - start)])


def rewrite_npz(path, replace: dict | None = None, add=None) -> None:
    """path again with entries `replace` (name -> callable(archive, name)) written differently
    and `add` (callable(archive)) appended."""
    with zipfile.ZipFile(path) as old:
        entries = {info.filename: old.read(info.filename) for info in old.infolist()}
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as new:
        for filename, data in entries.items():
            name = filename[:-4]
            if replace and name in replace:
                replace[name](new, name)
            else:
                new.writestr(filename, data)
        if add:
            add(new)


def peak_of(call) -> tuple[int, Exception | None]:
    """(peak traced bytes, the exception raised or None) of call()."""
    tracemalloc.start()
    try:
        call()
        error = None
    except Exception as exc:  # noqa: BLE001 - returned for the test to judge
        error = exc
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak, error


@pytest.fixture(scope="module")
def small_decomposition():
    points = ps.shapes.bumpy_sphere(2000, noise=0.001)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return points, ps.decompose(points, levels=3)


@pytest.fixture
def folder(tmp_path, small_decomposition):
    """A decomposition folder as decompose writes it: the model and the input's attributes."""
    points, dec = small_decomposition
    dec.save(tmp_path / "decomposition.npz")
    scan = io.Scan(points=points, vertex_attributes={"intensity": np.arange(len(points), dtype=np.uint16)})
    np.savez_compressed(tmp_path / "source.npz", **scan.to_arrays())
    return tmp_path


def meta_of(path) -> dict:
    with np.load(path) as f:
        return json.loads(f["meta_json"].tobytes().decode())


def set_meta(archive, name, meta):
    buffer = bytes_io.BytesIO()
    np.save(buffer, np.frombuffer(json.dumps(meta).encode(), np.uint8))
    archive.writestr(name + ".npy", buffer.getvalue())


# -- 1a: source.npz sized by the decomposition's real point count --------------------------------

def test_a_source_npz_that_declares_more_points_than_the_decomposition_is_refused_unread(folder):
    """Before, the budget (4 KB a point) came from the n_points source.npz declares about itself:
    a million declared for 2000 real points let a 64 MB entry unpack before any check."""
    meta = dict(meta_of(folder / "source.npz"), n_points=1_000_000)
    rewrite_npz(folder / "source.npz", replace={
        "meta_json": lambda archive, name: set_meta(archive, name, meta),
        "vertex_attributes/0": lambda archive, name: write_zero_entry(archive, name, BOMB)})
    peak, error = peak_of(lambda: read_decomposition(folder))
    assert peak < PEAK_BOUND, (peak, error)
    assert isinstance(error, ValueError) and "1000000 points where 2000 are expected" in str(error)


def test_a_source_npz_with_its_true_count_and_an_oversized_entry_is_refused_unread(folder):
    """With its true count, the old budget still allowed 256 MB beside 4 KB a point: the 64 MB
    entry unpacked before its shape was found wrong."""
    rewrite_npz(folder / "source.npz", replace={
        "vertex_attributes/0": lambda archive, name: write_zero_entry(archive, name, BOMB)})
    peak, error = peak_of(lambda: read_decomposition(folder))
    assert peak < PEAK_BOUND, (peak, error)
    assert isinstance(error, ValueError) and "refused unread" in str(error)


def test_the_command_line_refuses_the_source_bomb_in_one_line(folder, tmp_path):
    meta = dict(meta_of(folder / "source.npz"), n_points=1_000_000)
    rewrite_npz(folder / "source.npz", replace={"meta_json": lambda archive, name: set_meta(archive, name, meta)})
    error = one_line_error(run("reconstruct", str(folder), "-o", str(tmp_path / "out.ply")))
    assert "source.npz" in error and "refused unread" in error


# -- 1b: decomposition.npz: no unknown entries, no entry beyond what n points hold ---------------

def test_an_unknown_entry_in_a_decomposition_file_is_refused_unread(folder):
    """Before, an extra entry was unpacked whole and then ignored: the load succeeded."""
    rewrite_npz(folder / "decomposition.npz", add=lambda archive: write_zero_entry(archive, "zz_unknown", BOMB))
    peak, error = peak_of(lambda: ps.load(folder / "decomposition.npz"))
    assert peak < PEAK_BOUND, (peak, error)
    assert isinstance(error, ValueError) and "zz_unknown" in str(error) and "refused unread" in str(error)


def test_a_known_entry_declaring_more_than_its_points_hold_is_refused_unread(folder):
    """kernel_0 holds one float a cluster, at most one a point: 16 KB for 2000 points, not 64 MB."""
    rewrite_npz(folder / "decomposition.npz", replace={
        "kernel_0": lambda archive, name: write_zero_entry(archive, name, BOMB, descr="<f8")})
    peak, error = peak_of(lambda: ps.load(folder / "decomposition.npz"))
    assert peak < PEAK_BOUND, (peak, error)
    assert isinstance(error, ValueError) and "'kernel_0' declares" in str(error)


def decomposition_of(kind):
    """A small decomposition of each kind that save writes, with the entries peculiar to it."""
    sphere = ps.shapes.bumpy_sphere(2500, noise=0.001)
    if kind == "parts":
        v, f, _ = ps.meshes.joined(ps.meshes.uv_sphere(1.0, 48, 24), ps.meshes.uv_sphere(0.5, 32, 16))
        v[-(32 * 15 + 2):] += [3.0, 0, 0]  # the small sphere beside the big one: two parts
        return ps.decompose(v, 3, faces=f)
    if kind == "mirror":
        return ps.decompose(sphere[sphere[:, 0] >= 0.02], 3, mirror=ps.Mirror("x"))
    if kind == "encode":
        return ps.encode(sphere, ps.ellipsoid_base(sphere, n=1500))
    options = {"plain": {}, "diffusion": {"smoother": "diffusion"}, "rayshoot": {"encoding": "rayshoot"},
               "sheets": {"sheets": True}, "all options": {"decimation": 0.3, "kernel": 1.5, "neighbors": 30,
                                                          "smoother": "diffusion", "taubin": False}}[kind]
    return ps.decompose(sphere, 3, **options)


@pytest.mark.parametrize("kind", ["plain", "diffusion", "rayshoot", "sheets", "mirror", "parts", "encode",
                                  "all options"])
def test_every_kind_of_decomposition_loads_and_the_same_file_with_an_extra_entry_does_not(tmp_path, kind):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dec = decomposition_of(kind)
    path = tmp_path / "d.npz"
    dec.save(path)
    back = ps.load(path)
    assert np.array_equal(ps.reconstruct(back), ps.reconstruct(dec))
    if kind == "parts":
        assert "parts" in np.load(path).files
    if kind == "mirror":
        assert "mirror_seam" in np.load(path).files
    rewrite_npz(path, add=lambda archive: write_zero_entry(archive, "notes", 8))
    with pytest.raises(ValueError, match="notes; refused unread"):
        ps.load(path)


# -- 6: a named pipe ---------------------------------------------------------------------------

def test_load_and_read_refuse_a_named_pipe_instead_of_waiting_on_it(tmp_path):
    """Before, ps.load and Scan.from_arrays opened the pipe and waited for a writer forever."""
    calls = {"load": "ps.load(p)", "read": "ps.io.read(p)", "source": "ps.io.Scan.from_arrays(p)"}
    for name, call in calls.items():
        pipe = tmp_path / f"{name}.{'ply' if name == 'read' else 'npz'}"
        os.mkfifo(pipe)
        script = (f"import pointscale as ps\np = {str(pipe)!r}\ntry:\n    {call}\nexcept ValueError as e:\n"
                  "    print(e)\n")
        try:
            done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=30)
        except subprocess.TimeoutExpired:
            pytest.fail(f"{call} waited on a named pipe")
        assert "named pipe" in done.stdout and str(pipe) in done.stdout, (call, done.stdout, done.stderr)


# -- 2: E57 output keeps 8-bit colours held in 16-bit fields ---------------------------------------

def las_scan(red, green, blue, intensity=None):
    """A Scan as the LAS reader gives one: colours in uint16 fields."""
    n = len(red)
    points = np.column_stack([np.linspace(0, 10, n), np.sin(np.arange(n)), np.cos(np.arange(n) * 0.3)])
    attributes = {"red": red.astype(np.uint16), "green": green.astype(np.uint16), "blue": blue.astype(np.uint16)}
    if intensity is not None:
        attributes["intensity"] = intensity
    return io.Scan(points=points + [512000.0, 5403000.0, 400.0], vertex_attributes=attributes)


def test_eight_bit_colours_in_sixteen_bit_fields_survive_e57(tmp_path):
    """Before, every uint16 value was divided by 257: 0..255 became 0 (black)."""
    pytest.importorskip("pye57")
    rgb = np.random.default_rng(0).integers(0, 256, (3, 500))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no loss, so no warning
        io.write(tmp_path / "c.e57", las_scan(*rgb))
    back = io.read(tmp_path / "c.e57")
    for name, values in zip(("red", "green", "blue"), rgb):
        assert np.array_equal(back.vertex_attributes[name], values)


def test_sixteen_bit_colours_in_e57_are_scaled_with_a_warning(tmp_path):
    pytest.importorskip("pye57")
    rgb = np.random.default_rng(1).integers(0, 65536, (3, 500))
    rgb[:, 0] = [65535, 256, 0]
    with pytest.warns(UserWarning, match="16-bit colours red, green, blue written as 8-bit.*low 8 bits are lost"):
        io.write(tmp_path / "c.e57", las_scan(*rgb))
    back = io.read(tmp_path / "c.e57")
    for name, values in zip(("red", "green", "blue"), rgb):
        assert np.array_equal(back.vertex_attributes[name], np.round(values * 255 / 65535))


# -- 3: E57 fields that only some scans have; rowIndex and columnIndex -------------------------------

def two_scan_e57(path, grid: bool):
    pye57 = pytest.importorskip("pye57")
    rng = np.random.default_rng(0)
    e57 = pye57.E57(str(path), mode="w")
    for s in range(2):
        n = 300
        data = {"cartesianX": rng.uniform(0, 5, n), "cartesianY": rng.uniform(0, 5, n), "cartesianZ": rng.uniform(0, 1, n)}
        if s == 0 and not grid:  # one scanner with a camera, one without
            data.update(intensity=rng.uniform(0, 1, n), colorRed=rng.integers(0, 256, n).astype(np.uint8),
                        colorGreen=rng.integers(0, 256, n).astype(np.uint8),
                        colorBlue=rng.integers(0, 256, n).astype(np.uint8))
        if grid:
            data.update(intensity=rng.uniform(0, 1, n), rowIndex=(np.arange(n) // 20).astype(np.uint16),
                        columnIndex=(np.arange(n) % 20).astype(np.uint16))
        e57.write_scan_raw(data, rotation=np.array([1.0, 0, 0, 0]), translation=np.array([10.0 * s, 0, 0]))
    e57.close()
    return pye57


def test_a_field_only_one_scan_has_is_kept_and_the_others_filled_with_a_warning(tmp_path):
    """Before, io.read kept only scan_id: intensity and colours of scan 0 were dropped, silently."""
    pye57 = two_scan_e57(tmp_path / "mixed.e57", grid=False)
    with pytest.warns(UserWarning, match=r"scan 1 of 2 has no intensity, red, green, blue.*filled with 0"):
        scan = io.read(tmp_path / "mixed.e57")
    raw = pye57.E57(str(tmp_path / "mixed.e57")).read_scan(0, intensity=True, colors=True,
                                                                ignore_missing_fields=True)
    assert np.array_equal(scan.vertex_attributes["red"][:300], raw["colorRed"])
    assert np.array_equal(scan.vertex_attributes["red"][300:], np.zeros(300))
    assert np.allclose(scan.vertex_attributes["intensity"][:300], raw["intensity"])
    assert list(scan.vertex_attributes["scan_id"][[0, 300]]) == [0, 1]


def test_row_and_column_indices_are_kept_and_written_back(tmp_path):
    two_scan_e57(tmp_path / "grid.e57", grid=True)
    scan = io.read(tmp_path / "grid.e57")
    expected = np.tile(np.arange(300) // 20, 2)
    assert np.array_equal(scan.vertex_attributes["rowIndex"], expected)
    assert np.array_equal(scan.vertex_attributes["columnIndex"], np.tile(np.arange(300) % 20, 2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # scan_id is written too, as the scans (test_files_fifth_pass.py)
        io.write(tmp_path / "back.e57", scan)
    back = io.read(tmp_path / "back.e57")
    assert np.array_equal(back.vertex_attributes["rowIndex"], expected)
    assert np.array_equal(back.vertex_attributes["scan_id"], scan.vertex_attributes["scan_id"])


# -- 4: XYZ colour columns named in a header -------------------------------------------------------

def xyz_with_colours(path, header, rgb):
    points = np.column_stack([np.linspace(0, 4, len(rgb)), np.sin(np.arange(len(rgb))), np.zeros(len(rgb))])
    with open(path, "w") as f:
        if header:
            f.write(header + "\n")
        for p, c in zip(points, rgb):
            f.write(f"{p[0]:.6f} {p[1]:.6f} {p[2]:.6f} {c[0]} {c[1]} {c[2]}\n")


@pytest.mark.parametrize("header", ["//X Y Z R G B", "# x y z r g b", "# X Y Z Red Green Blue"])
def test_colour_columns_named_in_an_xyz_header_become_colours_every_writer_knows(tmp_path, header):
    """Before, R G B were float64 attributes: LAS wrote point format 6 (no RGB), PLY 'double R'."""
    rgb = np.random.default_rng(2).integers(0, 256, (400, 3))
    xyz_with_colours(tmp_path / "c.xyz", header, rgb)
    scan = io.read(tmp_path / "c.xyz")
    for name, values in zip(("red", "green", "blue"), rgb.T):
        assert scan.vertex_attributes[name].dtype == np.uint8 and np.array_equal(scan.vertex_attributes[name], values)
    io.write(tmp_path / "c.las", scan)
    las = io.read(tmp_path / "c.las")
    assert las.format_info["point_format"] == 7
    assert np.array_equal(las.vertex_attributes["red"], rgb[:, 0] * 257)
    io.write(tmp_path / "c.ply", scan)
    assert PlyData.read(str(tmp_path / "c.ply"))["vertex"].ply_property("red").val_dtype in ("u1", "uint8")


def test_sixteen_bit_xyz_colours_are_uint16_and_headerless_columns_are_not_guessed(tmp_path):
    rgb = np.random.default_rng(3).integers(0, 65536, (300, 3))
    xyz_with_colours(tmp_path / "c16.xyz", "//X Y Z R G B", rgb)
    scan = io.read(tmp_path / "c16.xyz")
    assert scan.vertex_attributes["red"].dtype == np.uint16
    assert np.array_equal(scan.vertex_attributes["blue"], rgb[:, 2])
    xyz_with_colours(tmp_path / "plain.xyz", None, rgb % 256)
    assert "red" not in io.read(tmp_path / "plain.xyz").vertex_attributes


# -- 5: PTS colours and intensity ------------------------------------------------------------------

def test_pts_writes_sixteen_bit_colours_as_eight_bit_and_says_what_it_keeps(tmp_path):
    """Before, LAS colours up to 65535 went into PTS's 0..255 columns, without a word."""
    rng = np.random.default_rng(4)
    rgb = rng.integers(0, 65536, (3, 400))
    rgb[:, 0] = 65535
    intensity = rng.integers(0, 65536, 400).astype(np.uint16)
    with pytest.warns(UserWarning) as record:
        io.write(tmp_path / "t.pts", las_scan(*rgb, intensity=intensity))
    messages = " ".join(str(w.message) for w in record)
    assert "16-bit colours red, green, blue written as 8-bit" in messages
    assert "intensity" in messages and "-2048..2047" in messages
    back = io.read(tmp_path / "t.pts")
    assert back.vertex_attributes["red"].max() == 255
    assert np.array_equal(back.vertex_attributes["green"], np.round(rgb[1] * 255 / 65535))
    assert np.array_equal(back.vertex_attributes["intensity"], intensity)  # kept as it was
    eight_bit = rgb % 256  # 8-bit colours in 16-bit fields, as photogrammetry exporters write LAS
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing is lost, so nothing is said
        io.write(tmp_path / "t8.pts", las_scan(*eight_bit))
    assert np.array_equal(io.read(tmp_path / "t8.pts").vertex_attributes["blue"], eight_bit[2])


# -- the finest level file is the input, bit for bit ---------------------------------------------

@pytest.mark.parametrize("extension", [".ply", ".xyz"])
def test_the_finest_level_file_holds_the_inputs_own_coordinates(tmp_path, extension):
    """README: "the finest level, which is the input". It was the model rebuilt, exact to
    rounding only: a reviewer's float64 torus at (1000, 2000, 50) came back with 184 of 21,600
    coordinates changed (up to 58 units in the last place), and a text sphere's exact zeros as
    7.7e-19. A technician comparing the file with the scan saw most points moved."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 90, endpoint=False), np.linspace(0, 2 * np.pi, 60, endpoint=False))
    u, v = u.ravel(), v.ravel()
    points = np.stack([(1.0 + 0.3 * np.cos(v)) * np.cos(u), (1.0 + 0.3 * np.cos(v)) * np.sin(u), 0.3 * np.sin(v)], 1)
    points = np.round(points * 1000 + [1000.0, 2000.0, 50.0], 6)
    points[::7, 2] = 0.0 + 50.0  # values a text file holds exactly
    source = tmp_path / f"torus{extension}"
    io.write(source, io.Scan(points=points))
    done = run("decompose", str(source), "-o", str(tmp_path / "out"), "--levels", "3", "--decimation", "0.3")
    assert done.returncode == 0, done.stderr
    written = io.read(tmp_path / "out" / f"level_2{extension}").points
    read_back = io.read(source).points
    assert np.array_equal(written, read_back)


def test_a_base_in_another_vertex_order_is_warned_of(tmp_path):
    """--base with the decomposition's count but another vertex order (a cloud re-saved sorted)
    paired each point with another's detail: points moved a median of half the model's size, and
    the command said nothing. Its --help asks for the same order; now a warning says it was not.
    1000 points: a shuffled base stretches its neighbours least on a small model."""
    rng = np.random.default_rng(4)
    u = rng.normal(size=(1000, 3))
    points = u / np.linalg.norm(u, axis=1, keepdims=True) * [1.5, 1.0, 0.8]
    source = tmp_path / "ell.ply"
    io.write(source, io.Scan(points=points))
    assert run("decompose", str(source), "-o", str(tmp_path / "out"), "--levels", "3").returncode == 0
    level0 = io.read(tmp_path / "out" / "level_0.ply")
    sorted_base = tmp_path / "sorted.ply"
    io.write(sorted_base, level0.with_geometry(level0.points[np.lexsort(level0.points.T)], None))
    lifted = tmp_path / "lifted.ply"
    io.write(lifted, level0.with_geometry(level0.points * [1.0, 1.0, 1.3] + [0.0, 0.0, 0.2], None))
    centimetres = tmp_path / "centimetres.ply"  # a uniform scale is an edit, however large
    io.write(centimetres, level0.with_geometry(level0.points * 100.0, None))
    for base, warned in ((sorted_base, True), (lifted, False), (centimetres, False)):
        done = run("reconstruct", str(tmp_path / "out"), "--base", str(base), "-o", str(tmp_path / f"r_{base.stem}.ply"))
        assert done.returncode == 0, done.stderr
        assert ("another vertex order" in done.stderr) == warned, done.stderr
        # The warning keeps its subject (the command line cut "--base <path>:" off as a file name).
        assert (f"warning: --base {base}: points that neighbour" in done.stderr) == warned, done.stderr


def test_float_colours_rounded_just_past_one_stay_fractions(tmp_path):
    """Float colours of 0..1 with one value rounded to 1.0000001 were taken for 8-bit values and
    written rounded: every colour 0 or 1, black (a reviewer's green, 253 at most, came out 1)."""
    rng = np.random.default_rng(3)
    colours = rng.uniform(0.0, 0.99, size=(200, 3))
    colours[7, 1] = 1.0000001
    scan = io.Scan(points=rng.normal(size=(200, 3)),
                   vertex_attributes={"red": colours[:, 0], "green": colours[:, 1], "blue": colours[:, 2]})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        io.write(tmp_path / "c.pts", scan)
    written = io.read(tmp_path / "c.pts").vertex_attributes
    assert int(written["green"][7]) == 255
    assert np.abs(written["red"].astype(float) - 255 * colours[:, 0]).max() <= 0.5
