"""Deform: edit the base (Level 0), Rebuild detail, Bake filter (Sec. 8.1-8.2)."""

from __future__ import annotations

import bpy

from .. import animation, compute, engine, group_weights, keys, mesh_io, mirror_modifier, storage, writeback
from ._common import DecomposedOperator, mode_problem, set_mode


def report_folds(op, obj, folds, done: str) -> None:
    """Say how many points fold (and, with Show Folds, mark them in the 'Folds' vertex group)."""
    settings = obj.data.multiscale
    if not settings.show_folds:
        keys.clear_fold_marks(obj)
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
            residual = compute.finest_residual(solver, dec, lambda: mesh_io.read_basis(mesh))
            result, folds = compute.rebuild(solver, dec, base, prevent_folds=mesh.multiscale.prevent_folds,
                                            residual=residual)
            k = mesh.multiscale.n_bands
            # An artist's sculpt of the last result is kept, as Decompose and Bake Filter keep theirs.
            active = obj.active_shape_key.name if obj.active_shape_key is not None else None
            kept, replaced = _keep_result(obj, keys.EDIT, keys.result_edited(mesh, keys.EDIT, keys.owned(mesh, k)))
        except ValueError as exc:
            self.report({"ERROR"}, f"Rebuild detail: {exc}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        # A bake the artist was looking at last (Edit Base shows Level 0 in between).
        filter_shown = keys.last_written_result(mesh) == keys.FILTER and keys.get(mesh, keys.FILTER) is not None
        writeback.show_result(obj, keys.EDIT, result)
        if kept and active == keys.EDIT:  # the artist goes on with the new result, not the kept one
            obj.active_shape_key_index = mesh.shape_keys.key_blocks.find(keys.EDIT)
        warn_if_scale_animated(self, mesh, "Rebuild detail")
        warn_if_mirror_changed(self, obj, dec, "Rebuild detail")
        if kept:
            self.report({"INFO"}, f"Rebuild detail: {_edits_kept(keys.EDIT, 'rebuilt', replaced)}")
        if filter_shown:
            self.report({"WARNING"}, f"Rebuild detail: '{keys.FILTER}' is switched off, and the rebuilt detail is "
                                     f"unfiltered. To filter this edit, set the band gains and press Bake Filter")
        values = keys.band_values(mesh, k)
        if any(v != 0.0 for v in values):
            self.report({"WARNING"}, f"Rebuild detail: the band gains ({_gains_text(values)}) are not in the rebuilt "
                                     f"detail: in the viewport they add their bands to it unturned, as on the "
                                     f"unedited model. Bake Filter applies them along the edit")
        report_folds(self, obj, folds, "Rebuilt the detail")
        for message in keys.layout_messages(mesh, "Rebuilt the detail"):
            self.report({"WARNING"}, message)
        self.return_to_mode(obj)
        return {"FINISHED"}


class POINTSCALE_OT_bake_filter(DecomposedOperator, bpy.types.Operator):
    """Reconstruct the current band gains and masks (normals recomputed) into the
    'Multiscale Filter' key, on top of the gains it holds while it is shown; the band sliders
    go back to gain 1"""

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
            residual = compute.finest_residual(solver, dec, lambda: mesh_io.read_basis(mesh))
            baked = _baked_gains_shown(mesh, k)
            result, folds, gains = compute.bake(solver, dec, base, values, weights,
                                                prevent_folds=mesh.multiscale.prevent_folds, baked=baked,
                                                residual=residual)
        except ValueError as exc:
            self.report({"ERROR"}, f"Bake filter: {exc}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        # A bake the viewport does not show, or one edited since (whose gains are unknown), is
        # not built on: keep it rather than write over it.
        edited = _shown(mesh, keys.FILTER) and keys.result_edited(mesh, keys.FILTER, keys.owned(mesh, k))
        try:
            kept, replaced = _keep_result(obj, keys.FILTER, baked is None)
        except ValueError as exc:  # the artist's own key of the name it would be kept under
            self.report({"ERROR"}, f"Bake filter: {exc}")
            self.return_to_mode(obj)
            return {"CANCELLED"}
        writeback.show_result(obj, keys.FILTER, result)
        warn_if_scale_animated(self, mesh, "Bake filter")
        warn_if_mirror_changed(self, obj, dec, "Bake filter")
        storage.store_baked_gains(mesh, gains, keys.key_fingerprint(mesh, keys.FILTER))
        if self.reset_bands:
            for l in range(k):
                kb = keys.get(mesh, keys.band_name(l))
                if kb is not None and not kb.mute:  # a muted band was not baked: its setting stays
                    kb.value = 0.0
            animated = [keys.band_name(l) for l in range(k) if animation.band_animated(mesh, l)]
            if animated:  # their keyframes or drivers set the value again on the next frame
                self.report({"WARNING"}, f"Bake filter: {', '.join(repr(n) for n in animated)} "
                                         f"{'is' if len(animated) == 1 else 'are'} keyframed or driven, so the value "
                                         "comes back on the next frame and the band applies twice (baked and live): "
                                         "remove the keyframes or driver, or set the slider to 0 in them")
        report_folds(self, obj, folds, f"Baked gains ({_gains_text(values)}){_on_top_text(baked)} into '{keys.FILTER}'")
        for message in keys.layout_messages(mesh, "Bake filter: baked"):
            self.report({"WARNING"}, message)
        if kept and edited:
            self.report({"INFO"}, f"Bake filter: {_edits_kept(keys.FILTER, 'baked', replaced)}; this bake starts "
                                  f"from the decomposition, not from the edited key")
        elif kept:
            self.report({"INFO"}, f"Bake filter: the earlier bake, switched off, is kept as "
                                  f"'{keys.FILTER + keys.PREVIOUS}'")
        self.return_to_mode(obj)
        return {"FINISHED"}


def _keep_result(obj, name: str, keep: bool) -> tuple:
    """Where ``keep``, renames the add-on's result key ``name`` to '<name> (previous)', switched
    off and recorded as the add-on's (keys.keep_as_previous: ValueError where the artist has a key
    of that name). Returns (kept, whether it replaced one kept before)."""
    mesh = obj.data
    replaced = keys.get(mesh, name + keys.PREVIOUS) is not None
    kept = keep and keys.keep_as_previous(obj, name, keys.owned(mesh, mesh.multiscale.n_bands))
    if kept:
        keys.add_owned(mesh, name + keys.PREVIOUS)
    return kept, replaced


def _edits_kept(name: str, since: str, replaced: bool) -> str:
    return (f"your edits of '{name}' since it was {since} are kept, switched off, as '{name + keys.PREVIOUS}'"
            f"{' (replacing the one kept before)' if replaced else ''}")


def warn_if_mirror_changed(op, obj, dec, what: str) -> None:
    """Say so where the Mirror modifiers no longer mirror the mesh as at Decompose."""
    from .decompose import _mirror_planes
    problem = now = None
    # The Basis is read only where a modifier is on (its size sets a seam without merge or clip).
    if obj.data.multiscale.use_mirror_modifier and mirror_modifier.mirror_modifiers(obj.modifiers):
        try:
            now = _mirror_planes(obj, mesh_io.read_basis(obj.data))
        except ValueError as exc:
            problem = str(exc)
    message = mirror_modifier.changed_message(dec.mirror, now, problem)
    if message:
        op.report({"WARNING"}, f"{what}: {message}")


def warn_if_scale_animated(op, mesh, what: str) -> None:
    """A result is shown alone at Scale = the band count; keyframes or a driver on Scale or on a
    Level key set the levels' mix again on the next frame, which then shows under the result."""
    if animation.scale_animated(mesh, mesh.multiscale.n_bands):
        op.report({"WARNING"}, f"{what}: the Scale slider or a Level key is keyframed or driven, so on the next "
                               "frame the levels show again under the result: remove the keyframes or driver, or "
                               f"key Scale at {mesh.multiscale.n_bands}")


def _baked_gains_shown(mesh, k: int):
    """The gains the 'Multiscale Filter' key shows, while the viewport shows it (the next bake
    multiplies into them, as the band sliders add onto it); else None. A key dialled to a value
    v shows about 1 + v (g - 1) of the gains g it was baked with (the key blends positions, and
    the positions follow the gains nearly linearly): a bake on top of a key at 0.5 took g."""
    kb = keys.get(mesh, keys.FILTER)
    if kb is None or kb.mute or kb.value == 0.0 or keys.FILTER not in keys.owned(mesh, k):
        return None
    baked = storage.baked_gains(mesh, keys.key_fingerprint(mesh, keys.FILTER))
    if baked is None or len(baked) != k:
        return None
    return baked if kb.value == 1.0 else 1.0 + kb.value * (baked - 1.0)


def _shown(mesh, name: str) -> bool:
    """Whether the result key ``name`` is there and shown (on, at a value other than 0)."""
    kb = keys.get(mesh, name)
    return kb is not None and not kb.mute and kb.value != 0.0


def _gains_text(gains) -> str:
    return ", ".join(f"{1 + v:.2f}" for v in gains)


def _on_top_text(baked) -> str:
    if baked is None:
        return ""
    if baked.ndim == 1:
        return f" on top of the earlier bake's ({_gains_text(baked - 1)})"
    return " on top of the earlier bake's painted gains"


CLASSES = [POINTSCALE_OT_edit_base, POINTSCALE_OT_rebuild_detail, POINTSCALE_OT_bake_filter]
