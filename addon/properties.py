"""Settings of a decomposition, kept on the mesh: ``mesh.multiscale``."""

from __future__ import annotations

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
)

from . import keys


def _gain_get(self):
    kb = keys.get(self.id_data, keys.band_name(self.index))
    return 1.0 + kb.value if kb is not None else 1.0


def _gain_set(self, value):
    kb = keys.get(self.id_data, keys.band_name(self.index))
    if kb is not None:
        kb.value = value - 1.0


class MULTISCALE_PG_band(bpy.types.PropertyGroup):
    """One band's gain; a view of the ``Band l`` key value (gain - 1), not a copy."""

    index: IntProperty(name="Band", min=0)
    gain: FloatProperty(
        name="Gain",
        description="Scale of this detail band, 0 to 5: 0 removes it, 1 keeps it, above 1 enhances it "
        "(the Band key value is gain - 1; paint the band's mask to apply it locally)",
        get=_gain_get,
        set=_gain_set,
        min=1.0 + keys.BAND_MIN,
        max=1.0 + keys.BAND_MAX,
        step=5,
    )


def _scale_get(self):
    return self.scale_store


def _scale_set(self, value):
    k = self.n_bands
    value = min(max(float(value), 0.0), float(k))
    self.scale_store = value
    if k > 0:
        keys.set_scale(self.id_data, value, k)


def _poll_other_mesh(self, obj):
    return obj.type == "MESH" and obj.data != self.id_data


def _poll_mesh(self, obj):
    return obj.type == "MESH"


class MULTISCALE_PG_settings(bpy.types.PropertyGroup):
    # --- decomposition settings
    levels: IntProperty(
        name="Levels",
        description="Point clouds P^0..P^k, so levels - 1 detail bands (4 gives the 3 bands of the paper's Fig. 7)",
        default=4,
        min=2,
        max=12,
    )
    decimation: FloatProperty(
        name="Decimation",
        description="Factor gamma: each coarser level is supported by gamma times as many points",
        default=0.25,
        min=0.02,
        max=0.9,
    )
    kernel: FloatProperty(
        name="Kernel Width",
        description="Gaussian kernel width as a multiple of the local sample spacing of each level",
        default=1.0,
        min=0.1,
        max=16.0,
    )
    neighbors: IntProperty(
        name="Neighbours", description="Support points in each local plane fit", default=24, min=4, max=256
    )
    smoother: EnumProperty(
        name="Smoother",
        items=[
            ("MLS", "MLS Projection", "Integrated least-squares projection onto decimated levels (Sec. 7)"),
            ("DIFFUSION", "Diffusion", "Laplacian diffusion on k-nearest-neighbour graphs (Sec. 5.1)"),
        ],
        default="MLS",
    )
    encoding: EnumProperty(
        name="Encoding",
        items=[
            ("PROJECTION", "Projection", "Top-down: project each point onto the smoother surface (Sec. 6.2)"),
            ("RAY", "Ray Shooting", "Bottom-up: shoot along the smooth normals (Sec. 6.1). Its finest level "
             "resamples the surface (most vertices within about 1% of the size, more where rays miss it): Rebuild Detail and Bake Filter "
             "add that difference back with the finest band, as a fixed offset per vertex that does not turn with "
             "an edited base"),
        ],
        default="PROJECTION",
    )
    keep_parts: BoolProperty(
        name="Keep Parts Apart",
        description="Decompose each connected part of the mesh (eyes, teeth, clothing layers) alone, so that "
        "close parts do not blend and an edit of one part's base leaves the others as they are",
        default=True,
    )
    use_mirror_modifier: BoolProperty(
        name="Use Mirror Modifier",
        description="When the mesh has a Mirror modifier, decompose the half together with its reflection, so "
        "that the seam stays on the mirror plane and merged at every level and gain (axes, mirror object, "
        "merge distance and clipping are read from every Mirror modifier, stacked ones combined)",
        default=True,
    )
    thin_sheets: BoolProperty(
        name="Keep Thin Sheets Apart",
        description="Keep the two sides of walls thinner than the smoothing kernel apart (leaves, ears, "
        "clothing, sheet metal), told apart by the vertex normals (estimated for a mesh without faces). "
        "Surfaces that turn by more than 120 degrees within the kernel are then not smoothed across. "
        "Slower, so off by default",
        default=False,
    )
    # --- state written by Decompose
    n_vertices: IntProperty(name="Vertices", description="Vertex count at decompose time", default=0)
    n_bands: IntProperty(name="Bands", default=0)
    bands: CollectionProperty(type=MULTISCALE_PG_band)
    scale_store: FloatProperty(default=0.0, options={"HIDDEN"})
    scale: FloatProperty(
        name="Scale",
        description="Continuous level: 0 is the smoothest level P^0, the number of bands the original "
        "(drives the Level keys, Eq. 20-21)",
        get=_scale_get,
        set=_scale_set,
        min=0.0,
        soft_max=12.0,
        max=12.0,
        step=5,
    )
    # --- folds (Rebuild Detail, Bake Filter)
    prevent_folds: BoolProperty(
        name="Prevent Folds",
        description="Limit the gain locally, and smoothly, wherever the rebuilt or baked surface would fold over "
        "itself. Points within a few rings of a fold move toward the base; where a fold persists the limit "
        "widens round by round, so it can reach well beyond the points that fold at first. Points out of its "
        "reach stay exactly as they were",
        default=False,
    )
    show_folds: BoolProperty(
        name="Show Folds",
        description="Put the points that fold into the 'Folds' vertex group (weight 1), to see them in Weight Paint",
        default=True,
    )
    # --- display
    detail_band: IntProperty(name="Band", description="Band whose detail coefficients are shown", default=0, min=0)
    # --- morph
    morph_target: PointerProperty(
        name="Target", type=bpy.types.Object, poll=_poll_other_mesh, description="Model B of the morph"
    )
    morph_base: EnumProperty(
        name="Base",
        items=[
            ("ELLIPSOID", "Ellipsoid", "The largest ellipsoid in the common bounding box (Sec. 8.3)"),
            ("OBJECT", "Object", "A chosen mesh as the common base surface"),
        ],
        default="ELLIPSOID",
    )
    morph_base_object: PointerProperty(
        name="Base Object", type=bpy.types.Object, poll=_poll_mesh, description="Common base surface"
    )
    morph_samples: IntProperty(
        name="Base Samples", description="Points sampled on the ellipsoid base", default=40000, min=1000
    )
    morph_align: EnumProperty(
        name="Align",
        description="Carry B onto A before the morph, for models that do not overlap where they lie; at "
        "'B detail' = 1 the morph lands where B is",
        items=[
            ("NONE", "None", "Morph A and B where they lie (they must overlap)"),
            ("BBOX", "Bounding Box", "Move and scale B's bounding box onto A's"),
            ("PCA", "Principal Axes", "Move, turn and scale B's principal axes onto A's"),
            ("ICP", "Closest Points", "Principal axes, then iterative closest points"),
        ],
        default="NONE",
    )
    use_modal: BoolProperty(default=True, options={"HIDDEN"})


CLASSES = [MULTISCALE_PG_band, MULTISCALE_PG_settings]


def register_props():
    bpy.types.Mesh.multiscale = PointerProperty(type=MULTISCALE_PG_settings)


def unregister_props():
    if hasattr(bpy.types.Mesh, "multiscale"):
        del bpy.types.Mesh.multiscale
