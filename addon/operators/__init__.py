"""Operators: ``bpy.ops.pointscale.*``."""

from . import bands, clear, decompose, deform, display, morph

MODULES = [decompose, deform, bands, display, morph, clear]
CLASSES = [cls for module in MODULES for cls in module.CLASSES]
