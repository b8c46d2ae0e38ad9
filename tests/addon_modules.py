"""The add-on's modules that need no Blender (logic, compute, job, recipe...), imported from
addon/ without running addon/__init__.py, which imports bpy to register the add-on. So their
tests run in any environment with the engine, bpy or not (tests/blender has the rest)."""

import importlib
import sys
import types
from pathlib import Path

ADDON = Path(__file__).resolve().parents[1] / "addon"
PACKAGE = "pointscale_addon_without_bpy"  # apart from tests/blender's "pointscale_addon"


def addon_module(name: str):
    """addon/<name>.py as a module; its relative imports load their siblings the same way."""
    if PACKAGE not in sys.modules:
        package = types.ModuleType(PACKAGE)
        package.__path__ = [str(ADDON)]  # a package whose __init__ never runs
        sys.modules[PACKAGE] = package
    module = importlib.import_module(f"{PACKAGE}.{name}")
    assert "bpy" not in getattr(module, "__dict__", {}), f"addon/{name}.py imports bpy"
    return module
