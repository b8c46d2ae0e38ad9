"""Fig. 8: Max Planck encoded onto an ellipsoid, detail scaled by 0, 0.5, 1, 1.5 and 2.

The base is not a smoothed Max Planck but the largest ellipsoid inside its bounding box
(pointscale.ellipsoid_base); pointscale.encode stores Max Planck as one band of normal offsets
from it, and reconstruct(enc, [g]) scales that band: 0 is the ellipsoid, 1 the bust, 2 a
caricature.
"""
import numpy as np

import common as C
import pointscale as ps

GAINS = [0.0, 0.5, 1.0, 1.5, 2.0]


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    points, faces = C.scan("max_planck.ply")
    base = ps.ellipsoid_base(points, n=20000)
    enc = ps.encode(points, base)
    shapes = [ps.reconstruct(enc, gains=[g]) for g in GAINS]
    stats = enc.stats[0]
    diag = float(np.linalg.norm(np.ptp(points, axis=0)))
    d = enc.details[0]
    numbers = {
        "points": len(points),
        "ellipsoid_samples": len(base),
        "detail_range_percent_of_diagonal": [round(100 * float(d.min()) / diag, 2), round(100 * float(d.max()) / diag, 2)],
        "pinned_points": int(stats.get("pinned", 0)),
        "not_converged": int(stats.get("not_converged", 0)),
        # the largest errors sit at the few pinned anchors, whose offsets could not be made normal
        "gain1_max_error_percent_of_diagonal": 100 * float(np.linalg.norm(shapes[2] - points, axis=1).max()) / diag,
        "gain1_p99_error_percent_of_diagonal": 100 * float(np.percentile(np.linalg.norm(shapes[2] - points, axis=1), 99)) / diag,
    }
    C.log(f"encoded onto {len(base)} ellipsoid samples: pinned {numbers['pinned_points']}, "
          f"gain-1 max error {numbers['gain1_max_error_percent_of_diagonal']:.2g} % of the diagonal")
    st = C.Studio(args.quick, 160, 200)
    st.frame(np.vstack(shapes), direction=(0.45, 1.0, -0.05))
    obj = st.mesh(points, faces, "Max Planck")
    panels = st.render_shapes(obj, shapes)
    labels = [f"detail x {g:g}" for g in GAINS]
    C.save(args, "fig08_ellipsoid", C.tile(panels, labels, quick=args.quick))
    C.finish(args, "fig08_ellipsoid", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
