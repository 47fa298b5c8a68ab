"""One scenario of a result: its selection, the noise bars and the MTF curves.

:func:`nearest_point` picks the scenario nearest to the paper's (20 km ground range,
5 km visibility for the noise; 23 km visibility for the MTF);
:func:`noise_panel` and :func:`mtf_panel` draw it on one Axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from .. import flags
from ..noise import SELF_EMISSION_SOURCES
from ._style import COLORS, MTF_COMPONENTS, NOISE_TERMS, units_of, value_label, with_unit, words

# ---- choosing one scenario -----------------------------------------------------------------

_OWN_DIMS = ("giqe", "frequency", "orientation")


def nearest_point(ds: xr.Dataset, targets, keep=()) -> tuple[dict, list]:
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
            text = with_unit(coord.values[index], units_of(coord), coord.values) + f" {words(dim)}"
            if coord.values[index] != target:
                text += f" (nearest to {with_unit(target, units_of(coord), coord.values)})"
        else:
            values = list(coord.values) if coord is not None else []
            index = values.index(target) if target in values else 0
            text = value_label(ds, dim, index)
            if ds.sizes[dim] > 1 and target not in values:
                text += f" (first of {ds.sizes[dim]})"
        selector[dim] = index
        described.append(text)
    return selector, described


def select_at(ds: xr.Dataset, name: str, selector: dict) -> xr.DataArray:
    da = ds[name]
    return da.isel({d: i for d, i in selector.items() if d in da.dims})


# ---- the noise bars --------------------------------------------------------------------------

def noise_panel(ax, ds: xr.Dataset, selector: dict) -> None:
    """Bars of the noise terms of one scenario, with its signal, contrast, well fill and SNR."""
    names = [name for name in NOISE_TERMS if name in ds and (
        name != "other_noise" or bool((ds[name] != 0).any()))]
    split = [name for name in SELF_EMISSION_SOURCES if name in names]
    contributing = [name for name in split if float(select_at(ds, name, selector)) > 0]
    if contributing:  # one bar per source that contributes instead of their sum
        names = [n for n in names if n != "self_emission_noise" and (
            n not in split or n in contributing)]
    else:
        names = [n for n in names if n not in split]
    values = np.array([float(select_at(ds, name, selector)) for name in names])
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
    text = "\n".join(
        f"{label}: {fmt.format(scale.get(name, 1) * float(select_at(ds, name, selector)))}"
        for name, label, fmt in facts)
    ax.text(0.98, 0.97, text, transform=ax.transAxes, ha="right", va="top", fontsize="small",
            bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.7"})


# ---- the MTF curves --------------------------------------------------------------------------

def _pixel_angle(ds: xr.Dataset, selector: dict) -> float | None:
    """Angle one pixel subtends at one scenario (GSD over slant range), if known [rad]."""
    if "gsd" not in ds or "slant_range" not in ds:
        return None
    value = float(select_at(ds, "gsd", selector)) / float(select_at(ds, "slant_range", selector))
    return value if np.isfinite(value) and value > 0 else None


def _mtf_curves(ds: xr.Dataset, selector: dict) -> dict:
    """|OTF| of every component present and of the system at one scenario, by name."""
    names = [n for n in (*MTF_COMPONENTS, "system", "system_unfiltered") if f"mtf_{n}" in ds]
    curves = {}
    for name in names:
        line = select_at(ds, f"mtf_{name}", selector)
        if line.dims != ("frequency",):
            raise ValueError(f"mtf_{name} at one scenario still has dims {line.dims}; "
                             "expected ('frequency',)")
        curves[name] = np.abs(line.values)
    return curves


@dataclass(frozen=True)
class FrequencyAxis:
    """The x axis of an MTF panel: values, label, Nyquist, and an optional top axis."""

    x: np.ndarray
    label: str
    nyquist: float | None = None
    top: tuple | None = None  # (forward, inverse, label) for a secondary x axis


def frequency_axis(ds: xr.Dataset, selector: dict, frequency: np.ndarray) -> FrequencyAxis:
    """Cycles per pixel with Nyquist at 0.5 (cycles/mrad on top); cycles/mrad if no pixel."""
    pixel = _pixel_angle(ds, selector)
    if pixel is None:
        return FrequencyAxis(frequency * 1e-3, "spatial frequency [cycles/mrad]")
    return FrequencyAxis(frequency * pixel, "spatial frequency [cycles/pixel]", 0.5,
                          (lambda u: u / pixel * 1e-3, lambda m: m * 1e3 * pixel,
                           "[cycles/mrad]"))


def mtf_panel(ax, ds: xr.Dataset, selector: dict, axis: FrequencyAxis) -> list:
    """Component MTFs and the system MTF of one scenario, Nyquist marked.

    Returns the components left out because they are identically one.
    """
    x, curves = axis.x, _mtf_curves(ds, selector)
    bad = "mtf_flags" in ds and bool(flags.is_invalid(select_at(ds, "mtf_flags", selector)))
    if bad or not np.isfinite(curves["system"]).any():
        ax.text(0.5, 0.5, "no valid MTF here\n(invalid flag)", ha="center",
                transform=ax.transAxes)
    ones = [n for n in MTF_COMPONENTS if n in curves and np.all(np.abs(curves[n] - 1) < 1e-12)]
    for k, name in enumerate(MTF_COMPONENTS):
        if name in curves and name not in ones:
            ax.plot(x, curves[name], color=COLORS[k], lw=1.4, label=name)
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


def mtf_handles(axes, ones) -> list:
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


def orientation_rows(ds: xr.Dataset) -> list:
    """Orientation indices worth a row each: both only if some component differs between them."""
    if "orientation" not in ds.dims or ds.sizes["orientation"] == 1:
        return [None]
    for name in ds.data_vars:
        var = ds[name]
        if name.startswith("mtf_") and "orientation" in var.dims and not np.allclose(
                var.isel(orientation=0), var.isel(orientation=-1), equal_nan=True):
            return list(range(ds.sizes["orientation"]))
    return [0]

