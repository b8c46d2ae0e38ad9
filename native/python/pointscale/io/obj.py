"""Wavefront OBJ, parsed with numpy: v (with optional w, or r g b [a] colours), vt, vn and f lines.

trimesh's OBJ loader was not used: even with maintain_order it drops vertices no face uses (a
point cloud with a few faces loses points) and returns UVs only when it can load the material.

Vertex order is the file's. OBJ gives normals and UVs per face corner; a Scan keeps them per
vertex (the points are what Pointscale processes, so vertices are never split): a vertex whose
corners disagree (a UV seam) keeps its first corner's value, with a warning. Faces may differ in
their corners' form (f v/vt in a textured group, f v elsewhere); the vertices no face gives a UV
are then filled with 0, and normals given by only some faces are left out, each with a warning.
The corners of one face share one form. Polygons are kept as
they are (no triangulation). Negative (relative) indices are resolved against the counts at the
end of the file, which is exact when all vertices come before the faces, as in nearly every file.
Groups, objects, materials and lines (l) are not kept (a warning counts them). Read, UVs are
the vertex attributes texture_u, texture_v (and texture_w of "vt u v w"), colours red, green,
blue (and alpha of "v x y z r g b a") as the file's floats (0..1 by convention), and the w of
"v x y z w" is vertex_w; each is written back in its place. Written, 8- and 16-bit integer
colours (from PLY or LAS) are divided by 255 or 65535; alpha from other formats is not written (most readers take
only 6 values on a v line), with a warning like any attribute OBJ has no place for.
"""
from __future__ import annotations

import io
import os
import warnings

import numpy as np

from .atomic import atomic_write
from .scan import Scan
from .text import kept_comments
from .text_tables import colour_for_text, numbers, polygons, read_text, savetxt, write_rows

_COLOURS = ("red", "green", "blue")
_WRITTEN_BY = "written by pointscale"
# The values of a v line after x y z, by its width: the weight w, or a colour (with alpha).
_V_EXTRAS = {3: (), 4: ("vertex_w",), 6: _COLOURS, 7: _COLOURS + ("alpha",)}
_TEXTURE_NAMES = ("texture_u", "texture_v", "texture_w")
_UV_NAMES = (("texture_u", "texture_v"), ("s", "t"), ("u", "v"))


def read_obj(path) -> Scan:
    path = os.fspath(path)
    lines = _lines(path)
    v = numbers(lines["v"], "v", path)
    if len(v) == 0:
        raise ValueError(f"{path}: no vertices")
    if v.shape[1] not in (3, 4, 6, 7):
        raise ValueError(f"{path}: v lines have {v.shape[1]} values; expected x y z [w] or x y z r g b")
    points = v[:, :3]
    if not np.isfinite(points).all():
        raise ValueError(f"{path}: non-finite coordinates")
    attributes = {name: v[:, 3 + i].copy() for i, name in enumerate(_V_EXTRAS[v.shape[1]])}
    vn = numbers(lines["vn"], "vn", path)
    vt = numbers(lines["vt"], "vt", path)
    faces, corner_vt, corner_vn = _faces(lines["f"], len(v), len(vt), len(vn), path, lines["seen"])
    normals = _per_vertex(vn[:, :3] if len(vn) else vn, faces, corner_vn, len(v), "normals", path)
    if vt.shape[1] > len(_TEXTURE_NAMES):
        raise ValueError(f"{path}: vt lines have {vt.shape[1]} values; expected u [v [w]]")
    uv = _per_vertex(vt, faces, corner_vt, len(v), "UVs", path)
    if uv is not None:
        attributes.update({name: uv[:, i].copy() for i, name in enumerate(_TEXTURE_NAMES[:uv.shape[1]])})
    try:
        return Scan(points=points, precision=np.float64, normals=normals, vertex_attributes=attributes,
                    faces=faces, format_info={"format": "obj", **({"comments": lines["comments"]}
                                                                  if lines["comments"] else {})})
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def write_obj(path, scan: Scan) -> None:
    """Writes v (with r g b when the scan has red/green/blue), vn, vt (from texture_u/texture_v,
    s/t or u/v) and f lines; coordinates with %.17g."""
    path = os.fspath(path)
    attributes = scan.vertex_attributes
    kept = []
    vertex_extras = _vertex_extras(scan)
    vertex = np.column_stack([scan.points] + [colour_for_text(attributes[c]) if c in _COLOURS + ("alpha",)
                                              else attributes[c] for c in vertex_extras])
    kept += vertex_extras
    uv_names = next((pair for pair in _UV_NAMES if all(n in attributes for n in pair)), None)
    if uv_names == _TEXTURE_NAMES[:2] and "texture_w" in attributes:
        uv_names = _TEXTURE_NAMES  # vt u v w, as read
    kept += list(uv_names or ())
    dropped = [n for n in attributes if n not in kept] + list(scan.face_attributes)
    if dropped:
        warnings.warn(f"{path}: OBJ has no place for {', '.join(dropped)}; not written", stacklevel=3)
    buffer = io.StringIO()
    buffer.write(f"# {_WRITTEN_BY}\n")
    for comment in kept_comments(scan):  # a CRS, the scanner, the exporter: from OBJ, XYZ, PTS or PLY
        buffer.write(f"# {comment}\n")
    savetxt(buffer, "v ", vertex, "%.17g")
    if scan.normals is not None:
        savetxt(buffer, "vn ", scan.normals, "%.17g")
    if uv_names:
        savetxt(buffer, "vt ", np.column_stack([attributes[n] for n in uv_names]).astype(np.float64), "%.17g")
    if scan.n_faces:
        # Normals and UVs are per vertex, so each corner refers to the same index in all of them.
        corner, refs = {(False, False): ("%d", 1), (True, False): ("%d/%d", 2), (False, True): ("%d//%d", 2),
                        (True, True): ("%d/%d/%d", 3)}[(uv_names is not None, scan.normals is not None)]
        if isinstance(scan.faces, np.ndarray):
            rows = np.repeat(scan.faces + 1, refs, axis=1)
            write_rows(buffer, rows, "f " + " ".join([corner] * scan.faces.shape[1]))
        else:
            for face in scan.faces:
                buffer.write("f " + " ".join(corner % ((i + 1,) * refs) for i in face) + "\n")
    with atomic_write(path) as temporary:
        with open(temporary, "w", encoding="utf-8") as f:
            f.write(buffer.getvalue())


