"""The paper's further operators (issue 3): diffusion smoothing (Sec. 5.1), ray-shooting encoding
(Sec. 6.1), encoding onto a given base (Sec. 8.2), morphing (Sec. 8.3) and thin sheets."""
import numpy as np
import pytest

import pointscale as ps
from pointscale.shapes import bump_field, fibonacci_sphere


def diag(points):
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def radial_amplitudes(points, frequencies):
    """Least-squares amplitudes of bump_field patterns in the radial function of `points`."""
    r = np.linalg.norm(points, axis=1)
    u = points / r[:, None]
    a = np.column_stack([np.ones(len(r))] + [bump_field(u, f) for f in frequencies])
    c, *_ = np.linalg.lstsq(a, r, rcond=None)
    return c[1:]


def distance_to_radial_surface(points, radius_of):
    """|r - R(u)| for a star-shaped surface r = R(u); close to the distance for gentle bumps."""
    r = np.linalg.norm(points, axis=1)
    return np.abs(r - radius_of(points / r[:, None]))


# ----------------------------------------------------------------------------------------------
# Diffusion (Sec. 5.1, 5.3)

def mean_sphere_volume(points):
    return 4.0 / 3.0 * np.pi * np.mean(np.linalg.norm(points, axis=1)) ** 3


def test_taubin_keeps_volume_where_laplacian_shrinks():
    p = ps.shapes.sphere(20000, noise=0.01)
    v0 = mean_sphere_volume(p)
    laplacian = ps.smooth_diffusion(p, 100)
    taubin = ps.smooth_diffusion(p, 100, taubin=True)
    assert mean_sphere_volume(laplacian) < 0.95 * v0, "plain Laplacian smoothing should shrink a closed shape"
    assert mean_sphere_volume(taubin) == pytest.approx(v0, rel=0.02)
    # Both smooth: the radial noise drops.
    noise = np.std(np.linalg.norm(p, axis=1))
    assert np.std(np.linalg.norm(taubin, axis=1)) < 0.5 * noise
    assert np.std(np.linalg.norm(laplacian, axis=1)) < 0.5 * noise


def test_diffusion_levels_get_smoother_level_by_level():
    p = ps.shapes.bumpy_sphere(20000, fine_frequency=40.0)
    levels = ps.diffusion_levels(p, 4, taubin=True)
    assert levels.shape == (4,) + p.shape
    np.testing.assert_array_equal(levels[-1], p)
    fine = [abs(radial_amplitudes(lv, [3.0, 40.0])[1]) for lv in levels]
    assert all(a < b for a, b in zip(fine, fine[1:])), f"fine amplitude per level {fine}"
    assert fine[0] < 0.2 * fine[-1]
    coarse = [radial_amplitudes(lv, [3.0, 40.0])[0] for lv in levels]
    assert min(coarse) > 0.8 * 0.08, f"the coarse shape should survive: {coarse}"


def assert_fine_pattern_fades_level_by_level(fine):
    """fine: the fine pattern's amplitude per level, coarsest first. Each level has less of it
    than the next, until it is gone (below 1% of the input's): there the two coarsest levels
    differ by rounding noise only."""
    gone = 0.01 * fine[-1]
    assert all(a < b or max(a, b) < gone for a, b in zip(fine, fine[1:])), f"fine amplitude per level {fine}"
    assert fine[1] < gone, f"fine amplitude per level {fine}"


def test_diffusion_smoother_in_a_decomposition_gets_smoother_level_by_level():
    p = ps.shapes.bumpy_sphere(20000, fine_frequency=40.0)
    dec = ps.decompose_rayshoot(p, 4, smoother="diffusion")
    assert dec.settings["smoother"] == "diffusion"
    fine = [abs(radial_amplitudes(dec.level(l), [3.0, 40.0])[1]) for l in range(dec.n_levels)]
    assert_fine_pattern_fades_level_by_level(fine)
    # Diffusion smooths more than the projection alone, band for band.
    plain = ps.decompose_rayshoot(p, 4, smoother="mls")
    assert abs(radial_amplitudes(dec.level(0), [3.0, 40.0])[0]) < radial_amplitudes(plain.level(0), [3.0, 40.0])[0]


