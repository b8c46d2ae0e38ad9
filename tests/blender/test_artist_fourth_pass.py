"""A fourth artist's pass (QA, 2026-12-07): Decompose says when the object is shown under an
unapplied non-uniform scale and when loose vertices join a part; a morph keeps A's modifiers;
the refusal of a non-mesh object reads as English."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender

SCALE_WORDS = "unapplied non-uniform scale"


def _uv_sphere(name="Ball"):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, radius=1.0)
    obj = bpy.context.active_object
    obj.name = name
    return obj


@pytest.mark.parametrize("scale, warned", [((1.0, 1.0, 4.0), True), ((2.0, 2.0, 2.0), False),
                                           ((-1.0, 1.0, 1.0), False), ((1.0, 1.0, 1.0), False)])
def test_decompose_warns_of_an_unapplied_non_uniform_scale(capfd, scale, warned):
    obj = _uv_sphere()
    obj.scale = scale
    obj.rotation_euler = (0.3, 0.2, 0.1)
    bpy.context.view_layer.update()
    h.decompose(obj, levels=3)
    out = capfd.readouterr().out
    assert (SCALE_WORDS in out) == warned, out
    if warned:
        assert "(1, 1, 4)" in out and "Ctrl+A" in out


def test_a_parents_stretch_is_warned_of_too(capfd):
    parent = bpy.data.objects.new("Stretch", None)
    bpy.context.scene.collection.objects.link(parent)
    parent.scale = (3.0, 1.0, 1.0)
    obj = _uv_sphere()
    obj.parent = parent
    bpy.context.view_layer.update()
    h.decompose(obj, levels=3)
    assert SCALE_WORDS in capfd.readouterr().out


def test_loose_vertices_are_counted_when_they_join_a_part(capfd):
    obj = _uv_sphere()
    me = obj.data
    before = len(me.vertices)
    me.vertices.add(20)
    co = np.zeros((20, 3), np.float32)
    co[:, 0] = np.linspace(-0.3, 0.3, 20)
    for i, v in enumerate(me.vertices[before:]):
        v.co = co[i]
    me.update()
    h.decompose(obj, levels=3)
    out = capfd.readouterr().out
    assert f"20 vertices in no edge (first: index {before})" in out, out
    # Without Keep Parts Apart the mesh is one surface: nothing is said.
    h.decompose(obj, levels=3, keep_parts=False)
    assert "in no edge" not in capfd.readouterr().out


def test_a_mesh_without_loose_vertices_or_edges_gets_no_loose_note(capfd):
    obj = h.mesh_object(h.noisy_sphere(3000), name="Cloud")  # vertices only: a point cloud
    h.decompose(obj, levels=3)
    assert "in no edge" not in capfd.readouterr().out


def test_the_morph_keeps_as_modifiers():
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    mirror = a.modifiers.new("Mirror", "MIRROR")
    mirror.use_axis = (True, False, False)
    a.modifiers.new("Smooth", "SMOOTH")
    morph = h.morph_onto_bumpy_b(a)
    assert morph is not a and morph.name == "A x B"
    assert [(m.name, m.type) for m in morph.modifiers] == [("Mirror", "MIRROR"), ("Smooth", "SMOOTH")]
    assert tuple(morph.modifiers["Mirror"].use_axis) == (True, False, False)
    # A is untouched, and the two objects do not share a mesh.
    assert [m.name for m in a.modifiers] == ["Mirror", "Smooth"] and morph.data is not a.data
    assert a.data.shape_keys is None


@pytest.mark.parametrize("kind, words", [("EMPTY", "is an empty, not a mesh"),
                                         ("ARMATURE", "is an armature, not a mesh"),
                                         ("CURVE", "is a curve, not a mesh")])
def test_a_non_mesh_object_is_named_in_english(kind, words):
    from importlib import import_module

    state = import_module(f"{h.ADDON_NAME}.state")
    data = {"EMPTY": None, "ARMATURE": bpy.data.armatures.new("Rig"),
            "CURVE": bpy.data.curves.new("Path", "CURVE")}[kind]
    obj = bpy.data.objects.new("Thing", data)
    assert words in state.mesh_object_problem(obj)


def test_the_morph_sits_where_a_is_shown_under_a_constraint_and_shows_its_keys():
    """The copy of A carries A's constraints and transform: placing it at A's world matrix as well
    applied a Copy Location offset twice (x = 11 for A at 6); A's Shape Key Lock hid the keys."""
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    target = bpy.data.objects.new("Target", None)
    bpy.context.scene.collection.objects.link(target)
    target.location = (5.0, 0.0, 0.0)
    follow = a.constraints.new("COPY_LOCATION")
    follow.target, follow.use_offset = target, True
    a.location = (1.0, 0.0, 0.0)
    a.shape_key_add(name="Basis")
    a.shape_key_add(name="Smile")
    a.show_only_shape_key = True
    morph = h.morph_onto_bumpy_b(a)
    bpy.context.view_layer.update()
    assert np.abs(np.array(morph.matrix_world) - np.array(a.matrix_world)).max() < 1e-6
    assert tuple(morph.matrix_world.translation) == pytest.approx((6.0, 0.0, 0.0))
    assert not morph.show_only_shape_key and a.show_only_shape_key
