"""Add-on preferences, keyed by the package name (``bl_ext.<repo>.pointscale`` when installed)."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, FloatProperty, IntProperty

PACKAGE = __package__


class MULTISCALE_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = PACKAGE

    threads: IntProperty(
        name="Threads", description="Worker threads of the engine, 0 for all cores", default=0, min=0, max=256
    )
    poll_interval: FloatProperty(
        name="Progress Interval",
        description="Seconds between progress updates of a running decompose",
        default=0.1,
        min=0.02,
        max=2.0,
    )

    normal_attributes: BoolProperty(
        name="Level Normal Attributes",
        description="Decompose also writes each level's normals as the attributes ms_normal_<l>, for shaders "
        "and Geometry Nodes (12 bytes a vertex per band in memory and in the .blend)",
        default=False,
    )

    def draw(self, context):
        col = self.layout.column()
        col.prop(self, "threads")
        col.prop(self, "poll_interval")
        col.prop(self, "normal_attributes")


def get(context=None):
    """The preferences, or an object with the defaults when the add-on was registered by hand."""
    context = context or bpy.context
    addon = context.preferences.addons.get(PACKAGE)
    if addon is not None and addon.preferences is not None:
        return addon.preferences
    return _Defaults()


class _Defaults:
    threads = 0
    poll_interval = 0.1
    normal_attributes = False


CLASSES = [MULTISCALE_AP_preferences]
