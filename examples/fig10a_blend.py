"""Fig. 10a: the morph's gains need not sum to one: (alpha, beta) = (1, 1) adds Max Planck's
detail to Igea's, on the common ellipsoid of Fig. 9."""
import numpy as np

import common as C
from fig09_morph import build_morph

STEPS = [(1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    a, faces, b, m, numbers = build_morph()
    shapes = [m.evaluate(al, be) for al, be in STEPS]
    diag = float(np.linalg.norm(np.ptp(a, axis=0)))
    numbers = {k: numbers[k] for k in ("igea_points", "max_planck_points", "alignment", "morph_report")}
    numbers["blend_1_1_rms_from_igea_percent_of_diagonal"] = round(
        100 * float(np.sqrt(((shapes[2] - shapes[0]) ** 2).sum(1).mean())) / diag, 3)
    st = C.Studio(args.quick, 200, 250)
    st.frame(np.vstack(shapes), direction=(0.3, 1.0, -0.05))
    obj = st.mesh(a, faces, "Blend")
    panels = st.render_shapes(obj, shapes)
    labels = ["Igea (1, 0)", "Max Planck (0, 1)", "both details (1, 1)"]
    C.save(args, "fig10a_blend", C.tile(panels, labels, quick=args.quick))
    C.finish(args, "fig10a_blend", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
