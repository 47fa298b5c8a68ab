"""Range performance and inverse questions over a finished sweep.

What procurement specifications ask: the longest ground range at which NIIRS
stays at or above a requirement (:func:`max_range`), the smallest aperture,
focal length or any parameter that raises NIIRS monotonically and meets the
requirement (:func:`min_parameter`), and how likely a predicted NIIRS meets a
requirement given the GIQE's own prediction error (:func:`probability_meets`).
All three work on every other swept dimension at once, lazily with dask, and
carry the reasons an answer is only a bound as flags.

Crossings are found on the sweep's own grid and interpolated linearly in the
quantity between the two grid values around the crossing, so the answer is as
fine as the grid (sweep the dimension finely where it matters).
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr
from scipy.special import ndtr

from .. import flags as fl

#: Flags of a crossing: why the answer is a bound, missing or extrapolated.
GOAL_FLAGS = MappingProxyType({
    "never_meets": 1,         # the requirement is not met anywhere on the grid: NaN
    "bound_at_grid_edge": 2,  # met at the grid's first (or up to its last) value: a bound
    "invalid_cell": 4,        # an invalid model cell (flags) ended the search: conservative
    "outside_calibration": 8,  # the answer lands on a cell outside the GIQE calibration
})

#: What each bit of :data:`GOAL_FLAGS` means (the ``goal_flags`` variable's ``flag_descriptions``).
GOAL_FLAG_DESCRIPTIONS = MappingProxyType({
    "never_meets": "the requirement is not met anywhere on the grid; the answer is NaN",
    "bound_at_grid_edge": "the requirement is met at the grid's first value (min_*) or up to "
                          "its last (max_range): the answer is only a bound",
    "invalid_cell": "an invalid model cell ended the search: the answer is conservative",
    "outside_calibration": "a model cell the answer is interpolated from is outside the GIQE "
                           "calibration or the NIIRS scale (its flags have a calibration bit): "
                           "the answer is extrapolated",
})

#: GIQE 5 standard error of prediction [NIIRS]: 0.35 on the 47-image validation set,
#: 0.28 on all 469 ratings (NGA, "General Image Quality Equation (GIQE) Version 5.0",
#: Harrington et al., 2015, Sec. 4); the report advises designing 0.1-0.2 NIIRS above a
#: specification.
GIQE5_STANDARD_ERROR = 0.35


def _crossing_kernel(values, meets, invalid, cells, *, coordinate, first_meeting,
                     calibration):
    """Crossing along the last axis: (answer, goal flags, landing cells' flags) elsewhere."""
    ok = meets & ~invalid
    if first_meeting:  # smallest coordinate at which the requirement is first met
        index = np.where(ok.any(-1), ok.argmax(-1), -1)
        at_end = index == 0
    else:  # last coordinate before the requirement first fails
        fails = ~ok
        first_fail = np.where(fails.any(-1), fails.argmax(-1), ok.shape[-1])
        index = first_fail - 1
        at_end = first_fail == ok.shape[-1]
    flags = np.where(index < 0, GOAL_FLAGS["never_meets"], 0)
    flags |= np.where(at_end & (index >= 0), GOAL_FLAGS["bound_at_grid_edge"], 0)
    answer, inner, other, used = _interpolate(values, coordinate, index, first_meeting, at_end)
    neighbour = np.clip(index + (1 if not first_meeting else -1), 0, ok.shape[-1] - 1)
    hit_invalid = np.take_along_axis(invalid, neighbour[..., None], -1)[..., 0]
    flags |= np.where(hit_invalid & ~at_end & (index >= 0), GOAL_FLAGS["invalid_cell"], 0)
    # the model flags of the cells the answer comes from: the grid value that meets the
    # requirement, and its neighbour when the answer is interpolated towards it
    landing = np.take_along_axis(cells, inner[..., None], -1)[..., 0]
    landing = landing | np.where(used, np.take_along_axis(cells, other[..., None], -1)[..., 0], 0)
    landing = np.where(index < 0, 0, landing)
    flags |= np.where((landing & calibration) != 0, GOAL_FLAGS["outside_calibration"], 0)
    return answer, flags.astype(np.int32), landing.astype(np.int32)


def _interpolate(values, coordinate, index, first_meeting, at_end):
    """Linear interpolation of the coordinate at the threshold (values already shifted).

    Returns the answer, the indices of the two grid values around it and where the
    second one enters the answer.
    """
    n = values.shape[-1]
    inner = np.clip(index, 0, n - 1)
    other = np.clip(inner + (-1 if first_meeting else 1), 0, n - 1)
    v0 = np.take_along_axis(values, inner[..., None], -1)[..., 0]
    v1 = np.take_along_axis(values, other[..., None], -1)[..., 0]
    c0, c1 = coordinate[inner], coordinate[other]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(np.isfinite(v1) & (v0 != v1), v0 / (v0 - v1), 0.0)
    t = np.clip(t, 0.0, 1.0)
    used = ~(at_end | ~np.isfinite(v1)) & (t > 0) & (index >= 0)
    answer = c0 + t * (c1 - c0)
    answer = np.where(at_end | ~np.isfinite(v1), c0, answer)
    return np.where(index < 0, np.nan, answer), inner, other, used


def _crossing(quantity, threshold, dim, flags, first_meeting, name, long_name):
    if dim not in quantity.dims:
        raise ValueError(f"dim {dim!r} is not a dimension of the quantity; it has {quantity.dims}")
    coordinate = quantity[dim].values
    if quantity.sizes[dim] < 2 or not np.all(np.diff(coordinate) > 0):
        raise ValueError(f"dim {dim!r} must have at least 2 increasing coordinate values")
    threshold = xr.DataArray(threshold) if not isinstance(threshold, xr.DataArray) else threshold
    cells = (flags if flags is not None else xr.zeros_like(quantity, dtype=np.int32))
    cells = cells.astype(np.int32)
    invalid = fl.is_invalid(cells) | quantity.isnull()
    shifted, invalid, cells = xr.broadcast(quantity - threshold, invalid, cells)
    shifted = shifted.where(~invalid, -np.inf)
    if shifted.chunks is not None or cells.chunks is not None:
        shifted, invalid, cells = (a.chunk({dim: -1}) for a in (shifted, invalid, cells))
    answer, goal_flags, landing = xr.apply_ufunc(
        _crossing_kernel, shifted, shifted >= 0, invalid, cells,
        kwargs={"coordinate": coordinate, "first_meeting": first_meeting,
                "calibration": fl.CALIBRATION_MASK},
        input_core_dims=[[dim], [dim], [dim], [dim]],
        output_core_dims=[[], [], []], dask="parallelized",
        output_dtypes=[float, np.int32, np.int32])
    units = quantity[dim].attrs.get("units", "")
    out = {
        name: answer.assign_attrs(units=units, long_name=long_name,
                                  ancillary_variables="goal_flags flags"
                                  if flags is not None else "goal_flags"),
        "goal_flags": goal_flags.assign_attrs(
            long_name="why the answer is a bound, missing or extrapolated", units="1",
            flag_masks=np.array(list(GOAL_FLAGS.values()), dtype=np.int32),
            flag_meanings=" ".join(GOAL_FLAGS),
            flag_descriptions="; ".join(f"{k}: {v}" for k, v in
                                        GOAL_FLAG_DESCRIPTIONS.items())),
    }
    if flags is not None:
        attrs = {**fl.flag_attrs(), **{k: v for k, v in flags.attrs.items()
                                       if k in ("flag_masks", "flag_meanings")}}
        out["flags"] = landing.assign_attrs(
            attrs, long_name=f"model flags of the cells the answer is interpolated from "
                             f"(OR of the {dim} values around the crossing)")
    return xr.Dataset(out, attrs={"threshold": str(threshold.values) if threshold.size == 1
                                  else "array"})


def max_range(niirs: xr.DataArray, threshold, dim: str = "ground_range",
              flags: xr.DataArray | None = None) -> xr.Dataset:
    """The longest range at which a quantity stays at or above a requirement.

    Scans ``dim`` from its first value: the answer lies between the last grid
    value that still meets ``threshold`` and the first that does not,
    interpolated linearly in the quantity.

    Parameters
    ----------
    niirs : xr.DataArray
        NIIRS (or any quantity that falls with range) over ``dim`` and any
        other dimensions (one answer for each of their combinations).
    threshold : float or xr.DataArray
        The requirement; a DataArray sweeps requirements.
    dim : str
        The range dimension (increasing coordinate).
    flags : xr.DataArray, optional
        The model's ``flags``: cells :func:`xbsm.flags.is_invalid` marks end
        the search (conservatively) and set ``invalid_cell``; a calibration
        bit on a cell the answer comes from sets ``outside_calibration``.
        Without it nothing says whether the answer is extrapolated: pass it.

    Returns
    -------
    xr.Dataset
        ``max_range`` (units of ``dim``; NaN where never met), ``goal_flags``
        (``never_meets``, ``bound_at_grid_edge``, ``invalid_cell``,
        ``outside_calibration``) and, with ``flags``, ``flags``: the model
        flags of the one or two grid cells the answer is interpolated from
        (decode with :func:`xbsm.flags.decode`).
    """
    return _crossing(niirs, threshold, dim, flags, False, "max_range",
                     f"longest {dim} meeting the requirement")


def min_parameter(niirs: xr.DataArray, threshold, dim: str,
                  flags: xr.DataArray | None = None) -> xr.Dataset:
    """The smallest value of a parameter at which a quantity first meets a requirement.

    For parameters that raise NIIRS as they grow (aperture diameter, focal
    length up to the sampling limit, ...): the answer lies between the first
    grid value that meets ``threshold`` and the one before it, interpolated
    linearly in the quantity.

    Parameters
    ----------
    niirs : xr.DataArray
        NIIRS (or any quantity) over ``dim`` and any other dimensions.
    threshold : float or xr.DataArray
        The requirement.
    dim : str
        The parameter's dimension (increasing coordinate).
    flags : xr.DataArray, optional
        The model's ``flags``; invalid cells never count as meeting, and a
        calibration bit on a cell the answer comes from sets
        ``outside_calibration``. Without it nothing says whether the answer is
        extrapolated: pass it.

    Returns
    -------
    xr.Dataset
        ``min_<dim>`` (units of ``dim``; NaN where never met), ``goal_flags``
        and, with ``flags``, ``flags`` (as :func:`max_range`).
    """
    return _crossing(niirs, threshold, dim, flags, True, f"min_{dim}",
                     f"smallest {dim} meeting the requirement")


def probability_meets(niirs: xr.DataArray, threshold,
                      standard_error: float = GIQE5_STANDARD_ERROR) -> xr.DataArray:
    """Probability that the true NIIRS meets a requirement, given the GIQE's error.

    The GIQE predicts the mean rating; treating the prediction error as normal
    with the published standard error, P = Phi((NIIRS - threshold) / sigma).

    Parameters
    ----------
    niirs : xr.DataArray
        Predicted NIIRS.
    threshold : float or xr.DataArray
        The requirement.
    standard_error : float
        Default 0.35 NIIRS, GIQE 5's standard error on its validation set
        (0.28 on all 469 ratings; NGA GIQE 5.0 report, 2015).

    Returns
    -------
    xr.DataArray
        ``probability_meets``, in [0, 1]. [1]
    """
    if not (np.isfinite(standard_error) and standard_error > 0):
        raise ValueError(f"standard_error must lie in (0, inf) NIIRS; got {standard_error!r}")
    z = (niirs - threshold) / standard_error
    p = xr.apply_ufunc(ndtr, z, dask="parallelized", output_dtypes=[float])
    return p.rename("probability_meets").assign_attrs(
        units="1", long_name="probability that NIIRS meets the requirement",
        standard_error=standard_error)
