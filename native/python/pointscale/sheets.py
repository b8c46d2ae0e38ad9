"""Thin sheets: which way each point faces, so that decompose keeps the two sides of a wall apart.

decompose(..., sheets=True) tells the sides of a wall thinner than its kernel (a leaf, sheet
metal, a wall scanned from both sides) by the points' outward normals: every fit, cluster and
level normal takes only points whose normals make an acute angle with the point's own
(native/include/pointscale/thin_sheets.h).
"""

from __future__ import annotations

import numpy as np


def check_sheet_normals(normals: np.ndarray) -> None:
    """Given outward normals tell the sides apart; a zero normal faces neither, so it is refused
    (ValueError). Without normals, the core estimates and orients them itself (16 neighbours, as
    estimate_normals), so that a decomposition does not hold them twice."""
    lengths = np.sqrt(np.einsum("ij,ij->i", normals, normals))
    zero = np.flatnonzero(~(lengths > 0.0))
    if zero.size:
        raise ValueError(f"sheets=True tells the sides of a wall by the normals, and {zero.size} of them are zero "
                         f"(the first at point {zero[0]}); give outward normals, or none to estimate them")
