"""Connected parts (issue 17, requirements 1 and 2): with a mesh's faces or edges, decompose keeps
its parts apart, and a part too small for the levels asked keeps those it supports."""
import warnings

import numpy as np
import pytest

import pointscale as ps
from pointscale import meshes
from pointscale.parts import PART_COARSE_POINTS, connected_parts, levels_kept


def diagonal(points):
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def beside(big, small, gap, axis=0):
    """small moved to lie `gap` beyond big along axis; both (vertices, faces)."""
    (bv, bf), (sv, sf) = big, small
    shift = np.zeros(3)
    shift[axis] = bv[:, axis].max() + gap - sv[:, axis].min()
    return bv, bf, sv + shift, sf


# (name, big part, small part, gap): different shapes, sizes, proportions and gaps.
SCENES = {
    "sphere and cube": (lambda: (meshes.bumpy(*meshes.uv_sphere(1.0, 128, 64)[:1], 0.01, 12),
                                 meshes.uv_sphere(1.0, 128, 64)[1]),
                        lambda: meshes.box(0.3, 16), 0.05),
    "torus and flat box": (lambda: _torus(1.0, 0.35, 160, 60), lambda: meshes.box((0.5, 0.3, 0.12), 24), 0.02),
    "two spheres": (lambda: meshes.uv_sphere(0.8, 96, 48),
                    lambda: (meshes.bumpy(*meshes.uv_sphere(0.45, 64, 32)[:1], 0.01, 8),
                             meshes.uv_sphere(0.45, 64, 32)[1]), 0.03),
}


def _torus(major, minor, segments, rings):
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, segments, endpoint=False),
                       np.linspace(0, 2 * np.pi, rings, endpoint=False), indexing="ij")
    r = major + minor * np.cos(v) * (1 + 0.03 * np.sin(9 * u))
    vertices = np.stack([r * np.cos(u), r * np.sin(u), minor * np.sin(v)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(segments), np.arange(rings), indexing="ij")
    at = lambda a, b: (a % segments) * rings + (b % rings)  # noqa: E731
    faces = np.stack([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)], axis=-1).reshape(-1, 4)
    return vertices, meshes.quads_to_triangles(faces)


def scene(name):
    big, small, gap = SCENES[name]
    bv, bf, sv, sf = beside(big(), small(), gap)
    v, f, part = meshes.joined((bv, meshes.quads_to_triangles(bf)), (sv, meshes.quads_to_triangles(sf)))
    return v, f, part


def lift(base, where, radius, height):
    d2 = ((base - where) ** 2).sum(axis=1)
    out = base.copy()
    out[:, 2] += height * np.exp(-d2 / radius ** 2)
    return out


@pytest.fixture(scope="module", params=sorted(SCENES))
def decomposed(request):
    v, f, part = scene(request.param)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dec = ps.decompose(v, 4, faces=f)
    return request.param, v, f, part, dec


def test_connected_parts_from_faces_polygons_and_edges():
    points = np.random.default_rng(0).normal(size=(9, 3))
    labels, count = connected_parts(points, faces=np.array([[0, 1, 2], [2, 3, 0], [5, 6, 7]]))
    assert count == 2
    assert (labels[[0, 1, 2, 3]] == 0).all() and (labels[[5, 6, 7]] == 1).all()
    # Vertices 4 and 8 are in no face: each joins its nearest vertex's part.
    for loose in (4, 8):
        nearest = np.argsort(np.linalg.norm(points - points[loose], axis=1))
        nearest = [i for i in nearest if i not in (4, 8)][0]
        assert labels[loose] == labels[nearest]
    polygons = [np.array([0, 1, 2, 3]), np.array([5, 6, 7])]  # mixed sizes, as a PLY's list
    assert (connected_parts(points, faces=polygons)[0] == labels).all()
    edges = np.array([[0, 1], [1, 2], [2, 3], [5, 6], [6, 7], [7, 8], [4, 0]])
    labels, count = connected_parts(points, edges=edges)
    assert count == 2 and labels[4] == labels[0] and labels[8] == labels[5]
    assert connected_parts(points)[1] == 1


@pytest.mark.parametrize("kwargs, match", [
    (dict(faces=np.array([[0, 1, 9]])), r"vertex indices in \[0, 8\]"),
    (dict(faces=np.array([[0, -1, 2]])), r"vertex indices"),
    (dict(faces=np.array([[0.0, 1.0, 2.0]])), "integer"),
    (dict(faces=np.array([[0], [1]])), "k >= 2"),
    (dict(edges=np.array([[0, 1, 2]])), r"shape \(m, 2\)"),
    (dict(faces=[[0, 1], [[2, 3]]]), "flat sequence"),
])
def test_bad_connectivity_is_refused(kwargs, match):
    points = np.random.default_rng(1).normal(size=(9, 3))
    with pytest.raises(ValueError, match=match):
        connected_parts(points, **kwargs)


