"""The standard figures: NIIRS and SNR against range, the noise and MTF breakdowns.

:func:`standard_figures` draws the equivalents of the paper's Figures 2-5
(LeMaster & Eismann 2017, Sec. 3) from any study result and writes them as
PNG files; it is what ``xbsm plot`` and ``xbsm run`` call. It uses
matplotlib's Agg renderer on figures of its own and never touches pyplot or
the global backend.

:func:`against_range`, :func:`noise_breakdown` and :func:`mtf_breakdown` draw
one panel on a matplotlib Axes (a new pyplot one if none is given) for use in
a notebook; nothing is shown or saved there.

Validity flags are drawn, never hidden: a value outside the GIQE calibration
(:func:`xbsm.flags.is_outside_calibration`) is drawn dashed, a value that is
invalid (:func:`xbsm.flags.is_invalid`) or off the plotted scale (NIIRS
outside 0-10, SNR below 0.01) is not drawn, and a marker on the axis edge
shows where a curve leaves the scale or stops having valid values.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import textwrap
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
import xarray as xr

from . import __version__, flags

NOISE_TERMS = MappingProxyType({
    "total_noise": "total",
    "scene_noise": "scene",
    "path_noise": "path",
    "self_emission_noise": "emission / stray",
    "dark_current_noise": "dark current",
    "quantization_noise": "quantization",
    "read_noise": "readout",
    "other_noise": "other",
})
"""Noise variables of a result and their bar labels, in the order of the paper's Figure 4."""

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

_UNIT_TEXT = MappingProxyType({"m s-1": "m/s", "rad s-1": "rad/s", "s-1": "1/s",
                               "m-2/3": "m^-2/3", "W m-2 m-1": "W/(m² m)", "count": "electrons"})
