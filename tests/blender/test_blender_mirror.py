"""Mirrored halves in Blender (issue 17, requirement 4): Decompose uses the mesh's Mirror
modifier, so that at any Scale and gain the seam vertices stay on the mirror plane and the
modifier keeps merging them: the evaluated mesh keeps its vertex count, the model does not tear."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def bumpy_half_sphere(plane_x=0.0, axes="x", segments=96, rings=48):
    """The x >= plane_x half (y >= 0 too for axes "xy") of a bumpy UV sphere centred on the
    plane, and its seam (the vertices on the x plane). The bumps are not symmetric within the half."""
    import pointscale as ps
    v, f = ps.meshes.uv_sphere(1.0, segments, rings)
    keep = np.ones(len(v), bool)
    for axis in ("xyz".index(a) for a in axes):
        v[np.abs(v[:, axis]) < 1e-12, axis] = 0.0  # cos(pi / 2) is 6e-17
        keep &= v[:, axis] >= 0.0
    v = ps.meshes.bumpy(v, 0.08, 5.0) + 0.01 * np.sin(9.0 * v[:, [1, 2, 0]] + 0.4).sum(axis=1, keepdims=True) * v
    renumber = np.cumsum(keep) - 1
    faces = renumber[f[keep[f].all(axis=1)]]
    half = v[keep] + [plane_x, 0.0, 0.0]
    return half, faces, v[keep, 0] == 0.0


def mirrored_object(plane_x=0.0, **modifier_settings):
    points, faces, seam = bumpy_half_sphere(plane_x)
    obj = h.mesh_object(points, faces, name="Half")
    modifier = obj.modifiers.new("Mirror", "MIRROR")  # X, merge within 0.001 by default
    for name, value in modifier_settings.items():
        setattr(modifier, name, value)
    return obj, points, seam


def shown_states(obj):
    """The evaluated mesh at Scale 0, at Scale 1.5, and at full Scale with a gain of 2 on every band."""
    s = obj.data.multiscale
    s.scale = 0.0
    yield "scale 0", h.evaluated(obj)
    s.scale = 1.5
    yield "scale 1.5", h.evaluated(obj)
    s.scale = float(s.n_bands)
    for band in s.bands:
        band.gain = 2.0
    yield "gains 2", h.evaluated(obj)


def seam_offset(obj, shown, seam, plane_x):
    """The seam vertices' largest distance from the plane, in the half's own vertices of the
    evaluated mesh (the Mirror modifier keeps them first), as a fraction of the diagonal."""
    half = shown[: len(seam)]
    return float(np.abs(half[seam, 0] - plane_x).max()) / h.diagonal(shown)


def test_the_mirror_modifier_keeps_the_seam_merged(capfd):
    obj, points, seam = mirrored_object()
    assert obj.data.multiscale.use_mirror_modifier  # on by default
    merged = len(h.evaluated(obj))
    assert merged == 2 * len(points) - seam.sum()
    h.decompose(obj, levels=4)
    assert "Mirror modifier" in capfd.readouterr().out  # the report says it was used
    for state, shown in shown_states(obj):
        assert len(shown) == merged, state
        assert seam_offset(obj, shown, seam, 0.0) <= 1e-6, state  # asked 1e-6; measured 0
    # In the keys themselves, not only after the modifier's merge: Level 0 holds the seam on the plane.
    assert np.abs(h.key(obj.data, "Level 0")[seam, 0]).max() == 0.0


def test_without_the_mirror_modifier_option_the_model_tears():
    obj, points, seam = mirrored_object()
    merged = len(h.evaluated(obj))
    obj.data.multiscale.use_mirror_modifier = False
    h.decompose(obj, levels=4)
    torn = {state: len(shown) - merged for state, shown in shown_states(obj)}
    # Measured: all 96 seam vertices come apart at Scale 0 and with the gains, 63 at Scale 1.5.
    assert torn["scale 0"] >= 0.9 * seam.sum() and torn["gains 2"] >= 0.9 * seam.sum(), torn
    assert torn["scale 1.5"] >= 0.5 * seam.sum(), torn
    drift = np.abs(h.key(obj.data, "Level 0")[seam, 0]).max() / h.diagonal(points)
    assert drift > 1e-2, drift  # measured 1.7e-2


def test_a_mirror_object_off_the_origin():
    # The object moved, and the mirror object 0.25 to its right: the plane is x = 0.25 in the mesh.
    empty = bpy.data.objects.new("Mirror Centre", None)
    bpy.context.scene.collection.objects.link(empty)
    empty.location = (1.25, 2.0, -3.0)
    empty.scale = (2.0, 1.0, 0.5)  # scale along the axes moves no plane
    obj, points, seam = mirrored_object(0.25, mirror_object=empty)
    obj.location = (1.0, 0.5, 0.0)
    merged = len(h.evaluated(obj))
    assert merged == 2 * len(points) - seam.sum()
    h.decompose(obj, levels=4)
    for state, shown in shown_states(obj):
        assert len(shown) == merged, state
        assert seam_offset(obj, shown, seam, 0.25) <= 1e-6, state
    assert np.abs(h.key(obj.data, "Level 0")[seam, 0] - 0.25).max() <= 1e-7  # 0.25 in single precision


def test_a_rotated_mirror_object_is_refused_clearly():
    empty = bpy.data.objects.new("Mirror Centre", None)
    bpy.context.scene.collection.objects.link(empty)
    empty.rotation_euler = (0.0, 0.0, 0.3)
    obj, _, _ = mirrored_object(mirror_object=empty)
    h.assert_refused(obj, "decompose", "mirror object is rotated against the mesh")


def test_two_axes_and_merge_off():
    points, faces, _ = bumpy_half_sphere(axes="xy", segments=128, rings=64)
    obj = h.mesh_object(points, faces, name="Quarter")
    modifier = obj.modifiers.new("Mirror", "MIRROR")
    modifier.use_axis = (True, True, False)
    modifier.use_mirror_merge = False  # the seam is then the vertices on the planes up to rounding
    before = len(h.evaluated(obj))
    h.decompose(obj, levels=3)
    assert_seams_on_the_x_and_y_planes(obj, points)
    assert len(h.evaluated(obj)) == before


def assert_seams_on_the_x_and_y_planes(obj, points):
    """Level 0 holds the vertices on x = 0 and on y = 0 exactly on their planes."""
    level0 = h.key(obj.data, "Level 0")
    for axis in (0, 1):
        on = points[:, axis] == 0.0
        assert on.sum() > 50
        assert np.abs(level0[on, axis]).max() == 0.0, axis


def test_an_edited_base_and_a_reloaded_decomposition_keep_the_seam():
    import importlib
    writeback = importlib.import_module(h.ADDON_NAME + ".writeback")
    obj, points, seam = mirrored_object()
    merged = len(h.evaluated(obj))
    h.decompose(obj, levels=4)
    writeback.forget_all()  # the engine object rebuilt from the mesh's attributes
    assert bpy.ops.pointscale.edit_base(mode="OBJECT") == {"FINISHED"}
    lifted = h.key(obj.data, "Level 0").astype(np.float64)
    lifted += 0.2 * np.exp(-np.sum((lifted - [0.0, 0.0, 1.0]) ** 2, axis=1) / 0.3)[:, None] * [0.2, 0.0, 1.0]
    h.set_key(obj.data, "Level 0", lifted)  # the lift also pushes the seam off the plane
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    edit = h.key(obj.data, "Multiscale Edit")
    assert np.abs(edit[seam, 0]).max() == 0.0
    assert edit[:, 2].max() > points[:, 2].max() + 0.1
    obj.data.multiscale.bands[0].gain = 2.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert np.abs(h.key(obj.data, "Multiscale Filter")[seam, 0]).max() == 0.0
    assert len(h.evaluated(obj)) == merged


def test_mirror_object_planes_in_the_mesh_space():
    import importlib
    mm = importlib.import_module(h.ADDON_NAME + ".mirror_modifier")
    quarter_turn = np.array([[0.0, 1.0, 0.0, -0.5], [-1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0, 0, 0, 1]])
    planes, problem = mm.mirror_planes((True, False, False), True, False, 0.002, 1.0, quarter_turn)
    # The mirror object's X plane is the mesh's y = 0.5 after a quarter turn.
    assert problem is None and planes.axes == "y" and planes.origin[1] == 0.5 and planes.seam == 0.001
    planes, problem = mm.mirror_planes((True, False, True), False, True, 0.002, 1.0)
    assert planes.axes == "xz" and planes.seam == 0.002  # clipping alone holds the vertices within it
    sheared = np.eye(4)
    sheared[1, 0] = 0.3
    planes, problem = mm.mirror_planes((True, False, False), True, False, 0.002, 1.0, sheared)
    assert planes is None and "not along one of the mesh's axes" in problem
    assert mm.mirror_planes((False, False, False), True, False, 0.002, 1.0) == (None, None)


def test_stacked_mirror_modifiers_give_every_plane():
    """An X and a Y Mirror modifier stacked (how artists often model a quarter): both planes are
    used. Reading only the first, a quarter torus 2.7 wide had its Y seam 0.23 off the plane at
    level 0 and 64 more vertices after the merge (QA, 2026-12-06)."""
    points, faces, _ = bumpy_half_sphere(axes="xy", segments=128, rings=64)
    obj = h.mesh_object(points, faces, name="Quarter, two modifiers")
    for name, axes in (("Mirror X", (True, False, False)), ("Mirror Y", (False, True, False))):
        modifier = obj.modifiers.new(name, "MIRROR")
        modifier.use_axis = axes
    merged = len(h.evaluated(obj))
    h.decompose(obj, levels=3)
    assert_seams_on_the_x_and_y_planes(obj, points)
    for state, shown in shown_states(obj):
        assert len(shown) == merged, state


def test_two_mirror_modifiers_on_one_axis_at_different_places_are_refused():
    obj, points, seam = mirrored_object()
    second = obj.modifiers.new("Mirror 2", "MIRROR")
    empty = bpy.data.objects.new("Elsewhere", None)
    bpy.context.collection.objects.link(empty)
    empty.location = (0.5, 0.0, 0.0)
    second.mirror_object = empty
    bpy.context.view_layer.objects.active = obj
    h.assert_refused(obj, "decompose", "two Mirror modifiers mirror along X")


def test_bisect_keeps_the_merged_vertex_count():
    """With Bisect on, Blender also joins a vertex within the bisect distance (0.001) of the plane
    with its reflection. The seam was half the merge distance, so a vertex a level brought near
    the plane was kept 1.01 seams (0.000505) off it, within the bisect distance: a reviewer's half
    head lost 4 vertices at Scale 0. The seam is now at least the bisect distance."""
    obj, points, seam = mirrored_object(use_bisect_axis=(True, False, False))
    merged = len(h.evaluated(obj))
    assert merged == 2 * len(points) - seam.sum()
    h.decompose(obj, levels=4)
    level0 = h.key(obj.data, "Level 0")
    near = np.abs(level0[~seam, 0]) < obj.modifiers["Mirror"].bisect_threshold
    assert not near.any(), np.abs(level0[~seam, 0]).min()
    for state, shown in shown_states(obj):
        assert len(shown) == merged, state


def test_a_whole_mesh_under_a_mirror_modifier_is_refused_in_blender_words():
    """A whole sphere (not a half) under a Mirror modifier: the engine's refusal offered "a seam
    of at least ...", a setting Blender does not have; it now names the modifier's Merge distance
    (the seam is half of it)."""
    import pointscale as ps
    v, f = ps.meshes.uv_sphere(1.0, 32, 16)
    obj = h.mesh_object(v, f, name="Whole")
    obj.modifiers.new("Mirror", "MIRROR")
    h.assert_refused(obj, "decompose", "Merge distance to at least")


def test_a_mirror_modifier_changed_after_decompose_is_told(capfd):
    """Decompose reads the Mirror modifiers once. One added, moved or removed after it mirrors a
    decomposition made for other planes (the seam may tear): Rebuild Detail and Bake Filter say
    so, and say nothing while the modifiers are as they were."""
    points, faces, seam = bumpy_half_sphere()
    obj = h.mesh_object(points, faces, name="Half")
    h.decompose(obj, levels=4)
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "Mirror modifier" not in capfd.readouterr().out
    modifier = obj.modifiers.new("Mirror", "MIRROR")
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "did not follow a Mirror modifier" in out and "Decompose again" in out, out
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert "did not follow a Mirror modifier" in capfd.readouterr().out

    h.decompose(obj, levels=4)  # now it follows the modifier
    capfd.readouterr()
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "Mirror modifier" not in capfd.readouterr().out
    modifier.use_axis = (False, True, False)  # mirrors along Y instead
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "now the Mirror modifier's planes y = 0" in capfd.readouterr().out
    obj.modifiers.remove(modifier)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert "no Mirror modifier mirrors the mesh now" in capfd.readouterr().out
