"""Output files that appear all at once or not at all.

Every file of a command is first written under a temporary name beside its final one; only
when all of them are complete are they renamed into place. An error, a cancel or Ctrl-C
removes the temporary files, so a folder never holds half of a result.
"""
from __future__ import annotations

import contextlib
import os
import signal
import tempfile
import threading
from pathlib import Path


class StagedOutput:
    def __init__(self):
        self._pending: list[tuple[Path, Path]] = []
        self._created_dirs: list[Path] = []

    def make_dir(self, folder: Path) -> None:
        """Creates `folder` (and missing parents); a failed command removes what it created."""
        missing = []
        f = folder
        while not f.exists():
            missing.append(f)
            f = f.parent
        folder.mkdir(parents=True, exist_ok=True)
        self._created_dirs.extend(reversed(missing))

    def temporary(self, final: Path) -> Path:
        """A fresh temporary path beside `final`, with the same extension (writers choose the
        format by it), renamed to `final` by commit()."""
        fd, name = tempfile.mkstemp(prefix=f".{final.stem}.", suffix=f".part{final.suffix}", dir=final.parent)
        os.close(fd)
        tmp = Path(name)
        self._pending.append((tmp, final))
        return tmp

    def commit(self, remove_after=()) -> None:
        """Renames every temporary file into place, then removes the files in `remove_after`
        (stale outputs of an earlier run). Ctrl-C waits until this is done, so the folder holds
        either the old result or the new one."""
        with _sigint_held():
            umask = os.umask(0)
            os.umask(umask)
            for tmp, final in self._pending:
                os.chmod(tmp, 0o666 & ~umask)  # mkstemp made it private; give it what open() would
                os.replace(tmp, final)
            for stale in remove_after:
                Path(stale).unlink(missing_ok=True)
            self._pending.clear()
            self._created_dirs.clear()

    def discard(self) -> None:
        for tmp, _ in self._pending:
            tmp.unlink(missing_ok=True)
        self._pending.clear()
        for folder in reversed(self._created_dirs):
            try:
                folder.rmdir()  # only if still empty
            except OSError:
                pass
        self._created_dirs.clear()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None:
            self.discard()
        return False


@contextlib.contextmanager
def _sigint_held():
    """Delays Ctrl-C (SIGINT) until the block is done; only the main thread can do so."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
