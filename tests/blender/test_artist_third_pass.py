"""A third artist's pass (QA, 2026-12-06): an edited base survives Decompose again, a second Bake
Filter keeps the first, Morph links where the view layer shows it and copies only the artist's
data, Clear finds every mask it made, levels fit the largest part, the panel and the reports speak
the panel's words, and ray shooting gives an unedited mesh back."""

import sys

import bmesh
import bpy
import numpy as np
import pytest
from mathutils import Matrix

import blender_helpers as h

pytestmark = pytest.mark.blender


def addon_module(name):
    return sys.modules[f"{h.ADDON_NAME}.{name}"]


def lifted_top(obj, by=0.3):
    """Raise the 'Level 0' key's upper half: an edit of the base."""
    co = h.key(obj.data, "Level 0").copy()
    co[co[:, 2] > 0.5, 2] += by
    h.set_key(obj.data, "Level 0", co)
    return co


# ---------------------------------------------------------------- 1. an edited base is kept

def test_decompose_again_keeps_an_edited_base(capfd):
    obj = h.mesh_object(h.noisy_sphere(4000), name="Edited")
    original = h.vertices(obj.data).astype(np.float64)
    h.decompose(obj)
    edited = lifted_top(obj)
    h.decompose(obj, levels=3)
    blocks = obj.data.shape_keys.key_blocks
    assert np.array_equal(h.key(obj.data, "Level 0 (previous)"), edited)
    assert blocks["Level 0 (previous)"].value == 0.0  # kept, not shown
    assert "Level 0 (previous)" in capfd.readouterr().out
    assert np.abs(h.evaluated(obj) - original).max() < 1e-6 * h.diagonal(original)
    # An unedited base is not kept again, and the kept one stays.
    h.decompose(obj, levels=4)
    assert np.array_equal(h.key(obj.data, "Level 0 (previous)"), edited)
    assert "Level 0 (previous)" not in capfd.readouterr().out
    # Clear keeps an edited base too, and says so.
    second = lifted_top(obj, by=0.2)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert np.array_equal(h.key(obj.data, "Level 0 (previous)"), second)
    assert "Level 0 (previous)" in capfd.readouterr().out


def test_an_artists_key_named_like_the_kept_base_is_refused():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Own")
    obj.shape_key_add(name="Basis")
    obj.shape_key_add(name="Level 0 (previous)")
    h.assert_refused(obj, "decompose", "Level 0 \\(previous\\)")


# ---------------------------------------------------------------- 2. bakes accumulate

def _engine_result(obj, gains):
    import pointscale as ps

    dec = addon_module("writeback").decomposition(obj.data, ps)
    return ps.reconstruct(dec, gains=gains)


def _painted_half(obj, band):
    assert bpy.ops.pointscale.paint_band_mask(band=band, enter_paint=False) == {"FINISHED"}
    upper = np.flatnonzero(h.vertices(obj.data)[:, 2] > 0.0).tolist()
    obj.vertex_groups[f"Band {band} mask"].add(upper, 0.0, "REPLACE")
    weights = np.ones(len(obj.data.vertices))
    weights[upper] = 0.0
    return weights


