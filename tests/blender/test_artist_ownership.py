"""The add-on modifies or deletes only data it created (QA pass, December 2026): an artist's
vertex group, shape key or attribute that merely has one of its names is refused or left alone,
never taken over. Also: an edited Basis is refused in the session as after a reload, the artist's
active vertex group, mode and colour attribute come back, and the parts refusal speaks the
panel's terms."""

import re
import sys

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def sphere():
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32)
    return bpy.context.active_object


def group_weights(obj, name):
    """{vertex index: weight} of the vertex group ``name``."""
    index = obj.vertex_groups[name].index
    return {v.index: g.weight for v in obj.data.vertices for g in v.groups if g.group == index}


# ---------------------------------------------------------------- 1. the artist's 'Folds' group

def test_an_artists_folds_group_is_neither_written_nor_cleared(capfd):
    obj = sphere()
    obj.vertex_groups.new(name="Folds").add(list(range(100)), 0.7, "REPLACE")
    mine = group_weights(obj, "Folds")
    h.decompose(obj)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert group_weights(obj, "Folds") == mine
    assert "vertex group 'Folds' of its own" in capfd.readouterr().out
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert group_weights(obj, "Folds") == mine


def test_the_add_ons_own_folds_group_is_still_cleared():
    obj = sphere()
    h.decompose(obj)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert obj.vertex_groups.get("Folds") is not None
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert obj.vertex_groups.get("Folds") is None


# ---------------------------------------------------------------- 2. result key names

@pytest.mark.parametrize("name", ["Multiscale Edit", "Multiscale Filter", "Multiscale Edit (previous)",
                                  "Multiscale Filter (previous)"])
def test_an_artists_key_with_a_result_name_is_refused(name):
    obj = sphere()
    obj.shape_key_add(name="Basis")
    obj.shape_key_add(name=name)
    h.set_key(obj.data, name, h.key(obj.data, "Basis") + [0, 0, 1])
    h.assert_refused(obj, "decompose", re.escape(f"'{name}' of its own"))


@pytest.mark.parametrize("operator, name", [("rebuild_detail", "Multiscale Edit"), ("bake_filter", "Multiscale Filter")])
def test_an_artists_result_named_key_made_after_decompose_is_refused_and_kept(operator, name):
    obj = sphere()
    h.decompose(obj)
    obj.shape_key_add(name=name, from_mix=False)
    mine = h.key(obj.data, "Basis") + [0, 0, 1]
    h.set_key(obj.data, name, mine)
    h.assert_refused(obj, operator, f"'{name}' of its own")
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert np.array_equal(h.key(obj.data, name), mine.astype(np.float32))


def test_the_add_ons_previous_results_are_still_replaced_and_kept_by_clear():
    obj = sphere()
    for _ in range(3):  # the second and third Decompose replace the add-on's own "(previous)" keys
        h.decompose(obj)
        assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
        assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    h.decompose(obj)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    names = [k.name for k in obj.data.shape_keys.key_blocks]
    assert names == ["Basis", "Multiscale Edit (previous)", "Multiscale Filter (previous)"]
    h.decompose(obj)  # after Clear they are still the add-on's to replace


# ---------------------------------------------------------------- 3. attributes with the add-on's prefixes

def test_the_artists_attributes_with_the_add_ons_prefixes_survive():
    obj = sphere()
    mesh = obj.data
    values = np.arange(len(mesh.vertices), dtype=np.float32)
    mesh.attributes.new("ms_detail_sculpt", "FLOAT", "POINT").data.foreach_set("value", values)
    mesh.attributes.new("ms_normal_mine", "FLOAT_VECTOR", "POINT")
    mesh.attributes.new(".ps.mine", "INT", "POINT")
    h.decompose(obj)
    h.decompose(obj, levels=3)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    names = {a.name for a in mesh.attributes}
    assert {"ms_detail_sculpt", "ms_normal_mine", ".ps.mine"} <= names
    assert not any(name.startswith("ms_detail_") and name[10:].isdigit() for name in names)
    assert np.array_equal(h.snapshot(obj)["attr:ms_detail_sculpt"], values)


