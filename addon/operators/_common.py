"""Shared poll and guard for operators that need an existing decomposition."""

from __future__ import annotations

import bpy

from .. import state


def mode_problem(obj, mode: str) -> str | None:
    """Why Blender would refuse to put ``obj`` in ``mode`` (it edits, sculpts and paints only
    visible objects), or None."""
    if mode == "OBJECT" or obj.mode == mode or obj.visible_get():
        return None
    shown = mode.replace("_", " ").title()
    return f"'{obj.name}' is hidden: unhide it (Alt+H in the viewport) to enter {shown} mode"


def set_mode(obj, mode: str) -> str | None:
    """Puts ``obj`` (the active object) in ``mode``; Blender's refusal comes back as a message
    for a report instead of a traceback."""
    problem = mode_problem(obj, mode)
    if problem:
        return problem
    if obj.mode == mode:
        return None
    try:
        bpy.ops.object.mode_set(mode=mode)
    except RuntimeError as exc:
        return f"'{obj.name}' could not enter {mode.replace('_', ' ').title()} mode: {str(exc).strip()}"
    return None


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
        problem = set_mode(obj, "OBJECT")
        if problem:
            self.report({"ERROR"}, problem)
            return None
        return obj

    def return_to_mode(self, obj) -> None:
        """Back to the mode the artist ran the operator from (Edit, Sculpt, Weight Paint...)."""
        mode = getattr(self, "entered_mode", "OBJECT")
        if mode != "OBJECT" and obj.mode != mode:
            problem = set_mode(obj, mode)
            if problem:
                self.report({"WARNING"}, problem)
