"""The command line's options: every one with help text and its default."""
from __future__ import annotations

import argparse
import re

from .. import __version__

# Options whose value may start with a minus sign (a negative gain): argparse would take
# "--gains -1,1,1" for two options, so main() joins such pairs into "--gains=-1,1,1" first.
OPTIONS_WITH_SIGNED_VALUES = ("--gains", "--mirror-origin")


class _Formatter(argparse.HelpFormatter):
    """Shows each option's default, where it has one worth showing."""

    def _get_help_string(self, action):
        text = action.help or ""
        shown = action.default is not None and action.default is not False and action.default != argparse.SUPPRESS
        if action.option_strings and shown and "%(default)" not in text:
            text += " (default: %(default)s)"
        return text


# What a signed value starts with: -1, -.5, -inf, -nan (not another option such as -o or --threads).
_SIGNED_VALUE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def join_signed_values(argv: list[str]) -> list[str]:
    """argv with each OPTIONS_WITH_SIGNED_VALUES option and a value after it that starts with a
    minus sign as one "--gains=-1,1,1" word. A following option is left alone, so that
    "--gains --threads 1" is reported as a --gains without its value."""
    out = []
    i = 0
    while i < len(argv):
        if argv[i] in OPTIONS_WITH_SIGNED_VALUES and i + 1 < len(argv) and _SIGNED_VALUE.match(argv[i + 1]):
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out


def path_given(text: str) -> str:
    """An -o value that names something: an empty one (an unset shell variable) would be the
    current folder."""
    if not text.strip():
        raise argparse.ArgumentTypeError("is empty; name the output")
    return text


DEMO_POINTS = (1000, 10_000_000)  # its 4 levels need 512 points; beyond 10M it is no longer a demo


def demo_points(text: str) -> int:
    """--points of the demo: a whole number in DEMO_POINTS."""
    lo, hi = DEMO_POINTS
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number from {lo} to {hi}, got {text!r}") from None
    if not lo <= value <= hi:
        raise argparse.ArgumentTypeError(f"must be from {lo} to {hi}, got {value}")
    return value


