"""Fig. 6: embossed text on a plane, deformed single-scale and multiscale.

The relief is modelled the way a Blender user would: a text object, extruded, converted to a
mesh, voxel-remeshed so that its caps are sampled as densely as its walls, and joined with a
subdivided plane. The mesh's vertices are the point cloud. (a) the relief, (b) single-scale: every
point lifted by a smooth bump, so the letters shear, (c) multiscale: only the base P^0 is lifted
and the detail follows its new normals, so the letters stay upright on the surface. Prints the
angle between each letter part's axis (bottom to top) and the surface normal around it.
"""
import bpy
import numpy as np
from mathutils.bvhtree import BVHTree

import common as C
import pointscale as ps

TEXT = "Pointscale"
SPACING = 0.012          # plane and voxel spacing
DEPTH = 0.07             # letter height above the plane
SIZE_X, SIZE_Y = 4.0, 2.0
HEIGHT, WIDTH = 0.7, 0.9  # the bump


def bump(xy):
    return HEIGHT * np.exp(-(xy ** 2).sum(axis=1) / WIDTH ** 2)


def mesh_arrays(me):
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    loops = np.empty(len(me.polygons), np.int32)
    me.polygons.foreach_get("loop_total", loops)
    vi = np.empty(len(me.loops), np.int32)
    me.loops.foreach_get("vertex_index", vi)
    return co.reshape(-1, 3).astype(np.float64), loops, vi


