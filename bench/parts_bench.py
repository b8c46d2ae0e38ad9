"""Connected parts (issue 17): what decompose's faces cost, against the same points without them.

    python bench/parts_bench.py [--data ../shared/data] [--repeat 3]

Inputs: the dragon scan in file order (one part: its faces alone give 151 pieces, the body and
150 fragments of at most 78 points, which share vertex positions with the body), and a 33k-vertex
bumpy UV sphere with 2,000 hair cards of 52 vertices (generator order). Times are medians of
--repeat runs in this process, levels=4 and the defaults.
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

import pointscale as ps
from median_time import median_time
from pointscale import meshes


def hair_cards(count: int = 2000, seed: int = 0):
    head_v, head_f = meshes.uv_sphere(1.0, 256, 128)
    parts = [(meshes.bumpy(head_v, 0.01, 12), head_f)]
    card_v, card_f = meshes.grid(0.05, 0.2, 3, 12)
    card_f = meshes.quads_to_triangles(card_f)
    rng = np.random.default_rng(seed)
    for _ in range(count):
        d = rng.normal(size=3)
        parts.append((card_v + 1.1 * d / np.linalg.norm(d) + 0.01 * rng.normal(size=3), card_f))
    return meshes.joined(*parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(Path(__file__).resolve().parents[1] / ".." / "shared" / "data"))
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    cases = []
    dragon = Path(args.data) / "dragon.ply"
    if dragon.exists():
        scan = ps.io.read(dragon)
        cases.append(("dragon, file order", scan.points, scan.faces))
    else:
        print(f"(no {dragon}: the dragon row is left out)")
    v, f, _ = hair_cards()
    cases.append(("head + 2,000 hair cards, generator order", v, f))
    print(f"{'input':<42} {'points':>8} {'parts':>6} {'no faces s':>11} {'faces s':>8} {'largest alone s':>16}")
    warnings.simplefilter("ignore")
    for name, points, faces in cases:
        points = np.asarray(points, dtype=np.float64)
        plain = median_time(lambda: ps.decompose(points, 4), args.repeat)
        joined = median_time(lambda: ps.decompose(points, 4, faces=faces), args.repeat)
        labels, parts = ps.parts.connected_parts(points, faces=faces)
        largest = points[labels == np.argmax(np.bincount(labels))]
        alone = median_time(lambda: ps.decompose(largest, 4), args.repeat)
        print(f"{name:<42} {len(points):>8} {parts:>6} {plain:>11.2f} {joined:>8.2f} {alone:>16.2f}")
    print("no faces: the points as one surface; faces: each connected part alone, joined; largest alone: "
          "the largest part's points by themselves, what the join and the small parts add to")


if __name__ == "__main__":
    main()
