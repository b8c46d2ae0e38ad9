"""Fixtures for tests that run inside Blender through the ``bpy`` module (pip install bpy).

Every test starts from an empty factory scene. The add-on is loaded from the
source tree (addon/) under the package name ``pointscale_addon``; test_install
checks the built zip separately.
"""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

bpy = pytest.importorskip("bpy", reason="needs Blender as a Python module: pip install bpy (4.5 LTS)")
ps = pytest.importorskip("pointscale", reason="needs the pointscale engine: pip install -e .")

ROOT = Path(__file__).resolve().parents[2]
ADDON_NAME = "pointscale_addon"


def load_addon():
    if ADDON_NAME in sys.modules:
        return sys.modules[ADDON_NAME]
    spec = importlib.util.spec_from_file_location(
        ADDON_NAME, ROOT / "addon" / "__init__.py", submodule_search_locations=[str(ROOT / "addon")]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[ADDON_NAME] = module
    spec.loader.exec_module(module)
    return module


def pytest_collection_modifyitems(config, items):
    here = Path(__file__).parent
    for item in items:
        if here in Path(item.fspath).parents:
            item.add_marker(pytest.mark.blender)


@pytest.fixture(scope="session")
def addon():
    module = load_addon()
    module.register()
    yield module
    module.unregister()


@pytest.fixture(autouse=True)
def empty_scene(addon):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    yield


def diagonal(points) -> float:
    points = np.asarray(points)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
