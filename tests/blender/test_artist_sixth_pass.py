"""A sixth artist's pass (trial, 2026-12-07): a mesh in Edit Mode through its linked duplicate
is refused before anything is written; a mesh split along a seam (coincident vertices, as
imported assets are) reports no folds when its base moves as a whole, and Prevent Folds leaves
it as rebuilt; Create Morph keeps a half model's mirror seam on its plane and refuses a zero
scale in words; reports name what they mean."""

import bmesh
import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _bumpy_ico_sphere(subdivisions=4):
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions)
    obj = bpy.context.active_object
    co = h.vertices(obj.data)
    d = 1 + 0.05 * np.sin(5 * co[:, 0]) * np.sin(5 * co[:, 1]) + 0.01 * np.sin(23 * co[:, 2])
    obj.data.vertices.foreach_set("co", (co * d[:, None]).astype(np.float32).ravel())
    obj.data.update()
    return obj


def test_a_mesh_in_edit_mode_through_its_linked_duplicate_is_refused_untouched(addon):
    """Decompose through the duplicate failed half way with a traceback and wiped the stored
    decomposition (every operator then said there was none); Bake Filter wrote its key first."""
    a = _bumpy_ico_sphere()
    a.data.multiscale.levels = 3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    twin = bpy.data.objects.new("Twin", a.data)
    bpy.context.scene.collection.objects.link(twin)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.context.view_layer.objects.active = twin
    keys_before = list(a.data.shape_keys.key_blocks.keys())
    a.data.multiscale.bands[1].gain = 2.0
    for name in ("decompose", "bake_filter", "rebuild_detail", "clear"):
        operator = getattr(bpy.ops.pointscale, name)
        assert not operator.poll(), name
        with pytest.raises(RuntimeError, match="is in Edit Mode through 'Icosphere': leave Edit Mode there first"):
            operator()
    assert list(a.data.shape_keys.key_blocks.keys()) == keys_before
    bpy.context.view_layer.objects.active = a
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.context.view_layer.objects.active = twin
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}  # the decomposition is still there


def test_a_mesh_split_along_a_seam_moved_as_a_whole_folds_nowhere(addon):
    """Its coincident vertex pairs folded at the rounding of their base positions: 4 points
    marked on a UV sphere split at its equator, and Prevent Folds moved 361 points by up to
    0.0675 (3% of the model) for nothing."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48)
    obj = bpy.context.active_object
    mesh = obj.data
    co = h.vertices(mesh)
    d = 1 + 0.04 * np.sin(9 * co[:, 0]) * np.sin(9 * co[:, 1]) + 0.01 * np.sin(40 * co[:, 2])
    mesh.vertices.foreach_set("co", (co * d[:, None]).astype(np.float32).ravel())
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bmesh.ops.split_edges(bm, edges=[e for e in bm.edges if all(abs(v.co.z) < 1e-4 for v in e.verts)])
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()
    assert len(mesh.vertices) == 4514 + 96  # the equator's vertices, twice
    mesh.multiscale.levels = 3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    basis = h.key(mesh, "Basis")
    level0 = h.key(mesh, "Level 0")
    level0[:, 2] += 0.2
    h.set_key(mesh, "Level 0", level0)
    for prevent in (False, True):
        mesh.multiscale.prevent_folds = prevent
        assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
        assert np.abs(h.key(mesh, "Multiscale Edit") - basis - [0.0, 0.0, 0.2]).max() < 1e-6, prevent
        folds = obj.vertex_groups.get("Folds")
        assert folds is None or not any(g.group == folds.index for v in mesh.vertices for g in v.groups)


def _half_sphere(name, shape):
    """A UV sphere's x >= 0 half, reshaped, under a Mirror modifier (merge and clipping on)."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32)
    obj = bpy.context.active_object
    obj.name = name
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bmesh.ops.delete(bm, geom=[v for v in bm.verts if v.co.x < -1e-5], context="VERTS")
    for v in bm.verts:
        v.co = shape(np.array(v.co))
        if abs(v.co.x) < 1e-5:
            v.co.x = 0.0
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()
    obj.modifiers.new("Mirror", "MIRROR").use_clip = True
    return obj


def test_a_morph_of_half_models_keeps_the_seam_on_the_mirror_plane(addon):
    """The morph object keeps A's Mirror modifier, but its keys moved the seam off the plane (by
    0.126 at B detail = 1 on a model 2 wide): the modifier merged none of it and the model tore."""
    a = _half_sphere("A", lambda p: p * (1 + 0.05 * np.sin(7 * p[1]) * np.sin(7 * p[2])))
    b = _half_sphere("B", lambda p: p * np.array([0.8, 1.0, 1.3]))
    seam = np.abs(h.vertices(a.data)[:, 0]) < 1e-6
    assert seam.sum() == 64
    bpy.context.view_layer.objects.active = a
    a.data.multiscale.morph_target = b
    a.data.multiscale.morph_samples = 4000
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    made = bpy.context.active_object.data
    for name in ("Basis", "A detail", "B detail"):
        assert np.abs(h.key(made, name)[seam, 0]).max() == 0.0, name
    off = np.abs(h.key(made, "B detail")[~seam, 0])
    assert off.min() > 0.0  # only the seam is put on the plane


