"""The shape-key layout that a decompose leaves on a mesh.

``Basis`` (never written), ``Level 0..k-1`` (absolute P^l), ``Band 0..k-1``
(Basis + P^{l+1} - P^l, value = gain - 1, masked by ``Band l mask`` once it is painted),
``Multiscale Edit`` (Rebuild detail) and ``Multiscale Filter`` (Bake filter). What a new
decomposition would write over is kept under a " (previous)" name: the last results, and an
edited ``Level 0``.
"""

from __future__ import annotations

import zlib

import numpy as np

from . import logic, mesh_io, recipe

LEVEL = "Level {}"
BAND = "Band {}"
MASK = "Band {} mask"
EDIT = "Multiscale Edit"
FILTER = "Multiscale Filter"
PREVIOUS = " (previous)"  # a re-decompose keeps the last results, and an edited base, under this suffix
BASE_PREVIOUS = LEVEL.format(0) + PREVIOUS
KEPT = (EDIT + PREVIOUS, FILTER + PREVIOUS, BASE_PREVIOUS)  # kept for the artist: switched off, never rewritten
RESULTS = (EDIT, FILTER) + KEPT  # the keys shown alone over the original, or not at all
WRITTEN_BASE = "pointscale_base"  # mesh ID property: fingerprint of 'Level 0' as Decompose wrote it
# Mesh ID property: {key name: CRC-32 (hex) of its positions as Decompose wrote them}, for the
# Level keys above 0 and the Band keys. Only Level 0 is the base a rebuild reads: an edit of
# another is said to be unused, and kept as "<name> (previous)" when a Decompose or Clear
# would drop it. A checksum, not a hash: Rebuild Detail checks every such key on each call.
WRITTEN_LAYOUT = "pointscale_layout_checksums"
# Mesh ID property: {result key name: fingerprint of its positions as Rebuild Detail or Bake
# Filter last wrote them}, so that an artist's sculpt of a result is kept, not written over.
WRITTEN_RESULTS = "pointscale_results"
OWNED = "pointscale_keys"  # mesh ID property: the key names this add-on created
GROUPS = "pointscale_groups"  # mesh ID property: the vertex groups this add-on created
BAND_MIN = -1.0  # gain 0
BAND_MAX = 4.0  # gain 5


def level_name(l: int) -> str:
    return LEVEL.format(l)


def band_name(l: int) -> str:
    return BAND.format(l)


def mask_name(l: int) -> str:
    return MASK.format(l)


def key_blocks(mesh):
    return None if mesh.shape_keys is None else mesh.shape_keys.key_blocks


def get(mesh, name):
    kbs = key_blocks(mesh)
    return None if kbs is None else kbs.get(name)


CREATED_BASIS = "pointscale_created_basis"  # mesh ID property: the Basis is this add-on's


def ensure_basis(obj):
    if obj.data.shape_keys is None:
        obj.shape_key_add(name="Basis", from_mix=False)
        obj.data.shape_keys.use_relative = True
        obj.data[CREATED_BASIS] = True
    return obj.data.shape_keys.reference_key


def remove_created_basis(obj) -> bool | None:
    """Removes the Basis this add-on created once no other key needs it, so that modifiers can be
    applied again. True when removed, False when other keys still need it, None when it is the
    artist's own (or there is none)."""
    mesh = obj.data
    if not mesh.get(CREATED_BASIS):
        return None
    kbs = key_blocks(mesh)
    if kbs is not None and len(kbs) > 1:
        return False
    if kbs is not None:
        obj.shape_key_clear()  # the mesh keeps the Basis' positions
    del mesh[CREATED_BASIS]
    return True


def removed_basis(mesh, k: int) -> str | None:
    """The name of the add-on's key that became the reference key when the artist removed the
    Basis key (Blender makes the next key the reference), or None. Every other key then moves
    from it, and a Decompose would read it as the shape to decompose."""
    if k < 1 or mesh.shape_keys is None or mesh.shape_keys.reference_key is None:
        return None
    reference = mesh.shape_keys.reference_key.name
    names = {level_name(l) for l in range(k)} | {band_name(l) for l in range(k)} | set(RESULTS)
    return reference if reference in names else None


