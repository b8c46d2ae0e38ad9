"""A seventh artist's pass (trial, 2026-12-07): a half model under a Mirror modifier found
hundreds of false folds once Level 0 was edited at all, and Prevent Folds then moved the whole
model."""

import bmesh
import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _bumpy_half_sphere():
    """An ico sphere's x >= 0 half, bumpy, under a Mirror modifier."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=5)
    obj = bpy.context.active_object
    mesh = obj.data
    co = h.vertices(mesh)
    d = 1 + 0.08 * np.sin(5 * co[:, 0]) * np.sin(5 * co[:, 1]) + 0.02 * np.sin(19 * co[:, 2])
    mesh.vertices.foreach_set("co", (co * d[:, None]).astype(np.float32).ravel())
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bmesh.ops.bisect_plane(bm, geom=bm.verts[:] + bm.edges[:] + bm.faces[:], plane_co=(0, 0, 0),
                           plane_no=(1, 0, 0), clear_inner=True)
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()
    obj.modifiers.new("Mirror", "MIRROR")
    return obj


def _folds_marked(obj) -> int:
    group = obj.vertex_groups.get("Folds")
    if group is None:
        return 0
    return sum(1 for v in obj.data.vertices if any(g.group == group.index for g in v.groups))


def test_a_nudge_of_one_base_vertex_of_a_mirrored_half_folds_nowhere(addon):
    """One vertex of Level 0 moved by 1e-4: 598 of 1473 points were said to fold, and with
    Prevent Folds 1472 other vertices moved by up to 0.32 on a model 2.2 across."""
    obj = _bumpy_half_sphere()
    mesh = obj.data
    mesh.multiscale.levels = 4
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    basis = h.key(mesh, "Basis")
    level0 = h.key(mesh, "Level 0")
    top = int(np.argmax(basis[:, 2]))
    level0[top, 2] += 1e-4
    h.set_key(mesh, "Level 0", level0)
    for prevent in (False, True):
        mesh.multiscale.prevent_folds = prevent
        mesh.multiscale.show_folds = True
        assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
        assert _folds_marked(obj) == 0, prevent
        moved = np.linalg.norm(h.key(mesh, "Multiscale Edit") - basis, axis=1)
        moved[top] = 0.0
        assert moved.max() < 1e-4, (prevent, moved.max())  # the nudge's own reach, in float32


def test_clear_keeps_the_last_results_as_decompose_again_does(addon):
    """Clear removed Multiscale Edit and Multiscale Filter, the artist's results, while it kept
    the intermediate 'Level 0 (previous)' (the viewport jumped back by 0.32)."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    level0 = h.key(mesh, "Level 0")
    level0[:, 2] += 0.2 * np.exp(-np.sum((level0 - level0[np.argmax(level0[:, 2])]) ** 2, axis=1) / 0.3)
    h.set_key(mesh, "Level 0", level0)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    mesh.multiscale.bands[1].gain = 2.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    results = {name: h.key(mesh, name) for name in ("Multiscale Edit", "Multiscale Filter")}
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    names = set(mesh.shape_keys.key_blocks.keys())
    assert names == {"Basis", "Level 0 (previous)", "Multiscale Edit (previous)", "Multiscale Filter (previous)"}
    for name, co in results.items():
        assert np.array_equal(h.key(mesh, name + " (previous)"), co)
        assert mesh.shape_keys.key_blocks[name + " (previous)"].value == 0.0
    # A second Decompose and Clear replace them, as before.
    h.decompose(obj, levels=3)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert set(mesh.shape_keys.key_blocks.keys()) == names


def test_clear_refuses_where_a_result_would_be_kept_over_the_artists_own_key(addon):
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    mesh.multiscale.bands[0].gain = 0.5
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    obj.shape_key_add(name="Multiscale Filter (previous)", from_mix=False)
    with pytest.raises(RuntimeError, match="shape key 'Multiscale Filter \\(previous\\)' of its own"):
        bpy.ops.pointscale.clear()
    assert mesh.shape_keys.key_blocks.get("Multiscale Filter") is not None  # nothing removed


