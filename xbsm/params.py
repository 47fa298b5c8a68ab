"""Sensor and scenario parameters as validated ``xr.Dataset`` objects.

``sensor(...)`` and ``scenario(...)`` are the public entry points. Every
parameter is SI (a plain float means SI) and may be a scalar or an
``xr.DataArray`` with dimensions of its own: such a dimension is a sweep and
every result carries it. Spectral parameters (quantum efficiency, optics
transmission, stray irradiance) are DataArrays over ``wavelength``; inside the
dataset each keeps its own wavelength coordinate under a private dimension
name (``<parameter>_wavelength``) so that differently sampled curves can live
side by side.

Defaults are pyBSM 0.16.1's, except the detector height default (see
:func:`sensor`). Bad input raises ``ValueError`` naming the parameter and its
allowed range; dask-backed inputs are checked lazily, when computed. Inputs
are never modified.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import math
import numbers
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import xarray as xr

from . import units
from ._metadata import declared
from .atmosphere.database import (  # the database's facts, re-exported where they bound inputs
    ALTITUDE_RANGE,
    CONDITION_RTOL,
    CONDITIONS,
    GROUND_RANGE_RANGE,
    WAVELENGTH_MAX,
    WAVELENGTH_MIN,
    database_conditions,
    describe_conditions,
    listed,
    visibility_range,
)


@dataclass(frozen=True)
class Spec:
    """Definition of one parameter: units, meaning and allowed interval.

    ``whole`` restricts a plain knob (:meth:`check`) to whole numbers.
    """

    units: str
    long_name: str
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    whole: bool = False

    def __post_init__(self):
        # an unbounded end is open: inf is never a valid parameter value
        if self.high == math.inf:
            object.__setattr__(self, "high_open", True)
        if self.low == -math.inf:
            object.__setattr__(self, "low_open", True)

    def interval(self) -> str:
        """The allowed interval, e.g. ``(0, inf)`` (whole numbers as integers)."""
        left = "(" if self.low_open else "["
        right = ")" if self.high_open else "]"
        low, high = (f"{int(v)}" if self.whole and math.isfinite(v) else f"{v:g}"
                     for v in (self.low, self.high))
        return f"{left}{low}, {high}{right}"

    def describe(self) -> str:
        """Human-readable allowed interval, e.g. ``(0, inf) m``."""
        return f"{self.interval()} {self.units}"

    def violated(self, values: np.ndarray) -> np.ndarray:
        """Boolean mask of values outside the interval (NaN counts as outside)."""
        return _outside(np.asarray(values, dtype=float), self.low, self.high, self.low_open,
                        self.high_open)

    def check(self, name: str, value):
        """``value`` if it is a plain real (whole, for ``whole``) number inside the interval."""
        kind = numbers.Integral if self.whole else numbers.Real
        if (not isinstance(value, kind) or isinstance(value, bool)
                or bool(self.violated(value))):
            number = "a whole number" if self.whole else "a real number"
            raise ValueError(f"{name} must be {number} in {self.interval()}; got {value!r}")
        return value


def _outside(values, low, high, low_open, high_open) -> np.ndarray:
    """Where ``values`` leave their intervals (NaN counts as outside); the bounds broadcast."""
    below = np.where(low_open, values <= low, values < low)
    above = np.where(high_open, values >= high, values > high)
    return below | above | np.isnan(values)


POSITIVE = {"low": 0.0, "low_open": True}
NONNEGATIVE = {"low": 0.0}
FRACTION = {"low": 0.0, "high": 1.0}


# ---- declared contracts of public functions (xclim's declare_units, in Spec words) ----------
# A public function carries its contract: one rule per checked argument (a Spec for a number,
# or one of the rules below) and the declaration of what it returns. Each rule's ``check``
# returns the value the function receives, or raises a one-line ValueError naming the
# argument and what it allows.


@dataclass(frozen=True)
class Values:
    """A physical argument (a float, an array or an eager DataArray) inside ``spec``'s interval.

    NaN counts as outside; dask-backed values are not computed to be checked.
    ``optional``: None is allowed (the argument is not given). ``infinite``: +inf is
    allowed too (a range to a focus at infinity), closing the interval's unbounded end.
    """

    spec: Spec
    optional: bool = False
    infinite: bool = False

    def check(self, name: str, value):
        """``value`` unchanged if every one of its values lies in the interval."""
        if value is None and self.optional:
            return value
        if getattr(getattr(value, "data", None), "chunks", None) is not None:
            return value
        values = np.asarray(value, dtype=float)
        mask = self.spec.violated(values)
        if self.infinite:
            mask &= ~np.isposinf(values)
        if np.any(mask):
            bad = float(values[mask].ravel()[0] if values.ndim else values)
            if self.infinite:
                raise ValueError(f"{name} must lie in {self.spec.interval()[:-1]}] "
                                 f"{self.spec.units}; got {bad!r}")
            _raise(name, self.spec, bad)
        return value


@dataclass(frozen=True)
class Choice:
    """A knob that takes one of ``choices`` (strings, or None where None means "none")."""

    choices: tuple

    def check(self, name: str, value):
        """``value`` if it is one of the choices."""
        if not ((value is None or isinstance(value, str)) and value in self.choices):
            raise ValueError(f"{name} must be one of {', '.join(map(repr, self.choices))}; "
                             f"got {value!r}")
        return value


@dataclass(frozen=True)
class Selection:
    """A non-empty selection of ``choices`` (one name or several); None selects all of them."""

    choices: tuple

    def check(self, name: str, value) -> tuple:
        """The chosen names as a tuple."""
        if value is None:
            return self.choices
        chosen = (value,) if isinstance(value, str) else tuple(value)
        if not chosen or any(c not in self.choices for c in chosen):
            raise ValueError(f"{name} must be a non-empty selection of {self.choices}; "
                             f"got {value!r}")
        return chosen


@dataclass(frozen=True)
class Pair:
    """A ``(low, high)`` pair of numbers inside ``spec``'s interval, returned as floats.

    ``low < high`` (``low <= high`` when ``equal``); an infinite end of ``spec`` may be
    reached (a range may be unbounded). ``optional``: None is allowed (no range).
    """

    spec: Spec
    equal: bool = False
    optional: bool = False

    def check(self, name: str, value):
        """``(low, high)`` as floats (None if optional and None)."""
        if value is None and self.optional:
            return None
        try:
            low, high = (float(v) for v in value)
        except (TypeError, ValueError):
            low = high = math.nan
        spec = self.spec
        inside = (math.isinf(v) or not spec.violated(v) for v in (low, high))
        ordered = low <= high if self.equal else low < high
        if not (ordered and all(inside) and low >= spec.low and high <= spec.high):
            raise ValueError(
                f"{name} must be {'None or ' if self.optional else ''}a (low, high) pair in "
                f"{spec.describe()} with low {'<=' if self.equal else '<'} high; got {value!r}")
        return low, high


@dataclass(frozen=True)
class Table:
    """A lookup table ``(x values, y values)``, returned as two float arrays sorted by x.

    At least two points, as many y as x, x finite and distinct, every y inside ``spec``'s
    interval. ``x`` and ``y`` name the two halves in the errors.
    """

    x: str
    y: str
    spec: Spec

    def check(self, name: str, value) -> tuple:
        """``(x, y)`` as float arrays sorted by x."""
        try:
            xs, ys = (np.asarray(v, dtype=float).ravel() for v in value)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a pair ({self.x}, {self.y}); "
                             f"got {value!r:.60}") from None
        if xs.size < 2 or xs.size != ys.size:
            raise ValueError(f"{name} table needs at least 2 {self.x} and as many {self.y}; "
                             f"got {xs.size} and {ys.size}")
        order = np.argsort(xs)
        xs, ys = xs[order], ys[order]
        if not (np.all(np.isfinite(xs)) and np.all(np.diff(xs) > 0)):
            raise ValueError(f"{name} table {self.x} must be finite and distinct")
        if np.any(self.spec.violated(ys)):
            raise ValueError(f"{name} table {self.y} must lie in {self.spec.describe()}")
        return xs, ys


@dataclass(frozen=True)
class Either:
    """One of ``choice``'s names, or anything else that ``other`` accepts."""

    choice: Choice
    other: object  # a rule

    def check(self, name: str, value):
        """``value`` if a choice, else what ``other`` makes of it."""
        if value is None or isinstance(value, str):
            if value in self.choice.choices:
                return value
            raise ValueError(f"{name} must be one of {', '.join(map(repr, self.choice.choices))}"
                             f" or a table; got {value!r}")
        return self.other.check(name, value)


