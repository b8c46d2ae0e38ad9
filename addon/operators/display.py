"""Display: detail coefficients as blue/white/red vertex colours (Fig. 2)."""

from __future__ import annotations

import bpy

from .. import logic, mesh_io, storage, writeback
from ._common import DecomposedOperator


def _show_attribute_colors(context):
    """Attribute colours in the 3D view the button was pressed in (or every 3D view when run
    from elsewhere, e.g. a script); other views keep their shading."""
    space = context.space_data
    if space is not None and space.type == "VIEW_3D":
        spaces = [space]
    elif context.screen is not None:
        spaces = [a.spaces.active for a in context.screen.areas if a.type == "VIEW_3D"]
    else:
        return
    for sp in spaces:
        if sp.shading.type != "SOLID":
            sp.shading.type = "SOLID"
        sp.shading.color_type = "VERTEX"  # shown as "Attribute" in the UI
    if context.screen is not None:
        for area in context.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


class POINTSCALE_OT_show_details(DecomposedOperator, bpy.types.Operator):
    """Colour the vertices by one band's detail coefficients: blue below the smoother level,
    white on it, red above it; the viewport switches to attribute colours"""

    bl_idname = "pointscale.show_details"
    bl_label = "Show Details"
    bl_options = {"REGISTER", "UNDO"}

    band: bpy.props.IntProperty(name="Band", min=0, default=0)
    scale: bpy.props.FloatProperty(
        name="Saturation", description="Detail that maps to full colour; 0 = the 98th percentile", min=0.0, default=0.0
    )

    def execute(self, context):
        obj = self.guard(context)
        if obj is None:
            return {"CANCELLED"}
        mesh = obj.data
        k = mesh.multiscale.n_bands
        if self.band >= k:
            self.report({"ERROR"}, f"band {self.band} does not exist: '{obj.name}' has bands 0..{k - 1}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        try:
            problem = writeback.colors_problem(mesh)
            if problem:
                raise ValueError(problem)
            d = storage.read_details(mesh, self.band)
        except ValueError as exc:
            self.report({"ERROR"}, f"Show Details on '{obj.name}': {exc}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        writeback.remember_colors(mesh)
        rgba = logic.detail_colors(d, self.scale or None)
        mesh_io.write_attribute(mesh, storage.COLOR, "FLOAT_COLOR", rgba)
        attr = mesh.color_attributes.get(storage.COLOR)
        mesh.color_attributes.active_color = attr
        mesh.color_attributes.render_color_index = mesh.color_attributes.find(storage.COLOR)
        mesh.multiscale.detail_band = self.band
        mesh.update()
        _show_attribute_colors(context)
        self.return_to_mode(obj)
        return {"FINISHED"}


CLASSES = [POINTSCALE_OT_show_details]
