"""Fig. 3: a linear blend between two subsequent levels of the bunny's decomposition.

pointscale.blend(dec, t) for t = 1, 1.25, 1.5, 1.75, 2: since P^2 - P^1 = D^1 n lies along the
normals of P^1, the straight-line blend (Eq. 20-21) moves every point along its normal.
"""
import numpy as np

import common as C
import pointscale as ps

TS = [1.0, 1.25, 1.5, 1.75, 2.0]


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    points, faces = C.scan("bunny.ply")
    C.log(f"bunny: {len(points)} points")
    dec = ps.decompose(points, levels=4)
    C.log(f"decomposed, support points {[s['support_points'] for s in dec.stats]}")
    blends = [ps.blend(dec, t) for t in TS]
    p1, p2 = dec.level(1), dec.level(2)
    n1 = dec.normals(1)
    step = p2 - p1
    along = np.abs((step * n1).sum(axis=1))
    diag = float(np.linalg.norm(np.ptp(points, axis=0)))
    numbers = {
        "points": len(points),
        "rms_P1_to_P2_percent_of_diagonal": round(100 * float(np.sqrt((step ** 2).sum(1).mean())) / diag, 4),
        "step_along_normal_fraction_min": float((along / np.maximum(np.linalg.norm(step, axis=1), 1e-300))[
            np.linalg.norm(step, axis=1) > 1e-9 * diag].min()),
        "rms_from_P1_percent_of_diagonal": [round(100 * float(np.sqrt(((b - p1) ** 2).sum(1).mean())) / diag, 4)
                                            for b in blends],
    }
    st = C.Studio(args.quick, 160, 160)
    st.frame(np.vstack([p1, p2]), direction=(0.6, 1.0, -0.25))
    obj = st.mesh(points, faces, "Bunny")
    panels = st.render_shapes(obj, blends)
    labels = [f"t = {t:g}" + (" (P1)" if t == 1 else " (P2)" if t == 2 else "") for t in TS]
    C.save(args, "fig03_blend", C.tile(panels, labels, quick=args.quick))
    C.finish(args, "fig03_blend", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
