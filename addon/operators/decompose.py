"""Decompose: the mesh's Basis -> Level/Band keys, masks and attributes.

From the UI (invoke) it runs in a worker thread under a modal operator, with
progress, status text and Esc to cancel.  From scripts and in background
mode (execute) it runs synchronously.  Either way every bpy write happens on
the main thread, and only after the engine has finished, so a cancel or an
error leaves the mesh exactly as it was.
"""

from __future__ import annotations

import bpy
import numpy as np

from .. import compute, engine, keys, mesh_io, mirror_modifier, preferences, state, storage, writeback
from ._background import RunsInBackground
from ._common import set_mode


def _problem(context):
    obj = context.active_object
    problem = state.mesh_object_problem(obj) or state.engine_problem()
    if problem is None:
        problem = state.running_problem(obj) or state.removed_basis_problem(obj)
    return problem


def _mirror_planes(obj, points):
    """The planes of the mesh's Mirror modifiers in its own coordinates, or None when there is
    none (or Use Mirror Modifier is off); ValueError when their settings cannot be honoured."""
    modifiers = mirror_modifier.mirror_modifiers(obj.modifiers)
    if not modifiers or not obj.data.multiscale.use_mirror_modifier:
        return None
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    found = []
    for modifier in modifiers:
        to_mirror_space = None
        if modifier.mirror_object is not None:
            if abs(modifier.mirror_object.matrix_world.to_3x3().determinant()) < 1e-12:
                raise ValueError(f"the Mirror Object '{modifier.mirror_object.name}' of modifier '{modifier.name}' has a "
                                 "zero scale, so it has no mirror plane: give it a scale on every axis")
            # Blender mirrors in the mirror object's space: the mesh's coordinates -> world -> its.
            to_mirror_space = np.array(modifier.mirror_object.matrix_world.inverted() @ obj.matrix_world)
        bisects = any(b and a for b, a in zip(modifier.use_bisect_axis, modifier.use_axis))
        planes, problem = mirror_modifier.mirror_planes(
            tuple(modifier.use_axis), modifier.use_mirror_merge, modifier.use_clip, modifier.merge_threshold,
            diagonal, to_mirror_space, modifier.bisect_threshold if bisects else 0.0)
        if problem:
            raise ValueError(f"{problem} (modifier '{modifier.name}')")
        found.append(planes)
    planes, problem = mirror_modifier.combined(found)
    if problem:
        raise ValueError(f"{problem} (modifiers {', '.join(repr(m.name) for m in modifiers)})")
    return planes


def _mirror_signature(obj) -> tuple:
    """What of an object's Mirror modifiers decides the planes Decompose reads (_mirror_planes)."""
    return tuple((tuple(m.use_axis), m.mirror_object.name if m.mirror_object else None, m.use_mirror_merge,
                  m.use_clip, round(m.merge_threshold, 9)) for m in mirror_modifier.mirror_modifiers(obj.modifiers))


def _mirrored_otherwise_message(obj) -> str | None:
    """The note for other objects sharing the mesh (linked duplicates) whose Mirror modifiers
    differ from obj's: the decomposition follows obj's, and the others' seams may tear."""
    if obj.data.users < 2:
        return None
    mine = _mirror_signature(obj)
    others = [o.name for o in bpy.data.objects if o.data == obj.data and o != obj and _mirror_signature(o) != mine]
    if not others:
        return None
    return (f"{', '.join(repr(n) for n in others)} {'shares' if len(others) == 1 else 'share'} this mesh but "
            f"{'mirrors' if len(others) == 1 else 'mirror'} it otherwise (Mirror modifiers): the decomposition "
            f"follows those of '{obj.name}', so a seam mirrored only there may tear; decompose from the object "
            "whose Mirror modifier the mesh is made for")


def _levels_that_fit(ps, n, levels, decimation, parts=False):
    """logic.levels_that_fit with the engine's least level 0, and the one it calls safe (a
    coarser base can be distorted) for the hint."""
    return compute.logic.levels_that_fit(n, levels, decimation, ps.multiscale.MIN_COARSE_POINTS, parts=parts,
                                         safe=getattr(ps.multiscale, "FEW_COARSE_POINTS", 100))


def _largest_part(ps, points, edges) -> int:
    """The vertex count of the part whose size bounds the levels when Keep Parts Apart
    decomposes each part alone: the largest that spans a surface (a flat ground under a rock
    keeps no bands, however large), else the largest."""
    labels, count = ps.parts.connected_parts(points, edges=edges)
    sizes = np.bincount(labels, minlength=count)
    leading = ps.parts.leading_part(points, labels, count)
    return int(sizes[leading] if leading is not None else sizes.max())


