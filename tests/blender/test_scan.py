"""A real scan with faces, imported with Blender's own PLY importer (skips without ../shared/data)."""

import os
from pathlib import Path

import bpy
import numpy as np
import pytest

import blender_helpers as h
from blender_helpers import ROOT, diagonal

pytestmark = [pytest.mark.blender, pytest.mark.data]

DATA = Path(os.environ.get("POINTSCALE_DATA", ROOT.parent / "shared" / "data"))


@pytest.fixture
def fandisk():
    path = DATA / "fandisk.ply"
    if not path.exists():
        pytest.skip(f"fandisk.ply not found in {DATA}")
    bpy.ops.wm.ply_import(filepath=str(path))
    obj = bpy.context.active_object
    me = obj.data
    counts = (len(me.vertices), len(me.polygons))
    before = h.vertices(me).copy()
    h.decompose(obj, levels=4)
    return obj, before, counts


def test_scan_keeps_faces_basis_and_filters(fandisk):
    obj, before, counts = fandisk
    me = obj.data
    assert counts == (6475, 12946)
    assert (len(me.vertices), len(me.polygons)) == counts  # faces kept as they are
    assert np.array_equal(h.key(me, "Basis"), before)
    tol = 1e-6 * diagonal(before)
    assert np.abs(h.evaluated(obj) - before).max() <= tol
    me.multiscale.bands[2].gain = 0.0  # remove the finest band
    assert np.abs(h.evaluated(obj) - before).max() > 100 * tol
    for band in me.multiscale.bands:
        band.gain = 0.0
    assert np.abs(h.evaluated(obj) - h.key(me, "Level 0")).max() <= tol


def test_scan_rebuild_on_unedited_base_gives_the_scan(fandisk):
    obj, before, _ = fandisk
    me = obj.data
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    error = np.abs(h.key(me, "Multiscale Edit") - before).max() / diagonal(before)
    assert error <= 1e-5