@dataclass(frozen=True)
class Instance:
    """An object of type ``kind``; ``described`` says which in the error."""

    kind: type
    described: str

    def check(self, name: str, value):
        """``value`` if it is an instance of ``kind``."""
        if not isinstance(value, self.kind):
            raise ValueError(f"{name} must be {self.described}; got {type(value).__name__}")
        return value


@dataclass(frozen=True)
class Resolved:
    """An argument a function of the package resolves: a preset name or the object itself.

    ``resolve(value)`` checks it, raising the error that names the argument.
    """

    resolve: object  # callable

    def check(self, name: str, value):
        """What ``value`` resolves to."""
        return self.resolve(value)


@dataclass(frozen=True)
class Contract:
    """What a public function checks on its arguments and declares of its result."""

    rules: MappingProxyType
    returns: object = None  # an xbsm._metadata.Output for a DataArray result, or None


def contract(returns=None, **rules):
    """Declare a public function's checked arguments and its output, and enforce them.

    Parameters
    ----------
    returns : xbsm._metadata.Output, optional
        Units and long name of a DataArray result (set on every call).
    **rules : Spec, Values, Choice, Selection, Pair, Table, Either, Instance or Resolved
        One per checked argument, by name; the function receives what the rule returns
        (a Selection's tuple, a Pair's floats). Defaults are checked too.

    The decorated function carries the declaration as ``__contract__`` (a
    :class:`Contract`), so that documentation and tests can read it.
    """
    def decorate(func):
        signature = inspect.signature(func)
        positional = [name for name, p in signature.parameters.items()
                      if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
        where = {name: (positional.index(name) if name in positional else None,
                        signature.parameters[name].default) for name in rules}

        @functools.wraps(func)
        def checked(*args, **kwargs):
            args = list(args)
            for name, rule in rules.items():
                position, default = where[name]
                if name in kwargs:
                    kwargs[name] = rule.check(name, kwargs[name])
                elif position is not None and position < len(args):
                    args[position] = rule.check(name, args[position])
                elif default is not inspect.Parameter.empty:
                    kwargs[name] = rule.check(name, default)
            out = func(*args, **kwargs)
            return out if returns is None else declared(out, returns)

        checked.__contract__ = Contract(MappingProxyType(rules), returns)
        return checked

    return decorate


SENSOR_SPECS: dict[str, Spec] = {
    "aperture_diameter": Spec("m", "effective aperture diameter", **POSITIVE),
    "focal_length": Spec("m", "effective focal length", **POSITIVE),
    "pixel_pitch_x": Spec("m", "detector pitch along x", **POSITIVE),
    "pixel_pitch_y": Spec("m", "detector pitch along y", **POSITIVE),
    "detector_width_x": Spec("m", "detector active width along x", **POSITIVE),
    "detector_width_y": Spec("m", "detector active width along y", **POSITIVE),
    "wavelength_min": Spec(
        "m", "short edge of the spectral band", WAVELENGTH_MIN, WAVELENGTH_MAX, high_open=True
    ),
    "wavelength_max": Spec(
        "m", "long edge of the spectral band", WAVELENGTH_MIN, WAVELENGTH_MAX, low_open=True
    ),
    "obscuration_ratio": Spec(
        "1", "relative linear obscuration of the aperture", 0.0, 1.0, high_open=True
    ),
    "integration_time": Spec("s", "maximum integration time", **POSITIVE),
    "dark_current": Spec("s-1", "detector dark current in electrons per second", **NONNEGATIVE),
    "read_noise": Spec("1", "read noise in rms electrons", **NONNEGATIVE),
    "other_noise": Spec(
        "1", "root-sum-square of other noise sources in rms electrons", **NONNEGATIVE
    ),
    "max_well": Spec("1", "detector well capacity in electrons", **POSITIVE),
    "max_well_fill": Spec(
        "1", "largest allowed fraction of the well", 0.0, 1.0, low_open=True
    ),
    "bit_depth": Spec("1", "analog-to-digital converter resolution in bits", **POSITIVE),
    "tdi_stages": Spec("1", "number of time-delay-integration stages", low=1.0),
    "frame_stacks": Spec("1", "number of frames added together", low=1.0),
    "cold_shield_temperature": Spec("K", "cold shield temperature", **POSITIVE),
    "optics_temperature": Spec("K", "optics temperature", **POSITIVE),
    "optics_emissivity": Spec("1", "emissivity of the optics (cold filter excluded)", **FRACTION),
    "cold_filter_transmission": Spec("1", "cold filter transmission", **FRACTION),
    "cold_filter_temperature": Spec("K", "cold filter temperature", **POSITIVE),
    "cold_filter_emissivity": Spec("1", "cold filter emissivity", **FRACTION),
    "jitter_x": Spec("rad", "rms line-of-sight jitter along x", **NONNEGATIVE),
    "jitter_y": Spec("rad", "rms line-of-sight jitter along y", **NONNEGATIVE),
    "drift_rate_x": Spec("rad s-1", "line-of-sight drift rate along x"),
    "drift_rate_y": Spec("rad s-1", "line-of-sight drift rate along y"),
    "wavefront_variance": Spec(
        "rad2", "wavefront phase variance at the reference wavelength", **NONNEGATIVE
    ),
    "wavefront_wavelength": Spec(
        "m", "wavelength at which the wavefront variance is given", **POSITIVE
    ),
    "wavefront_correlation_length_x": Spec(
        "m", "correlation length of the pupil phase along x", **POSITIVE
    ),
    "wavefront_correlation_length_y": Spec(
        "m", "correlation length of the pupil phase along y", **POSITIVE
    ),
    "defocus_opd": Spec(
        "m", "defocus wavefront coefficient W020 (path difference at the pupil edge)",
        **NONNEGATIVE
    ),
    "optics_transmission": Spec("1", "optics transmission (obscuration excluded)", **FRACTION),
    "quantum_efficiency": Spec("1", "detector quantum efficiency", **FRACTION),
    "stray_irradiance": Spec(
        "W m-2 m-1", "stray-light spectral irradiance at the focal plane", **NONNEGATIVE
    ),
}

SPECTRAL = ("optics_transmission", "quantum_efficiency", "stray_irradiance")

SCENARIO_SPECS: dict[str, Spec] = {
    "altitude": Spec("m", "sensor altitude above ground", *ALTITUDE_RANGE),
    "ground_range": Spec("m", "ground range from sensor nadir to target", *GROUND_RANGE_RANGE),
    # within the range of the database in use (checked by scenario: xbsm.atmosphere)
    "visibility": Spec("km", "meteorological visibility (MODTRAN rural aerosol)", **POSITIVE),
    "platform_speed": Spec("m s-1", "platform ground speed", **NONNEGATIVE),
    "target_reflectance": Spec("1", "target reflectance", **FRACTION),
    "target_temperature": Spec("K", "target temperature", **POSITIVE),
    "background_reflectance": Spec("1", "background reflectance", **FRACTION),
    "background_temperature": Spec("K", "background temperature", **POSITIVE),
    "high_altitude_wind_speed": Spec(
        "m s-1", "high-altitude wind speed of the Hufnagel-Valley profile", **NONNEGATIVE
    ),
    "cn2_at_1m": Spec(
        "m-2/3", "refractive-index structure parameter 1 m above ground", **NONNEGATIVE
    ),
    "cn2_tropopause": Spec(
        "m-2/3", "coefficient of the Hufnagel-Valley tropopause term (height in metres)",
        **NONNEGATIVE
    ),
    "cn2_upper_air": Spec(
        "m-2/3", "coefficient of the Hufnagel-Valley 1.5 km scale-height term", **NONNEGATIVE
    ),
    "cn2_multiplier": Spec("1", "multiplier of the whole Cn2 profile", **NONNEGATIVE),
}

#: The atmosphere conditions a database may hold as dimensions besides visibility
#: (:data:`xbsm.atmosphere.CONDITIONS`): optional scenario parameters, each one of the
#: values the database in use holds.
CONDITION_SPECS: dict[str, Spec] = {
    "aerosol_model": Spec("1", CONDITIONS["aerosol_model"][1], **NONNEGATIVE),
    "atmosphere_profile": Spec("1", CONDITIONS["atmosphere_profile"][1], **NONNEGATIVE),
    "sun_zenith": Spec("rad", CONDITIONS["sun_zenith"][1], 0.0, math.pi / 2),
    "sun_azimuth": Spec("rad", CONDITIONS["sun_azimuth"][1], -2 * math.pi, 2 * math.pi),
    "day_of_year": Spec("1", CONDITIONS["day_of_year"][1], 1.0, 366.0),
    "ground_altitude": Spec("m", CONDITIONS["ground_altitude"][1], -1000.0, 10000.0),
}


def parameter_spec(name: str) -> Spec:
    """The :class:`Spec` of a sensor, scenario or condition parameter (KeyError if none)."""
    for specs in (SENSOR_SPECS, SCENARIO_SPECS, CONDITION_SPECS):
        if name in specs:
            return specs[name]
    raise KeyError(name)


PROFILE_DEFAULTS = MappingProxyType({
    "high_altitude_wind_speed": 21.0, "cn2_at_1m": 1.7e-14, "cn2_tropopause": 5.94e-53,
    "cn2_upper_air": 2.7e-16})
"""Hufnagel-Valley 5/7, the defaults of :func:`scenario` (a ``cn2_profile`` replaces it)."""


#: Dimension names xbsm uses itself; a sweep dimension may not take one of them (it would
#: merge silently with xbsm's own axis), nor the name of another parameter.
RESERVED_DIMS = (
    "wavelength", "frequency", "orientation", "giqe", "fx", "fy", "x", "y", "component",
    "kernel_x", "kernel_y", "reflectance", "path", "position", "bin", "height",
    *(f"{name}_wavelength" for name in ("optics_transmission", "quantum_efficiency",
                                          "stray_irradiance")),
)


RESULT_NAMES = (
    "niirs", "snr", "snr_frame", "effective_integration_time", "target_photoelectrons",
    "background_photoelectrons", "contrast_photoelectrons", "well_fill", "shot_noise",
    "scene_noise", "path_noise", "self_emission_noise", "dark_current_noise",
    "quantization_noise", "read_noise", "other_noise", "total_noise", "rer_x", "rer_y",
    "eho_x", "eho_y", "rer", "eho", "coherence_diameter", "cutoff_frequency", "rer_giqe5",
    "gsd", "gsd_gp", "gsd_w", "noise_gain", "slant_range", "elevation_angle", "flags",
    "spectral_weights", "aperture", "turbulence", "detector", "jitter", "drift", "wavefront",
    "filter", "system_unfiltered", "system", "netd", "netd_frame", "ner", "ner_target", "nei",
    "signal_derivative",
)
"""Variables of the results of ``snr``, ``netd``, ``niirs`` and ``system_otf``: a sweep dimension of
one of these names would replace the variable by its coordinate (a parameter the result
echoes under its own name, ``read_noise`` and ``other_noise``, may sweep on it)."""


def _check_dims(name: str, value: xr.DataArray, allowed=()) -> None:
    """Refuse sweep dimensions that would collide with xbsm's own or another parameter."""
    for dim in value.dims:
        if dim in allowed:
            continue
        if dim in RESERVED_DIMS:
            raise ValueError(
                f"{name} is swept on dimension {dim!r}, a name xbsm uses itself; rename it "
                f"(reserved: {', '.join(RESERVED_DIMS)})")
        if dim in RESULT_NAMES and dim != name:
            raise ValueError(
                f"{name} is swept on dimension {dim!r}, the name of a result variable; "
                "name the dimension anything else (result variables: see xbsm.params."
                "RESULT_NAMES)")
        if dim != name and (dim in SENSOR_SPECS or dim in SCENARIO_SPECS):
            raise ValueError(
                f"{name} is swept on dimension {dim!r}, the name of another parameter; "
                f"name the dimension {name!r} or anything that is not a parameter")


def _raise(name: str, spec: Spec, bad) -> None:
    raise ValueError(f"{name} must lie in {spec.describe()}; got {float(bad)!r}")


def _lazy_check(block, name, spec):
    mask = spec.violated(block)
    if np.any(mask):
        _raise(name, spec, np.asarray(block)[mask].ravel()[0])
    return block


def _as_float64(name: str, value, spec: Spec):
    """``value`` as float64 (promoting integers and float16/32); a clear error otherwise."""
    kind = np.asarray(value).dtype.kind if not isinstance(value, xr.DataArray) else value.dtype.kind
    if kind == "b" or kind not in "iuf":
        shown = (f"an xr.DataArray of dtype {value.dtype} on dims {value.dims}"
                 if isinstance(value, xr.DataArray) else f"{value!r:.80}")
        raise ValueError(
            f"{name} must be a real number or an xr.DataArray of real numbers "
            f"[{spec.units}]; got {shown}")
    if isinstance(value, xr.DataArray):
        return value if value.dtype == np.float64 else value.astype(np.float64)
    return np.asarray(value, dtype=np.float64)


def _validated(name: str, value, spec: Spec, allowed_dims=()) -> xr.DataArray:
    """Return ``value`` as a float64 DataArray in SI with attrs, raising if out of range."""
    if isinstance(value, xr.Variable):
        value = xr.DataArray(value)
    if isinstance(value, xr.DataArray):
        out = units.in_units(name, _as_float64(name, value, spec), spec.units).copy(deep=False)
        if out.size == 0:
            raise ValueError(f"{name} is an empty sweep (dims {out.dims}); give at least one value")
    else:
        array = _as_float64(name, value, spec)
        if array.ndim:
            raise ValueError(
                f"{name} must be a scalar or an xr.DataArray with named dimensions; "
                f"got an unlabelled array of shape {array.shape}"
            )
        out = xr.DataArray(array)
    _check_dims(name, out, allowed_dims)
    if out.chunks is not None:
        import dask.array as dsa

        data = dsa.map_blocks(_lazy_check, out.data, name, spec, dtype=out.dtype)
        out = out.copy(data=data)
    else:
        mask = spec.violated(out.values)
        if np.any(mask):
            _raise(name, spec, out.values[mask].ravel()[0])
    return out.assign_attrs(units=spec.units, long_name=spec.long_name)


def _spectral(name: str, value, spec: Spec) -> xr.DataArray:
    """Validate a spectral parameter and move it onto its own wavelength dim."""
    if not isinstance(value, xr.DataArray) or "wavelength" not in value.dims:
        return _validated(name, value, spec)
    if "wavelength" not in value.coords:
        raise ValueError(
            f"{name} is on dimension 'wavelength' but has no 'wavelength' coordinate: give "
            "the wavelength of each value [m], strictly increasing, e.g. xr.DataArray(values, "
            "dims='wavelength', coords={'wavelength': wavelengths})")
    wl = np.asarray(value["wavelength"].values, dtype=float)
    if wl.size < 1 or np.any(np.diff(wl) <= 0) or not np.all(np.isfinite(wl)):
        raise ValueError(f"{name}: its wavelength coordinate must be finite and increase strictly")
    private = f"{name}_wavelength"
    return _validated(name, value.rename(wavelength=private), spec, allowed_dims=(private,))


def _check_band_overlap(name: str, curve: xr.DataArray, low: float, high: float) -> None:
    """Refuse a spectral curve that gives no signal in the band [low, high].

    The curve must reach into the band and, for QE and transmission, be non-zero
    somewhere in it; a curve that covers part of the band is legitimate (zero outside
    its own range).
    """
    dim = f"{name}_wavelength"
    if dim in curve.dims:
        wl = curve[dim].values
        if wl[-1] < low or wl[0] > high:
            hint = (" Are its wavelengths in micrometres or nanometres? xbsm uses metres."
                    if wl[-1] > 1e-3 or wl[0] > 1e-3 else "")
            raise ValueError(
                f"{name} is given over [{wl[0]:g}, {wl[-1]:g}] m, outside the band "
                f"[wavelength_min, wavelength_max] = [{low:g}, {high:g}] m; its wavelengths "
                f"must reach into the band.{hint}")
        lo, hi = max(wl[0], low), min(wl[-1], high)
        inside = curve.where((curve[dim] >= lo) & (curve[dim] <= hi), drop=True)
        if wl.size > 1 and curve.chunks is None:  # and the curve at the band edges
            inside = xr.concat([inside, curve.interp({dim: [lo, hi]})], dim)
    else:
        inside = curve
    if name != "stray_irradiance" and inside.chunks is None and not bool((inside > 0).any()):
        raise ValueError(f"{name} is zero over the whole band [{low:g}, {high:g}] m: no signal")


def partial_spectral_coverage(sensor: xr.Dataset) -> bool:
    """Whether a spectral curve of ``sensor`` covers only part of its band.

    Such a curve is legitimate (it is zero outside its own wavelengths), but the
    results carry the ``partial_spectral_coverage`` flag so that the user learns it.
    The ends are compared with a relative tolerance of 1e-9 (a curve given at the
    band edges in another floating-point spelling covers the band).
    """
    variables = sensor.variables  # not a DataArray per parameter: single calls are hot
    low, high = (float(variables[name].values) for name in ("wavelength_min", "wavelength_max"))
    tolerance = 1e-9 * high
    for name in SPECTRAL:
        dim = f"{name}_wavelength"
        if dim in variables[name].dims:
            wavelengths = variables[dim].values
            if wavelengths[0] > low + tolerance or wavelengths[-1] < high - tolerance:
                return True
    return False


def unknown_keyword(kind: str, given: str, known) -> ValueError:
    """The error for a keyword that does not exist, suggesting the closest names."""
    close = difflib.get_close_matches(given, list(known), n=3)
    hint = f"did you mean {' or '.join(map(repr, close))}?" if close else (
        f"known: {', '.join(sorted(known))}")
    return ValueError(f"unknown {kind} {given!r}; {hint}")


def _suggesting(func):
    """Turn Python's 'unexpected keyword argument' into one that names the closest keywords."""
    signature = inspect.signature(func)

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        for name in kwargs:
            if name not in signature.parameters:
                raise unknown_keyword(f"xbsm.{func.__name__} keyword", name,
                                      signature.parameters)
        return func(*args, **kwargs)

    return wrapper


def _check_shared_dims(values, kind: str, indexes=None) -> None:
    """Parameters swept on one dimension must agree on its length and coordinates.

    ``values`` maps parameter names to DataArrays or Variables; ``kind`` names them in
    the error ("sensor", or "sensor and scenario" for the two datasets of a model call).
    ``indexes`` maps each name to its indexes by dimension (default: the DataArrays' own).
    """
    seen = {}
    for name, value in values.items():
        own = value.indexes if indexes is None else indexes[name]
        for dim, size in zip(value.dims, value.shape, strict=True):
            index = own.get(dim)
            if dim not in seen:
                seen[dim] = (name, size, index)
                continue
            first, first_size, first_index = seen[dim]
            if first_size != size:
                raise ValueError(
                    f"{kind} parameters {first} and {name} both sweep dimension {dim!r} but "
                    f"with {first_size} and {size} values; one dimension is one sweep: "
                    "give them one length, or different dimension names for a product")
            if index is not None and first_index is not None and not index.equals(first_index):
                raise ValueError(
                    f"{kind} parameters {first} and {name} both sweep dimension {dim!r} with "
                    "different coordinate values; give them the same coordinates or "
                    "different dimension names")


def _finish(values: dict[str, xr.DataArray], kind: str) -> xr.Dataset:
    _check_shared_dims(values, kind)
    ds = xr.Dataset(values)
    ds.attrs["xbsm_kind"] = kind
    return ds


@_suggesting
def sensor(
    *,
    aperture_diameter,
    focal_length,
    pixel_pitch_x,
    wavelength_min,
    wavelength_max,
    pixel_pitch_y=None,
    detector_width_x=None,
    detector_width_y=None,
    obscuration_ratio=0.0,
    optics_transmission=1.0,
    quantum_efficiency=1.0,
    stray_irradiance=0.0,
    integration_time=1.0,
    dark_current=0.0,
    read_noise=0.0,
    other_noise=0.0,
    max_well=1.0e8,
    max_well_fill=1.0,
    bit_depth=100.0,
    tdi_stages=1.0,
    frame_stacks=1.0,
    cold_shield_temperature=70.0,
    optics_temperature=270.0,
    optics_emissivity=0.0,
    cold_filter_transmission=1.0,
    cold_filter_temperature=70.0,
    cold_filter_emissivity=0.0,
    jitter_x=0.0,
    jitter_y=0.0,
    drift_rate_x=0.0,
    drift_rate_y=0.0,
    wavefront_variance=0.0,
    wavefront_wavelength=0.633e-6,
    wavefront_correlation_length_x=None,
    wavefront_correlation_length_y=None,
    defocus_opd=0.0,
    filter_kernel=None,
) -> xr.Dataset:
    """Camera parameters as a validated dataset.

    Parameters
    ----------
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter. [m]
    focal_length : float or xr.DataArray
        Effective focal length. [m]
    pixel_pitch_x : float or xr.DataArray
        Detector centre-to-centre spacing along x. [m]
    wavelength_min, wavelength_max : float
        Spectral band edges, inside the database's 0.3-14 um. [m]
    pixel_pitch_y : float or xr.DataArray, optional
        Pitch along y; defaults to ``pixel_pitch_x``. [m]
    detector_width_x : float or xr.DataArray, optional
        Active detector width along x; defaults to the pitch (100% fill). [m]
    detector_width_y : float or xr.DataArray, optional
        Active width along y; defaults to the same fill factor as along x,
        ``detector_width_x / pixel_pitch_x * pixel_pitch_y``. (pyBSM 0.16.1
        uses the inverse fill factor, ``p_x / w_x * p_y``;
        :mod:`xbsm.pybsm_compat` reproduces that.) [m]
    obscuration_ratio : float or xr.DataArray
        Relative linear obscuration of the aperture. [1]
    optics_transmission, quantum_efficiency : float or xr.DataArray
        Scalars or curves over ``wavelength`` [m], resampled linearly onto the
        database wavelengths and zero outside the curve's own range. [1]
    stray_irradiance : float or xr.DataArray
        Stray-light spectral irradiance added at the focal plane (paper Eq. 2). [W m-2 m-1]
    integration_time : float or xr.DataArray
        Maximum integration time; shortened when the well would overfill. [s]
    dark_current : float or xr.DataArray
        Dark current. [electrons/s]
    read_noise, other_noise : float or xr.DataArray
        Read noise and the root-sum-square of any other noise. [rms electrons]
    max_well : float or xr.DataArray
        Well capacity. [electrons]
    max_well_fill : float or xr.DataArray
        Largest allowed well fill fraction, (0, 1]. [1]
    bit_depth : float or xr.DataArray
        ADC resolution. [bits]
    tdi_stages, frame_stacks : float or xr.DataArray
        Time-delay-integration stages and number of frames added. [1]
    cold_shield_temperature, optics_temperature, cold_filter_temperature : float
        Temperatures for self-emission. [K]
    optics_emissivity, cold_filter_transmission, cold_filter_emissivity : float
        [1]
    jitter_x, jitter_y : float or xr.DataArray
        rms line-of-sight jitter. [rad]
    drift_rate_x, drift_rate_y : float or xr.DataArray
        Line-of-sight drift rate. [rad/s]
    wavefront_variance : float or xr.DataArray
        Pupil phase variance at ``wavefront_wavelength``: (2 pi waves rms)^2. [rad^2]
    wavefront_wavelength : float or xr.DataArray
        [m]
    wavefront_correlation_length_x, wavefront_correlation_length_y : float, optional
        Correlation lengths of the pupil phase; default the aperture diameter. [m]
    defocus_opd : float or xr.DataArray
        Defocus as the wavefront coefficient W020: the optical path difference at the
        pupil edge between the wavefront and the sphere centred on the detector, >= 0;
        0 (default) is in focus. A length, not waves, because a focus error is one
        path difference at every wavelength of the band (W020 / lambda waves at each);
        the OTF depends only on its magnitude. It gives the geometric blur circle's
        angular diameter d = 8 W020 / D (:func:`xbsm.otf.defocus.blur_circle_diameter`),
        and a focus shift dz gives W020 = dz D^2 / (8 f^2) paraxially
        (:func:`xbsm.otf.aperture.defocus_wavefront_coefficient` for pyBSM's form).
        It enters the aperture OTF by the method knob ``defocus_otf`` (Hopkins 1955 by
        default; docs/otf.md). [m]
    filter_kernel : array_like or xr.DataArray, optional
        2-D post-processing (sharpening) kernel, rows along y, columns along x;
        dims ``kernel_y``, ``kernel_x``. Default: no filter ([[1]]).

    Returns
    -------
    xr.Dataset
        One variable per parameter, each with ``units`` and ``long_name``.
    """
    given = dict(locals())
    # validate what the defaults are derived from first, so an error names the input
    checked = [name for name in ("pixel_pitch_x", "pixel_pitch_y", "detector_width_x",
                                 "aperture_diameter")
               if given[name] is not None or name in ("pixel_pitch_x", "aperture_diameter")]
    for name in checked:
        given[name] = _validated(name, given[name], SENSOR_SPECS[name])
    # defaults derived from another parameter sweep on that parameter's dimensions
    derived = {}
    if pixel_pitch_y is None:
        given["pixel_pitch_y"] = given["pixel_pitch_x"]
        derived["pixel_pitch_y"] = given["pixel_pitch_x"].dims
    if detector_width_x is None:
        given["detector_width_x"] = given["pixel_pitch_x"]
        derived["detector_width_x"] = given["pixel_pitch_x"].dims
    if detector_width_y is None:
        given["detector_width_y"] = (
            given["detector_width_x"] / given["pixel_pitch_x"] * given["pixel_pitch_y"]
        )
        derived["detector_width_y"] = given["detector_width_y"].dims
    for axis in ("x", "y"):
        key = f"wavefront_correlation_length_{axis}"
        if given[key] is None:
            given[key] = given["aperture_diameter"]
            derived[key] = given["aperture_diameter"].dims
    kernel = given.pop("filter_kernel")
    values = {}
    for name, spec in SENSOR_SPECS.items():
        if name in SPECTRAL:
            values[name] = _spectral(name, given[name], spec)
        elif name in checked:
            values[name] = given[name]
        else:
            values[name] = _validated(name, given[name], spec, derived.get(name, ()))
    for name in ("wavelength_min", "wavelength_max"):
        if values[name].ndim:
            raise ValueError(f"{name} must be a scalar (band edges cannot be swept)")
    if not float(values["wavelength_min"]) < float(values["wavelength_max"]):
        raise ValueError(
            "wavelength_min must be smaller than wavelength_max; got "
            f"{float(values['wavelength_min'])!r} >= {float(values['wavelength_max'])!r}"
        )
    low, high = float(values["wavelength_min"]), float(values["wavelength_max"])
    for name in SPECTRAL:
        _check_band_overlap(name, values[name], low, high)
    values["filter_kernel"] = _kernel(kernel)
    return _finish(values, "sensor")


def _kernel(kernel) -> xr.DataArray:
    if kernel is None:
        kernel = [[1.0]]
    if isinstance(kernel, xr.DataArray):
        _check_kernel_labels(kernel)
        out = kernel.transpose("kernel_y", "kernel_x").astype(float)
    else:
        try:
            array = np.asarray(kernel, dtype=float)
        except (TypeError, ValueError):
            raise ValueError("filter_kernel must be a 2-D array of real numbers that sums to 1 "
                             f"(e.g. [[-0.25, 1.5, -0.25]]); got {kernel!r:.60}") from None
        if array.ndim == 1:
            array = array[np.newaxis, :]
        if array.ndim != 2 or array.size == 0:
            raise ValueError(
                f"filter_kernel must be a non-empty 2-D array; got shape {array.shape}"
            )
        out = xr.DataArray(array, dims=("kernel_y", "kernel_x"))
    _check_kernel_values(out.values)
    return out.assign_attrs(units="1", long_name="post-processing filter kernel")


def _check_kernel_labels(kernel) -> None:
    """A labelled kernel (DataArray or Variable) has the kernel dims and real numbers."""
    if set(kernel.dims) != {"kernel_y", "kernel_x"}:
        raise ValueError("filter_kernel must have dims ('kernel_y', 'kernel_x')")
    if kernel.dtype.kind not in "iuf":
        raise ValueError(f"filter_kernel must hold real numbers; got dtype {kernel.dtype}")


def _check_kernel_values(values: np.ndarray) -> None:
    """A kernel's values are finite and sum to one (within 1e-9)."""
    if not np.all(np.isfinite(values)):
        raise ValueError("filter_kernel must be finite")
    total = float(np.sum(values))
    if not math.isclose(total, 1.0, rel_tol=0, abs_tol=1e-9):
        raise ValueError(f"filter_kernel must sum to 1 (within 1e-9); got {total!r}")


@_suggesting
def scenario(
    *,
    altitude,
    ground_range,
    visibility,
    platform_speed=0.0,
    target_reflectance=0.15,
    target_temperature=295.0,
    background_reflectance=0.07,
    background_temperature=293.0,
    high_altitude_wind_speed=21.0,
    cn2_at_1m=1.7e-14,
    cn2_tropopause=5.94e-53,
    cn2_upper_air=2.7e-16,
    cn2_multiplier=1.0,
    cn2_profile=None,
    aerosol_model=None,
    atmosphere_profile=None,
    sun_zenith=None,
    sun_azimuth=None,
    day_of_year=None,
    ground_altitude=None,
) -> xr.Dataset:
    """Imaging geometry, atmosphere and target as a validated dataset.

    Parameters
    ----------
    altitude : float or xr.DataArray
        Sensor altitude above the (spherical) ground, 2 m to 550 km. [m]
    ground_range : float or xr.DataArray
        Ground distance from the sensor's nadir point to the target, 0-300 km. [m]
    visibility : float or xr.DataArray
        Meteorological visibility, within the smallest and largest of the atmosphere
        database in use (the shipped one: 5 to 23 km, generated at 23, MODTRAN rural
        IHAZE 1, and 5, IHAZE 2; between them interpolated in extinction and flagged
        ``visibility_interpolated``). [km]
    platform_speed : float or xr.DataArray
        Platform ground speed (blends short and long exposure turbulence). [m/s]
    target_reflectance, background_reflectance : float or xr.DataArray
        Lambertian reflectances used by :func:`xbsm.snr` with
        ``targets="scenario"``; the GIQE uses its own standard target. [1]
    target_temperature, background_temperature : float or xr.DataArray
        [K]
    high_altitude_wind_speed : float or xr.DataArray
        Hufnagel-Valley wind parameter; 21 m/s is HV 5/7. [m/s]
    cn2_at_1m : float or xr.DataArray
        Refractive-index structure parameter near the ground; 1.7e-14 is HV 5/7;
        0 switches turbulence off. [m^-2/3]
    cn2_tropopause : float or xr.DataArray
        Coefficient of the Hufnagel-Valley tropopause term
        :math:`(v/27)^2 h^{10} e^{-h/1000}` (``h`` in metres); 5.94e-53 is HV 5/7. [m^-2/3]
    cn2_upper_air : float or xr.DataArray
        Coefficient of the Hufnagel-Valley term :math:`e^{-h/1500}`; 2.7e-16 is HV 5/7.
        [m^-2/3]
    cn2_multiplier : float or xr.DataArray
        Factor of the whole Cn2 profile (Hufnagel-Valley or ``cn2_profile``); 0 switches
        turbulence off. [1]
    cn2_profile : xr.DataArray, optional
        A table of Cn2 [m^-2/3] over a ``height`` coordinate [m] (from 0 m, strictly
        increasing, up to at least the sensor altitude; values >= 0), interpolated
        log-linearly along the path in place of Hufnagel-Valley
        (:func:`xbsm.otf.turbulence.cn2_table`). The Hufnagel-Valley parameters must
        then keep their defaults. Stored as the variable ``cn2_profile``.
    aerosol_model, atmosphere_profile, sun_zenith, sun_azimuth, day_of_year, \
ground_altitude : float or xr.DataArray, optional
        Atmosphere conditions (:data:`CONDITION_SPECS`: codes [1], angles [rad],
        the day [1], the target's altitude above sea level [m]) for a database that holds
        them as dimensions (:data:`xbsm.atmosphere.CONDITIONS`): each one of the values
        the database in use holds; a condition it holds with one value may be left out.
        The shipped database holds none of them (its conditions are fixed: paper
        Appendix A). Stored only when given.

    Returns
    -------
    xr.Dataset
        One variable per parameter, each with ``units`` and ``long_name``.
    """
    given = dict(locals())
    values = {name: _validated(name, given[name], spec) for name, spec in SCENARIO_SPECS.items()}
    if cn2_profile is not None:
        values["cn2_profile"] = _profile_table(values, cn2_profile)
    values.update({name: _validated(name, given[name], spec)
                   for name, spec in CONDITION_SPECS.items() if given[name] is not None})
    _check_held(values)
    return _finish(values, "scenario")


def _check_held(values: dict) -> None:
    """Eager visibility and conditions within what the database in use holds."""
    held = database_conditions()  # the database in use (xbsm.atmosphere.use_database)
    vis = values["visibility"]
    if vis.chunks is None:
        lo, hi = min(held["visibility"]), max(held["visibility"])
        outside = (vis.values < lo) | (vis.values > hi)
        if np.any(outside):
            raise ValueError(
                f"visibility must be within {visibility_range(held['visibility'])}; got "
                f"{float(vis.values[outside].ravel()[0])!r}")
    for name in CONDITION_SPECS:
        if name not in values:
            continue
        if name not in held:
            raise ValueError(
                f"{name}: the atmosphere database in use holds no {name} dimension (it holds "
                f"{describe_conditions(held)}); use a database generated for several {name} "
                "values (xbsm.atmosphere.use_database) or leave it out")
        value = values[name]
        if value.chunks is None:
            known = np.isclose(value.values[..., None], held[name], rtol=CONDITION_RTOL,
                               atol=0.0).any(axis=-1)
            if not np.all(known):
                raise ValueError(
                    f"{name} must be one of {listed(name, held[name])}, the values of the "
                    f"atmosphere database in use; got {float(value.values[~known].ravel()[0])!r}")


def cn2_table(cn2_profile):
    """Validate a user table of :math:`C_n^2` over height; returns it as float64.

    Parameters
    ----------
    cn2_profile : xr.DataArray
        1-D over a ``height`` dimension whose coordinate is the height above the
        ground, strictly increasing, from 0 m or below; values finite and >= 0, at
        least two heights. Between heights :math:`C_n^2` is interpolated linearly in its
        logarithm (linearly where a neighbour is 0); above the last height the table
        refuses the path. [m^(-2/3)]

    Returns
    -------
    xr.DataArray
        The checked table, float64. [m^(-2/3)]
    """
    if not isinstance(cn2_profile, xr.DataArray) or cn2_profile.dims != ("height",) \
            or "height" not in cn2_profile.coords:
        raise ValueError("cn2_profile must be a 1-D xr.DataArray over dim 'height' with a "
                         "height coordinate [m] (Cn2 in m-2/3)")
    h = np.asarray(cn2_profile["height"].values, dtype=float)
    c = np.asarray(cn2_profile.values, dtype=float)
    if h.size < 2:
        raise ValueError(f"cn2_profile must have at least 2 heights; got {h.size}")
    if not np.all(np.isfinite(h)) or not np.all(np.diff(h) > 0):
        raise ValueError("cn2_profile heights must be finite and strictly increasing [m]; "
                         f"got {h.tolist()[:6]}")
    if h[0] > 0.0:
        raise ValueError("cn2_profile heights must start at or below 0 m (the target on the "
                         f"ground) to cover the path; got first height {h[0]!r}")
    bad = ~np.isfinite(c) | (c < 0.0)
    if np.any(bad):
        raise ValueError("cn2_profile values must lie in [0, inf) m-2/3; got "
                         f"{c[bad][0]!r} at height {h[bad][0]!r} m")
    if not np.any(c > 0.0):
        raise ValueError("cn2_profile must have a Cn2 > 0 somewhere; to switch turbulence "
                         "off set cn2_multiplier=0")
    out = xr.DataArray(c, dims="height", coords={"height": h},
                       attrs={"units": "m-2/3",
                              "long_name": "refractive-index structure parameter table"})
    out["height"].attrs.update(units="m", long_name="height above the ground")
    return out


def table_values(table: xr.DataArray):
    """(heights, Cn2) of a checked :func:`cn2_table` as read-only arrays (for the kernels)."""
    out = (np.array(table["height"].values, dtype=float), np.array(table.values, dtype=float))
    for a in out:
        a.flags.writeable = False
    return out


def _profile_table(values: dict, cn2_profile) -> xr.DataArray:
    """The checked ``cn2_profile``: HV parameters at their defaults, covering the altitudes."""
    for name, default in PROFILE_DEFAULTS.items():
        v = values[name]
        if v.ndim or v.chunks is not None or float(v.values) != default:
            raise ValueError(
                f"{name} is a Hufnagel-Valley parameter and cn2_profile replaces that profile: "
                f"leave {name} at its default {default!r} (scale a table with cn2_multiplier)")
    table = cn2_table(cn2_profile)
    altitude = values["altitude"]
    if altitude.chunks is None and float(altitude.max()) > float(table["height"][-1]):
        raise ValueError(
            "cn2_profile must cover the path: heights up to at least the highest altitude "
            f"{float(altitude.max())!r} m; its last height is {float(table['height'][-1])!r} m")
    return table


#: Arguments of model calls that are not sensor or scenario parameters.
ARGUMENT_SPECS = MappingProxyType({
    "reflectance": Spec("1", "target reflectance", **FRACTION),
    "temperature": Spec("K", "target temperature", **POSITIVE),
    "integration_time": SENSOR_SPECS["integration_time"],
    "frequency": Spec("cycles/rad", "angular spatial frequency"),
})


def argument(name: str, value, allowed_dims=()) -> xr.DataArray:
    """Validate a model-call argument (:data:`ARGUMENT_SPECS`) like a parameter."""
    return _validated(name, value, ARGUMENT_SPECS[name], allowed_dims)


def labelled(name: str, values, dim: str) -> xr.DataArray:
    """A DataArray as given, or a plain 1-D sequence labelled along ``dim`` (its own coordinate)."""
    if isinstance(values, xr.DataArray):
        return values
    array = np.asarray(values)
    if array.ndim > 1:
        raise ValueError(f"{name} must be 1-D, or an xr.DataArray with named dimensions; "
                         f"got shape {array.shape}")
    array = np.atleast_1d(array)
    return xr.DataArray(array, dims=dim, coords={dim: array})


MAX_FREQUENCIES = 1_000_000
"""Most frequencies one model call evaluates (each costs a wavelength axis of OTFs)."""


def frequencies(name: str, values: xr.DataArray) -> xr.DataArray:
    """Validate a frequency grid: finite, on the caller's own dims, not absurdly large."""
    if not isinstance(values, xr.DataArray):
        raise ValueError(f"{name} must be an xr.DataArray with named dimensions "
                         f"(e.g. dims ('fy',)) [cycles/rad]; got {type(values).__name__}")
    if values.size > MAX_FREQUENCIES:
        raise ValueError(f"{name} has {values.size} values; at most {MAX_FREQUENCIES} per call "
                         "(xbsm.params.MAX_FREQUENCIES): evaluate the grid in pieces")
    own = ("frequency", "fx", "fy", "x", "y")
    allowed = tuple(d for d in values.dims if d in own)
    return _validated(name, values, ARGUMENT_SPECS["frequency"], allowed)


def check_kind(ds: xr.Dataset, kind: str, argument: str) -> None:
    """Raise a clear error when a dataset of the wrong kind is passed."""
    if not isinstance(ds, xr.Dataset) or ds.attrs.get("xbsm_kind") != kind:
        raise ValueError(
            f"{argument} must be the dataset returned by xbsm.{kind}(...) "
            f"or xbsm.pybsm_compat.{kind}(...)"
        )


def _check_parameters(kind: str, variables, specs) -> set:
    """Every parameter of one dataset present, on allowed dims and within its range.

    The eager scalars (all of them in a single scenario) are compared in one array
    operation; a violation is reported for the first offending parameter in ``specs``
    order, as one parameter at a time would. Returns the names of those scalars.
    """
    try:
        values = [variables[name] for name in specs]
    except KeyError:
        missing = next(name for name in specs if name not in variables)
        raise ValueError(f"the {kind} dataset has no parameter {missing!r}; "
                         f"make it with xbsm.{kind}(...)") from None
    data = [v.data for v in values]  # once each: a Variable's ``data`` costs 0.4 us a read
    scalar = [d.ndim == 0 and _holds_values(d) for d in data]  # the array's ndim: cheaper
    low, high, low_open, high_open = _bounds(kind, specs)
    flat = np.array([d if s else np.nan for d, s in zip(data, scalar, strict=True)],
                    dtype=float)
    outside = _outside(flat, low, high, low_open, high_open)
    scalars = set()
    for (name, spec), value, is_scalar, bad in zip(specs.items(), values, scalar, outside,
                                                   strict=True):
        if is_scalar:
            if bad:
                _raise(name, spec, value.values)
            scalars.add(name)
            continue
        # a parameter swept alongside another on that one's own dimension is paired
        # with it (a derived default such as pixel_pitch_y, or a user's paired sweep)
        paired = tuple(dim for dim in value.dims
                       if dim in variables and variables[dim].dims == (dim,))
        _check_dims(name, value, allowed=(f"{name}_wavelength", *paired))
        if _is_eager(value):
            mask = spec.violated(value.values)
            if np.any(mask):
                _raise(name, spec, value.values[mask].ravel()[0])
    return scalars


def _is_eager(variable: xr.Variable) -> bool:
    """Whether a Variable holds its values (not dask); ``Variable.chunks`` costs far more."""
    return _holds_values(variable.data)


def _holds_values(data) -> bool:
    """Whether a Variable's ``data`` is its values (not a dask array)."""
    return getattr(data, "chunks", None) is None


def _bounds(kind: str, specs) -> tuple:
    """Each spec's (low, high, low_open, high_open) as arrays, in ``specs`` order."""
    if kind not in _BOUNDS:
        _BOUNDS[kind] = tuple(np.array([getattr(s, field) for s in specs.values()])
                              for field in ("low", "high", "low_open", "high_open"))
    return _BOUNDS[kind]


_BOUNDS: dict[str, tuple] = {}
"""Cache of :func:`_bounds` by dataset kind (the spec tables are fixed)."""


def check_inputs(sensor: xr.Dataset, scenario: xr.Dataset) -> None:
    """Validate a sensor and a scenario again where a model call receives them.

    Datasets may have been edited after :func:`sensor` / :func:`scenario` (e.g.
    ``s.assign(aperture_diameter=-0.1)``): every parameter is checked against its
    range again (eager values; dask values are checked when computed), and the two
    datasets' shared dimensions must agree in size and coordinates.

    Raises
    ------
    ValueError
        Naming the parameter and its allowed range, or the conflicting dimension.
    """
    check_kind(sensor, "sensor", "sensor")
    check_kind(scenario, "scenario", "scenario")
    # on the datasets' Variables: a DataArray per parameter would cost more than the checks
    sensor_variables, scenario_variables = sensor.variables, scenario.variables
    sensor_scalars = _check_parameters("sensor", sensor_variables, SENSOR_SPECS)
    scenario_scalars = _check_parameters("scenario", scenario_variables, SCENARIO_SPECS)
    for name, spec in CONDITION_SPECS.items():  # the optional conditions, where given
        variable = scenario_variables.get(name)
        if variable is not None and _is_eager(variable):
            bad = spec.violated(variable.values)
            if np.any(bad):
                _raise(name, spec, variable.values[bad].ravel()[0])
    low, high = (sensor_variables[name] for name in ("wavelength_min", "wavelength_max"))
    if low.ndim or high.ndim or not float(low.values) < float(high.values):
        raise ValueError("wavelength_min and wavelength_max must be scalars with "
                         f"wavelength_min < wavelength_max; got {low.values} and {high.values}")
    if "filter_kernel" not in sensor:
        raise ValueError("the sensor dataset has no parameter 'filter_kernel'; make it with "
                         "xbsm.sensor(...)")
    kernel = sensor_variables["filter_kernel"]  # an edited kernel: dims, finite, sums to 1
    _check_kernel_labels(kernel)
    _check_kernel_values(kernel.values)
    if not sensor.sizes.keys() & scenario.sizes.keys():
        return  # inside one dataset xarray keeps every dimension consistent
    values, indexes = {}, {}
    for ds, variables, scalars in ((sensor, sensor_variables, sensor_scalars),
                                   (scenario, scenario_variables, scenario_scalars)):
        own = None
        for name in ds.data_vars:
            if name in scalars:  # a scalar shares no dimension
                continue
            variable = variables[name]
            if variable.data.ndim:
                if own is None:
                    own = ds.indexes
                values[name], indexes[name] = variable, own
    _check_shared_dims(values, "sensor and scenario", indexes)
