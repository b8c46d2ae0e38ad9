"""Whether a band's value is keyframed or driven: its key's value, or the panel's Gain slider."""

from __future__ import annotations

from . import keys


def band_animated(mesh, l: int) -> bool:
    """Whether band l's value has keyframes or a driver: on its shape key, or on the panel's
    Gain slider (the mesh's multiscale.bands[l].gain, where hovering it and pressing I puts them)."""
    return (_animated(mesh.shape_keys, f'key_blocks["{keys.band_name(l)}"].value')
            or _animated(mesh, f"multiscale.bands[{l}].gain"))


def scale_animated(mesh, k: int) -> bool:
    """Whether what shows the levels has keyframes or a driver: the panel's Scale slider (the
    mesh's multiscale.scale) or a Level key's value. A result is shown alone at Scale k; they
    set the levels' mix again on the next frame, under the result."""
    return (_animated(mesh, "multiscale.scale")
            or any(_animated(mesh.shape_keys, f'key_blocks["{keys.level_name(l)}"].value') for l in range(k)))


def _animated(owner, path: str) -> bool:
    """Whether ``owner``'s property at ``path`` has keyframes or a driver: in its action, in a
    strip of its NLA tracks that is not muted, or as a driver."""
    animation = owner.animation_data if owner is not None else None
    if animation is None:
        return False
    return any(c.data_path == path for c in list(animation.drivers) + _own_fcurves(animation, with_nla=True))


def _own_fcurves(animation, with_nla: bool = False) -> list:
    """The F-curves that animate ``animation``'s owner: its action's (the slot it is assigned,
    from Blender 4.4 on: an action shared by several objects keeps each one's curves in its own
    slot) and, with_nla, those of its unmuted NLA strips'."""
    curves = _fcurves(animation.action, getattr(animation, "action_slot", None))
    if with_nla:
        for track in animation.nla_tracks:
            if track.mute:
                continue
            for strip in track.strips:
                if not strip.mute:
                    curves += _fcurves(strip.action, getattr(strip, "action_slot", None))
    return curves


def _fcurves(action, slot=None) -> list:
    """An action's F-curves for ``slot`` (_curve_collections)."""
    return [c for curves in _curve_collections(action, slot) for c in curves]


def _curve_collections(action, slot=None) -> list:
    """The F-curve collections of an action for ``slot``: a layered action's (Blender 4.4 on)
    channel bags of that slot, or a legacy action's Action.fcurves (gone from 5.0 on)."""
    if action is None:
        return []
    layers = list(getattr(action, "layers", ()))
    if layers:
        if slot is None:
            return []  # no slot assigned: the action animates nothing here
        bags = [strip.channelbag(slot) for layer in layers for strip in layer.strips if hasattr(strip, "channelbag")]
        return [bag.fcurves for bag in bags if bag is not None]
    return [action.fcurves] if hasattr(action, "fcurves") else []


def animation_back_to(shape_keys, renamed: str, name: str) -> None:
    """Blender's rename of the key ``name`` to ``renamed`` carried its value's keyframes and
    driver along; they are the result's animation, so they go to the new key of ``name``: the
    renamed one, kept switched off, would be switched on again by them."""
    animation = shape_keys.animation_data if shape_keys is not None else None
    if animation is None:
        return
    old, new = f'key_blocks["{renamed}"].value', f'key_blocks["{name}"].value'
    for curve in list(animation.drivers) + _own_fcurves(animation):
        if curve.data_path == old:
            curve.data_path = new


def own_action(owner):
    """A copy of ``owner`` (Object.copy(), Mesh.copy()) shares its original's action: a keyframe
    put on the copy would change the original's animation. The copy gets its own copy of the
    action, on the same slot (Blender 4.4 on), as Duplicate gives by default. Returns that copy,
    or None where there was no action."""
    animation = owner.animation_data if owner is not None else None
    if animation is None or animation.action is None:
        return None
    slot = getattr(animation, "action_slot", None)
    identifier = slot.identifier if slot is not None else None
    copy = animation.action.copy()
    animation.action = copy
    if identifier is not None and getattr(animation, "action_slot", None) is None:
        match = [s for s in copy.slots if s.identifier == identifier]
        if match:
            animation.action_slot = match[0]
    return copy


def drop_curves(owner, prefix: str) -> None:
    """Removes the F-curves of ``owner``'s own action whose data path starts with ``prefix``:
    a copy's curves of properties it no longer has (a morph's mesh, without A's decomposition)."""
    animation = owner.animation_data if owner is not None else None
    if animation is None:
        return
    for curves in _curve_collections(animation.action, getattr(animation, "action_slot", None)):
        for curve in [c for c in curves if c.data_path.startswith(prefix)]:
            curves.remove(curve)