def text_mesh():
    """The extruded, voxel-remeshed text: (vertices, quads), letters from z = -2 spacings to DEPTH."""
    curve = bpy.data.curves.new("Text", type="FONT")
    curve.body = TEXT
    curve.size = 0.82
    curve.extrude = (DEPTH + 2 * SPACING) / 2
    curve.align_x, curve.align_y = "CENTER", "CENTER"
    obj = bpy.data.objects.new("Text", curve)
    bpy.context.scene.collection.objects.link(obj)
    mod = obj.modifiers.new("Remesh", "REMESH")
    mod.mode = "VOXEL"
    mod.voxel_size = SPACING
    dg = bpy.context.evaluated_depsgraph_get()
    me = bpy.data.meshes.new_from_object(obj.evaluated_get(dg))
    bpy.data.objects.remove(obj)
    v, loops, vi = mesh_arrays(me)
    quads = vi.reshape(-1, 4)  # voxel remesh makes quads only
    v[:, 2] += (DEPTH - 2 * SPACING) / 2  # bottom at -2 spacings, top at DEPTH
    # drop the bottom cap (hidden under the plane)
    n = np.cross(v[quads[:, 2]] - v[quads[:, 0]], v[quads[:, 3]] - v[quads[:, 1]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    bottom = (n[:, 2] < -0.7) & (v[quads].mean(axis=1)[:, 2] < 0)
    quads = quads[~bottom]
    used = np.unique(quads)
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    return v[used], remap[quads]


def plane_under(text_v, text_q):
    """A grid plane with the vertices well inside the letters' footprint removed (its faces still
    reach under the letters' walls, so there are no cracks)."""
    nx, ny = int(SIZE_X / SPACING) + 1, int(SIZE_Y / SPACING) + 1
    x, y = np.meshgrid(np.linspace(-SIZE_X / 2, SIZE_X / 2, nx), np.linspace(-SIZE_Y / 2, SIZE_Y / 2, ny), indexing="ij")
    grid = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    bvh = BVHTree.FromPolygons([tuple(p) for p in text_v], text_q.tolist())

    def inside(p):
        hit = bvh.ray_cast((p[0], p[1], DEPTH + 1.0), (0.0, 0.0, -1.0))
        return hit[0] is not None

    footprint = np.array([inside(p) for p in grid])
    d = int(np.ceil(1.5))
    f2 = footprint.reshape(nx, ny)
    deep = f2.copy()
    for sx, sy in ((d, 0), (-d, 0), (0, d), (0, -d)):
        deep &= np.roll(np.roll(f2, sx, 0), sy, 1)
    keep = ~deep.ravel()
    idx = np.arange(nx * ny).reshape(nx, ny)
    quads = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1).reshape(-1, 4)
    quads = quads[keep[quads].all(axis=1)]
    remap = np.full(len(grid), -1)
    remap[keep] = np.arange(int(keep.sum()))
    return grid[keep], remap[quads]


def components(n, quads):
    """Connected components of a quad mesh (label propagation with pointer jumping)."""
    e = np.concatenate([quads[:, [0, 1]], quads[:, [1, 2]], quads[:, [2, 3]], quads[:, [3, 0]]])
    lab = np.arange(n)
    while True:
        m = np.minimum(lab[e[:, 0]], lab[e[:, 1]])
        new = lab.copy()
        np.minimum.at(new, e[:, 0], m)
        np.minimum.at(new, e[:, 1], m)
        new = new[new]
        if np.array_equal(new, lab):
            return np.unique(lab, return_inverse=True)[1]
        lab = new


def letter_angles(result, points, part, n_plane):
    """Per letter part: the angle between its axis and the surface normal under it, in degrees.

    The deformed plane around the letter is fitted as a quadratic map of the original (x, y)
    (least squares over the plane points within 0.1 of the letter's footprint). The axis is the
    mean of the letter's top cap on `result` minus the mean of that map at the same (x, y): the
    letter's height vector. The normal is the map's normal at the letter's centre.
    """
    angles = []
    xy = points[:, :2]
    for c in range(part.max() + 1):
        mine = np.flatnonzero(part == c) + n_plane
        top = mine[points[mine, 2] > DEPTH - 1e-6]
        if len(top) < 10:
            continue
        lo, hi = xy[mine].min(axis=0) - 0.1, xy[mine].max(axis=0) + 0.1
        near = np.flatnonzero(((xy[:n_plane] >= lo) & (xy[:n_plane] <= hi)).all(axis=1))
        centre = xy[top].mean(axis=0)

        def design(q):
            u, v = (q - centre).T
            return np.column_stack([np.ones_like(u), u, v, u * u, u * v, v * v])

        coef = np.linalg.lstsq(design(xy[near]), result[near], rcond=None)[0]  # (6, 3)
        under = design(xy[top]) @ coef
        axis = result[top].mean(axis=0) - under.mean(axis=0)
        normal = np.cross(coef[1], coef[2])  # d/du x d/dv at the centre
        angles.append(np.degrees(np.arccos(abs(axis @ normal) / (np.linalg.norm(axis) * np.linalg.norm(normal)))))
    return np.array(angles)


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    st = C.Studio(args.quick, 800, 230)
    text_v, text_q = text_mesh()
    plane_v, plane_q = plane_under(text_v, text_q)
    points = np.vstack([plane_v, text_v])
    faces = np.vstack([plane_q, text_q + len(plane_v)])
    part = components(len(text_v), text_q)
    C.log(f"relief: plane {len(plane_v)} + text {len(text_v)} vertices = {len(points)} points, "
          f"{part.max() + 1} letter parts")
    dec = ps.decompose(points, levels=4, decimation=0.2, kernel=2.0)
    base = dec.base
    lifted = base.copy()
    lifted[:, 2] += bump(base[:, :2])
    multi = ps.reconstruct(dec, base=lifted)
    single = points.copy()
    single[:, 2] += bump(points[:, :2])
    a_single = letter_angles(single, points, part, len(plane_v))
    a_multi = letter_angles(multi, points, part, len(plane_v))
    C.log(f"letter axis to normal, max: single-scale {a_single.max():.1f} deg, multiscale {a_multi.max():.1f} deg")
    numbers = {
        "points": len(points),
        "letter_parts_measured": len(a_single),
        "base_height_range_over_letter_height": float(np.ptp(base[:, 2])) / DEPTH,
        "single_scale_angle_deg": {"max": float(a_single.max()), "mean": float(a_single.mean())},
        "multiscale_angle_deg": {"max": float(a_multi.max()), "mean": float(a_multi.mean())},
    }

    st.frame(np.vstack([points, single, multi]), direction=(0.2, 1.0, -0.5), lens=50, margin=1.0)
    obj = st.mesh(points, faces, "Relief", smooth=False)
    panels = st.render_shapes(obj, (points, single, multi))
    labels = ["(a) original relief",
              f"(b) single-scale: letters lean up to {a_single.max():.0f} deg",
              f"(c) multiscale: letters lean at most {a_multi.max():.1f} deg"]
    C.save(args, "fig06_emboss", C.tile(panels, labels, cols=1, quick=args.quick))
    C.finish(args, "fig06_emboss", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
