"""A rock standing on a ground plane, both parts of one mesh (Keep Parts Apart on): the ground,
flat and with more vertices, led the parts, so the rock kept only the levels its own size
supports among the others (2 of 4, its Band 0 and 1 zero), and a small rock was refused at any
level count. The levels are the largest part's that is not flat."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def _rock_on_ground(segments, ground):
    from pointscale import meshes
    rv, rf = meshes.uv_sphere(1.0, segments, segments // 2)
    rv = meshes.bumpy(rv, 0.08, 3.0) + np.array([0.0, 0.0, 1.1])
    gv, gf = meshes.grid(8.0, 8.0, ground, ground)
    v, f, part = meshes.joined((rv, rf), (gv, meshes.quads_to_triangles(gf)))
    return h.mesh_object(v, f, name="Rock on ground"), part == 0


def test_a_rock_on_a_larger_ground_keeps_every_band(capfd):
    obj, rock = _rock_on_ground(64, 80)
    assert (~rock).sum() > rock.sum()
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    mesh = obj.data
    assert mesh.multiscale.n_bands == 3
    basis = h.key(mesh, "Basis")
    for l in range(3):
        moved = np.abs(h.key(mesh, f"Band {l}") - basis)
        assert moved[rock].max() > 0.01, l  # the rock's own bands
        assert moved[~rock].max() < 1e-6  # the ground keeps none
    out = capfd.readouterr().out
    assert "spans no surface" in out and f"of {rock.sum()};" in out  # level 0's coarseness: the rock's


def test_a_small_rock_on_a_larger_ground_is_decomposed_with_the_levels_it_supports(capfd):
    obj, rock = _rock_on_ground(32, 40)  # 482 rock vertices: 4 levels need 512
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    assert obj.data.multiscale.n_bands == 2
    assert "the largest part of the mesh that is not flat has 482 vertices" in capfd.readouterr().out
