"""Deform: edit the base (Level 0), Rebuild detail, Bake filter (Sec. 8.1-8.2)."""

from __future__ import annotations

import bpy

from .. import compute, engine, group_weights, keys, mesh_io, writeback
from ._common import DecomposedOperator, mode_problem, set_mode


def report_folds(op, obj, folds, done: str) -> None:
    """Say how many points fold (and, with Show Folds, mark them in the 'Folds' vertex group)."""
    settings = obj.data.multiscale
    marked = settings.show_folds and keys.show_folds(obj, folds.mask)
    if settings.show_folds and not marked:
        op.report({"WARNING"}, f"'{obj.name}' has a vertex group '{keys.FOLDS}' of its own, which Show Folds "
                               "leaves alone: rename it to have the folding points marked")
    if folds.count == 0:
        prevented = f" (gain limited at {int(folds.changed.sum())} points)" if settings.prevent_folds and folds.changed.any() else ""
        op.report({"INFO"}, f"{done}; no point folds{prevented}")
        return
    where = f", marked in the '{keys.FOLDS}' vertex group" if marked else ""
    hint = "" if settings.prevent_folds else "; turn on Prevent Folds, or lower the gains"
    op.report({"WARNING"}, f"{done}; {folds.count} points fold over the base{where}{hint}")


class POINTSCALE_OT_edit_base(DecomposedOperator, bpy.types.Operator):
    """Make the 'Level 0' key active and enter Edit mode: move the smooth base with any tool,
    then press Rebuild Detail"""

    bl_idname = "pointscale.edit_base"
    bl_label = "Edit Base"
    bl_options = {"REGISTER", "UNDO"}

    mode: bpy.props.EnumProperty(
        name="Mode", items=[("EDIT", "Edit", ""), ("SCULPT", "Sculpt", ""), ("OBJECT", "Object", "Only activate")],
        default="EDIT",
    )

    def execute(self, context):
        obj = self.guard(context)
        if obj is None:
            return {"CANCELLED"}
        problem = mode_problem(obj, self.mode)  # before anything changes
        if problem:
            self.report({"ERROR"}, f"Edit base: {problem}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        mesh = obj.data
        idx = mesh.shape_keys.key_blocks.find(keys.level_name(0))
        obj.active_shape_key_index = idx
        obj.show_only_shape_key = False
        mesh.multiscale.scale = 0.0  # object mode shows Level 0 too
        for name in keys.RESULTS:
            kb = keys.get(mesh, name)
            if kb is not None:
                kb.value = 0.0
        problem = set_mode(obj, self.mode)
        if problem:
            self.report({"WARNING"}, f"Edit base: 'Level 0' is active, but {problem}")
        return {"FINISHED"}


class POINTSCALE_OT_rebuild_detail(DecomposedOperator, bpy.types.Operator):
    """Carry the full detail onto the edited 'Level 0' key along its new normals
    (normals recomputed on every level) and show it as the 'Multiscale Edit' key"""

    bl_idname = "pointscale.rebuild_detail"
    bl_label = "Rebuild Detail"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        obj = self.guard(context)
        if obj is None:
            return {"CANCELLED"}
        ps = engine.get()
        mesh = obj.data
        try:
            problem = keys.result_problem(mesh, keys.EDIT, mesh.multiscale.n_bands)
            if problem:
                raise ValueError(f"'{obj.name}': {problem}")
            dec = writeback.decomposition(mesh, ps)
            base = mesh_io.read_key(keys.get(mesh, keys.level_name(0)))
            solver = writeback.reconstructor(mesh, ps)
            result, folds = compute.rebuild(solver, dec, base, prevent_folds=mesh.multiscale.prevent_folds)
        except ValueError as exc:
            self.report({"ERROR"}, f"Rebuild detail: {exc}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        writeback.show_result(obj, keys.EDIT, result)
        report_folds(self, obj, folds, "Rebuilt the detail")
        self.return_to_mode(obj)
        return {"FINISHED"}


class POINTSCALE_OT_bake_filter(DecomposedOperator, bpy.types.Operator):
    """Exact reconstruction of the current band gains and masks (normals recomputed)
    into the 'Multiscale Filter' key; the band sliders go back to gain 1"""

    bl_idname = "pointscale.bake_filter"
    bl_label = "Bake Filter"
    bl_options = {"REGISTER", "UNDO"}

    reset_bands: bpy.props.BoolProperty(
        name="Reset Bands", description="Set the band gains back to 1 after baking, so they do not apply twice",
        default=True,
    )

    def execute(self, context):
        obj = self.guard(context)
        if obj is None:
            return {"CANCELLED"}
        ps = engine.get()
        mesh = obj.data
        k = mesh.multiscale.n_bands
        try:
            problem = keys.result_problem(mesh, keys.FILTER, k)
            if problem:
                raise ValueError(f"'{obj.name}': {problem}")
            dec = writeback.decomposition(mesh, ps)
            base = mesh_io.read_key(keys.get(mesh, keys.level_name(0)))
            values = keys.band_values(mesh, k)
            weights = group_weights.read(obj, keys.band_masks(obj, k), len(mesh.vertices))
            solver = writeback.reconstructor(mesh, ps)
            result, folds = compute.bake(solver, dec, base, values, weights,
                                         prevent_folds=mesh.multiscale.prevent_folds)
        except ValueError as exc:
            self.report({"ERROR"}, f"Bake filter: {exc}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        writeback.show_result(obj, keys.FILTER, result)
        if self.reset_bands:
            for l in range(k):
                kb = keys.get(mesh, keys.band_name(l))
                if kb is not None:
                    kb.value = 0.0
        gains = ", ".join(f"{1 + v:.2f}" for v in values)
        report_folds(self, obj, folds, f"Baked gains ({gains}) into '{keys.FILTER}'")
        self.return_to_mode(obj)
        return {"FINISHED"}


CLASSES = [POINTSCALE_OT_edit_base, POINTSCALE_OT_rebuild_detail, POINTSCALE_OT_bake_filter]
