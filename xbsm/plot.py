"""The standard figures: a quantity against range, the noise breakdown, the MTF breakdown.

Each function draws on a matplotlib Axes (a new one if none is given) and
returns it; nothing is shown or saved here.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

NOISE_TERMS = MappingProxyType({
    "total_noise": "total",
    "scene_noise": "scene",
    "path_noise": "path",
    "self_emission_noise": "emission / stray",
    "dark_current_noise": "dark current",
    "quantization_noise": "quantization",
    "read_noise": "readout",
})


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
        With a ``ground_range`` dimension [m].
    ax : matplotlib.axes.Axes, optional
    hue : str, optional
        Dimension drawn as separate lines.
    **kwargs
        Passed to ``Axes.plot``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    groups = [(None, da)] if hue is None else [(v, da.sel({hue: v})) for v in da[hue].values]
    for value, line in groups:
        label = kwargs.pop("label", None) if value is None else f"{hue} = {value:g}"
        ax.plot(line["ground_range"].values / 1e3, line.values, label=label, **kwargs)
    ax.set_xlabel("ground range [km]")
    name = da.attrs.get("long_name", da.name or "")
    units = da.attrs.get("units", "")
    ax.set_ylabel(f"{name} [{units}]" if units not in ("", "1") else name)
    if hue is not None:
        ax.legend()
    return ax


def noise_breakdown(snr: xr.Dataset, ax=None):
    """Bar chart of the noise terms of one scenario (paper Figure 4).

    Parameters
    ----------
    snr : xr.Dataset
        :func:`xbsm.snr` output reduced to a single scenario.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    values = [float(snr[name]) for name in NOISE_TERMS]
    ax.bar(range(len(values)), values, color="tab:blue")
    ax.set_xticks(range(len(values)), list(NOISE_TERMS.values()), rotation=45, ha="right")
    ax.set_ylabel("rms photoelectrons")
    ax.set_title(
        f"total photoelectrons {float(snr.target_photoelectrons):,.0f}; contrast "
        f"{float(snr.contrast_photoelectrons):,.0f}; well fill {100 * float(snr.well_fill):.0f}%",
        fontsize="small",
    )
    return ax


def mtf_breakdown(otf: xr.Dataset, focal_length: float, nyquist: float | None = None,
                  ax=None, orientation=None):
    """MTF of every component and of the system against image-plane frequency (paper Figure 5).

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
    cycles_per_mm = otf["frequency"].values / focal_length * 1e-3
    order = np.argsort(cycles_per_mm)
    for name, da in otf.data_vars.items():
        if "frequency" not in da.dims or name in ("system", "system_unfiltered"):
            continue
        ax.plot(cycles_per_mm[order], np.abs(da.values)[order], label=name.replace("_", " "))
    ax.plot(cycles_per_mm[order], np.abs(otf["system"].values)[order], "k", lw=2, label="system")
    if nyquist is not None:
        x = nyquist / focal_length * 1e-3
        ax.annotate("", xy=(x, 0), xytext=(x, 0.1), arrowprops={"facecolor": "black"})
    ax.set_xlim(0, cycles_per_mm.max())
    ax.set_ylim(0, None)
    ax.set_xlabel("spatial frequency at the focal plane [cycles/mm]")
    ax.set_ylabel("MTF")
    ax.legend(fontsize="small")
    return ax
