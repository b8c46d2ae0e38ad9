"""The decomposition folder that `pointscale decompose` writes and the other commands read.

    decomposition.npz   the model (pointscale.load reads it)
    source.npz          the input's faces, every vertex and face attribute and what its format
                        needs to be written back (pointscale.io.Scan.to_arrays), no pickles;
                        both .npz files hold the same source_id (source_identifier), and a
                        source.npz of another decomposition is refused
    level_0.EXT ..      every level as a file in the input's format (or --format), with the
    level_k.EXT         level's own normals and the input's attributes

Both .npz files are read with allow_pickle=False and checked before use.
"""
from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import numpy as np

from .. import io
from ..io.scan import stored_source_id
from ..multiscale import load

DECOMPOSITION_FILE = "decomposition.npz"
SOURCE_FILE = "source.npz"
# The level files decompose writes: level_N with N as level_name() spells it (no leading zeros) and
# an extension it writes, in lower case as writable_extension() makes it. A user's level_1.txt or
# level_12.png beside them looks alike but is not ours, and is neither counted nor removed.
_LEVEL_FILE = re.compile(r"^level_(0|[1-9][0-9]*)(\.[a-z0-9]+)$")


# CloudCompare's ASCII clouds: read, and written by reconstruct -o, but never the extension of a
# level file (a text cloud's levels are .xyz, the same columns): a user's notes in level_1.txt
# beside the levels must not count as one of them.
TEXT_CLOUD_EXTENSIONS = (".txt", ".asc")
LEVEL_EXTENSIONS = tuple(e for e in io.SUPPORTED_EXTENSIONS if e not in TEXT_CLOUD_EXTENSIONS)


def level_extension(input_extension: str) -> str:
    """The extension of the level files of an input with this one: its own, or .xyz for a text cloud."""
    return ".xyz" if input_extension in TEXT_CLOUD_EXTENSIONS else input_extension


def level_name(level: int, extension: str) -> str:
    return f"level_{level}{extension}"


def owned_files(folder: Path) -> list[Path]:
    """The files of an earlier decomposition in `folder`: what decomposing again replaces."""
    if not folder.is_dir():
        return []
    names = [p for p in folder.iterdir() if p.is_file() and is_level_file(p.name)]
    names += [folder / n for n in (DECOMPOSITION_FILE, SOURCE_FILE, "faces.npy") if (folder / n).is_file()]
    return sorted(names)


def folder_signature(folder: Path) -> dict:
    """The files of a decomposition in `folder` (owned_files) as they are now: name -> (inode,
    modification time, size). decompose takes one before it starts and compares before it puts
    its files in place: another decompose into the same folder that finished in between would
    otherwise leave one run's model beside the other's level files, both saying they wrote them."""
    out = {}
    for path in owned_files(folder):
        try:
            st = path.stat()
        except OSError:
            continue
        out[path.name] = (st.st_ino, st.st_mtime_ns, st.st_size)
    return out


def is_level_file(name: str) -> bool:
    match = _LEVEL_FILE.match(name)
    return match is not None and match.group(2) in LEVEL_EXTENSIONS


def model_file(path: Path) -> Path:
    return path / DECOMPOSITION_FILE if path.is_dir() else path


def source_identifier(points: np.ndarray, arrays: dict) -> str:
    """The identifier decompose writes into both decomposition.npz (settings["source_id"]) and
    source.npz: a digest of the input's points and of source.npz's arrays, so that a source.npz
    of another input (or of the same points with other attributes or normals) is told apart,
    while a run again on the same input writes the same files, bit for bit."""
    digest = hashlib.sha256()
    for name, values in [("points", np.asarray(points)), *sorted(arrays.items())]:
        values = np.ascontiguousarray(values)
        digest.update(f"{name}:{values.dtype.str}:{values.shape};".encode())
        digest.update(values.tobytes())
    return digest.hexdigest()[:32]


def read_source(path: Path, n_points: int | None = None, source_id: str | None = None):
    """The input's attributes saved beside a decomposition, or None for a folder without them.
    n_points, the decomposition's own point count, sizes what source.npz may unpack: the count
    source.npz declares is the file's word about itself, and a crafted one would let it unpack
    gigabytes (4 KB a point) before anything else is checked."""
    folder = model_file(path).parent
    source = folder / SOURCE_FILE
    if source.exists() and not source.is_file():  # read as absent, the result would lose every attribute
        raise ValueError(f"{source} is not a file: decompose the input again, or remove it to rebuild without the "
                         "input's attributes and faces")
    if source.is_file():
        try:
            scan = io.Scan.from_arrays(source, n_points=n_points)
            stored = stored_source_id(source)
        except ValueError:
            raise
        except Exception as exc:  # zip and header errors of a damaged or crafted file
            raise ValueError(f"cannot read {source}: {_one_line(exc)}") from None
        if stored != source_id:  # both None: a folder of a pointscale that wrote no identifier
            raise ValueError(f"{source} and {model_file(path)} come from different decompositions (source "
                             f"{stored or 'without an identifier'}, decomposition {source_id or 'without one'}): "
                             "put back the source.npz written with it, or decompose the input again")
        return scan
    if (folder / "faces.npy").is_file():
        raise ValueError(f"{folder / 'faces.npy'} is an older pointscale's face file, which needs loading Python "
                         "objects (a pickle) and is not read; decompose the input again")
    return None


def read_decomposition(path: Path):
    """(Decomposition, source Scan or None) of a folder written by decompose, or of its .npz."""
    file = model_file(path)
    if not file.is_file():
        raise ValueError(f"no decomposition at {path} (expected a folder holding {DECOMPOSITION_FILE}, or the file)")
    dec = load(file)
    source_id = dec.settings.get("source_id")
    if source_id is not None and not isinstance(source_id, str):
        raise ValueError(f"{file}: settings['source_id'] must be text, got {json.dumps(source_id)[:40]}")
    source = read_source(path, dec.n_points, source_id)
    if source is not None and source.n_points != dec.n_points:
        raise ValueError(f"{file.parent / SOURCE_FILE} describes {source.n_points} points, "
                         f"the decomposition {dec.n_points}: the folder mixes two runs")
    return dec, source


def _one_line(exc: Exception) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