def test_one_part_gives_the_same_decomposition_as_no_connectivity():
    v, f = meshes.uv_sphere(1.0, 96, 48)
    v = meshes.bumpy(v, 0.02, 6)
    plain = ps.decompose(v, 3)
    joined = ps.decompose(v, 3, faces=f)
    assert joined.parts is None and joined.part_labels is None
    for l in range(3):
        assert np.array_equal(plain.level(l), joined.level(l))
    assert np.array_equal(plain.details, joined.details)


def test_editing_one_part_leaves_the_other_as_it_was(decomposed):
    name, v, f, part, dec = decomposed
    diag = diagonal(v)
    unedited = ps.reconstruct(dec)
    assert np.abs(unedited - v).max() < 1e-12 * diag  # still an exact round trip
    for moved in (0, 1):
        sel = part == moved
        base = dec.base
        centre = base[sel][np.argmax(base[sel][:, 0] if moved == 0 else -base[sel][:, 0])]  # the side facing the other
        edited = base.copy()
        edited[sel] = lift(base[sel], centre, 0.3 * diagonal(v[sel]), 0.1 * diagonal(v[sel]))
        out = ps.reconstruct(dec, None, edited)
        other = ~sel
        assert np.abs(out[other] - unedited[other]).max() < 1e-9 * diag, name
        assert np.abs(out[sel] - unedited[sel]).max() > 1e-3 * diag  # the edit did something
        assert np.abs(ps.Reconstructor(dec).reconstruct(None, edited) - out).max() == 0.0
        # A solver that met the unedited base first finds the rings, parts kept apart, then.
        solver = ps.Reconstructor(dec)
        assert np.array_equal(solver.reconstruct(), unedited)
        assert np.array_equal(solver.reconstruct(None, edited), out)


def test_without_connectivity_the_parts_blend(decomposed):
    """What connectivity prevents: decomposed as one surface, an edit of one part moves the other."""
    name, v, f, part, _ = decomposed
    dec = ps.decompose(v, 4)
    sel = part == 1
    base = dec.base
    edited = base.copy()
    edited[sel] = lift(base[sel], base[sel][np.argmin(base[sel][:, 0])], 0.3 * diagonal(v[sel]), 0.1 * diagonal(v[sel]))
    moved = np.abs(ps.reconstruct(dec, None, edited)[~sel] - ps.reconstruct(dec)[~sel]).max()
    assert moved > 1e-4 * diagonal(v)


def test_each_part_matches_the_part_decomposed_alone(decomposed):
    name, v, f, part, dec = decomposed
    diag = diagonal(v)
    for p, report in enumerate(dec.parts):
        sel = part == p
        assert report["points"] == sel.sum() and report["first_vertex"] == np.flatnonzero(sel)[0]
        kept = report["levels"]
        if kept < 2:
            for l in range(dec.n_levels):
                assert np.abs(dec.level(l)[sel] - v[sel]).max() < 1e-12 * diag
            continue
        alone = ps.decompose(v[sel], kept)
        shift = dec.n_levels - kept
        for l in range(dec.n_levels):
            assert np.abs(dec.level(l)[sel] - alone.level(max(l - shift, 0))).max() < 1e-12 * diag, (name, p, l)
        # Its coarser bands are zero: the levels there repeat its smoothest one.
        assert (dec.details[:shift][:, sel] == 0.0).all()


def test_parts_survive_save_and_load(decomposed, tmp_path):
    name, v, f, part, dec = decomposed
    dec.save(tmp_path / "parts.npz")
    back = ps.load(tmp_path / "parts.npz")
    assert back.parts == dec.parts
    assert np.array_equal(back.part_labels, part)
    sel = part == 1
    edited = dec.base.copy()
    edited[sel] += np.array([0.0, 0.0, 0.05])
    assert np.array_equal(ps.reconstruct(back, None, edited), ps.reconstruct(dec, None, edited))


def test_saved_parts_are_checked(decomposed):
    _, _, _, _, dec = decomposed
    arrays = dec.to_dict()
    arrays["parts"] = arrays["parts"][:-1]
    with pytest.raises(ValueError, match="parts must have shape"):
        ps.Decomposition.from_dict(arrays)
    arrays["parts"] = np.full(dec.n_points, -1)
    with pytest.raises(ValueError, match="parts"):
        ps.Decomposition.from_dict(arrays)


# Small parts beside a large one: (size, segments) of a box, levels, decimation.
SMALL = [((0.3, 0.3, 0.3), 16, 4, 0.25), ((0.5, 0.5, 0.5), 24, 5, 0.3), ((0.25, 0.25, 0.25), 30, 4, 0.25),
         ((0.2, 0.4, 0.1), 20, 5, 0.3), ((0.4, 0.4, 0.4), 40, 3, 0.1), ((0.6, 0.2, 0.2), 36, 4, 0.2)]


