"""Create Morph copies A: the copy's animation is its own (a keyframe on the morph object left
A's animation changed, as the two shared one action)."""

import bpy
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _location_x(obj, frame):
    bpy.context.scene.frame_set(frame)
    return obj.matrix_world.translation.x


def test_a_keyframe_on_the_morph_object_leaves_a_animation_as_it_was():
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    a.location.x = 0.0
    a.keyframe_insert("location", index=0, frame=1)
    a.location.x = 2.0
    a.keyframe_insert("location", index=0, frame=10)
    h.decompose(a, levels=3)
    action = a.animation_data.action
    morph = h.morph_onto_bumpy_b(a)
    assert morph.animation_data.action is not None and morph.animation_data.action != action
    assert _location_x(morph, 10) == pytest.approx(2.0)  # A's animation, copied
    morph.location.x = 7.0
    morph.keyframe_insert("location", index=0, frame=10)
    assert _location_x(a, 10) == pytest.approx(2.0)  # A's own stays
    assert _location_x(morph, 10) == pytest.approx(7.0)
    assert a.animation_data.action == action


def test_a_morph_of_an_object_without_animation_gets_none():
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    h.decompose(a, levels=3)
    actions = len(bpy.data.actions)
    morph = h.morph_onto_bumpy_b(a)
    assert morph.animation_data is None or morph.animation_data.action is None
    assert len(bpy.data.actions) == actions


def test_the_morph_mesh_keeps_no_curves_of_a_decomposition_it_does_not_have():
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    h.decompose(a, levels=3)
    a.data.keyframe_insert("multiscale.bands[0].gain", frame=1)
    a.data.keyframe_insert("multiscale.scale", frame=1)
    morph = h.morph_onto_bumpy_b(a)
    assert _curve_paths(morph.data) == []
    assert sorted(_curve_paths(a.data)) == ["multiscale.bands[0].gain", "multiscale.scale"]  # A keeps its own


def _curve_paths(owner) -> list:
    """The data paths of the F-curves in ``owner``'s action (its slot's, from Blender 4.4 on)."""
    animation = owner.animation_data
    action = animation.action if animation is not None else None
    if action is None:
        return []
    layers = list(getattr(action, "layers", ()))
    if layers:
        bags = [strip.channelbag(animation.action_slot) for layer in layers for strip in layer.strips]
        return [c.data_path for bag in bags if bag is not None for c in bag.fcurves]
    return [c.data_path for c in action.fcurves]