def _prepare(op, context):
    """Read the input on the main thread: (points, kwargs) or None after a report."""
    obj = context.active_object
    if obj.mode == "EDIT":
        obj.update_from_editmode()  # read the edit; the mode changes only when results are written
    mesh = obj.data
    points = mesh_io.read_basis(mesh)
    s = mesh.multiscale
    ps = engine.get()
    try:
        kwargs = compute.decompose_kwargs(
            s.levels, s.decimation, s.kernel, s.neighbors, preferences.get(context).threads, s.smoother, s.encoding
        )
        problem = compute.logic.check_points(points)
        if problem:
            raise ValueError(problem)
        op._input_notes = []
        # Decompose works on the active object, with its mesh's settings, as every other operator
        # of the add-on: other selected objects are named, not decomposed with settings not theirs.
        op._others = [o.name for o in context.selected_objects if o != obj and o.type == "MESH" and o.data != mesh]
        if s.keep_parts and len(mesh.edges):
            kwargs["edges"] = mesh_io.read_edges(mesh)
            op._input_notes.append(compute.logic.loose_vertices_message(len(points), kwargs["edges"]))
        op._input_notes.append(compute.logic.uneven_scale_message(np.array(obj.matrix_world)[:3, :3], obj.name))
        op._input_notes.append(_mirrored_otherwise_message(obj))
        op._input_notes.append(compute.logic.unapplied_modifiers_message(
            [(m.name, m.type) for m in obj.modifiers
             if m.show_viewport and not (m.type == "MIRROR" and s.use_mirror_modifier)], obj.name))
        # A mesh too small for the levels asked gets the levels it supports, and is told how to
        # get the rest; the panel's setting stays as the artist set it. With Keep Parts Apart
        # its largest part is what has to support them: found here for a mesh too small as a
        # whole, else only when the engine refuses them (_decompose_fitting_parts; the names
        # checked below for these levels include those of fewer).
        asked = kwargs["levels"]
        kwargs["levels"], op._levels_note = _levels_that_fit(ps, len(points), asked, kwargs["decimation"])
        largest = _largest_part(ps, points, kwargs["edges"]) if op._levels_note and "edges" in kwargs else len(points)
        if largest < len(points):
            kwargs["levels"], op._levels_note = _levels_that_fit(ps, largest, asked, kwargs["decimation"], parts=True)
        op._levels_fitted = kwargs["levels"]
        k = kwargs["levels"] - 1
        problem = _names_taken(context, obj, k)
        if problem:
            raise ValueError(problem)
        # Normals orient level 0 (and tell the sides of thin sheets): an imported point cloud's
        # own, else, for thin sheets, the faces' vertex normals.
        normals = mesh_io.read_imported_normals(mesh)
        if normals is not None:
            unusable = int((~np.isfinite(normals).all(axis=1) | (np.abs(normals).max(axis=1) == 0)).sum())
            if unusable:
                raise ValueError(f"its point attribute 'normal' (read as the vertices' normals, as Blender's PLY "
                                 f"importer gives a point cloud its file's) has {unusable} of {len(normals)} vectors "
                                 "zero or not a number: fill them, or remove the attribute to let Decompose "
                                 "estimate the normals")
        if normals is None and s.thin_sheets:
            normals = mesh_io.read_vertex_normals(mesh)
            if normals is not None:  # the faces' normals tell the sides: they must agree
                op._input_notes.append(compute.logic.winding_message(
                    compute.logic.faces_wound_against_neighbours(*mesh_io.read_faces(mesh)), len(mesh.polygons)))
        if normals is not None:
            kwargs["normals"] = normals
        if s.thin_sheets:
            kwargs["sheets"] = True
        planes = _mirror_planes(obj, points)
        op._mirror_note = None
        if planes is not None:
            kwargs["mirror"] = ps.Mirror(planes.axes, planes.origin, planes.seam)
            op._mirror_note = f"symmetric about {planes.describe()}"
    except ValueError as exc:
        op.report({"ERROR"}, f"Decompose '{obj.name}': {exc}")
        return None
    return points, kwargs


def _computed(ps, points, kwargs, progress=None):
    """Everything but the bpy writes, in the worker thread under the modal: the engine, then the
    keys' float32 arrays and the recipe (the Basis the engine saw and its settings, which the
    .blend keeps to decompose again)."""
    try:
        layout, kwargs = _decompose_fitting_parts(ps, points, kwargs, progress)
    except ValueError as exc:  # the engine's words for Keep Parts Apart, in the panel's
        raise ValueError(compute.logic.engine_message(str(exc), kwargs["neighbors"], kwargs["levels"])) from None
    return layout, writeback.key_data(layout, points, kwargs, ps.__version__)