@pytest.mark.parametrize("mode", ["EDIT", "SCULPT"])
def test_paint_band_mask_leaves_the_artist_in_their_mode(addon, mode):
    """A refused band, and a mask made without entering Weight Paint, left the object in Object
    Mode."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4)
    obj = bpy.context.active_object
    h.decompose(obj, levels=3)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode=mode)
    with pytest.raises(RuntimeError, match="band 7 does not exist"):
        bpy.ops.pointscale.paint_band_mask(band=7)
    assert obj.mode == mode
    assert bpy.ops.pointscale.paint_band_mask(band=1, enter_paint=False) == {"FINISHED"}
    assert obj.mode == mode and obj.vertex_groups.get("Band 1 mask") is not None
    bpy.ops.object.mode_set(mode="OBJECT")


def test_edits_of_other_levels_and_bands_are_said_unused_and_kept(addon, capfd):
    """Level 1 lifted and Band 1 edited: Rebuild Detail and Bake Filter used neither, without a
    word, and Decompose again wrote over both."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=4)
    level1, band1 = h.key(mesh, "Level 1"), h.key(mesh, "Band 1")
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "not used" not in capfd.readouterr().out  # nothing edited: nothing said
    lifted = level1.copy()
    lifted[np.argmax(lifted[:, 2]), 2] += 0.3
    h.set_key(mesh, "Level 1", lifted)
    edited_band = band1 * np.float32(1.01)
    h.set_key(mesh, "Band 1", edited_band)
    for operator in (bpy.ops.pointscale.rebuild_detail, bpy.ops.pointscale.bake_filter):
        capfd.readouterr()
        assert operator() == {"FINISHED"}
        said = capfd.readouterr().out
        assert "'Level 1', 'Band 1' were edited since Decompose and are not used" in said, said
    h.decompose(obj, levels=4)
    assert np.array_equal(h.key(mesh, "Level 1 (previous)"), lifted)
    assert np.array_equal(h.key(mesh, "Band 1 (previous)"), edited_band)
    assert np.array_equal(h.key(mesh, "Level 1"), level1)  # the new decomposition's, as before
    assert mesh.shape_keys.key_blocks["Level 1 (previous)"].value == 0.0
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "not used" not in capfd.readouterr().out
    # Clear keeps them too, and the next edit of Level 2 is kept beside them.
    level2 = h.key(mesh, "Level 2")
    level2[:, 0] += 0.01
    h.set_key(mesh, "Level 2", level2)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    names = set(mesh.shape_keys.key_blocks.keys())
    assert {"Level 1 (previous)", "Band 1 (previous)", "Level 2 (previous)"} <= names
    assert not any(name in names for name in ("Level 1", "Band 1", "Level 2"))
    assert np.array_equal(h.key(mesh, "Level 2 (previous)"), level2)


def _decomposed_with_a_key_moved(name: str, axis: int):
    """A sphere decomposed into 3 levels, then its key `name` moved by 0.01 along `axis`:
    (object, mesh, the key's moved positions)."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    moved = h.key(mesh, name)
    moved[:, axis] += 0.01
    h.set_key(mesh, name, moved)
    return obj, mesh, moved


def test_an_edited_level_is_not_kept_over_the_artists_own_key(addon):
    obj, mesh, level1 = _decomposed_with_a_key_moved("Level 1", 2)
    obj.shape_key_add(name="Level 1 (previous)", from_mix=False)
    with pytest.raises(RuntimeError, match="'Level 1 \\(previous\\)' of its own"):
        bpy.ops.pointscale.decompose()
    with pytest.raises(RuntimeError, match="'Level 1 \\(previous\\)' of its own"):
        bpy.ops.pointscale.clear()
    assert np.array_equal(h.key(mesh, "Level 1"), level1)


def test_a_bake_leaves_a_muted_bands_setting_as_it_was(addon):
    """The bake rightly left a muted band out, but set its slider back to gain 1 (3 was lost)."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    mesh.multiscale.bands[0].gain = 0.5
    mesh.multiscale.bands[1].gain = 3.0
    mesh.shape_keys.key_blocks["Band 1"].mute = True
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert mesh.multiscale.bands[0].gain == pytest.approx(1.0)
    assert mesh.multiscale.bands[1].gain == pytest.approx(3.0)


