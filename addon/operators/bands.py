"""Bands: paint a band's mask, reset the gains."""

from __future__ import annotations

import bpy

from .. import animation, keys
from ._common import DecomposedOperator, set_mode


class POINTSCALE_OT_paint_band_mask(DecomposedOperator, bpy.types.Operator):
    """Create or activate the band's mask vertex group ('Band l mask', or the group you picked
    as the band key's Vertex Group) and enter Weight Paint: weight 0 keeps the original there,
    1 applies the band's gain fully. A new mask starts at 1 everywhere, so paint with a lower
    weight (or Subtract) where the gain should fade out"""

    bl_idname = "pointscale.paint_band_mask"
    bl_label = "Paint Band Mask"
    bl_options = {"REGISTER", "UNDO"}

    band: bpy.props.IntProperty(name="Band", min=0)
    enter_paint: bpy.props.BoolProperty(name="Enter Weight Paint", default=True)

    def execute(self, context):
        obj = self.guard(context)
        if obj is None:
            return {"CANCELLED"}
        k = obj.data.multiscale.n_bands
        if self.band >= k:
            self.report({"ERROR"}, f"band {self.band} does not exist: '{obj.name}' has bands 0..{k - 1}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        kb = keys.get(obj.data, keys.band_name(self.band))
        if kb is None:
            self.report({"ERROR"}, f"'{obj.name}' has no key '{keys.band_name(self.band)}': Decompose again")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        picked = obj.vertex_groups.get(kb.vertex_group) if kb.vertex_group else None
        if picked is not None and picked.name != keys.mask_name(self.band):
            vg = picked  # a group the artist picked as the band's mask: painted, never replaced
            self.report({"INFO"}, f"Paint band mask: '{vg.name}', the group you picked for '{kb.name}', is its mask")
        else:
            try:
                vg = keys.ensure_mask(obj, self.band)
            except ValueError as exc:
                self.report({"ERROR"}, str(exc))
                self.return_to_mode(obj)
                return {"CANCELLED"}
        kb.vertex_group = vg.name
        obj.vertex_groups.active_index = vg.index
        if self.enter_paint and not bpy.app.background:
            problem = set_mode(obj, "WEIGHT_PAINT")
            if problem:
                self.report({"WARNING"}, f"Paint band mask: '{vg.name}' is ready, but {problem}")
                self.return_to_mode(obj)
        else:  # the mask is ready; the artist stays where they were (Edit, Sculpt...)
            self.return_to_mode(obj)
        return {"FINISHED"}


class POINTSCALE_OT_reset_bands(DecomposedOperator, bpy.types.Operator):
    """Set every band gain back to 1 (the original detail); masks are kept"""

    bl_idname = "pointscale.reset_bands"
    bl_label = "Reset Gains"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        obj = self.guard(context)
        if obj is None:
            return {"CANCELLED"}
        animated = []
        for l in range(obj.data.multiscale.n_bands):
            kb = keys.get(obj.data, keys.band_name(l))
            if kb is not None:
                kb.value = 0.0
                if animation.band_animated(obj.data, l):
                    animated.append(kb.name)
        if animated:  # their keyframes or drivers set the gain again on the next frame
            self.report({"WARNING"}, f"Reset gains: {', '.join(repr(n) for n in animated)} "
                                     f"{'is' if len(animated) == 1 else 'are'} keyframed or driven, so the gain "
                                     "comes back on the next frame: remove the keyframes or driver to keep it at 1")
        self.return_to_mode(obj)
        return {"FINISHED"}


CLASSES = [POINTSCALE_OT_paint_band_mask, POINTSCALE_OT_reset_bands]
