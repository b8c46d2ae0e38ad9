"""The Basis key removed by hand: 'Level 0' became the reference key, every key then moved from
the smooth base, and the panel went on as if nothing had happened while Rebuild and Bake blamed
an edit of the mesh. Now every operator that needs the decomposition says what happened."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def test_a_removed_basis_key_is_named_as_such(capfd):
    obj = h.mesh_object(h.noisy_sphere(3000), name="A")
    h.decompose(obj, levels=3)
    obj.active_shape_key_index = 0
    assert obj.data.shape_keys.key_blocks[0].name == "Basis"
    bpy.ops.object.shape_key_remove()
    assert obj.data.shape_keys.reference_key.name == "Level 0"
    capfd.readouterr()
    for op in (bpy.ops.pointscale.rebuild_detail, bpy.ops.pointscale.bake_filter):
        with pytest.raises(RuntimeError, match="the Basis key of 'A' was removed: 'Level 0' is now the reference key"):
            op()


def _decomposed_then_basis_removed(name="K", smile=False):
    obj = h.mesh_object(h.noisy_sphere(3000), name=name)
    original = h.vertices(obj.data).copy()
    shapes = {}
    h.decompose(obj, levels=3)
    if smile:  # a key of the artist's
        obj.shape_key_add(name="Smile", from_mix=False)
        shapes["Smile"] = original * np.float32(1.1)
        h.set_key(obj.data, "Smile", shapes["Smile"])
    obj.active_shape_key_index = 0
    bpy.ops.object.shape_key_remove()
    assert obj.data.shape_keys.reference_key.name == "Level 0"
    return obj, original, shapes


def test_decompose_refuses_while_a_level_is_the_reference_key():
    # Decompose used to decompose the smooth Level 0 and write its own new Level 0 over the
    # reference key: the original shape (still in the keys) was lost.
    obj, original, _ = _decomposed_then_basis_removed()
    h.assert_refused(obj, "decompose", r"the Basis key of 'K' was removed: 'Level 0' is now the reference key.*"
                                       r"Undo the removal \(Ctrl\+Z\), or Clear")
    for op in ("decompose", "rebuild_detail", "bake_filter"):
        with pytest.raises(RuntimeError) as refused:
            getattr(bpy.ops.pointscale, op)()
        assert "Decompose again" not in str(refused.value)
    level, band = h.key(obj.data, "Level 1"), h.key(obj.data, "Band 1")
    assert np.abs((level.astype(np.float64) + band) / 2 - original).max() < 1e-6  # still recoverable


def test_clear_puts_the_original_shape_back_after_the_basis_was_removed():
    # Clear used to remove every key and leave the mesh on a smoothed level (0.02-0.18 off).
    obj, original, _ = _decomposed_then_basis_removed()
    assert np.abs(h.vertices(obj.data) - original).max() > 0.05
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert obj.data.shape_keys is None  # the Basis was the add-on's, as before the removal
    assert np.abs(h.vertices(obj.data) - original).max() < 1e-6
    assert np.abs(h.evaluated(obj) - original).max() < 1e-6


def test_clear_keeps_the_artists_keys_moving_from_the_restored_basis():
    obj, original, shapes = _decomposed_then_basis_removed(smile=True)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    kbs = obj.data.shape_keys.key_blocks
    assert [kb.name for kb in kbs] == ["Basis", "Smile"]
    assert np.abs(h.key(obj.data, "Basis") - original).max() < 1e-6
    assert np.abs(h.vertices(obj.data) - original).max() < 1e-6
    kbs["Smile"].value = 1.0
    assert np.abs(h.evaluated(obj) - shapes["Smile"]).max() < 1e-5
    kbs["Smile"].value = 0.0
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}  # and the original decomposes again


def test_clear_refuses_when_the_keys_that_hold_the_original_were_edited():
    obj, original, _ = _decomposed_then_basis_removed()
    h.set_key(obj.data, "Band 1", h.key(obj.data, "Band 1") * np.float32(1.01))
    h.assert_refused(obj, "clear", r"the Basis key of 'K' was removed, and 'Band 1', which holds the original "
                                   r"shape, was edited since Decompose: undo the removal \(Ctrl\+Z\)")


def test_morph_refuses_an_a_whose_basis_key_was_removed():
    # A's reference key is then its smooth Level 0: the morph was made from that, not from A.
    obj, _, _ = _decomposed_then_basis_removed(name="A")
    b = h.mesh_object(h.noisy_sphere(2000, seed=1) * 1.2, name="B")
    bpy.context.view_layer.objects.active = obj
    obj.data.multiscale.morph_target = b
    n_objects = len(bpy.data.objects)
    with pytest.raises(RuntimeError, match=r"the Basis key of 'A' was removed.*Undo the removal \(Ctrl\+Z\)"):
        bpy.ops.pointscale.morph()
    assert len(bpy.data.objects) == n_objects