def test_modifiers_that_change_the_shape_are_named_at_decompose(addon, capfd):
    """An unapplied Displace made the bumps in the viewport; Decompose worked on the smooth mesh
    without a word (it warns of an unapplied non-uniform scale)."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=5)
    obj = bpy.context.active_object
    obj.modifiers.new("Bumps", "DISPLACE")
    obj.modifiers.new("Weights", "VERTEX_WEIGHT_EDIT")
    capfd.readouterr()
    h.decompose(obj, levels=3)
    out = capfd.readouterr().out
    assert "modifiers that change its shape ('Bumps')" in out, out
    obj.modifiers["Bumps"].show_viewport = False
    h.decompose(obj, levels=3)
    assert "modifiers that change its shape" not in capfd.readouterr().out
    # A Mirror modifier is read by Decompose itself, unless Use Mirror Modifier is off.
    obj.modifiers.new("Half", "MIRROR").use_bisect_axis[0] = True
    obj.data.multiscale.use_mirror_modifier = False
    h.decompose(obj, levels=3)
    assert "modifiers that change its shape ('Half')" in capfd.readouterr().out


def test_a_linked_duplicate_mirrored_otherwise_is_named_at_decompose(addon, capfd):
    """Decompose from the user without the Mirror modifier: the other user's seam tore (its seam
    vertices up to 0.049 off the plane), without a word."""
    obj = _bumpy_half_sphere()
    obj.modifiers.remove(obj.modifiers["Mirror"])
    twin = bpy.data.objects.new("Twin", obj.data)
    bpy.context.scene.collection.objects.link(twin)
    twin.modifiers.new("Mirror", "MIRROR")
    bpy.context.view_layer.objects.active = obj
    capfd.readouterr()
    h.decompose(obj, levels=3)
    out = capfd.readouterr().out
    assert "'Twin' shares this mesh but mirrors it otherwise" in out, out
    obj.modifiers.new("Mirror", "MIRROR")  # now alike: nothing to say
    h.decompose(obj, levels=3)
    assert "mirrors it otherwise" not in capfd.readouterr().out


def test_absolute_keys_are_refused_by_rebuild_and_bake(addon):
    """With Relative turned off after the Decompose, Rebuild Detail and Bake Filter said they
    had rebuilt and baked, and the viewport kept showing the Basis."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    mesh.shape_keys.use_relative = False
    for operator in (bpy.ops.pointscale.rebuild_detail, bpy.ops.pointscale.bake_filter):
        assert not operator.poll()
        with pytest.raises(RuntimeError, match="made absolute \\(Relative is off\\): turn Relative back on"):
            operator()
    assert mesh.shape_keys.key_blocks.get("Multiscale Edit") is None
    assert bpy.ops.pointscale.clear() == {"FINISHED"}  # Clear still cleans up


def test_clear_says_what_it_kept_now_and_what_was_kept_before(addon, capfd):
    """A 'Level 0 (previous)' left by an earlier Decompose was reported by the next Clear as
    'kept Level 0, changed since Decompose wrote it', though the fresh Level 0 was unedited and
    dropped."""
    obj, mesh, level0 = _decomposed_with_a_key_moved("Level 0", 0)
    h.decompose(obj, levels=3)  # keeps the edit as 'Level 0 (previous)'
    capfd.readouterr()
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "changed since Decompose wrote it" not in out, out
    assert "kept the earlier 'Level 0 (previous)'" in out, out
    assert np.array_equal(h.key(mesh, "Level 0 (previous)"), level0)


