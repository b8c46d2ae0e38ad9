"""An editing session's Reconstructor redoes, on each edited call, only what the base's changes
since its last edited call reach (reconstruction.cpp, rebuild_since_last_edit). Whatever the
sequence of calls, each must give what the stateless reconstruct gives, bit for bit."""
import numpy as np
import pytest

import pointscale as ps
from helpers import diagonal


def dab(base, normals, centre, radius, height):
    """A smooth bump along the centre's normal, as one brush dab."""
    t = np.clip(1 - np.linalg.norm(base - base[centre], axis=1) / radius, 0, 1)
    return base + height * (t * t * (3 - 2 * t))[:, None] * normals[centre]


def session_steps(dec, rng, count):
    """(gains, base) pairs of an editing session: brush dabs that add up, a dab undone, a base
    moved everywhere, the stored base handed back, gains changed (one per band and painted),
    and the same call twice."""
    base, normals = dec.base, dec.normals(0)
    n, k, diag = len(base), dec.n_bands, diagonal(base)
    current, gains, history = base.copy(), None, []
    for _ in range(count):
        step = rng.integers(0, 11)
        if step < 5:
            history.append(current)
            current = dab(current, normals, rng.integers(n), rng.uniform(0.03, 0.2) * diag,
                          rng.uniform(-0.06, 0.06) * diag)
        elif step == 5 and history:
            current = history.pop()
        elif step == 6:
            current = base + rng.normal(0.0, 1e-3 * diag, base.shape)
        elif step == 7:
            current = base.copy()
        elif step == 8:
            gains = [float(g) for g in rng.uniform(0.0, 2.0, k)]
        elif step == 9:
            gains = rng.uniform(0.0, 2.0, (k, n))
        else:
            gains = None
        yield gains, current
        if rng.random() < 0.25:
            yield gains, current


@pytest.mark.parametrize("shape, seed", [("bumpy sphere", 1), ("handles", 2), ("torus, shuffled", 3)])
def test_every_call_of_a_session_matches_reconstruct_bit_for_bit(shape, seed):
    rng = np.random.default_rng(seed)
    if shape == "bumpy sphere":
        points = ps.shapes.bumpy_sphere(12000)
    elif shape == "handles":
        points = ps.shapes.handles_plane(size=2.0, count=4, width=0.1, height=0.4, spacing=0.035)[0]
    else:
        points = ps.shapes.bumpy_torus(12000)
        points = points[rng.permutation(len(points))]
    dec = ps.decompose(points, levels=4)
    session = ps.Reconstructor(dec)
    calls = 0
    for gains, base in session_steps(dec, rng, 30):
        np.testing.assert_array_equal(session.reconstruct(gains, base=base), ps.reconstruct(dec, gains, base=base))
        calls += 1
    assert calls >= 30


def test_a_cancelled_call_leaves_the_session_as_good_as_new():
    dec = ps.decompose(ps.shapes.bumpy_sphere(8000), levels=3)
    base, normals, diag = dec.base, dec.normals(0), diagonal(dec.base)
    session = ps.Reconstructor(dec)
    first = dab(base, normals, 10, 0.1 * diag, 0.03 * diag)
    np.testing.assert_array_equal(session.reconstruct(base=first), ps.reconstruct(dec, base=first))
    second = dab(first, normals, 500, 0.1 * diag, 0.03 * diag)
    with pytest.raises(ps.Cancelled):
        session.reconstruct(base=second, progress=lambda fraction: False)
    third = dab(second, normals, 2000, 0.1 * diag, -0.03 * diag)
    for edited in (third, second, first):
        np.testing.assert_array_equal(session.reconstruct(base=edited), ps.reconstruct(dec, base=edited))


def test_a_dab_moves_only_what_it_reaches():
    """The point of it: after a dab, the points far from it are the last call's, and those it
    reaches moved (so the check above is not passing on calls that redo nothing)."""
    dec = ps.decompose(ps.shapes.bumpy_sphere(12000), levels=4)
    base, normals, diag = dec.base, dec.normals(0), diagonal(dec.base)
    session = ps.Reconstructor(dec)
    before = session.reconstruct(base=dab(base, normals, 0, 0.1 * diag, 0.03 * diag))
    centre = 6000
    after = session.reconstruct(base=dab(dab(base, normals, 0, 0.1 * diag, 0.03 * diag), normals, centre,
                                         0.1 * diag, 0.03 * diag))
    far = np.linalg.norm(base - base[centre], axis=1) > 0.3 * diag
    near = np.linalg.norm(base - base[centre], axis=1) < 0.05 * diag
    assert far.sum() > 6000 and near.sum() > 20
    np.testing.assert_array_equal(after[far], before[far])
    assert np.linalg.norm(after[near] - before[near], axis=1).min() > 1e-3 * diag