def basis_from_layout(mesh, k: int) -> tuple:
    """(the original positions, None) back from the finest Level and Band keys
    (logic.basis_from_keys), or (None, why not): a key that holds it removed or edited."""
    top, finest = level_name(k - 1), band_name(k - 1)
    kbs = key_blocks(mesh)
    if kbs is None or top not in kbs or finest not in kbs:
        return None, f"the keys '{top}' and '{finest}' that hold the original shape are gone"
    level, band = mesh_io.read_key(kbs[top]), mesh_io.read_key(kbs[finest])
    written = mesh.get(WRITTEN_LAYOUT) or {}  # checksums of the keys as Decompose wrote them
    edited = [name for name, co in ((top, level), (finest, band)) if name in written and _checksum(co) != written[name]]
    if k == 1 and WRITTEN_BASE in mesh.keys() and _fingerprint(level) != mesh[WRITTEN_BASE]:
        edited.insert(0, top)  # Level 0 has a fingerprint of its own
    if edited:
        return None, f"'{edited[0]}', which holds the original shape, was edited since Decompose"
    return logic.basis_from_keys(level, band), None


def restore_basis(obj, k: int) -> str | None:
    """Makes the reference key a Basis again after the artist removed theirs: the add-on's key
    that took its place is renamed 'Basis' and given the original positions, which the mesh then
    shows; every other key moves from it again. Returns why it cannot (and changes nothing)."""
    mesh = obj.data
    reference = removed_basis(mesh, k)
    if reference is None:
        return None
    co, problem = basis_from_layout(mesh, k)
    if problem:
        return problem
    kb = mesh.shape_keys.reference_key
    mesh_io.write_key(kb, co)
    kb.name = "Basis"
    kb.value = 0.0
    if OWNED in mesh.keys():
        mesh[OWNED] = [name for name in mesh[OWNED] if name != reference]
    mesh_io.write_vertices(mesh, co)
    return None


def owned(mesh, old_k: int) -> set:
    """Key names this add-on created on ``mesh``. Decompositions made before the list was kept
    own the standard names of their ``old_k`` bands."""
    if OWNED in mesh.keys():
        return set(mesh[OWNED])
    if old_k <= 0:
        return set()
    return {level_name(l) for l in range(old_k)} | {band_name(l) for l in range(old_k)} | {EDIT, FILTER}


def layout_problem(mesh, k: int, old_k: int) -> str | None:
    """Why a decompose into k bands cannot write its keys: absolute keys, or a key of the
    artist's with one of the layout's or the results' names (which would be overwritten)."""
    kbs = key_blocks(mesh)
    if kbs is None:
        return None
    if not mesh.shape_keys.use_relative:
        return "its shape keys are absolute (Relative is off): turn Relative on, or remove the keys, first"
    mine = owned(mesh, old_k)
    for name in [level_name(l) for l in range(k)] + [band_name(l) for l in range(k)] + list(RESULTS):
        if name in kbs and name not in mine:
            return f"it has a shape key '{name}' of its own: rename it first, the decomposition writes that name"
    return copies_problem(mesh, edited_layout_keys(mesh, mine), mine)


def result_problem(mesh, name: str, old_k: int) -> str | None:
    """Why Rebuild Detail / Bake Filter cannot write the result key ``name``: a key of the
    artist's has that name (made after the Decompose, which refuses one made before)."""
    if get(mesh, name) is not None and name not in owned(mesh, old_k):
        return (f"it has a shape key '{name}' of its own, and the result is written under that name: "
                "rename that key first; nothing was modified")
    return None


def owned_groups(mesh, old_k: int) -> set:
    """Vertex-group names this add-on created on ``mesh`` (band masks, Folds). Decompositions made
    before the list was kept own the masks of their ``old_k`` bands, and a Folds group they marked."""
    if GROUPS in mesh.keys():
        return set(mesh[GROUPS])
    mine = {mask_name(l) for l in range(old_k)} if old_k > 0 else set()
    if FOLDS_MARKED in mesh.keys():
        mine.add(FOLDS)
    return mine


def set_owned_groups(mesh, names) -> None:
    mesh[GROUPS] = sorted(set(names))


