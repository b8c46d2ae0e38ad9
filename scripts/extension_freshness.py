"""Whether dist/ holds the extension zip of the sources as they are now (no bpy needed).

scripts/build_extension.py --if-stale builds only when this finds a problem, and
tests/blender/test_install.py fails with the problem when it finds one, so the install test
never checks an old zip. The engine wheels are stamped with a digest of what they are built
from (native/, CMakeLists.txt, pyproject.toml); the zip must hold those wheels and addon/ as it
is now.
"""

from __future__ import annotations

import hashlib
import re
import zipfile
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DIST = ROOT / "dist"
WHEELS = DIST / "wheels"
STAMP = WHEELS / "SOURCES"  # the digest of the sources the wheels in dist/wheels were built from
ZIP_GLOB = "pointscale-*-linux_x64.zip"
BUILD = "python scripts/build_extension.py"


def sources_digest() -> str:
    """A digest of every file the engine wheel is built from (names and bytes)."""
    files = [ROOT / "CMakeLists.txt", ROOT / "pyproject.toml"]
    files += sorted(p for p in (ROOT / "native").rglob("*")
                    if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".pyc")
    h = hashlib.blake2b(digest_size=16)
    for path in files:
        h.update(path.relative_to(ROOT).as_posix().encode() + b"\0")
        h.update(path.read_bytes())
    return h.hexdigest()


def write_stamp() -> None:
    """Called by the build right after it has built the wheels from the sources."""
    STAMP.write_text(sources_digest() + "\n")


def wheel_problem(tags) -> str | None:
    """Why dist/wheels cannot serve these Python tags (e.g. "cp311"), or None."""
    for tag in tags:
        if not list(WHEELS.glob(f"pointscale-*-{tag}-*.whl")):
            return f"dist/wheels has no engine wheel for {tag}"
    if not STAMP.exists() or STAMP.read_text().strip() != sources_digest():
        return "the engine wheels in dist/wheels were built from other sources than native/ holds now"
    return None


def zip_problem(tags) -> str | None:
    """Why the newest dist/pointscale-*-linux_x64.zip is not addon/ with dist/wheels, or None."""
    zips = sorted(DIST.glob(ZIP_GLOB))
    if not zips:
        return f"dist/ has no extension zip ({ZIP_GLOB})"
    with zipfile.ZipFile(zips[-1]) as z:
        infos = {info.filename: info for info in z.infolist()}
        for tag in tags:
            if not any(re.fullmatch(rf"wheels/pointscale-[^/]*-{tag}-[^/]*\.whl", name) for name in infos):
                return f"{zips[-1].name} has no engine wheel for {tag}"
        for name, info in infos.items():
            if name.startswith("wheels/") and name.endswith(".whl"):
                built = DIST / name
                if not built.exists() or zlib.crc32(built.read_bytes()) != info.CRC:
                    return f"{zips[-1].name} holds another {name} than dist/{name}"
        sources = {src.relative_to(ROOT / "addon").as_posix(): src for src in (ROOT / "addon").rglob("*.py")}
        for rel, src in sources.items():
            if rel not in infos or z.read(rel) != src.read_bytes():
                return f"{zips[-1].name} holds another addon/{rel} than the source tree"
        gone = sorted(name for name in infos if name.endswith(".py") and name not in sources)
        if gone:
            return f"{zips[-1].name} holds {gone[0]}, which addon/ no longer has"
    return None


def stale_reason(tags) -> str | None:
    """Why dist/ has no current extension zip for these Python tags, or None when it has."""
    return wheel_problem(tags) or zip_problem(tags)


def newest_zip() -> Path:
    return sorted(DIST.glob(ZIP_GLOB))[-1]
