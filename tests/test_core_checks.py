"""The checks live in the core (native/include/pointscale/validation.h): a C++ caller of an entry
point gets the same ValueError (std::invalid_argument) as a caller of the package, and each check
is written once. pointscale._core is called here directly, as a C++ caller would call the core:
without the package's conversions, with the core's own option structs."""
from pathlib import Path

import numpy as np
import pytest

import pointscale as ps
from pointscale import _core

REPO = Path(__file__).resolve().parents[1]
GOOD = ps.shapes.bumpy_sphere(3000)
ORIGIN = np.zeros(3)


def message(call) -> str:
    with pytest.raises(ValueError) as info:
        call()
    return str(info.value)


def same_message(public, core, fragment: str) -> None:
    """The package's call and the core's fail alike, with the core's message."""
    text = message(core)
    assert fragment in text, text
    assert message(public) == text


@pytest.fixture(scope="module")
def dec():
    return ps.decompose(GOOD, levels=3)


# --- points and normals ----------------------------------------------------------------------

@pytest.mark.parametrize("points, fragment", [
    (np.full((3000, 3), np.nan), "points contains NaN or infinite coordinates (3000 points)"),
    (np.zeros((0, 3)), "points is empty"),
    (GOOD[:100], "decompose needs at least"),
    (np.ones((3000, 3)), "all points are identical"),
    (np.outer(np.linspace(0, 1, 3000), [1.0, 2.0, 3.0]), "points are collinear"),
    (GOOD * 1e60, "points span"),
])
def test_decompose_checks_its_points_in_the_core(points, fragment):
    options = _core.DecomposeOptions()
    same_message(lambda: ps.decompose(points), lambda: _core.decompose(points, ORIGIN, None, options=options),
                 fragment)


def test_normals_must_match_the_points_in_every_entry_point():
    wrong = np.ones((5, 3))
    same_message(lambda: ps.decompose(GOOD, normals=wrong),
                 lambda: _core.decompose(GOOD, ORIGIN, wrong, options=_core.DecomposeOptions()),
                 "normals must have the shape of points (3000, 3), got (5, 3)")
    base = ps.shapes.fibonacci_sphere(500)
    same_message(lambda: ps.encode(GOOD, base, base_normals=wrong),
                 lambda: _core.encode(GOOD, base, wrong, options=_core.EncodeOptions()),
                 "base_normals must have the shape of base_points (500, 3)")
    same_message(lambda: ps.morph(GOOD, GOOD, base, base_normals=wrong),
                 lambda: _core.morph(GOOD, GOOD, base, wrong, options=_core.MorphOptions()),
                 "base_normals must have the shape of base_points (500, 3)")


def test_the_surface_checks_are_the_cores():
    line = np.outer(np.arange(100.0), [1.0, 0.0, 0.0])
    same_message(lambda: ps.estimate_normals(line), lambda: _core.estimate_normals(line, neighbors=16, orient=True),
                 "points are collinear")
    same_message(lambda: ps.estimate_normals(GOOD, neighbors=2),
                 lambda: _core.estimate_normals(GOOD, neighbors=2, orient=False), "neighbors must be >= 3")
    same_message(lambda: ps.encode(GOOD, line), lambda: _core.encode(GOOD, line, None, options=_core.EncodeOptions()),
                 "base_points are collinear")


# --- options ---------------------------------------------------------------------------------

@pytest.mark.parametrize("settings, fragment", [
    (dict(levels=1), "levels must be at least 2"),
    (dict(levels=65), "levels must be at most 64"),
    (dict(decimation=1.5), "decimation must be in (0, 1), got 1.5"),
    (dict(kernel=-1.0), "kernel must be in [0.001, 1000]"),
    (dict(max_variation=float("nan")), "max_variation must be > 0"),
    (dict(mls=_core.MlsOptions(neighbors=3)), "neighbors must be >= 4"),
    (dict(mls=_core.MlsOptions(tolerance=0.0)), "tolerance must be > 0"),
    (dict(mls=_core.MlsOptions(max_iterations=5000)), "max_iterations must be at most 1000"),
])
def test_decompose_options_are_checked_by_the_core(settings, fragment):
    options = _core.DecomposeOptions(**settings)
    assert fragment in message(options.validate)
    assert fragment in message(lambda: _core.decompose(GOOD, ORIGIN, None, options=options))