def groups_problem(obj, k: int, old_k: int) -> str | None:
    """Why a decompose into k bands cannot use its mask names: a vertex group of the artist's
    named ``Band l mask`` (the add-on would take it as the band's mask, and Clear remove it)."""
    mine = owned_groups(obj.data, old_k)
    for name in [mask_name(l) for l in range(k)]:
        if obj.vertex_groups.get(name) is not None and name not in mine:
            return (f"it has a vertex group '{name}' of its own: rename it first, the add-on makes that group "
                    "as the band's mask (to use your group as a mask, pick it as the band key's Vertex Group "
                    "after the Decompose)")
    return None


def ensure_key(obj, name: str, co: np.ndarray, slider=(0.0, 1.0)):
    """Create (from the Basis) or reuse the relative key ``name`` and fill it."""
    ref = ensure_basis(obj)
    kb = obj.data.shape_keys.key_blocks.get(name)
    if kb is None:
        kb = obj.shape_key_add(name=name, from_mix=False)
    kb.relative_key = ref
    kb.slider_min, kb.slider_max = slider
    mesh_io.write_key(kb, co)
    return kb


def remove_key(obj, name: str) -> None:
    kb = get(obj.data, name)
    if kb is not None:
        obj.shape_key_remove(kb)


def ensure_mask(obj, l: int):
    """The vertex group ``Band l mask``; a new one starts at weight 1 everywhere (full band).
    Made when the artist first paints the band (0.5 s at 1M vertices), not by Decompose: a band
    key without a vertex group applies fully, as a full mask does. ValueError when a group of
    that name is the artist's own (one this add-on did not make)."""
    name = mask_name(l)
    mesh = obj.data
    mine = owned_groups(mesh, mesh.multiscale.n_bands)
    vg = obj.vertex_groups.get(name)
    if vg is not None and name not in mine:
        raise ValueError(f"'{obj.name}' has a vertex group '{name}' of its own: rename it first, the add-on "
                         "makes that group as the band's mask (or pick your group as the band key's Vertex Group)")
    if vg is None:
        vg = obj.vertex_groups.new(name=name)
        vg.add(range(len(mesh.vertices)), 1.0, "REPLACE")
    set_owned_groups(mesh, mine | {name})
    return vg


FOLDS = "Folds"
FOLDS_MARKED = "pointscale_folds_marked"  # mesh ID property: how many points show_folds last marked


def clear_fold_marks(obj) -> None:
    """Empties the add-on's ``Folds`` group when it marks points: marks of an earlier result
    (Show Folds since turned off, or an earlier decomposition) would tell of folds that are gone."""
    mesh = obj.data
    if mesh.get(FOLDS_MARKED) and obj.vertex_groups.get(FOLDS) is not None:
        show_folds(obj, np.zeros(len(mesh.vertices), dtype=bool))


def show_folds(obj, mask: np.ndarray) -> bool:
    """The vertex group ``Folds``: weight 1 on the points that fold, none elsewhere. False (and
    nothing changed) when a ``Folds`` group is the artist's own, which is never written. The
    active vertex group stays the one the artist had."""
    mesh = obj.data
    mine = owned_groups(mesh, mesh.multiscale.n_bands)
    folded = np.flatnonzero(mask).tolist()
    old = obj.vertex_groups.get(FOLDS)
    if old is not None and FOLDS not in mine:
        return False
    # Nothing folds and the group this add-on left holds nothing: keep it. Removing a group
    # walks every vertex's weights (0.1 s at a million vertices), for no change.
    if not folded and old is not None and mesh.get(FOLDS_MARKED) == 0:
        return True
    active = obj.vertex_groups.active.name if obj.vertex_groups.active is not None else None
    # A new group each time: emptying the old one vertex by vertex took 30 ms at 100k.
    if old is not None:
        obj.vertex_groups.remove(old)
    vg = obj.vertex_groups.new(name=FOLDS)  # becomes the active group
    if folded:
        vg.add(folded, 1.0, "REPLACE")
    mesh[FOLDS_MARKED] = len(folded)
    set_owned_groups(mesh, mine | {FOLDS})
    if active is not None and active != FOLDS:
        obj.vertex_groups.active_index = obj.vertex_groups[active].index
    return True


