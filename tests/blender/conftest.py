"""Fixtures for tests that run inside Blender through the ``bpy`` module (pip install bpy).

Every test starts from an empty factory scene. The add-on is loaded from the
source tree (addon/) under the package name ``pointscale_addon``; test_install
checks the built zip separately.
"""

from pathlib import Path

import pytest

bpy = pytest.importorskip("bpy", reason="needs Blender as a Python module: pip install bpy (4.5 LTS)")
ps = pytest.importorskip("pointscale", reason="needs the pointscale engine: pip install -e .")

from blender_helpers import load_addon  # noqa: E402


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