def test_a_second_bake_multiplies_into_the_first(tmp_path):
    obj = h.mesh_object(h.noisy_sphere(4000), name="Bakes")
    scale = h.diagonal(h.vertices(obj.data))
    h.decompose(obj)
    s = obj.data.multiscale
    mask = _painted_half(obj, 2)
    s.bands[2].gain = 3.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    # Repainting the mask afterwards changes nothing that was baked.
    obj.vertex_groups["Band 2 mask"].add(list(range(len(mask))), 1.0, "REPLACE")
    s.bands[0].gain = 0.5
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    gains = np.ones((3, len(mask)))
    gains[0] = 0.5
    gains[2] = 1.0 + 2.0 * mask
    second = h.key(obj.data, "Multiscale Filter")
    assert np.abs(second - _engine_result(obj, gains)).max() < 1e-6 * scale
    assert np.abs(h.evaluated(obj) - second).max() < 1e-6 * scale

    # The baked gains are saved with the mesh: a reload bakes the next step alike.
    s.bands[1].gain = 2.0
    path = str(tmp_path / "bakes.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    third = h.key(obj.data, "Multiscale Filter").copy()
    bpy.ops.wm.open_mainfile(filepath=path)
    obj = bpy.data.objects["Bakes"]
    bpy.context.view_layer.objects.active = obj
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert np.array_equal(h.key(obj.data, "Multiscale Filter"), third)


def _first_bake(name):
    """A decomposed sphere with its finest band baked at gain 3: (object, the Filter key)."""
    obj = h.mesh_object(h.noisy_sphere(4000), name=name)
    h.decompose(obj)
    obj.data.multiscale.bands[2].gain = 3.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    return obj, h.key(obj.data, "Multiscale Filter").copy()


def test_a_bake_switched_off_is_kept_when_the_next_starts_afresh(capfd):
    obj, first = _first_bake("Off")
    s = obj.data.multiscale
    obj.data.shape_keys.key_blocks["Multiscale Filter"].value = 0.0  # the artist looks at the original
    s.bands[0].gain = 0.5
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert np.array_equal(h.key(obj.data, "Multiscale Filter (previous)"), first)
    scale = h.diagonal(h.vertices(obj.data))
    expect = _engine_result(obj, np.array([0.5, 1.0, 1.0]))
    assert np.abs(h.key(obj.data, "Multiscale Filter") - expect).max() < 1e-6 * scale
    assert "Multiscale Filter (previous)" in capfd.readouterr().out


def test_a_bake_builds_only_on_the_gains_that_made_the_filter_key_as_it_is():
    """An undo in Edit Mode restores the key but not the mesh's properties: the gains stored
    for a later bake then no longer made the key, and the next bake must not build on them."""
    obj, first = _first_bake("Undone")
    s = obj.data.multiscale
    s.bands[0].gain = 0.5
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    h.set_key(obj.data, "Multiscale Filter", first)  # as the undo leaves it
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}  # at unit gains
    scale = h.diagonal(h.vertices(obj.data))
    assert np.abs(h.key(obj.data, "Multiscale Filter") - _engine_result(obj, np.ones(3))).max() < 1e-6 * scale
    assert np.array_equal(h.key(obj.data, "Multiscale Filter (previous)"), first)


def test_an_artists_own_previous_keys_are_never_written_over():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Mine")
    h.decompose(obj)
    # Clear, with an edited base to keep where the artist has a key of that name.
    lifted_top(obj)
    own = obj.shape_key_add(name="Level 0 (previous)", from_mix=False)
    mine = h.key(obj.data, "Level 0 (previous)").copy()
    h.assert_refused(obj, "clear", "shape key 'Level 0 \\(previous\\)' of its own")
    assert np.array_equal(h.key(obj.data, "Level 0 (previous)"), mine) and "Level 0" in obj.data.shape_keys.key_blocks
    obj.shape_key_remove(own)
    # Bake, with an earlier bake switched off to keep where the artist has a key of that name.
    obj.data.multiscale.bands[2].gain = 3.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    obj.data.shape_keys.key_blocks["Multiscale Filter"].value = 0.0
    obj.shape_key_add(name="Multiscale Filter (previous)", from_mix=False)
    mine = h.key(obj.data, "Multiscale Filter (previous)").copy()
    baked = h.key(obj.data, "Multiscale Filter").copy()
    h.assert_refused(obj, "bake_filter", "shape key 'Multiscale Filter \\(previous\\)' of its own")
    assert np.array_equal(h.key(obj.data, "Multiscale Filter (previous)"), mine)
    assert np.array_equal(h.key(obj.data, "Multiscale Filter"), baked)


# ---------------------------------------------------------------- 3-4. Morph

