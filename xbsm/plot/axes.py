"""One panel on a matplotlib Axes, for notebooks.

Each function draws on the Axes it is given (a new pyplot one if none) and
returns it; nothing is shown or saved here.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ._goal import draw_goal_lines, finish_goal_axes, goal_answer, goal_legend
from ._layout import mark_handles, run_starts, x_values
from ._panels import FrequencyAxis, mtf_handles, mtf_panel, noise_panel
from ._style import NIIRS_SCALE, UNIT_TEXT, units_of, value_label


def _axes(ax):
    """``ax``, or the Axes of a new pyplot figure with a layout engine (nothing cut when saved)."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(layout="constrained")
    return ax


def _is_niirs(da: xr.DataArray) -> bool:
    """Whether ``da`` is a NIIRS (by name or long name): its axis is the rating scale."""
    long_name = str(da.attrs.get("long_name", ""))
    return da.name == "niirs" or "NIIRS" in long_name or "Interpretability" in long_name


def against_range(da: xr.DataArray, ax=None, hue: str | None = None,
                  flags: xr.DataArray | None = None, **kwargs):
    """Line plot of a quantity against ground range in km, one line per ``hue`` value.

    A NIIRS (a variable named ``niirs``) is drawn on the rating scale,
    :data:`NIIRS_SCALE` (0-10), as the figures of ``xbsm plot`` are: values
    off the scale are not drawn, and a marker on the axis edge (with a legend
    entry) shows where each curve leaves it.

    Parameters
    ----------
    da : xr.DataArray
        With a ``ground_range`` dimension [m] and, besides ``hue``, no other.
    ax : matplotlib.axes.Axes, optional
        Default: a new pyplot figure with the constrained layout engine.
    hue : str, optional
        Dimension drawn as separate lines, labelled with their values and units.
    flags : xr.DataArray, optional
        The result's ``flags`` over the same cells (for a NIIRS, of the same
        ``giqe``): values outside the GIQE calibration are drawn dashed,
        invalid ones are not drawn (a cross marks where they start).
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
    scale = NIIRS_SCALE if _is_niirs(da) else None
    invalid, outside = _flag_masks(da, flags)
    lines = range(da.sizes[hue]) if hue is not None else [None]
    used = set()
    for k in lines:
        pick = {hue: k} if k is not None else {}
        line = da.isel(pick)
        x = line["ground_range"].values / 1e3
        text = value_label(da, hue, k) if k is not None else label
        used |= _line(ax, x, line.values, invalid.isel(pick).values,
                      outside.isel(pick).values, scale, text, kwargs)
    ax.set_xlabel("ground range [km]")
    name, units = da.attrs.get("long_name", da.name or ""), units_of(da)
    ax.set_ylabel(f"{name} [{UNIT_TEXT.get(units, units)}]" if units not in ("", "1")
                  else name)
    if scale is not None:
        ax.set_ylim(*scale)
    marks = mark_handles(used, scale or (np.nan, np.nan), "NIIRS" if scale else str(name),
                          calibrated=False)
    if hue is not None or label is not None or marks:
        handles, _ = ax.get_legend_handles_labels()
        ax.legend(handles=handles + marks, fontsize="small")
    return ax


def _flag_masks(da: xr.DataArray, flags) -> tuple[xr.DataArray, xr.DataArray]:
    """(invalid, outside calibration) like ``da`` from ``flags`` (all False without)."""
    from .. import flags as fl

    if flags is None:
        none = xr.zeros_like(da, dtype=bool)
        return none, none
    single = [d for d in flags.dims if d not in da.dims and flags.sizes[d] == 1]
    flags = flags.squeeze(single)
    if set(flags.dims) - set(da.dims):
        raise ValueError(f"flags has dims {flags.dims} that da {da.dims} lacks (select the "
                         "same giqe and cells first)")
    return tuple(group(flags).broadcast_like(da).transpose(*da.dims)
                 for group in (fl.is_invalid, fl.is_outside_calibration))


def _line(ax, x, y, invalid, outside, scale, label, kwargs) -> set:
    """One curve: solid, dashed where outside the calibration, not drawn off the scale.

    Returns the marks used (``"outside"``, ``"below"``, ``"above"``, ``"invalid"``).
    """
    y = np.asarray(y, dtype=float)
    lo, hi = scale if scale is not None else (-np.inf, np.inf)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(y) & ~invalid
        below, above = valid & (y < lo), valid & (y > hi)
    drawn = valid & ~below & ~above
    near = outside | np.concatenate([outside[1:], [False]]) | np.concatenate(
        [[False], outside[:-1]])
    (solid,) = ax.plot(x, np.where(drawn & ~outside, y, np.nan), **kwargs, label=label)
    color = solid.get_color()
    used = set()
    if (drawn & outside).any():
        style = {k: v for k, v in kwargs.items() if k not in ("ls", "linestyle", "color")}
        ax.plot(x, np.where(drawn & near, y, np.nan), "--", color=color, **style)
        used.add("outside")
    for name, mask, level, marker in (("below", below, lo, "v"), ("above", above, hi, "^"),
                                      ("invalid", ~valid, lo, "x")):
        starts = run_starts(mask)
        if starts.any() and np.isfinite(level):
            ax.plot(x[starts], np.full(starts.sum(), level), marker, color=color, ms=7,
                    clip_on=False, zorder=5)
            used.add(name)
    return used


def noise_breakdown(snr: xr.Dataset, ax=None, sensor: xr.Dataset | None = None):
    """Bar chart of the noise terms of one scenario (paper Figure 4).

    The self-emission and stray-light noise is one bar ("emission / stray"),
    or one bar per source that contributes (cold shield, optics, cold filter,
    stray light) when ``sensor`` is given or ``snr`` already carries the split
    (:func:`xbsm.noise.self_emission_noise_terms`).

    Parameters
    ----------
    snr : xr.Dataset
        :func:`xbsm.snr` or :func:`xbsm.niirs` output reduced to a single scenario.
    ax : matplotlib.axes.Axes, optional
        Default: a new pyplot figure with the constrained layout engine.
    sensor : xr.Dataset, optional
        The sensor of ``snr`` (:func:`xbsm.sensor`), to split the self-emission
        noise by source.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    if sensor is not None:
        snr = with_self_emission_split(snr, sensor)
    noise_panel(ax, snr, {})
    return ax