def test_the_public_options_reach_the_same_checks():
    for kwargs, fragment in [(dict(levels=1), "levels must be at least 2"), (dict(kernel=-1), "kernel must be in"),
                             (dict(neighbors=3), "neighbors must be >= 4"),
                             (dict(max_iterations=5000), "max_iterations must be at most 1000")]:
        assert fragment in message(lambda: ps.decompose(GOOD, **kwargs))
        assert fragment in message(lambda: ps.decompose_rayshoot(GOOD, **kwargs))


@pytest.mark.parametrize("settings, fragment", [
    (dict(lam=2.0), "lam must be in [0.001, 1]"),
    (dict(neighbors=2), "neighbors must be >= 3"),
    (dict(mu=-0.1), "mu must be below -lam = -0.5"),
    (dict(iterations=0), "iterations must be >= 1"),
    (dict(mu=-10.0, iterations=100), "amplify some frequencies"),
])
def test_diffusion_settings_are_checked_by_the_core(settings, fragment):
    options = _core.DiffusionOptions(**settings)
    assert fragment in message(lambda: _core.diffuse(GOOD, options))
    public = dict(settings)
    public.setdefault("iterations", 10)
    assert fragment in message(lambda: ps.smooth_diffusion(GOOD, **public))


def test_decompose_names_its_diffusion_settings():
    diffusion = _core.DiffusionOptions(iterations=20000)
    text = message(lambda: _core.decompose(GOOD, ORIGIN, None, options=_core.DecomposeOptions(), diffusion=diffusion))
    assert "diffusion_iterations must be at most 10000" in text
    assert message(lambda: ps.decompose(GOOD, smoother="diffusion", diffusion_iterations=20000)) == text


def test_the_other_option_structs_have_their_checks():
    base = ps.shapes.fibonacci_sphere(500)
    cases = [
        (_core.EncodeOptions(kernel=0.0), lambda o: _core.encode(GOOD, base, None, options=o), "kernel must be in"),
        (_core.MorphOptions(interpolation_neighbors=0), lambda o: _core.morph(GOOD, GOOD, base, None, options=o),
         "interpolation_neighbors must be >= 1"),
        (_core.RayOptions(max_distance=-1.0), lambda o: _core.shoot_rays(GOOD[:5], GOOD[:5] / np.linalg.norm(
            GOOD[:5], axis=1)[:, None], GOOD, kernel=1.0, options=o), "max_distance must be > 0"),
        (_core.RayOptions(max_distance=0.0), lambda o: _core.shoot_rays(GOOD[:5], GOOD[:5] / np.linalg.norm(
            GOOD[:5], axis=1)[:, None], GOOD, kernel=1.0, options=o), "max_distance must be > 0"),
        (_core.MlsOptions(neighbors=2000), lambda o: _core.project(GOOD, base, kernel=1.0, mls=o),
         "neighbors must be at most 1024"),
    ]
    for options, call, fragment in cases:
        assert fragment in message(options.validate)
        assert fragment in message(lambda: call(options))


def test_kernel_and_threads_are_checked_by_the_core():
    same_message(lambda: ps.project(GOOD, GOOD, kernel=1e4),
                 lambda: _core.project(GOOD, GOOD, kernel=1e4, mls=_core.MlsOptions()),
                 "kernel must be in [0.001, 1000] (a multiple of the local spacing), got 10000.0")
    same_message(lambda: ps.estimate_normals(GOOD, threads=2000),
                 lambda: _core.estimate_normals(GOOD, neighbors=16, orient=True, threads=2000),
                 "threads must be in [0, 1024] (0: all cores), got 2000")


# --- reconstruction: gains, base, model ------------------------------------------------------