def test_a_zero_scale_is_refused_in_words(addon):
    """A flattened to zero on one axis gave a Python traceback ('matrix does not have an
    inverse'); a Mirror Object of zero scale gave that text as Decompose's report."""
    a = _bumpy_ico_sphere(3)
    a.name = "A"
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=1.2)
    b = bpy.context.active_object
    a.scale = (1.0, 1.0, 0.0)
    bpy.context.view_layer.update()
    bpy.context.view_layer.objects.active = a
    a.data.multiscale.morph_target = b
    with pytest.raises(RuntimeError, match="A 'A' has a zero scale .*Give it a scale on every axis"):
        bpy.ops.pointscale.morph()
    a.scale = (1.0, 1.0, 1.0)
    empty = bpy.data.objects.new("MirrorEmpty", None)
    bpy.context.scene.collection.objects.link(empty)
    empty.scale = (0.0, 1.0, 1.0)
    a.modifiers.new("Mirror", "MIRROR").mirror_object = empty
    bpy.context.view_layer.update()
    a.data.multiscale.levels = 3
    with pytest.raises(RuntimeError, match="Mirror Object 'MirrorEmpty' of modifier 'Mirror' has a zero scale"):
        bpy.ops.pointscale.decompose()


def test_reports_name_the_keys_kept_and_the_settings_as_typed(addon, capfd):
    obj = _bumpy_ico_sphere(3)
    obj.data.multiscale.levels = 4
    obj.data.multiscale.decimation = 0.3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    out = capfd.readouterr().out
    # The keys are kept under these names (it named the ones they had).
    assert "kept as 'Multiscale Edit (previous)', 'Multiscale Filter (previous)'" in out, out
    assert "decimation=0.3 " in out and "0.30000001" not in out, out


def test_a_zero_normal_attribute_is_refused_naming_it(addon):
    """A point attribute 'normal' left at zero (a bake, an importer) was refused in the engine's
    words ('normals: ... Give oriented normals'), though the artist gave none in the panel."""
    obj = _bumpy_ico_sphere(4)
    obj.data.attributes.new("normal", "FLOAT_VECTOR", "POINT")
    obj.data.multiscale.levels = 3
    with pytest.raises(RuntimeError, match="its point attribute 'normal' .* has 642 of 642 vectors zero"):
        bpy.ops.pointscale.decompose()
    assert obj.data.shape_keys is None


def _marked(obj):
    group = obj.vertex_groups.get("Folds")
    if group is None:
        return 0
    return sum(1 for v in obj.data.vertices for g in v.groups if g.group == group.index and g.weight > 0)


def test_fold_marks_of_an_earlier_result_are_cleared(addon):
    """With Show Folds off, a bake that no longer folds, and Decompose again, left the 'Folds'
    group marking 4421 points that no longer fold."""
    obj = _bumpy_ico_sphere(5)
    s = obj.data.multiscale
    s.levels = 3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    s.show_folds = True
    s.bands[0].gain = s.bands[1].gain = 5.0
    bpy.ops.pointscale.bake_filter()
    s.bands[0].gain = s.bands[1].gain = 5.0
    bpy.ops.pointscale.bake_filter()
    assert _marked(obj) > 1000
    s.show_folds = False
    s.prevent_folds = True
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert _marked(obj) == 0
    s.show_folds = True
    s.prevent_folds = False
    s.bands[0].gain = s.bands[1].gain = 5.0
    bpy.ops.pointscale.bake_filter()
    assert _marked(obj) > 0
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    assert _marked(obj) == 0


def test_a_bake_on_a_filter_key_dialled_down_builds_on_what_is_shown(addon):
    """'Multiscale Filter' at 0.5, then Bake Filter at unit sliders: the bake built on the full
    earlier gains and set the key back to 1, so the shape jumped by 0.035 (of 2)."""
    obj = _bumpy_ico_sphere(5)
    s = obj.data.multiscale
    s.levels = 3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    s.bands[1].gain = 3.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    obj.data.shape_keys.key_blocks["Multiscale Filter"].value = 0.5
    shown = h.evaluated(obj)
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert obj.data.shape_keys.key_blocks["Multiscale Filter"].value == 1.0
    assert np.abs(h.evaluated(obj) - shown).max() < 1e-4


def test_a_keyframed_band_is_said_to_apply_twice_after_a_bake(addon, capfd):
    obj = _bumpy_ico_sphere(4)
    obj.data.multiscale.levels = 3
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    band = obj.data.shape_keys.key_blocks["Band 1"]
    band.value = 1.0
    band.keyframe_insert("value", frame=1)
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "'Band 1' is keyframed or driven, so the value comes back on the next frame" in out, out
