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
