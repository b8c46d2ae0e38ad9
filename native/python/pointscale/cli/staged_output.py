"""Output files that appear all at once or not at all.

Every file of a command is first written under a temporary name beside its final one; only
when all of them are complete are they renamed into place. An error, a cancel, Ctrl-C, SIGTERM
or SIGHUP (cli/__init__.py) removes the temporary files, so a folder never holds half of a result.
"""
from __future__ import annotations

import contextlib
import os
import signal
import tempfile
from pathlib import Path

from .stop_signals import handlers_swapped


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
        (stale outputs of an earlier run). Ctrl-C, SIGTERM and SIGHUP wait until this is done, and a rename that
        fails puts back what the ones before it replaced, so the folder holds either the old
        result or the new one."""
        with _sigint_held():
            for _, final in self._pending:  # what no rename can replace, found before any is done
                if final.is_dir() and not final.is_symlink():
                    raise ValueError(f"{final} is a folder; the output needs a file of that name there "
                                     "(move the folder, or write to another -o)")
            umask = os.umask(0)
            os.umask(umask)
            placed: list[Path] = []               # finals written so far
            replaced: list[tuple[Path, Path]] = []  # (backup, final): the earlier files they replace
            try:
                for tmp, final in self._pending:
                    os.chmod(tmp, 0o666 & ~umask)  # mkstemp made it private; give it what open() would
                    if final.exists() or final.is_symlink():
                        replaced.append((_kept_aside(final), final))
                    try:
                        os.replace(tmp, final)
                    except OSError as e:
                        raise OSError(e.errno, f"could not write {final}: {e.strerror}") from None
                    placed.append(final)
            except BaseException:
                _put_back(placed, replaced)
                raise
            for backup, _ in replaced:  # the new files are in place: a second name left behind is no failure
                with contextlib.suppress(OSError):
                    backup.unlink(missing_ok=True)
            for stale in remove_after:
                Path(stale).unlink(missing_ok=True)
            self._pending.clear()
            self._created_dirs.clear()
            global _committed
            _committed = True

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


def _kept_aside(final: Path) -> Path:
    """A second name, beside it, for the file (or link) `final`, which it returns: a commit that
    fails puts the file back from there. A hard link, so that `final` itself stays in place until
    the new file replaces it in one step; where the file system has none, a rename."""
    fd, name = tempfile.mkstemp(prefix=f".{final.stem}.", suffix=f".old{final.suffix}", dir=final.parent)
    os.close(fd)
    os.unlink(name)  # only its unused name is wanted
    try:
        os.link(final, name, follow_symlinks=False)
    except (OSError, NotImplementedError):  # no hard links there, or none to a link itself
        os.replace(final, name)
    return Path(name)


def _put_back(placed: list[Path], replaced: list[tuple[Path, Path]]) -> None:
    """Undoes a commit that failed midway: removes the files it placed, and puts back every file
    they replaced, each on its own (one that cannot be put back does not keep the others from
    it; the first such error is raised after all were tried)."""
    errors = []
    kept = {final for _, final in replaced}
    for final in placed:
        if final not in kept:
            try:
                final.unlink(missing_ok=True)
            except OSError as e:
                errors.append(e)
    for backup, final in reversed(replaced):
        try:
            if final in placed or not (final.exists() or final.is_symlink()):
                os.replace(backup, final)
            else:  # not replaced yet: still the old file, of which backup is a second name
                backup.unlink()
        except OSError as e:
            errors.append(OSError(e.errno, f"could not put back {final}: {e.strerror}; the earlier file "
                                           f"is kept as {backup}"))
    if errors:
        raise errors[0]


# Whether a commit of this process has put its files in place: a command stopped after that
# says so (cli/__init__.py).
_committed = False


def committed() -> bool:
    return _committed


def forget_commits() -> None:
    """A new command starts (the command line's main may run several in one process)."""
    global _committed
    _committed = False


@contextlib.contextmanager
def _sigint_held():
    """Delays Ctrl-C (SIGINT), SIGTERM and SIGHUP until the block is done. Their Python handlers
    are swapped for one that only notes them: the system may deliver a signal to any thread (the
    engine's, the writers'), so blocking it in the main thread alone did not hold it, and a stop
    in the middle of the renames left the earlier files' backups behind. After a block that
    completed, the first noted signal goes to the handler it would have reached. Only the main
    thread can swap them."""
    noted: list[int] = []
    with handlers_swapped(lambda signum: lambda number, frame: noted.append(number)) as previous:
        yield
    if noted:
        handler = previous.get(noted[0])
        if callable(handler):
            handler(noted[0], None)
        elif handler == signal.SIG_DFL:
            signal.raise_signal(noted[0])
