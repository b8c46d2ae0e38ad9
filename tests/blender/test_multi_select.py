"""Decompose with several objects selected acts on the active one, as every operator of the
add-on does (each mesh keeps its own settings in its panel), and now says which it decomposed
and that the other selected ones were left as they are."""

import bpy
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def test_decompose_names_the_selected_objects_it_left(capfd):
    import pointscale as ps

    rocks = [h.mesh_object(ps.shapes.bumpy_sphere(2000, seed=i) + [3 * i, 0, 0], name=f"Rock{i}") for i in range(3)]
    for o in rocks:
        o.select_set(True)
    bpy.context.view_layer.objects.active = rocks[1]
    capfd.readouterr()
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    out = capfd.readouterr().out
    assert [o.data.shape_keys is not None for o in rocks] == [False, True, False]
    assert ("Decomposed only the active object 'Rock1': 'Rock0', 'Rock2' are selected too but left as they are "
            "(each mesh has its own settings: make each active and Decompose it)") in out
    for o in rocks:  # alone, nothing more is said
        o.select_set(o is rocks[2])
    bpy.context.view_layer.objects.active = rocks[2]
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    assert "Decomposed only" not in capfd.readouterr().out
