"""The core releases the GIL, uses every core, and can be cancelled cleanly."""
import os
import subprocess
import sys
import textwrap
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


def _thread_ids() -> set:
    return set(os.listdir("/proc/self/task"))


def _cpu_ns(tid: str) -> int:
    """CPU time of a thread of this process, in ns (Linux's per-thread CPU clock, read by its
    thread id), or 0 when it has ended."""
    try:
        return time.clock_gettime_ns(((~int(tid)) << 3) | 6)
    except OSError:
        return 0


# More CPU than a kept worker spends watching for the next loop after one ends (200 us).
WORKED_NS = 1_000_000


def _other_threads_that_worked(call) -> set:
    """The threads other than the caller's that worked while call() ran: those that started
    during it (thread ids are sampled every millisecond, so one that lives a millisecond is
    seen; the sampler itself is left out), and those already there whose CPU time grew by more
    than WORKED_NS (the core keeps its workers between calls)."""
    time.sleep(0.01)  # a kept worker still watching after an earlier loop goes to sleep
    me = str(threading.get_native_id())
    before = {tid: _cpu_ns(tid) for tid in _thread_ids() - {me}}
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
    grew = {tid for tid, ns in before.items() if _cpu_ns(tid) - ns > WORKED_NS}
    return (grew | (seen - set(before))) - set(sampler_id) - {me}


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores")
@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="reads threads through Linux's /proc")
def test_the_core_works_on_a_second_thread(big):
    # Asks whether a second thread did work, not how much: a busy machine delays a worker but
    # does not stop the core from handing it chunks. How much the second core speeds things up
    # is measured in bench/cores_bench.py, not asserted here.
    surface = big[::3]
    assert _other_threads_that_worked(lambda: ps.project(big, surface, threads=2))
    # threads=1 keeps the work on the calling thread, the kept worker included.
    assert not _other_threads_that_worked(lambda: ps.project(big[:100000], surface, threads=1))


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


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores")
@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads through Linux's /proc")
def test_a_thread_count_holds_for_its_own_call_only(big):
    # threads=1 once stayed set for every later call of the process, such as reconstruct(),
    # which takes no thread count of its own.
    dec = ps.decompose(big[:100000], levels=3)
    ps.estimate_normals(big[:20000], threads=1)
    assert _other_threads_that_worked(lambda: ps.reconstruct(dec, base=dec.base * 1.01))


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores")
@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads through Linux's /proc")
def test_two_threads_calling_at_once_keep_their_own_thread_counts(big):
    # Thread A decomposes with threads=1 and pauses in its first progress report while thread
    # B projects with threads=2; then A goes on. A's call must stay on A's own thread: no
    # thread may start, and no other thread may work, while A's later reports run. The reports
    # come from the calling thread in the middle of each parallel loop, while that loop's
    # workers are alive, so a worker A started or handed chunks would be seen. Nothing else
    # works then (B has been joined, the main thread waits for A, and the core's kept worker,
    # B's helper, has gone to sleep), and threads that end only leave the set of ids, so a
    # count that is right cannot fail this by chance.
    a_started, b_joined = threading.Event(), threading.Event()
    resumed = []  # the thread ids and their CPU times when A went on
    started = []  # per report of A after that, the threads that were not there then
    worked = []   # and those that were, with more CPU time than then
    errors = []

    def progress_a(fraction):
        if not a_started.is_set():
            a_started.set()
            assert b_joined.wait(300), "thread B did not finish"
            time.sleep(0.01)  # B's kept worker stops watching for another loop
            me = str(threading.get_native_id())
            resumed.append({tid: _cpu_ns(tid) for tid in _thread_ids() - {me}})
        started.append(_thread_ids() - set(resumed[0]) - {str(threading.get_native_id())})
        worked.append({tid for tid, ns in resumed[0].items() if _cpu_ns(tid) - ns > WORKED_NS})
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
    assert not set().union(*worked), [sorted(s) for s in worked if s]


FORKED = textwrap.dedent("""
    import os, sys, threading, time
    import numpy as np, pointscale as ps
    points = ps.shapes.bumpy_sphere(200000)
    expected = ps.project(points[:50000], points[::3], threads=2)[0]  # the parent's kept worker
    pid = os.fork()
    if pid == 0:  # the child has no worker threads of its parent's: it must not wait for them
        try:
            got = ps.project(points[:50000], points[::3], threads=2)[0]
            same = np.array_equal(got, expected)
            threads = len(os.listdir("/proc/self/task"))  # the child's own kept worker, and itself
            os._exit(0 if same and threads >= 2 else 3)
        except BaseException:
            os._exit(4)
    for _ in range(1200):  # at most two minutes
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            print("child", os.waitstatus_to_exitcode(status))
            break
        time.sleep(0.1)
    else:
        os.kill(pid, 9)
        print("child hung")
""")


@pytest.mark.skipif(not hasattr(os, "fork") or not os.path.isdir("/proc/self/task"),
                    reason="needs fork, and Linux's /proc to count the child's threads")
def test_a_forked_child_runs_the_core_on_its_own_workers():
    """A child made by fork() has no threads but the one that forked: the core's kept workers
    stay with the parent, and the child starts its own, with the same result."""
    result = subprocess.run([sys.executable, "-c", FORKED], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "child 0", (result.stdout, result.stderr)


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores")
def test_loops_one_after_another_run_on_the_same_kept_worker():
    """The core keeps its worker between loops instead of starting a thread per loop. Each loop
    has 40 chunks of 1 ms, so its worker takes some of them however late it wakes."""
    from pointscale import _testing
    helpers = []
    for _ in range(3):
        caller, numbers, _ = _testing.loop_threads(40, 1000, threads=2)
        others = set(numbers) - {caller}
        assert len(others) == 1, (caller, numbers)  # the caller and one worker shared the chunks
        helpers.append(others.pop())
    assert helpers[0] == helpers[1] == helpers[2], helpers


def test_workers_round_as_the_calling_thread_does():
    """A kept worker was started by an earlier call, in that call's floating-point environment;
    it takes each loop's caller's for that loop (and a thread started for a loop does too)."""
    from pointscale import _testing
    _testing.loop_threads(40, 200, threads=2)  # the kept worker, started in the default mode
    for threads in (2, 8):  # the kept worker; threads started for the loop
        caller, numbers, upward = _testing.loop_threads(40, 200, threads=threads, upward=True)
        assert all(upward), (threads, numbers, upward)
        assert len(set(numbers)) > 1 or (os.cpu_count() or 1) < 2, numbers  # other threads took chunks
        _, _, plain = _testing.loop_threads(40, 200, threads=threads)
        assert not any(plain), plain