def write_layout(obj, levels: np.ndarray, bands: np.ndarray, old_k: int, base_fingerprint: str | None = None) -> list:
    """Level and Band keys for k = len(levels) (``bands``: logic.band_key_data). Removes the
    stale keys this add-on made, keeps the last Multiscale Edit / Filter and an edited Level 0
    as "... (previous)", and keeps the active key. Returns the names of the keys it kept that
    way. ``base_fingerprint``: recipe.fingerprint of ``levels[0]`` when the caller made it
    (off the main thread)."""
    mesh = obj.data
    mine = owned(mesh, old_k)
    groups = owned_groups(mesh, old_k)  # recorded from now on, also when the list was not kept yet
    active = obj.active_shape_key.name if obj.active_shape_key is not None else None
    k = levels.shape[0]
    existed = {kb.name for kb in key_blocks(mesh)} if key_blocks(mesh) is not None else set()
    kept = [BASE_PREVIOUS] if keep_edited_base(obj, mine, levels[0]) else []
    kept += keep_edited_layout(obj, mine)
    layout = [level_name(l) for l in range(k)] + [band_name(l) for l in range(k)]
    for l in range(k):
        ensure_key(obj, level_name(l), levels[l]).value = 0.0
    mesh[WRITTEN_BASE] = base_fingerprint or _fingerprint(levels[0])
    mesh[WRITTEN_LAYOUT] = {**{level_name(l): _checksum(levels[l]) for l in range(1, k)},
                            **{band_name(l): _checksum(bands[l]) for l in range(k)},
                            _BASIS_CHECKSUM: _checksum(mesh_io.read_basis(mesh))}
    for l in range(k):
        before = get(mesh, band_name(l))
        chosen = before.vertex_group if before is not None else ""
        kb = ensure_key(obj, band_name(l), bands[l], slider=(BAND_MIN, BAND_MAX))
        kb.value = 0.0
        # A mask in use for an earlier decompose stays in use: the add-on's painted one, or any
        # vertex group the artist picked for the band key; a new band has none (see ensure_mask).
        mask = obj.vertex_groups.get(mask_name(l))
        if chosen and obj.vertex_groups.get(chosen) is not None:
            kb.vertex_group = chosen
        else:
            kb.vertex_group = mask.name if mask is not None and mask.name in groups else ""
    for name in sorted(mine - set(layout) - set(RESULTS)):
        if not name.endswith(PREVIOUS):
            remove_key(obj, name)
    kept += [name + PREVIOUS for name in (EDIT, FILTER) if keep_as_previous(obj, name, mine)]
    # The "(previous)" keys stay the add-on's: the next Decompose replaces them, Clear keeps them.
    mesh[OWNED] = layout + sorted(name for name in mine | set(kept)
                                  if name.endswith(PREVIOUS) and get(mesh, name) is not None)
    set_owned_groups(mesh, groups)
    _in_layout_order(obj, layout, set(layout) - existed)
    _restore_active(obj, active)
    return kept


def _in_layout_order(obj, layout: list, new: set) -> None:
    """Puts the Level and Band keys in layout order (logic.keys_in_layout_order) with Blender's
    Move Shape Key, which keeps every key's data, settings, animation and drivers as they are."""
    import bpy

    names = [kb.name for kb in obj.data.shape_keys.key_blocks]
    moves = logic.moves_up(names, logic.keys_in_layout_order(names, layout, new))
    if not moves:
        return
    try:
        with bpy.context.temp_override(object=obj, active_object=obj):
            for index in moves:
                obj.active_shape_key_index = index
                bpy.ops.object.shape_key_move(type="UP")
    except RuntimeError:
        pass  # Blender refused a move: the keys are all there and right, only listed out of order


def _fingerprint(co) -> str:
    return recipe.fingerprint(np.ascontiguousarray(co, dtype=np.float32))


def _checksum(co) -> str:
    """CRC-32 of the positions as a key holds them (float32), with their count."""
    co = np.ascontiguousarray(co, dtype=np.float32)
    return f"{len(co)}:{zlib.crc32(memoryview(co).cast('B')):08x}"


_BASIS_CHECKSUM = "(Basis)"  # in WRITTEN_LAYOUT: the Basis the keys were written over


def _written_checksums(mesh) -> dict | None:
    """What Decompose wrote into each Level (above 0) and Band key, by name, or None where that
    is unknown (a decomposition made before the checksums were kept) or no key can be compared
    with it (the Basis changed since, and Blender carried that into every relative key)."""
    written = mesh.get(WRITTEN_LAYOUT)
    if written is None:
        return None
    basis = written.get(_BASIS_CHECKSUM)
    if basis is not None and _checksum(mesh_io.read_basis(mesh)) != basis:
        return None
    return {name: checksum for name, checksum in written.items() if name != _BASIS_CHECKSUM}


