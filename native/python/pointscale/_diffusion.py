"""Diffusion settings as the core takes them, shared by smooth_diffusion and the "diffusion"
smoother of decompose and decompose_rayshoot (a module of its own so that neither imports the
other). The core checks them (validate(DiffusionOptions), validation.h)."""
from __future__ import annotations

import numpy as np

from . import _core
from ._checks import number


def diffusion_options(iterations, lam, mu, taubin, neighbors, *, prefix: str = "") -> _core.DiffusionOptions:
    """The core's settings, the numbers converted (prefix names neighbors and iterations in
    messages). mu None takes Taubin's default pair for lam when taubin, else plain smoothing (0)."""
    lam = number(lam, "lam")
    neighbors = number(neighbors, prefix + "neighbors", integer=True)
    iterations = number(iterations, prefix + "iterations", integer=True)
    if mu is None:
        if not isinstance(taubin, (bool, np.bool_)):  # "no" or 0.5 would read as true
            raise ValueError(f"{prefix}taubin must be True or False, got {taubin!r}".replace("diffusion_taubin", "taubin"))
        mu = _core.taubin_mu(lam=lam, pass_band=0.1) if taubin else 0.0
    else:
        mu = number(mu, "mu")
    return _core.DiffusionOptions(neighbors=neighbors, lam=lam, mu=mu, iterations=iterations)


def smoother_options(iterations, lam, taubin, neighbors) -> _core.DiffusionOptions:
    """The core's settings for the "diffusion" smoother of a decomposition."""
    return diffusion_options(iterations, lam, None, taubin, neighbors, prefix="diffusion_")


def settings_record(options: _core.DiffusionOptions) -> dict:
    """The smoother's settings as a decomposition's settings keep them."""
    return dict(neighbors=options.neighbors, lam=options.lam, mu=options.mu, iterations=options.iterations)
