"""Connected parts in Blender (issue 17): Decompose passes the mesh's edges, so a sphere and a
cube joined into one object 0.05 apart keep their shapes, and an edit of one moves nothing else."""

import importlib

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def joined_sphere_and_cube():
    import pointscale as ps
    sv, sf = ps.meshes.uv_sphere(1.0, 96, 48)
    cv, cf = ps.meshes.box(0.3, 16)
    cv = cv + np.array([1.0 + 0.05 + 0.15, 0.0, 0.0])
    v, f, part = ps.meshes.joined((sv, sf), (cv, ps.meshes.quads_to_triangles(cf)))
    return h.mesh_object(v, f, name="Joined"), v, part


def test_decompose_keeps_joined_parts_apart():
    obj, v, part = joined_sphere_and_cube()
    me = obj.data
    assert me.multiscale.keep_parts  # on by default
    h.decompose(obj, levels=4)
    level0 = h.key(me, "Level 0").astype(np.float64)
    radius = np.linalg.norm(level0[part == 0], axis=1)
    assert radius.max() < 1.01, radius.max()  # one surface, it bulges towards the cube
    cube = v[part == 1]
    cube_diag = np.linalg.norm(cube.max(0) - cube.min(0))
    assert np.linalg.norm(level0[part == 1] - cube, axis=1).max() < 0.10 * cube_diag

    # Lift the cube's base only, and rebuild: the sphere stays exactly where it was.
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    before = h.key(me, "Multiscale Edit").copy()
    assert bpy.ops.pointscale.edit_base(mode="OBJECT") == {"FINISHED"}
    lifted = level0.copy()
    lifted[part == 1, 2] += 0.1
    h.set_key(me, "Level 0", lifted)
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    after = h.key(me, "Multiscale Edit")
    assert np.array_equal(after[part == 0], before[part == 0])
    assert np.abs(after[part == 1, 2] - before[part == 1, 2] - 0.1).max() < 1e-3


def test_the_small_part_is_named_and_the_setting_can_be_turned_off():
    import pointscale as ps
    compute = importlib.import_module(h.ADDON_NAME + ".compute")
    mesh_io = importlib.import_module(h.ADDON_NAME + ".mesh_io")
    obj, v, part = joined_sphere_and_cube()
    edges = mesh_io.read_edges(obj.data)
    assert edges.shape == (len(obj.data.edges), 2)
    layout = compute.decompose(ps, v, levels=4, edges=edges)
    assert any("part 1" in m and "too small" in m for m in layout.warnings), layout.warnings
    assert len(layout.dec.parts) == 2

    obj.data.multiscale.keep_parts = False
    h.decompose(obj, levels=4)
    radius = np.linalg.norm(h.key(obj.data, "Level 0")[part == 0].astype(np.float64), axis=1)
    assert radius.max() > 1.02  # decomposed as one surface, the sphere reaches towards the cube
