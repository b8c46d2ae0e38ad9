"""Check 5: edit Level 0 (lift a region), Rebuild detail: the Fig. 5 handles stay normal to the new base."""

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def bump(xy, height=0.8, width=1.0):
    return height * np.exp(-(xy**2).sum(axis=1) / width**2)


def handle_angles(result, points, handle, centres, surface):
    """Angle (degrees) between each handle's axis and the normal of the surface around it."""
    angles = []
    for i, (cx, cy) in enumerate(centres):
        mine = handle == i
        top = mine & (points[:, 2] > points[mine, 2].max() - 1e-6)
        low = mine & (points[:, 2] < points[mine, 2].min() + 1e-6)
        axis = result[top].mean(axis=0) - result[low].mean(axis=0)
        r = np.hypot(points[:, 0] - cx, points[:, 1] - cy)
        ring = surface[(handle == -1) & (r > 0.15) & (r < 0.4)]
        normal = np.linalg.svd(ring - ring.mean(axis=0), full_matrices=False)[2][2]
        angles.append(np.degrees(np.arccos(abs(axis @ normal) / np.linalg.norm(axis))))
    return np.array(angles)


def test_rebuild_detail_keeps_handles_normal_to_the_edited_base():
    import pointscale as ps

    points, handle, centres = ps.shapes.handles_plane(spacing=0.04)
    obj = h.mesh_object(points, name="Handles")
    h.decompose(obj, levels=4, decimation=0.2, kernel=2.0)
    me = obj.data
    original = h.key(me, "Basis").astype(np.float64)

    # Unedited base: Rebuild returns the original.
    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    assert np.abs(h.key(me, "Multiscale Edit") - original).max() < 1e-5

    # "Edit mode": lift a circular region of Level 0, as a user would with proportional editing.
    assert bpy.ops.pointscale.edit_base(mode="OBJECT") == {"FINISHED"}
    assert obj.active_shape_key.name == "Level 0"
    base = h.key(me, "Level 0").astype(np.float64)
    lifted = base.copy()
    lifted[:, 2] += bump(base[:, :2])
    h.set_key(me, "Level 0", lifted)

    assert bpy.ops.pointscale.rebuild_detail() == {"FINISHED"}
    result = h.key(me, "Multiscale Edit").astype(np.float64)
    multiscale = handle_angles(result, points, handle, centres, lifted)
    assert multiscale.max() < 3.0, multiscale

    # The same lift applied to the original points (single scale) tilts the flank handles:
    single = original.copy()
    single[:, 2] += bump(original[:, :2])
    assert handle_angles(single, points, handle, centres, single).max() > 10.0

    # What Blender shows is the rebuilt result (Multiscale Edit at 1, levels off).
    assert me.shape_keys.key_blocks["Multiscale Edit"].value == 1.0
    assert np.abs(h.evaluated(obj) - result).max() < 1e-5
    # The Basis is still the original.
    assert np.array_equal(h.key(me, "Basis"), original.astype(np.float32))