_SCALES = MappingProxyType({
    "m": ((1e3, "km"), (1.0, "m"), (1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm")),
    "s": ((1.0, "s"), (1e-3, "ms"), (1e-6, "µs")),
    "rad": ((1.0, "rad"), (1e-3, "mrad"), (1e-6, "µrad")),
})
_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
           "tab:pink", "tab:gray", "tab:olive", "tab:cyan")
_KEY_SENSOR = MappingProxyType({"aperture_diameter": "aperture", "focal_length": "focal length",
                                 "pixel_pitch_x": "pixel pitch"})


# ---- units and labels ----------------------------------------------------------------------

def _scale(values, units: str) -> tuple[float, str]:
    """A display factor and unit for values in ``units`` (m -> km for kilometres, ...)."""
    steps = _SCALES.get(units)
    if not steps:
        return 1.0, _UNIT_TEXT.get(units, units)
    finite = np.abs(np.asarray(values, dtype=float))
    finite = finite[np.isfinite(finite) & (finite > 0)]
    largest = finite.max() if finite.size else 1.0
    for factor, text in steps:
        if largest >= factor:
            return factor, text
    return steps[-1]


def _quantity(value, units: str, like=None) -> str:
    """``value`` with its unit, e.g. ``"9 km"``, ``"100 m/s"``, ``"0.4"``.

    The unit is chosen for ``like`` (all values of a coordinate) if given, else for ``value``.
    """
    factor, text = _scale([value] if like is None else like, units)
    number = f"{float(value) / factor:.4g}"
    return number if units in ("", "1") else f"{number}\u00a0{text}"  # no line break inside


def _words(name: str) -> str:
    return name.replace("_", " ")


def _value_label(ds: xr.Dataset, dim: str, index: int) -> str:
    """Legend or panel label of one value along ``dim``, with units."""
    coord = ds[dim] if dim in ds.coords else None
    if coord is None:
        return f"{_words(dim)} #{index}"
    value = coord.values[index]
    if dim == "band":
        edges = [float(ds[name].values[index]) for name in ("wavelength_min", "wavelength_max")
                 if name in ds.coords and ds[name].dims == ("band",)]
        span = f" ({edges[0] * 1e9:.0f}-{edges[1] * 1e9:.0f}\u00a0nm)" if len(edges) == 2 else ""
        return f"{value} band{span}"
    paired = [name for name in ds.coords if name != dim and ds[name].dims == (dim,)]
    if coord.attrs.get("long_name") == "case number" and paired:
        return ", ".join(f"{_words(name)} = {_quantity(ds[name].values[index], _units(ds[name]))}"
                         for name in paired)
    if coord.dtype.kind in "iuf":
        return f"{_words(dim)} = {_quantity(value, _units(coord), coord.values)}"
    return f"{_words(dim)} = {value}"


def _units(da: xr.DataArray) -> str:
    """The ``units`` attribute, else those of the sensor or scenario parameter of that name."""
    if "units" in da.attrs:
        return str(da.attrs["units"])
    from .params import SCENARIO_SPECS, SENSOR_SPECS

    spec = SENSOR_SPECS.get(str(da.name)) or SCENARIO_SPECS.get(str(da.name))
    return spec.units if spec is not None else "1"


def _axis_label(name: str, units: str, values) -> tuple[float, str]:
    """Display factor and axis label ``"name [unit]"`` of a coordinate."""
    factor, text = _scale(values, units)
    return factor, f"{_words(name)} [{text}]" if units not in ("", "1") else _words(name)


# ---- the scenario, for titles --------------------------------------------------------------

@dataclass(frozen=True)
class _Context:
    """What a figure needs beyond the variables: title lines and the MTF frequency grid."""

    title: str
    frequency: np.ndarray | None


def _context(ds: xr.Dataset) -> _Context:
    """Title lines (study title, fixed parameters, method) and the MTF frequencies."""
    study = _study_of(ds)
    lines = [str(ds.attrs["title"])] if ds.attrs.get("title") else []
    fixed = []
    if study is not None:
        from .params import SCENARIO_SPECS, SENSOR_SPECS

        fixed += [f"{_words(k)} {_quantity(v, SCENARIO_SPECS[k].units)}"
                  for k, v in study.scenario.items() if np.ndim(v) == 0]
        fixed += [f"{text} {_quantity(study.sensor[k], SENSOR_SPECS[k].units)}"
                  for k, text in _KEY_SENSOR.items() if k in study.sensor and k not in ds.coords]
        if "band" not in ds.dims and {"wavelength_min", "wavelength_max"} <= set(study.sensor):
            fixed.append(f"band {study.sensor['wavelength_min'] * 1e9:.0f}-"
                         f"{study.sensor['wavelength_max'] * 1e9:.0f}\u00a0nm")
    if ds.attrs.get("xbsm_method"):
        fixed.append(f"method {ds.attrs['xbsm_method']}")
    if fixed:
        lines.append(", ".join(fixed))
    frequency = ds["frequency"].values if "frequency" in ds.coords else (
        study.mtf_frequency if study is not None else None)
    return _Context("\n".join(lines), frequency)


def _study_of(ds: xr.Dataset):
    """The study a result was made from (its ``xbsm_study`` attribute), if it still parses."""
    text = ds.attrs.get("xbsm_study")
    if not text:
        return None
    from .study import StudyError, parse

    try:
        return parse(str(text), "the result's xbsm_study attribute")
    except StudyError:
        return None


def _suptitle(fig, text: str) -> None:
    """The figure title, each line wrapped to the figure's width."""
    width = max(40, int(fig.get_figwidth() * 12))
    lines = [textwrap.fill(line, width) for line in text.strip().splitlines()]
    fig.suptitle("\n".join(lines), fontsize="medium")


# ---- faceting -------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Layout:
    """Which dimension goes where: x axis, line colour, panel column, panel row."""

    x: str
    hue: str | None
    col: str | None
    row: str | None


def _layout(da: xr.DataArray) -> _Layout | None:
    """Place every dimension of ``da`` (size-1 ones aside); None if nothing varies.

    The x axis is ``ground_range`` (else the first dimension); the lines are
    ``visibility`` (else the longest other dimension but ``band``); the panel
    columns ``band`` (else the next); one more dimension makes panel rows.

    Raises
    ------
    ValueError
        If a dimension is left over, or a faceted one has more than :data:`MAX_PANELS` values.
    """
    dims = [dim for dim in da.dims if da.sizes[dim] > 1]
    if not dims:
        return None
    x = "ground_range" if "ground_range" in dims else dims[0]
    rest = [dim for dim in dims if dim != x]

    def take(preferred):
        dim = preferred if preferred in rest else (rest[0] if rest else None)
        if dim is not None:
            rest.remove(dim)
        return dim

    # lines: visibility, else the longest dimension other than band; panels: band first
    others = sorted((d for d in rest if d != "band"), key=lambda d: -da.sizes[d])
    hue = take("visibility" if "visibility" in rest else (others[0] if others else None))
    col, row = take("band"), take(None)
    if rest:
        raise ValueError(
            f"cannot draw {da.name}: dimension {rest[0]!r} is left over (x axis {x!r}, lines "
            f"{hue!r}, panel columns {col!r}, panel rows {row!r}); select one value first, "
            f"e.g. ds.isel({rest[0]}=0)")
    for dim in (col, row):
        if dim is not None and da.sizes[dim] > MAX_PANELS:
            raise ValueError(
                f"cannot draw {da.name}: dimension {dim!r} has {da.sizes[dim]} values, one "
                f"panel each; at most {MAX_PANELS} are allowed (select some first)")
    return _Layout(x, hue, col, row)


def _grid(layout: _Layout, sizes, height: float = 3.8):
    """A constrained-layout Figure and its (rows x columns) array of axes."""
    from matplotlib.figure import Figure

    ncols = sizes[layout.col] if layout.col else 1
    nrows = sizes[layout.row] if layout.row else 1
    fig = Figure(figsize=(1.0 + 4.6 * ncols, 1.6 + height * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True)
    return fig, axes


def _panels(layout: _Layout, sizes):
    """(row index, column index, isel selector) of every panel."""
    rows = range(sizes[layout.row]) if layout.row else [None]
    cols = range(sizes[layout.col]) if layout.col else [None]
    for i, r in enumerate(rows):
        for j, c in enumerate(cols):
            selector = {d: k for d, k in ((layout.row, r), (layout.col, c)) if d is not None}
            yield i, j, selector


# ---- one line with its flags ----------------------------------------------------------------

def _run_starts(mask: np.ndarray) -> np.ndarray:
    """True at the first element of every run of True."""
    return mask & ~np.concatenate([[False], mask[:-1]])


def _draw_series(ax, x, y, invalid, outside, color, bounds) -> set:
    """One flagged curve: solid inside, dashed outside the calibration, markers where it leaves.

    Returns the set of styles used (``"inside"``, ``"outside"``, ``"below"``, ``"above"``,
    ``"invalid"``).
    """
    y = np.asarray(y, dtype=float)
    lo, hi = bounds
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(y) & ~invalid
        below, above = valid & (y < lo), valid & (y > hi)
    drawn = valid & ~below & ~above
    near = outside | np.concatenate([outside[1:], [False]]) | np.concatenate([[False],
                                                                                outside[:-1]])
    solid, dashed = drawn & ~outside, drawn & near
    ax.plot(x, np.where(solid, y, np.nan), "-", color=color, lw=1.6)
    ax.plot(x, np.where(dashed, y, np.nan), "--", color=color, lw=1.2)
    lonely = solid & ~np.concatenate([solid[1:], [False]]) & ~np.concatenate([[False],
                                                                               solid[:-1]])
    ax.plot(x[lonely], y[lonely], "o", color=color, ms=3)
    used = {name for name, mask in (("inside", solid), ("outside", drawn & outside))
            if mask.any()}
    for name, mask, level, marker in (("below", below, lo, "v"), ("above", above, hi, "^"),
                                      ("invalid", ~valid, lo, "x")):
        starts = _run_starts(mask)
        if starts.any():
            ax.plot(x[starts], np.full(starts.sum(), level), marker, color=color, ms=7,
                    clip_on=False, zorder=5)
            used.add(name)
    return used


def _mark_handles(used: set, bounds, quantity: str, calibrated: bool) -> list:
    """Legend entries explaining the line styles and markers actually used."""
    from matplotlib.lines import Line2D

    texts = {
        "outside": ("--", None, "outside the GIQE calibration (extrapolated)"),
        "below": ("none", "v", f"{quantity} falls below {bounds[0]:g} from here (not drawn)"),
        "above": ("none", "^", f"{quantity} exceeds {bounds[1]:g} from here (not drawn)"),
        "invalid": ("none", "x", "no valid value from here (NaN or invalid flag; not drawn)"),
    }
    handles = [Line2D([], [], color="k", lw=1.6, label="inside the GIQE calibration")
               ] if calibrated and "inside" in used else []
    for name in ("outside", "below", "above", "invalid"):
        if name in used:
            style, marker, label = texts[name]
            handles.append(Line2D([], [], color="k", ls=style, marker=marker, lw=1.2,
                                  label=label))
    return handles


# ---- Figures 2 and 3: a quantity against range ----------------------------------------------

@dataclass(frozen=True)
class _Curves:
    """A quantity to draw against its first dimension, with its flags and axis settings."""

    values: xr.DataArray
    invalid: xr.DataArray  # bool, like values
    outside: xr.DataArray  # bool, like values
    ylabel: str
    bounds: tuple
    log: bool
    calibrated: bool


def _hue_colors(da: xr.DataArray, hue: str | None):
    """Line colours, and (values, label) for a colour bar when there are too many for a legend."""
    n = da.sizes[hue] if hue else 1
    if n <= len(_COLORS):
        return _COLORS[:n], None
    from matplotlib import colormaps

    values, label = _x_values(da, hue)
    low, span = values.min(), np.ptp(values) or 1.0
    return [colormaps["viridis"]((v - low) / span) for v in values], (values, label)


def _x_values(da: xr.DataArray, dim: str) -> tuple[np.ndarray, str]:
    """Values and axis label of the x dimension (a paired sweep by its first parameter)."""
    if dim not in da.coords or da[dim].dtype.kind not in "iuf":
        return np.arange(da.sizes[dim], dtype=float), _words(dim)
    coord = da[dim]
    paired = [name for name in da.coords if name != dim and da[name].dims == (dim,)]
    if coord.attrs.get("long_name") == "case number" and paired:
        coord = da[paired[0]]
    factor, label = _axis_label(str(coord.name), _units(coord), coord.values)
    return np.asarray(coord.values, dtype=float) / factor, label


def _against(curves: _Curves, layout: _Layout, title: str):
    """One figure: a panel per facet, a line per hue value, flags drawn."""
    da = curves.values
    fig, axes = _grid(layout, da.sizes)
    x, xlabel = _x_values(da, layout.x)
    hues = list(range(da.sizes[layout.hue])) if layout.hue else [None]
    colors, bar = _hue_colors(da, layout.hue)
    used = set()
    for i, j, selector in _panels(layout, da.sizes):
        ax = axes[i, j]
        for k, color in zip(hues, colors, strict=True):
            pick = {**selector, **({layout.hue: k} if k is not None else {})}
            used |= _draw_series(ax, x, da.isel(pick).values, curves.invalid.isel(pick).values,
                                 curves.outside.isel(pick).values, color, curves.bounds)
        ax.set_title("; ".join(_value_label(da, d, k) for d, k in selector.items()),
                     fontsize="medium")
        ax.grid(True, alpha=0.3)
    _finish_axes(axes, curves, xlabel, x)
    marks = _mark_handles(used, curves.bounds, curves.ylabel.split(" (")[0], curves.calibrated)
    _legend(fig, da, layout, *((hues, colors) if bar is None else ([], [])), marks)
    if bar is not None:
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        values, label = bar
        fig.colorbar(ScalarMappable(Normalize(values.min(), values.max()), "viridis"),
                     ax=axes, label=label)
    _suptitle(fig, title)
    return fig


def _finish_axes(axes, curves: _Curves, xlabel: str, x) -> None:
    """Axis labels, scales and limits shared by every panel."""
    ax = axes[0, 0]
    if curves.log:
        ax.set_yscale("log")
        with np.errstate(invalid="ignore"):
            shown = curves.values.where(~curves.invalid & (curves.values >= curves.bounds[0]))
        any_shown = bool(shown.notnull().any())
        low, top = (float(shown.min()), float(shown.max())) if any_shown else (1.0, 10.0)
        if bool(shown.isnull().any()):  # markers sit on the floor
            low = curves.bounds[0]
        ax.set_ylim(max(curves.bounds[0], 10 ** np.floor(np.log10(low))),
                    10 ** np.ceil(np.log10(max(top, 10 * curves.bounds[0]))))
    else:
        ax.set_ylim(*curves.bounds)
    if np.isfinite(x).any() and np.nanmax(x) > np.nanmin(x):
        ax.set_xlim(np.nanmin(x), np.nanmax(x))
    for row in axes:
        row[0].set_ylabel(curves.ylabel)
    for ax in axes[-1]:
        ax.set_xlabel(xlabel)


def _legend(fig, da, layout: _Layout, hues, colors, marks: list) -> None:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=c, lw=2, label=_value_label(da, layout.hue, k))
               for k, c in zip(hues, colors, strict=True) if k is not None]
    handles += marks
    if handles:
        fig.legend(handles=handles, loc="outside lower center", fontsize="small",
                   ncols=min(3, len(handles)), frameon=False)