def _excluded_and_shown():
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    import pointscale as ps

    b = h.mesh_object(ps.shapes.bumpy_sphere(2000, coarse=0.1, fine=0.02), name="B")
    hidden = bpy.data.collections.new("Reference")
    bpy.context.scene.collection.children.link(hidden)
    bpy.context.scene.collection.objects.unlink(a)
    hidden.objects.link(a)
    shown = bpy.data.collections.new("Work")
    bpy.context.scene.collection.children.link(shown)
    shown.objects.link(a)
    bpy.context.view_layer.layer_collection.children["Reference"].exclude = True
    bpy.context.view_layer.objects.active = a
    a.data.multiscale.morph_target = b
    a.data.multiscale.morph_samples = 3000
    return a, b


def test_morph_links_the_new_object_where_the_view_layer_shows_it():
    a, b = _excluded_and_shown()
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    morph = bpy.data.objects["A x B"]
    assert morph.name in bpy.context.view_layer.objects
    assert [c.name for c in morph.users_collection] == ["Work"]
    assert bpy.context.view_layer.objects.active == morph


def test_a_failed_morph_leaves_no_object_behind(monkeypatch):
    a, b = _excluded_and_shown()
    objects, meshes = set(bpy.data.objects.keys()), set(bpy.data.meshes.keys())

    def fail(*_args, **_kwargs):
        raise RuntimeError("Blender refused")

    monkeypatch.setattr(addon_module("keys"), "ensure_key", fail)
    with pytest.raises(RuntimeError, match="Morph") as refused:
        bpy.ops.pointscale.morph()
    assert "Traceback" not in str(refused.value)
    assert set(bpy.data.objects.keys()) == objects and set(bpy.data.meshes.keys()) == meshes


def test_the_morph_copy_keeps_the_artists_data_and_drops_the_add_ons():
    a = h.mesh_object(h.noisy_sphere(3000), name="A")
    n = len(a.data.vertices)
    a.data.attributes.new("ms_detail_sculpt", "FLOAT", "POINT")
    a.vertex_groups.new(name="Band 7 mask")
    a.vertex_groups.new(name="Jaw")
    h.decompose(a)
    a.data.multiscale.bands[2].gain = 5.0
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert a.vertex_groups.get("Folds") is not None
    assert bpy.ops.pointscale.paint_band_mask(band=1, enter_paint=False) == {"FINISHED"}
    morph = h.morph_onto_bumpy_b(a)
    assert morph.name == "A x B" and len(morph.data.vertices) == n
    assert morph.data.attributes.get("ms_detail_sculpt") is not None
    assert not [x.name for x in morph.data.attributes if x.name.startswith(("ms_detail_", ".ps."))
                and x.name != "ms_detail_sculpt"]
    assert sorted(g.name for g in morph.vertex_groups) == ["Band 7 mask", "Jaw"]
    # Its only bookkeeping is the Basis the add-on made for the morph keys.
    assert [p for p in morph.data.keys() if p.startswith("pointscale")] == ["pointscale_created_basis"]


# ---------------------------------------------------------------- 5. Clear finds every mask

def test_clear_removes_an_unpainted_mask_of_a_band_a_later_decompose_dropped():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Masks")
    h.decompose(obj)
    assert bpy.ops.pointscale.paint_band_mask(band=2, enter_paint=False) == {"FINISHED"}
    h.decompose(obj, levels=3)
    assert bpy.ops.pointscale.clear() == {"FINISHED"}
    assert [g.name for g in obj.vertex_groups] == []
    assert "pointscale_groups" not in obj.data.keys()


# ---------------------------------------------------------------- 6. levels fit the largest part

def _spheres(count):
    me = bpy.data.meshes.new("Spheres")
    bm = bmesh.new()
    for i in range(count):
        bmesh.ops.create_icosphere(bm, subdivisions=3, radius=1.0, matrix=Matrix.Translation((3 * i, 0, 0)))
    bm.to_mesh(me)
    bm.free()
    co = h.vertices(me).astype(np.float64)
    co += 0.01 * np.sin(20 * co)
    me.vertices.foreach_set("co", co.astype(np.float32).ravel())
    me.update()
    obj = bpy.data.objects.new("Spheres", me)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    return obj