def renamed_layout_keys(mesh, among=None) -> list:
    """(name, written as) for each key that holds exactly what Decompose wrote into another Level
    or Band key: a key of the add-on's renamed, or two of them swapped. Sliders and bakes read
    each band by its name, so such a key is read as the wrong band, or not at all. among: the
    names to look at (each read once more), or None for every key once a Level or Band key of
    the add-on's is missing (else none can be a renamed one)."""
    written = _written_checksums(mesh)
    kbs = key_blocks(mesh)
    if not written or kbs is None:
        return []
    if among is None:
        if all(name in kbs for name in written):
            return []
        among = [kb.name for kb in kbs if kb != mesh.shape_keys.reference_key]
    by_checksum = {}
    for name, checksum in written.items():
        by_checksum.setdefault(checksum, []).append(name)
    found = []
    for name in among:
        kb = kbs.get(name)
        if kb is None:
            continue
        checksum = _checksum(mesh_io.read_key(kb))
        if written.get(name) == checksum:
            continue  # as written
        others = [other for other in by_checksum.get(checksum, ()) if other != name]
        if len(others) == 1:  # a key that matches several (two zero bands) tells nothing
            found.append((name, others[0]))
    return found


def edited_layout_keys(mesh, mine: set) -> list:
    """The add-on's Level keys above 0 and Band keys whose positions differ from what Decompose
    wrote (none for a decomposition made before the checksums were kept). None either once the
    Basis changed (an edit of the mesh, Apply Scale, a subdivision): Blender carries that change
    into every relative key, which is no edit of theirs."""
    written = mesh.get(WRITTEN_LAYOUT)
    if written is None:
        return []
    basis = written.get(_BASIS_CHECKSUM)
    if basis is not None and _checksum(mesh_io.read_basis(mesh)) != basis:
        return []
    edited = []
    for name, checksum in written.items():
        if name == _BASIS_CHECKSUM:
            continue
        kb = get(mesh, name)
        if kb is not None and name in mine and _checksum(mesh_io.read_key(kb)) != checksum:
            edited.append(name)
    return edited


def layout_messages(mesh, done: str) -> list:
    """The warnings for Level (above 0) and Band keys changed since Decompose: renamed or
    swapped ones (holding what another was written with), which sliders and bakes read as the
    wrong band, and edited ones, which nothing reads."""
    edited = edited_layout_keys(mesh, owned(mesh, mesh.multiscale.n_bands))
    renamed = renamed_layout_keys(mesh, among=edited) if edited else []
    moved = {name for name, _ in renamed}
    edited = [name for name in edited if name not in moved]
    messages = []
    if renamed:
        said = ", ".join(f"{name!r} holds what Decompose wrote as {was!r}" for name, was in renamed)
        messages.append(f"{done}, but {said}: a key of the add-on's was renamed, or two were swapped. Each band's "
                        "slider, the Gain sliders and Bake Filter read a band by its key's name, so they no longer "
                        "agree: rename the keys back")
    if edited:
        names = ", ".join(repr(name) for name in edited)
        messages.append(
            f"{done}, but {names} {'was' if len(edited) == 1 else 'were'} edited since Decompose and "
            f"{'is' if len(edited) == 1 else 'are'} not used: only '{level_name(0)}' is the base it builds on "
            f"(Edit Base edits it). A new Decompose or Clear keeps "
            f"{'it as ' + repr(edited[0] + PREVIOUS) if len(edited) == 1 else 'each as <name>' + PREVIOUS}")
    return messages


def is_edited_layout_copy(name: str) -> bool:
    """Whether ``name`` is a kept copy of an edited Level (above 0) or Band key."""
    if not name.endswith(PREVIOUS) or name == BASE_PREVIOUS:
        return False
    original = name[: -len(PREVIOUS)]
    return original.startswith(("Level ", "Band ")) and original.split(" ", 1)[1].isdigit()


