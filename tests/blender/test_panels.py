"""The sidebar panels draw without errors in every state (no UI in background mode, so a
recording stand-in plays the layout) and explain what is missing."""

import bpy
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


class FakeLayout:
    def __init__(self, log):
        self.log = log
        self.use_property_split = False
        self.use_property_decorate = False
        self.scale_y = 1.0

    def __getattr__(self, name):
        def call(*args, **kw):
            self.log.append((name, args, kw))
            if name in {"prop"}:
                data, prop = args[0], args[1]
                assert hasattr(data, prop), f"no property {prop!r} on {data!r}"
            if name == "operator":
                idname = args[0]
                mod, op = idname.split(".")
                getattr(getattr(bpy.ops, mod), op).get_rna_type()  # raises if not registered
                return _OpProps()
            return FakeLayout(self.log)

        return call


class _OpProps:
    def __setattr__(self, name, value):
        object.__setattr__(self, name, value)


def draw_all(context):
    log = []
    classes = [getattr(bpy.types, n) for n in dir(bpy.types) if n.startswith("POINTSCALE_PT_")]
    assert len(classes) == 7
    for cls in classes:
        if cls.poll(context):
            panel = type("P", (), {"layout": FakeLayout(log)})()
            cls.draw(panel, context)
    return log


def labels(log):
    return " ".join(str(kw.get("text", "")) for name, args, kw in log if name == "label")


def test_panels_draw_in_every_state():
    bpy.ops.object.camera_add()
    assert "not a mesh" in labels(draw_all(bpy.context))
    obj = h.mesh_object(h.noisy_sphere(4000))
    before = draw_all(bpy.context)
    assert any(name == "operator" and args[0] == "pointscale.decompose" for name, args, kw in before)
    h.decompose(obj)
    after = draw_all(bpy.context)
    ops = {args[0] for name, args, kw in after if name == "operator"}
    assert {"pointscale.rebuild_detail", "pointscale.paint_band_mask", "pointscale.show_details",
            "pointscale.bake_filter", "pointscale.edit_base", "pointscale.morph"} <= ops
    assert "3 bands" in labels(after)
    assert "morph" in labels(after).lower() or "target" in labels(after).lower()
