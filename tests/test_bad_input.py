"""Every bad input raises ValueError with a clear message: no crash, no hang."""
import numpy as np
import pytest

import pointscale as ps

GOOD = ps.shapes.bumpy_sphere(3000)


@pytest.mark.parametrize("points, message", [
    (np.full((3000, 3), np.nan), "NaN"),
    (np.where(np.arange(9000).reshape(3000, 3) == 7, np.inf, GOOD), "NaN or infinite"),
    (np.zeros((0, 3)), "empty"),
    (GOOD[:100], "at least"),
    (np.ones((3000, 3)), "identical"),
    (np.outer(np.linspace(0, 1, 3000), [1.0, 2.0, 3.0]), "collinear"),
    (np.column_stack([np.random.default_rng(0).uniform(size=(3000, 2)), np.zeros(3000)]), "one plane"),
    (GOOD.astype(np.complex128), "real numbers"),
    (GOOD.astype(str), "real numbers"),
    (GOOD[:, :2], "shape"),
    (GOOD.reshape(-1), "shape"),
    ([[1, 2, 3], [4, 5]], "array"),
])
def test_decompose_rejects(points, message):
    with pytest.raises(ValueError, match=message):
        ps.decompose(points)


@pytest.mark.parametrize("kwargs, message", [
    (dict(levels=1), "levels"), (dict(levels=2.5), "whole"), (dict(decimation=1.5), "decimation"),
    (dict(decimation=0), "decimation"), (dict(kernel=-1), "kernel"), (dict(neighbors=2), "neighbors"),
    (dict(normals=np.ones((5, 3))), "normals"), (dict(progress=3), "progress"),
])
def test_decompose_rejects_options(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ps.decompose(GOOD, **kwargs)


@pytest.fixture(scope="module")
def dec():
    return ps.decompose(GOOD, levels=3)


@pytest.mark.parametrize("gains", [[1, 1, 1], np.ones((2, 5)), [1, np.nan], "ab"])
def test_reconstruct_rejects_gains_of_the_wrong_shape(dec, gains):
    with pytest.raises(ValueError, match="gains"):
        ps.reconstruct(dec, gains=gains)


def test_reconstruct_rejects_a_base_of_the_wrong_length(dec):
    with pytest.raises(ValueError, match="base"):
        ps.reconstruct(dec, base=GOOD[:-1])
    with pytest.raises(ValueError, match="NaN"):
        ps.reconstruct(dec, base=np.full_like(GOOD, np.nan))


def collapsed_bases(dec):
    """Edited bases that span no surface: one position, a line, and a copy 1e-60 wide."""
    base = dec.base
    line = base.copy()
    line[:, 1:] = 0.0
    tiny = base.mean(axis=0) + 1e-60 * (base - base.mean(axis=0))
    return [("identical", np.repeat(base[:1], len(base), axis=0)), ("collinear", line), ("identical", tiny)]


@pytest.mark.parametrize("case", [0, 1, 2])
def test_an_edited_base_that_spans_no_surface_is_refused(dec, case):
    """A base collapsed to a point or a line has no normals to turn the detail by: it was taken
    without a word, and folds="report" called the point-sized one clean (API trial). A
    flattened base is an edit like any other."""
    match, base = collapsed_bases(dec)[case]
    for call in (lambda: ps.reconstruct(dec, base=base), lambda: ps.Reconstructor(dec).reconstruct(base=base),
                 lambda: ps.reconstruct(dec, base=base, folds="report")):
        with pytest.raises(ValueError, match=f"the base's points are {match}|all the base's points are {match}"):
            call()
    flat = dec.base.copy()
    flat[:, 2] = 0.0
    assert np.isfinite(ps.reconstruct(dec, base=flat)).all()


def test_reconstructor_rejects_what_reconstruct_rejects(dec):
    solver = ps.Reconstructor(dec)
    for gains in ([1, 1, 1], np.ones((2, 5)), [1, np.nan]):
        with pytest.raises(ValueError, match="gains"):
            solver.reconstruct(gains=gains)
    with pytest.raises(ValueError, match="base"):
        solver.reconstruct(base=GOOD[:-1])
    with pytest.raises(ValueError, match="Decomposition"):
        ps.Reconstructor(GOOD)


def test_other_functions_reject_bad_input(dec):
    with pytest.raises(ValueError, match="t must be"):
        ps.blend(dec, 5)
    with pytest.raises(ValueError, match="level"):
        dec.level(7)
    # A string or a bool is not a number here, though float() and int() take them (API trial).
    for t in ("1", True, np.bool_(True)):
        with pytest.raises(ValueError, match="t must be"):
            ps.blend(dec, t)
    for l in (True, np.bool_(False)):
        with pytest.raises(ValueError, match="level"):
            dec.normals(l)
        with pytest.raises(ValueError, match="level"):
            dec.level(l)
    assert np.array_equal(ps.blend(dec, np.float32(1.0)), dec.level(1))
    with pytest.raises(ValueError, match="Decomposition"):
        ps.reconstruct(GOOD)
    with pytest.raises(ValueError, match="onto"):
        ps.project(GOOD, GOOD[:2])
    for near, message in [(np.zeros(5, int), "near must be"), (np.full(3000, 0.5), "integers"),
                          (np.full(3000, 100), r"\[0, 99\]"), (np.full(3000, -1), "index onto")]:
        with pytest.raises(ValueError, match=message):
            ps.project(GOOD, GOOD[:100], near=near)
    with pytest.raises(ValueError, match="target"):
        ps.decimate(GOOD, 10**6)
    with pytest.raises(ValueError, match="collinear"):
        ps.estimate_normals(np.outer(np.arange(100.0), [1, 0, 0]))


def test_load_rejects_a_file_that_is_not_a_decomposition(tmp_path):
    np.savez(tmp_path / "x.npz", a=np.zeros(3))
    with pytest.raises(ValueError, match="not a pointscale decomposition"):
        ps.load(tmp_path / "x.npz")
    (tmp_path / "y.npz").write_bytes(b"garbage")
    with pytest.raises(ValueError, match="cannot read"):
        ps.load(tmp_path / "y.npz")


def test_a_very_coarse_base_is_warned_about():
    with pytest.warns(UserWarning, match="62 support points at level 0"):
        ps.decompose(ps.shapes.bumpy_sphere(4000), levels=4)


# ---------------------------------------------------------------------------------------------
# Regression tests for what a fuzzing run found: each was a crash, an abort, a hang, a silent
# NaN or an exception other than ValueError.

import io
import subprocess
import sys
import textwrap
import zipfile

from pointscale import _core


@pytest.fixture(scope="module")
def saved(dec):
    """The arrays of a valid 2-band decomposition, as Decomposition.save writes them."""
    return {k: np.array(v) for k, v in dec.to_dict().items()}


def write(tmp_path, arrays, name="d.npz"):
    path = tmp_path / name
    np.savez(path, **arrays)
    return path


def changed(saved, **changes):
    arrays = {k: v.copy() for k, v in saved.items()}
    for key, value in changes.items():
        if value is None:
            del arrays[key]
        else:
            arrays[key] = value(arrays[key]) if callable(value) else value
    return arrays


def test_a_valid_file_still_loads_and_round_trips(tmp_path, dec, saved):
    back = ps.load(write(tmp_path, saved))
    assert np.array_equal(ps.reconstruct(back), ps.reconstruct(dec))


@pytest.mark.parametrize("rows", [0, 1, -1, +1])  # 0 rows segfaulted reconstruct; 1 gave NaN; n +- 1 wrong points
def test_load_rejects_base_normals_with_another_row_count_than_points(tmp_path, saved, rows):
    n = len(saved["base"])
    count = rows if rows in (0, 1) else n + rows
    normals = np.resize(saved["base_normals"], (count, 3))
    with pytest.raises(ValueError, match="base_normals"):
        ps.load(write(tmp_path, changed(saved, base_normals=normals)))


def test_load_rejects_a_file_with_zero_bands(tmp_path, saved):
    # reconstruct(d, None, d.base), Reconstructor and reconstruct_levels segfaulted on it
    arrays = changed(saved, details=lambda a: a[:0], labels=lambda a: a[:0])
    with pytest.raises(ValueError, match="bands"):
        ps.load(write(tmp_path, arrays))


@pytest.mark.parametrize("key", ["base", "details", "base_normals", "kernel_0", "kernel_1", "local_0", "local_1",
                                 "origin"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_load_rejects_nan_or_inf_in_any_float_array(tmp_path, saved, key, bad):
    def spoil(a):
        a = a.astype(np.float64).copy()
        a.reshape(-1)[a.size // 2] = bad
        return a
    with pytest.raises(ValueError, match=f"{key} holds NaN or infinite"):
        ps.load(write(tmp_path, changed(saved, **{key: spoil})))


@pytest.mark.parametrize("key, value, message", [
    ("labels", lambda a: a + 10**6, "labels"),
    ("anchors_0", lambda a: a[::-1].copy(), "member of its own cluster"),
    ("neighborhoods_1", lambda a: np.where(a == a.max(), -1, a), "neighborhoods_1"),
    ("frames_0", lambda a: a.astype(np.float64), "integers"),
    ("base", lambda a: a.astype(np.int64), "floating"),
    ("kernel_0", lambda a: -a, "kernel_0"),
    ("settings", np.frombuffer(b"{not json", np.uint8), "settings are not valid JSON"),
    ("settings", np.frombuffer(b"[1, 2]", np.uint8), "JSON object"),
    ("settings", np.frombuffer(b'{"a": ' * 5000 + b"1" + b"}" * 5000, np.uint8), "settings"),
    ("format_version", np.array([], dtype=np.int64), "format_version"),  # was IndexError
    ("origin", None, "missing 'origin'"),  # was KeyError
    ("local_1", None, "missing 'local_1'"),
])
def test_load_rejects_damaged_arrays_with_one_value_error(tmp_path, saved, key, value, message):
    with pytest.raises(ValueError, match=message) as info:
        ps.load(write(tmp_path, changed(saved, **{key: value})))
    assert "\n" not in str(info.value)


def test_load_turns_damaged_bytes_into_value_errors(tmp_path, saved):
    good = io.BytesIO()
    np.savez_compressed(good, **saved)
    data = good.getvalue()
    rng = np.random.default_rng(0)
    cases = {"truncated": data[: len(data) // 2], "empty": b"", "garbage": rng.bytes(500)}
    for i in range(8):  # single bit flips all over the archive: BadZipFile, zlib.error, CRC errors...
        flipped = bytearray(data)
        flipped[int(rng.integers(0, len(data)))] ^= 1 << int(rng.integers(0, 8))
        cases[f"flip{i}"] = bytes(flipped)
    listing = io.BytesIO()
    with zipfile.ZipFile(listing, "w") as z:  # a zip, but not of .npy members
        z.writestr("base.npy", b"not an array")
    cases["zip of text"] = listing.getvalue()
    one = io.BytesIO()
    np.save(one, saved["base"])
    cases["one .npy array"] = one.getvalue()
    for name, content in cases.items():
        path = tmp_path / "x.npz"
        path.write_bytes(content)
        try:
            dec = ps.load(path)
        except ValueError as exc:
            assert "\n" not in str(exc), name
        else:  # a flip in padding may leave the file intact: then it must still be the same model
            assert np.isfinite(ps.reconstruct(dec)).all(), name


def test_the_core_checks_the_model_arrays_too(saved):
    """C++ callers get the structural checks without the Python layer (Model.from_arrays)."""
    core = {k: v for k, v in saved.items() if k not in ("origin", "settings", "format_version", "stats")}
    _core.Model.from_arrays(dict(core))  # the valid arrays load
    n = len(core["base"])
    spoiled = [
        ("base_normals", core["base_normals"][:1], "base_normals must have the"),
        ("details", core["details"][:0], "no bands"),
        ("kernel_0", np.where(np.arange(len(core["kernel_0"])) == 3, np.nan, core["kernel_0"]), "kernel widths"),
        ("kernel_1", np.zeros_like(core["kernel_1"]), "kernel widths"),
        ("local_0", np.full((n, 3), np.inf), "local coordinates"),
        ("details", np.full_like(core["details"], np.nan), "details holds NaN"),
        ("anchors_0", core["anchors_0"][::-1].copy(), "anchor of cluster"),
    ]
    for key, value, message in spoiled:
        arrays = dict(core)
        arrays[key] = value
        if key == "details" and value.shape[0] == 0:
            arrays["labels"] = core["labels"][:0]
        with pytest.raises(ValueError, match=message):
            _core.Model.from_arrays(arrays)


@pytest.mark.parametrize("scale", [1e150, 1e200, 1e308, 1e-300])
def test_extreme_coordinates_are_value_errors(scale):
    """At 1e150 these segfaulted or returned the input unprojected (the covariances overflow);
    at 1e200-1e308 numpy raised LinAlgError; at 1e-300 the points were called identical."""
    p = GOOD * scale if scale < 1e300 else np.clip(GOOD * 1e308, -1.7e308, 1.7e308)
    calls = [lambda: ps.project(p, p[::3]), lambda: ps.project_sheets(p, p[::3]),
             lambda: ps.encode(p, p[::3]), lambda: ps.shoot_rays(p[:50], GOOD[:50], p),
             lambda: ps.decompose(p, levels=3), lambda: ps.estimate_normals(p)]
    averaging = [lambda: ps.decimate(p, 100)[0], lambda: ps.smooth_diffusion(p, 5)]
    for call in calls + (averaging if scale > 1 else []):
        with pytest.raises(ValueError, match="coordinate|span"):
            call()
    for call in averaging if scale < 1 else []:  # means of tiny numbers are fine: no surface fit
        assert np.isfinite(call()).all()


def test_sets_are_judged_by_shape_whatever_their_size():
    tiny = 1e-300
    with pytest.raises(ValueError, match="collinear"):
        ps.project(GOOD, np.outer(np.arange(100.0), [1, 2, 3]) * tiny)
    with pytest.raises(ValueError, match="one plane"):
        ps.decompose(np.column_stack([GOOD[:, :2], np.zeros(len(GOOD))]) * tiny)
    with pytest.raises(ValueError, match="span only"):  # a sphere: too small, not "identical"
        ps.decompose(GOOD * tiny)


@pytest.mark.parametrize("scale", [1e-45, 1e45])
def test_the_edges_of_the_supported_range_work(scale):
    """Sets spanning 1e-45 or 1e45 give the unit set's results, scaled (to rounding)."""
    pos, nrm = ps.project(GOOD[::7] * scale, GOOD * scale)
    ref, ref_n = ps.project(GOOD[::7], GOOD)
    assert np.abs(pos / scale - ref).max() < 1e-12
    assert np.abs(nrm - ref_n).max() < 1e-9
    d = ps.decompose(GOOD * scale, levels=3)
    assert np.abs(ps.reconstruct(d) / scale - GOOD).max() < 1e-12


def test_kernel_widths_stay_positive_when_every_point_is_repeated():
    """onto made of 8 positions, each repeated 60 times: no sample has a neighbour to measure
    its spacing by, so the kernel widths were 0 and shoot_rays looped for ever (project NaN)."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    onto = np.repeat(corners, 60, axis=0)
    code = textwrap.dedent("""
        import numpy as np, pointscale as ps
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
        onto = np.repeat(corners, 60, axis=0)
        hits, dist, missed = ps.shoot_rays(onto[::7] * 0.5, onto[::7], onto)
        print("done", np.isfinite(hits).all())
    """)
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert result.stdout.split() == ["done", "True"], result.stderr
    pos, nrm = ps.project(onto * 0.9, onto)
    assert np.isfinite(pos).all() and np.isfinite(nrm).all()


THREAD_LIMIT = textwrap.dedent("""
    import resource, numpy as np, pointscale as ps
    points = ps.shapes.bumpy_sphere(20000)
    vm = [int(l.split()[1]) * 1024 for l in open("/proc/self/status") if l.startswith("VmSize")][0]
    resource.setrlimit(resource.RLIMIT_AS, (vm + 300 * 2**20, resource.RLIM_INFINITY))  # room for ~30 stacks
    try:
        ps.project(points, points[::4], threads=1000)
        print("no error")
    except RuntimeError as exc:
        print("RuntimeError:", exc)
    pos, _ = ps.project(points, points[::4], threads=1)  # the process goes on working
    print("after", bool(np.isfinite(pos).all()))
""")


def test_a_thread_that_fails_to_start_raises_instead_of_aborting():
    """Under a memory limit std::thread's constructor throws; parallel_for unwound past the
    joinable workers and the process died in std::terminate ("terminate called without an
    active exception")."""
    result = subprocess.run([sys.executable, "-c", THREAD_LIMIT], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("RuntimeError: could not start worker thread"), result.stdout
    assert "ask for fewer threads" in lines[0]
    assert lines[-1] == "after True"


@pytest.mark.parametrize("threads", [2000, 1025, -1, 2**31, 1.5, "2", None])
def test_threads_outside_0_to_1024_are_value_errors(threads):
    with pytest.raises(ValueError, match="threads"):
        ps.project(GOOD[:100], GOOD, threads=threads)


def test_taubin_steps_that_amplify_are_refused():
    # mu=-10 grows some frequencies 5.5x per iteration: 1000 iterations gave NaN silently
    with pytest.raises(ValueError, match="amplify"):
        ps.smooth_diffusion(GOOD, 1000, mu=-10)
    # the default Taubin step grows them 1.00066x: 100000 iterations collapsed the base to a
    # plane and the round trip was off by the radius
    with pytest.raises(ValueError, match="diffusion_iterations"):
        ps.decompose(GOOD, levels=3, smoother="diffusion", diffusion_iterations=100000)
    with pytest.raises(ValueError, match="amplify"):  # 4.6x in all: refused too
        ps.decompose(GOOD, levels=3, smoother="diffusion", diffusion_iterations=2500)
    with pytest.raises(ValueError, match="mu"):
        ps.smooth_diffusion(GOOD, 10, mu=-1e6)


def test_a_diffusion_decomposition_within_the_bounds_round_trips():
    dec = ps.decompose(GOOD, levels=3, smoother="diffusion", diffusion_iterations=2000)
    assert np.abs(ps.reconstruct(dec) - GOOD).max() < 1e-9
    out = ps.smooth_diffusion(GOOD, 10000)  # plain Laplacian steps never amplify
    assert np.isfinite(out).all()


def test_unbounded_iteration_counts_and_levels_are_refused():
    with pytest.raises(ValueError, match="at most"):  # 10 * 4**28 steps: ran for ever
        ps.diffusion_levels(GOOD, levels=30)
    with pytest.raises(ValueError, match="max_iterations"):
        ps.decompose(GOOD, levels=3, max_iterations=10**6)
    with pytest.raises(ValueError, match="max_iterations"):
        ps.project(GOOD[:10], GOOD, max_iterations=10**6)
    with pytest.raises(ValueError, match="iterations"):
        ps.smooth_diffusion(GOOD, 10**6)


@pytest.mark.parametrize("call", [
    lambda v: ps.decompose(GOOD, levels=v),
    lambda v: ps.decompose(GOOD, neighbors=v),
    lambda v: ps.decompose(GOOD, levels=3, max_iterations=v),
    lambda v: ps.decompose(GOOD, levels=3, smoother="diffusion", diffusion_iterations=v),
    lambda v: ps.smooth_diffusion(GOOD, v),
    lambda v: ps.diffusion_levels(GOOD, iterations=v),
    lambda v: ps.decimate(GOOD, v),
    lambda v: ps.ellipsoid_base(GOOD, n=v),
    lambda v: ps.project(GOOD[:10], GOOD, neighbors=v),
    lambda v: ps.estimate_normals(GOOD, neighbors=v),
    lambda v: ps.coarse_base_warning(100, levels=v),
])
@pytest.mark.parametrize("value", [2**31, 2**63, 10**30])
def test_integers_past_2_to_the_31_are_value_errors(call, value):
    # pybind11 raised TypeError ("incompatible function arguments"), or Python ZeroDivisionError
    with pytest.raises(ValueError):
        call(value)


@pytest.mark.parametrize("returned", ["yes", "", [1], {"a": 1}])
def test_a_progress_callback_returning_a_non_bool_is_a_value_error(dec, returned):
    # pybind11 raised "Unable to cast Python instance" (RuntimeError / TypeError)
    calls = [lambda cb: ps.decompose(GOOD, levels=3, progress=cb),
             lambda cb: ps.project(GOOD, GOOD[::3], progress=cb),
             lambda cb: ps.smooth_diffusion(GOOD, 50, progress=cb),
             lambda cb: ps.reconstruct(dec, base=dec.base, progress=cb)]
    # A Reconstructor's second call on an edited base finds every level's normals cached: its
    # callback is still called (once per level), so it is still checked and can still cancel.
    kept = ps.Reconstructor(dec)
    kept.reconstruct(base=dec.base * 1.01)
    calls.append(lambda cb: kept.reconstruct(base=dec.base * 1.01, progress=cb))
    for call in calls:
        with pytest.raises(ValueError, match="progress must return"):
            call(lambda fraction: returned)
        with pytest.raises(ps.Cancelled):  # False still cancels
            call(lambda fraction: False)


@pytest.mark.parametrize("array", ["base", "details"])
def test_a_decomposition_that_comes_out_not_finite_is_refused(monkeypatch, array):
    # The last guard of decompose reads the core's model in place (a copy would add its size to
    # the peak). No valid input makes the core return a NaN, so the model it returns is made to
    # say it holds one.
    real = _core.decompose

    class NotFinite:
        def __init__(self, model):
            self._model = model

        def __getattr__(self, name):
            if name == f"{array}_finite":
                return False
            return getattr(self._model, name)

    monkeypatch.setattr(_core, "decompose", lambda *args, **kwargs: NotFinite(real(*args, **kwargs)))
    with pytest.raises(ValueError, match=f"decomposition's {array.rstrip('s')} is not finite"):
        ps.decompose(ps.shapes.bumpy_sphere(3000), levels=3)


def test_a_finite_model_says_so(dec):
    assert dec._model.base_finite and dec._model.details_finite


@pytest.mark.parametrize("kwargs,name", [
    (dict(kernel="3"), "kernel"), (dict(decimation="0.25"), "decimation"), (dict(kernel=b"1"), "kernel"),
    (dict(smoother="diffusion", taubin="no"), "taubin"), (dict(smoother="diffusion", taubin=1.5), "taubin"),
    (dict(smoother="diffusion", taubin=None), "taubin"),
])
def test_text_for_a_number_and_anything_for_taubin_are_refused(kwargs, name):
    """kernel='3' was read as 3.0, and taubin took any value (Ellipsis, 'no', 1.5) as true."""
    with pytest.raises(ValueError, match=name):
        ps.decompose(GOOD, levels=2, **kwargs)


def test_a_reconstructor_called_from_its_own_progress_callback_refuses_instead_of_hanging():
    """A preview refresh wired into the progress hook called the same Reconstructor again: the
    thread waited on itself for ever, and Ctrl-C could not stop it."""
    dec = ps.decompose(ps.shapes.bumpy_sphere(6000), levels=3)
    solver = ps.Reconstructor(dec)
    said = []

    def refresh(fraction):
        try:
            solver.reconstruct((1, 1.5))
        except ValueError as exc:
            said.append(str(exc))
        return True

    out = solver.reconstruct((1, 2), dec.base * 1.02, progress=refresh)
    assert said and "called again from within its own call" in said[0]
    assert np.array_equal(out, ps.reconstruct(dec, (1, 2), dec.base * 1.02))
    assert np.array_equal(solver.reconstruct((1, 1.5)), ps.reconstruct(dec, (1, 1.5)))  # usable after


def test_decompositions_compare_by_their_arrays():
    """d1 == d2 was False for bit-identical decompositions, and for a saved and loaded one (the
    dataclass compared the core objects by identity)."""
    points = ps.shapes.bumpy_sphere(5000, noise=0.002)
    d1, d2 = ps.decompose(points, levels=3), ps.decompose(points, levels=3)
    assert d1 == d2 and d1 == ps.Decomposition.from_dict(d1.to_dict())
    assert d1 != ps.decompose(points, levels=3, kernel=1.5)
    moved = ps.Decomposition.from_dict(d1.to_dict())
    moved.origin = moved.origin + 1.0
    assert d1 != moved and d1 != "a decomposition"
