"""The artist's own data survives: their shape keys, earlier results, the active key and the
vertex order are respected, and a damaged layout is refused with a message, not a traceback."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def test_own_keys_with_layout_like_names_survive_decompose_and_clear():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Own")
    obj.shape_key_add(name="Basis")
    mine = {"Level 5": 0.1, "Band 7": 0.2}
    for name, dz in mine.items():
        obj.shape_key_add(name=name)
        h.set_key(obj.data, name, h.key(obj.data, "Basis") + [0, 0, dz])
    h.decompose(obj, levels=4)
    h.decompose(obj, levels=3)  # fewer bands: the stale Level 2 / Band 2 go, the artist's stay
    kbs = obj.data.shape_keys.key_blocks
    assert "Level 2" not in kbs and "Band 2" not in kbs
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    kbs = obj.data.shape_keys.key_blocks
    assert "Level 0" not in kbs and "Band 0" not in kbs
    for name, dz in mine.items():
        assert np.allclose(h.key(obj.data, name) - h.key(obj.data, "Basis"), [0, 0, dz], atol=1e-6), name


def test_a_key_of_the_artist_with_a_layout_name_is_refused():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Clash")
    obj.shape_key_add(name="Basis")
    obj.shape_key_add(name="Level 0")
    h.assert_refused(obj, "decompose", "'Level 0' of its own")


def test_absolute_shape_keys_are_refused_not_switched():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Absolute")
    obj.shape_key_add(name="Basis")
    obj.shape_key_add(name="Key 1")
    obj.data.shape_keys.use_relative = False
    before = h.snapshot(obj)
    with pytest.raises(RuntimeError, match="absolute"):
        bpy.ops.pointscale.decompose()
    assert obj.data.shape_keys.use_relative is False
    assert h.same(before, h.snapshot(obj))


def test_decompose_again_keeps_the_earlier_result_and_the_active_key():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Again")
    h.decompose(obj)
    me = obj.data
    h.set_key(me, "Level 0", h.key(me, "Level 0") * 1.1)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    edit = h.key(me, "Multiscale Edit").copy()
    obj.active_shape_key_index = me.shape_keys.key_blocks.find("Band 1")
    h.decompose(obj, levels=3)
    assert np.array_equal(h.key(me, "Multiscale Edit (previous)"), edit)
    assert "Multiscale Edit" not in me.shape_keys.key_blocks
    assert obj.active_shape_key.name == "Band 1"
    # ... and one more decompose replaces that "(previous)" rather than piling up copies
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    h.decompose(obj, levels=3)
    assert sum(kb.name.startswith("Multiscale Edit") for kb in me.shape_keys.key_blocks) == 1


def test_a_removed_layout_key_is_refused_with_a_message():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Removed")
    h.decompose(obj)
    obj.shape_key_remove(obj.data.shape_keys.key_blocks["Level 0"])
    before = h.snapshot(obj)
    for op, kw in [("rebuild_detail", {}), ("bake_filter", {}), ("edit_base", {"mode": "OBJECT"}),
                   ("paint_band_mask", {"band": 0, "enter_paint": False})]:
        assert not getattr(bpy.ops.pointscale, op).poll(), op
        with pytest.raises(RuntimeError, match="no shape key 'Level 0'"):
            getattr(bpy.ops.pointscale, op)(**kw)
        assert h.same(before, h.snapshot(obj)), op
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}  # the way out
    assert bpy.ops.pointscale.rebuild_detail.poll()


def test_reordered_vertices_are_refused():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Sorted")
    h.decompose(obj)
    with h.edited_bmesh(obj) as bm:
        order = np.random.default_rng(0).permutation(len(bm.verts))
        for v, i in zip(bm.verts, order):
            v.index = int(i)
        bm.verts.sort()
    assert len(obj.data.vertices) == 4000
    h.assert_refused(obj, "rebuild_detail", "reordered")


def test_show_details_without_its_attribute_reports():
    obj = h.mesh_object(h.noisy_sphere(4000), name="NoAttr")
    h.decompose(obj)
    obj.data.attributes.remove(obj.data.attributes["ms_detail_0"])
    with pytest.raises(RuntimeError, match="ms_detail_0 was removed"):
        bpy.ops.pointscale.show_details(band=0)


def test_a_refused_decompose_leaves_edit_mode_alone():
    obj = h.mesh_object([(0, 0, 0), (1, 0, 0), (0, 1, 0)], faces=[(0, 1, 2)], name="Tiny")
    bpy.ops.object.mode_set(mode="EDIT")
    with pytest.raises(RuntimeError, match="3 vertices"):
        bpy.ops.pointscale.decompose()
    assert obj.mode == "EDIT"
    bpy.ops.object.mode_set(mode="OBJECT")


def test_nothing_else_runs_on_an_object_while_it_is_being_decomposed(addon):
    import importlib

    state = importlib.import_module(h.ADDON_NAME + ".state")
    obj = h.mesh_object(h.noisy_sphere(4000), name="Busy")
    h.decompose(obj)
    state.running.add(obj.session_uid)  # what the modal Decompose does while its worker runs
    try:
        for op in ("decompose", "rebuild_detail", "bake_filter", "edit_base", "clear", "reset_bands"):
            assert not getattr(bpy.ops.pointscale, op).poll(), op
        with pytest.raises(RuntimeError, match="being decomposed"):
            bpy.ops.pointscale.rebuild_detail()
    finally:
        state.running.discard(obj.session_uid)
    assert bpy.ops.pointscale.rebuild_detail.poll()


def test_a_morph_of_a_decomposed_object_carries_none_of_its_decomposition():
    import pointscale as ps

    a = ps.shapes.bumpy_sphere(3000, coarse=0.05, fine=0.0)
    b = ps.shapes.bumpy_sphere(2200, coarse=0.08, coarse_frequency=5.0, fine=0.0, seed=1)
    A = h.mesh_object(a, name="A")
    h.decompose(A, levels=3)
    for band in (0, 1):  # masks are made when painted: make them, so that the morph could copy them
        assert bpy.ops.pointscale.paint_band_mask(band=band, enter_paint=False) == {"FINISHED"}
    B = h.mesh_object(b, name="B")
    bpy.context.view_layer.objects.active = A
    A.data.multiscale.morph_target = B
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    M = bpy.context.active_object
    assert M is not A
    assert not [g.name for g in M.vertex_groups if g.name.endswith(" mask")]
    assert "pointscale" not in M.data.keys() and "pointscale_keys" not in M.data.keys()
    assert M.data.multiscale.morph_target is None and M.data.multiscale.n_bands == 0
    assert [g.name for g in A.vertex_groups] == ["Band 0 mask", "Band 1 mask"]  # A keeps its own
