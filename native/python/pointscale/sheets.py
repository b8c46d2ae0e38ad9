"""Thin sheets: which way each point faces, so that decompose keeps the two sides of a wall apart.

decompose(..., sheets=True) tells the sides of a wall thinner than its kernel (a leaf, sheet
metal, a wall scanned from both sides) by the points' outward normals: every fit, cluster and
level normal takes only points whose normals make an acute angle with the point's own
(native/include/pointscale/thin_sheets.h).
"""

from __future__ import annotations

import numpy as np

from .surface import estimate_normals


def sheet_sides(points: np.ndarray, normals, threads: int = 0) -> np.ndarray:
    """The (n, 3) outward normals that tell the sides apart: the given ones, else estimated and oriented.

    Raises ValueError for a zero normal, which faces neither side.
    """
    if normals is None:
        return estimate_normals(points, orient=True, threads=threads)
    lengths = np.sqrt(np.einsum("ij,ij->i", normals, normals))
    zero = np.flatnonzero(~(lengths > 0.0))
    if zero.size:
        raise ValueError(f"sheets=True tells the sides of a wall by the normals, and {zero.size} of them are zero "
                         f"(the first at point {zero[0]}); give outward normals, or none to estimate them")
    return normals
