"""Checks of -o made before any computing, so that a bad path fails in a second, not after the work."""
from __future__ import annotations

import tempfile
from pathlib import Path

from .. import io
from .folder import owned_files


def writable_extension(path: Path | str, what: str) -> str:
    extension = Path(path).suffix.lower()
    if extension not in io.SUPPORTED_EXTENSIONS:
        raise ValueError(f"{what} {path}: unknown extension {extension or '(none)'!r}; "
                         f"supported: {', '.join(io.SUPPORTED_EXTENSIONS)}")
    return extension


def _nearest_existing(path: Path) -> Path:
    p = path.absolute()
    while not p.exists():
        p = p.parent
    return p


def _require_writable_folder(folder: Path, shown: Path) -> None:
    if not folder.is_dir():
        raise ValueError(f"cannot write {shown}: {folder} is a file, not a folder")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise ValueError(f"cannot write {shown}: {folder} is not writable ({exc.strerror})") from None


def check_output_folder(out: Path, force: bool) -> list[Path]:
    """Checks that decompose can write the folder `out`; returns an earlier run's files there,
    which the new run replaces (only with force)."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"-o {out} is a file; decompose writes a folder")
    _require_writable_folder(_nearest_existing(out), out)
    earlier = owned_files(out)
    if earlier and not force:
        raise ValueError(f"{out} already holds a decomposition ({len(earlier)} files, e.g. {earlier[0].name}); "
                         "pass --force to replace it, or choose another folder")
    return earlier


def check_output_file(out: Path, force: bool) -> None:
    if out.is_dir():
        raise ValueError(f"-o {out} is a folder; reconstruct writes one file")
    writable_extension(out, "-o")
    if out.exists() and not force:
        raise ValueError(f"{out} exists; pass --force to overwrite it")
    parent = out.absolute().parent
    if not parent.exists():
        raise ValueError(f"cannot write {out}: the folder {parent} does not exist")
    _require_writable_folder(parent, out)
