"""Access to the ``pointscale`` engine (the bundled wheel), imported lazily.

The add-on talks to the C++ core only through the ``pointscale`` package.
"""

from __future__ import annotations

_engine = None
_error = None


def get():
    """The ``pointscale`` module; raises RuntimeError with a readable message."""
    global _engine, _error
    if _engine is None:
        try:
            import pointscale  # the engine wheel, not this add-on

            _engine = pointscale
            _error = None
        except Exception as exc:  # ImportError, or a broken native module
            _error = f"the pointscale engine could not be loaded: {exc}"
            raise RuntimeError(_error) from exc
    return _engine


def available() -> bool:
    try:
        get()
        return True
    except RuntimeError:
        return False


def error() -> str | None:
    return _error


def cancelled_type():
    """The engine's cancellation exception, which a cancelled progress callback raises."""
    return get().Cancelled