def test_an_artists_normal_named_attribute_survives_when_the_add_on_writes_no_normals():
    """By default the add-on writes no ms_normal_<l> columns, so an artist's own of that name is
    not its to remove, by Clear or by the Clear a second Decompose does."""
    obj = sphere()
    mesh = obj.data
    values = np.arange(3 * len(mesh.vertices), dtype=np.float32)
    mesh.attributes.new("ms_normal_0", "FLOAT_VECTOR", "POINT").data.foreach_set("vector", values)
    h.decompose(obj)
    h.decompose(obj, levels=3)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    kept = mesh.attributes.get("ms_normal_0")
    assert kept is not None
    got = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    kept.data.foreach_get("vector", got)
    assert np.array_equal(got, values)


def test_an_artists_attribute_with_a_detail_name_is_refused():
    obj = sphere()
    obj.data.attributes.new("ms_detail_1", "FLOAT", "POINT")
    h.assert_refused(obj, "decompose", "attribute 'ms_detail_1' of its own")


def test_an_artists_detail_colour_attribute_is_refused_by_show_details():
    obj = sphere()
    h.decompose(obj)
    obj.data.color_attributes.new("ms_detail_color", "BYTE_COLOR", "POINT")
    h.assert_refused(obj, "show_details", "'ms_detail_color' of its own")
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert obj.data.color_attributes.get("ms_detail_color") is not None


# ---------------------------------------------------------------- 4. a 'Band l mask' the artist made

def test_a_band_mask_group_made_before_decompose_is_refused():
    obj = sphere()
    obj.vertex_groups.new(name="Band 0 mask").add(list(range(len(obj.data.vertices))), 1.0, "REPLACE")
    h.assert_refused(obj, "decompose", "vertex group 'Band 0 mask' of its own")
    assert obj.vertex_groups.get("Band 0 mask") is not None


def test_a_band_mask_group_made_after_decompose_is_neither_taken_nor_cleared():
    obj = sphere()
    h.decompose(obj)
    obj.vertex_groups.new(name="Band 1 mask").add(list(range(len(obj.data.vertices))), 1.0, "REPLACE")
    h.assert_refused(obj, "paint_band_mask", "vertex group 'Band 1 mask' of its own", band=1, enter_paint=False)
    assert obj.data.shape_keys.key_blocks["Band 1"].vertex_group == ""
    assert bpy.ops.pointscale.paint_band_mask(band=0, enter_paint=False) == {"FINISHED"}  # the add-on's own
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert [g.name for g in obj.vertex_groups] == ["Band 1 mask"]


# ---------------------------------------------------------------- 5. an edited Basis

@pytest.mark.parametrize("operator", ["bake_filter", "rebuild_detail"])
def test_a_basis_edited_after_decompose_is_refused_in_the_session(operator):
    obj = sphere()
    h.decompose(obj)
    basis = h.key(obj.data, "Basis")
    basis[:, 2] += 0.3 * (basis[:, 0] > 0)
    h.set_key(obj.data, "Basis", basis)
    h.assert_refused(obj, operator, "its Basis changed since it was decomposed")


# ---------------------------------------------------------------- 6. the active vertex group

@pytest.mark.parametrize("operator", ["bake_filter", "rebuild_detail"])
def test_the_artists_active_vertex_group_stays_active(operator):
    obj = sphere()
    h.decompose(obj)
    assert bpy.ops.pointscale.paint_band_mask(band=1, enter_paint=False) == {"FINISHED"}
    obj.vertex_groups.new(name="Mine")
    obj.vertex_groups.active_index = obj.vertex_groups["Band 1 mask"].index
    for _ in range(2):  # the second press replaces the Folds group it made
        assert getattr(bpy.ops.pointscale, operator)() == {"FINISHED"}
        assert obj.vertex_groups.get("Folds") is not None
        assert obj.vertex_groups.active.name == "Band 1 mask"


