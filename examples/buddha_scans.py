"""Beyond the paper: the 1.1M-point Happy Buddha raw range scans, decomposed as they are.

happy_buddha_scans.ply is 15 range scans merged with their recorded poses, stand and turntable
parts included: real scanner noise, overlaps and small misalignments, no faces, no normals. The
whole cloud is decomposed into 4 levels (no subsampling), and rendered as 1.1M point spheres.
Panels: the raw scans, P^2, P^1, P^0, and a filter that removes the finest band (the scanner
noise) while doubling band 1: gains (1, 2, 0). Prints the timings.
"""
import time

import numpy as np

import common as C
import pointscale as ps

GAINS = (1.0, 2.0, 0.0)


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    (path,) = C.need_models("happy_buddha_scans.ply")
    points, _ = C.read_model(path)
    n_all = len(points)
    if args.quick:  # the test: a 1-in-10 subset keeps the pipeline exercised in seconds
        points = points[::10]
    points = C.align_up(points, up="y", front="z")
    points, scale, _ = C.normalise(points)
    C.log(f"happy_buddha_scans: {len(points)} of {n_all} points")
    t = time.perf_counter()
    dec = ps.decompose(points, levels=4)
    t_dec = time.perf_counter() - t
    C.log(f"decomposed in {t_dec:.1f} s")
    t = time.perf_counter()
    levels = ps.reconstruct_levels(dec)
    filtered = ps.reconstruct(dec, gains=GAINS)
    t_rec = time.perf_counter() - t
    stats = dec.stats
    to_mm = 1000.0 / scale  # the file is in metres
    numbers = {
        "points": len(points),
        "decompose_seconds": round(t_dec, 1),
        "reconstruct_levels_and_filter_seconds": round(t_rec, 1),
        "support_points": [s["support_points"] for s in stats],
        "not_converged": [s["not_converged"] for s in stats],
        "band_rms_mm": [round(float(np.sqrt((d ** 2).mean())) * to_mm, 4) for d in dec.details],
        "finest_band_p99_abs_mm": round(float(np.percentile(np.abs(dec.details[-1]), 99)) * to_mm, 4),
    }
    C.log(f"band rms {numbers['band_rms_mm']} mm; not converged per level {numbers['not_converged']}")
    st = C.Studio(args.quick, 160, 330)
    st.frame(np.vstack([points[::20], filtered[::20]]), direction=(0.25, 1.0, -0.05))
    spacing = 2.0 / 0.2 * 0.00025 * (np.sqrt(10) if args.quick else 1.0)  # ~0.25 mm scan spacing
    cloud = st.points(points, 0.75 * spacing, "Scans")
    panels = st.render_shapes(cloud, (levels[-1], levels[2], levels[1], levels[0], filtered))
    labels = ["raw scans (P3)", "P2", "P1", "P0", f"gains {tuple(int(g) for g in GAINS)}"]
    C.save(args, "buddha_scans", C.tile(panels, labels, quick=args.quick))
    C.finish(args, "buddha_scans", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