def test_gains_and_base_are_checked_by_the_core(dec):
    model = dec._model
    for gains, fragment in [(np.ones(5), "gains must have shape (2,) per band or (2, 3000) per point"),
                            (np.array([1.0, np.nan]), "gains contain NaN"),
                            (np.array([1.0, 1e7]), "gains must be within +-1e+06")]:
        same_message(lambda: ps.reconstruct(dec, gains), lambda: model.reconstruct(gains), fragment)
        solver = _core.Reconstructor(model)
        assert fragment in message(lambda: solver.reconstruct(gains))
    base = dec.base[:-1]
    fragment = "base must have the decomposition's 3000 points, got 2999"
    same_message(lambda: ps.reconstruct(dec, base=base),
                 lambda: model.reconstruct(np.ones(2), base=base, origin=dec.origin), fragment)
    assert fragment in message(lambda: _core.Reconstructor(model).reconstruct(np.ones(2), base=base,
                                                                              origin=dec.origin))
    far = dec.base + 1e60
    same_message(lambda: ps.reconstruct(dec, base=far), lambda: model.reconstruct(np.ones(2), base=far,
                                                                                  origin=dec.origin),
                 "base reach")


def test_projection_hints_are_checked_by_the_core():
    onto = GOOD[:100]
    same_message(lambda: ps.project(GOOD, onto, near=np.full(3000, 100)),
                 lambda: _core.project(GOOD, onto, kernel=1.0, mls=_core.MlsOptions(), near=np.full(3000, 100)),
                 "near must index onto: each in [0, 99], got [100, 100]")


# --- each check once -------------------------------------------------------------------------

@pytest.mark.parametrize("fragment", [
    "must be at least 2 (a base and one band)", "decimation must be in (0, 1)", "amplify some frequencies",
    "define no surface", "are collinear", "all lie in one plane", "contains NaN or infinite coordinates",
    "coordinates beyond", "gains contain NaN", "must have the shape of", "for a stable explicit step",
    "(0: all cores), got", "sets wider than", "from the centre of",
])
def test_each_check_is_written_once(fragment):
    """A check's message is written in one source file, the core's validation (the package
    may quote a range in a type error, never the check itself)."""
    sources = [p for p in (REPO / "native").rglob("*") if p.suffix in (".cpp", ".h", ".py")]
    holders = [p.relative_to(REPO).as_posix() for p in sources if fragment in p.read_text(encoding="utf-8")]
    assert holders == ["native/src/validation.cpp"], holders


def test_the_fold_functions_check_their_input_in_the_core(dec):
    model = dec._model
    ref = _core.fold_reference(model)
    wrong = np.zeros((10, 3))
    same_message(lambda: ps.find_folds(dec, wrong), lambda: _core.find_folds(model, ref, wrong),
                 "points must have the decomposition's 3000 points, got 10")
    result = ps.reconstruct(dec, [2.0, 2.0])
    assert "max_rounds must be at most 1000" in message(lambda: _core.limit_folds(model, ref, result.copy(),
                                                                                   max_rounds=5000))
    other = ps.decompose(ps.shapes.bumpy_sphere(2000), levels=3)._model
    assert "made for another model" in message(lambda: _core.find_folds(other, ref, result[:2000]))
    assert "input must have the decomposition's" in message(lambda: _core.fold_reference(model, input=wrong))


def test_parts_rows_are_checked_by_the_core():
    labels = np.zeros(len(GOOD), np.int32)
    assert "k must be at least 1" in message(lambda: _core.knn_within_parts(GOOD, labels, k=0))
    assert "part label out of range" in message(lambda: _core.knn_within_parts(GOOD, labels - 1, k=4))


def test_decimation_checks_its_input_in_the_core():
    for target, fragment in [(10**6, "target (1000000) exceeds the number of points (3000)"),
                             (0, "target must be >= 1, got 0")]:
        same_message(lambda: ps.decimate(GOOD, target), lambda: _core.decimate(GOOD, target, 0.05), fragment)
    same_message(lambda: ps.decimate(GOOD, 100, max_variation=-1.0), lambda: _core.decimate(GOOD, 100, -1.0),
                 "max_variation must be > 0")
