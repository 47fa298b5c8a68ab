"""One panel on a matplotlib Axes, for notebooks.

Each function draws on the Axes it is given (a new pyplot one if none) and
returns it; nothing is shown or saved here.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ._goal import _answer, _draw_goal_lines, _finish_goal_axes, _goal_legend
from ._layout import _x_values
from ._panels import _FrequencyAxis, _mtf_handles, _mtf_panel, _noise_panel
from ._style import _UNIT_TEXT, _units, _value_label


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




def range_performance(goal: xr.Dataset, x: str | None = None, hue: str | None = None,
                      ax=None):
    """Answer of :func:`xbsm.study.max_range` or ``min_parameter`` against a swept parameter.

    The range performance a specification asks for, e.g. the longest ground
    range at which NIIRS >= 5 as a function of aperture. ``max_range`` is drawn
    in km. Exact crossings are filled points on solid lines; answers that are
    only bounds are open markers with an arrow towards the true answer (circle:
    met up to the grid's edge, ``bound_at_grid_edge``; square: an invalid model
    cell ended the search, ``invalid_cell``); cells that never meet the
    requirement are not drawn and the legend names them.

    Parameters
    ----------
    goal : xr.Dataset
        Output of :func:`xbsm.study.max_range` or :func:`xbsm.study.min_parameter`:
        one answer variable and ``goal_flags``.
    x : str, optional
        Dimension on the x axis (default: the answer's first dimension).
    hue : str, optional
        Dimension drawn as separate lines (default: the one dimension left, if any).
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes

    Raises
    ------
    ValueError
        If ``goal`` is not such a Dataset, or has dimensions besides ``x`` and ``hue``
        (other than of length 1).
    """
    from ..study.goals import GOAL_FLAGS

    answer = _answer(goal, x, hue)
    xs, xlabel = _x_values(answer.da, answer.x)
    ax = _axes(ax)
    seen = _draw_goal_lines(ax, answer, xs, GOAL_FLAGS)
    _finish_goal_axes(ax, answer, xs, xlabel)
    _goal_legend(ax, answer, seen)
    return ax
