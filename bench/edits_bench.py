#!/usr/bin/env python3
"""Edits at any scale (issue 16): the figures behind the tests, printed (no assertions).

    python bench/edits_bench.py [--no-scans] [--other-scans]

1. Tall handles on a lifted base: the largest angle, over the 16 handles, between a handle's
   axis and the analytic normal of the lift at its centre, per shape, setting and lift
   (centred on a handle and between handles; radius as a multiple of the handle spacing;
   height 0.5 and 1.0 times the radius). Each cell gives two measures of the axis: top face
   mean minus bottom ring mean / principal axis of all the handle's points (the issue's).
2. Scans (Max Planck, bunny; skipped without ../shared/data): brush lifts of 5, 10 and 15% of
   the diagonal at three places, and a 60-degree bend of one end. Per edit, over the points the
   edit moved: the 95th percentile of the change in each detail offset's angle to the base
   normal (independent 24-neighbour PCA of the unedited and of the edited base), the same with
   the edited PCA taken over the unedited neighbour sets; the same over the points where that
   reference is well defined (its 24 neighbours face the same way, and they spread across their
   plane at least 20 times more than off it, on both bases); the same measure of an offset
   turned by the change of a PCA normal with 20 and with 32 neighbours at its own base position
   (no engine: how far the measure moves when "about 24 neighbours" is taken as 20 or 32); and
   the largest change of an offset's length. With --other-scans, the same on scans the issue does not name (igea,
   nefertiti, lucy, armadillo, every 5th point of the dragon), brushes at other places.
3. reconstruct and Reconstructor at 100k points (bumpy sphere, generator order), medians of
   15: unedited, and handed its own base back; then on bases that change from call to call:
   two lifts that move the base everywhere, in turn, and 16 brush dabs 5% of the diagonal wide,
   one after another (each call's base is the one before plus a dab); a fresh Reconstructor's
   first edited call (median of 9).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the tests' edits and measures, so both use the same ones

import pointscale as ps  # noqa: E402
from helpers import SHARED_DATA, diagonal  # noqa: E402
from test_edits_at_any_scale import (SHAPES, bend, brush, gaussian_lift, handle_axis_angles,  # noqa: E402
                                     handle_principal_axis_angles, lift_normal, pca_normals, plane_is_clear,
                                     reference_defined, rotation_between)


def handles() -> None:
    print("1. tall handles: largest angle (degrees) over the 16 handles, axis / principal axis")
    print("| shape, decimation, levels, kernel | base height range / handle height | lift height / radius |"
          " on, 0.75 | on, 1 | on, 1.5 | on, 2 | between, 0.75 | between, 1 | between, 1.5 | between, 2 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for (name, decimation), (width, height, spacing, _, levels) in SHAPES.items():
        points, handle, centres = ps.shapes.handles_plane(size=2.0, count=4, width=width, height=height,
                                                          spacing=spacing)
        for kernel in (1.0, 2.0):
            dec = ps.decompose(points, levels=levels, decimation=decimation, kernel=kernel)
            for lift_factor in (0.5, 1.0):
                cells = []
                for centre in (centres[9], centres[5] + 0.25):
                    for factor in (0.75, 1.0, 1.5, 2.0):
                        radius = 0.5 * factor
                        lift = lift_factor * radius
                        result = ps.reconstruct(dec, base=gaussian_lift(dec.base, centre, radius, lift))
                        normal_at = lambda c: lift_normal(c, centre, radius, lift)[0]  # noqa: E731
                        angles = handle_axis_angles(result, points, handle, centres, normal_at)
                        principal = handle_principal_axis_angles(result, handle, centres, normal_at)
                        cells.append(f"{angles.max():.2f} / {principal.max():.2f}")
                flat = np.ptp(dec.base[:, 2]) / height
                print(f"| {name} ({len(points)} pts), {decimation}, {levels}, {kernel:g} | {flat:.3f} |"
                      f" {lift_factor:g} | " + " | ".join(cells) + " |")


ISSUE_SCANS = ("max_planck.ply", "bunny.ply")
# Scans the issue does not name, with other brush centres (seeds 2, 5, 11): 38-134k points
# (the issue's two have 25k and 36k); the dragon taken every 5th point (88k of its 438k).
OTHER_SCANS = {"igea.ply": 1, "nefertiti.ply": 1, "lucy_50k.ply": 1, "armadillo_points_normals.ply": 1,
               "dragon.ply": 5}


def scans(names=ISSUE_SCANS, seeds=(1, 3, 7)) -> None:
    print("\n2. scans: p95 change of offset angle to the base normal (degrees); the same with the edited"
          " PCA over the unedited neighbour sets; the first over the points where the PCA reference is"
          " well defined; largest relative change of an offset's length")
    print("| scan | edit | points moved | p95 | p95, same neighbour sets | p95 where the reference is well"
          " defined (share of points) | p95 of a turn by PCA-20 / PCA-32 normals (no engine) | length change |")
    print("|---|---|---|---|---|---|---|---|")
    for name in names:
        path = SHARED_DATA / name
        if not path.exists():
            print(f"| {name} | skipped: not in {SHARED_DATA} | | | | | |")
            continue
        points = ps.io.read(path).points
        step = names[name] if isinstance(names, dict) else 1
        points = points[::step]
        scan_label = name if step == 1 else f"{name}, every {step}th point"
        dec = ps.decompose(points, levels=4)
        base, diag = dec.base, diagonal(dec.base)
        n0 = pca_normals(base, dec.normals(0))
        before = ps.reconstruct(dec) - base
        rings = cKDTree(base).query(base, 24)[1]
        defined = reference_defined(dec)
        edits = []
        for seed in seeds:
            centre = np.random.default_rng(seed).integers(len(points))
            for frac in (0.05, 0.10, 0.15):
                edits.append((f"brush {frac:.0%} at #{centre}", brush(base, n0, centre, frac * diag, 0.3 * frac * diag)))
        extent = np.ptp(base, axis=0)
        order = np.argsort(extent)
        for sign in (1, -1):
            along, towards = sign * np.eye(3)[order[2]], np.eye(3)[order[0]]
            edited, theta = bend(base, along, towards, 60.0)
            assert abs(np.degrees(theta.max()) - 60.0) < 1e-9, 'the bend must reach 60 degrees'
            edits.append((f"bend 60 deg, {'+' if sign > 0 else '-'} end", edited))
        for label, edited in edits:
            after = ps.reconstruct(dec, base=edited) - edited
            moved = np.linalg.norm(edited - base, axis=1) > 1e-9 * diag
            l0, l1 = np.linalg.norm(before, axis=1), np.linalg.norm(after, axis=1)
            use = moved & (l0 > 1e-9 * diag)
            polar0 = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", before, n0) / l0, -1, 1)))
            n1 = pca_normals(edited, n0)

            def change_of(offsets, normals):
                length = np.maximum(np.linalg.norm(offsets, axis=1), 1e-300)
                polar1 = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", offsets, normals) / length, -1, 1)))
                return np.abs(polar1 - polar0)
            change = [change_of(after, n1), change_of(after, fixed_set_normals(edited, rings, n0))]
            row = [np.percentile(c[use], 95) for c in change]
            spread = [np.percentile(change_of(turned_by_pca(base, edited, before, n0, k), n1)[use], 95) for k in (20, 32)]
            clear = use & defined & plane_is_clear(edited)
            on_clear = np.percentile(change[0][clear], 95)
            length = np.abs(l1 / np.maximum(l0, 1e-300) - 1)[use].max()
            print(f"| {scan_label} | {label} | {use.sum()} | {row[0]:.2f} | {row[1]:.2f} | {on_clear:.2f}"
                  f" ({clear.sum() / use.sum():.0%}) | {spread[0]:.2f} / {spread[1]:.2f} | {length:.1e} |")


def fixed_set_normals(points, rings, reference):
    q = points[rings] - points[rings].mean(axis=1, keepdims=True)
    n = np.linalg.eigh(np.einsum("nki,nkj->nij", q, q))[1][:, :, 0]
    return n * np.where(np.einsum("ij,ij->i", n, reference) < 0, -1.0, 1.0)[:, None]


def turned_by_pca(base, edited, offsets, reference, k):
    """The offsets turned, each at its own base position, by the change of its k-neighbour PCA
    normal from the stored base to the edited one: an edit's turn taken from the measure's own
    kind of normal, with another neighbour count."""
    n0 = pca_normals(base, reference, k)
    return np.einsum("nij,nj->ni", rotation_between(n0, pca_normals(edited, n0, k)), offsets)


def timings() -> None:
    print("\n3. reconstruct at 100k points x 4 levels, medians of 15 (ms)")
    dec = ps.decompose(ps.shapes.bumpy_sphere(100_000), levels=4)
    base = dec.base
    lifted = base.copy()
    lifted[:, 2] += 0.2 * np.exp(-((base[:, :2] - 0.3) ** 2).sum(axis=1) / 0.3)
    t0 = time.perf_counter()
    solver = ps.Reconstructor(dec)
    print(f"Reconstructor setup (its first edited call finds the edit support): {(time.perf_counter() - t0) * 1e3:.1f} ms")
    t0 = time.perf_counter()
    ps.reconstruct(dec, base=lifted)
    print(f"reconstruct's first edited call (finds the edit support, kept with the decomposition): "
          f"{(time.perf_counter() - t0) * 1e3:.1f} ms")

    def first_edited_call():  # what Blender's first Rebuild Detail pays
        fresh = ps.Reconstructor(dec)
        t = time.perf_counter()
        fresh.reconstruct(base=lifted)
        return time.perf_counter() - t
    first = statistics.median(first_edited_call() for _ in range(9))
    print(f"a fresh Reconstructor's first edited call (finds the edit support; median of 9): {first * 1e3:.1f} ms")
    for label, b in (("unedited", None), ("its own base back", base)):
        row = []
        for f in (lambda: ps.reconstruct(dec, base=b), lambda: solver.reconstruct(base=b)):
            f()
            times = []
            for _ in range(15):
                t0 = time.perf_counter()
                f()
                times.append(time.perf_counter() - t0)
            row.append(statistics.median(times) * 1e3)
        print(f"{label:40s} reconstruct {row[0]:6.1f}   Reconstructor {row[1]:6.1f}")
    # Edited calls, each on a base that differs from the one before: a Reconstructor redoes only
    # what changed since its last edited call, so a base handed twice would time nothing.
    lowered = base.copy()
    lowered[:, 2] -= 0.2 * np.exp(-((base[:, :2] + 0.3) ** 2).sum(axis=1) / 0.3)
    everywhere = [lifted, lowered] * 8
    normals, diag = dec.normals(0), diagonal(base)
    rng = np.random.default_rng(0)
    dabs, current = [], lifted
    for _ in range(16):  # brush dabs 5% of the diagonal wide that add up, on the lifted base
        centre = rng.integers(len(base))
        t = np.clip(1 - np.linalg.norm(current - current[centre], axis=1) / (0.05 * diag), 0, 1)
        current = current + (0.01 * diag) * (t * t * (3 - 2 * t))[:, None] * normals[centre]
        dabs.append(current)
    for label, bases in (("a base moved everywhere (two, in turn)", everywhere), ("brush dabs, one after another", dabs)):
        both = ([], [])
        solver.reconstruct(base=bases[-1])
        for b in bases:
            for times, f in zip(both, (lambda: ps.reconstruct(dec, base=b), lambda: solver.reconstruct(base=b))):
                t0 = time.perf_counter()
                f()
                times.append(time.perf_counter() - t0)
        print(f"{label:40s} reconstruct {statistics.median(both[0]) * 1e3:6.1f}   "
              f"Reconstructor {statistics.median(both[1]) * 1e3:6.1f}   (medians of {len(bases)})")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--no-scans", action="store_true")
    p.add_argument("--other-scans", action="store_true",
                   help="also the scans the issue does not name (OTHER_SCANS), brushes at other places;"
                        " not with --no-scans")
    args = p.parse_args()
    if args.no_scans and args.other_scans:
        p.error("--other-scans runs scans: leave out --no-scans")
    import warnings
    warnings.simplefilter("ignore", UserWarning)  # coarse-base warnings: the handles want a flat base
    handles()
    if not args.no_scans:
        scans()
        if args.other_scans:
            scans(OTHER_SCANS, seeds=(2, 5, 11))
    timings()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