# ---------------------------------------------------------------- 7. the mode

@pytest.mark.parametrize("mode", ["EDIT", "WEIGHT_PAINT", "SCULPT"])
@pytest.mark.parametrize("operator, kwargs", [("reset_bands", {}), ("show_details", {"band": 0})])
def test_reset_gains_and_show_details_return_to_the_artists_mode(operator, kwargs, mode):
    obj = sphere()
    h.decompose(obj)
    bpy.ops.object.mode_set(mode=mode)
    assert getattr(bpy.ops.pointscale, operator)(**kwargs) == {"FINISHED"}
    assert obj.mode == mode
    bpy.ops.object.mode_set(mode="OBJECT")


# ---------------------------------------------------------------- 8. colours after a second Decompose

def test_decompose_again_gives_back_the_colours_show_details_replaced():
    obj = sphere()
    colors = obj.data.color_attributes
    colors.new("Col", "FLOAT_COLOR", "POINT")
    colors.new("Dirt", "BYTE_COLOR", "CORNER")
    colors.active_color = colors["Col"]
    h.decompose(obj)
    assert bpy.ops.pointscale.show_details(band=0) == {"FINISHED"}
    h.decompose(obj)
    assert colors.active_color is not None and colors.active_color.name == "Col"
    assert colors.get("ms_detail_color") is None
    # What Show Details replaces now is what Clear gives back, not what it replaced before.
    colors.active_color = colors["Dirt"]
    assert bpy.ops.pointscale.show_details(band=0) == {"FINISHED"}
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert colors.active_color.name == "Dirt"


# ---------------------------------------------------------------- 9. parts too small, in the panel's terms

ENGINE_REFUSAL = ("every connected part is too small to decompose: the largest has 441 points, and levels=2 needs "
                  "at least 32 (levels=3 needs 128). Decompose without faces and edges to treat the parts as one surface")


def test_every_part_too_small_names_neighbours_and_keep_parts_apart(monkeypatch):
    compute = sys.modules[h.ADDON_NAME + ".compute"]

    def refuse(*_args, **_kwargs):
        raise ValueError(ENGINE_REFUSAL)

    monkeypatch.setattr(compute, "decompose", refuse)
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    obj.data.multiscale.neighbors = 256
    with pytest.raises(RuntimeError) as refused:
        bpy.ops.pointscale.decompose()
    message = str(refused.value)
    assert "Neighbours 256" in message and "Keep Parts Apart" in message and "441" in message
    assert "faces and edges" not in message and "needs at least 32" not in message
    logic = sys.modules[h.ADDON_NAME + ".logic"]
    assert logic.parts_message("flat input", 24, 3) == "flat input"


def test_clear_still_removes_every_attribute_the_add_on_wrote(monkeypatch):
    # Removal by exact names must still find all of them: the earlier format's model columns
    # (written without a recipe) and the level normals.
    import pointscale as ps
    from pointscale_addon import compute, preferences, writeback

    monkeypatch.setattr(preferences._Defaults, "normal_attributes", True)
    obj = sphere()
    mesh = obj.data
    before = {a.name for a in mesh.attributes}
    points = h.vertices(mesh)
    writeback.apply_layout(obj, compute.decompose(ps, points, levels=3), basis=points)
    assert mesh["pointscale"]["format"] == 1 and len([a for a in mesh.attributes if a.name.startswith(".ps.")]) > 10
    assert mesh.attributes.get("ms_normal_1") is not None
    h.decompose(obj, levels=3)  # format 2 over format 1: none of the model's columns stay
    assert not [a.name for a in mesh.attributes if a.name.startswith(".ps.") and a.name != ".ps.order"]
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert {a.name for a in mesh.attributes} == before
