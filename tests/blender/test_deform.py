"""Check 5: edit Level 0 (lift a region), Rebuild detail: the Fig. 5 handles stay normal to the new base."""

import importlib

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def bump(xy, height=0.8, width=1.0):
    return height * np.exp(-(xy**2).sum(axis=1) / width**2)




def test_rebuild_detail_keeps_handles_normal_to_the_edited_base():
    import pointscale as ps

    points, handle, centres = ps.shapes.handles_plane(spacing=0.04)
    obj = h.mesh_object(points, name="Handles")
    h.decompose(obj, levels=4, decimation=0.2, kernel=2.0)
    me = obj.data
    original = h.key(me, "Basis").astype(np.float64)

    # Unedited base: Rebuild returns the original, from the engine's exact base (the key holds
    # it in single precision), so that the stored level-0 normals are used.
    compute = importlib.import_module(h.ADDON_NAME + ".compute")
    writeback = importlib.import_module(h.ADDON_NAME + ".writeback")
    dec = writeback.decomposition(me, ps)
    assert compute.edited_base(dec, h.key(me, "Level 0")) is None
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert np.abs(h.key(me, "Multiscale Edit") - original).max() < 1e-5

    # "Edit mode": lift a circular region of Level 0, as a user would with proportional editing.
    assert bpy.ops.pointscale.edit_base(mode="OBJECT") == {"FINISHED"}
    assert obj.active_shape_key.name == "Level 0"
    base = h.key(me, "Level 0").astype(np.float64)
    lifted = base.copy()
    lifted[:, 2] += bump(base[:, :2])
    h.set_key(me, "Level 0", lifted)

    assert compute.edited_base(dec, h.key(me, "Level 0")) is not None
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    result = h.key(me, "Multiscale Edit").astype(np.float64)
    multiscale = ps.shapes.handle_angles(result, points, handle, centres, lifted)
    assert multiscale.max() < 3.0, multiscale

    # The same lift applied to the original points (single scale) tilts the flank handles:
    single = original.copy()
    single[:, 2] += bump(original[:, :2])
    assert ps.shapes.handle_angles(single, points, handle, centres, single).max() > 10.0

    # What Blender shows is the rebuilt result (Multiscale Edit at 1, levels off).
    assert me.shape_keys.key_blocks["Multiscale Edit"].value == 1.0
    assert np.abs(h.evaluated(obj) - result).max() < 1e-5
    # The Basis is still the original.
    assert np.array_equal(h.key(me, "Basis"), original.astype(np.float32))


def test_edit_mode_workflow_writes_level0_and_rebuilds():
    """The artist's path: Edit Base (Edit mode on 'Level 0'), move vertices, Rebuild Detail."""
    import bmesh

    # 8000 points leave 125 support points at level 0; far coarser bases get distorted (see the
    # warning in pointscale.decompose), and an edit then reaches far across them.
    obj = h.mesh_object(h.noisy_sphere(8000), name="EditMe")
    h.decompose(obj, levels=4)
    me = obj.data
    level0 = h.key(me, "Level 0").copy()
    assert bpy.ops.pointscale.edit_base(mode="EDIT") == {"FINISHED"}
    assert obj.mode == "EDIT" and obj.active_shape_key.name == "Level 0"
    bm = bmesh.from_edit_mesh(me)
    top = []
    for v in bm.verts:
        if v.co.z > 0.5:
            v.co.z += 0.3
            top.append(v.index)
    bmesh.update_edit_mesh(me)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert obj.mode == "EDIT"  # back where the artist was, to go on editing the base
    bpy.ops.object.mode_set(mode="OBJECT")
    top = np.array(top)
    edited = h.key(me, "Level 0")
    assert np.allclose(edited[top, 2], level0[top, 2] + 0.3, atol=1e-5)  # the edit went to Level 0
    result = h.key(me, "Multiscale Edit")
    basis = h.key(me, "Basis")
    lift = result[top, 2] - basis[top, 2]
    assert np.median(lift) == pytest.approx(0.3, abs=0.03)
    rest = np.setdiff1d(np.arange(len(basis)), top)
    far = rest[basis[rest, 2] < -0.5]
    moved = np.linalg.norm(result[far] - basis[far], axis=1)
    assert np.median(moved) < 0.01 * 0.3 and moved.max() < 0.05 * 0.3  # far from the edit, little moves