def _decompose_fitting_parts(ps, points, kwargs, progress):
    """compute.decompose: (layout, the settings it used). With Keep Parts Apart each part is
    decomposed alone, and the engine refuses levels that its largest part cannot support; then
    the levels that part supports are used, and a warning says so. The parts are found only
    then: finding them costs 1.8 s at 1M vertices (as much again as the engine spends on them)."""
    try:
        return compute.decompose(ps, points, progress=progress, **kwargs), kwargs
    except ValueError as exc:
        if "edges" not in kwargs or not compute.logic.is_parts_refusal(str(exc)):
            raise
        refusal = exc
    levels, note = _levels_that_fit(ps, _largest_part(ps, points, kwargs["edges"]), kwargs["levels"],
                                   kwargs["decimation"], parts=True)
    if levels >= kwargs["levels"]:
        raise refusal
    kwargs = dict(kwargs, levels=levels)
    layout = compute.decompose(ps, points, progress=progress, **kwargs)
    layout.warnings = (note,) + tuple(layout.warnings)
    return layout, kwargs


def _changed_meanwhile(context, obj, points, k) -> str | None:
    """What the artist changed while the job ran that writing its result would lose or take
    over (the UI stays live): the Basis it read, or a key, group or attribute now named as the
    results are. None when nothing was."""
    if obj.type != "MESH" or len(obj.data.vertices) != len(points):
        return "the mesh changed while it was being decomposed"
    if obj.mode == "EDIT":
        obj.update_from_editmode()  # an edit in progress counts
    mesh = obj.data
    if not np.array_equal(mesh_io.read_basis(mesh), points):
        return "its vertices moved while it was being decomposed (decompose again to use them)"
    return _names_taken(context, obj, k)


def _names_taken(context, obj, k) -> str | None:
    """Only what the add-on made may be written over: an artist's key, vertex group or
    attribute with one of the names a decomposition of k bands writes is refused, not taken over."""
    mesh = obj.data
    n_bands = mesh.multiscale.n_bands
    return (keys.layout_problem(mesh, k, n_bands) or keys.groups_problem(obj, k, n_bands)
            or storage.attributes_problem(mesh, k, preferences.get(context).normal_attributes))


