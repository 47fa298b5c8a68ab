"""xbsm: an xarray-based electro-optical imaging system performance model.

Public entry points::

    atm = xbsm.open_atmosphere()
    s = xbsm.sensor(aperture_diameter=..., focal_length=..., ...)
    sc = xbsm.scenario(altitude=..., ground_range=..., visibility=...)
    r = xbsm.snr(s, sc)
    n = xbsm.niirs(s, sc)
    img = xbsm.simulate_image(image, s, sc, gsd=0.05, seed=0)
"""

__version__ = "0.1.0"  # first: submodules read it while the package initialises

from . import (
               examples,
               flags,
               geometry,
               measure,
               metrics,
               noise,
               otf,
               plot,
               pybsm_compat,
               radiometry,
               simulate,
)
from .atmosphere import atmosphere_at, open_atmosphere
from .methods import Method, method
from .model import niirs, snr, system_otf
from .params import scenario, sensor
from .simulate import simulate_image

__all__ = [
    "Method",
    "examples",
    "flags",
    "geometry",
    "measure",
    "metrics",
    "noise",
    "otf",
    "plot",
    "radiometry",
    "simulate",
    "atmosphere_at",
    "method",
    "open_atmosphere",
    "pybsm_compat",
    "scenario",
    "sensor",
    "niirs",
    "snr",
    "system_otf",
    "simulate_image",
]
