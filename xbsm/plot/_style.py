"""Constants, display units, labels and titles shared by every xbsm figure.

Values arrive in SI units; :func:`_scale` picks a readable unit for display
(m -> km, rad -> mrad), :func:`value_label` names one value of a swept
dimension with its unit (legends, panel titles), and :func:`context_of` gathers
the title lines a result carries (study title, fixed parameters, method).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import xarray as xr

NOISE_TERMS = MappingProxyType({
    "total_noise": "total",
    "scene_noise": "scene",
    "path_noise": "path",
    "self_emission_noise": "emission / stray",
    "cold_shield_noise": "cold shield",
    "optics_emission_noise": "optics emission",
    "cold_filter_emission_noise": "cold filter emission",
    "stray_light_noise": "stray light",
    "dark_current_noise": "dark current",
    "quantization_noise": "quantization",
    "read_noise": "readout",
    "other_noise": "other",
})
"""Noise variables of a result and their bar labels, in the order of the paper's Figure 4.

The self-emission and stray-light noise is one bar, or, where a result carries its split
(:func:`xbsm.noise.self_emission_noise_terms`) and some source is set, one bar per source
that contributes."""

MTF_COMPONENTS = ("aperture", "turbulence", "detector", "jitter", "drift", "wavefront",
                  "filter")
"""OTF components of a result (``mtf_<name>``), in the order of the paper's Figure 5."""

NIIRS_SCALE = (0.0, 10.0)
"""The rating scale: NIIRS axes span it, values off it are not drawn. [1]"""

SNR_FLOOR = 1e-2
"""Bottom of the log SNR axes; smaller values are not drawn. [1]"""

MAX_PANELS = 8
"""Most values a faceted dimension may have (one panel each)."""

DPI = 150
"""Resolution of the PNG files. [dots per inch]"""

MTF_RANGES = (0.0, 100e3)
"""Ground ranges of the MTF breakdown (paper Figure 5a, 5b). [m]"""

NOISE_POINT = MappingProxyType({"ground_range": 20e3, "visibility": 5.0})
"""Scenario of the noise breakdown (paper Figure 4): 20 km ground range, 5 km visibility."""

MTF_POINT = MappingProxyType({"visibility": 23.0})
"""Visibility of the MTF breakdown (paper Figure 5). [km]"""

UNIT_TEXT = MappingProxyType({"m s-1": "m/s", "rad s-1": "rad/s", "s-1": "1/s",
                               "m-2/3": "m^-2/3", "W m-2 m-1": "W/(m² m)", "count": "electrons"})
