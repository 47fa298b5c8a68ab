"""User-defined OTFs from tables (paper Table 1, IBSM Secs. 3.2.6-7)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._metadata import described
from .spectral import is_lazy

__all__ = ["user_defined", "OUTSIDE_RULES"]

OUTSIDE_RULES = ("zero", "nan", "error")

_RADIAL = "_table_frequency"
_FX, _FY = "_table_fx", "_table_fy"


def _check_axis(table, dim):
    coord = table[dim]
    values = np.asarray(coord.values, dtype=float)
    if values.size < 2 or not np.all(np.diff(values) > 0):
        raise ValueError(f"table coordinate {dim!r} must hold at least 2 increasing values")
    return values


def _check_outside(name, value, low, high):
    if is_lazy(value):
        value = value.compute()
    arr = np.asarray(value)
    if arr.size and (np.nanmin(arr) < low or np.nanmax(arr) > high):
        raise ValueError(
            f"{name} outside the table range [{low!r}, {high!r}]: "
            f"[{np.nanmin(arr)!r}, {np.nanmax(arr)!r}] (use outside='zero' or 'nan')"
        )


def _radial_interp_kernel(rho, table, nodes, fill):
    """Piecewise-linear interpolation of ``table[..., k]`` at ``rho`` (plain numpy).

    ``rho`` and ``table[..., 0]`` broadcast against each other; ``nodes`` is increasing.
    Outside ``[nodes[0], nodes[-1]]`` the result is ``fill``.
    """
    upper = np.clip(np.searchsorted(nodes, rho, side="right"), 1, nodes.size - 1)
    x0, x1 = nodes[upper - 1], nodes[upper]
    shape = np.broadcast_shapes(rho.shape, table.shape[:-1])
    table = np.broadcast_to(table, shape + table.shape[-1:])
    upper = np.broadcast_to(upper, shape)[..., None]
    y0 = np.take_along_axis(table, upper - 1, axis=-1)[..., 0]
    y1 = np.take_along_axis(table, upper, axis=-1)[..., 0]
    out = y0 + (y1 - y0) / (x1 - x0) * (rho - x0)
    inside = (rho >= nodes[0]) & (rho <= nodes[-1])
    return np.where(inside, out, fill)


def user_defined(fx, fy, table, outside="zero"):
    r"""OTF interpolated from a user table over radial frequency or over (fx, fy).

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    table : xr.DataArray
        Tabulated OTF (real or complex). Either with a dimension ``frequency``
        (radial frequency :math:`\rho \ge 0`, increasing) for a rotationally
        symmetric OTF, or with dimensions ``fx`` and ``fy`` (each increasing).
        Any other dimension (e.g. ``wavelength``) is kept. [1]
    outside : {"zero", "nan", "error"}
        Value where the requested frequency lies outside the table:
        ``"zero"`` (default; a tabulated OTF normally ends at its cutoff),
        ``"nan"``, or ``"error"`` (raise ``ValueError``; this computes the
        frequency range of dask inputs).

    Returns
    -------
    xr.DataArray
        OTF, broadcast over the frequency dimensions and the table's other
        dimensions. [1]

    Notes
    -----
    Piecewise-linear interpolation in frequency (bilinear for an (fx, fy)
    table) of the real and imaginary parts:

    .. math:: H(\rho) = H_i + (H_{i+1} - H_i)\frac{\rho - \rho_i}{\rho_{i+1} - \rho_i},
              \quad \rho = \sqrt{f_x^2 + f_y^2}
    """
    if outside not in OUTSIDE_RULES:
        raise ValueError(f"outside must be one of {OUTSIDE_RULES}; got {outside!r}")
    if not isinstance(table, xr.DataArray):
        raise ValueError("table must be an xr.DataArray with dim 'frequency' or dims 'fx', 'fy'")
    fill = 0.0 if outside == "zero" else np.nan
    kwargs = {"fill_value": fill, "bounds_error": False}
    if "frequency" in table.dims:
        values = _check_axis(table, "frequency")
        if values[0] < 0:
            raise ValueError("table coordinate 'frequency' must be >= 0 (radial frequency)")
        rho = np.hypot(fx, fy)
        if outside == "error":
            _check_outside("radial frequency", rho, values[0], values[-1])
        out = xr.apply_ufunc(
            _radial_interp_kernel, rho, table.drop_vars("frequency").rename(frequency=_RADIAL),
            input_core_dims=[[], [_RADIAL]], kwargs={"nodes": values, "fill": fill},
            dask="parallelized", output_dtypes=[np.result_type(table.dtype, float)],
        )
    elif "fx" in table.dims and "fy" in table.dims:
        x, y = _check_axis(table, "fx"), _check_axis(table, "fy")
        if outside == "error":
            _check_outside("fx", fx, x[0], x[-1])
            _check_outside("fy", fy, y[0], y[-1])
        t = table.rename({"fx": _FX, "fy": _FY})
        fx_b, fy_b = xr.broadcast(fx, fy)
        out = t.interp({_FX: fx_b, _FY: fy_b}, method="linear", kwargs=kwargs)
        out = out.drop_vars([_FX, _FY], errors="ignore")
    else:
        raise ValueError(
            f"table must have dimension 'frequency' or dimensions 'fx' and 'fy'; got {table.dims}"
        )
    return described(out, user_defined)
