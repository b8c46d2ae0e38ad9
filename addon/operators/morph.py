"""Morph (Eq. 22, Fig. 9-10a): a new object whose keys 'A detail' and 'B detail' are alpha and beta."""

from __future__ import annotations

import bpy
import numpy as np

from .. import compute, engine, keys, mesh_io, state
from ._common import set_mode


def _world_points(obj, into):
    """Basis of ``obj`` in the local space of ``into``, with edits still in its Edit mode."""
    if obj.mode == "EDIT":
        obj.update_from_editmode()  # B or the base in Edit mode with A active: read what is shown
    co = mesh_io.read_basis(obj.data).astype(np.float64)
    m = np.array(into.matrix_world.inverted() @ obj.matrix_world)
    return co @ m[:3, :3].T + m[:3, 3]


def morph_problem(context):
    obj = context.active_object
    problem = state.mesh_object_problem(obj) or state.engine_problem()
    if problem:
        return problem
    s = obj.data.multiscale
    target = s.morph_target or next(
        (o for o in context.selected_objects if o is not obj and o.type == "MESH"), None
    )
    if target is None:
        return "Choose a target mesh (B) in the Morph panel, or select it with A active"
    if target.type != "MESH" or target.data == obj.data:
        return "The morph target must be another mesh object"
    if s.morph_base == "OBJECT" and (s.morph_base_object is None or s.morph_base_object.type != "MESH"):
        return "Choose a base mesh, or use the automatic ellipsoid"
    if len(target.data.vertices) == 0:
        return f"The morph target '{target.name}' has no vertices"
    if s.morph_base == "OBJECT" and len(s.morph_base_object.data.vertices) == 0:
        return f"The base mesh '{s.morph_base_object.name}' has no vertices"
    return None


class POINTSCALE_OT_morph(bpy.types.Operator):
    """Create a new object: A projected onto a common base, with relative keys 'A detail' (alpha)
    and 'B detail' (beta); A and B are not modified"""

    bl_idname = "pointscale.morph"
    bl_label = "Create Morph"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        problem = morph_problem(context)
        if problem:
            cls.poll_message_set(problem)
            return False
        return True

    def execute(self, context):
        problem = morph_problem(context)
        if problem:
            self.report({"ERROR"}, problem)
            return {"CANCELLED"}
        a_obj = context.active_object
        problem = set_mode(a_obj, "OBJECT")
        if problem:
            self.report({"ERROR"}, f"Morph: {problem}")
            return {"CANCELLED"}
        s = a_obj.data.multiscale
        b_obj = s.morph_target or next(o for o in context.selected_objects if o is not a_obj and o.type == "MESH")
        a = mesh_io.read_basis(a_obj.data).astype(np.float64)
        b = _world_points(b_obj, a_obj)
        base = _world_points(s.morph_base_object, a_obj) if s.morph_base == "OBJECT" else None
        try:
            p0, pa, pb, messages = compute.morph_keys(engine.get(), a, b, base, s.morph_samples, s.morph_align)
        except ValueError as exc:
            self.report({"ERROR"}, f"Morph: {exc}")
            return {"CANCELLED"}
        mesh = a_obj.data.copy()
        mesh.name = f"{a_obj.name} x {b_obj.name}"
        obj = bpy.data.objects.new(mesh.name, mesh)
        if mesh.shape_keys is not None:
            obj.shape_key_clear()
        for name in [a.name for a in mesh.attributes if a.name.startswith((".ps.", "ms_"))]:
            mesh.attributes.remove(mesh.attributes[name])
        for prop in ("pointscale", keys.OWNED):
            if prop in mesh.keys():
                del mesh[prop]
        # The copy carries A's vertex groups (stored on the mesh) and morph settings: drop the
        # band masks and the target, which belong to A's decomposition.
        for vg in [g for g in obj.vertex_groups if g.name.startswith("Band ") and g.name.endswith(" mask")]:
            obj.vertex_groups.remove(vg)
        mesh.multiscale.morph_target = None
        mesh.multiscale.n_bands = 0
        mesh.multiscale.n_vertices = 0
        mesh.multiscale.bands.clear()
        mesh_io.write_vertices(mesh, p0)
        obj.matrix_world = a_obj.matrix_world.copy()
        (a_obj.users_collection[0] if a_obj.users_collection else context.scene.collection).objects.link(obj)
        keys.ensure_basis(obj)
        ka = keys.ensure_key(obj, "A detail", pa, slider=(-1.0, 2.0))
        kb = keys.ensure_key(obj, "B detail", pb, slider=(-1.0, 2.0))
        ka.value, kb.value = 1.0, 0.0
        mesh.update()
        for o in context.selected_objects:
            o.select_set(False)
        obj.select_set(True)
        context.view_layer.objects.active = obj
        for message in messages:
            self.report({"WARNING"}, f"Morph: {message}")
        self.report({"INFO"}, f"Morph '{obj.name}': set 'A detail' (alpha) and 'B detail' (beta) to blend")
        return {"FINISHED"}


CLASSES = [POINTSCALE_OT_morph]
