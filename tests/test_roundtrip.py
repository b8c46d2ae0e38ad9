"""Exact reconstruction (Eq. 9-11) and the trivial filters, on generated shapes."""
import numpy as np
import pytest

import pointscale as ps
from helpers import diagonal

# A round trip gives the input back to rounding: measured 1e-17..3e-13 of the diagonal (the plane
# with box handles is the largest), so a bound of 1e-11 catches a loss of precision.
ROUND_TRIP = 1e-11
# One step of Eq. 8, level(l) + detail * normal = level(l + 1): measured at most 6e-17.
ONE_STEP = 1e-13

SHAPES = {
    "noisy sphere": lambda: ps.shapes.sphere(20000, noise=0.01),
    "plane with box handles": lambda: ps.shapes.handles_plane()[0],
    "bumpy torus": lambda: ps.shapes.bumpy_torus(30000),
    "open patch with boundary": lambda: ps.shapes.wavy_patch(20000),
}


@pytest.fixture(scope="module", params=list(SHAPES))
def case(request):
    points = SHAPES[request.param]()
    return points, ps.decompose(points, levels=4)


def test_unit_gains_return_the_input(case):
    points, dec = case
    error = np.abs(ps.reconstruct(dec) - points).max()
    assert error <= ROUND_TRIP * diagonal(points), error


def test_every_level_keeps_all_points_indexed_like_the_input(case):
    points, dec = case
    assert dec.n_levels == 4 and dec.details.shape == (3, len(points))
    for l in range(dec.n_levels):
        assert dec.level(l).shape == points.shape
    assert np.abs(dec.level(3) - points).max() <= ROUND_TRIP * diagonal(points)
    # Eq. 8: every level is the one below displaced along its normals by the signed detail.
    for l in range(3):
        step = dec.level(l) + dec.details[l][:, None] * dec.normals(l)
        assert np.abs(step - dec.level(l + 1)).max() <= ONE_STEP * diagonal(points)


def test_stored_base_normals_are_the_recomputed_ones(case):
    # Unedited, reconstruction reads level 0's normals from the model instead of fitting
    # them again: that is exact only if they are bit for bit what the fit gives.
    # Centred on their bounding box, the points decompose about the origin 0, so that dec.base
    # given back is the model's base bit for bit (no centring rounds it); then every level
    # rebuilt from it (level 0's normals fitted) is the one rebuilt from the stored normals.
    points, dec = case
    centred = points - 0.5 * (points.min(axis=0) + points.max(axis=0))
    about_zero = ps.decompose(centred, levels=4)
    assert not about_zero.origin.any()
    assert np.array_equal(ps.reconstruct_levels(about_zero, base=about_zero.base), ps.reconstruct_levels(about_zero))
    assert np.array_equal(ps.reconstruct_levels(about_zero)[-1], ps.reconstruct(about_zero))
    # Off the origin, centring the base given back would round it off the stored one: it is
    # recognised as the stored base, and gives the unedited points bit for bit.
    assert np.array_equal(ps.reconstruct(dec, base=dec.base), ps.reconstruct(dec))
    assert np.array_equal(ps.Reconstructor(dec).reconstruct(base=dec.base), ps.reconstruct(dec))
    assert np.array_equal(ps.reconstruct(dec, [0.5, 2.0, 1.0], dec.base.copy()), ps.reconstruct(dec, [0.5, 2.0, 1.0]))


def test_the_reconstructor_gives_reconstruct_bit_for_bit(case):
    # It holds the model in another point order; every fit must still be the same one.
    points, dec = case
    solver = ps.Reconstructor(dec)
    rng = np.random.default_rng(3)
    edited = dec.base + 0.05 * diagonal(points) * np.sin(dec.base[:, [1, 2, 0]] * 3.0)
    painted = rng.uniform(0.0, 2.0, (dec.n_bands, dec.n_points))
    for kwargs in (dict(), dict(base=edited), dict(gains=[0.0, 1.0, 2.0], base=edited), dict(gains=painted),
                   dict(gains=painted, base=edited)):
        assert np.array_equal(solver.reconstruct(**kwargs), ps.reconstruct(dec, **kwargs)), kwargs


def _alone(dec, gains, base):
    """The core's reconstruction with nothing kept between calls (no EditMemo)."""
    return dec._model.reconstruct(ps.multiscale._gains_array(dec, gains), base=base, origin=dec.origin)


def test_reconstruct_keeps_what_every_edit_needs_and_gives_the_same_points(case):
    # The first call on an edited base finds what every edit needs and keeps it with the
    # decomposition; the calls after it read it. Each gives what the model gives with nothing
    # kept, bit for bit, at unit, band and painted gains, whichever call came first.
    points, dec = case
    fresh = ps.Decomposition.from_dict(dec.to_dict())
    wave = dec.base + 0.05 * diagonal(points) * np.sin(dec.base[:, [1, 2, 0]] * 3.0)
    lift = dec.base + 0.02 * diagonal(points) * np.cos(dec.base[:, [2, 0, 1]] * 2.0)
    painted = np.random.default_rng(5).uniform(0.0, 2.0, (dec.n_bands, dec.n_points))
    calls = [([0.0, 1.0, 2.0], wave), (None, wave), (painted, lift), (None, lift), ([1.0, 1.0, 1.0], wave)]
    for gains, base in calls:
        assert np.array_equal(ps.reconstruct(fresh, gains, base), _alone(fresh, gains, base))
    assert "edit" in fresh._cache  # kept: the calls above after the first read it


