"""Fig. 5: multiscale vs single-scale deformation of a plane with 16 box handles.

(a) the plane, (b) its smooth base P^0, (c) the base lifted by a Gaussian bump, (d) single-scale:
every point lifted by the same bump, (e) multiscale: the detail of all bands carried along the
normals of the lifted base (pointscale.reconstruct(dec, base=lifted)). Prints the angle between
each handle's axis and the normal of the surface around it.
"""
import numpy as np

import common as C
import pointscale as ps

HEIGHT, WIDTH = 0.8, 1.0  # the bump: 0.8 high, Gaussian of width 1 on a 4 x 4 plane


def bump(xy):
    return HEIGHT * np.exp(-(xy ** 2).sum(axis=1) / WIDTH ** 2)




def main(argv=None):
    args = C.parse_args(__doc__, argv)
    points, handle, centres = ps.shapes.handles_plane()
    C.log(f"plane with {len(centres)} handles: {len(points)} points")
    dec = ps.decompose(points, levels=4, decimation=0.2, kernel=2.0)
    base = dec.base
    lifted = base.copy()
    lifted[:, 2] += bump(base[:, :2])
    single = points.copy()
    single[:, 2] += bump(points[:, :2])
    multi = ps.reconstruct(dec, base=lifted)
    a_single = ps.shapes.handle_angles(single, points, handle, centres, single)
    a_multi = ps.shapes.handle_angles(multi, points, handle, centres, lifted)
    numbers = {
        "points": len(points),
        "base_height_range": float(np.ptp(base[:, 2])),
        "single_scale_angle_deg": {"max": float(a_single.max()), "mean": float(a_single.mean())},
        "multiscale_angle_deg": {"max": float(a_multi.max()), "mean": float(a_multi.mean())},
        "single_scale_angles_deg": np.round(a_single, 2),
        "multiscale_angles_deg": np.round(a_multi, 2),
    }
    C.log(f"handle-to-normal angle, max: single-scale {a_single.max():.1f} deg, multiscale {a_multi.max():.2f} deg")

    st = C.Studio(args.quick, 266, 190)
    st.frame(np.vstack([points, lifted, multi, single]), direction=(0.55, 1.0, -0.75), lens=50)
    on_plane = handle == -1
    plane = st.points(points[on_plane], 0.0165, "Plane")
    knobs = st.points(points[~on_plane], 0.0165, "Handles", st.clay((0.30, 0.42, 0.55), "Handle clay"))
    panels = []
    for shape in (points, base, lifted, single, multi):
        if len(panels) == 3:
            st.resize(400, 286)
        st.set_points(plane, shape[on_plane])
        st.set_points(knobs, shape[~on_plane])
        panels.append(st.render([plane, knobs]))
        C.log(f"panel {len(panels)}/5")
    labels = ["(a) original", "(b) smooth base P0", "(c) deformed base",
              f"(d) single-scale: handles tilt up to {a_single.max():.0f} deg",
              f"(e) multiscale: handles tilt at most {a_multi.max():.1f} deg"]
    rows = [C.tile(panels[:3], labels[:3], quick=args.quick), C.tile(panels[3:], labels[3:], quick=args.quick)]
    C.save(args, "fig05_handles", C.stack(rows))
    C.finish(args, "fig05_handles", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
