"""Fig. 7: spectral filtering of Max Planck, a 4-level decomposition and four band gains.

Top row: the levels P^0..P^3 of the decomposition (P^3 is the scan). Middle row: P^0 + a0 D^0 +
a1 D^1 + a2 D^2 for the paper's gains (2,2,1), (1,1,2), (1,1,3), (0,0,1). Bottom row: the same
with folds prevented (reconstruct(..., folds="prevent")), the gain limited where the surface
would fold over itself.
"""
import numpy as np

import common as C
import pointscale as ps

GAINS = [(2, 2, 1), (1, 1, 2), (1, 1, 3), (0, 0, 1)]


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    points, faces = C.scan("max_planck.ply")
    C.log(f"max_planck: {len(points)} points")
    dec = ps.decompose(points, levels=4)
    C.log(f"decomposed into {dec.n_levels} levels, support points per level "
          f"{[s['support_points'] for s in dec.stats]}")
    levels = ps.reconstruct_levels(dec)
    reported = [ps.reconstruct(dec, gains=g, folds="report") for g in GAINS]
    filtered = [points_ for points_, _ in reported]
    prevented = [ps.reconstruct(dec, gains=g, folds="prevent") for g in GAINS]
    diag = float(np.linalg.norm(np.ptp(points, axis=0)))
    numbers = {
        "points": len(points),
        "support_points": [s["support_points"] for s in dec.stats],
        "band_rms_percent_of_diagonal": [round(100 * float(np.sqrt((d ** 2).mean())) / diag, 3) for d in dec.details],
        "round_trip_max_error_percent": 100 * float(np.abs(levels[-1] - points).max()) / diag,
    }
    for g, f in zip(GAINS, filtered):
        numbers[f"gains {g}: rms change % of diagonal"] = round(100 * float(np.sqrt(((f - points) ** 2).sum(1).mean())) / diag, 3)
    for g, (_, folds), (_, kept) in zip(GAINS, reported, prevented):
        numbers[f"gains {g}: points that fold, plain / prevented"] = [folds.count, kept.count]
        numbers[f"gains {g}: points the prevention moved"] = int(kept.changed.sum())

    st = C.Studio(args.quick, 200, 250)
    kept = [p for p, _ in prevented]
    st.frame(np.vstack([levels[0], levels[-1]] + filtered + kept), direction=(0.45, 1.0, -0.05))
    obj = st.mesh(points, faces, "Max Planck")
    panels = st.render_shapes(obj, list(levels) + filtered + kept)
    labels = ([f"P{l}" for l in range(4)] + [f"gains {g}" for g in GAINS]
              + [f"{g}, folds prevented" for g in GAINS])
    C.save(args, "fig07_spectral_filter", C.tile(panels, labels, cols=4, quick=args.quick))
    C.finish(args, "fig07_spectral_filter", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
