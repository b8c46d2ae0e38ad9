"""Meshes with faces, made in code, for tests and examples of connectivity (pointscale.parts):
each returns (vertices (n, 3), faces (m, 4) quads or (m, 3) triangles), vertices shared."""
from __future__ import annotations

import numpy as np


def _welded(vertices: np.ndarray, faces: np.ndarray, tolerance: float):
    """Merges vertices closer than tolerance (a grid's shared rows), renumbering the faces."""
    keys = np.round(vertices / tolerance).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # keep the vertices in the order they were made
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return vertices[first[order]], rank[inverse.reshape(-1)][faces]


def grid(size_u: float, size_v: float, segments_u: int, segments_v: int):
    """A flat grid in z = 0, centred on the origin: ((su+1)(sv+1), 3) vertices, su*sv quads."""
    u = np.linspace(-0.5, 0.5, segments_u + 1) * size_u
    v = np.linspace(-0.5, 0.5, segments_v + 1) * size_v
    uu, vv = np.meshgrid(u, v, indexing="ij")
    vertices = np.stack([uu.ravel(), vv.ravel(), np.zeros(uu.size)], axis=1)
    i, j = np.meshgrid(np.arange(segments_u), np.arange(segments_v), indexing="ij")
    a = (i * (segments_v + 1) + j).ravel()
    faces = np.stack([a, a + segments_v + 1, a + segments_v + 2, a + 1], axis=1)
    return vertices, faces


def box(size=(1.0, 1.0, 1.0), segments: int = 16):
    """The surface of a box centred on the origin, `segments` quads along its longest edge
    (Blender's cube subdivided: a cube of 16 segments has 6 * 16**2 + 2 = 1538 vertices)."""
    size = np.broadcast_to(np.asarray(size, dtype=np.float64), (3,))
    counts = np.maximum(1, np.round(segments * size / size.max()).astype(int))
    vertices, faces = [], []
    offset = 0
    for axis in range(3):
        a, b = [d for d in range(3) if d != axis]
        for side in (-1.0, 1.0):
            v, f = grid(size[a], size[b], counts[a], counts[b])
            out = np.zeros_like(v)
            out[:, a], out[:, b], out[:, axis] = v[:, 0], v[:, 1], side * 0.5 * size[axis]
            if side * (1 if (axis == 1) else -1) > 0:
                f = f[:, ::-1]  # outward winding on every side
            vertices.append(out)
            faces.append(f + offset)
            offset += len(v)
    return _welded(np.concatenate(vertices), np.concatenate(faces), 1e-9 * size.max())


def uv_sphere(radius: float = 1.0, segments: int = 64, rings: int = 32):
    """A UV sphere like Blender's: segments * (rings - 1) + 2 vertices, triangles at the poles."""
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    t, f = np.meshgrid(theta, phi, indexing="ij")
    body = np.stack([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)], axis=-1).reshape(-1, 3)
    vertices = np.concatenate([[[0.0, 0.0, 1.0]], body, [[0.0, 0.0, -1.0]]]) * radius
    ring = lambda r, s: 1 + r * segments + (s % segments)  # noqa: E731
    s = np.arange(segments)
    top = np.stack([np.zeros(segments, int), ring(0, s), ring(0, s + 1)], axis=1)
    bottom_pole = len(vertices) - 1
    bottom = np.stack([np.full(segments, bottom_pole), ring(rings - 2, s + 1), ring(rings - 2, s)], axis=1)
    r, ss = np.meshgrid(np.arange(rings - 2), s, indexing="ij")
    r, ss = r.ravel(), ss.ravel()
    quads = np.stack([ring(r, ss), ring(r + 1, ss), ring(r + 1, ss + 1), ring(r, ss + 1)], axis=1)
    tri = np.concatenate([top, bottom, quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return vertices, tri


def bumpy(vertices: np.ndarray, amplitude: float, frequency: float, centre=(0.0, 0.0, 0.0)) -> np.ndarray:
    """vertices moved along their direction from centre by a smooth bump field, to give a
    part detail to decompose."""
    from .shapes import bump_field
    d = vertices - np.asarray(centre)
    r = np.linalg.norm(d, axis=1, keepdims=True)
    u = d / np.maximum(r, 1e-300)
    return vertices + amplitude * bump_field(u, frequency)[:, None] * u


def joined(*meshes):
    """One mesh of several: the vertices stacked, the faces renumbered. Returns (vertices, faces,
    part) with part (n,) the index of the mesh each vertex came from. Faces must have equal corner
    counts; triangulate quads first (quads_to_triangles) to join them with triangles."""
    vertices, faces, part = [], [], []
    offset = 0
    for index, (v, f) in enumerate(meshes):
        vertices.append(v)
        faces.append(f + offset)
        part.append(np.full(len(v), index))
        offset += len(v)
    return np.concatenate(vertices), np.concatenate(faces), np.concatenate(part)


def quads_to_triangles(faces: np.ndarray) -> np.ndarray:
    """(m, 4) quads as (2m, 3) triangles."""
    if faces.shape[1] == 3:
        return faces
    return np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals: each vertex's area-weighted face normals summed, as Blender computes
    them, outward where the faces wind outward. faces (m, 3) or (m, 4); returns (n, 3)."""
    tri = quads_to_triangles(np.asarray(faces))
    a, b, c = (vertices[tri[:, i]] for i in range(3))
    face = np.cross(b - a, c - a)  # twice the area, along the normal
    out = np.zeros_like(vertices, dtype=np.float64)
    for i in range(3):
        np.add.at(out, tri[:, i], face)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return out / np.where(length > 0, length, 1.0)
