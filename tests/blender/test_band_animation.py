"""Which keyframes animate a band: those of the mesh's own slot of its action, and those in its
NLA strips. Blender 5 read every slot of a shared action (another object's keyframes were
warned of as this one's), and no version read the NLA (keyframes pushed down into a strip were
not warned of, and the band applied twice)."""

import bpy
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _decomposed(name):
    obj = h.mesh_object(h.noisy_sphere(3000), name=name)
    h.decompose(obj, levels=3)
    return obj


def _keyframe_band(obj, name="Band 0"):
    band = obj.data.shape_keys.key_blocks[name]
    band.value = 0.5
    band.keyframe_insert("value", frame=1)
    return obj.data.shape_keys.animation_data


def test_keyframes_pushed_down_into_the_nla_are_warned_of(capfd):
    obj = _decomposed("A")
    animation = _keyframe_band(obj)
    action = animation.action
    slot = getattr(animation, "action_slot", None)
    track = animation.nla_tracks.new()
    strip = track.strips.new("pushed down", 1, action)
    if slot is not None:
        strip.action_slot = slot
    animation.action = None
    bpy.context.view_layer.objects.active = obj
    capfd.readouterr()
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert "'Band 0' is keyframed or driven" in capfd.readouterr().out
    track.mute = True  # a muted track animates nothing
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert "is keyframed or driven" not in capfd.readouterr().out


@pytest.mark.skipif(bpy.app.version < (4, 4, 0), reason="actions have slots from Blender 4.4 on")
def test_another_objects_keyframes_in_a_shared_action_are_not_this_ones(capfd):
    a, b = _decomposed("A"), _decomposed("B")
    animation = _keyframe_band(a)  # A's keys get the action, in their own slot
    b.data.shape_keys.animation_data_create()
    b.data.shape_keys.animation_data.action = animation.action
    _keyframe_band(b, "Band 1")  # B's go into the same action, in another slot
    assert b.data.shape_keys.animation_data.action == animation.action
    assert len(animation.action.slots) == 2
    bpy.context.view_layer.objects.active = a
    capfd.readouterr()
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "'Band 0' is keyframed or driven" in out and "'Band 1'" not in out, out
    bpy.context.view_layer.objects.active = b
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "'Band 1' is keyframed or driven" in out and "'Band 0'" not in out, out


def test_a_keyframed_scale_slider_is_warned_of_by_rebuild_and_bake(capfd):
    """Rebuild Detail and Bake Filter show their result alone at Scale = the band count; keyframes
    on Scale set it back on the next frame, and the levels showed under the result, unsaid."""
    obj = _decomposed("A")
    mesh = obj.data
    mesh.multiscale.scale = 0.3
    mesh.keyframe_insert("multiscale.scale", frame=1)
    bpy.context.view_layer.objects.active = obj
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    said = [line for line in capfd.readouterr().out.splitlines() if "Scale slider or a Level key" in line]
    assert len(said) == 2 and said[0].startswith("Warning: Rebuild detail") and "key Scale at 2" in said[0], said


def test_an_unanimated_scale_slider_is_not_warned_of(capfd):
    obj = _decomposed("A")
    _keyframe_band(obj)  # a band's keyframes are not the Scale's
    bpy.context.view_layer.objects.active = obj
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "Scale slider" not in capfd.readouterr().out
