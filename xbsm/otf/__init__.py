"""Optical transfer functions, one module per mechanism, and the system product."""

from . import (
    aperture,
    defocus,
    detector,
    filters,
    motion,
    psf,
    spectral,
    system,
    turbulence,
    user,
    wavefront,
)

__all__ = [
    "aperture",
    "defocus",
    "detector",
    "filters",
    "motion",
    "psf",
    "spectral",
    "system",
    "turbulence",
    "user",
    "wavefront",
]