def _bits(ds: xr.Dataset, like: xr.DataArray, names=None, group=None) -> xr.DataArray:
    """Where ``ds.flags`` has any of the bits ``names`` (or the group test), like ``like``."""
    if "flags" not in ds:
        return xr.zeros_like(like, dtype=bool)
    bits = ds["flags"]
    if "giqe" in bits.dims and "giqe" not in like.dims:
        bits = bits.reduce(np.bitwise_or.reduce, dim="giqe")
    if group is not None:
        out = group(bits)
    else:
        out = xr.zeros_like(bits, dtype=bool)
        for name in names:
            out = out | flags.has_flag(bits, name)
    single = [d for d in out.dims if d not in like.dims and out.sizes[d] == 1]
    return out.squeeze(single).broadcast_like(like).transpose(*like.dims)


def _squeeze(ds: xr.Dataset, da: xr.DataArray) -> tuple[xr.DataArray, str]:
    """``da`` without its length-1 dimensions, and their values for the title."""
    single = [d for d in da.dims if da.sizes[d] == 1]
    labels = ", ".join(_value_label(ds, d, 0) for d in single)
    return da.squeeze(single), f": {labels}" if labels else ""


def _niirs_figures(ds: xr.Dataset, ctx: _Context):
    """Figure 2: NIIRS against range, one figure per GIQE version."""
    if "niirs" not in ds:
        return
    versions = list(ds["giqe"].values) if "giqe" in ds["niirs"].dims else [None]
    for version in versions:
        da = ds["niirs"].sel(giqe=version) if version is not None else ds["niirs"]
        da, single = _squeeze(ds, da)
        layout = _layout(da)
        if layout is None:
            return
        flagged = ds if version is None or "flags" not in ds else ds.sel(giqe=version)
        label = f"NIIRS (GIQE {int(version)})" if version is not None else "NIIRS"
        curves = _Curves(da, _bits(flagged, da, group=flags.is_invalid),
                         _bits(flagged, da, group=flags.is_outside_calibration), label,
                         NIIRS_SCALE, log=False, calibrated=True)
        name = f"figure2_niirs_giqe{int(version)}.png" if version is not None else (
            "figure2_niirs.png")
        yield name, _against(curves, layout, f"{label} against {_words(layout.x)}{single}\n"
                             f"{ctx.title}")