def _vertex_extras(scan: Scan) -> tuple:
    """The attributes a v line carries after x y z: red green blue (and alpha, when it came from
    an OBJ's 7-value v lines: other tools read only 6), or the weight vertex_w, or none."""
    attributes = scan.vertex_attributes
    if all(c in attributes for c in _COLOURS):
        with_alpha = "alpha" in attributes and scan.format_info.get("format") == "obj"
        return _V_EXTRAS[7] if with_alpha else _V_EXTRAS[6]
    return _V_EXTRAS[4] if "vertex_w" in attributes else ()


def _lines(path: str) -> dict:
    text = read_text(path, "a text OBJ file")
    lines = {"v": [], "vt": [], "vn": [], "f": []}
    seen = []  # per f line: the v, vt and vn lines above it, which its negative indices count back from
    others = {}
    comments = []
    for line in text.splitlines():
        parts = line.split(None, 1)
        if parts and parts[0].startswith("#"):
            comment = line.strip().lstrip("#").strip()
            if comment and comment != _WRITTEN_BY:
                comments.append(comment)
            continue
        if parts and parts[0] in lines:
            lines[parts[0]].append(parts[1].split("#", 1)[0] if len(parts) > 1 else "")
            if parts[0] == "f":
                seen.append((len(lines["v"]), len(lines["vt"]), len(lines["vn"])))
        elif parts and not parts[0].startswith("#"):
            others[parts[0]] = others.get(parts[0], 0) + 1
    if others:  # materials (mtllib, usemtl), groups, objects, smoothing, lines, points...
        said = ", ".join(f"{count} {keyword}" for keyword, count in others.items())
        warnings.warn(f"{path}: OBJ lines other than v, vt, vn and f are not kept ({said})", stacklevel=4)
    lines["seen"] = np.array(seen, dtype=np.int64).reshape(-1, 3)
    lines["comments"] = comments
    return lines


def _faces(face_lines: list, nv: int, nvt: int, nvn: int, path: str, seen: np.ndarray):
    """(faces, vt index per corner or None, vn index per corner or None), 0-based; a corner
    whose face gives no vt (or vn) while others do has -1 there. seen: per face line, the v, vt
    and vn lines above it."""
    if not face_lines:
        return None, None, None
    lengths = np.array([len(line.split()) for line in face_lines])
    tokens = " ".join(face_lines).split()
    slashes = tokens[0].count("/")
    double = "//" in tokens[0]
    text = " ".join(tokens)
    present = None  # which of v, vt, vn each corner gives, when faces differ in that
    if text.count("/") != slashes * len(tokens) or text.count("//") != double * len(tokens):
        refs, present = _corners_of_mixed_forms(tokens, lengths, path)
        double = False
    else:
        if double:
            text = text.replace("//", "/0/")
        try:
            refs = np.array(text.replace("/", " ").split(), dtype=np.int64).reshape(len(tokens), -1)
        except (ValueError, OverflowError):  # OverflowError: an index past 64 bits
            raise ValueError(f"{path}: a face holds something that is not a vertex index") from None
    if (lengths < 3).any():
        raise ValueError(f"{path}: a face has fewer than 3 corners")
    columns = []
    for j, count in enumerate((nv, nvt, nvn)[:refs.shape[1]]):
        column = refs[:, j]
        if double and j == 1 or present is not None and not present[:, j].any():
            columns.append(None)
            continue
        # OBJ indices are 1-based; negative ones count back from the last of its kind defined
        # above the face (relative indices, as exporters that write object by object use them).
        written = column
        above = np.repeat(seen[:, j], lengths)
        column = np.where(written < 0, written + above, written - 1)
        bad = (column < 0) | (column >= count)
        if present is not None:
            bad &= present[:, j]
        if bad.any():  # name the index as the file writes it, the first one out of range
            what = ("vertex", "texture coordinate", "normal")[j]
            at = int(np.argmax(bad))
            first = int(written[at])
            many = ("vertices", "texture coordinates", "normals")[j]
            back = (f" (or -{int(above[at])}..-1, counted back from the {many} above the face)" if above[at]
                    else f"; no {many} stand above the face to count back from")
            allowed = f"outside 1..{count}{back}" if count else f"but the file has no {many}"
            raise ValueError(f"{path}: a face refers to {what} {first}, {allowed}")
        if present is not None:
            column = np.where(present[:, j], column, -1)
        columns.append(column)
    columns += [None] * (3 - len(columns))
    return polygons(lengths, columns[0]), columns[1], columns[2]