def test_a_basis_edit_carried_into_the_keys_is_no_edit_of_theirs(addon, capfd):
    """A Basis vertex moved in Edit Mode: Blender carries the move into every relative key, and
    the next Decompose kept 'Level 1 (previous)', 'Band 0 (previous)'... as 'your edits of other
    levels and bands'."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4)
    obj = bpy.context.active_object
    mesh = obj.data
    h.decompose(obj, levels=3)
    obj.active_shape_key_index = 0
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(mesh)
    bm.verts.ensure_lookup_table()
    bm.verts[0].co.z += 0.05
    bmesh.update_edit_mesh(mesh)
    bpy.ops.object.mode_set(mode="OBJECT")
    capfd.readouterr()
    h.decompose(obj, levels=3)
    out = capfd.readouterr().out
    assert "your edits of other levels and bands" not in out, out
    assert not any(name.startswith(("Level 1 ", "Band ")) and name.endswith("(previous)")
                   for name in mesh.shape_keys.key_blocks.keys())


def test_a_gain_keyframed_on_the_panels_slider_is_warned_of(addon, capfd):
    """Keyframes on the panel's Gain slider (the mesh's multiscale.bands[0].gain, where hovering
    it and pressing I puts them) got past Bake Filter's check, which read the Band keys only:
    the band came back on the next frame and applied twice, without a word. Reset Gains too."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    scene = bpy.context.scene
    scene.frame_set(1)
    mesh.keyframe_insert("multiscale.bands[0].gain", frame=1)
    mesh.multiscale.bands[0].gain = 3.0
    mesh.keyframe_insert("multiscale.bands[0].gain", frame=20)
    scene.frame_set(20)
    capfd.readouterr()
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert "'Band 0' is keyframed or driven" in capfd.readouterr().out
    assert bpy.ops.pointscale.reset_bands() == {"FINISHED"}
    assert "Reset gains: 'Band 0' is keyframed or driven" in capfd.readouterr().out
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}  # band 1, not animated: nothing said of it
    assert "'Band 1'" not in capfd.readouterr().out


def test_paint_band_mask_keeps_the_group_the_artist_picked(addon):
    """A group picked as the band key's Vertex Group (as the docs advise) was replaced by a new
    'Band 1 mask' at weight 1, and the band applied everywhere again."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    face = obj.vertex_groups.new(name="Face")
    face.add([0, 1, 2, 3], 1.0, "REPLACE")
    mesh.shape_keys.key_blocks["Band 1"].vertex_group = "Face"
    assert bpy.ops.pointscale.paint_band_mask(band=1, enter_paint=False) == {"FINISHED"}
    assert mesh.shape_keys.key_blocks["Band 1"].vertex_group == "Face"
    assert obj.vertex_groups.get("Band 1 mask") is None
    assert obj.vertex_groups.active.name == "Face"


def test_a_kept_result_stays_off_when_its_value_was_keyframed(addon):
    """Keyframes on 'Multiscale Filter' followed the key when it was kept as '(previous)': at
    frame 20 the old and the new bake both showed at 1."""
    obj = h.mesh_object(h.noisy_sphere(3000))
    mesh = obj.data
    h.decompose(obj, levels=3)
    mesh.multiscale.bands[0].gain = 2.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    scene = bpy.context.scene
    key = mesh.shape_keys.key_blocks["Multiscale Filter"]
    key.value = 0.0
    key.keyframe_insert("value", frame=1)
    key.value = 1.0
    key.keyframe_insert("value", frame=20)
    scene.frame_set(20)
    key.mute = True  # not built on: the next bake starts from the sliders and keeps this one
    mesh.multiscale.bands[0].gain = 0.5
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    scene.frame_set(1)
    scene.frame_set(20)
    blocks = mesh.shape_keys.key_blocks
    assert blocks["Multiscale Filter (previous)"].value == 0.0
    assert blocks["Multiscale Filter"].value == 1.0  # the animation goes on driving the result
