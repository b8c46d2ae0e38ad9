"""Check 9: bad input is reported cleanly and leaves the data untouched."""

import bmesh
import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender

DATA_OPERATORS = [
    ("rebuild_detail", {}),
    ("bake_filter", {}),
    ("show_details", {"band": 0}),
    ("paint_band_mask", {"band": 0, "enter_paint": False}),
    ("reset_bands", {}),
    ("edit_base", {"mode": "OBJECT"}),
]


def test_non_mesh_object_fails_poll_with_a_message():
    bpy.ops.object.camera_add()
    assert not bpy.ops.pointscale.decompose.poll()
    with pytest.raises(RuntimeError, match="not a mesh"):
        bpy.ops.pointscale.decompose()
    for name, kw in DATA_OPERATORS:
        assert not getattr(bpy.ops.pointscale, name).poll()
    bpy.ops.object.select_all(action="DESELECT")
    bpy.context.view_layer.objects.active = None
    with pytest.raises(RuntimeError, match="No active object"):
        bpy.ops.pointscale.decompose()


def test_three_vertices_are_refused():
    obj = h.mesh_object([(0, 0, 0), (1, 0, 0), (0, 1, 0)], faces=[(0, 1, 2)])
    h.assert_refused(obj, "decompose", "3 vertices")
    assert obj.data.shape_keys is None and obj.data.multiscale.n_bands == 0


def test_nan_coordinates_are_refused():
    pts = h.noisy_sphere(4000)
    pts[17] = np.nan
    obj = h.mesh_object(pts)
    h.assert_refused(obj, "decompose", "NaN")
    assert obj.data.shape_keys is None


def test_flat_input_reports_the_engine_message():
    x, y = np.meshgrid(np.linspace(0, 1, 40), np.linspace(0, 1, 40))
    obj = h.mesh_object(np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)]))
    h.assert_refused(obj, "decompose", "plane")


def test_topology_change_after_decompose_is_refused():
    obj = h.mesh_object(h.noisy_sphere(4000), name="Topo")
    h.decompose(obj)
    me = obj.data
    with h.edited_bmesh(obj) as bm:
        bmesh.ops.delete(bm, geom=[bm.verts[i] for i in range(10)], context="VERTS")
    assert len(me.vertices) == 3990
    before = h.snapshot(obj)
    for name, kw in DATA_OPERATORS:
        op = getattr(bpy.ops.pointscale, name)
        assert not op.poll(), name
        with pytest.raises(RuntimeError, match="topology changed"):
            op(**kw)
        assert h.same(before, h.snapshot(obj)), name
    me.multiscale.scale = 1.0  # the slider itself does no harm: it only sets key values
    # Decompose again is the way out.
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    assert me.multiscale.n_vertices == 3990 and bpy.ops.pointscale.rebuild_detail.poll()