def keep_edited_layout(obj, mine: set) -> list:
    """Copies each edited Level (above 0) and Band key into "<name> (previous)", switched off
    (replacing an older one of the add-on's), before a new decomposition or Clear writes over
    it or removes it. Returns the names made. An artist's own key of such a name is never
    written over: ValueError (own_key_problem)."""
    edited = edited_layout_keys(obj.data, mine)
    problem = copies_problem(obj.data, edited, mine)
    if problem:
        raise ValueError(problem)
    return [_keep_copy(obj, name, mesh_io.read_key(get(obj.data, name)), mine) for name in edited]


def copies_problem(mesh, names, mine: set) -> str | None:
    """Why the keys ``names`` cannot be kept as "<name> (previous)": the artist has a key of
    such a name of their own (own_key_problem), or None."""
    return next((p for p in (own_key_problem(mesh, name + PREVIOUS, mine) for name in names) if p), None)


def to_keep(mesh, mine: set) -> list:
    """The names of the keys a Clear (or a new Decompose) keeps as "(previous)": an edited
    Level 0, the edited Level and Band keys above it, and the last results."""
    names = [level_name(0)] if edited_base(mesh, mine) is not None else []
    names += edited_layout_keys(mesh, mine)
    return names + [name for name in (EDIT, FILTER) if name in mine and get(mesh, name) is not None]


def _keep_copy(obj, name: str, co, mine: set) -> str:
    """``co`` written into the key "<name> (previous)", switched off, as the add-on's."""
    ensure_key(obj, name + PREVIOUS, co).value = 0.0
    mine.add(name + PREVIOUS)
    return name + PREVIOUS


def key_fingerprint(mesh, name: str) -> str | None:
    """A fingerprint of the key ``name``'s positions as they are now, or None without that key."""
    kb = get(mesh, name)
    return None if kb is None else _fingerprint(mesh_io.read_key(kb))


_LAST_SHOWN = "(last shown)"  # in WRITTEN_RESULTS: the result key written and shown last


def record_written_result(mesh, name: str, co) -> None:
    """Keeps the fingerprint of the result key ``name`` as just written with positions ``co``,
    and that it is the one shown last."""
    written = dict(mesh[WRITTEN_RESULTS]) if WRITTEN_RESULTS in mesh.keys() else {}
    written[name] = _fingerprint(co)
    written[_LAST_SHOWN] = name
    mesh[WRITTEN_RESULTS] = written


def last_written_result(mesh) -> str | None:
    """The result key Rebuild Detail or Bake Filter wrote and showed last, or None."""
    return mesh[WRITTEN_RESULTS].get(_LAST_SHOWN) if WRITTEN_RESULTS in mesh.keys() else None


def result_edited(mesh, name: str, mine: set) -> bool:
    """Whether the add-on's result key ``name`` changed since the add-on wrote it (an artist
    sculpted or tweaked it). One written before fingerprints were kept (an older file) is not
    known to be edited, and counts as not: keeping it would replace the '(previous)' key the
    file may hold, an earlier sculpt kept for the artist, with a result nobody changed."""
    kb = get(mesh, name)
    if kb is None or name not in mine or WRITTEN_RESULTS not in mesh.keys():
        return False
    written = mesh[WRITTEN_RESULTS]
    return name in written and _fingerprint(mesh_io.read_key(kb)) != written[name]


def edited_base(mesh, mine: set, written=None) -> np.ndarray | None:
    """The 'Level 0' key's positions when the artist edited them since the Decompose wrote it,
    else None. Decompositions made before the fingerprint was kept count as edited when the key
    differs from ``written`` (the base about to be written), or, without one, always: better
    an unneeded copy than a lost edit."""
    kb = get(mesh, level_name(0))
    if kb is None or level_name(0) not in mine:
        return None
    co = mesh_io.read_key(kb)
    if WRITTEN_BASE in mesh.keys():
        return co if _fingerprint(co) != mesh[WRITTEN_BASE] else None
    if written is not None and np.array_equal(co, np.asarray(written, dtype=np.float32)):
        return None
    return co


def own_key_problem(mesh, name: str, mine: set) -> str | None:
    """Why the add-on cannot keep something under the key ``name``: the artist has a key of that
    name of their own, which it must not write over."""
    if get(mesh, name) is not None and name not in mine:
        return (f"the mesh has a shape key '{name}' of its own, where the add-on keeps its earlier result; rename "
                "that key first")
    return None


