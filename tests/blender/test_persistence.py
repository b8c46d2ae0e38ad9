"""Checks 7 and 8: save and reload; undo after a decompose."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def test_save_reload_keeps_everything(tmp_path):
    pts = h.noisy_sphere(4000)
    obj = h.mesh_object(pts, name="Saved")
    h.decompose(obj, levels=4, decimation=0.3, kernel=1.5)
    me = obj.data
    me.multiscale.bands[2].gain = 1.75
    me.multiscale.scale = 2.5
    before = h.snapshot(obj)
    path = str(tmp_path / "saved.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert "Saved" not in bpy.data.objects
    bpy.ops.wm.open_mainfile(filepath=path)

    obj = bpy.data.objects["Saved"]
    me = obj.data
    assert h.same(before, h.snapshot(obj))  # keys, values, attributes (hidden ones too), groups
    s = me.multiscale
    assert (s.levels, s.n_bands, s.n_vertices) == (4, 3, 4000)
    assert s.decimation == pytest.approx(0.3) and s.kernel == pytest.approx(1.5)
    assert s.scale == pytest.approx(2.5)
    assert [round(b.gain, 4) for b in s.bands] == [1.0, 1.0, 1.75]

    # Rebuild detail works from the reloaded data: an unedited base gives the original back.
    bpy.context.view_layer.objects.active = obj
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert np.abs(h.key(me, "Multiscale Edit") - h.key(me, "Basis")).max() < 1e-5
    # ... and an edited one carries the detail (the result differs from the plain base).
    lifted = h.key(me, "Level 0") + np.array([0, 0, 0.1], np.float32) * (h.key(me, "Level 0")[:, :1] > 0)
    h.set_key(me, "Level 0", lifted)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    moved = np.linalg.norm(h.key(me, "Multiscale Edit") - h.key(me, "Basis"), axis=1)
    right = h.key(me, "Level 0")[:, 0] > 0.2
    assert np.median(moved[right]) == pytest.approx(0.1, rel=0.2)


def test_undo_after_decompose():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Undo")
    before = h.snapshot(obj)
    # Headless, no window manager pushes undo steps around operators, so push them as it would:
    # one before the operator and one after it (bpy 4.5 and 5.2 both undo then).
    bpy.ops.ed.undo_push(message="before")
    h.decompose(obj)
    bpy.ops.ed.undo_push(message="Decompose")
    decomposed = h.snapshot(bpy.data.objects["Undo"])
    assert "key:Level 0" in decomposed

    assert bpy.ops.ed.undo() == {"FINISHED"}
    obj = bpy.data.objects["Undo"]  # undo rebuilds the data: the old reference is gone
    assert obj.data.shape_keys is None and h.same(before, h.snapshot(obj))
    assert bpy.ops.ed.redo() == {"FINISHED"}
    assert h.same(decomposed, h.snapshot(bpy.data.objects["Undo"]))


def test_every_operator_registers_undo(addon):
    # In the UI, these flags are what push the undo steps that the test above pushes by hand.
    from pointscale_addon.operators import CLASSES

    assert len(CLASSES) >= 9
    for cls in CLASSES:
        assert {"REGISTER", "UNDO"} <= set(cls.bl_options), cls.bl_idname
