"""Pointscale: multiscale point-sampled surfaces after Pauly, Kobbelt and Gross (2006).

A surface becomes a smooth base P^0 and a stack of signed normal-displacement bands, so that
detail can be filtered band by band, carried along a deformed base, or moved between models.
"""
from ._core import Cancelled
from .multiscale import (Decomposition, Reconstructor, blend, coarse_base_warning, decompose, decompose_rayshoot,
                         load, rays_missed_points, rays_missed_warning, reconstruct, reconstruct_levels)
from .surface import decimate, estimate_normals, project
from .folds import Folds, find_folds
from .mirror import Mirror
from .morphing import Morph, morph
from .operators import diffusion_levels, ellipsoid_base, encode, project_sheets, shoot_rays, smooth_diffusion
from . import alignment, io, meshes, mirror, parts, shapes

__version__ = "0.1.0"
__all__ = [
    "Cancelled", "Decomposition", "Folds", "Mirror", "Reconstructor", "blend", "find_folds", "coarse_base_warning", "decimate", "decompose",
    "estimate_normals", "load",
    "io", "project", "reconstruct", "reconstruct_levels", "shapes",
    "Morph", "decompose_rayshoot", "diffusion_levels", "ellipsoid_base", "encode", "morph", "project_sheets",
    "rays_missed_points", "rays_missed_warning", "shoot_rays", "smooth_diffusion",
]
