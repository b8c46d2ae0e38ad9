"""Checked diffusion settings, shared by smooth_diffusion and the "diffusion" smoother of
decompose and decompose_rayshoot (a module of its own so that neither imports the other)."""
from __future__ import annotations

import numpy as np

from . import _core
from ._checks import MAX_DIFFUSION_ITERATIONS, MAX_NEIGHBORS, positive, require_stable_diffusion


def diffusion_settings(lam, mu, taubin, neighbors):
    """Checks the diffusion parameters; returns (neighbors, lam, mu)."""
    lam = positive(lam, "lam")
    if not 1e-3 <= lam <= 1.0:
        raise ValueError(f"lam must be in [0.001, 1] for a stable explicit step, got {lam}")
    neighbors = positive(neighbors, "neighbors", integer=True, minimum=3, maximum=MAX_NEIGHBORS)
    if mu is None:
        mu = _core.taubin_mu(lam=lam, pass_band=0.1) if taubin else 0.0
    else:
        try:
            if isinstance(mu, (bool, np.bool_)):
                raise TypeError
            mu = float(mu)
        except (TypeError, ValueError):
            raise ValueError(f"mu must be a number below -lam, got {mu!r}") from None
        if not np.isfinite(mu) or mu >= -lam or mu < -1e3:
            raise ValueError(f"mu must be below -lam = {-lam} (Taubin's inflating step) and at least -1000, got {mu}")
    return neighbors, lam, mu


def smoother_options(iterations, lam, taubin, neighbors) -> _core.DiffusionOptions:
    """The core's settings for the "diffusion" smoother of a decomposition."""
    k, lam, mu = diffusion_settings(lam, None, taubin, neighbors)
    iterations = positive(iterations, "diffusion_iterations", integer=True, maximum=MAX_DIFFUSION_ITERATIONS)
    require_stable_diffusion(lam, mu, iterations, "diffusion_iterations")
    return _core.DiffusionOptions(neighbors=k, lam=lam, mu=mu, iterations=iterations)


def settings_record(options: _core.DiffusionOptions) -> dict:
    """The smoother's settings as a decomposition's settings keep them."""
    return dict(neighbors=options.neighbors, lam=options.lam, mu=options.mu, iterations=options.iterations)