def _snr_figure(ds: xr.Dataset, ctx: _Context):
    """Figure 3: contrast SNR against range (log axis)."""
    if "snr" not in ds:
        return
    da, single = _squeeze(ds, ds["snr"])
    layout = _layout(da)
    if layout is None:
        return
    invalid = _bits(ds, da, names=("beyond_database", "snr_nonpositive"))
    curves = _Curves(da, invalid, xr.zeros_like(da, dtype=bool), "contrast SNR",
                     (SNR_FLOOR, np.inf), log=True, calibrated=False)
    yield "figure3_snr.png", _against(curves, layout, f"contrast SNR against "
                                      f"{_words(layout.x)}{single}\n{ctx.title}")


# ---- Figures 4 and 5: one scenario --------------------------------------------------------

_OWN_DIMS = ("giqe", "frequency", "orientation")


def _point(ds: xr.Dataset, targets, keep=()) -> tuple[dict, list]:
    """One scenario: the nearest value to each target, the first of any other dimension.

    Returns the ``isel`` selector and a description of each choice for the title.
    """
    selector, described = {}, []
    for dim in ds.dims:
        if dim in keep or dim in _OWN_DIMS:
            continue
        coord = ds[dim] if dim in ds.coords else None
        target = targets.get(dim)
        if coord is not None and target is not None and coord.dtype.kind in "iuf":
            index = int(np.nanargmin(np.abs(coord.values - target)))
            text = _quantity(coord.values[index], _units(coord), coord.values) + f" {_words(dim)}"
            if coord.values[index] != target:
                text += f" (nearest to {_quantity(target, _units(coord), coord.values)})"
        else:
            values = list(coord.values) if coord is not None else []
            index = values.index(target) if target in values else 0
            text = _value_label(ds, dim, index)
            if ds.sizes[dim] > 1 and target not in values:
                text += f" (first of {ds.sizes[dim]})"
        selector[dim] = index
        described.append(text)
    return selector, described