def test_bake_filter_says_how_many_points_fold_and_prevent_folds_removes_them():
    keys = importlib.import_module(h.ADDON_NAME + ".keys")
    mesh_io = importlib.import_module(h.ADDON_NAME + ".mesh_io")
    import pointscale as ps

    obj = h.mesh_object(ps.shapes.bumpy_sphere(6000), name="Folding")
    h.decompose(obj, levels=4)
    me = obj.data
    bands = [keys.band_name(l) for l in range(me.multiscale.n_bands)]

    def folded():
        (weights,) = mesh_io.read_group_weights(obj, [keys.FOLDS], len(me.vertices))
        return int((weights > 0).sum())

    for name in bands:  # every band 5 times over: the bumps fold (54 points in the engine alone)
        me.shape_keys.key_blocks[name].value = keys.BAND_MAX
    me.multiscale.prevent_folds = False
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert folded() > 20
    for name in bands:
        me.shape_keys.key_blocks[name].value = keys.BAND_MAX
    me.multiscale.prevent_folds = True
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert folded() == 0
    # Nothing folds again: the emptied group is kept as it is (no work at a million vertices),
    # and folds that come back are marked in it.
    group = obj.vertex_groups[keys.FOLDS]
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert obj.vertex_groups[keys.FOLDS] == group and folded() == 0
    for name in bands:
        me.shape_keys.key_blocks[name].value = keys.BAND_MAX
    me.multiscale.prevent_folds = False
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert folded() > 20
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert keys.FOLDS not in obj.vertex_groups and keys.FOLDS_MARKED not in me.keys()


def test_rebuild_and_bake_share_one_kept_reconstructor():
    """Rebuild Detail and Bake Filter run on the mesh's pointscale.Reconstructor, kept between
    calls, and give what reconstruct() gives."""
    import pointscale as ps

    writeback = importlib.import_module(h.ADDON_NAME + ".writeback")
    compute = importlib.import_module(h.ADDON_NAME + ".compute")
    obj = h.mesh_object(h.noisy_sphere(6000), name="KeptSolver")
    h.decompose(obj, levels=3)
    me = obj.data
    base = h.key(me, "Level 0").astype(np.float64)
    lifted = base.copy()
    lifted[:, 2] += bump(base[:, :2], height=0.2, width=0.5)
    h.set_key(me, "Level 0", lifted)

    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    solver = writeback.reconstructor(me, ps)
    dec = writeback.decomposition(me, ps)
    expected = ps.reconstruct(dec, base=compute.edited_base(dec, h.key(me, "Level 0")))
    assert np.array_equal(h.key(me, "Multiscale Edit"), expected.astype(np.float32))

    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert writeback.reconstructor(me, ps) is solver
    assert np.array_equal(h.key(me, "Multiscale Filter"), expected.astype(np.float32))

    # Decomposed again: the old engine object's solver is let go at once (it holds a copy of the
    # model), and the next press makes one for the new object.
    h.decompose(obj, levels=3)
    assert not [key for key in writeback._solvers if key[0] == me.session_uid]
    assert writeback.reconstructor(me, ps) is not solver

    writeback.forget_all()  # a new file: the engine object and its solver are made again
    assert not writeback._solvers


def test_a_mirrored_level_0_rebuilds_the_mirrored_model():
    """A scale of -1 on Level 0 (x to -x): the detail is mirrored with it and stays outside.
    Before, the turns (rotations only) read the mirrored base as turned over and put most of
    the detail on the inside."""
    obj = h.mesh_object(h.noisy_sphere(8000), name="Mirrored")
    h.decompose(obj, levels=4)
    me = obj.data
    original = h.key(me, "Basis").astype(np.float64)
    assert bpy.ops.pointscale.edit_base(mode="OBJECT") == {"FINISHED"}
    base = h.key(me, "Level 0").astype(np.float64)
    h.set_key(me, "Level 0", base * np.array([-1.0, 1.0, 1.0]))
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    result = h.key(me, "Multiscale Edit").astype(np.float64)
    size = np.ptp(original, axis=0).max()
    # The keys are single precision: measured within rounding of float32 coordinates.
    assert np.abs(result - original * np.array([-1.0, 1.0, 1.0])).max() < 1e-5 * size
