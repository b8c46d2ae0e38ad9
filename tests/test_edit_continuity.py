"""An edit that changes the base a little changes the result a little (Sec. 8.1): no point's
detail jumps as the edit goes on.

Each case runs one edit from part of the way to all of it, finds the step where the result
moves most for how far the base moved, and narrows it down by bisection to two bases 1e-13
apart: there the result must move by no more than rounding. A ring whose plane swings round
under a strong shear (the blend zone of a part turned rigidly) gave up its own turn for its
level-0 cluster's at once, and its points' detail turned 90 degrees at that one step.
"""
import numpy as np
import pytest

import pointscale as ps
from helpers import diagonal, shared_model


def finned_torus(nu=300, nv=80, radius=1.0, tube=0.3, fins=6, fin_height=0.25, fin_width=0.06):
    """A torus with thin fins standing on the outer half of its tube."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, nu, endpoint=False), np.linspace(0, 2 * np.pi, nv, endpoint=False))
    u, v = u.ravel(), v.ravel()
    r = np.full(u.shape, tube)
    for k in range(fins):
        du = np.angle(np.exp(1j * (u - 2 * np.pi * k / fins)))
        r += fin_height * np.exp(-(du / fin_width) ** 4) * np.sqrt(np.clip(np.cos(v), 0, None))
    return np.c_[(radius + r * np.cos(v)) * np.cos(u), (radius + r * np.cos(v)) * np.sin(u), r * np.sin(v)]


def part_turned(base, along, about, degrees, shift, blend):
    """The edit s in [0, 1]: the base beyond its centre along the unit vector `along` turned
    rigidly about the unit axis `about` (through the centre) by s * degrees and moved by
    s * shift, blended into the rest over the width `blend`."""
    centre = base.mean(axis=0)
    weight = np.clip((base - centre) @ along / blend, 0, 1)[:, None]
    k = np.array([[0, -about[2], about[1]], [about[2], 0, -about[0]], [-about[1], about[0], 0]])

    def edit(s):
        a = np.radians(degrees * s)
        turn = np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k  # Rodrigues
        moved = (base - centre) @ turn.T + centre + s * np.asarray(shift)
        return (1 - weight) * base + weight * moved
    return edit


def largest_jump(dec, edit, start, steps=40):
    """The largest move of any point, as a share of the diagonal, between two bases of the
    edit 1e-13 apart, found by bisection from the step of [start, 1] where the result moved
    most for how far the base moved."""
    diag = diagonal(dec.base)
    at = lambda s: ps.reconstruct(dec, base=edit(s))  # noqa: E731
    grid = np.linspace(start, 1.0, steps + 1)
    results = [at(s) for s in grid]
    ratios = [np.linalg.norm(b - a, axis=1).max() / np.linalg.norm(edit(t) - edit(s), axis=1).max()
              for a, b, s, t in zip(results, results[1:], grid, grid[1:])]
    k = int(np.argmax(ratios))
    lo, hi = grid[k], grid[k + 1]
    low, high = results[k], results[k + 1]
    while hi - lo > 1e-13:
        mid = 0.5 * (lo + hi)
        middle = at(mid)
        if np.linalg.norm(middle - low, axis=1).max() >= np.linalg.norm(high - middle, axis=1).max():
            hi, high = mid, middle
        else:
            lo, low = mid, middle
    return np.linalg.norm(high - low, axis=1).max() / diag


@pytest.mark.parametrize("degrees, lift", [(40.0, 0.3), (-55.0, 0.1)])
def test_a_part_turned_rigidly_moves_the_finned_torus_continuously(degrees, lift):
    """The fins jumped 10% of the diagonal at one step of (40, 0.3); the other edit turns the
    other way and further."""
    points = finned_torus()
    dec = ps.decompose(points, levels=4)
    up, x = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    edit = part_turned(dec.base, up, x, degrees, lift * up, 0.3)
    assert largest_jump(dec, edit, 0.5) < 1e-9


@pytest.mark.parametrize("degrees", [90.0, 179.0])
def test_a_part_turned_far_moves_the_finned_torus_continuously(degrees):
    """Turns far past 90 degrees, where rings that keep their shape keep their own turn however
    far it is from their cluster's: a first version of that rule slerped between turns half a
    circle apart, and the 90-degree turn jumped 9% of the diagonal."""
    points = finned_torus()
    dec = ps.decompose(points, levels=4)
    up, x = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    assert largest_jump(dec, part_turned(dec.base, up, x, degrees, 0.2 * up, 0.3), 0.0) < 1e-9


@pytest.mark.parametrize("degrees", [35.0, -50.0])
def test_a_part_turned_rigidly_moves_a_scan_continuously(degrees):
    """One end of the bunny turned in its own plane (about its thinnest principal axis),
    blended over 15% of the diagonal: its detail jumped 3.4% of the diagonal at one step of
    the 35-degree turn, turning 84 degrees."""
    points = ps.io.read(shared_model("bunny.ply")).points
    dec = ps.decompose(points, levels=4)
    axes = np.linalg.svd(dec.base - dec.base.mean(axis=0), full_matrices=False)[2]
    edit = part_turned(dec.base, axes[0], axes[2], degrees, np.zeros(3), 0.15 * diagonal(dec.base))
    assert largest_jump(dec, edit, 0.5) < 1e-9


@pytest.mark.parametrize("copies", [25, 200])
def test_a_rigid_turn_of_a_base_with_coincident_points_is_that_turn(copies):
    """A point repeated 24 times or more (a scan's repeated returns) filled a neighbour's whole
    ring: a rigid turn of the base turned that neighbour's detail wrongly, by 8% of the
    diagonal, and the error jumped as the turn grew (API trial)."""
    points = ps.shapes.bumpy_sphere(5000)
    points = np.concatenate([points, np.repeat(points[:1], copies, axis=0)])
    dec = ps.decompose(points, levels=4)
    centre = dec.base.mean(axis=0)
    for degrees in (34.5, 90.0):
        a = np.radians(degrees)
        turn = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])
        result = ps.reconstruct(dec, base=(dec.base - centre) @ turn.T + centre)
        error = np.linalg.norm(result - ((points - centre) @ turn.T + centre), axis=1).max()
        assert error < 1e-12 * diagonal(points), (degrees, error / diagonal(points))
