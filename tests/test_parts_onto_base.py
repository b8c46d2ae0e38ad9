"""Connected parts for encode and morph (issue 17, req. 1): each part goes onto the base alone."""
import warnings

import numpy as np
import pytest

import pointscale as ps
from pointscale import meshes


def head_and_eye(bump=0.03, eye_shift=(0.0, 0.0, 0.0), eye_segments=(40, 20)):
    """A bumpy sphere with a small separate sphere 0.04 off its surface: (points, faces, part)."""
    hv, hf = meshes.uv_sphere(1.0, 96, 48)
    hv = meshes.bumpy(hv, bump, 6)
    ev, ef = meshes.uv_sphere(0.2, *eye_segments)
    ev = meshes.bumpy(ev, 0.01, 9) + np.array([0.55, 0.0, 0.9 + 0.04 + 0.2]) + np.asarray(eye_shift)
    return meshes.joined((hv, hf), (ev, ef))


def test_encode_keeps_parts_apart_and_each_part_is_encoded_alone():
    points, faces, part = head_and_eye()
    base = ps.ellipsoid_base(points, n=12000)
    dec = ps.encode(points, base, faces=faces)
    scale = np.ptp(points, axis=0).max()
    assert len(dec.parts) == 2 and np.array_equal(dec.part_labels, part)
    # exact up to what encode reports it could not make consistent (here the crowded poles of
    # the UV sphere, 3.4e-8, the same as the head encoded alone)
    residual = dec.stats[0]["consistency_residual"]
    assert np.abs(ps.reconstruct(dec) - points).max() <= residual + 1e-12 * scale
    for p in (0, 1):
        alone = ps.encode(points[part == p], base)
        for gains in ([0.0], [2.0]):
            assert np.abs(ps.reconstruct(dec, gains)[part == p] - ps.reconstruct(alone, gains)).max() < 1e-12 * scale
    # lift the eye's base only: the head does not move
    lifted = dec.base.copy()
    lifted[part == 1, 2] += 0.05
    moved = ps.reconstruct(dec, base=lifted)
    assert np.abs(moved[part == 0] - ps.reconstruct(dec)[part == 0]).max() < 1e-9 * scale
    assert np.abs(moved[part == 1, 2] - points[part == 1, 2] - 0.05).max() < 0.01
    # one surface: the eye's projections share clusters and normals with the head's
    one = ps.encode(points, base)
    lifted = one.base.copy()
    lifted[part == 1, 2] += 0.05
    assert np.abs(ps.reconstruct(one, base=lifted)[part == 0] - ps.reconstruct(one)[part == 0]).max() > 1e-6 * scale


def test_encode_names_a_part_too_small_for_a_band():
    points, faces, part = head_and_eye(eye_segments=(16, 8))
    assert (part == 1).sum() < 320
    base = ps.ellipsoid_base(points, n=12000)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dec = ps.encode(points, base, faces=faces)
    assert any("part 1 (" in str(w.message) for w in caught), [str(w.message) for w in caught]
    # it keeps no band: every gain leaves it where it is
    assert np.abs(ps.reconstruct(dec, [0.0])[part == 1] - points[part == 1]).max() < 1e-12


def test_morph_matches_part_with_part():
    a, fa, part_a = head_and_eye(bump=0.03)
    b, fb, part_b = head_and_eye(bump=0.06, eye_shift=(0.0, 0.05, 0.0))
    base = ps.ellipsoid_base(a, b, n=12000)
    m = ps.morph(a, b, base, faces_a=fa, faces_b=fb)
    for p in (0, 1):
        alone = ps.morph(a[part_a == p], b[part_b == p], base)
        assert np.array_equal(m.detail_b[part_a == p], alone.detail_b)
        assert np.array_equal(m.evaluate(0.0, 1.0)[part_a == p], alone.evaluate(0.0, 1.0))
    # as one surface, the head's offsets near the eye are carried onto the eye and the other way round
    one = ps.morph(a, b, base)
    assert np.abs(one.detail_b[part_a == 1] - m.detail_b[part_a == 1]).max() > 0.01


def test_morph_needs_connectivity_for_both_and_matching_parts():
    a, fa, _ = head_and_eye()
    b, fb, _ = head_and_eye(bump=0.05)
    base = ps.ellipsoid_base(a, b, n=8000)
    with pytest.raises(ValueError, match="both models"):
        ps.morph(a, b, base, faces_a=fa)
    sv, sf = meshes.uv_sphere(1.0, 64, 32)
    with pytest.raises(ValueError, match="2 connected parts and B has 1"):
        ps.morph(a, sv, base, faces_a=fa, faces_b=sf)


def test_morph_warns_when_paired_parts_differ_in_size():
    """B lists its eye first: part 0 of A (the head, 0.94 of A's size) is paired with B's eye
    (0.19 of B's size), ratio 4.9, and morphed into it; that used to be silent. In A's order the
    pairs' sizes agree within 1.01 and nothing is said."""
    from pointscale.parts_onto_base import PAIRED_SIZE_RATIO
    a, fa, part_a = head_and_eye(bump=0.03)
    hv, hf = meshes.uv_sphere(1.0, 64, 32)
    ev, ef = meshes.uv_sphere(0.2, 40, 20)
    ev = ev + np.array([0.55, 0.0, 1.14])
    base = ps.ellipsoid_base(a, n=6000)
    for eye_first in (False, True):
        b, fb, _ = meshes.joined((ev, ef), (hv, hf)) if eye_first else meshes.joined((hv, hf), (ev, ef))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ps.morph(a, b, base, faces_a=fa, faces_b=fb)
        said = [str(w.message) for w in caught if "differ in size" in str(w.message)]
        if not eye_first:
            assert not said
            continue
        assert len(said) == 1 and caught[0].filename == __file__
        assert f"more than {PAIRED_SIZE_RATIO:g} times" in said[0]
        assert "A's part 0 (4514 points from vertex 0, 0.94 of A's size) with B's part 0 (762 points" in said[0]
        assert "0.19 of B's size" in said[0]
        assert "A's 0 with B's 1, A's 1 with B's 0" in said[0]
