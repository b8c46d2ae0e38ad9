"""Decompose and Create Morph from the UI button: the engine in a worker thread under a modal
handler (addon/operators/_background.py), with progress, Esc to cancel and nothing written
until it ends. Modal operators need a window, which Blender as a Python module has not: these
tests drive the operators' own start, modal and finish code from a stand-in window manager,
timer events and Esc, as Blender would."""

import time
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

import blender_helpers as h

pytestmark = pytest.mark.blender


class _WindowManager:
    """What the modal code asks of bpy.types.WindowManager, recorded."""

    def __init__(self):
        self.timers, self.handlers, self.progress = [], [], []

    def event_timer_add(self, interval, window=None):
        timer = SimpleNamespace(interval=interval)
        self.timers.append(timer)
        return timer

    def event_timer_remove(self, timer):
        self.timers.remove(timer)

    def modal_handler_add(self, operator):
        self.handlers.append(operator)

    def progress_begin(self, low, high):
        self.progress.append("begin")

    def progress_update(self, value):
        self.progress.append(value)

    def progress_end(self):
        self.progress.append("end")


class _Workspace:
    def __init__(self):
        self.status = []

    def status_text_set(self, text):
        self.status.append(text)


class _Context:
    """bpy.context with a window: the stand-in window manager and workspace, no area."""

    def __init__(self):
        self.window = object()
        self.window_manager = _WindowManager()
        self.workspace = _Workspace()
        self.area = None

    def __getattr__(self, name):
        return getattr(bpy.context, name)


def _driver(operator_class):
    """The operator's own methods on a plain object (bpy operators cannot be made outside
    bpy.ops), its reports recorded."""
    names = ("start_in_background", "_prepare", "finished", "failed", "cancelled_report", "_finish")

    class Driver(operator_class.__mro__[1]):  # RunsInBackground
        pass

    for name in names:
        if hasattr(operator_class, name):
            setattr(Driver, name, getattr(operator_class, name))
    driver = Driver()
    driver.reports = []
    driver.report = lambda kind, message: driver.reports.append((next(iter(kind)), message))
    return driver


def _run(driver, context, *, esc_at=None, before_end=None, timeout=120.0):
    """Timer events until the modal ends (Esc as the esc_at-th event); returns its result."""
    timer = context.window_manager.timers[0]
    deadline, k = time.monotonic() + timeout, 0
    while time.monotonic() < deadline:
        if esc_at is not None and k == esc_at:
            event = SimpleNamespace(type="ESC", value="PRESS", timer=None)
        else:
            event = SimpleNamespace(type="TIMER", value="NOTHING", timer=timer)
            if before_end is not None and not driver._job.running:
                before_end()
                before_end = None
        k += 1
        result = driver.modal(context, event)
        if result != {"RUNNING_MODAL"}:
            return result
        time.sleep(0.01)
    raise AssertionError("the modal did not end")


def _morph_models():
    A, B, _, _ = h.two_models(scale=2)
    return A, B


def _morph_class(addon):
    return addon.operators.morph.POINTSCALE_OT_morph


def _decompose_class(addon):
    return addon.operators.decompose.POINTSCALE_OT_decompose


def test_create_morph_runs_in_the_background_and_makes_what_execute_makes(addon):
    A, B = _morph_models()
    context = _Context()
    driver = _driver(_morph_class(addon))
    assert driver.start_in_background(context) == {"RUNNING_MODAL"}
    assert context.window_manager.handlers == [driver] and len(context.window_manager.timers) == 1
    assert "Esc to cancel" in context.workspace.status[-1] and "morphing 'A' towards 'B'" in context.workspace.status[-1]
    assert len(bpy.data.objects) == 2                      # nothing is made while it runs
    assert _run(driver, context) == {"FINISHED"}
    made = bpy.context.active_object
    assert made.name == "A x B" and set(made.data.shape_keys.key_blocks.keys()) == {"Basis", "A detail", "B detail"}
    assert context.window_manager.timers == [] and context.window_manager.progress[0] == "begin"
    assert context.window_manager.progress[-1] == "end" and context.workspace.status[-1] is None
    assert driver._job is None                             # the finished operator keeps no arrays
    # The same object as the synchronous operator (scripts, background mode) makes.
    for o in bpy.data.objects:
        o.select_set(o in (A, B))
    bpy.context.view_layer.objects.active = A
    assert bpy.ops.pointscale.morph() == {"FINISHED"}
    again = bpy.context.active_object
    for name in ("Basis", "A detail", "B detail"):
        assert np.array_equal(h.key(made.data, name), h.key(again.data, name)), name


def test_esc_cancels_create_morph_and_makes_nothing(addon):
    _morph_models()
    context = _Context()
    driver = _driver(_morph_class(addon))
    driver.start_in_background(context)
    assert _run(driver, context, esc_at=0) == {"CANCELLED"}
    assert driver.reports == [("WARNING", "Create Morph cancelled; nothing was made")]
    assert len(bpy.data.objects) == 2 and len(bpy.data.meshes) == 2
    assert context.window_manager.timers == [] and context.workspace.status[-1] is None


def test_a_morph_whose_target_is_deleted_meanwhile_makes_nothing(addon):
    A, B = _morph_models()
    context = _Context()
    driver = _driver(_morph_class(addon))
    driver.start_in_background(context)
    assert _run(driver, context, before_end=lambda: bpy.data.objects.remove(B)) == {"CANCELLED"}
    assert driver.reports[-1][0] == "ERROR" and "disappeared" in driver.reports[-1][1]
    assert [o.name for o in bpy.data.objects] == ["A"]