@pytest.mark.parametrize("kwargs, message", [
    (dict(iterations=0), "iterations"),
    (dict(lam=0.0), "lam"),
    (dict(lam=1.5), "lam"),
    (dict(mu=-0.1), "mu"),
    (dict(mu="x"), "mu"),
    (dict(neighbors=2), "neighbors"),
])
def test_diffusion_bad_options(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ps.smooth_diffusion(ps.shapes.sphere(500), **kwargs)


def test_diffusion_bad_points():
    p = ps.shapes.sphere(500)
    p[3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        ps.smooth_diffusion(p)
    with pytest.raises(ValueError, match="shape"):
        ps.smooth_diffusion(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="at least"):
        ps.smooth_diffusion(ps.shapes.sphere(5))
    with pytest.raises(ValueError, match="growth"):
        ps.diffusion_levels(ps.shapes.sphere(500), growth=0.5)


# ----------------------------------------------------------------------------------------------
# Ray shooting (Sec. 6.1)

def test_rays_from_far_away_hit_the_near_side():
    # Origins 4 radii off the surface are far outside every kernel: without a floor on the
    # weights the first plane was fitted to about one sample and 118 of these 333 rays landed
    # elsewhere (the far side included). Each must hit where the sphere is, at distance r - 1.
    onto = ps.shapes.sphere(12000)
    dirs = fibonacci_sphere(333)
    hits, dist, missed = ps.shoot_rays(5.0 * dirs, -dirs, onto)
    assert not missed.any()
    err = np.abs(dist - 4.0)
    assert np.all(err < np.median(err) + 3e-3), np.sort(err)[-5:]


def test_shoot_rays_hits_a_sphere_and_reports_misses():
    onto = ps.shapes.sphere(5000)
    dirs = fibonacci_sphere(200)
    origins = 3.0 * dirs
    hits, dist, missed = ps.shoot_rays(origins, -dirs, onto)
    assert not missed.any()
    np.testing.assert_allclose(np.linalg.norm(hits, axis=1), 1.0, atol=3e-3)
    np.testing.assert_allclose(dist, 2.0, atol=3e-3)
    # Rays tangent to a plane never meet it: reported, kept at their origin.
    plane = np.column_stack([np.random.default_rng(1).uniform(-1, 1, (3000, 2)), np.zeros(3000)])
    o = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.2]])
    d = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    hits, dist, missed = ps.shoot_rays(o, d, plane)
    assert missed.tolist() == [True, False]
    np.testing.assert_array_equal(hits[0], o[0])
    assert dist[1] == pytest.approx(0.2, abs=1e-6)
    # A hit beyond max_distance is a miss too.
    _, _, missed = ps.shoot_rays(o[1:], d[1:], plane, max_distance=0.1)
    assert missed.tolist() == [True]
    # A limit of 0 would miss everything: refused (None is no limit).
    with pytest.raises(ValueError, match="max_distance must be > 0"):
        ps.shoot_rays(o[1:], d[1:], plane, max_distance=0.0)


def test_rayshoot_decomposition_round_trip_on_its_finest_level():
    frequency = 25.0
    p = ps.shapes.bumpy_sphere(20000, fine_frequency=frequency)
    dec = ps.decompose_rayshoot(p, 4)
    assert dec.settings["encoding"] == "rayshoot"
    missed = dec.settings["rays_missed"]
    assert len(missed) == 3 and all(isinstance(m, int) for m in missed)
    assert [len(m) for m in ps.rays_missed_points(dec)] == missed
    assert sum(missed) < 0.001 * len(p)
    finest = ps.reconstruct(dec)
    np.testing.assert_allclose(finest, dec.level(3), atol=1e-12)
    # The finest level resamples the input surface.
    surface = lambda u: 1.0 + 0.08 * bump_field(u, 3.0) + 0.01 * bump_field(u, frequency)
    assert distance_to_radial_surface(finest, surface).max() < 1e-3 * diag(p)
    # And it is a multiscale representation: band filtering works on it.
    fine = radial_amplitudes(ps.reconstruct(dec, [1, 1, 0]), [3.0, frequency])[1]
    assert abs(fine) < radial_amplitudes(finest, [3.0, frequency])[1]


