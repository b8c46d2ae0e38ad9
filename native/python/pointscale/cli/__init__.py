"""Command line: pointscale decompose | reconstruct | info | demo.

Errors print one line and exit with code 2; Ctrl-C exits with 130, and SIGTERM or SIGHUP with
128 plus the signal's number, and none of them leaves partial files.
"""
from __future__ import annotations

import signal
import sys
import warnings

from .. import Cancelled, io
from . import commands
from .parser import build_parser, join_signed_values
from .staged_output import committed, forget_commits
from .stop_signals import STOP_SIGNALS, handlers_swapped

EXIT_ERROR = 2
EXIT_INTERRUPTED = 130  # 128 + SIGINT, what shells report for Ctrl-C


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, stopping a command as Ctrl-C does: its temporary files are removed."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _ignore_stops_from_now_on() -> None:
    """The first stop is heard; the ones after it (a closed terminal sends SIGHUP twice) must
    not cut short the removal of the temporary files it starts."""
    for signum in STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)


def _raise_terminated(signum, frame):
    _ignore_stops_from_now_on()
    raise Terminated(signum)


def _raise_interrupt(signum, frame):
    _ignore_stops_from_now_on()
    raise KeyboardInterrupt


def _stop_handler(signum):
    """SIGTERM and SIGHUP raise Terminated, and Ctrl-C KeyboardInterrupt, each only once."""
    return _raise_interrupt if signum == signal.SIGINT else _raise_terminated


def _what_was_written() -> str:
    return "its files were written before it stopped" if committed() else "no files were written"


def _one_line(text: str) -> str:
    lines = str(text).strip().splitlines()
    return lines[0] if lines else ""


_warned = set()

# The package's messages name its Python options; on the command line they are these.
_CLI_WORDS = (("sheets=True", "--sheets"), ("smoother='diffusion'", "--smoother diffusion"),
              ("encoding='rayshoot'", "--encoding rayshoot"), ("smoother='mls'", "--smoother mls"),
              ("encoding='projection'", "--encoding projection"),
              # An STL holds no normals, but its faces' winding tells the sides apart as well.
              ("give outward normals (normals=..., e.g. a mesh's vertex normals) or the mesh's consistently wound "
               "faces (faces=...)",
               "give a file with outward normals (nx, ny, nz) or with consistently wound faces (an STL; a PLY, OBJ "
               "or OFF with faces)"))


def _in_cli_words(text: str) -> str:
    for python, cli in _CLI_WORDS:
        text = text.replace(python, cli)
    return text


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """One line per warning. A writer's warning names the (temporary) file it was writing; the
    same warning for every level is shown once, without the name."""
    text = _in_cli_words(_one_line(message))
    head, _, rest = text.partition(": ")
    if rest and ("/" in head or "\\" in head) and not head.startswith("--"):  # "--base path: ..." keeps its subject
        text = rest
    if text not in _warned:
        _warned.add(text)
        print(f"pointscale: warning: {text}", file=sys.stderr)


def main(argv=None) -> int:
    argv = join_signed_values(sys.argv[1:] if argv is None else list(argv))
    parser = build_parser(", ".join(io.SUPPORTED_EXTENSIONS))
    args = parser.parse_args(argv)
    run = {"decompose": commands.cmd_decompose, "reconstruct": commands.cmd_reconstruct,
           "info": commands.cmd_info, "demo": commands.cmd_demo}[args.command]
    warnings.showwarning = _show_warning
    forget_commits()
    try:
        with handlers_swapped(_stop_handler, keep_ignored=True):
            run(args)
    except Terminated as stop:
        print(f"pointscale: stopped by {signal.Signals(stop.signum).name}; {_what_was_written()}", file=sys.stderr)
        return 128 + stop.signum
    except KeyboardInterrupt:
        print(f"pointscale: interrupted; {_what_was_written()}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Cancelled:
        print("pointscale: cancelled; no files were written", file=sys.stderr)
        return EXIT_ERROR
    except ValueError as exc:
        print(f"pointscale: error: {_in_cli_words(_one_line(exc))}", file=sys.stderr)
        return EXIT_ERROR
    except MemoryError:
        print("pointscale: error: out of memory", file=sys.stderr)
        return EXIT_ERROR
    except OSError as exc:
        where = f" {exc.filename}" if exc.filename else ""
        print(f"pointscale: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return EXIT_ERROR
    except Exception as exc:  # a worker thread that could not start, a library's own error
        print(f"pointscale: error: {type(exc).__name__}: {_one_line(exc)}", file=sys.stderr)
        return EXIT_ERROR
    return 0
