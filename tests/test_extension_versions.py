"""scripts/build_extension.py: the Blender version range the zip's manifest claims follows the
engine wheels inside (Blender 4.2-5.0 ship Python 3.11, 5.1+ ship 3.13)."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("build_extension", ROOT / "scripts" / "build_extension.py")
build_extension = importlib.util.module_from_spec(spec)
spec.loader.exec_module(build_extension)


def wheels(*tags):
    return [Path(f"pointscale-0.1.0-{t}-{t}-manylinux_2_34_x86_64.whl") for t in tags]


@pytest.mark.parametrize("tags, expected", [
    (("cp311",), ("4.2.0", "5.1.0")),      # 5.1 would copy it in and refuse to enable it
    (("cp313",), ("5.1.0", None)),
    (("cp311", "cp313"), ("4.2.0", None)),
])
def test_range_follows_the_wheels(tags, expected):
    assert build_extension.version_range(wheels(*tags)) == expected


def test_a_python_no_blender_ships_is_refused():
    with pytest.raises(SystemExit, match="3.12|312"):
        build_extension.version_range(wheels("cp311", "cp312"))


def test_staged_manifest_gets_wheels_and_range(tmp_path, monkeypatch):
    monkeypatch.setattr(build_extension, "WHEELS", tmp_path / "wheels")
    monkeypatch.setattr(build_extension, "STAGE", tmp_path / "stage")
    (tmp_path / "wheels").mkdir()
    for whl in wheels("cp313") + [Path("plyfile-1.1.3-py3-none-any.whl")]:
        (tmp_path / "wheels" / whl).write_bytes(b"")
    import tomllib

    stage = build_extension.stage((ROOT / "blender_manifest.toml").read_text())
    manifest = tomllib.loads((stage / "blender_manifest.toml").read_text())
    assert manifest["blender_version_min"] == "5.1.0" and "blender_version_max" not in manifest
    assert manifest["wheels"] == ["./wheels/plyfile-1.1.3-py3-none-any.whl",
                                  "./wheels/pointscale-0.1.0-cp313-cp313-manylinux_2_34_x86_64.whl"]
    assert manifest["id"] == "pointscale"  # the rest of the manifest is kept