def test_a_memo_found_for_a_model_of_another_size_is_refused():
    # The package keeps one memo per decomposition; the core's own callers could mix them up,
    # and a memo read for more or fewer points than it holds would read out of its bounds.
    small = ps.decompose(ps.shapes.bumpy_sphere(3000, seed=1), levels=3)
    large = ps.decompose(ps.shapes.bumpy_sphere(4000, seed=2), levels=3)
    memo = ps.multiscale._core.EditMemo()
    ones = np.ones(small.n_bands)
    small._model.reconstruct(ones, base=small.base * 1.01, origin=small.origin, memo=memo)
    with pytest.raises(ValueError, match="EditMemo was found for a model of 3000 points"):
        large._model.reconstruct(ones, base=large.base * 1.01, origin=large.origin, memo=memo)


@pytest.mark.parametrize("stop_below", [0.0, 0.6])
def test_reconstruct_cancelled_on_its_first_edited_call_keeps_nothing_half_found(case, stop_below):
    # Cancelled inside the unedited pass, or just as the support is complete (2/3), the call
    # keeps nothing half-found: the next call finds it again and is right.
    points, dec = case
    fresh = ps.Decomposition.from_dict(dec.to_dict())
    wave = dec.base + 0.05 * diagonal(points) * np.sin(dec.base[:, [1, 2, 0]] * 3.0)
    seen = []
    with pytest.raises(ps.Cancelled):
        ps.reconstruct(fresh, None, wave, progress=lambda f: seen.append(f) or f < stop_below)
    assert seen[-1] < 1.0
    for gains in ([1.0, 2.0, 1.0], None):
        assert np.array_equal(ps.reconstruct(fresh, gains, wave), _alone(fresh, gains, wave)), gains


def test_a_result_does_not_depend_on_the_calls_before_it(case):
    # The same calls on a copy of the model made afresh, in another order, give the same points
    # bit for bit (what an edited base needs is kept, and must be the same whichever call found it).
    points, dec = case
    wave = dec.base + 0.05 * diagonal(points) * np.sin(dec.base[:, [1, 2, 0]] * 3.0)
    lift = dec.base + 0.02 * diagonal(points) * np.cos(dec.base[:, [2, 0, 1]] * 2.0)
    calls = [dict(base=wave), dict(gains=[1.0, 2.0, 0.5], base=wave), dict(gains=[1.0, 2.0, 0.5], base=lift),
             dict(), dict(gains=[0.0, 1.0, 1.0])]
    first = [ps.reconstruct(dec, **kwargs) for kwargs in calls]
    copy = ps.Decomposition.from_dict(dec.to_dict())
    for i in reversed(range(len(calls))):
        assert np.array_equal(ps.reconstruct(copy, **calls[i]), first[i]), calls[i]


def test_a_reconstructor_finds_the_edit_support_on_its_first_edited_call(case):
    # Unedited calls first (Bake Filter's order), then edits: the support it finds then, in its
    # own point order, must be the one reconstruct() finds.
    points, dec = case
    solver = ps.Reconstructor(dec)
    assert np.array_equal(solver.reconstruct([2.0, 1.0, 1.0]), ps.reconstruct(dec, [2.0, 1.0, 1.0]))
    wave = dec.base + 0.05 * diagonal(points) * np.sin(dec.base[:, [1, 2, 0]] * 3.0)
    for gains in ([2.0, 1.0, 1.0], None, [2.0, 1.0, 1.0]):
        assert np.array_equal(solver.reconstruct(gains, wave), ps.reconstruct(dec, gains, wave)), gains


@pytest.mark.parametrize("stop_below", [0.0, 0.6])
def test_a_reconstructor_cancelled_on_its_first_edited_call_is_still_right(case, stop_below):
    # Blender's first Rebuild Detail finds the edit support: it reports progress there and can
    # be cancelled. Cancelled at the first report (inside the unedited pass), or just as the
    # support is complete (2/3), nothing half-found may stay behind for the next call.
    points, dec = case
    solver = ps.Reconstructor(dec)
    wave = dec.base + 0.05 * diagonal(points) * np.sin(dec.base[:, [1, 2, 0]] * 3.0)
    seen = []
    with pytest.raises(ps.Cancelled):
        solver.reconstruct([1.0, 2.0, 1.0], wave, progress=lambda f: seen.append(f) or f < stop_below)
    if stop_below == 0.0:
        assert len(seen) == 1 and 0.0 < seen[0] < 1.0 / 3.0  # within the unedited pass
    else:
        assert seen[-1] == pytest.approx(2.0 / 3.0) and max(seen[:-1]) < stop_below
    for gains in ([1.0, 2.0, 1.0], None):
        assert np.array_equal(solver.reconstruct(gains, wave), ps.reconstruct(dec, gains, wave)), gains


