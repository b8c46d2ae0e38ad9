"""The core releases the GIL, uses every core, and can be cancelled cleanly."""
import os
import threading
import time

import numpy as np
import pytest

import pointscale as ps


@pytest.fixture(scope="module")
def big():
    return ps.shapes.bumpy_sphere(300000, noise=0.001)


def test_python_keeps_running_during_a_decompose(big):
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    t = threading.Thread(target=ticker)
    t.start()
    start = time.perf_counter()
    ps.decompose(big, levels=3)
    elapsed = time.perf_counter() - start
    stop.set()
    t.join()
    during = [x for x in ticks if start <= x <= start + elapsed]
    # With the GIL held the ticker would stall for the whole call.
    assert len(during) > 0.3 * elapsed / 0.005, (len(during), elapsed)


def _threads_of_this_process() -> int:
    return len(os.listdir("/proc/self/task"))


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores")
@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads through Linux's /proc")
def test_the_core_starts_a_second_thread(big):
    # Counts the threads that exist during a projection, not how much CPU they got: a busy
    # machine delays a worker but does not stop the core from starting it. How much the second
    # core speeds things up is measured in bench/cores_bench.py, not asserted here.
    surface = big[::3]
    before = _threads_of_this_process()
    seen = []
    stop = threading.Event()

    def sampler():
        while not stop.is_set():
            seen.append(_threads_of_this_process())
            time.sleep(0.001)

    t = threading.Thread(target=sampler)
    t.start()
    try:
        ps.project(big, surface, threads=2)
    finally:
        stop.set()
        t.join()
    # `before` counts the main thread; the sampler adds one, a second core worker one more.
    assert max(seen) >= before + 2, (before, max(seen))
    # threads=1 keeps the work on the calling thread.
    seen.clear()
    stop.clear()
    t = threading.Thread(target=sampler)
    t.start()
    try:
        ps.project(big[:100000], surface, threads=1)
    finally:
        stop.set()
        t.join()
    assert max(seen) == before + 1, (before, max(seen))


def test_progress_reports_and_cancel_stops_cleanly(big):
    seen = []
    ps.decompose(big[:50000], levels=3, progress=lambda f: seen.append(f) or True)
    assert seen and seen[-1] == pytest.approx(1.0) and all(0 <= f <= 1 for f in seen)
    assert seen == sorted(seen)

    calls = []

    def cancel_soon(f):
        calls.append(f)
        return f < 0.2

    start = time.perf_counter()
    with pytest.raises(ps.Cancelled):
        ps.decompose(big, levels=3, progress=cancel_soon)
    assert max(calls) < 0.5  # stopped early, not at the end
    # Nothing half-written stays behind: a new run works and gives the exact result.
    dec = ps.decompose(big[:50000], levels=3)
    assert np.abs(ps.reconstruct(dec) - big[:50000]).max() < 1e-9


def test_an_exception_in_the_callback_propagates(big):
    def boom(f):
        raise RuntimeError("from the callback")

    with pytest.raises(RuntimeError, match="from the callback"):
        ps.decompose(big[:50000], levels=3, progress=boom)


def test_results_do_not_depend_on_the_thread_count():
    # Work is split into the same chunks whatever the thread count, and nothing a chunk
    # computes depends on another: the decompositions agree to the last bit. Eight threads on
    # fewer cores still start eight workers, and the decimation splits 8 times as many
    # subtrees in parallel, each keeping its nodes in its own share of one block.
    points = ps.shapes.bumpy_sphere(60000, noise=0.002)
    one = ps.decompose(points, levels=4, threads=1)
    for threads in (2, 8):
        other = ps.decompose(points, levels=4, threads=threads)
        assert np.array_equal(one.details, other.details)
        assert np.array_equal(one.base, other.base)
        assert np.array_equal(ps.reconstruct(one), ps.reconstruct(other))