def keep_edited_base(obj, mine: set, written=None) -> bool:
    """Copies an edited 'Level 0' into the key 'Level 0 (previous)' (replacing an older one),
    switched off, before a new decomposition or Clear writes over it or removes it. An artist's
    own key of that name is never written over: ValueError (own_key_problem)."""
    co = edited_base(obj.data, mine, written)
    if co is None:
        return False
    problem = copies_problem(obj.data, [level_name(0)], mine)
    if problem:
        raise ValueError(problem)
    _keep_copy(obj, level_name(0), co, mine)
    return True


def keep_as_previous(obj, name: str, mine: set) -> bool:
    """Renames the add-on's result key ``name`` to "name (previous)", switched off, replacing an
    older one of the add-on's (an artist's key of that name is refused before: layout_problem)."""
    kb = get(obj.data, name)
    if kb is None or name not in mine:
        return False
    problem = own_key_problem(obj.data, name + PREVIOUS, mine)
    if problem:  # Blender would name ours '.001' and the artist's key would pass for ours
        raise ValueError(problem)
    if name + PREVIOUS in mine:
        remove_key(obj, name + PREVIOUS)
    kb.name = name + PREVIOUS
    kb.value = 0.0  # kept, not shown: what replaces it is shown alone
    from .animation import animation_back_to  # (animation.py reads the key names from here)
    animation_back_to(obj.data.shape_keys, name + PREVIOUS, name)
    mine.add(name + PREVIOUS)
    return True


def remove_layout(obj, k: int) -> tuple:
    """Removes the keys this add-on made, but for the kept "(previous)" keys, which stay
    recorded as the add-on's (a later Decompose replaces them); an edited Level 0 and the last
    Multiscale Edit and Filter are kept as ones first, as a new Decompose keeps them. Returns
    (the names of those it made now, the names of older ones it kept)."""
    mesh = obj.data
    active = obj.active_shape_key.name if obj.active_shape_key is not None else None
    mine = owned(mesh, k)
    made = [BASE_PREVIOUS] if keep_edited_base(obj, mine) else []
    made += keep_edited_layout(obj, mine)
    for name in (EDIT, FILTER):
        if keep_as_previous(obj, name, mine):
            made.append(name + PREVIOUS)
            if active == name:
                active = name + PREVIOUS
    kept = sorted(name for name in mine if name.endswith(PREVIOUS) and get(mesh, name) is not None)
    for name in sorted(mine - set(kept)):
        remove_key(obj, name)
    if kept:
        mesh[OWNED] = kept
    elif OWNED in mesh.keys():
        del mesh[OWNED]
    for prop in (WRITTEN_BASE, WRITTEN_LAYOUT, WRITTEN_RESULTS):
        if prop in mesh.keys():
            del mesh[prop]
    _restore_active(obj, active)
    return made, [name for name in kept if name not in made]


def add_owned(mesh, name: str) -> None:
    """Records a key made after the decompose (Multiscale Edit / Filter) as the add-on's."""
    names = list(mesh[OWNED]) if OWNED in mesh.keys() else sorted(owned(mesh, mesh.multiscale.n_bands))
    if name not in names:
        mesh[OWNED] = names + [name]


def _restore_active(obj, name) -> None:
    # Removing keys shifts the active index; keep the artist on the key they had, or the Basis.
    kbs = key_blocks(obj.data)
    if kbs is None:
        return
    i = kbs.find(name) if name else -1
    obj.active_shape_key_index = max(i, 0)


def set_scale(mesh, t: float, k: int) -> None:
    """Level key values that show the blend P(t) (Eq. 20-21)."""
    values = logic.level_key_values(t, k)
    for l in range(k):
        kb = get(mesh, level_name(l))
        if kb is not None:
            kb.value = float(values[l])


def band_values(mesh, k: int) -> np.ndarray:
    out = np.zeros(k)
    for l in range(k):
        kb = get(mesh, band_name(l))
        if kb is not None and not kb.mute:
            out[l] = kb.value
    return out


def band_masks(obj, k: int) -> list:
    """Mask names in use per band (None when a band key has no mask)."""
    names = []
    for l in range(k):
        kb = get(obj.data, band_name(l))
        names.append(kb.vertex_group if kb is not None and kb.vertex_group else None)
    return names