# A corner's form by its slashes: v, v/vt, v/vt/vn, v//vn (two slashes and one more for "//").
_FORM_PARTS = {0: (True, False, False), 1: (True, True, False), 2: (True, True, True), 3: (True, False, True)}


def _corners_of_mixed_forms(tokens: list, lengths: np.ndarray, path: str):
    """(refs (corners, 3) with 0 where a corner gives no vt or vn, which each gives (corners, 3))
    of faces whose corner forms differ from face to face (a model textured in some groups only,
    f v/vt there and f v elsewhere), as OBJ allows. The corners of one face share one form."""
    forms = np.array([t.count("/") + ("//" in t) for t in tokens])
    starts = np.cumsum(lengths) - lengths
    if (forms != np.repeat(forms[starts], lengths)).any():
        raise ValueError(f"{path}: a face's corners mix the forms v, v/vt, v//vn and v/vt/vn")
    if (forms > 3).any():
        raise ValueError(f"{path}: a face holds something that is not a vertex index")
    present = np.array([_FORM_PARTS[f] for f in forms.tolist()], dtype=bool).reshape(-1, 3)
    parts = [(t.split("/") + ["", ""])[:3] for t in tokens]
    try:
        refs = np.array([int(x) if want else 0 for p, form in zip(parts, present.tolist())
                         for x, want in zip(p, form)], dtype=np.int64).reshape(-1, 3)
    except (ValueError, OverflowError):
        raise ValueError(f"{path}: a face holds something that is not a vertex index") from None
    return refs, present


def _per_vertex(values: np.ndarray, faces, corner: np.ndarray | None, n: int, what: str, path: str):
    """Per-corner values (vt or vn through the face references) as one per vertex, or None.
    Corners of -1 give none (faces of another form): a vertex only such faces use is filled with
    0, with a warning counting them; normals are then left out instead (a zero normal orients
    nothing, and decompose refuses it)."""
    if len(values) == 0:
        return None
    if corner is None:
        return values if len(values) == n else None  # no corner references: by index when counts match
    vertex = faces.ravel() if isinstance(faces, np.ndarray) else np.concatenate(faces)
    partial = bool((corner < 0).any())
    if partial:
        vertex, corner = vertex[corner >= 0], corner[corner >= 0]
    out = np.full((n, values.shape[1]), np.nan)
    first = np.full(n, -1)
    used, earliest = np.unique(vertex, return_index=True)
    first[used] = corner[earliest]  # each vertex takes its earliest corner's value
    have = first >= 0
    out[have] = values[first[have]]
    split = int((~np.all(values[corner] == out[vertex], axis=1)).sum())
    if split:
        warnings.warn(f"{path}: {split} face corners give their vertex different {what} (a seam); "
                      "each vertex keeps its first", stacklevel=4)
    if partial and not have.all() and what == "normals":  # a zero normal would be refused as an orientation
        warnings.warn(f"{path}: some faces give normals and others do not; {int((~have).sum())} of {n} vertices "
                      f"have none, so the file's normals are left out (decompose estimates its own)", stacklevel=4)
        return None
    if partial and not have.all():
        warnings.warn(f"{path}: some faces give {what} and others do not; {int((~have).sum())} of {n} vertices "
                      f"have none, filled with 0", stacklevel=4)
        out[~have] = 0.0
    elif not have.all():
        if len(values) == n:
            out[~have] = values[~have]
        else:
            warnings.warn(f"{path}: {int((~have).sum())} vertices have no {what}; {what} not kept", stacklevel=4)
            return None
    return out
