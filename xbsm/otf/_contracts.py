"""The argument rules the OTF mechanisms declare (private to :mod:`xbsm.otf`).

Each public OTF function declares its checked arguments with
:func:`xbsm.params.contract`, as every other public function does, so a bad input
raises the same one-line ``ValueError`` everywhere: the argument's name and its
allowed interval with units (``wavelength must lie in (0, inf) m; got -1.0``). NaN is
outside every interval; dask-backed values are not computed to be checked; an
optional argument (a rule with ``optional=True``) may be None. The rules shared by
several mechanisms live here; one mechanism's own rules sit beside its function.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from .. import params
from ..params import Spec, Values

WAVELENGTH = Values(Spec("m", "wavelength", **params.POSITIVE))
APERTURE_DIAMETER = Values(Spec("m", "effective aperture diameter", **params.POSITIVE))
FOCAL_LENGTH = Values(Spec("m", "effective focal length", **params.POSITIVE))
LENGTH = Values(Spec("m", "length", **params.POSITIVE))
"""A detector width or pitch, a correlation length, a coherence diameter, a range."""
ANGLE = Values(Spec("rad", "angle", **params.POSITIVE))
"""An instantaneous field of view."""
BLUR = Values(Spec("rad", "blur size", **params.NONNEGATIVE))
"""An rms jitter or a Gaussian blur size."""
RATE = Values(Spec("rad s-1", "angular drift rate"))
"""Any finite number."""
DURATION = Values(Spec("s", "integration time", **params.NONNEGATIVE))
SPEED = Values(Spec("m s-1", "wind speed", **params.NONNEGATIVE))
CN2 = Values(Spec("m-2/3", "refractive-index structure parameter", **params.NONNEGATIVE))
CN2_SCALE = Values(Spec("1", "multiplier of the Cn2 profile", **params.NONNEGATIVE))
COUNT = Values(Spec("1", "count", **params.NONNEGATIVE))
"""A number of charge transfers."""
POSITIVE_NUMBER = Values(Spec("1", "positive number", **params.POSITIVE))
"""A number of clock phases or TDI stages, a rate ratio."""
UNIT_INTERVAL = Values(Spec("1", "fraction", **params.FRACTION))
"""A transfer efficiency or an exposure coefficient."""
NONNEGATIVE_WEIGHTS = Values(Spec("1", "spectral weights", **params.NONNEGATIVE))


@dataclass(frozen=True)
class Weights:
    """Spectral weights: a DataArray over ``dim``, every value >= 0, not all zero along ``dim``.

    Dask-backed weights are not computed to be checked.
    """

    dim: str = "wavelength"

    def check(self, name: str, value):
        """``value`` unchanged if it is such weights."""
        if not isinstance(value, xr.DataArray) or self.dim not in value.dims:
            raise ValueError(f"{name} must be a DataArray with dimension {self.dim!r}")
        NONNEGATIVE_WEIGHTS.check(name, value)
        if value.chunks is None and not np.all(value.sum(self.dim).values > 0):
            raise ValueError(f"{name} must not be all zero along {self.dim!r}")
        return value
