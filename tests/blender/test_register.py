"""Check 1: the add-on registers and unregisters twice, cleanly."""

import bpy

from blender_helpers import load_addon


def _registered():
    return (
        hasattr(bpy.types.Mesh, "multiscale"),
        hasattr(bpy.types, "POINTSCALE_PT_main"),
        hasattr(bpy.types, "POINTSCALE_OT_decompose"),
    )


def test_register_unregister_twice(addon):
    module = load_addon()
    assert _registered() == (True, True, True)
    for _ in range(2):
        module.unregister()
        assert _registered() == (False, False, False)
        assert module._on_load not in bpy.app.handlers.load_post
        module.register()
        assert _registered() == (True, True, True)
        assert bpy.app.handlers.load_post.count(module._on_load) == 1
    # registering over a registration is harmless too
    module.register()
    assert _registered() == (True, True, True)
    bpy.ops.mesh.primitive_cube_add()
    assert bpy.context.object.data.multiscale.levels == 4
    assert bpy.ops.pointscale.decompose.poll()