def test_an_engine_refusal_in_the_background_is_reported_in_the_panels_words(addon):
    A, B = _morph_models()
    B.data.vertices.foreach_set("co", np.zeros(3 * len(B.data.vertices), np.float32))  # B on one point
    B.data.update()
    context = _Context()
    driver = _driver(_morph_class(addon))
    driver.start_in_background(context)
    assert _run(driver, context) == {"CANCELLED"}
    kind, message = driver.reports[-1]
    assert kind == "ERROR" and message.startswith("Morph: ") and "'B'" in message, message
    assert len(bpy.data.objects) == 2


def test_decompose_runs_in_the_background_marks_the_mesh_busy_and_writes_at_the_end(addon):
    obj = h.mesh_object(h.noisy_sphere(6000))
    context = _Context()
    driver = _driver(_decompose_class(addon))
    assert driver.start_in_background(context) == {"RUNNING_MODAL"}
    state = addon.state
    assert obj.session_uid in state.running            # no second job on it meanwhile
    assert obj.data.shape_keys is None                  # nothing written while it runs
    assert _run(driver, context) == {"FINISHED"}
    assert obj.session_uid not in state.running
    assert obj.data.multiscale.n_bands == 3 and "Level 0" in obj.data.shape_keys.key_blocks
    assert driver._job is None and driver._points is None
    assert context.window_manager.timers == [] and context.workspace.status[-1] is None


def test_esc_cancels_decompose_and_leaves_the_mesh_as_it_was(addon):
    obj = h.mesh_object(h.noisy_sphere(6000))
    before = h.vertices(obj.data)
    context = _Context()
    driver = _driver(_decompose_class(addon))
    driver.start_in_background(context)
    assert _run(driver, context, esc_at=0) == {"CANCELLED"}
    assert driver.reports == [("WARNING", "Decompose cancelled; the mesh is unchanged")]
    assert obj.data.shape_keys is None and np.array_equal(h.vertices(obj.data), before)
    assert obj.session_uid not in addon.state.running


def test_a_decompose_whose_vertices_moved_meanwhile_writes_nothing(addon):
    """The UI stays live while the engine runs: a vertex the artist moved then would be lost
    under keys built from the Basis as it was."""
    obj = h.mesh_object(h.noisy_sphere(6000))
    context = _Context()
    driver = _driver(_decompose_class(addon))
    driver.start_in_background(context)

    def move_a_vertex():
        obj.data.vertices[10].co.z += 0.05
        obj.data.update()

    assert _run(driver, context, before_end=move_a_vertex) == {"CANCELLED"}
    moved = h.vertices(obj.data)[10]
    kind, message = driver.reports[-1]
    assert kind == "ERROR" and "moved while it was being decomposed" in message and "nothing was written" in message
    assert obj.data.shape_keys is None and moved[2] == pytest.approx(h.noisy_sphere(6000)[10, 2] + 0.05, abs=1e-6)
    assert obj.session_uid not in addon.state.running


def test_a_key_named_as_a_result_meanwhile_is_not_taken_over(addon):
    obj = h.mesh_object(h.noisy_sphere(6000))
    context = _Context()
    driver = _driver(_decompose_class(addon))
    driver.start_in_background(context)
    mine = np.full((6000, 3), 0.5)

    def add_my_key():
        obj.shape_key_add(name="Basis")
        key = obj.shape_key_add(name="Level 1")
        key.data.foreach_set("co", mine.astype(np.float32).ravel())

    assert _run(driver, context, before_end=add_my_key) == {"CANCELLED"}
    kind, message = driver.reports[-1]
    assert kind == "ERROR" and "Level 1" in message and "nothing was written" in message, message
    assert list(obj.data.shape_keys.key_blocks.keys()) == ["Basis", "Level 1"]
    assert np.array_equal(h.key(obj.data, "Level 1"), mine)


def test_a_linked_duplicate_waits_for_the_decompose_of_its_mesh(addon):
    """Alt+D shares the mesh: a second Decompose (or Clear, or Rebuild) through the duplicate
    would write the same keys as the job's."""
    obj = h.mesh_object(h.noisy_sphere(6000))
    twin = bpy.data.objects.new("Twin", obj.data)
    bpy.context.scene.collection.objects.link(twin)
    context = _Context()
    driver = _driver(_decompose_class(addon))
    driver.start_in_background(context)
    problem = addon.state.running_problem(twin)
    assert problem and "shared with another object" in problem and "being decomposed" in problem
    bpy.context.view_layer.objects.active = twin
    assert not bpy.ops.pointscale.decompose.poll()
    assert _run(driver, context) == {"FINISHED"}
    assert addon.state.running_problem(twin) is None and not addon.state.running
    assert bpy.ops.pointscale.decompose.poll()


def test_esc_after_the_engine_finished_still_cancels(addon):
    """Esc that comes after the engine's last progress call, before the result is written:
    the status bar said 'cancelling', so nothing is written."""
    obj = h.mesh_object(h.noisy_sphere(6000))
    context = _Context()
    driver = _driver(_decompose_class(addon))
    driver.start_in_background(context)
    assert _run(driver, context, before_end=lambda: driver._job.cancel()) == {"CANCELLED"}
    assert driver.reports == [("WARNING", "Decompose cancelled; the mesh is unchanged")]
    assert obj.data.shape_keys is None and not addon.state.running