def test_rayshoot_bad_input():
    p = ps.shapes.sphere(2000)
    with pytest.raises(ValueError, match="smoother"):
        ps.decompose_rayshoot(p, smoother="gauss")
    with pytest.raises(ValueError, match="at least"):
        ps.decompose_rayshoot(p[:100], 4)
    with pytest.raises(ValueError, match="levels"):
        ps.decompose_rayshoot(p, 1)
    with pytest.raises(ValueError, match="zero vectors"):
        ps.shoot_rays(p[:2], np.zeros((2, 3)), p)
    with pytest.raises(ValueError, match="shape of origins"):
        ps.shoot_rays(p[:2], p[:3], p)
    with pytest.raises(ValueError, match="Decomposition"):
        ps.rays_missed_points("nope")


# ----------------------------------------------------------------------------------------------
# Encoding onto a base (Sec. 8.2, Fig. 8)

AXES = np.array([1.0, 0.8, 0.7])


def ellipsoid_distance(points, centre, axes):
    """Distance to an ellipsoid, to first order: |f| / |grad f| with f = |x / a| - 1."""
    q = (points - centre) / axes
    f = np.linalg.norm(q, axis=1) - 1.0
    grad = q / axes / np.linalg.norm(q, axis=1)[:, None]
    return np.abs(f) / np.linalg.norm(grad, axis=1)


def bumpy_ellipsoid(n=20000, fine=0.03, frequency=8.0):
    u = fibonacci_sphere(n)
    return u * AXES * (1.0 + 0.15 * bump_field(u, 2.0) + fine * bump_field(u, frequency))[:, None]


def test_ellipsoid_base_fills_the_common_bounding_box():
    a = bumpy_ellipsoid(5000)
    b = ps.shapes.sphere(3000, radius=0.5) + [0.9, 0.0, 0.0]
    base = ps.ellipsoid_base(a, b, n=4000)
    assert base.shape == (4000, 3)
    both = np.vstack([a, b])
    lo, hi = both.min(axis=0), both.max(axis=0)
    np.testing.assert_allclose(base.min(axis=0), lo, atol=0.02 * diag(both))
    np.testing.assert_allclose(base.max(axis=0), hi, atol=0.02 * diag(both))
    assert ellipsoid_distance(base, 0.5 * (lo + hi), 0.5 * (hi - lo)).max() < 1e-9


def test_encode_gain_zero_lands_on_the_base_and_gain_one_returns_the_model():
    model = bumpy_ellipsoid()
    base = ps.ellipsoid_base(model, n=20000)
    lo, hi = model.min(axis=0), model.max(axis=0)
    dec = ps.encode(model, base)
    assert dec.n_bands == 1 and dec.n_points == len(model)
    assert dec.stats[0]["degenerate"] == 0 and dec.stats[0]["pinned"] == 0
    on_base = ps.reconstruct(dec, [0.0])
    assert ellipsoid_distance(on_base, 0.5 * (lo + hi), 0.5 * (hi - lo)).max() < 1e-3 * diag(base)
    # Round trip to 1e-11 of the diagonal (measured 4.8e-13).
    assert np.abs(ps.reconstruct(dec, [1.0]) - model).max() <= 1e-11 * diag(model)
    # Gains in between blend; the same point moves along one line (Fig. 8).
    half = ps.reconstruct(dec, [0.5])
    assert np.abs(half - 0.5 * (on_base + model)).max() <= 1e-11 * diag(model)  # measured 2.4e-13


def test_encode_works_far_outside_the_base_kernels():
    # The model lies about 40 kernel widths from the base: unscaled Gaussian weights would all
    # underflow to zero there (exp(-1600)).
    base = ps.shapes.sphere(20000)
    model = 2.0 * ps.shapes.bumpy_sphere(20000, coarse=0.05, fine=0.0)
    dec = ps.encode(model, base)
    h = dec.stats[0]["kernel_width"]
    assert np.min(np.abs(dec.details)) > 30 * h
    assert dec.stats[0]["degenerate"] == 0 and dec.stats[0]["pinned"] == 0
    on_base = ps.reconstruct(dec, [0.0])
    assert np.abs(np.linalg.norm(on_base, axis=1) - 1.0).max() < 1e-3 * diag(base)
    # The details are 30 kernel widths long here, so rounding grows with them: measured 1.1e-9.
    assert np.abs(ps.reconstruct(dec, [1.0]) - model).max() <= 1e-8 * diag(model)