def _at(ds: xr.Dataset, name: str, selector: dict) -> xr.DataArray:
    da = ds[name]
    return da.isel({d: i for d, i in selector.items() if d in da.dims})


def _noise_panel(ax, ds: xr.Dataset, selector: dict) -> None:
    """Bars of the noise terms of one scenario, with its signal, contrast, well fill and SNR."""
    names = [name for name in NOISE_TERMS if name in ds and (
        name != "other_noise" or bool((ds[name] != 0).any()))]
    values = np.array([float(_at(ds, name, selector)) for name in names])
    ax.set_xticks(range(len(names)), [NOISE_TERMS[n] for n in names], rotation=40, ha="right")
    ax.set_ylabel("noise [rms electrons]")
    if not np.isfinite(values).any():
        ax.text(0.5, 0.5, "no valid values here\n(no atmosphere data)", ha="center",
                transform=ax.transAxes)
        return
    colors = ["0.3" if name == "total_noise" else "tab:blue" for name in names]
    bars = ax.bar(range(len(names)), np.nan_to_num(values), color=colors)
    ax.bar_label(bars, labels=[f"{v:.3g}" if v >= 1e-3 * np.nanmax(values) else "≈0"
                               for v in values], fontsize="small")
    ax.set_ylim(0, 1.35 * np.nanmax(values))
    facts = [(name, text, fmt) for name, text, fmt in (
        ("target_photoelectrons", "signal", "{:,.0f} electrons"),
        ("contrast_photoelectrons", "contrast", "{:,.0f} electrons"),
        ("well_fill", "well fill", "{:.0%}"), ("snr", "contrast SNR", "{:.3g}"),
        ("effective_integration_time", "integration time", "{:.3g} ms")) if name in ds]
    scale = {"effective_integration_time": 1e3}
    text = "\n".join(f"{label}: {fmt.format(scale.get(name, 1) * float(_at(ds, name, selector)))}"
                     for name, label, fmt in facts)
    ax.text(0.98, 0.97, text, transform=ax.transAxes, ha="right", va="top", fontsize="small",
            bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.7"})


def _noise_figure(ds: xr.Dataset, ctx: _Context):
    """Figure 4: the noise breakdown at 20 km ground range, 5 km visibility (or nearest)."""
    if "total_noise" not in ds:
        return
    from matplotlib.figure import Figure

    selector, described = _point(ds, NOISE_POINT, keep=("band",))
    bands = list(range(ds.sizes["band"])) if "band" in ds.dims else [None]
    fig = Figure(figsize=(1.0 + 4.6 * len(bands), 5.2), layout="constrained")
    axes = fig.subplots(1, len(bands), squeeze=False, sharey=True)[0]
    for ax, band in zip(axes, bands, strict=True):
        _noise_panel(ax, ds, {**selector, **({"band": band} if band is not None else {})})
        if band is not None:
            ax.set_title(_value_label(ds, "band", band), fontsize="medium")
        if ax is not axes[0]:
            ax.set_ylabel("")
    where = " at " + ", ".join(described) if described else ""
    _suptitle(fig, f"Noise breakdown{where} (total: root sum square of the terms)\n"
                   f"{ctx.title}")
    yield "figure4_noise.png", fig


def _pixel_angle(ds: xr.Dataset, selector: dict) -> float | None:
    """Angle one pixel subtends at one scenario (GSD over slant range), if known [rad]."""
    if "gsd" not in ds or "slant_range" not in ds:
        return None
    value = float(_at(ds, "gsd", selector)) / float(_at(ds, "slant_range", selector))
    return value if np.isfinite(value) and value > 0 else None


def _mtf_curves(ds: xr.Dataset, selector: dict) -> dict:
    """|OTF| of every component present and of the system at one scenario, by name."""
    names = [n for n in (*MTF_COMPONENTS, "system", "system_unfiltered") if f"mtf_{n}" in ds]
    curves = {}
    for name in names:
        line = _at(ds, f"mtf_{name}", selector)
        if line.dims != ("frequency",):
            raise ValueError(f"mtf_{name} at one scenario still has dims {line.dims}; "
                             "expected ('frequency',)")
        curves[name] = np.abs(line.values)
    return curves


@dataclass(frozen=True)
class _FrequencyAxis:
    """The x axis of an MTF panel: values, label, Nyquist, and an optional top axis."""

    x: np.ndarray
    label: str
    nyquist: float | None = None
    top: tuple | None = None  # (forward, inverse, label) for a secondary x axis


def _frequency_axis(ds: xr.Dataset, selector: dict, frequency: np.ndarray) -> _FrequencyAxis:
    """Cycles per pixel with Nyquist at 0.5 (cycles/mrad on top); cycles/mrad if no pixel."""
    pixel = _pixel_angle(ds, selector)
    if pixel is None:
        return _FrequencyAxis(frequency * 1e-3, "spatial frequency [cycles/mrad]")
    return _FrequencyAxis(frequency * pixel, "spatial frequency [cycles/pixel]", 0.5,
                          (lambda u: u / pixel * 1e-3, lambda m: m * 1e3 * pixel,
                           "[cycles/mrad]"))


def _mtf_panel(ax, ds: xr.Dataset, selector: dict, axis: _FrequencyAxis) -> list:
    """Component MTFs and the system MTF of one scenario, Nyquist marked.

    Returns the components left out because they are identically one.
    """
    x, curves = axis.x, _mtf_curves(ds, selector)
    bad = "mtf_flags" in ds and bool(flags.is_invalid(_at(ds, "mtf_flags", selector)))
    if bad or not np.isfinite(curves["system"]).any():
        ax.text(0.5, 0.5, "no valid MTF here\n(invalid flag)", ha="center",
                transform=ax.transAxes)
    ones = [n for n in MTF_COMPONENTS if n in curves and np.all(np.abs(curves[n] - 1) < 1e-12)]
    for k, name in enumerate(MTF_COMPONENTS):
        if name in curves and name not in ones:
            ax.plot(x, curves[name], color=_COLORS[k], lw=1.4, label=name)
    if "filter" in curves and "filter" not in ones and "system_unfiltered" in curves:
        ax.plot(x, curves["system_unfiltered"], "k--", lw=1.4, label="system without filter")
    ax.plot(x, curves["system"], "k", lw=2.4, label="system")
    ax.set_xlim(0, np.nanmax(x))
    ax.set_ylim(0, 1.02)
    ax.grid(True, alpha=0.3)
    ax.set_xlabel(axis.label)
    if axis.nyquist is not None:
        ax.annotate("Nyquist", xy=(axis.nyquist, 0.0), xytext=(axis.nyquist, 0.2), ha="center",
                    arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.5})
    if axis.top is not None:
        forward, inverse, label = axis.top
        ax.secondary_xaxis("top", functions=(forward, inverse)).set_xlabel(
            label, fontsize="small")
    return ones


