"""xbsm: an xarray-based electro-optical imaging system performance model.

Public entry points::

    atm = xbsm.open_atmosphere()
    s = xbsm.sensor(aperture_diameter=..., focal_length=..., ...)
    sc = xbsm.scenario(altitude=..., ground_range=..., visibility=...)
    r = xbsm.snr(s, sc)
    n = xbsm.niirs(s, sc)
    img = xbsm.simulate_image(image, s, sc, gsd=0.05, seed=0)

The submodules and functions below are imported on first use (PEP 562), so that
``import xbsm`` is quick and the ``xbsm`` command can set up its signal handlers
before numpy, xarray and dask are imported.
"""

import importlib

from ._version import __version__ as __version__  # re-exported: the one home is _version

#: Public name -> the module that defines it (a submodule is its own entry).
_PUBLIC = {
    "examples": "examples",
    "flags": "flags",
    "geometry": "geometry",
    "measure": "measure",
    "metrics": "metrics",
    "noise": "noise",
    "otf": "otf",
    "plot": "plot",
    "pybsm_compat": "pybsm_compat",
    "radiometry": "radiometry",
    "simulate": "simulate",
    "Method": "methods",
    "method": "methods",
    "atmosphere_at": "atmosphere",
    "open_atmosphere": "atmosphere",
    "scenario": "params",
    "sensor": "params",
    "mrc": "model",
    "mrtd": "model",
    "netd": "model",
    "niirs": "model",
    "snr": "model",
    "system_otf": "model",
    "target_acquisition": "model",
    "simulate_image": "simulate",
}

__all__ = list(_PUBLIC)


def __getattr__(name):
    source = _PUBLIC.get(name, name)  # any other public submodule, as an eager import gave
    try:
        module = importlib.import_module(f".{source}", __name__)
    except ModuleNotFoundError as err:
        if name.startswith("_") or err.name != f"{__name__}.{source}":
            raise
        raise AttributeError(f"module 'xbsm' has no attribute {name!r}") from None
    value = module if source == name else getattr(module, name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *__all__})
