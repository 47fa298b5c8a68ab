"""Physical constants, in SI units, in one place.

The defaults come from :mod:`scipy.constants` (CODATA 2018 exact SI values).
pyBSM 0.16.1 hard-codes the CODATA 2014 values; they are kept here as
:data:`PYBSM_CODATA_2014` so that ``method="pybsm"`` reproduces its numbers to
floating-point rounding (the two sets differ by 1.4e-8 relative in h and 5.7e-7
in k, enough to move photoelectron counts beyond 1e-9).
"""

from __future__ import annotations

from dataclasses import dataclass

import scipy.constants as _sc


@dataclass(frozen=True)
class Constants:
    """A consistent set of the physical constants the model uses."""

    planck: float
    """Planck constant h. [J s]"""
    speed_of_light: float
    """Speed of light in vacuum c. [m/s]"""
    boltzmann: float
    """Boltzmann constant k. [J/K]"""
    elementary_charge: float
    """Elementary charge q. [C]"""
    name: str


CODATA = Constants(
    planck=_sc.h,
    speed_of_light=_sc.c,
    boltzmann=_sc.k,
    elementary_charge=_sc.e,
    name="scipy.constants (CODATA 2018)",
)

# The values pyBSM 0.16.1 hard-codes (radiance/functional.py, otf/functional.py).
PYBSM_CODATA_2014 = Constants(
    planck=6.62607004e-34,
    speed_of_light=299792458.0,
    boltzmann=1.38064852e-23,
    elementary_charge=1.60217662e-19,
    name="CODATA 2014 as hard-coded in pyBSM 0.16.1",
)

EARTH_RADIUS = 6378.164e3
"""Radius of the spherical Earth used for all geometry (the paper, Sec. 2.6). [m]"""