_SCALES = MappingProxyType({
    "m": ((1e3, "km"), (1.0, "m"), (1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm")),
    "s": ((1.0, "s"), (1e-3, "ms"), (1e-6, "µs")),
    "rad": ((1.0, "rad"), (1e-3, "mrad"), (1e-6, "µrad")),
})
COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
           "tab:pink", "tab:gray", "tab:olive", "tab:cyan")
_KEY_SENSOR = MappingProxyType({"aperture_diameter": "aperture", "focal_length": "focal length",
                                 "pixel_pitch_x": "pixel pitch"})


# ---- units and labels ----------------------------------------------------------------------

def _scale(values, units: str) -> tuple[float, str]:
    """A display factor and unit for values in ``units`` (m -> km for kilometres, ...)."""
    steps = _SCALES.get(units)
    if not steps:
        return 1.0, UNIT_TEXT.get(units, units)
    finite = np.abs(np.asarray(values, dtype=float))
    finite = finite[np.isfinite(finite) & (finite > 0)]
    largest = finite.max() if finite.size else 1.0
    for factor, text in steps:
        if largest >= factor:
            return factor, text
    return steps[-1]


def with_unit(value, units: str, like=None) -> str:
    """``value`` with its unit, e.g. ``"9 km"``, ``"100 m/s"``, ``"0.4"``.

    The unit is chosen for ``like`` (all values of a coordinate) if given, else for ``value``.
    """
    factor, text = _scale([value] if like is None else like, units)
    number = f"{float(value) / factor:.4g}"
    return number if units in ("", "1") else f"{number}\u00a0{text}"  # no line break inside


def words(name: str) -> str:
    return name.replace("_", " ")


def value_label(ds: xr.Dataset, dim: str, index: int) -> str:
    """Legend or panel label of one value along ``dim``, with units."""
    coord = ds[dim] if dim in ds.coords else None
    if coord is None:
        return f"{words(dim)} #{index}"
    value = coord.values[index]
    if dim == "band":
        edges = [float(ds[name].values[index]) for name in ("wavelength_min", "wavelength_max")
                 if name in ds.coords and ds[name].dims == ("band",)]
        span = f" ({edges[0] * 1e9:.0f}-{edges[1] * 1e9:.0f}\u00a0nm)" if len(edges) == 2 else ""
        return f"{value} band{span}"
    paired = [name for name in ds.coords if name != dim and ds[name].dims == (dim,)]
    if coord.attrs.get("long_name") == "case number" and paired:
        return ", ".join(f"{words(name)} = {with_unit(ds[name].values[index], units_of(ds[name]))}"
                         for name in paired)
    if coord.dtype.kind in "iuf":
        return f"{words(dim)} = {with_unit(value, units_of(coord), coord.values)}"
    return f"{words(dim)} = {value}"


def units_of(da: xr.DataArray) -> str:
    """The ``units`` attribute, else those of the sensor or scenario parameter of that name."""
    if "units" in da.attrs:
        return str(da.attrs["units"])
    from ..params import parameter_spec

    try:
        return parameter_spec(str(da.name)).units
    except KeyError:
        return "1"


def axis_label(name: str, units: str, values) -> tuple[float, str]:
    """Display factor and axis label ``"name [unit]"`` of a coordinate."""
    factor, text = _scale(values, units)
    return factor, f"{words(name)} [{text}]" if units not in ("", "1") else words(name)


# ---- the scenario, for titles --------------------------------------------------------------

@dataclass(frozen=True)
class Context:
    """What a figure needs beyond the variables: title lines and the MTF frequency grid."""

    title: str
    frequency: np.ndarray | None


def context_of(ds: xr.Dataset) -> Context:
    """Title lines (study title, fixed parameters, method) and the MTF frequencies.

    The fixed parameters are those a study result records in its attributes
    (:mod:`xbsm.study.attributes`); a result without them gets no such line.
    """
    from ..params import SENSOR_SPECS, parameter_spec
    from ..study.attributes import parameters_of

    sensor, scenario = parameters_of(ds)
    lines = [str(ds.attrs["title"])] if ds.attrs.get("title") else []
    fixed = [f"{words(k)} {with_unit(v, parameter_spec(k).units)}" for k, v in scenario.items()]
    fixed += [f"{text} {with_unit(sensor[k], SENSOR_SPECS[k].units)}"
              for k, text in _KEY_SENSOR.items() if k in sensor and k not in ds.coords]
    if "band" not in ds.dims and {"wavelength_min", "wavelength_max"} <= set(sensor):
        fixed.append(f"band {sensor['wavelength_min'] * 1e9:.0f}-"
                     f"{sensor['wavelength_max'] * 1e9:.0f}\u00a0nm")
    if ds.attrs.get("xbsm_method"):
        fixed.append(f"method {ds.attrs['xbsm_method']}")
    if fixed:
        lines.append(", ".join(fixed))
    frequency = ds["frequency"].values if "frequency" in ds.coords else None
    return Context("\n".join(lines), frequency)


def set_suptitle(fig, text: str) -> None:
    """The figure title, each line wrapped to the figure's width."""
    width = max(40, int(fig.get_figwidth() * 12))
    lines = [textwrap.fill(line, width) for line in text.strip().splitlines()]
    fig.suptitle("\n".join(lines), fontsize="medium")

