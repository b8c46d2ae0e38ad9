"""A fifth artist's pass (review, 2026-12-08): a mask vertex group named like a UV map or
'position' bakes with its own weights; Create Morph names A's shape keys it leaves out and
says when the morph cannot reach B; the Prevent Folds tooltip says how far the limit reaches."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _sphere_with_groups(names):
    """A UV sphere (with its UV map 'UVMap'), a colour attribute 'Col', and a vertex group of
    each name holding random weights on random vertices."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24)
    obj = bpy.context.active_object
    obj.data.color_attributes.new("Col", "FLOAT_COLOR", "POINT")
    rng = np.random.default_rng(0)
    n = len(obj.data.vertices)
    for name in names:
        group = obj.vertex_groups.new(name=name)
        for i, w in zip(rng.choice(n, n // 3, replace=False), rng.random(n // 3)):
            group.add([int(i)], float(w), "REPLACE")
    return obj


def test_group_weights_read_a_group_named_like_another_attribute_exactly(addon):
    """On Blender 4.5, Geometry Nodes read a group named 'UVMap' or 'position' as that attribute:
    the bulk reader was off by up to 1 and 1.5 there. It now agrees with the vertex-by-vertex
    reader for every name."""
    import importlib
    group_weights = importlib.import_module(f"{addon.__name__}.group_weights")
    mesh_io = importlib.import_module(f"{addon.__name__}.mesh_io")
    names = ["UVMap", "position", "Col", "sharp_face", "Band mask of my own"]
    obj = _sphere_with_groups(names)
    n = len(obj.data.vertices)
    for name, bulk, exact in zip(names, group_weights.read(obj, names, n), mesh_io.read_group_weights(obj, names, n)):
        assert np.array_equal(bulk, exact), (name, np.abs(bulk - exact).max())


@pytest.mark.parametrize("name", ["UVMap", "position"])
def test_bake_filter_keeps_a_mask_named_like_a_uv_map_to_its_weights(name):
    """A band key masked by a vertex group on the upper half only, its gain 0: Bake Filter must
    leave the lower half where it is, as the viewport shows it. Before, on Blender 4.5, the bake
    moved the lower half by 0.048-0.052 of the diagonal (the group read as the UV map or the
    positions); now by 0."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32)
    obj = bpy.context.active_object
    me = obj.data
    rng = np.random.default_rng(1)
    co = h.vertices(me)
    co *= (1.0 + 0.03 * rng.standard_normal(len(co)))[:, None]  # relief for the finest band
    me.vertices.foreach_set("co", co.astype(np.float32).ravel())
    me.update()
    h.decompose(obj, levels=3)
    group = obj.vertex_groups.new(name=name)
    group.add(np.flatnonzero(co[:, 2] > 0).tolist(), 1.0, "REPLACE")
    me.shape_keys.key_blocks["Band 1"].vertex_group = group.name
    me.multiscale.bands[1].gain = 0.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    baked = h.key(me, "Multiscale Filter")
    lower = co[:, 2] < -0.1
    assert np.abs(baked[lower] - co[lower]).max() < 1e-6 * h.diagonal(co)
    assert np.abs(baked[~lower] - co[~lower]).max() > 1e-3 * h.diagonal(co)  # the upper half was filtered


def test_create_morph_names_the_shape_keys_of_a_it_leaves_out(capfd):
    """A's own key 'Smile' (at value 1) was dropped from the morph without a word; now a warning
    names it, and none of the add-on's own keys. An A with no keys of its own gets no warning."""
    plain = h.mesh_object(h.noisy_sphere(3000), name="Plain")
    h.decompose(plain, levels=3)
    h.morph_onto_bumpy_b(plain)
    assert "own shape keys" not in capfd.readouterr().out
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    a.shape_key_add(name="Basis")
    smile = a.shape_key_add(name="Smile", from_mix=False)
    smile.value = 1.0
    h.decompose(a, levels=3)
    capfd.readouterr()
    morph = h.morph_onto_bumpy_b(a)
    out = capfd.readouterr().out
    assert [kb.name for kb in morph.data.shape_keys.key_blocks] == ["Basis", "A detail", "B detail"]
    said = [line for line in out.splitlines() if "own shape keys" in line]
    assert len(said) == 1 and said[0].startswith("Warning:") and "'Smile'" in said[0], out
    assert "Level 0" not in said[0] and "Band 0" not in said[0]
    assert [kb.name for kb in a.data.shape_keys.key_blocks][:2] == ["Basis", "Smile"]  # A keeps it



def test_create_morph_warns_in_the_panels_words_when_the_morph_cannot_reach_b(capfd):
    """A box B morphed from an ellipsoid over their ellipsoid base: at 'B detail' 1 the morph
    misses the box's corners (the engine now says so); the report speaks of the keys, not of
    Python."""
    import pointscale as ps
    u = np.random.default_rng(0).normal(size=(3000, 3))
    a = h.mesh_object(u / np.linalg.norm(u, axis=1, keepdims=True) * [1.5, 1.0, 0.7], name="A")
    v, f = ps.meshes.box((2.0, 1.6, 1.2), segments=24)
    b = h.mesh_object(v, [list(face) for face in f], name="Box")
    bpy.context.view_layer.objects.active = a
    a.data.multiscale.morph_target = b
    a.data.multiscale.morph_samples = 4000
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    said = [line for line in capfd.readouterr().out.splitlines() if "misses B" in line]
    assert len(said) == 1 and said[0].startswith("Warning: Morph: 'B detail' at 1 misses B by more than 1%"), said
    assert "points_b" not in said[0] and "evaluate(" not in said[0]


def test_the_prevent_folds_tooltip_says_the_limit_can_reach_beyond_the_folds():
    """The tooltip said 'only points near a fold change', but the limit widens each round a fold
    persists: on Suzanne with a lifted half, points 0.21 of the diagonal from every first fold
    moved (README, Folds)."""
    description = bpy.types.Mesh.bl_rna.properties["multiscale"].fixed_type.properties["prevent_folds"].description
    assert "only points near a fold change" not in description
    assert "widens" in description and "beyond" in description