class POINTSCALE_OT_decompose(RunsInBackground, bpy.types.Operator):
    """Split the mesh into a smooth base and detail bands (Level and Band shape keys).
    The Basis is read, never modified; faces are kept but not used"""

    bl_idname = "pointscale.decompose"
    bl_label = "Decompose"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        problem = _problem(context)
        if problem:
            cls.poll_message_set(problem)
            return False
        return True

    # --- synchronous: scripts, background mode, redo
    def execute(self, context):
        prepared = _prepare(self, context)
        if prepared is None:
            return {"CANCELLED"}
        points, kwargs = prepared
        obj = context.active_object
        try:
            # No progress callback: the engine may call it from its own threads,
            # and bpy must only be touched from the main thread.
            result = _computed(engine.get(), points, kwargs)
        except ValueError as exc:
            self.report({"ERROR"}, f"Decompose '{obj.name}': {exc}")
            return {"CANCELLED"}
        return self._finish(context, obj, result, points)

    def _finish(self, context, obj, result, points):
        layout, data = result
        n = len(points)
        if obj.type != "MESH" or len(obj.data.vertices) != n:
            self.report({"ERROR"}, f"'{obj.name}' changed while it was being decomposed; nothing was written")
            return {"CANCELLED"}
        # Edit, Sculpt or Weight Paint on a key that is about to change: leave it first.
        problem = set_mode(obj, "OBJECT")
        if problem:
            self.report({"ERROR"}, f"Decompose: {problem}; nothing was written")
            return {"CANCELLED"}
        # Keys of the earlier decomposition renamed to names of the artist's stay, and so does
        # their value: over the new decomposition they apply again.
        layout_names = {keys.level_name(l) for l in range(layout.k)} | {keys.band_name(l) for l in range(layout.k)}
        renamed = [(keys.get(obj.data, name), was) for name, was in keys.renamed_layout_keys(obj.data)
                   if name not in layout_names]
        applied = [(kb.name, was, kb.value) for kb, was in renamed if not kb.mute and kb.value != 0.0]
        # What the earlier bands' sliders and masks were, for the artist: the new bands start at
        # gain 1, and a mask stays with its band's number, whatever frequencies that band now holds.
        old_k = obj.data.multiscale.n_bands if storage.has_data(obj.data) else 0
        old_gains = keys.band_values(obj.data, old_k)
        old_masks = keys.band_masks(obj, old_k)
        kept = writeback.apply_layout(obj, layout, basis=points, data=data)
        k = layout.k
        if any(v != 0.0 for v in old_gains):
            self.report({"INFO"}, f"Decompose '{obj.name}': the band gains ({', '.join(f'{1 + v:.2f}' for v in old_gains)}) "
                                  "were the earlier bands'; the new bands start at gain 1 (Bake Filter before "
                                  "decomposing again keeps a filter's look)")
        moved = [name for l, name in enumerate(old_masks) if name and l < k
                 and keys.get(obj.data, keys.band_name(l)) is not None
                 and keys.get(obj.data, keys.band_name(l)).vertex_group == name]
        if moved and k != old_k:
            self.report({"WARNING"}, f"Decompose '{obj.name}': {', '.join(repr(n) for n in moved)} "
                                     f"{'masks' if len(moved) == 1 else 'mask'} the band of the same number among "
                                     f"{k} bands, painted for one among {old_k}: the frequencies it covers changed "
                                     "(Band 0 is the coarsest). Repaint it, or pick another group for the band key")
        for name, was, value in applied:
            self.report({"WARNING"}, f"Decompose '{obj.name}': {name!r} holds the earlier decomposition's {was!r} "
                                     f"(renamed) and still applies, at {value:g}, over the new one: set it to 0 "
                                     "or delete it")
        if keys.BASE_PREVIOUS in kept:
            self.report({"INFO"}, f"Decompose '{obj.name}': the earlier 'Level 0', changed since it was written (an "
                                  "edit, or a change of the Basis or of the mesh that Blender carried into it), is "
                                  f"kept as '{keys.BASE_PREVIOUS}', switched off (the new 'Level 0' is the new "
                                  "decomposition's)")
        copies = [name for name in kept if keys.is_edited_layout_copy(name)]
        if copies:
            self.report({"INFO"}, f"Decompose '{obj.name}': your edits of other levels and bands are kept as "
                                  f"{', '.join(repr(name) for name in copies)}, switched off")
        results = [name for name in kept if name != keys.BASE_PREVIOUS and name not in copies]
        if results:
            self.report({"INFO"}, f"Decompose '{obj.name}': the earlier results are kept as "
                                  f"{', '.join(repr(name) for name in results)}, switched off")
        for message in layout.warnings:
            self.report({"WARNING"}, f"Decompose '{obj.name}': {message}")
        for message in getattr(self, "_input_notes", ()):
            if message:
                self.report({"WARNING"}, f"Decompose '{obj.name}': {message}")
        # The whole mesh's note, unless its largest part had fewer levels still (in layout.warnings).
        if getattr(self, "_levels_note", None) and k + 1 == getattr(self, "_levels_fitted", k + 1):
            self.report({"WARNING"}, f"Decompose '{obj.name}': {self._levels_note}")
        if getattr(self, "_mirror_note", None):
            self.report({"INFO"}, f"Decompose '{obj.name}': {self._mirror_note}")
        self.report({"INFO"}, f"Decomposed '{obj.name}': {n} vertices, {k + 1} levels, {k} bands")
        others = getattr(self, "_others", ())
        if others:
            many = len(others) > 1
            self.report({"WARNING"}, f"Decomposed only the active object '{obj.name}': "
                                     f"{', '.join(repr(name) for name in others)} {'are' if many else 'is'} selected "
                                     f"too but left as {'they are' if many else 'it is'} (each mesh has its own "
                                     "settings: make each active and Decompose it)")
        return {"FINISHED"}

    # --- modal: the UI button (_background.py)
    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return self.start_in_background(context)

    def start_in_background(self, context):
        prepared = _prepare(self, context)
        if prepared is None:
            return {"CANCELLED"}
        points, kwargs = prepared
        obj = context.active_object
        self._obj_name = obj.name
        self._obj_uid = obj.session_uid  # names can change during the job
        self._points = points
        ps = engine.get()
        return self.start(context, lambda progress: _computed(ps, points, kwargs, progress),
                          what=f"decomposing '{obj.name}' ({len(points)} vertices)", name="pointscale-decompose",
                          cancelled_type=engine.cancelled_type(), busy=(obj.session_uid, obj.data.session_uid))

    cancelled_report = "Decompose cancelled; the mesh is unchanged"

    def failed(self, error) -> str:
        self._points = None
        return f"Decompose '{self._obj_name}': {error}"

    def finished(self, context, result):
        points, self._points = self._points, None  # the finished operator keeps no arrays
        obj = next((o for o in bpy.data.objects if o.session_uid == self._obj_uid), None)
        if obj is None:
            self.report({"ERROR"}, f"'{self._obj_name}' disappeared while it was being decomposed")
            return {"CANCELLED"}
        problem = _changed_meanwhile(context, obj, points, result[0].k)
        if problem:
            self.report({"ERROR"}, f"Decompose '{obj.name}': {problem}; nothing was written")
            return {"CANCELLED"}
        return self._finish(context, obj, result, points)


CLASSES = [POINTSCALE_OT_decompose]
