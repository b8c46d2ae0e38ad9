"""Morph (Eq. 22, Fig. 9-10a): a new object whose keys 'A detail' and 'B detail' are alpha and beta."""

from __future__ import annotations

import bpy
import numpy as np

from .. import animation, compute, engine, keys, logic, mesh_io, state, storage, writeback
from ._background import RunsInBackground
from ._common import set_mode


def _world_points(obj, into):
    """Basis of ``obj`` in the local space of ``into``, with edits still in its Edit mode."""
    if obj.mode == "EDIT":
        obj.update_from_editmode()  # B or the base in Edit mode with A active: read what is shown
    co = mesh_io.read_basis(obj.data).astype(np.float64)
    m = np.array(into.matrix_world.inverted() @ obj.matrix_world)
    return co @ m[:3, :3].T + m[:3, 3]


def _shown_points(context, obj, into):
    """The vertices of ``obj`` as the viewport shows it (its shape keys and modifiers applied: a
    half under a Mirror modifier is read whole, a key at 1 with its shape), in the local space of
    ``into``, and what of it differs from its Basis (for the report)."""
    if obj.mode == "EDIT":
        obj.update_from_editmode()
    evaluated = obj.evaluated_get(context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    try:
        co = mesh_io.read_vertices(mesh).astype(np.float64)
    finally:
        evaluated.to_mesh_clear()
    m = np.array(into.matrix_world.inverted() @ obj.matrix_world)
    return co @ m[:3, :3].T + m[:3, 3], _shown_changes(obj)


def _shown_changes(obj) -> list:
    """What the viewport shows of ``obj`` other than its Basis: its shape keys in play and its
    modifiers, named for the report."""
    out = []
    kbs = keys.key_blocks(obj.data)
    if kbs is not None:
        reference = obj.data.shape_keys.reference_key
        if obj.show_only_shape_key:  # Shape Key Lock: the active key alone, at full
            playing = [obj.active_shape_key] if obj.active_shape_key not in (None, reference) else []
        else:
            playing = [kb for kb in kbs if kb != reference and not kb.mute and kb.value != 0.0]
        out += [f"shape key '{kb.name}'" for kb in playing]
    return out + [f"modifier '{modifier.name}'" for modifier in obj.modifiers if modifier.show_viewport]


def _mirror_seams(obj, points) -> list:
    """[(axis, plane coordinate, vertices on the plane)] of ``obj``'s Mirror modifiers, as
    Decompose reads them, in its own coordinates: the morph object keeps A's modifiers, and a
    seam vertex the morph moved off the plane would no longer merge with its reflection (a half
    model tore down the middle). Empty without Mirror modifiers, with Use Mirror Modifier off,
    or where Decompose could not honour them (it says why)."""
    from .decompose import _mirror_planes

    try:
        planes = _mirror_planes(obj, points)
    except ValueError:
        return []
    if planes is None:
        return []
    out = []
    for a in planes.axes:
        axis = "xyz".index(a)
        on_plane = np.abs(points[:, axis] - planes.origin[axis]) <= planes.seam
        if on_plane.any():
            out.append((axis, float(planes.origin[axis]), on_plane))
    return out


def morph_problem(context):
    obj = context.active_object
    problem = state.mesh_object_problem(obj) or state.engine_problem() or state.removed_basis_problem(obj)
    if problem:  # (with A's Basis key removed, its reference key is a smooth level, not its shape)
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
    for o, role in ((obj, "A"), (target, "target B")):
        if abs(o.matrix_world.to_3x3().determinant()) < 1e-12:
            return (f"{role} '{o.name}' has a zero scale (or its parent has): it has no shape to morph. Give it a "
                    "scale on every axis (Object > Transform)")
    if s.morph_base == "OBJECT" and len(s.morph_base_object.data.vertices) == 0:
        return f"The base mesh '{s.morph_base_object.name}' has no vertices"
    return None


def own_shape_keys(mesh) -> list:
    """The names of the artist's shape keys on A's mesh, which the morph object leaves out: every
    key but the Basis and those the add-on made (its decomposition's)."""
    kbs = keys.key_blocks(mesh)
    if kbs is None:
        return []
    mine = keys.owned(mesh, mesh.multiscale.n_bands)
    reference = mesh.shape_keys.reference_key
    return [kb.name for kb in kbs if kb != reference and kb.name not in mine]


def _new_morph_object(context, a_obj, b_obj, p0, pa, pb):
    """The morph object: a copy of A (its modifiers, constraints, materials and parent, as
    Duplicate gives) on a copy of A's mesh at p0 with the keys 'A detail' and 'B detail', linked
    where the view layer shows it, active and selected. On failure it is removed again."""
    mesh = a_obj.data.copy()
    mesh.name = f"{a_obj.name} x {b_obj.name}"
    obj = a_obj.copy()
    obj.data = mesh
    obj.name = mesh.name
    copies = []
    try:
        copies = [c for c in (animation.own_action(obj), animation.own_action(mesh)) if c is not None]
        if mesh.shape_keys is not None:
            obj.shape_key_clear()
        _drop_decomposition(obj)
        animation.drop_curves(mesh, "multiscale.")  # A's gain and Scale sliders: none here
        mesh_io.write_vertices(mesh, p0)
        obj.show_only_shape_key = False  # A's Shape Key Lock would hide the morph's keys
        _shown_collection(context, a_obj).objects.link(obj)
        keys.ensure_basis(obj)
        ka = keys.ensure_key(obj, "A detail", pa, slider=(-1.0, 2.0))
        kb = keys.ensure_key(obj, "B detail", pb, slider=(-1.0, 2.0))
        ka.value, kb.value = 1.0, 0.0
        mesh.update()
        for o in context.selected_objects:
            o.select_set(False)
        obj.select_set(True)
        context.view_layer.objects.active = obj
    except Exception:
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
        for action in copies:
            bpy.data.actions.remove(action)
        raise
    return obj


def _drop_decomposition(obj) -> None:
    """The copy of A's mesh carries A's decomposition: remove exactly what the add-on made on A
    (its attributes by name, the vertex groups and ID properties it recorded) and the morph
    settings; the artist's own data of any name stays."""
    mesh = obj.data
    groups = keys.owned_groups(mesh, mesh.multiscale.n_bands)
    writeback.drop_detail_colors(mesh)
    storage.clear(mesh)
    for name in groups:
        vg = obj.vertex_groups.get(name)
        if vg is not None:
            obj.vertex_groups.remove(vg)
    for prop in writeback.ID_PROPERTIES:
        if prop in mesh.keys():
            del mesh[prop]
    mesh.multiscale.morph_target = None
    mesh.multiscale.n_bands = 0
    mesh.multiscale.n_vertices = 0
    mesh.multiscale.bands.clear()


def _shown_collection(context, a_obj):
    """Where the morph goes: beside A, in the first of A's collections the view layer includes,
    else the active collection, else the scene's."""
    included = _included_collections(context.view_layer.layer_collection)
    for collection in a_obj.users_collection:
        if collection in included:
            return collection
    if context.collection is not None and context.collection in included:
        return context.collection
    return context.scene.collection


def _included_collections(layer_collection) -> set:
    """The collections under ``layer_collection`` that the view layer does not exclude."""
    found = set()
    if layer_collection.exclude:
        return found
    found.add(layer_collection.collection)
    for child in layer_collection.children:
        found |= _included_collections(child)
    return found


class POINTSCALE_OT_morph(RunsInBackground, bpy.types.Operator):
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

    def _prepare(self, context):
        """Reads A, B and the base on the main thread: (a, b, base, settings) or None after a report."""
        problem = morph_problem(context)
        if problem:
            self.report({"ERROR"}, problem)
            return None
        a_obj = context.active_object
        problem = set_mode(a_obj, "OBJECT")
        if problem:
            self.report({"ERROR"}, f"Morph: {problem}")
            return None
        s = a_obj.data.multiscale
        b_obj = s.morph_target or next(o for o in context.selected_objects if o is not a_obj and o.type == "MESH")
        self._names = (a_obj.name, b_obj.name, s.morph_base_object.name if s.morph_base == "OBJECT" else None)
        self._a_uid, self._b_uid = a_obj.session_uid, b_obj.session_uid  # names can change during the job
        a = mesh_io.read_basis(a_obj.data).astype(np.float64)
        self._seams = _mirror_seams(a_obj, a)
        b, self._b_shown = _shown_points(context, b_obj, a_obj)  # B as the artist sees it
        base = _world_points(s.morph_base_object, a_obj) if s.morph_base == "OBJECT" else None
        return a, b, base, (s.morph_samples, s.morph_align)

    # --- synchronous: scripts, background mode, redo
    def execute(self, context):
        prepared = self._prepare(context)
        if prepared is None:
            return {"CANCELLED"}
        a, b, base, (samples, align) = prepared
        try:
            # No progress callback: the engine may call it from its own threads, and bpy must
            # only be touched from the main thread.
            result = compute.morph_keys(engine.get(), a, b, base, samples, align)
        except ValueError as exc:
            self.report({"ERROR"}, self.failed(exc))
            return {"CANCELLED"}
        return self.finished(context, result)

    # --- modal: the UI button (_background.py); A and B may be large (a 437k-vertex A takes
    # seconds), and the morph writes nothing until it is done.
    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return self.start_in_background(context)

    def start_in_background(self, context):
        prepared = self._prepare(context)
        if prepared is None:
            return {"CANCELLED"}
        a, b, base, (samples, align) = prepared
        ps = engine.get()
        return self.start(context, lambda progress: compute.morph_keys(ps, a, b, base, samples, align, progress),
                          what=f"morphing '{self._names[0]}' towards '{self._names[1]}' ({len(a)} vertices)",
                          name="pointscale-morph", cancelled_type=engine.cancelled_type())

    cancelled_report = "Create Morph cancelled; nothing was made"

    def failed(self, error) -> str:
        if isinstance(error, ValueError):  # the engine's keywords for A, B and the base, in the panel's terms
            return f"Morph: {logic.morph_message(str(error), *self._names)}"
        return f"Morph: {error}"

    def finished(self, context, result):
        p0, pa, pb, messages = result
        by_uid = {o.session_uid: o for o in bpy.data.objects}
        a_obj, b_obj = by_uid.get(self._a_uid), by_uid.get(self._b_uid)
        if a_obj is None or b_obj is None or a_obj.type != "MESH" or len(a_obj.data.vertices) != len(p0):
            self.report({"ERROR"}, f"Morph: '{self._names[0]}' or '{self._names[1]}' changed or disappeared while "
                                   "the morph was computed; nothing was made")
            return {"CANCELLED"}
        seams = getattr(self, "_seams", ())
        for axis, origin, on_plane in seams:  # A's copy keeps A's Mirror modifier: its seam must stay merged
            for p in (p0, pa, pb):
                p[on_plane, axis] = origin
        try:
            obj = _new_morph_object(context, a_obj, b_obj, p0, pa, pb)
        except (RuntimeError, ValueError) as exc:  # Blender refused a step: nothing half-made stays
            self.report({"ERROR"}, f"Morph: could not make the new object: {str(exc).strip()}")
            return {"CANCELLED"}
        for message in messages:
            self.report({"WARNING"}, f"Morph: {message}")
        dropped = own_shape_keys(a_obj.data)
        if dropped:
            self.report({"WARNING"}, f"Morph: A's own shape keys are not carried to '{obj.name}': "
                                     f"{', '.join(repr(name) for name in dropped)} (the morph is made from A's Basis "
                                     f"and has the keys 'A detail' and 'B detail' only; '{a_obj.name}' keeps them)")
        b_shown = getattr(self, "_b_shown", ())
        if b_shown:
            self.report({"INFO"}, f"Morph: the target '{b_obj.name}' is read as shown, with its {', '.join(b_shown)}")
        self.report({"INFO"}, f"Morph '{obj.name}': set 'A detail' (alpha) and 'B detail' (beta) to blend")
        return {"FINISHED"}


CLASSES = [POINTSCALE_OT_morph]
