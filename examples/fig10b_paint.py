"""Fig. 10b: painted gains on Igea, through the add-on's band masks.

A Blender user's workflow: Decompose (4 levels), open the band masks (Paint Band Mask), paint
them (here: weights set by script with a smooth fall-off around two spots, as a soft brush
would), set the gains and Bake Filter, which reconstructs exactly with per-point gains
1 + (gain - 1) * weight and recomputed normals. On the blue spot the middle band 1 is removed
(gain 0: the curls melt away, the finest strands stay); on the red spot the finest band 2 is
scaled by 4 (every strand is carved deeper). Panels: the scan, the painted masks, the baked result, and a close-up
of each spot before and after.
"""
import bpy
import numpy as np

import common as C

SMOOTH_BAND, SMOOTH_GAIN = 1, 0.0
ENHANCE_BAND, ENHANCE_GAIN = 2, 4.0
RADIUS = 0.38


def spot(points, direction, radius=RADIUS):
    """Weights 1 near the surface point farthest along `direction`, falling smoothly to 0 at radius."""
    d = np.asarray(direction, float)
    centre = points[np.argmax(points @ (d / np.linalg.norm(d)))]
    r = np.linalg.norm(points - centre, axis=1) / radius
    w = np.clip(1 - r, 0, 1)
    return w * w * (3 - 2 * w), centre  # smoothstep fall-off


def paint(obj, band, weights):
    assert bpy.ops.pointscale.paint_band_mask(band=band, enter_paint=False) == {"FINISHED"}
    vg = obj.vertex_groups[f"Band {band} mask"]
    vg.remove(list(range(len(weights))))
    for value in np.unique(np.round(weights, 3)):
        if value > 0:
            vg.add(np.flatnonzero(np.round(weights, 3) == value).tolist(), float(value), "REPLACE")


def main(argv=None):
    args = C.parse_args(__doc__, argv)
    points, faces = C.scan("igea.ply")
    st = C.Studio(args.quick, 200, 250)
    obj = C.addon_decompose(st, points, faces, "Igea", levels=4)
    settings = obj.data.multiscale
    C.log(f"add-on Decompose: {settings.n_bands} bands on {len(points)} vertices")
    w_smooth, c_smooth = spot(points, (0.75, -0.7, 0.55))   # hair on the statue's left (right in the picture)
    w_enh, c_enh = spot(points, (-0.75, -0.7, 0.55))        # hair on the statue's right
    paint(obj, SMOOTH_BAND, w_smooth)
    paint(obj, ENHANCE_BAND, w_enh)
    assert bpy.ops.pointscale.paint_band_mask(band=0, enter_paint=False) == {"FINISHED"}
    settings.bands[SMOOTH_BAND].gain = SMOOTH_GAIN
    settings.bands[ENHANCE_BAND].gain = ENHANCE_GAIN
    assert bpy.ops.pointscale.bake_filter() == {"FINISHED"}
    result = C.read_key(obj, "Multiscale Filter")
    C.log("painted two spots and baked the filter")

    # what changed, and only where painted
    move = np.linalg.norm(result - points, axis=1)
    diag = float(np.linalg.norm(np.ptp(points, axis=0)))
    attr = obj.data.attributes[f"ms_detail_{SMOOTH_BAND}"]
    d_removed = np.empty(len(attr.data), np.float32)
    attr.data.foreach_get("value", d_removed)
    inner_s, inner_e = w_smooth > 0.9, w_enh > 0.9
    outside = (w_smooth == 0) & (w_enh == 0)

    def rms_move(sel):
        return float(np.sqrt((move[sel] ** 2).mean()))

    numbers = {
        "points": len(points),
        "painted_vertices": {"smooth": int((w_smooth > 0).sum()), "enhance": int((w_enh > 0).sum())},
        "rms_move_percent_of_diagonal": {
            "smooth_spot": round(100 * rms_move(inner_s) / diag, 4),
            "enhance_spot": round(100 * rms_move(inner_e) / diag, 4),
            "unpainted": round(100 * rms_move(outside) / diag, 6),
        },
        "removed_band_rms_in_smooth_spot_percent_of_diagonal": round(
            100 * float(np.sqrt((d_removed[inner_s].astype(float) ** 2).mean())) / diag, 4),
        "max_move_unpainted_percent_of_diagonal": 100 * float(move[outside].max()) / diag,
    }
    C.log(f"rms move: smooth spot {numbers['rms_move_percent_of_diagonal']['smooth_spot']} %, enhance spot "
          f"{numbers['rms_move_percent_of_diagonal']['enhance_spot']} %, unpainted "
          f"{numbers['rms_move_percent_of_diagonal']['unpainted']} % of the diagonal")

    # panels: scan, masks, result (shape keys drive what is rendered)
    clay_rgb, blue, red = np.array(C.CLAY), np.array([0.15, 0.35, 0.85]), np.array([0.85, 0.18, 0.12])
    ws, we = w_smooth[:, None], w_enh[:, None]
    rgb = np.ones((len(points), 4), np.float32)
    rgb[:, :3] = clay_rgb * (1 - ws - we) + blue * ws + red * we
    attr = obj.data.color_attributes.new("painted", "FLOAT_COLOR", "POINT")
    attr.data.foreach_set("color", rgb.reshape(-1))
    clay = obj.data.materials[0]
    masks = st.attribute_material("painted", "Painted masks")
    filt = obj.data.shape_keys.key_blocks["Multiscale Filter"]
    st.frame(np.vstack([points, result]), direction=(0.0, 1.0, -0.15))
    panels = []
    for value, mat in ((0.0, clay), (0.0, masks), (1.0, clay)):
        filt.value = value
        obj.data.materials[0] = mat
        panels.append(st.render([obj]))
        C.log(f"panel {len(panels)}/5")
    # close-ups of each spot, same camera for before and after
    closeups = []
    for centre in (c_smooth, c_enh):
        for o in [o for o in bpy.data.objects if o.type in {"CAMERA", "LIGHT"}]:
            bpy.data.objects.remove(o)
        near = points[np.linalg.norm(points - centre, axis=1) < RADIUS * 1.1]
        normal = near.mean(axis=0) - points.mean(axis=0)
        view = -normal / np.linalg.norm(normal) + np.array([0.0, 1.0, -0.15])
        st.frame(near, direction=view, lens=60)
        for value in (0.0, 1.0):
            filt.value = value
            closeups.append(st.render([obj]))
        C.log(f"close-up {len(closeups) // 2}/2")
    labels = ["Igea (scan)", "painted masks", f"baked: band {SMOOTH_BAND} x{SMOOTH_GAIN:g} / band {ENHANCE_BAND} x{ENHANCE_GAIN:g}"]
    top = C.tile(panels, labels, quick=args.quick)
    cl_labels = ["blue spot before", "after (smoothed)", "red spot before", "after (enhanced)"]
    bottom = C.tile(closeups, cl_labels, quick=args.quick)
    C.save(args, "fig10b_paint", C.stack([top, bottom]))
    C.finish(args, "fig10b_paint", numbers)


if __name__ == "__main__":
    main()
    C.exit_now()