def test_a_reconstructor_called_from_several_threads_gives_each_its_own_result():
    from concurrent.futures import ThreadPoolExecutor
    points = ps.shapes.bumpy_sphere(20000)
    dec = ps.decompose(points, levels=4)
    solver = ps.Reconstructor(dec)
    gains = [np.array([1.0, g, 2.0 - g]) for g in np.linspace(0.0, 2.0, 8)]
    expected = [ps.reconstruct(dec, gains=g) for g in gains]
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda g: solver.reconstruct(gains=g), gains))
    for got, want in zip(results, expected):
        assert np.array_equal(got, want)


def test_reconstruct_from_several_threads_on_one_decomposition_gives_each_its_own_result():
    # Calls on one decomposition share only what every edit needs (found by whichever call gets
    # there first, then read only), never their working storage.
    from concurrent.futures import ThreadPoolExecutor
    points = ps.shapes.bumpy_sphere(20000)
    dec = ps.decompose(points, levels=4)
    base = dec.base * 1.1
    gains = [np.array([1.0, g, 2.0 - g]) for g in np.linspace(0.0, 2.0, 8)] + [np.ones(3)]
    # With nothing kept, straight from the model:
    expected = [dec._model.reconstruct(g, base=base, origin=dec.origin) for g in gains]
    assert "edit" not in dec._cache  # the threads below find it
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda g: ps.reconstruct(dec, gains=g, base=base), gains * 3))
    for i, got in enumerate(results):
        assert np.array_equal(got, expected[i % len(gains)])
    assert "edit" in dec._cache


def _thread_ids() -> set:
    return set(os.listdir("/proc/self/task"))


def _threads_started_during(call) -> set:
    """The threads, other than the sampler, that this process started while call() ran: its
    thread ids are sampled every millisecond, and ids only ever join the set when a thread
    starts (one that ends before the first sample cannot be mistaken for a new one)."""
    before = _thread_ids()
    seen = set()
    sampler_id = []
    stop = threading.Event()

    def sampler():
        sampler_id.append(str(threading.get_native_id()))
        while not stop.is_set():
            seen.update(_thread_ids())
            time.sleep(0.001)

    t = threading.Thread(target=sampler)
    t.start()
    try:
        call()
    finally:
        stop.set()
        t.join()
    return seen - before - set(sampler_id)


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores")
@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads through Linux's /proc")
def test_a_thread_count_holds_for_its_own_call_only(big):
    # threads=1 once stayed set for every later call of the process, such as reconstruct(),
    # which takes no thread count of its own.
    dec = ps.decompose(big[:100000], levels=3)
    ps.estimate_normals(big[:20000], threads=1)
    assert _threads_started_during(lambda: ps.reconstruct(dec, base=dec.base * 1.01))


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores")
@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads through Linux's /proc")
def test_two_threads_calling_at_once_keep_their_own_thread_counts(big):
    # Thread A decomposes with threads=1 and pauses in its first progress report while thread
    # B projects with threads=2; then A goes on. A's call must stay on A's own thread: no
    # thread may start while A's later reports run. The reports come from the calling thread in
    # the middle of each parallel loop, while that loop's workers are alive, so a worker A
    # started would be seen. Nothing else starts a thread then (B has been joined, the main
    # thread waits for A), and threads that end only leave the set of ids, so a count that is
    # right cannot fail this by chance.
    a_started, b_joined = threading.Event(), threading.Event()
    resumed = []  # the thread ids when A went on
    started = []  # per report of A after that, the threads that were not there then
    errors = []

    def progress_a(fraction):
        if not a_started.is_set():
            a_started.set()
            assert b_joined.wait(300), "thread B did not finish"
            resumed.append(_thread_ids())
        started.append(_thread_ids() - resumed[0])
        return True

    def run_a():
        try:
            ps.decompose(big, levels=3, threads=1, progress=progress_a)
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)
        finally:
            a_started.set()

    def run_b():
        try:
            assert a_started.wait(300), "thread A did not start"
            ps.project(big[:100000], big[::3], threads=2)
        except BaseException as exc:
            errors.append(exc)

    a, b = threading.Thread(target=run_a), threading.Thread(target=run_b)
    a.start()
    b.start()
    b.join()
    b_joined.set()
    a.join()
    assert not errors, errors
    assert len(started) > 10, len(started)  # A reported often enough to have seen a worker
    assert not set().union(*started), [sorted(s) for s in started if s]
