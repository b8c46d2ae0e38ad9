"""Keys of the add-on's renamed or swapped by hand. Swapping the names of Band 0 and Band 1 made
Bake Filter disagree with the preview (each reads a band by its key's name) and the warning
called them edited; a Band key renamed to a name of the artist's stayed applied after a new
Decompose, which then made a new Band key of that name: the band applied twice, unsaid."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _decomposed():
    obj = h.mesh_object(h.noisy_sphere(3000), name="A")
    h.decompose(obj, levels=3)
    return obj


def test_swapped_band_keys_are_said_to_be_swapped_not_edited(capfd):
    obj = _decomposed()
    kbs = obj.data.shape_keys.key_blocks
    kbs["Band 0"].name = "tmp"
    kbs["Band 1"].name = "Band 0"
    kbs["tmp"].name = "Band 1"
    capfd.readouterr()
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "'Band 0' holds what Decompose wrote as 'Band 1'" in out and "'Band 1' holds what Decompose wrote as 'Band 0'" in out, out
    assert "edited since Decompose" not in out, out


def test_a_band_renamed_and_still_applied_is_warned_of_by_a_new_decompose(capfd):
    obj = _decomposed()
    band = obj.data.shape_keys.key_blocks["Band 1"]
    band.name = "Fine detail"
    band.value = 0.5
    capfd.readouterr()
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "'Fine detail' holds the earlier decomposition's 'Band 1' (renamed) and still applies, at 0.5" in out, out
    assert obj.data.shape_keys.key_blocks["Fine detail"].value == 0.5  # the artist's key is left as it is


def test_keys_as_written_say_nothing(capfd):
    obj = _decomposed()
    obj.data.shape_keys.key_blocks["Band 1"].value = 0.5
    capfd.readouterr()
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "holds" not in out and "renamed" not in out, out
