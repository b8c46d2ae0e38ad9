"""How a decomposition was made, so that it can be made again instead of saved (no bpy).

The engine's decompose is deterministic: the same points and settings give the same model bit
for bit, whatever the thread count. So a .blend keeps the recipe (the settings passed to the
engine as JSON, and fingerprints of the Basis and edges it read) instead of the model, about
200 bytes a vertex; the first operator that needs the model after a reload decomposes the
Basis again and checks it against the fingerprints.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np

# Settings that do not change the result: threads (the result does not depend on them) and the
# progress callback. Arrays are the mesh's own data, fingerprinted or kept as attributes.
_NOT_KEPT = {"threads", "progress"}
_ARRAYS = {"edges", "normals"}


def fingerprint(a) -> str:
    """A hash of the array's dtype, shape and bytes (its exact values)."""
    a = np.ascontiguousarray(a)
    h = hashlib.blake2b(digest_size=16)
    h.update(f"{a.dtype.str}{a.shape}".encode())
    h.update(memoryview(a).cast("B"))
    return h.hexdigest()


def make(kwargs: dict, points, version: str = "") -> dict | None:
    """The recipe for ``compute.decompose(ps, points, **kwargs)``, or None when a setting cannot
    be written as JSON (then the whole model has to be stored)."""
    out = {"points": fingerprint(np.asarray(points, dtype=np.float32)), "engine": version, "kwargs": {}}
    for name, value in kwargs.items():
        if name in _NOT_KEPT:
            continue
        if name == "edges":
            out["edges"] = fingerprint(np.asarray(value, dtype=np.int32))
        elif name == "normals":
            out["normals"] = value is not None  # the array itself goes into an attribute
        elif name == "mirror":
            if value is None:
                out["kwargs"]["mirror"] = None
            else:
                out["mirror"] = {"axes": value.axes, "origin": list(value.origin), "seam": value.seam}
        elif isinstance(value, (bool, int, float, str)) or value is None:
            out["kwargs"][name] = value
        else:
            return None
    return out


def dumps(recipe: dict) -> str:
    return json.dumps(recipe, sort_keys=True)


def loads(text: str) -> dict:
    return json.loads(text)


def problem(recipe: dict, points, edges=None) -> str | None:
    """Why the mesh no longer gives the decomposition back: a changed Basis or edges."""
    if fingerprint(np.asarray(points, dtype=np.float32)) != recipe["points"]:
        return ("its Basis changed since it was decomposed (an edit of the mesh itself, or an applied transform), "
                "and the stored decomposition belongs to the Basis as it was")
    if "edges" in recipe and (edges is None or fingerprint(np.asarray(edges, dtype=np.int32)) != recipe["edges"]):
        return "its edges changed since it was decomposed (Keep Parts Apart reads them)"
    return None


def changed_band(details: np.ndarray, saved: list) -> int | None:
    """The first band whose rebuilt details differ from the saved ``ms_detail_<l>`` (float32,
    None where the attribute was removed), or None when all agree bit for bit."""
    for l, column in enumerate(saved):
        if column is not None and not np.array_equal(np.asarray(details[l], dtype=np.float32), column):
            return l
    return None
