"""A sixth engine pass (review, 2026-12-08): sheets=True takes the sides from a mesh's faces when
it has no normals (an STL), on the command line too; morph warns when evaluate(0, 1) cannot
reach B; ray shooting warns of a coarse base and of rays that missed.

The shapes are made here: a bent sheet solidified into a two-sided shell one spacing thick
(both sides and the rim joined by consistently wound faces), a box morphed from an ellipsoid.
"""
import warnings

import numpy as np
import pytest

import pointscale as ps
from pointscale import meshes
from pointscale.cli import main as cli_main
from pointscale.sheets import estimated_sides_warning, winding_normals

SPACING = 0.02


def _boundary_edges(faces):
    """The (e, 2) edges of quads that only one face runs through, in that face's direction."""
    directed = np.concatenate([faces[:, [c, (c + 1) % faces.shape[1]]] for c in range(faces.shape[1])])
    _, inverse, counts = np.unique(np.sort(directed, axis=1), axis=0, return_inverse=True, return_counts=True)
    return directed[counts[inverse.ravel()] == 1]


def bent_shell(gap_in_spacings=1.0):
    """A bent sheet 1.2 x 0.8 made two-sided, its sides `gap` apart along the sheet's normal and
    joined at the rim, every face wound outward: (vertices, triangles, sheet vertex count, sheet
    vertices (m, 3), gap). Vertex i of the outer side faces vertex i + m of the inner one."""
    v, f = meshes.grid(1.2, 0.8, 60, 40)
    v[:, 2] = 0.15 * np.sin(2 * v[:, 0])
    gap = gap_in_spacings * SPACING
    normal = meshes.vertex_normals(v, f)
    m = len(v)
    rim = _boundary_edges(f)
    rim_quads = np.stack([rim[:, 1], rim[:, 0], rim[:, 0] + m, rim[:, 1] + m], axis=1)
    faces = np.concatenate([f, f[:, ::-1] + m, rim_quads])
    return np.concatenate([v + 0.5 * gap * normal, v - 0.5 * gap * normal]), meshes.quads_to_triangles(faces), m, v, gap


def thickness_per_level(dec, m, sheet, gap, levels):
    """Per level but the finest, the least and largest distance between a sheet vertex's two
    sides, over the vertices 0.15 from the rim (three level-0 kernels), as a share of the gap."""
    inside = (np.abs(sheet[:, 0]) < 0.45) & (np.abs(sheet[:, 1]) < 0.25)
    out = []
    for l in range(levels - 1):
        level = dec.level(l)
        d = np.linalg.norm(level[:m][inside] - level[m:][inside], axis=1) / gap
        out.append((d.min(), d.max()))
    return np.array(out)


def _caught(call):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    return result, [str(w.message) for w in caught]


# -- 1. sheets=True on a mesh without normals: the faces' winding tells the sides -------------------

def test_sheets_take_the_sides_from_the_faces_winding_without_normals():
    """Before, the normals were estimated from the points, which oriented both sides of a wall
    one spacing thick alike: the thickness fell to 0.00-0.03 of the gap at levels 0-2. The
    faces' winding gives both sides outward normals, the mesh's vertex normals: measured
    0.986-1.002 of the gap, the same decomposition as with those normals given."""
    points, faces, m, sheet, gap = bent_shell()
    dec, said = _caught(lambda: ps.decompose(points, 3, faces=faces, sheets=True, threads=2))
    thickness = thickness_per_level(dec, m, sheet, gap, 3)
    assert thickness.min() > 0.95 and thickness.max() < 1.05, thickness
    assert not any("sides apart" in s or "estimated" in s for s in said), said
    given = ps.decompose(points, 3, normals=meshes.vertex_normals(points, faces), sheets=True, threads=2)
    assert np.array_equal(dec.base, given.base)
    assert np.abs(ps.reconstruct(dec) - points).max() < 1e-9


