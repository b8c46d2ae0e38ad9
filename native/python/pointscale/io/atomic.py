"""atomic_write: a file appears at its path only once it has been written completely."""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


@contextlib.contextmanager
def atomic_write(path):
    """Yields a temporary path in the same folder as `path`; renames it over `path` when the block
    completes, and removes it when the block raises anything (KeyboardInterrupt included).

    The same folder keeps the rename on one file system, where it is atomic: a reader never sees
    half a file, and a failed write leaves the previous file in place. The temporary name keeps
    the extension, since some writers (laspy, trimesh) choose their format by it.
    """
    path = Path(os.fspath(path))
    if path.is_symlink():  # write through the link, as open() would, not over it
        path = Path(os.path.realpath(path))
    if path.exists() and not path.is_file():
        # A rename over a device or a named pipe would replace it with a plain file (as root,
        # /dev/null itself); a folder cannot be replaced. Nothing is written.
        kind = "a folder" if path.is_dir() else "not a regular file (a device, a named pipe or a socket)"
        raise ValueError(f"{os.fspath(path)} is {kind}: write to a file")
    folder = path.parent if str(path.parent) else Path(".")
    folder.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix}", dir=folder)
    os.close(handle)
    temporary = Path(temporary)
    try:
        yield temporary
        # mkstemp creates the file 0600; give the result the permissions a plain open() would.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise
