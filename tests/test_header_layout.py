"""The core's headers: public ones (native/include/pointscale/*.h) are what the bindings and a C++
user need, and never reach into the internals (native/include/pointscale/detail/)."""
from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
INCLUDE = REPO / "native" / "include" / "pointscale"
INCLUDE_LINE = re.compile(r'^\s*#\s*include\s+"(pointscale/[^"]+)"', re.MULTILINE)


def includes(path: Path) -> list[str]:
    return INCLUDE_LINE.findall(path.read_text(encoding="utf-8"))


def test_public_headers_do_not_include_internal_ones():
    for header in sorted(INCLUDE.glob("*.h")):
        internal = [h for h in includes(header) if h.startswith("pointscale/detail/")]
        assert not internal, f"{header.name} includes {internal}"


def test_bindings_include_public_headers_only():
    for source in sorted((REPO / "native" / "bindings").rglob("*")):
        if source.suffix not in (".cpp", ".h"):
            continue
        internal = [h for h in includes(source) if h.startswith("pointscale/detail/")]
        assert not internal, f"{source.relative_to(REPO)} includes {internal}"


def test_every_included_header_exists():
    for source in sorted((REPO / "native").rglob("*")):
        if source.suffix not in (".cpp", ".h"):
            continue
        for h in includes(source):
            assert (INCLUDE.parent / h).is_file(), f"{source.relative_to(REPO)} includes missing {h}"