def test_winding_normals_are_the_meshes_vertex_normals():
    v, f = meshes.box((1.0, 0.7, 0.5), segments=8)
    normals, why_not = winding_normals(v, f)
    assert why_not is None
    assert np.abs(normals - meshes.vertex_normals(v, f)).max() < 1e-12
    # a list of polygons of mixed sizes gives the same (quads split into triangles or not)
    tri = meshes.quads_to_triangles(f)
    mixed = [list(q) for q in f[: len(f) // 2]] + [list(t) for t in tri[len(f) // 2: len(f)]] + \
            [list(t) for t in tri[len(f) + len(f) // 2:]]
    normals_mixed, _ = winding_normals(v, mixed)
    assert np.einsum("ij,ij->i", normals_mixed, normals).min() > 0.9


def test_inconsistent_winding_falls_back_to_estimated_normals_and_says_so():
    """A shell with some faces flipped: the winding no longer tells the sides, so the normals are
    estimated as without faces, and a warning names the first edge wound alike on both sides."""
    points, faces, m, sheet, gap = bent_shell()
    flipped = faces.copy()
    flipped[::50] = flipped[::50, ::-1]
    dec, said = _caught(lambda: ps.decompose(points, 3, faces=flipped, sheets=True, threads=2))
    assert any("wind" in s and "same way" in s and "estimated from the points instead" in s for s in said), said
    alone, _ = _caught(lambda: ps.decompose(points, 3, sheets=True, threads=2))
    assert np.array_equal(dec.base, alone.base)  # exactly today's estimate


def test_a_vertex_in_no_face_falls_back_to_estimated_normals_and_says_so():
    points, faces, m, sheet, gap = bent_shell()
    points = np.vstack([points, points[:1] + [0.0, 0.0, 0.3 * SPACING]])  # a loose vertex, in no face
    _, said = _caught(lambda: ps.decompose(points, 3, faces=faces, sheets=True, threads=2))
    assert any(f"the first is vertex {len(points) - 1}" in s and "estimated" in s for s in said), said


def _level_thickness_from_files(folder, points, m, sheet, gap):
    """thickness_per_level of the decomposition the command line wrote, whatever order the file
    reader gave its vertices (an STL's are welded from its triangles)."""
    dec = ps.load(folder / "decomposition.npz")
    source = dec.level(dec.n_levels - 1)
    order = {tuple(np.round(p, 9)): i for i, p in enumerate(source)}
    index = np.array([order[tuple(np.round(p, 9))] for p in points])

    class InInputOrder:
        def level(self, l):
            return dec.level(l)[index]
    return thickness_per_level(InInputOrder(), m, sheet, gap, dec.n_levels)


@pytest.mark.parametrize("extension, parts", [(".stl", "faces"), (".ply", "faces"), (".ply", "none")])
def test_the_command_line_takes_the_sides_from_a_files_faces(tmp_path, capsys, extension, parts):
    """pointscale decompose --sheets on a mesh file with faces and no normals: before, 0.00-0.04
    of the gap at levels 0-1 (the points' estimate); now 0.986-1.002 of it, as in Python."""
    points, faces, m, sheet, gap = bent_shell()
    path = tmp_path / f"shell{extension}"
    ps.io.write(path, ps.io.Scan(points=points.astype(np.float32).astype(np.float64), faces=faces))
    out = tmp_path / "out"
    code = cli_main(["decompose", str(path), "-o", str(out), "--levels", "3", "--threads", "2", "--sheets",
                     "--parts", parts, "--format", ".ply"])
    assert code == 0, capsys.readouterr().err
    thickness = _level_thickness_from_files(out, points.astype(np.float32).astype(np.float64), m, sheet, gap)
    assert thickness.min() > 0.95 and thickness.max() < 1.05, thickness


def test_the_command_lines_sides_warning_no_longer_asks_an_stl_for_normals():
    """The estimate's warning asked the file for normals (nx, ny, nz), which an STL cannot hold;
    it now names consistently wound faces as well."""
    from pointscale.cli import _in_cli_words
    points, _, _, _, _ = bent_shell()
    message = estimated_sides_warning(points, threads=2)
    assert message is not None  # the estimate orients both sides of this shell alike
    said = _in_cli_words(message)
    assert "consistently wound faces (an STL" in said and "normals=" not in said, said


# -- 2. morph says when evaluate(0, 1) cannot reach B ------------------------------------------------

def _box(n, half=(1.0, 0.8, 0.6), seed=3):
    """n points on the surface of a box (sharp edges), spread by area."""
    g = np.random.default_rng(seed)
    half = np.asarray(half)
    areas = np.array([half[1] * half[2], half[0] * half[2], half[0] * half[1]])
    axis = g.choice(3, size=n, p=areas / areas.sum())
    p = g.uniform(-1.0, 1.0, (n, 3)) * half
    p[np.arange(n), axis] = np.where(g.random(n) < 0.5, -1.0, 1.0) * half[axis]
    return p


def _ellipsoid(n, axes, seed=0):
    u = np.random.default_rng(seed).normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True) * np.asarray(axes)


def _box_distance(x, half=(1.0, 0.8, 0.6)):
    q = np.abs(x) - np.asarray(half)
    return np.abs(np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0))


def test_morph_warns_when_evaluate_0_1_misses_b():
    """A box morphed from an ellipsoid over their ellipsoid base: evaluate(0, 1) missed the box by
    3.4% of its diagonal without a word, while encode of the box onto that base warned. Now the
    morph warns too, naming B, from its own result."""
    a, b = _ellipsoid(8000, (1.5, 1.0, 0.7)), _box(8000)
    base = ps.ellipsoid_base(a, b, n=8000)
    m, said = _caught(lambda: ps.morph(a, b, base, threads=2))
    diagonal = np.linalg.norm(b.max(axis=0) - b.min(axis=0))
    assert _box_distance(m.evaluate(0, 1)).max() > 0.02 * diagonal  # the miss is there
    assert any(s.startswith("morph: evaluate(0, 1) misses B (points_b)") for s in said), said
    # An ellipsoid B fits its ellipsoid base (encoding it there is exact): nothing is said of B.
    a, b = _ellipsoid(6000, (1.2, 1.0, 0.8)), _ellipsoid(6000, (1.0, 1.1, 0.9), seed=2)
    _, said = _caught(lambda: ps.morph(a, b, ps.ellipsoid_base(a, b, n=6000), threads=2))
    assert not any("misses B" in s for s in said), said


# -- 3. ray shooting warns as the projection encoding does -------------------------------------------

@pytest.mark.parametrize("call", [
    lambda p: ps.decompose(p, 4, encoding="rayshoot", threads=2),
    lambda p: ps.decompose_rayshoot(p, 4, threads=2),
])
def test_rayshoot_gives_the_coarse_base_warning(call):
    points = ps.shapes.bumpy_sphere(4000)
    _, said = _caught(lambda: call(points))
    assert ps.coarse_base_warning(4000, 4, 0.25) in said, said


def test_rayshoot_warns_with_the_count_of_rays_that_missed():
    points = ps.shapes.bumpy_sphere(200)
    dec, said = _caught(lambda: ps.decompose(points, 3, encoding="rayshoot", threads=2))
    missed = sum(dec.settings["rays_missed"])
    assert missed > 0  # this coarse a sphere leaves some rays without a surface
    assert any(s.startswith(f"ray shooting: {missed} rays found no surface") for s in said), said
    # Where every ray arrives, nothing is said of them.
    dec, said = _caught(lambda: ps.decompose_rayshoot(ps.shapes.bumpy_sphere(12000), 3, threads=2))
    assert sum(dec.settings["rays_missed"]) == 0
    assert not any("rays found no surface" in s for s in said), said


def test_a_closed_mesh_wound_inside_out_is_taken_turned_outward():
    """Consistent winding says which way faces look, not that they look out: a closed mesh wound
    inside out passed the winding check, and sheets=True then turned every level's normals in
    (a reviewer's bumpy icosphere: 100% facing in, its bump read as a dent, no word). A closed
    part enclosing a negative volume is now turned outward, with a warning; an open sheet keeps
    the winding it was given."""
    v, f = ps.meshes.uv_sphere(1.0, 64, 32)
    v = ps.meshes.bumpy(v, 0.04, 4.0)
    outward = v / np.linalg.norm(v, axis=1, keepdims=True)
    reversed_faces = np.asarray(f)[:, ::-1]
    normals, why_not = winding_normals(v, reversed_faces)
    assert why_not is None
    assert np.mean(np.einsum("ij,ij->i", normals, outward) > 0) > 0.99
    dec, said = _caught(lambda: ps.decompose(v, 3, faces=reversed_faces, sheets=True, threads=2))
    assert any("wound inside out" in s for s in said), said
    assert np.mean(np.einsum("ij,ij->i", dec.normals(1), outward) < 0) < 0.01
    # An open cap of the same sphere, wound inside out: kept as given (which side is out is the mesh's call).
    cap = v[:, 2] > 0.3
    keep = cap[np.asarray(f)].all(axis=1)
    renumber = np.cumsum(cap) - 1
    cap_faces = renumber[np.asarray(f)[keep]][:, ::-1]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cap_normals, _ = winding_normals(v[cap], cap_faces)
    assert not any("inside out" in str(w.message) for w in caught)
    assert np.mean(np.einsum("ij,ij->i", cap_normals, outward[cap]) < 0) > 0.99