def test_encode_bad_input():
    model = ps.shapes.sphere(1000)
    with pytest.raises(ValueError, match="base_points"):
        ps.encode(model, np.zeros((0, 3)))
    with pytest.raises(ValueError, match="identical"):
        ps.encode(model, np.ones((50, 3)))
    with pytest.raises(ValueError, match="base_normals"):
        ps.encode(model, model, base_normals=np.ones((10, 3)))
    with pytest.raises(ValueError, match="kernel"):
        ps.encode(model, model, kernel=-1)
    with pytest.raises(ValueError, match="flat"):
        ps.ellipsoid_base(np.column_stack([model[:, :2], np.zeros(len(model))]))
    with pytest.raises(ValueError, match="n must"):
        ps.ellipsoid_base(model, n=0)


# ----------------------------------------------------------------------------------------------
# Morphing (Sec. 8.3, Eq. 22)

@pytest.fixture(scope="module")
def two_models():
    a = ps.shapes.bumpy_sphere(15000, coarse=0.1, coarse_frequency=3.0, fine=0.0)
    # B: another pattern, another sampling and count.
    u = fibonacci_sphere(11000)
    rng = np.random.default_rng(3)
    u = u[rng.permutation(len(u))]
    b_radius = lambda v: 1.0 + 0.06 * bump_field(v, 5.0)
    b = u * b_radius(u)[:, None]
    base = ps.ellipsoid_base(a, b, n=20000)
    return a, b, b_radius, base, ps.morph(a, b, base)


def test_morph_one_zero_returns_a(two_models):
    a, _, _, _, m = two_models
    assert m.base.shape == a.shape and m.detail_b.shape == (len(a),)
    np.testing.assert_allclose(m.evaluate(1.0, 0.0), a, atol=1e-9 * diag(a))


def test_morph_zero_one_lands_on_b(two_models):
    a, b, b_radius, _, m = two_models
    assert distance_to_radial_surface(m.evaluate(0.0, 1.0), b_radius).max() < 0.01 * diag(b)


