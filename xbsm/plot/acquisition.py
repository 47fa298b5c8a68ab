"""The standard target-acquisition figure: P(task) against range, one line per task."""

from __future__ import annotations

import xarray as xr

from .axes import against_range


def probability_against_range(result: xr.Dataset, ax=None, **selection):
    """P(detect), P(recognize), P(identify) against ground range, from one result.

    Parameters
    ----------
    result : xr.Dataset
        From :func:`xbsm.target_acquisition`, swept over ``ground_range``.
    ax : matplotlib.axes.Axes, optional
        Default: a new pyplot figure.
    **selection
        One value of every other dimension (``target="vehicle"``, ...); a dimension of
        length one needs none.

    Returns
    -------
    matplotlib.axes.Axes
        Lines over ``task``; cells outside the model's stated range dashed, invalid
        ones (beyond the atmosphere database) not drawn (:func:`xbsm.plot.against_range`).
    """
    p = result["probability"].sel(selection)
    flags = result["flags"].sel(selection)
    others = [d for d in p.dims if d not in ("ground_range", "task") and p.sizes[d] == 1]
    p, flags = p.squeeze(others), flags.squeeze([d for d in others if d in flags.dims])
    ax = against_range(p.transpose("ground_range", "task"), ax=ax, hue="task", flags=flags)
    ax.set_ylim(0.0, 1.0)
    ax.set_ylabel("probability of the task")
    return ax