def test_progress_on_an_edited_base_rises_to_one(case):
    # reconstruct() and a Reconstructor's first and later calls each report fractions that
    # never go back, and end at 1 (a progress bar that jumps back or stops short looks broken).
    points, dec = case
    solver = ps.Reconstructor(dec)
    wave = dec.base + 0.05 * diagonal(points) * np.sin(dec.base[:, [1, 2, 0]] * 3.0)
    calls = [lambda cb: ps.reconstruct(dec, None, wave, progress=cb),
             lambda cb: ps.reconstruct(dec, [1.0, 2.0, 1.0], wave, progress=cb),
             lambda cb: solver.reconstruct(None, wave, progress=cb),
             lambda cb: solver.reconstruct(None, wave, progress=cb),
             lambda cb: solver.reconstruct([1.0, 2.0, 1.0], wave, progress=cb)]
    for n, call in enumerate(calls):
        seen = []
        call(seen.append)
        assert seen and np.all(np.diff(seen) >= 0.0) and 0.0 <= seen[0] and seen[-1] == 1.0, (n, seen)


def test_zero_gains_give_the_base(case):
    points, dec = case
    assert np.array_equal(ps.reconstruct(dec, gains=np.zeros(3)), dec.base)


def test_blend_at_whole_numbers_is_the_level(case):
    points, dec = case
    for l in range(dec.n_levels):
        assert np.array_equal(ps.blend(dec, l), dec.level(l))  # the level itself, no arithmetic
    mid = ps.blend(dec, 1.5)
    assert np.abs(mid - 0.5 * (dec.level(1) + dec.level(2))).max() <= ONE_STEP * diagonal(points)  # measured 2e-20


def test_per_point_gains_match_per_band_gains(case):
    points, dec = case
    g = np.array([0.5, 2.0, 0.0])
    painted = np.repeat(g[:, None], len(points), axis=1)
    # Measured equal bit for bit; the bound allows another order of the products only.
    assert np.abs(ps.reconstruct(dec, gains=g) - ps.reconstruct(dec, gains=painted)).max() <= ONE_STEP * diagonal(points)


def test_painted_gains_only_change_where_painted():
    points = ps.shapes.bumpy_sphere(20000)
    dec = ps.decompose(points, levels=3)
    gains = np.ones((2, len(points)))
    left = points[:, 0] < -0.3
    gains[:, left] = 0.0
    out = ps.reconstruct(dec, gains=gains)
    far_right = points[:, 0] > 0.3
    assert np.abs(out[far_right] - points[far_right]).max() < ROUND_TRIP * diagonal(points)
    assert np.abs(out[left] - points[left]).max() > 1e-3  # the painted side was smoothed


def test_far_from_origin_still_round_trips():
    points = ps.shapes.bumpy_sphere(15000, fine=0.005) + 1e6
    dec = ps.decompose(points, levels=3)
    error = np.abs(ps.reconstruct(dec) - points).max()
    assert error <= ROUND_TRIP * diagonal(points), error
    assert np.abs(dec.base.mean(axis=0) - 1e6).max() < 0.1


def test_duplicate_points_are_valid():
    points = ps.shapes.sphere(8000, noise=0.005)
    points = np.vstack([points, points[:500]])
    dec = ps.decompose(points, levels=3)
    assert np.abs(ps.reconstruct(dec) - points).max() <= ROUND_TRIP * diagonal(points)


def test_save_and_load_round_trip(tmp_path):
    # Shuffled, so that no cluster's points are neighbours in the point order: the core keeps
    # per-point frame coordinates in cluster order and saves them in point order.
    points = np.random.default_rng(3).permutation(ps.shapes.bumpy_sphere(10000))
    dec = ps.decompose(points, levels=3)
    dec.save(tmp_path / "d.npz")
    back = ps.load(tmp_path / "d.npz")
    assert np.array_equal(back.base, dec.base) and np.array_equal(back.details, dec.details)
    assert back.settings == dec.settings
    assert np.array_equal(ps.reconstruct(back, gains=[1, 2]), ps.reconstruct(dec, gains=[1, 2]))
    saved, again = dec.to_dict(), back.to_dict()
    assert saved.keys() == again.keys()
    assert all(np.array_equal(saved[key], again[key]) for key in saved)


def test_input_normals_set_the_orientation():
    points = ps.shapes.bumpy_sphere(10000)
    inward = -points / np.linalg.norm(points, axis=1, keepdims=True)
    dec_in = ps.decompose(points, levels=3, normals=inward)
    dec_out = ps.decompose(points, levels=3)
    assert np.abs(dec_in.details + dec_out.details).max() <= ONE_STEP * diagonal(points)  # measured 0
    # Without normals a closed shape is oriented outward: bumps are positive detail.
    assert (np.einsum("ij,ij->i", dec_out.normals(0), points) > 0).mean() > 0.99
