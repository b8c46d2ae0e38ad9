"""The Level and Band keys stay in order when Decompose runs again with more levels: it used to
add the new keys at the end, after the old Band keys (Basis, Level 0, Level 1, Band 0, Band 1,
Level 2, Level 3, Band 2, Band 3). The artist's own keys keep their places beside the add-on's."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def names(obj):
    return [kb.name for kb in obj.data.shape_keys.key_blocks]


def test_more_levels_keep_the_keys_in_order_with_their_data_and_the_artists_keys_in_place():
    obj = h.mesh_object(h.noisy_sphere(12000, seed=4))
    h.decompose(obj, levels=3)
    # The artist's key between the add-on's, animated, and a band key's gain animated too.
    smile = obj.shape_key_add(name="Smile", from_mix=False)
    smile.value = 0.3
    smile.keyframe_insert("value", frame=1)
    band = obj.data.shape_keys.key_blocks["Band 1"]
    band.value = 0.5
    band.keyframe_insert("value", frame=1)
    bpy.context.view_layer.objects.active = obj
    obj.active_shape_key_index = names(obj).index("Smile")
    h.decompose(obj, levels=5)
    assert names(obj) == ["Basis", "Level 0", "Level 1", "Level 2", "Level 3", "Band 0", "Band 1", "Band 2",
                          "Band 3", "Smile"]
    assert obj.active_shape_key.name == "Smile"      # the artist stays on the key they had
    # Each key holds its own level: the levels of the stored decomposition, in order.
    addon = h.load_addon()
    dec = addon.storage.load(obj.data, addon.engine.get())
    for l in range(4):
        assert np.allclose(h.key(obj.data, f"Level {l}"), dec.level(l), atol=1e-5 * h.diagonal(dec.level(4)))
    for kb in obj.data.shape_keys.key_blocks[1:]:
        assert kb.relative_key.name == "Basis"
    # Their animation follows them (it names the keys, and the keys moved with their data).
    bpy.context.scene.frame_set(2)
    bpy.context.scene.frame_set(1)
    kbs = obj.data.shape_keys.key_blocks
    assert (kbs["Smile"].value, kbs["Band 1"].value, kbs["Band 0"].value) == pytest.approx((0.3, 0.5, 0.0))
    # Fewer levels again: the keys it removes leave the others in order.
    h.decompose(obj, levels=4)
    assert names(obj) == ["Basis", "Level 0", "Level 1", "Level 2", "Band 0", "Band 1", "Band 2", "Smile"]
