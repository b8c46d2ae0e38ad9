"""Clear: remove everything a decompose wrote: keys, the Basis it made, attributes, colours,
unpainted masks and the settings' state."""

from __future__ import annotations

import bpy

from .. import keys, state, storage, writeback
from ._common import set_mode


class POINTSCALE_OT_clear(bpy.types.Operator):
    """Remove everything Decompose made: the Level, Band and result keys (and the Basis it
    created, unless other keys need it), the stored decomposition, the detail colours and the
    band masks that were not painted. Other shape keys and painted masks are kept"""

    bl_idname = "pointscale.clear"
    bl_label = "Clear Multiscale Data"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        problem = state.mesh_object_problem(obj) or state.running_problem(obj)
        if problem is None and not storage.has_data(obj.data) and obj.data.multiscale.n_bands == 0:
            problem = f"'{obj.name}' has no multiscale data"
        if problem:
            cls.poll_message_set(problem)
            return False
        return True

    def execute(self, context):
        obj = context.active_object
        problem = set_mode(obj, "OBJECT")
        if problem:
            self.report({"ERROR"}, f"Clear: {problem}")
            return {"CANCELLED"}
        problem = writeback.clear_problem(obj)
        if problem:
            self.report({"ERROR"}, f"Clear: {problem}")
            return {"CANCELLED"}
        # The Basis key removed by hand: the mesh shows a level, but the finest keys still hold
        # the original shape, which a Basis gets back before the keys go.
        restored = keys.removed_basis(obj.data, obj.data.multiscale.n_bands)
        problem = keys.restore_basis(obj, obj.data.multiscale.n_bands)
        if problem:
            self.report({"ERROR"}, f"Clear: the Basis key of '{obj.name}' was removed, and {problem}: undo the "
                                   "removal (Ctrl+Z); nothing was modified")
            return {"CANCELLED"}
        if restored:
            self.report({"INFO"}, f"Clear '{obj.name}': the Basis key had been removed; put the original shape back "
                                  f"from the Level and Band keys (it was on '{restored}')")
        for note in writeback.clear(obj):
            self.report({"INFO"}, f"Clear '{obj.name}': {note}")
        return {"FINISHED"}


CLASSES = [POINTSCALE_OT_clear]