def _mtf_handles(axes, ones) -> list:
    """Legend entries of every curve drawn in ``axes`` (once each) and of the ones left out."""
    from matplotlib.lines import Line2D

    handles = {}
    for ax in np.ravel(axes):
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    out = list(handles.values())
    if ones:
        out.append(Line2D([], [], ls="none", label=f"identically 1, not drawn: "
                          f"{', '.join(dict.fromkeys(ones))}"))
    return out


def _orientations(ds: xr.Dataset) -> list:
    """Orientation indices worth a row each: both only if some component differs between them."""
    if "orientation" not in ds.dims or ds.sizes["orientation"] == 1:
        return [None]
    for name in ds.data_vars:
        var = ds[name]
        if name.startswith("mtf_") and "orientation" in var.dims and not np.allclose(
                var.isel(orientation=0), var.isel(orientation=-1), equal_nan=True):
            return list(range(ds.sizes["orientation"]))
    return [0]


def _mtf_figure(ds: xr.Dataset, ctx: _Context):
    """Figure 5: the MTF breakdown at 0 and 100 km ground range, red band, 23 km visibility."""
    if "mtf_system" not in ds:
        return
    if ctx.frequency is None or len(ctx.frequency) != ds.sizes["frequency"]:
        raise ValueError("the mtf_* variables have no frequency coordinate [cycles/rad] and "
                         "the result has no study text to recover it from")
    from matplotlib.figure import Figure

    selector, described = _point(ds, {"band": "red", **MTF_POINT}, keep=("ground_range",))
    ranges = sorted({int(np.abs(ds["ground_range"].values - r).argmin()) for r in
                     MTF_RANGES}) if "ground_range" in ds.dims else [None]
    rows, ones = _orientations(ds), []
    fig = Figure(figsize=(1.0 + 4.8 * len(ranges), 2.0 + 3.8 * len(rows)), layout="constrained")
    axes = fig.subplots(len(rows), len(ranges), squeeze=False, sharey=True)
    for i, row in enumerate(rows):
        for j, gr in enumerate(ranges):
            pick = {**selector, **({"ground_range": gr} if gr is not None else {}),
                    **({"orientation": row} if row is not None else {})}
            axis = _frequency_axis(ds, pick, np.asarray(ctx.frequency, dtype=float))
            ones += _mtf_panel(axes[i, j], ds, pick, axis)
            axes[i, j].set_title(_mtf_title(ds, pick, row), fontsize="medium")
        axes[i, 0].set_ylabel("MTF")
    fig.legend(handles=_mtf_handles(axes, ones), loc="outside lower center", fontsize="small",
               ncols=4, frameon=False)
    if rows == [0]:
        described.append(f"{ds['orientation'].values[0]} orientation (x and y identical)")
    _suptitle(fig, f"MTF breakdown: {', '.join(described)}\n{ctx.title}")
    yield "figure5_mtf.png", fig