def eared_ball(n, seed):
    """A ball with two long, thin ears lying back along it, as a rabbit's do: the ears fold over
    any smooth base of the whole, so a normal line from the base meets the model up to 5 times."""
    rng = np.random.default_rng(seed)

    def turn(degrees):
        t = np.radians(degrees)
        return np.array([[np.cos(t), 0.0, np.sin(t)], [0.0, 1.0, 0.0], [-np.sin(t), 0.0, np.cos(t)]])

    radii, tilt = np.array([0.9, 0.25, 0.08]), turn(-25.0)
    centres = [np.array([-0.2, y, 1.05]) for y in (-0.35, 0.35)]
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    head, ears = u[: n // 2], [(u[m::2][: n // 4] * radii) @ tilt.T + c for m, c in enumerate(centres)]
    inside = lambda p, c: ((((p - c) @ tilt) / radii) ** 2).sum(axis=1) < 1.0
    head = head[~(inside(head, centres[0]) | inside(head, centres[1]))]
    ears = [e[np.linalg.norm(e, axis=1) > 1.0] for e in ears]
    return np.vstack([head] + ears)


def test_morph_onto_a_model_that_folds_over_the_base_lands_on_it():
    # Another sampling of the same eared ball: beta = 1 must land on it, ears included. A mean of
    # B's offsets over the neighbours of every sheet of an ear landed between the sheets
    # (measured on three pairs of seeds: the 99th percentile 1.87-1.91% of the diagonal, against
    # 1.01-1.06% matching the sheets; the samples' own spacing is about 0.8%).
    from scipy.spatial import cKDTree
    a, b = eared_ball(30000, 1), eared_ball(24000, 2)
    m = ps.morph(a, b)
    miss = cKDTree(b).query(m.evaluate(0.0, 1.0))[0] / diag(b)
    assert np.percentile(miss, 99) < 0.013, np.percentile(miss, 99)
    np.testing.assert_allclose(m.evaluate(1.0, 0.0), a, atol=1e-9 * diag(a))


def test_morph_of_two_scans_of_the_bunny_lands_on_the_second():
    # The bunny's ears fold over its ellipsoid. Measured: the 99th percentile 0.29% of the
    # diagonal (2.15% with a mean over every sheet).
    from scipy.spatial import cKDTree
    from helpers import shared_model
    a, b = (ps.io.read(shared_model(name)).points for name in ("bunny.ply", "bunny_scans.ply"))
    b = b[::3]
    m = ps.morph(a, b)
    miss = cKDTree(b).query(m.evaluate(0.0, 1.0))[0] / diag(b)
    assert np.percentile(miss, 99) < 0.004, np.percentile(miss, 99)


def test_morph_blends_and_extrapolates(two_models):
    a, _, _, _, m = two_models
    mid = m.evaluate(0.5, 0.5)
    np.testing.assert_allclose(mid, 0.5 * (m.evaluate(1.0, 0.0) + m.evaluate(0.0, 1.0)), atol=1e-12)
    # (0, 0) is the common base; (1, 1) is not a convex combination (Fig. 10a) and still works.
    np.testing.assert_allclose(m.evaluate(0.0, 0.0), m.base)
    both = m.evaluate(1.0, 1.0)
    assert np.isfinite(both).all() and np.abs(both - a).max() > 0.01


def test_morph_bad_input(two_models):
    a, b, _, base, m = two_models
    with pytest.raises(ValueError, match="finite"):
        m.evaluate(np.nan, 0.0)
    with pytest.raises(ValueError, match="numbers"):
        m.evaluate("a", 0.0)
    with pytest.raises(ValueError, match="points_b"):
        ps.morph(a, b[:, :2], base)
    with pytest.raises(ValueError, match="interpolation_neighbors"):
        ps.morph(a, b, base, interpolation_neighbors=0)
    with pytest.raises(ValueError, match="collinear"):
        ps.morph(a, b, np.column_stack([np.linspace(0, 1, 50)] * 3))


# ----------------------------------------------------------------------------------------------
# Thin sheets: two parallel sheets half a kernel width apart (PointCloudLibrary/pcl#3116)

def mean_spacing(cloud, count=300):
    """The kernel's spacing: mean distance to the 6 nearest other points, over a sample."""
    idx = np.random.default_rng(0).choice(len(cloud), count, replace=False)
    d = np.linalg.norm(cloud[idx][:, None, :] - cloud[None, :, :], axis=2)
    d.sort(axis=1)
    return d[:, 1:7].mean()


def test_two_sheets_half_a_kernel_apart_each_project_onto_themselves():
    t = np.arange(-1.0, 1.0 + 1e-9, 1.0 / 40)
    x, y = (v.ravel() for v in np.meshgrid(t, t, indexing="ij"))
    lower = np.column_stack([x, y, 0.05 * np.sin(2 * x)])
    gap, kernel = 0.02, 1.5
    upper = lower + [0.0, 0.0, gap]
    both = np.vstack([lower, upper])
    h = kernel * mean_spacing(both)
    assert 0.45 <= gap / h <= 0.6, f"the sheets are {gap / h:.2f} kernel widths apart"
    inner = (np.abs(x) < 0.8) & (np.abs(y) < 0.8)
    for sheet in (lower[inner], upper[inner]):
        kept, normals = ps.project_sheets(sheet, both, kernel=kernel)
        assert np.abs(kept - sheet).max() < 0.1 * gap
        assert np.abs(normals[:, 2]).min() > 0.99
        # The isotropic projection merges them into their middle surface, as PCL's MLS does.
        merged, _ = ps.project(sheet, both, kernel=kernel)
        assert np.abs(merged - sheet)[:, 2].min() > 0.4 * gap


def test_project_sheets_bad_input():
    p = ps.shapes.sphere(500)
    with pytest.raises(ValueError, match="sheet"):
        ps.project_sheets(p, p, sheet=2.0)
    with pytest.raises(ValueError, match="sheet"):
        ps.project_sheets(p, p, sheet=0.0)
    with pytest.raises(ValueError, match="onto_normals"):
        ps.project_sheets(p, p, onto_normals=p[:10])
    with pytest.raises(ValueError, match="onto_normals: .* of them are zero"):
        ps.project_sheets(p, p, onto_normals=np.zeros_like(p))


# ----------------------------------------------------------------------------------------------
# decompose(smoother=..., encoding=...)

def test_decompose_diffusion_smoother_round_trip_and_smoother_levels():
    p = ps.shapes.bumpy_sphere(20000, fine_frequency=40.0)
    dec = ps.decompose(p, 4, smoother="diffusion")
    assert dec.settings["smoother"] == "diffusion"
    assert np.abs(ps.reconstruct(dec) - p).max() <= 1e-11 * diag(p)  # measured 3e-15
    fine = [abs(radial_amplitudes(dec.level(l), [3.0, 40.0])[1]) for l in range(dec.n_levels)]
    assert_fine_pattern_fades_level_by_level(fine)
    plain = ps.decompose(p, 4)
    assert radial_amplitudes(dec.level(0), [3.0, 40.0])[0] < radial_amplitudes(plain.level(0), [3.0, 40.0])[0]


def test_decompose_rayshoot_encoding_and_bad_options():
    p = ps.shapes.bumpy_sphere(20000)
    dec = ps.decompose(p, 4, encoding="rayshoot", smoother="diffusion")
    assert dec.settings["encoding"] == "rayshoot" and len(dec.settings["rays_missed"]) == 3
    with pytest.raises(ValueError, match="smoother"):
        ps.decompose(p, smoother="gauss")
    with pytest.raises(ValueError, match="encoding"):
        ps.decompose(p, encoding="orthogonal")


# ----------------------------------------------------------------------------------------------
# A real scan onto its ellipsoid, as the paper did with Max Planck (Fig. 8)

@pytest.mark.data
def test_encode_a_scan_onto_its_ellipsoid():
    from helpers import shared_model
    from plyfile import PlyData
    v = PlyData.read(str(shared_model("bunny.ply")))["vertex"]
    p = np.column_stack([v["x"], v["y"], v["z"]]).astype(np.float64)
    base = ps.ellipsoid_base(p, n=20000)
    dec = ps.encode(p, base)
    lo, hi = p.min(axis=0), p.max(axis=0)
    assert ellipsoid_distance(ps.reconstruct(dec, [0.0]), 0.5 * (lo + hi), 0.5 * (hi - lo)).max() < 1e-3 * diag(p)
    err = np.linalg.norm(ps.reconstruct(dec, [1.0]) - p, axis=1)
    # Parts reach past the ellipsoid's centres of curvature: the few points with no consistent
    # position are counted, the error left is reported, and nearly all points come back exactly.
    assert dec.stats[0]["pinned"] < 0.005 * len(p)
    assert np.percentile(err, 99) < 1e-5 * diag(p)
    assert err.max() <= dec.stats[0]["consistency_residual"] * (1 + 1e-6) + 1e-12


# ----------------------------------------------------------------------------------------------
# Progress and cancellation, like the core functions

@pytest.mark.parametrize("call", [
    lambda cb: ps.smooth_diffusion(ps.shapes.sphere(4000), 20, progress=cb),
    lambda cb: ps.encode(ps.shapes.bumpy_sphere(4000), ps.shapes.sphere(2000), progress=cb),
    lambda cb: ps.morph(ps.shapes.sphere(3000), ps.shapes.bumpy_sphere(3000), ps.shapes.sphere(2000), progress=cb),
    lambda cb: ps.decompose_rayshoot(ps.shapes.bumpy_sphere(8000), 3, progress=cb),
])
def test_progress_and_cancel(call):
    seen = []
    call(lambda f: seen.append(f))
    assert seen and seen[-1] == pytest.approx(1.0) and all(0.0 <= f <= 1.0 for f in seen)
    with pytest.raises(ps.Cancelled):
        call(lambda f: False)

    def boom(f):
        raise KeyError("from the callback")
    with pytest.raises(KeyError):
        call(boom)


def test_encoded_and_rayshoot_decompositions_save_and_load(tmp_path):
    p = ps.shapes.bumpy_sphere(6000)
    for dec in (ps.encode(p, ps.shapes.sphere(3000)), ps.decompose_rayshoot(p, 3)):
        dec.save(tmp_path / "d.npz")
        back = ps.load(tmp_path / "d.npz")
        assert back.settings == dec.settings
        gains = [0.5] * dec.n_bands
        np.testing.assert_array_equal(ps.reconstruct(back, gains), ps.reconstruct(dec, gains))
