"""A second artist's pass (QA, 2026-12-06): results kept by a second Decompose are switched off
(they used to stay on and stack under the next edit, and still showed after Clear), a hidden
object gets a report rather than a traceback from Blender's mode switch, and a vertex group the
artist picked for a band key survives a second Decompose."""

import sys

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def lifted_top(obj, by=0.3):
    """Raise the 'Level 0' key's upper half: an edit of the base."""
    co = h.key(obj.data, "Level 0").copy()
    co[co[:, 2] > 0.5, 2] += by
    h.set_key(obj.data, "Level 0", co)


def test_kept_results_are_switched_off_and_never_stack():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Stack")
    original = h.vertices(obj.data).astype(np.float64)
    scale = h.diagonal(original)
    h.decompose(obj)
    lifted_top(obj)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    h.decompose(obj)  # keeps both results as "(previous)"
    blocks = obj.data.shape_keys.key_blocks
    assert blocks["Multiscale Edit (previous)"].value == 0.0
    assert blocks["Multiscale Filter (previous)"].value == 0.0
    # A new decomposition shows the original, not the kept edit on top of it.
    assert np.abs(h.evaluated(obj) - original).max() < 1e-6 * scale
    # The next edit shows alone: as its own key says, not stacked on the kept one.
    lifted_top(obj)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    shown = h.evaluated(obj)
    edit = h.key(obj.data, "Multiscale Edit").astype(np.float64)
    assert np.abs(shown - edit).max() < 1e-6 * scale
    blocks["Multiscale Edit (previous)"].value = 1.0  # the artist turns a kept result on ...
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert blocks["Multiscale Edit (previous)"].value == 0.0  # ... and a new result shows alone again
    # Clear keeps the earlier results (switched off) and the mesh looks as it did.
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert "Multiscale Edit (previous)" in obj.data.shape_keys.key_blocks
    assert np.abs(h.evaluated(obj) - original).max() < 1e-6 * scale


@pytest.mark.parametrize("hide", ["hide_viewport", "hide_set"])
@pytest.mark.parametrize("mode", ["EDIT", "SCULPT"])
def test_edit_base_on_a_hidden_object_is_refused_with_a_report(hide, mode):
    obj = h.mesh_object(h.noisy_sphere(4000), name="Hidden")
    h.decompose(obj)
    if hide == "hide_set":
        obj.hide_set(True)
    else:
        obj.hide_viewport = True
    assert not obj.visible_get()
    h.assert_refused(obj, "edit_base", "is hidden: unhide it", mode=mode)
    assert obj.data.multiscale.scale == obj.data.multiscale.n_bands  # still showing the original
    assert obj.mode == "OBJECT"
    assert bpy.ops.pointscale.edit_base(mode="OBJECT") == {"FINISHED"}  # only activates the key: fine hidden


def test_a_vertex_group_the_artist_picked_for_a_band_survives_a_second_decompose():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Picked")
    face = obj.vertex_groups.new(name="Face")
    face.add(list(range(0, 4000, 2)), 1.0, "REPLACE")
    h.decompose(obj)
    obj.data.shape_keys.key_blocks["Band 1"].vertex_group = "Face"
    h.decompose(obj, kernel=1.2)
    assert obj.data.shape_keys.key_blocks["Band 1"].vertex_group == "Face"
    assert obj.data.shape_keys.key_blocks["Band 0"].vertex_group == ""


def test_a_flat_mesh_is_refused_in_the_add_ons_words():
    logic = sys.modules[h.ADDON_NAME + ".logic"]
    message = logic.engine_message("points all lie in one plane: there is no detail to separate from a base "
                                   "(use project() to work with planar data)", 24, 4)
    assert "project()" not in message and "flat mesh" in message
    assert logic.engine_message("flat input", 24, 3) == "flat input"
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=60, y_subdivisions=60)
    with pytest.raises(RuntimeError, match="flat mesh is all base"):
        bpy.ops.pointscale.decompose()


def test_a_morph_target_without_vertices_is_named():
    a = h.mesh_object(h.noisy_sphere(4000), name="A")
    empty = bpy.data.objects.new("Empty B", bpy.data.meshes.new("Empty B"))
    bpy.context.collection.objects.link(empty)
    a.data.multiscale.morph_target = empty
    bpy.context.view_layer.objects.active = a
    assert not bpy.ops.pointscale.morph.poll()
    with pytest.raises(RuntimeError, match="'Empty B' has no vertices"):
        bpy.ops.pointscale.morph()


def test_morph_reads_a_target_left_in_edit_mode_as_shown():
    import bmesh

    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    b = h.mesh_object(h.noisy_sphere(2500, seed=1), name="B")
    a.data.multiscale.morph_target = b
    bpy.context.view_layer.objects.active = b
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(b.data)
    for v in bm.verts:
        v.co.z *= 1.5  # an edit not yet written to the mesh
    bmesh.update_edit_mesh(b.data)
    bpy.context.view_layer.objects.active = a
    assert b.mode == "EDIT" and a.mode == "OBJECT"
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    in_edit = h.key(bpy.context.active_object.data, "B detail").copy()
    bpy.context.view_layer.objects.active = b
    bpy.ops.object.mode_set(mode="OBJECT")  # now written
    bpy.context.view_layer.objects.active = a
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    assert np.array_equal(in_edit, h.key(bpy.context.active_object.data, "B detail"))
