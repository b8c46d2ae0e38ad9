"""The Basis key removed by hand: 'Level 0' became the reference key, every key then moved from
the smooth base, and the panel went on as if nothing had happened while Rebuild and Bake blamed
an edit of the mesh. Now every operator that needs the decomposition says what happened."""

import bpy
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
