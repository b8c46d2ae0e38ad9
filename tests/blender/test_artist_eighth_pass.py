"""An eighth artist's pass (trial on Blender 5.2, 2026-12-07): a sculpt of 'Multiscale Edit'
was written over by the next Rebuild Detail, unsaid; Bake Filter called an edited filter
"switched off"; Rebuild Detail switched a baked filter off, and left live band gains on top of
the rebuilt detail, without a word."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _decomposed():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Sculpted")
    h.decompose(obj, levels=4)
    return obj


def _lift_level0(obj, amount=0.05):
    me = obj.data
    level0 = h.key(me, "Level 0").astype(np.float64)
    level0[:, 2] += amount * np.exp(-((level0[:, :2] - [0.0, 0.0]) ** 2).sum(axis=1) / 0.2)
    assert bpy.ops.pointscale.edit_base(mode="OBJECT") == {"FINISHED"}
    h.set_key(me, "Level 0", level0)


def test_a_sculpted_result_is_kept_by_the_next_rebuild(capfd):
    obj = _decomposed()
    me = obj.data
    _lift_level0(obj)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}  # unchanged: nothing to keep
    assert me.shape_keys.key_blocks.get("Multiscale Edit (previous)") is None
    sculpted = h.key(me, "Multiscale Edit").copy()
    sculpted[:50] += 0.02  # the artist's tweak of the result
    h.set_key(me, "Multiscale Edit", sculpted)
    _lift_level0(obj, 0.03)
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    out = capfd.readouterr().out
    kept = me.shape_keys.key_blocks.get("Multiscale Edit (previous)")
    assert kept is not None and kept.value == 0.0, out
    assert np.array_equal(h.key(me, "Multiscale Edit (previous)"), sculpted)
    assert "your edits of 'Multiscale Edit'" in out, out
    assert not np.array_equal(h.key(me, "Multiscale Edit"), sculpted)


def test_an_edited_filter_is_said_to_be_edited_not_switched_off(capfd):
    obj = _decomposed()
    me = obj.data
    me.multiscale.bands[2].gain = 2.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    tweaked = h.key(me, "Multiscale Filter").copy()
    tweaked[:50] += 0.02
    h.set_key(me, "Multiscale Filter", tweaked)
    me.multiscale.bands[0].gain = 1.5
    capfd.readouterr()
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "your edits of 'Multiscale Filter' since it was baked are kept" in out, out
    assert "switched off, is kept" not in out, out
    assert np.array_equal(h.key(me, "Multiscale Filter (previous)"), tweaked)


def test_rebuild_says_what_it_leaves_off(capfd):
    obj = _decomposed()
    me = obj.data
    me.multiscale.bands[2].gain = 0.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    _lift_level0(obj)
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "'Multiscale Filter' is switched off" in out, out
    assert "are not in the rebuilt detail" not in out  # the bake set the sliders back to gain 1
    me.multiscale.bands[1].gain = 3.0
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "the band gains (1.00, 3.00, 1.00) are not in the rebuilt detail" in out, out
    assert "is switched off" not in out  # the filter was off already


def test_decompose_again_says_the_gains_start_over_and_a_mask_covers_another_band(capfd):
    obj = _decomposed()  # 4 levels: 3 bands
    me = obj.data
    me.multiscale.bands[0].gain = 0.5
    me.multiscale.bands[2].gain = 3.0
    assert bpy.ops.pointscale.paint_band_mask(band=2, enter_paint=False) == {"FINISHED"}
    group = obj.vertex_groups["Band 2 mask"]
    group.add(list(range(100)), 0.5, "REPLACE")
    capfd.readouterr()
    h.decompose(obj, levels=4, kernel=2.0)  # the same band count
    out = capfd.readouterr().out
    assert "the band gains (0.50, 1.00, 3.00) were the earlier bands'" in out, out
    assert "masks the band of the same number" not in out, out
    assert all(b.gain == 1.0 for b in me.multiscale.bands)
    h.decompose(obj, levels=5)  # 4 bands: Band 2 is not the finest now
    out = capfd.readouterr().out
    assert "'Band 2 mask' masks the band of the same number among 4 bands, painted for one among 3" in out, out
    assert "band gains" not in out  # they were at 1


def test_a_second_sculpt_is_said_to_replace_the_first_and_stays_active(capfd):
    obj = _decomposed()
    me = obj.data
    _lift_level0(obj)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    for round_ in range(2):
        sculpted = h.key(me, "Multiscale Edit").copy()
        sculpted[:50] += 0.02
        h.set_key(me, "Multiscale Edit", sculpted)
        obj.active_shape_key_index = me.shape_keys.key_blocks.find("Multiscale Edit")
        capfd.readouterr()
        assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
        out = capfd.readouterr().out
        assert ("replacing the one kept before" in out) == (round_ == 1), out
        assert obj.active_shape_key.name == "Multiscale Edit"  # the new result, not the kept sculpt
        assert np.array_equal(h.key(me, "Multiscale Edit (previous)"), sculpted)


def test_a_file_from_before_result_fingerprints_keeps_its_kept_sculpt(capfd):
    """A .blend saved before the add-on kept fingerprints of its results has none: its first
    Rebuild Detail must not call the result edited, nor put it over the '(previous)' key, which
    may hold an earlier sculpt (a reviewer found both)."""
    obj = _decomposed()
    me = obj.data
    _lift_level0(obj)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    sculpted = h.key(me, "Multiscale Edit").copy()
    sculpted[:50] += 0.02
    h.set_key(me, "Multiscale Edit", sculpted)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}  # kept as '(previous)'
    del me["pointscale_results"]  # as an older file has it
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "your edits" not in capfd.readouterr().out
    assert np.array_equal(h.key(me, "Multiscale Edit (previous)"), sculpted)
