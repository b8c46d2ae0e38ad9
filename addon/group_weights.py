"""Vertex-group weights in bulk, through Geometry Nodes.

Vertex groups have no foreach_get: mesh_io.read_group_weights walks the vertices in Python
(2 s at 1M vertices for three masks). Here a Geometry Nodes tree copies each group into a float
point attribute ("Named Attribute" reads a vertex group exactly, as float32), on a temporary
object that shares the mesh (vertex groups live on the mesh) and has no other modifier, so its
evaluated vertices are the mesh's own, whatever modifiers the artist's object has. 0.15 s at 1M.
"""

from __future__ import annotations

import bpy
import numpy as np

from . import mesh_io

_PREFIX = ".pointscale_weight_"


def read(obj, group_names, n: int) -> list:
    """Weights (n,) float64 per named vertex group, None where the group does not exist (or the
    name is None); exactly mesh_io.read_group_weights, which it falls back to when Geometry
    Nodes cannot (e.g. a scene without a view layer to evaluate in)."""
    names = [name if name and obj.vertex_groups.get(name) is not None else None for name in group_names]
    wanted = [name for name in names if name is not None]
    if not wanted:
        return [None] * len(names)
    try:
        read_by_name = _evaluated_weights(obj, wanted, n)
    except (RuntimeError, KeyError, ValueError, TypeError, AttributeError):
        return mesh_io.read_group_weights(obj, group_names, n)
    return [None if name is None else read_by_name[name] for name in names]


def _tree(names):
    tree = bpy.data.node_groups.new(".pointscale weights", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    geometry = tree.nodes.new("NodeGroupInput").outputs[0]
    for i, name in enumerate(names):
        group = tree.nodes.new("GeometryNodeInputNamedAttribute")
        group.data_type = "FLOAT"
        group.inputs["Name"].default_value = name
        store = tree.nodes.new("GeometryNodeStoreNamedAttribute")
        store.data_type = "FLOAT"
        store.domain = "POINT"
        store.inputs["Name"].default_value = f"{_PREFIX}{i}"
        tree.links.new(geometry, store.inputs["Geometry"])
        tree.links.new(group.outputs["Attribute"], store.inputs["Value"])
        geometry = store.outputs["Geometry"]
    tree.links.new(geometry, tree.nodes.new("NodeGroupOutput").inputs[0])
    return tree


def _evaluated_weights(obj, names, n: int) -> dict:
    scene = bpy.context.scene
    tree = _tree(names)
    probe = bpy.data.objects.new(".pointscale weights", obj.data)
    try:
        probe.show_only_shape_key = True  # the Basis alone: mixing the keys would only cost time
        probe.modifiers.new("weights", "NODES").node_group = tree
        scene.collection.objects.link(probe)
        evaluated = probe.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mesh = evaluated.to_mesh()
        try:
            if len(mesh.vertices) != n:
                raise ValueError("the evaluated mesh has other vertices")
            out = {}
            for i, name in enumerate(names):
                values = np.empty(n, dtype=np.float32)
                mesh.attributes[f"{_PREFIX}{i}"].data.foreach_get("value", values)
                out[name] = values.astype(np.float64)
            return out
        finally:
            evaluated.to_mesh_clear()
    finally:
        bpy.data.objects.remove(probe)  # unlinks it; the mesh goes back to one user
        bpy.data.node_groups.remove(tree)
