"""Shared poll and guard for operators that need an existing decomposition."""

from __future__ import annotations

import bpy

from .. import state


class DecomposedOperator:
    """Mixin: poll explains what is missing; execute re-checks before touching data."""

    @classmethod
    def poll(cls, context):
        problem = state.decomposed_problem(context.active_object) or state.engine_problem()
        if problem:
            cls.poll_message_set(problem)
            return False
        return True

    def guard(self, context):
        """The active object, in object mode, or None after an error report."""
        obj = context.active_object
        problem = state.decomposed_problem(obj) or state.engine_problem()
        if problem is None and obj.mode == "EDIT":
            obj.update_from_editmode()  # read the edit without leaving edit mode yet
            problem = state.decomposed_problem(obj)
        if problem is None:
            problem = state.vertex_order_problem(obj)
        if problem:
            self.report({"ERROR"}, problem)
            return None
        self.entered_mode = obj.mode
        if obj.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        return obj

    def return_to_mode(self, obj) -> None:
        """Back to the mode the artist ran the operator from (Edit, Sculpt, Weight Paint...)."""
        mode = getattr(self, "entered_mode", "OBJECT")
        if mode != "OBJECT" and obj.mode != mode:
            bpy.ops.object.mode_set(mode=mode)
