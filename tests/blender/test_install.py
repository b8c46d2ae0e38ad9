"""Check 10: the built zip installs into a fresh user extension repository of real Blender,
and Decompose runs through the installed copy with the bundled engine wheel. It runs under both
bpy 4.5 and 5.2 (tests/test_blender_on_bpy52.py), on one zip that holds both engine wheels.

Runs in a subprocess with its own BLENDER_USER_RESOURCES (a fresh user folder), and hides
the developer's editable engine there, so only the zip's wheel can satisfy ``import pointscale``.
"""

import importlib.util
import json
import os
import re
import subprocess
import sys
import tomllib
import zipfile

import pytest

from blender_helpers import ROOT

pytestmark = pytest.mark.blender

SCRIPT = r'''
import json, sys
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in type(f).__module__.lower()
                    and "scikitbuild" not in type(f).__name__.lower()]
# The source tree goes; a virtual environment inside the clone (.venv, where bpy is) stays.
sys.path[:] = [p for p in sys.path if not p.startswith(sys.argv[2]) or p.startswith(sys.prefix)]
import bpy, numpy as np
out = {}
out["install"] = sorted(bpy.ops.extensions.package_install_files(
    filepath=sys.argv[1], repo="user_default", enable_on_install=True))
out["modules"] = sorted(m for m in sys.modules if m.startswith("bl_ext.user_default.pointscale"))[:1]
import pointscale
out["engine"] = pointscale.__file__
bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=5)
obj = bpy.context.object
basis = np.empty(len(obj.data.vertices) * 3, np.float32); obj.data.vertices.foreach_get("co", basis)
out["decompose"] = sorted(bpy.ops.pointscale.decompose())
out["keys"] = [kb.name for kb in obj.data.shape_keys.key_blocks]
out["rebuild"] = sorted(bpy.ops.pointscale.rebuild_detail())
kb = obj.data.shape_keys.key_blocks["Multiscale Edit"]
co = np.empty(len(kb.points) * 3, np.float32); kb.points.foreach_get("co", co)
out["rebuild_error"] = float(np.abs(co - basis).max())
out["addon_file"] = sys.modules["bl_ext.user_default.pointscale"].__file__
print("RESULT" + json.dumps(out))
'''


# This Python's engine wheel tag: the zip must bundle it for this Blender to install it.
CP = f"cp{sys.version_info.major}{sys.version_info.minor}"

# scripts/extension_freshness.py: is dist/'s zip the one addon/ and native/ make now?
_spec = importlib.util.spec_from_file_location("extension_freshness", ROOT / "scripts" / "extension_freshness.py")
freshness = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(freshness)


@pytest.fixture(scope="module")
def built_zip():
    # The zip is built by a step of its own (scripts/test.sh and .ci/run run it before pytest),
    # not here: a missing or old zip fails, never skips, so that no run passes without checking it.
    problem = freshness.stale_reason([CP])
    if problem:
        pytest.fail(f"{problem}: run `{freshness.BUILD}` first (./scripts/test.sh runs it, then the tests)",
                    pytrace=False)
    return freshness.newest_zip()


def test_zip_installs_and_decomposes(built_zip, tmp_path):
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    env.pop("PYTHONPATH", None)
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(built_zip), str(ROOT)], env=env,
                          capture_output=True, text=True, timeout=170, cwd=str(tmp_path))
    line = next((l for l in proc.stdout.splitlines() if l.startswith("RESULT")), None)
    assert line is not None, proc.stdout[-3000:] + proc.stderr[-3000:]
    out = json.loads(line[len("RESULT"):])
    user = str(tmp_path / "user")
    assert out["install"] == ["FINISHED"]
    assert out["addon_file"].startswith(user)  # the installed copy, not the source tree
    assert out["engine"].startswith(user)  # the bundled wheel, not the editable engine
    assert out["decompose"] == ["FINISHED"] and out["rebuild"] == ["FINISHED"]
    assert out["keys"][:2] == ["Basis", "Level 0"] and "Band 2" in out["keys"]
    assert out["rebuild_error"] < 1e-5


def test_zip_manifest_covers_its_wheels(built_zip):
    # Blender 4.2-5.0 ship Python 3.11, 5.1+ ship 3.13: the range must be what the wheels serve,
    # or Blender copies the zip in and then refuses to enable it.
    with zipfile.ZipFile(built_zip) as z:
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        tags = {m.group(1) for n in z.namelist() if (m := re.fullmatch(r"wheels/pointscale-[^-]+-(cp\d+)-.*", n))}
    assert CP in tags
    expected = {frozenset({"cp311"}): ("4.2.0", "5.1.0"), frozenset({"cp313"}): ("5.1.0", None),
                frozenset({"cp311", "cp313"}): ("4.2.0", None)}[frozenset(tags)]
    assert (manifest["blender_version_min"], manifest.get("blender_version_max")) == expected
    assert sorted(manifest["wheels"]) == sorted(f"./{n}" for n in z.namelist() if n.startswith("wheels/"))