class _OneLineErrors(argparse.ArgumentParser):
    """An option error as one line and exit code 2, as every other error: argparse would print
    the whole usage block first. --help still shows it."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(formats: str) -> argparse.ArgumentParser:
    parser = _OneLineErrors(
        prog="pointscale", formatter_class=_Formatter, allow_abbrev=False,
        description="Multiscale point-sampled surfaces (Pauly, Kobbelt, Gross 2006): split a scan or mesh into a "
                    "smooth base and detail bands, filter the bands, carry the detail onto an edited base.",
        epilog=f"File formats, chosen by extension: {formats}.")
    parser.add_argument("--version", action="version", version=f"pointscale {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    d = sub.add_parser("decompose", formatter_class=_Formatter, allow_abbrev=False,
                       help="split a model into a smooth base and detail bands",
                       description="Decomposes INPUT into levels P^0 (smoothest) .. P^k (the input) and writes a "
                                   "folder: decomposition.npz, source.npz (the input's attributes) and "
                                   "level_0 .. level_k in the input's format.")
    d.add_argument("input", help=f"the model to decompose ({formats})")
    d.add_argument("-o", "--output", type=path_given, required=True, help="output folder (created if missing)")
    d.add_argument("--levels", type=int, default=4, help="point clouds P^0..P^k; the detail bands are levels - 1")
    d.add_argument("--decimation", type=float, default=0.25,
                   help="gamma in (0, 1): each coarser level is supported by this fraction of the points")
    d.add_argument("--kernel", type=float, default=1.0, help="kernel width as a multiple of the local spacing")
    d.add_argument("--neighbors", type=int, default=24, help="support points in each plane fit")
    d.add_argument("--smoother", choices=("mls", "diffusion"), default="mls",
                   help="low-pass filter of each level: MLS projection (Sec. 7) or diffusion (Sec. 5.1)")
    d.add_argument("--encoding", choices=("projection", "rayshoot"), default="projection",
                   help="detail encoding: projection (exact round trip) or ray shooting (Sec. 6.1)")
    d.add_argument("--parts", choices=("faces", "none"), default="faces",
                   help="faces: a mesh's connected parts (by its faces) are decomposed apart, so close parts "
                        "neither blend nor move together; none: every point is one surface")
    d.add_argument("--sheets", action="store_true",
                   help="keep two-sided thin sheets apart (leaves, sheet metal, walls scanned from both sides): the "
                        "sides are told apart by the file's normals, which must face outward; without them by "
                        "its faces' winding (an STL), or by normals estimated and oriented for a point cloud; "
                        "costs time (README, Thin sheets)")
    d.add_argument("--mirror", metavar="AXES",
                   help="the input is one half of a mirror-symmetric model, e.g. x (the plane x = 0), xy or xyz: "
                        "the half and its reflections are decomposed as one, so the result is exactly symmetric "
                        "and points on a plane stay on it at every level; about twice the time for one plane "
                        "(README, Mirror symmetry)")
    d.add_argument("--mirror-origin", metavar="X,Y,Z",
                   help="the point the mirror planes pass through, in the file's coordinates (default 0,0,0)")
    d.add_argument("--mirror-seam", metavar="DISTANCE", type=float,
                   help="points this close to a plane are on it (default: 1e-6 of the bounding-box diagonal)")
    d.add_argument("--estimate-normals", action="store_true",
                   help="leave the file's normals out and estimate oriented ones (for normals that are partly "
                        "zero or point inward); a file whose normals are all zero is decomposed this way anyway")
    d.add_argument("--format", help="extension of the level files, e.g. .ply or .las (default: the input's)")
    d.add_argument("--force", action="store_true",
                   help="replace an earlier decomposition in the output folder (its level files are removed)")
    d.add_argument("--threads", type=int, default=0, help="worker threads, 0 for all cores")

    r = sub.add_parser("reconstruct", formatter_class=_Formatter, allow_abbrev=False,
                       help="rebuild the model from a decomposition, with band gains or an edited base",
                       description="Rebuilds the finest level from a decomposition folder, each band scaled by its "
                                   "gain, on the stored or an edited base, with the input's attributes.")
    r.add_argument("decomposition", help="folder written by decompose (or its decomposition.npz)")
    r.add_argument("-o", "--output", type=path_given, required=True, help="output file; its extension picks the format")
    r.add_argument("--gains", help="comma-separated gain per band, coarse to fine, e.g. 2,2,1 or -1,1,1 "
                                   "(default: all 1)")
    r.add_argument("--base", help="an edited level 0 (same vertex count and order), in any supported format")
    r.add_argument("--folds", choices=("ignore", "report", "prevent"), default="ignore",
                   help="report the points where the surface folds over itself, or prevent folds by limiting the "
                        "gain smoothly where they would appear")
    r.add_argument("--fold-reference", choices=("input", "base"), default="input",
                   help="count only the folds the gains or the edit add to the input's own, or every fold over "
                        "the base")
    r.add_argument("--force", action="store_true", help="overwrite the output file if it exists")
    r.add_argument("--threads", type=int, default=0, help="worker threads, 0 for all cores")

    i = sub.add_parser("info", formatter_class=_Formatter, allow_abbrev=False, help="describe a decomposition",
                       description="Prints a decomposition's levels, per-band statistics, settings and source.")
    i.add_argument("decomposition", help="folder written by decompose (or its decomposition.npz)")

    m = sub.add_parser("demo", formatter_class=_Formatter, allow_abbrev=False,
                       help="run the whole pipeline on procedural shapes (no download)",
                       description="Runs the whole pipeline on procedural shapes, with nothing to download: decomposes a "
                                   "bumpy sphere into 4 levels, checks its round trip, writes every level and three "
                                   "band filters as PLYs, then bends a plane with 16 handles at its base (the paper's "
                                   "Fig. 5). Open the PLYs in MeshLab or Blender.")
    m.add_argument("-o", "--output", type=path_given, default="pointscale-demo", help="output folder")
    m.add_argument("--points", type=demo_points, default=100000,
                   help=f"points of the demo sphere, {DEMO_POINTS[0]} to {DEMO_POINTS[1]}")
    m.add_argument("--force", action="store_true",
                   help="replace files of the demo's names in a folder an earlier demo did not write")
    return parser
