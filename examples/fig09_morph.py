"""Fig. 9: morphing Igea into Max Planck through a common ellipsoid (Eq. 22).

Both busts are brought to a common bounding box and aligned automatically: each is imported
with z up and its face towards -y, then Max Planck's principal axes are turned onto Igea's (of
the 24 axis pairings, the smallest rotation) and each axis is scaled to Igea's box. Both
are encoded onto the largest ellipsoid inside that box (pointscale.ellipsoid_base) and
pointscale.morph carries Max Planck's offsets onto Igea's samples; Morph.evaluate(alpha, beta)
shows p + (alpha d_Igea + beta d_Planck) n for (1, 0) .. (0, 1) in five steps.
"""
import itertools

import numpy as np

import common as C
import pointscale as ps

STEPS = [(1.0, 0.0), (0.75, 0.25), (0.5, 0.5), (0.25, 0.75), (0.0, 1.0)]


def _frame(p):
    c = p.mean(axis=0)
    w, v = np.linalg.eigh(np.cov((p - c).T))
    return c, v[:, ::-1]  # columns: principal axes, largest first


def align_to(b, a):
    """b turned onto a's principal axes and scaled per axis to a's bounding box.

    Both models come in the same viewing convention (z up, -y front: what a user sets when
    importing), so of the 24 ways to pair the principal axes (axis order and signs) the one with
    the smallest rotation is taken: the principal axes then correct the remaining tilt between
    the two busts. Returns (aligned b, dict: the rotation angle in degrees and the axis pairing).
    """
    ca, fa = _frame(a)
    cb, fb = _frame(b)
    qa = (a - ca) @ fa  # a in its principal frame
    lo, hi = qa.min(axis=0), qa.max(axis=0)
    best = None
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            R = fb[:, perm] * np.array(signs)
            turn = R @ fa.T  # b's coordinates -> a's coordinates (row vectors)
            if np.linalg.det(turn) < 0:  # a mirror, not a rotation
                continue
            if best is None or np.trace(turn) > np.trace(best[1]):
                best = (perm, turn, R)
    perm, turn, R = best
    qb = (b - cb) @ R
    blo, bhi = qb.min(axis=0), qb.max(axis=0)
    qb = lo + (qb - blo) * (hi - lo) / (bhi - blo)
    angle = float(np.degrees(np.arccos(np.clip((np.trace(turn) - 1) / 2, -1, 1))))
    return qb @ fa.T + ca, {"rotation_deg": round(angle, 2), "axes": list(perm),
                            "box_scale": np.round((hi - lo) / (bhi - blo), 3)}


def build_morph():
    """(igea points, igea faces, morph, numbers) shared by Fig. 9 and Fig. 10a."""
    C.need_models("igea.ply", "max_planck.ply")  # both, before any work
    a, faces = C.scan("igea.ply")
    b, _ = C.scan("max_planck.ply")
    b, choice = align_to(b, a)
    C.log(f"aligned Max Planck to Igea: turned by {choice['rotation_deg']} deg, box scale {choice['box_scale']}")
    base = ps.ellipsoid_base(a, b, n=20000)
    m = ps.morph(a, b, base)
    diag = float(np.linalg.norm(np.ptp(a, axis=0)))
    numbers = {
        "igea_points": len(a), "max_planck_points": len(b), "ellipsoid_samples": len(base),
        "alignment": choice,
        "detail_igea_range_percent_of_diagonal": [round(100 * float(m.detail_a.min()) / diag, 2),
                                                 round(100 * float(m.detail_a.max()) / diag, 2)],
        "detail_planck_range_percent_of_diagonal": [round(100 * float(m.detail_b.min()) / diag, 2),
                                                   round(100 * float(m.detail_b.max()) / diag, 2)],
        "morph_report": m.report,
        "alpha1_beta0_max_error_percent_of_diagonal": 100 * float(np.linalg.norm(m.evaluate(1, 0) - a, axis=1).max()) / diag,
    }
    C.log(f"morph: {m.report}")
    return a, faces, b, m, numbers


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    a, faces, b, m, numbers = build_morph()
    shapes = [m.evaluate(al, be) for al, be in STEPS]
    st = C.Studio(args.quick, 160, 200)
    st.frame(np.vstack(shapes), direction=(0.3, 1.0, -0.05))
    obj = st.mesh(a, faces, "Morph")
    panels = st.render_shapes(obj, shapes)
    labels = [f"({al:g}, {be:g})" for al, be in STEPS]
    C.save(args, "fig09_morph", C.tile(panels, labels, quick=args.quick))
    C.finish(args, "fig09_morph", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
