"""An edited half of a mirrored model that reaches across its mirror plane. The result is held at
the plane there (Symmetry.symmetric), as Blender's Mirror modifier with Clipping holds vertices.
Before, that happened without a word: a half flipped across its plane came back flattened onto
it (a reviewer's bumpy half sphere: every one of 4097 points within 3e-6 of the plane)."""

import warnings

import numpy as np
import pytest

import pointscale as ps
from pointscale import meshes


@pytest.fixture(scope="module")
def half_ellipsoid():
    """A bumpy ellipsoid's half on the side y >= 0.3 of the plane y = 0.3."""
    v, _ = meshes.uv_sphere(1.0, 96, 48)
    v = meshes.bumpy(v, 0.04, 5) * [1.4, 0.8, 1.0] + [0.0, 0.3, 0.0]
    half = v[v[:, 1] >= 0.3 - 1e-12]
    mirror = ps.Mirror("y", origin=(0.0, 0.3, 0.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ps.decompose(half, 4, mirror=mirror, threads=2)


def rebuilt(dec, base):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = ps.reconstruct(dec, base=base)
    return out, [str(w.message) for w in caught]


def test_a_half_flipped_across_its_plane_is_refused(half_ellipsoid):
    dec = half_ellipsoid
    flipped = dec.base.copy()
    flipped[:, 1] = 0.6 - flipped[:, 1]  # across y = 0.3
    with pytest.raises(ValueError, match="lie across it"):
        ps.reconstruct(dec, base=flipped)
    with pytest.raises(ValueError, match="lie across it"):
        ps.Reconstructor(dec).reconstruct(base=flipped)


def test_points_pushed_across_the_plane_are_counted_in_a_warning(half_ellipsoid):
    dec = half_ellipsoid
    pushed = dec.base.copy()
    pushed[:, 1] -= 0.05
    across = int(((pushed[:, 1] < 0.3 - dec.mirror.seam) & (np.abs(dec.base[:, 1] - 0.3) > dec.mirror.seam)).sum())
    out, said = rebuilt(dec, pushed)
    assert across > 50
    assert any(s.startswith(f"reconstruct: {across} points of the edited base lie across the y mirror plane")
               for s in said), said
    assert np.all(out[:, 1] >= 0.3)  # held at the plane, on the half's side


def test_an_edit_that_keeps_the_half_on_its_side_says_nothing(half_ellipsoid):
    dec = half_ellipsoid
    lifted = dec.base.copy()
    lifted[:, 2] += 0.1 * np.exp(-np.sum((lifted - [0.0, 1.0, 0.0]) ** 2, axis=1) / 0.1)
    _, said = rebuilt(dec, lifted)
    assert not any("mirror plane" in s for s in said), said


@pytest.mark.parametrize("caller", ["find_folds", "Reconstructor.reconstruct", "reconstruct_levels"])
def test_the_warning_names_the_function_called(half_ellipsoid, caller):
    """Each function that takes an edited base says its own name (find_folds said
    "reconstruct:", which the caller never called)."""
    dec = half_ellipsoid
    pushed = dec.base.copy()
    pushed[:, 1] -= 0.05
    call = {"find_folds": lambda: ps.find_folds(dec, ps.reconstruct(dec), base=pushed),
            "Reconstructor.reconstruct": lambda: ps.Reconstructor(dec).reconstruct(base=pushed),
            "reconstruct_levels": lambda: ps.reconstruct_levels(dec, base=pushed)}[caller]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    said = [str(w.message) for w in caught if "mirror plane" in str(w.message)]
    assert said and all(s.startswith(f"{caller}: ") for s in said), said
