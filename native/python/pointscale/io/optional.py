"""Libraries that only some formats need, imported when a file of that format is opened, so that
`import pointscale` (and Blender, which bundles only the engine) never needs them."""
from __future__ import annotations

import importlib


def optional_module(name: str, formats: str, install: str):
    """The module `name`, or a ValueError saying which pip package the `formats` need."""
    try:
        return importlib.import_module(name)
    except ImportError:
        raise ValueError(f"reading and writing {formats} needs {name}: pip install {install}") from None
