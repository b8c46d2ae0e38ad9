"""Why an operator cannot run: one message, shared by poll and execute."""

from __future__ import annotations

from . import engine, keys, storage


def mesh_object_problem(obj) -> str | None:
    if obj is None:
        return "No active object: select a mesh"
    if obj.type != "MESH":
        kind = {"POINTCLOUD": "point cloud", "GPENCIL": "grease pencil object",
                "GREASEPENCIL": "grease pencil object"}.get(obj.type, obj.type.lower().replace("_", " "))
        article = "an" if kind[:1] in "aeiou" else "a"
        return f"'{obj.name}' is {article} {kind}, not a mesh: multiscale editing works on mesh objects"
    if obj.library is not None or obj.data.library is not None:
        return f"'{obj.name}' is linked from a library and cannot be edited"
    if obj.data.is_editmode and obj.mode != "EDIT":
        # A linked duplicate in Edit Mode holds the mesh: its vertices and attributes are in the
        # edit, not in the mesh, until it leaves (writing them now fails half way).
        import bpy

        holders = [o.name for o in bpy.data.objects if o.data == obj.data and o.mode == "EDIT"]
        through = f" through '{holders[0]}'" if holders else ""
        return (f"the mesh of '{obj.name}' ('{obj.data.name}') is in Edit Mode{through}: leave Edit Mode there "
                "first")
    return None


# session_uid of every object with a decompose in flight, and of its mesh: other operators
# wait for it, on that object and on every object that shares the mesh (a linked duplicate).
running: set = set()


def running_problem(obj) -> str | None:
    if obj is None:
        return None
    if obj.session_uid in running:
        return f"'{obj.name}' is being decomposed (Esc cancels): wait for it to finish"
    mesh = getattr(obj, "data", None)
    if mesh is not None and mesh.session_uid in running:
        return (f"the mesh of '{obj.name}' ('{mesh.name}', shared with another object) is being decomposed "
                "(Esc cancels): wait for it to finish")
    return None


def engine_problem() -> str | None:
    if not engine.available():
        return engine.error() or "the pointscale engine is not available"
    return None


def decomposed_problem(obj) -> str | None:
    """None when ``obj`` holds a decomposition that matches its current topology."""
    problem = mesh_object_problem(obj) or running_problem(obj)
    if problem:
        return problem
    mesh = obj.data
    if not storage.has_data(mesh) or mesh.multiscale.n_bands < 1:
        return f"'{obj.name}' has no multiscale decomposition yet: run Decompose first"
    n_now = len(mesh.vertices)
    n_then = mesh.multiscale.n_vertices
    if n_now != n_then or storage.stored_count(mesh) != n_now:
        return (
            f"'{obj.name}' has {n_now} vertices but was decomposed with {n_then}: the topology changed. "
            "Decompose again (or Clear) to start over; nothing was modified"
        )
    if mesh.shape_keys is None or mesh.shape_keys.reference_key is None:
        return f"'{obj.name}' lost its shape keys: Decompose again"
    if not mesh.shape_keys.use_relative:  # absolute keys show none of the results
        return (f"the shape keys of '{obj.name}' were made absolute (Relative is off): turn Relative back on under "
                "Shape Keys; the Level, Band and result keys show only as relative keys")
    k = mesh.multiscale.n_bands
    kbs = mesh.shape_keys.key_blocks
    names = [keys.level_name(l) for l in range(k)] + [keys.band_name(l) for l in range(k)]
    problem = removed_basis_problem(obj)
    if problem:
        return problem
    for name in names:
        if name not in kbs:
            return f"'{obj.name}' has no shape key '{name}' any more (removed or renamed): Decompose again"
    return None


def removed_basis_problem(obj) -> str | None:
    """The Basis key removed by hand: one of the add-on's keys is the reference key (the first,
    which every other key moves from, and the shape a Decompose reads), so nothing may write
    over it or read it as the original."""
    mesh = obj.data
    reference = keys.removed_basis(mesh, mesh.multiscale.n_bands) if storage.has_data(mesh) else None
    if reference is None:
        return None
    return (f"the Basis key of '{obj.name}' was removed: '{reference}' is now the reference key, which every other "
            "key moves from. Undo the removal (Ctrl+Z), or Clear to get the original shape back without the keys")


def vertex_order_problem(obj) -> str | None:
    """Checked when an operator runs (it reads every vertex, too slow for poll): vertices
    reordered since the decompose, e.g. by Sort Mesh Elements, keep their count but not their data."""
    if not storage.order_intact(obj.data):
        return (f"the vertices of '{obj.name}' were reordered since it was decomposed: "
                "Decompose again (or Clear) to start over; nothing was modified")
    return None
