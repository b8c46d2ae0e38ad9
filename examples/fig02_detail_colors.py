"""Fig. 2: multiscale encoding on Max Planck, detail coefficients as colour.

Done the way a Blender user would: the add-on's Decompose on the imported mesh, the Levels
slider (Scale) to show P^1 and P^2, and Show Details to colour a band blue (below the smoother
level) / white / red (above it, along the outward normal). Panels: P^1, P^2 (which is P^1
displaced along its normals by D^1), D^1 as colours on P^2, and the finest band D^2 as colours on
P^3, the scan.
"""
import bpy
import numpy as np

import common as C


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    points, faces = C.scan("max_planck.ply")
    st = C.Studio(args.quick, 200, 250)
    obj = C.addon_decompose(st, points, faces, "Max Planck", levels=4)
    settings = obj.data.multiscale
    k = settings.n_bands
    C.log(f"add-on Decompose: {k} bands on {len(points)} vertices")
    clay = obj.data.materials[0]
    colours = st.attribute_material("ms_detail_color")
    numbers = {"points": len(points)}
    details = {}
    for band in (2, 1):
        assert bpy.ops.pointscale.show_details(band=band) == {"FINISHED"}
        attr = obj.data.attributes[f"ms_detail_{band}"]
        d = np.empty(len(attr.data), np.float32)
        attr.data.foreach_get("value", d)
        details[band] = d
        diag = float(np.linalg.norm(np.ptp(points, axis=0)))
        numbers[f"D{band}"] = {
            "min_percent_of_diagonal": round(100 * float(d.min()) / diag, 3),
            "max_percent_of_diagonal": round(100 * float(d.max()) / diag, 3),
            "p98_abs_percent_of_diagonal": round(100 * float(np.percentile(np.abs(d), 98)) / diag, 3),
            "positive_fraction": round(float((d > 0).mean()), 3),
        }
        C.log(f"D{band}: range {d.min():.4f} .. {d.max():.4f}, 98th percentile |d| {np.percentile(np.abs(d), 98):.4f}")
    p1 = C.read_key(obj, "Level 1")
    st.frame(np.vstack([points, p1]), direction=(0.45, 1.0, -0.05))
    panels = []
    for scale, band in ((1.0, None), (2.0, None), (2.0, 1), (3.0, 2)):
        settings.scale = scale
        if band is None:
            obj.data.materials[0] = clay
        else:
            assert bpy.ops.pointscale.show_details(band=band) == {"FINISHED"}
            obj.data.materials[0] = colours
        panels.append(st.render([obj]))
        C.log(f"panel {len(panels)}/4")
    labels = ["P1", "P2 = P1 + D1 n", "D1 on P2 (blue -, red +)", "D2 on P3 (the scan)"]
    C.save(args, "fig02_detail_colors", C.tile(panels, labels, quick=args.quick))
    C.finish(args, "fig02_detail_colors", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