def test_levels_fit_the_largest_part_with_keep_parts_apart(capfd):
    obj = _spheres(4)  # 4 x 162 vertices: the whole mesh fits 4 levels, no part does
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    assert obj.data.multiscale.n_bands == 2
    assert "the largest part of the mesh that is not flat has 162 vertices" in capfd.readouterr().out


# ---------------------------------------------------------------- 7. the panel names the problem

def test_the_panel_names_the_actual_problem():
    from test_panels import draw_all, labels

    obj = h.mesh_object(h.noisy_sphere(4000), name="Panel")
    h.decompose(obj)
    obj.data.shape_keys.key_blocks["Level 0"].name = "My base"
    shown = labels(draw_all(bpy.context))
    assert "no shape key 'Level 0'" in shown and "Topology" not in shown


# ---------------------------------------------------------------- 8. the panel's words in reports

@pytest.mark.parametrize("smoother,encoding,named", [
    ("DIFFUSION", "PROJECTION", "Smoother: Diffusion"),
    ("MLS", "RAY", "Encoding: Ray Shooting"),
])
def test_thin_sheets_refusals_use_the_panels_names(smoother, encoding, named):
    obj = h.mesh_object(h.noisy_sphere(3000), name="Sheets")
    s = obj.data.multiscale
    s.thin_sheets, s.smoother, s.encoding = True, smoother, encoding
    before = h.snapshot(obj)
    with pytest.raises(RuntimeError) as refused:
        bpy.ops.pointscale.decompose()
    message = str(refused.value)
    assert "Keep Thin Sheets Apart" in message and named in message
    assert "sheets=True" not in message and "smoother='" not in message and "encoding='" not in message
    assert h.same(before, h.snapshot(obj))


@pytest.mark.parametrize("small", ["A", "B"])
def test_a_morph_of_too_few_vertices_names_the_object(small):
    import pointscale as ps

    a = h.mesh_object(h.noisy_sphere(2000)[: 3 if small == "A" else 2000], name="Small A")
    b_points = ps.shapes.bumpy_sphere(2000, coarse=0.1, fine=0.02)
    b = h.mesh_object(b_points[: 3 if small == "B" else 2000], name="Small B")
    bpy.context.view_layer.objects.active = a
    a.data.multiscale.morph_target = b
    with pytest.raises(RuntimeError) as refused:
        bpy.ops.pointscale.morph()
    message = str(refused.value)
    which = "object A 'Small A'" if small == "A" else "target B 'Small B'"
    assert f"{which} has 3 vertices; Morph needs at least 8" in message
    assert "points_a" not in message and "points_b" not in message


# ---------------------------------------------------------------- 9. ray shooting gives the mesh back

def test_ray_shooting_gives_an_unedited_mesh_back():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Rays")
    basis = h.vertices(obj.data).astype(np.float64)
    scale = h.diagonal(basis)
    h.decompose(obj, encoding="RAY")
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert np.abs(h.key(obj.data, "Multiscale Edit") - basis).max() < 1e-6 * scale
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    baked = h.key(obj.data, "Multiscale Filter").astype(np.float64)
    assert np.abs(baked - basis).max() < 1e-6 * scale
    # The finest band's gain scales what ray shooting's finest level left out too, as the band key shows it.
    obj.data.multiscale.bands[2].gain = 2.0
    preview = h.evaluated(obj) - (baked - basis)  # the sliders alone, without the bake shown under them
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    assert np.abs(h.key(obj.data, "Multiscale Filter") - preview).max() < 1e-5 * scale
    # An edit still moves the detail with the base.
    lifted_top(obj, by=0.1)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    moved = h.key(obj.data, "Multiscale Edit")[:, 2] - basis[:, 2]
    assert np.median(moved[basis[:, 2] > 0.7]) == pytest.approx(0.1, rel=0.2)
