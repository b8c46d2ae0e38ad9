"""Issue 18, artist details: Clear removes all it made (the Basis it created, unpainted masks,
the detail colours), and Rebuild Detail and Bake Filter return to the artist's mode."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def sphere_mesh(name="Ball"):
    import pointscale as ps
    v, f = ps.meshes.uv_sphere(1.0, 96, 48)
    return h.mesh_object(ps.meshes.bumpy(v, 0.03, 5), f, name=name)


def test_clear_removes_the_basis_it_made_so_modifiers_apply_again():
    obj = sphere_mesh()
    before = h.vertices(obj.data).copy()
    h.decompose(obj, levels=3)
    assert obj.data.shape_keys is not None
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert obj.data.shape_keys is None
    assert np.array_equal(h.vertices(obj.data), before)
    assert not [g.name for g in obj.vertex_groups]  # the unpainted masks went too
    obj.modifiers.new("Subdivision", "SUBSURF")
    assert bpy.ops.object.modifier_apply(modifier="Subdivision") == {"FINISHED"}


def test_clear_keeps_the_artists_own_keys_and_painted_masks(capfd):
    obj = sphere_mesh()
    obj.shape_key_add(name="Basis")
    obj.shape_key_add(name="Smile")
    h.decompose(obj, levels=3)
    for band in (0, 1):  # both masks made, as the brush button makes them; only band 1 painted
        assert bpy.ops.pointscale.paint_band_mask(band=band) == {"FINISHED"}
    bpy.ops.object.mode_set(mode="OBJECT")
    obj.vertex_groups["Band 1 mask"].add([0, 1, 2], 0.25, "REPLACE")
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert [k.name for k in obj.data.shape_keys.key_blocks] == ["Basis", "Smile"]
    assert [g.name for g in obj.vertex_groups] == ["Band 1 mask"]
    assert "kept the painted Band 1 mask" in capfd.readouterr().out


def test_clear_keeps_a_basis_that_keys_made_after_need(capfd):
    obj = sphere_mesh()
    h.decompose(obj, levels=3)
    obj.shape_key_add(name="Later", from_mix=False)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert [k.name for k in obj.data.shape_keys.key_blocks] == ["Basis", "Later"]
    assert "kept the Basis key" in capfd.readouterr().out


def test_clear_gives_back_the_colours_show_details_replaced():
    obj = sphere_mesh()
    mesh = obj.data
    mesh.color_attributes.new("Paint", "FLOAT_COLOR", "POINT")
    mesh.color_attributes.new("Dirt", "BYTE_COLOR", "CORNER")
    mesh.color_attributes.active_color = mesh.color_attributes["Dirt"]
    mesh.color_attributes.render_color_index = mesh.color_attributes.find("Paint")
    h.decompose(obj, levels=3)
    assert bpy.ops.pointscale.show_details(band=0) == {"FINISHED"}
    assert mesh.color_attributes.active_color.name == "ms_detail_color"
    assert bpy.ops.pointscale.show_details(band=1) == {"FINISHED"}  # twice: the first saved state holds
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert mesh.color_attributes.get("ms_detail_color") is None
    assert mesh.color_attributes.active_color.name == "Dirt"
    assert mesh.color_attributes[mesh.color_attributes.render_color_index].name == "Paint"


@pytest.mark.parametrize("mode", ["EDIT", "SCULPT"])
def test_rebuild_detail_and_bake_filter_return_to_the_artists_mode(mode):
    obj = sphere_mesh()
    h.decompose(obj, levels=3)
    assert bpy.ops.pointscale.edit_base(mode=mode) == {"FINISHED"}
    assert obj.mode == mode
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert obj.mode == mode
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert obj.mode == mode
    bpy.ops.object.mode_set(mode="OBJECT")


def test_suzanne_is_decomposed_with_the_levels_she_supports(capfd):
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    assert len(obj.data.vertices) == 507
    h.decompose(obj, levels=4)
    assert obj.data.multiscale.n_bands == 2  # 3 levels
    assert obj.data.multiscale.levels == 4  # the artist's setting stays
    out = capfd.readouterr().out
    assert "507 vertices" in out and "Subdivision Surface" in out and "Decimation to 0.59 (then level 0 keeps at least 100 points)" in out


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_imported_point_cloud_normals_orient_the_levels(tmp_path, sign):
    """A PLY point cloud's normals (Blender's importer keeps them as the `normal` attribute) say
    which side is out: inward ones turn every level's normals inward."""
    import importlib

    import pointscale as ps
    writeback = importlib.import_module(h.ADDON_NAME + ".writeback")
    points = ps.shapes.bumpy_sphere(6000, seed=4)
    normals = sign * points / np.linalg.norm(points, axis=1, keepdims=True)
    ps.io.write(tmp_path / "cloud.ply", ps.io.Scan(points=points, normals=normals))
    bpy.ops.wm.ply_import(filepath=str(tmp_path / "cloud.ply"))
    obj = bpy.context.active_object
    assert obj.data.attributes.get("normal") is not None
    h.decompose(obj, levels=3)
    dec = writeback.decomposition(obj.data, ps)
    level0 = dec.normals(0)
    outward = np.einsum("ij,ij->i", level0, dec.level(0)) > 0
    assert outward.mean() == (1.0 if sign > 0 else 0.0), outward.mean()
