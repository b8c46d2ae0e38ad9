"""scripts/extension_freshness.py: the install test and the build step's --if-stale agree on
when dist/'s extension zip is the one addon/ and native/ make now, and say why when it is not."""

import importlib.util
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("extension_freshness", ROOT / "scripts" / "extension_freshness.py")
freshness = importlib.util.module_from_spec(spec)
spec.loader.exec_module(freshness)

WHEEL = "pointscale-0.1.0-cp311-cp311-manylinux_2_28_x86_64.whl"


@pytest.fixture
def tree(tmp_path, monkeypatch):
    """A clone in miniature, built: sources, a stamped wheel and the zip of both."""
    (tmp_path / "addon").mkdir()
    (tmp_path / "addon" / "__init__.py").write_text("# add-on\n")
    (tmp_path / "native" / "src").mkdir(parents=True)
    (tmp_path / "native" / "src" / "core.cpp").write_text("// core\n")
    (tmp_path / "CMakeLists.txt").write_text("")
    (tmp_path / "pyproject.toml").write_text("")
    for name, value in (("ROOT", tmp_path), ("DIST", tmp_path / "dist"), ("WHEELS", tmp_path / "dist" / "wheels"),
                        ("STAMP", tmp_path / "dist" / "wheels" / "SOURCES")):
        monkeypatch.setattr(freshness, name, value)
    (tmp_path / "dist" / "wheels").mkdir(parents=True)
    (tmp_path / "dist" / "wheels" / WHEEL).write_bytes(b"wheel")
    freshness.write_stamp()
    with zipfile.ZipFile(tmp_path / "dist" / "pointscale-0.1.0-linux_x64.zip", "w") as z:
        z.writestr("__init__.py", "# add-on\n")
        z.writestr(f"wheels/{WHEEL}", b"wheel")
    return tmp_path


def test_a_fresh_build_is_current(tree):
    assert freshness.stale_reason(["cp311"]) is None


def test_each_change_is_named(tree):
    assert "no engine wheel for cp313" in freshness.stale_reason(["cp311", "cp313"])
    (tree / "addon" / "keys.py").write_text("")
    assert "addon/keys.py" in freshness.stale_reason(["cp311"])
    (tree / "addon" / "keys.py").unlink()
    (tree / "addon" / "__init__.py").write_text("# changed\n")
    assert "addon/__init__.py" in freshness.stale_reason(["cp311"])
    (tree / "native" / "src" / "core.cpp").write_text("// changed\n")
    assert "other sources than native/" in freshness.stale_reason(["cp311"])


def test_a_zip_of_older_wheels_is_stale(tree):
    (tree / "dist" / "wheels" / WHEEL).write_bytes(b"rebuilt wheel")
    assert f"another wheels/{WHEEL}" in freshness.stale_reason(["cp311"])


def test_no_zip_at_all(tree):
    (tree / "dist" / "pointscale-0.1.0-linux_x64.zip").unlink()
    assert "no extension zip" in freshness.stale_reason(["cp311"])
