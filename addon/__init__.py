"""Pointscale Multiscale: multiscale editing of meshes and point clouds (Pauly, Kobbelt, Gross 2006).

Registration only; see the modules for the rest.  Safe to register and
unregister repeatedly.
"""

import bpy

from . import operators, panels, preferences, properties

_MODULES = [properties, preferences, operators, panels]
_registered = False


@bpy.app.handlers.persistent
def _on_load(*_args):
    from . import writeback

    writeback.forget_all()  # cached engine objects belong to the previous file


def _classes():
    return [cls for module in _MODULES for cls in module.CLASSES]


def register():
    global _registered
    if _registered:
        unregister()
    for cls in _classes():
        try:
            bpy.utils.register_class(cls)
        except ValueError:  # already registered by an earlier, unbalanced load
            bpy.utils.unregister_class(cls)
            bpy.utils.register_class(cls)
    properties.register_props()
    if _on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_on_load)
    _registered = True


def unregister():
    global _registered
    from . import writeback

    writeback.forget_all()
    if _on_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_on_load)
    properties.unregister_props()
    for cls in reversed(_classes()):
        if cls.is_registered:
            bpy.utils.unregister_class(cls)
    _registered = False
