"""Why an operator cannot run: one message, shared by poll and execute."""

from __future__ import annotations

from . import engine, storage


def mesh_object_problem(obj) -> str | None:
    if obj is None:
        return "No active object: select a mesh"
    if obj.type != "MESH":
        return f"'{obj.name}' is a {obj.type.lower()}, not a mesh: multiscale editing works on mesh objects"
    if obj.library is not None or obj.data.library is not None:
        return f"'{obj.name}' is linked from a library and cannot be edited"
    return None


def engine_problem() -> str | None:
    if not engine.available():
        return engine.error() or "the pointscale engine is not available"
    return None


def decomposed_problem(obj) -> str | None:
    """None when ``obj`` holds a decomposition that matches its current topology."""
    problem = mesh_object_problem(obj)
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
    return None