def with_self_emission_split(ds: xr.Dataset, sensor: xr.Dataset) -> xr.Dataset:
    """``ds`` with the self-emission noise split by source, if it has that noise.

    On the result's own ``wavelength`` grid (:func:`xbsm.snr`), else on 201
    wavelengths across the sensor's band (:func:`xbsm.niirs` has none): the split
    needs only each source's share, which both grids give to quadrature accuracy.
    """
    from .. import noise

    if "self_emission_noise" not in ds or all(n in ds for n in noise.SELF_EMISSION_SOURCES):
        return ds
    if "wavelength" in ds.coords and ds["wavelength"].ndim == 1:
        wavelength = ds["wavelength"]
    else:
        low, high = float(sensor["wavelength_min"]), float(sensor["wavelength_max"])
        values = np.linspace(low, high, 201)
        wavelength = xr.DataArray(values, dims="wavelength", coords={"wavelength": values})
    return ds.merge(noise.self_emission_noise_terms(ds["self_emission_noise"], sensor,
                                                    wavelength), compat="override")


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
    axis = FrequencyAxis(np.asarray(otf["frequency"].values, dtype=float) * to_mm,
                          "spatial frequency at the focal plane [cycles/mm]",
                          None if nyquist is None else nyquist * to_mm)
    ones = mtf_panel(ax, otf.drop_vars(["mtf_flags"], errors="ignore"), {}, axis)
    ax.legend(handles=mtf_handles([ax], ones), fontsize="small")
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

    answer = goal_answer(goal, x, hue)
    xs, xlabel = x_values(answer.da, answer.x)
    ax = _axes(ax)
    seen = draw_goal_lines(ax, answer, xs, GOAL_FLAGS)
    finish_goal_axes(ax, answer, xs, xlabel)
    goal_legend(ax, answer, seen)
    return ax