def _mtf_title(ds: xr.Dataset, pick: dict, row) -> str:
    parts = []
    if "ground_range" in pick:
        values = ds["ground_range"].values
        parts.append(_quantity(values[pick["ground_range"]], "m", values) + " ground range")
    if "effective_integration_time" in ds:
        seconds = float(_at(ds, "effective_integration_time", pick))
        parts.append(f"integration time {_quantity(seconds, 's')}")
    if row is not None and len(_orientations(ds)) > 1:
        orientation = ds["orientation"].values[row] if "orientation" in ds.coords else row
        parts.append(f"{orientation} orientation")
    return ", ".join(parts)


# ---- one panel on a given Axes (notebooks) -------------------------------------------------

def _axes(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    return ax


def against_range(da: xr.DataArray, ax=None, hue: str | None = None, **kwargs):
    """Line plot of a quantity against ground range in km, one line per ``hue`` value.

    Parameters
    ----------
    da : xr.DataArray
        With a ``ground_range`` dimension [m] and, besides ``hue``, no other.
    ax : matplotlib.axes.Axes, optional
    hue : str, optional
        Dimension drawn as separate lines, labelled with their values and units.
    **kwargs
        Passed to ``Axes.plot``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    extra = [d for d in da.dims if d not in ("ground_range", hue)]
    if "ground_range" not in da.dims or extra:
        raise ValueError(f"da must have dims ground_range and hue={hue!r} only; got {da.dims} "
                         "(select or facet the others first)")
    ax = _axes(ax)
    label = kwargs.pop("label", None)
    lines = range(da.sizes[hue]) if hue is not None else [None]
    for k in lines:
        line = da.isel({hue: k}) if k is not None else da
        ax.plot(line["ground_range"].values / 1e3, line.values, **kwargs,
                label=_value_label(da, hue, k) if k is not None else label)
    ax.set_xlabel("ground range [km]")
    name, units = da.attrs.get("long_name", da.name or ""), _units(da)
    ax.set_ylabel(f"{name} [{_UNIT_TEXT.get(units, units)}]" if units not in ("", "1")
                  else name)
    if hue is not None or label is not None:
        ax.legend()
    return ax


def noise_breakdown(snr: xr.Dataset, ax=None):
    """Bar chart of the noise terms of one scenario (paper Figure 4).

    Parameters
    ----------
    snr : xr.Dataset
        :func:`xbsm.snr` or :func:`xbsm.niirs` output reduced to a single scenario.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    _noise_panel(ax, snr, {})
    return ax


def mtf_breakdown(otf: xr.Dataset, focal_length: float, nyquist: float | None = None,
                  ax=None, orientation=None):
    """MTF of every component and of the system against image-plane frequency (paper Figure 5).

    Components that are identically one (no wavefront error, no filter) are not
    drawn; the legend names them.

    Parameters
    ----------
    otf : xr.Dataset
        :func:`xbsm.system_otf` output for one scenario, on ``frequency`` [cycles/rad].
    focal_length : float
        Converts object-space frequency to cycles/mm at the focal plane. [m]
    nyquist : float, optional
        Nyquist frequency, marked with an arrow. [cycles/rad]
    ax : matplotlib.axes.Axes, optional
    orientation : optional
        Which ``orientation`` to draw if the dataset has that dimension (default the first).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    if "orientation" in otf.dims:
        otf = otf.sel(orientation=orientation) if orientation is not None else otf.isel(
            orientation=0)
    otf = otf.rename({name: f"mtf_{name}" for name in otf.data_vars})
    to_mm = 1e-3 / focal_length
    axis = _FrequencyAxis(np.asarray(otf["frequency"].values, dtype=float) * to_mm,
                          "spatial frequency at the focal plane [cycles/mm]",
                          None if nyquist is None else nyquist * to_mm)
    ones = _mtf_panel(ax, otf.drop_vars(["mtf_flags"], errors="ignore"), {}, axis)
    ax.legend(handles=_mtf_handles([ax], ones), fontsize="small")
    ax.set_ylabel("MTF")
    return ax


# ---- writing ----------------------------------------------------------------------------------

def _png(fig) -> bytes:
    """``fig`` as a 256-colour PNG (a third of the RGBA size; line art looks the same)."""
    from PIL import Image, PngImagePlugin

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI)
    buffer.seek(0)
    image = Image.open(buffer).convert("RGB").quantize(256, dither=0)  # 0: no dithering
    info = PngImagePlugin.PngInfo()
    info.add_text("Software", f"xbsm {__version__}")
    out = io.BytesIO()
    image.save(out, format="png", optimize=True, pnginfo=info)
    return out.getvalue()


def _save(fig, path: Path) -> Path:
    """Write ``fig`` as PNG under a temporary name in the same directory, then rename it."""
    data = _png(fig)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return path


def standard_figures(ds: xr.Dataset, directory) -> list[Path]:
    """The equivalents of the paper's Figures 2-5 of a study result, as PNG files.

    Parameters
    ----------
    ds : xr.Dataset
        A loaded result of :func:`xbsm.study.run` (or the NetCDF file it wrote), of any study.
    directory : str or Path
        Where the files go; created if missing.

    Returns
    -------
    list of Path
        The files written, in this order and only where the variables exist:
        ``figure2_niirs_giqe<N>.png`` (NIIRS against ground range, or against the
        first swept dimension, one file per GIQE version), ``figure3_snr.png``,
        ``figure4_noise.png`` (at 20 km ground range and 5 km visibility, or the
        nearest) and ``figure5_mtf.png`` (at 0 and 100 km, red band, 23 km
        visibility, or the nearest; only with ``mtf_*`` variables).

    Raises
    ------
    ValueError
        If ``ds`` has none of the variables drawn, or a dimension that can be neither
        drawn nor faceted (lines per ``visibility``, panel columns per ``band``, one more
        dimension as panel rows, at most :data:`MAX_PANELS` panels per row or column).

    Notes
    -----
    Each file is written under a temporary name in ``directory`` and renamed into
    place when complete, so an interrupted call never leaves a truncated PNG.
    """
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"ds must be an xarray Dataset (a study result); got {type(ds).__name__}")
    if not any(name in ds for name in ("niirs", "snr", "total_noise", "mtf_system")):
        raise ValueError("ds has none of the variables of the standard figures (niirs, snr, "
                         "total_noise, mtf_system)")
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    ctx = _context(ds)
    written = []
    for figures in (_niirs_figures, _snr_figure, _noise_figure, _mtf_figure):
        for name, fig in figures(ds, ctx):
            written.append(_save(fig, directory / name))
    return written