@pytest.fixture(scope="module")
def big_sphere():
    v, f = meshes.uv_sphere(1.0, 160, 80)
    return meshes.bumpy(v, 0.01, 12), f


@pytest.mark.parametrize("size, segments, levels, decimation", SMALL)
def test_a_small_part_keeps_its_shape_and_is_named(big_sphere, size, segments, levels, decimation):
    bv, bf, sv, sf = beside(big_sphere, meshes.box(size, segments), 0.05)
    v, f, part = meshes.joined((bv, bf), (sv, meshes.quads_to_triangles(sf)))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dec = ps.decompose(v, levels, decimation=decimation, faces=f)
    small = dec.parts[1]
    assert dec.parts[0]["levels"] == levels  # the large part keeps every level
    assert small["levels"] < levels
    dev = np.linalg.norm(dec.level(0)[part == 1] - sv, axis=1)
    assert dev.max() < 0.10 * diagonal(sv)
    messages = [str(w.message) for w in caught]
    named = [m for m in messages if f"part 1 ({len(sv)} points from vertex {len(bv)}" in m]
    assert len(named) == 1, messages
    assert "too small" in named[0]


def test_a_small_part_is_too_coarse_without_connectivity(big_sphere):
    """What the part rule prevents: the same box, in the large part's levels, strays far."""
    bv, bf, sv, sf = beside(big_sphere, meshes.box(0.3, 16), 0.05)
    v = np.vstack([bv, sv])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dec = ps.decompose(v, 4)
    assert np.linalg.norm(dec.level(0)[len(bv):] - sv, axis=1).max() > 0.15 * diagonal(sv)


def test_levels_kept_follows_the_support_count():
    sizes = np.array([40000, 1538, 5402, 500, 3])
    kept = levels_kept(sizes, 4, 0.25, 24, 8)
    assert kept[0] == 4
    for size, k in zip(sizes[1:], kept[1:]):
        if k > 1:
            assert np.floor(size * 0.25 ** (k - 1)) >= PART_COARSE_POINTS
        if k < 4:
            assert np.floor(size * 0.25 ** k) < PART_COARSE_POINTS
    assert kept[-1] == 1


def test_flat_and_tiny_parts_keep_no_bands(big_sphere):
    bv, bf = big_sphere
    card_v, card_f = meshes.grid(0.6, 0.5, 60, 50)  # exactly flat: no detail to separate
    card_v = card_v + np.array([0.0, 0.0, 1.1])
    tri = np.array([[0.0, 0.0, -1.2], [0.05, 0.0, -1.2], [0.0, 0.05, -1.2]])  # a loose triangle
    v, f, part = meshes.joined((bv, bf), (card_v, meshes.quads_to_triangles(card_f)), (tri, np.array([[0, 1, 2]])))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dec = ps.decompose(v, 4, faces=f)
    assert [p["levels"] for p in dec.parts] == [4, 1, 1]
    assert "spans no surface" in dec.parts[1]["why"]
    message = " ".join(str(w.message) for w in caught)
    assert "part 1" in message and "part 2" in message
    for p in (1, 2):
        sel = part == p
        for l in range(dec.n_levels):
            assert np.abs(dec.level(l)[sel] - v[sel]).max() < 1e-12 * diagonal(v)
        assert np.isfinite(dec.normals(0)[sel]).all()
    # Gains and edits leave such parts where they are, and never give NaN.
    out = ps.reconstruct(dec, [2.0, 0.5, 3.0])
    assert np.abs(out[part > 0] - v[part > 0]).max() < 1e-12 * diagonal(v)


def test_only_tiny_parts_is_a_clear_error():
    tris = np.random.default_rng(2).normal(size=(300, 3))
    faces = np.arange(300).reshape(-1, 3)
    with pytest.raises(ValueError, match="every connected part is too small"):
        ps.decompose(tris, 4, faces=faces)


def test_progress_and_cancel_over_parts():
    v, f, part = scene("sphere and cube")
    seen = []

    def progress(fraction):
        seen.append(fraction)
        return True

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ps.decompose(v, 4, faces=f, progress=progress)
    assert seen and seen[-1] == pytest.approx(1.0) and min(seen) >= 0.0
    assert all(b >= a - 1e-12 for a, b in zip(seen, seen[1:]))
    with pytest.raises(ps.Cancelled):
        ps.decompose(v, 4, faces=f, progress=lambda fraction: fraction < 0.5)


def test_parts_that_are_all_flat_are_a_clear_error():
    a_v, a_f = meshes.grid(1.0, 1.0, 60, 60)
    b_v, b_f = meshes.grid(0.5, 0.5, 50, 50)
    b_v = b_v + np.array([0.0, 0.0, 0.3])
    v, f, _ = meshes.joined((a_v, meshes.quads_to_triangles(a_f)), (b_v, meshes.quads_to_triangles(b_f)))
    with pytest.raises(ValueError, match="spans a surface"):
        ps.decompose(v, 3, faces=f)
