"""The modal Decompose's operator without a window (tests/test_addon_job.py tests its worker,
addon/job.py, without Blender)."""

import bpy
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


def test_invoke_without_a_window_runs_synchronously():
    obj = h.mesh_object(h.noisy_sphere(4000))
    assert bpy.ops.pointscale.decompose("INVOKE_DEFAULT") == {"FINISHED"}
    assert obj.data.multiscale.n_bands == 3
