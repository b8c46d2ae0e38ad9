"""The signals that stop a command (Ctrl-C, SIGTERM, SIGHUP), and swapping their handlers.

SIGTERM and SIGHUP are what `timeout`, a batch scheduler's time limit and a closed terminal
send: by default they end the process at once, which left a command's temporary files behind.
"""
from __future__ import annotations

import contextlib
import signal

STOP_SIGNALS = (signal.SIGINT,) + tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextlib.contextmanager
def handlers_swapped(handler_for, keep_ignored: bool = False):
    """Each stop signal's Python handler set to handler_for(signum) for the block, and put back
    after it; yields the handlers it replaced, by signal. Only the main thread can set them:
    elsewhere nothing changes, and with keep_ignored neither does a signal the process ignores
    (nohup's SIGHUP)."""
    previous = {}
    for signum in STOP_SIGNALS:
        try:
            if keep_ignored and signal.getsignal(signum) is signal.SIG_IGN:
                continue
            previous[signum] = signal.signal(signum, handler_for(signum))
        except (ValueError, OSError):  # not the main thread
            pass
    try:
        yield previous
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
