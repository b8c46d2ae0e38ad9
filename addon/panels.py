"""View3D > Sidebar > Multiscale."""

from __future__ import annotations

import textwrap

import bpy
import numpy as np

from . import engine, keys, logic, mirror_modifier, state, storage
from .operators import morph as morph_ops


class _Panel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Multiscale"

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH"


class _Sub(_Panel):
    bl_parent_id = "POINTSCALE_PT_main"


def _why(layout, text):
    if text:
        box = layout.box()
        box.label(text=text, icon="INFO")


def _wrapped(layout, text, icon):
    """A long message as lines a narrow sidebar shows whole (a label does not wrap)."""
    for i, line in enumerate(textwrap.wrap(text, 40)):
        layout.label(text=line, icon=icon if i == 0 else "BLANK1")


class POINTSCALE_PT_main(_Panel, bpy.types.Panel):
    bl_label = "Multiscale"

    @classmethod
    def poll(cls, context):
        return True

    def draw(self, context):
        layout = self.layout
        obj = context.active_object
        problem = state.mesh_object_problem(obj)
        if problem:
            layout.label(text=problem, icon="INFO")
            return
        if not engine.available():
            layout.label(text="Engine not loaded", icon="ERROR")
            layout.label(text=engine.error() or "")
            return
        s = obj.data.multiscale
        if s.n_bands:
            problem = state.decomposed_problem(obj)
            if problem:
                _wrapped(layout.column(align=True), problem, icon="ERROR")
            else:
                layout.label(text=f"{s.n_vertices} vertices, {s.n_bands} bands", icon="CHECKMARK")


class POINTSCALE_PT_decompose(_Sub, bpy.types.Panel):
    bl_label = "Decompose"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        s = context.active_object.data.multiscale
        col = layout.column()
        col.prop(s, "levels")
        col.prop(s, "decimation")
        col.prop(s, "kernel")
        col.prop(s, "smoother")
        col.prop(s, "encoding")
        col.prop(s, "neighbors")
        col.prop(s, "keep_parts")
        col.prop(s, "thin_sheets")
        row = col.row()
        row.active = bool(mirror_modifier.mirror_modifiers(context.active_object.modifiers))
        row.prop(s, "use_mirror_modifier")
        obj = context.active_object
        if logic.uneven_scale_message(np.array(obj.matrix_world)[:3, :3], obj.name):
            _wrapped(layout.column(align=True), "Unapplied non-uniform scale: the decomposition follows the "
                     "mesh's unscaled shape. Apply Scale (Ctrl+A) to decompose the shape you see", icon="ERROR")
        row = layout.row()
        row.scale_y = 1.4
        row.operator("pointscale.decompose", icon="MOD_SMOOTH")
        if s.n_bands or storage.has_data(context.active_object.data):
            layout.operator("pointscale.clear", icon="X")


class _Decomposed(_Sub):
    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH" and obj.data.multiscale.n_bands > 0


class POINTSCALE_PT_levels(_Decomposed, bpy.types.Panel):
    bl_label = "Levels"

    def draw(self, context):
        layout = self.layout
        s = context.active_object.data.multiscale
        layout.prop(s, "scale", slider=True)
        layout.label(text=f"0 = smoothest, {s.n_bands} = original")


class POINTSCALE_PT_bands(_Decomposed, bpy.types.Panel):
    bl_label = "Bands"

    def draw(self, context):
        layout = self.layout
        obj = context.active_object
        s = obj.data.multiscale
        for item in s.bands:
            row = layout.row(align=True)
            kb = keys.get(obj.data, keys.band_name(item.index))
            if kb is None:
                row.label(text=f"Band {item.index}: key missing", icon="ERROR")
                continue
            row.prop(item, "gain", text=f"Band {item.index}", slider=True)
            masked = bool(kb.vertex_group) and obj.vertex_groups.get(kb.vertex_group) is not None
            op = row.operator("pointscale.paint_band_mask", text="", icon="BRUSH_DATA" if masked else "ADD")
            op.band = item.index
        layout.operator("pointscale.reset_bands", icon="LOOP_BACK")
        layout.operator("pointscale.bake_filter", icon="SHAPEKEY_DATA")
        row = layout.row(align=True)
        row.prop(s, "prevent_folds")
        row.prop(s, "show_folds")


class POINTSCALE_PT_deform(_Decomposed, bpy.types.Panel):
    bl_label = "Deform"

    def draw(self, context):
        layout = self.layout
        col = layout.column(align=True)
        col.operator("pointscale.edit_base", icon="EDITMODE_HLT").mode = "EDIT"
        col.operator("pointscale.edit_base", text="Sculpt Base", icon="SCULPTMODE_HLT").mode = "SCULPT"
        layout.operator("pointscale.rebuild_detail", icon="FILE_REFRESH")
        s = context.active_object.data.multiscale
        row = layout.row(align=True)
        row.prop(s, "prevent_folds")
        row.prop(s, "show_folds")


class POINTSCALE_PT_morph(_Sub, bpy.types.Panel):
    bl_label = "Morph"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        s = context.active_object.data.multiscale
        layout.prop(s, "morph_target")
        layout.prop(s, "morph_base")
        if s.morph_base == "OBJECT":
            layout.prop(s, "morph_base_object")
        else:
            layout.prop(s, "morph_samples")
        layout.prop(s, "morph_align")
        layout.operator("pointscale.morph", icon="MOD_SIMPLEDEFORM")
        _why(layout, morph_ops.morph_problem(context))


class POINTSCALE_PT_display(_Decomposed, bpy.types.Panel):
    bl_label = "Display"

    def draw(self, context):
        layout = self.layout
        s = context.active_object.data.multiscale
        row = layout.row(align=True)
        row.prop(s, "detail_band")
        row.operator("pointscale.show_details", icon="COLOR").band = min(s.detail_band, max(s.n_bands - 1, 0))


CLASSES = [
    POINTSCALE_PT_main,
    POINTSCALE_PT_decompose,
    POINTSCALE_PT_levels,
    POINTSCALE_PT_bands,
    POINTSCALE_PT_deform,
    POINTSCALE_PT_morph,
    POINTSCALE_PT_display,
]
