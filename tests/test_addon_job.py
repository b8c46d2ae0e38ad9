"""The worker behind the modal Decompose (addon/job.py), without Blender: the calling thread
keeps running, Esc cancels cleanly, errors reach the caller. Modal operators do not run in
background mode, so this drives the same Job object that the modal operator polls from its
timer; tests/blender/test_job.py runs the operator itself.
"""

import time

import numpy as np
import pytest

import pointscale as ps
from addon_modules import addon_module


@pytest.fixture(scope="module")
def big_cloud():
    return ps.shapes.bumpy_sphere(120000)


def test_main_thread_runs_while_decomposing(big_cloud):
    job_mod, compute = addon_module("job"), addon_module("compute")
    job = job_mod.Job(lambda progress: compute.decompose(ps, big_cloud, progress=progress, levels=4),
                      cancelled_type=ps.Cancelled).start()
    ticks, fractions = 0, set()
    while job.running:
        ticks += 1  # pure-Python work on the "UI" thread
        fractions.add(round(job.fraction, 2))
        time.sleep(0.005)
    assert job.error is None and not job.cancelled
    assert job.result.levels.shape == (3, len(big_cloud), 3)
    assert ticks > 20, "the main thread was starved: is the GIL released?"
    assert len(fractions) >= 3  # progress was reported along the way


def test_cancel_stops_early_and_drops_the_result(big_cloud):
    job_mod, compute = addon_module("job"), addon_module("compute")
    job = job_mod.Job(lambda progress: compute.decompose(ps, big_cloud, progress=progress, levels=4),
                      cancelled_type=ps.Cancelled).start()
    while job.running and job.fraction < 0.05:
        time.sleep(0.002)
    t0 = time.perf_counter()
    job.cancel()
    assert job.wait(timeout=30)
    stop = time.perf_counter() - t0
    assert job.cancelled and job.result is None and job.error is None
    assert stop < 5.0, f"cancel took {stop:.1f} s"


def test_errors_are_handed_to_the_main_thread():
    job_mod, compute = addon_module("job"), addon_module("compute")
    bad = np.zeros((10, 3))
    job = job_mod.Job(lambda progress: compute.decompose(ps, bad, progress=progress), cancelled_type=ps.Cancelled)
    job.start().wait()
    assert isinstance(job.error, ValueError) and not job.cancelled
