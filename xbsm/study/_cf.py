"""CF details of a study result: what its flags describe, coordinates, compression.

:func:`cf_attributes` sets the attributes a CF reader (``ncdump -h``, a CF
checker, a notebook) needs beyond ``units`` and ``long_name``: each data
variable names the flag variable that describes it (``ancillary_variables``),
the flag variable says which of its bits apply to which variables and over
which dimensions, the ``giqe`` coordinate has units and a CF integer type.
:func:`set_encoding` records on each variable how it is to be written (no
``_FillValue`` on coordinates, optional zlib compression of the data
variables); :func:`cf_encoding` is the same as a ``to_netcdf(encoding=...)``
mapping for a writer that passes encodings explicitly.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import flags as fl

__all__ = ["FLAG_VARIABLES", "cf_attributes", "cf_encoding", "set_encoding"]

#: The flag variable of each group of a study's outputs: ``mtf_*`` variables are described
#: by ``mtf_flags`` (the system OTF's flags), every other variable by ``flags``.
FLAG_VARIABLES = ("flags", "mtf_flags")

#: netCDF4 encoding keys a writer may be handed (xarray's netCDF4 backend).
_ENCODING_KEYS = ("zlib", "complevel", "shuffle", "fletcher32", "contiguous", "chunksizes",
                  "_FillValue", "dtype", "compression")

_COORDINATE_ATTRS = {
    "band": {"long_name": "spectral band"},
    "orientation": {"long_name": "direction of the spatial-frequency slice (x or y)"},
    "giqe": {"long_name": "GIQE version", "units": "1"},
}


def _flag_variable(name: str) -> str:
    return "mtf_flags" if name.startswith("mtf_") else "flags"


def _bits(group) -> str:
    return ", ".join(group)


def _flags_comment(ds: xr.Dataset, name: str) -> str:
    """What the flag variable ``name`` describes: its dimensions and its bits, by variable."""
    described = [v for v in ds.data_vars if v not in FLAG_VARIABLES
                 and _flag_variable(v) == name]
    dims = ", ".join(ds[name].dims) or "no dimensions"
    text = (f"One value per cell of ({dims}); a variable with fewer dimensions (gsd has no "
            "visibility) is described by the flags of every cell it spans. "
            f"Describes: {', '.join(described)} (their ancillary_variables). ")
    if name == "mtf_flags":
        return text + ("Every bit applies to every mtf_ variable of the cell (decode with "
                       "xbsm.flags.decode).")
    per_giqe = "giqe" in ds[name].dims
    return text + (
        f"Invalid bits ({_bits(fl.INVALID)}) mean the values of the cell are NaN or may be "
        "wrong; notice bits "
        f"({_bits(fl.NOTICE)}) say how they were obtained; both apply to every variable of "
        "the cell" + (" and are the same for every giqe" if per_giqe else "") + ". "
        f"Calibration bits ({_bits(fl.CALIBRATION)}) apply to niirs only"
        + (", per GIQE version (the giqe of the same index)" if per_giqe else "")
        + ": the GIQE is extrapolated there. Decode with xbsm.flags.decode.")


def cf_attributes(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with the CF attributes of a study result (nothing is computed).

    - ``ancillary_variables`` on every data variable: ``"flags"``, or
      ``"mtf_flags"`` for the ``mtf_*`` variables (where those flag variables exist);
    - a ``comment`` on each flag variable saying over which dimensions it runs and
      which of its bits apply to which variables;
    - ``giqe`` as a 32-bit integer coordinate (CF 1.8 has no 64-bit integers) with
      ``units = "1"``; ``long_name`` on ``band`` and ``orientation``.

    Parameters
    ----------
    ds : xr.Dataset
        A study result (lazy or computed).

    Returns
    -------
    xr.Dataset
        A shallow copy; ``ds`` is not modified.
    """
    ds = ds.copy()
    for name in ds.data_vars:
        if name in FLAG_VARIABLES:
            continue
        flag_name = _flag_variable(name)
        if flag_name in ds.data_vars:
            ds[name].attrs["ancillary_variables"] = flag_name
    for name in FLAG_VARIABLES:
        if name in ds.data_vars:
            ds[name].attrs["comment"] = _flags_comment(ds, name)
    if "giqe" in ds.coords and ds["giqe"].dtype == np.int64:
        ds = ds.assign_coords(giqe=ds["giqe"].astype(np.int32))
    for name, attrs in _COORDINATE_ATTRS.items():
        if name in ds.coords:
            ds[name].attrs.update({k: v for k, v in attrs.items() if k not in ds[name].attrs})
    return ds


def set_encoding(ds: xr.Dataset, compress: int = 0) -> xr.Dataset:
    """``ds`` with each variable's ``.encoding`` saying how NetCDF should hold it.

    Coordinates get ``_FillValue = None`` (CF 2.5.1: a coordinate variable has no
    missing values, so it must not carry a fill value); with ``compress`` from 1 to 9,
    every data variable with a dimension gets ``zlib = True``, ``complevel = compress`` and
    ``shuffle = True`` (0: no compression).

    Parameters
    ----------
    ds : xr.Dataset
        A study result.
    compress : int
        zlib level, 0 (none) to 9.

    Returns
    -------
    xr.Dataset
        A shallow copy; ``ds`` is not modified.
    """
    if isinstance(compress, bool) or not isinstance(compress, int | np.integer) or not (
            0 <= compress <= 9):
        raise ValueError(f"compress must be a whole number from 0 (none) to 9; got {compress!r}")
    ds = ds.copy()
    for name in ds.coords:
        ds[name].encoding = {**ds[name].encoding, "_FillValue": None}
    for name in ds.data_vars:
        encoding = {k: v for k, v in ds[name].encoding.items()
                    if k not in ("zlib", "complevel", "shuffle", "compression")}
        if compress and ds[name].ndim:  # a scalar is stored whole, never compressed
            encoding.update(zlib=True, complevel=int(compress), shuffle=True)
        ds[name].encoding = encoding
    return ds


def cf_encoding(ds: xr.Dataset) -> dict:
    """The ``encoding=`` mapping of ``ds.to_netcdf`` for a study result.

    Every variable's own ``.encoding`` (netCDF4 keys only: compression as
    :func:`set_encoding` set it) and, on every coordinate, ``_FillValue = None``.
    ``to_netcdf(path, encoding=cf_encoding(ds))`` writes what :func:`set_encoding`
    recorded even where the variables' ``.encoding`` was lost on the way (a writer
    that rebuilds the variables).

    Parameters
    ----------
    ds : xr.Dataset
        A study result.

    Returns
    -------
    dict
        ``{variable name: {encoding key: value}}`` for every variable of ``ds``.
    """
    out = {}
    for name, var in ds.variables.items():
        encoding = {k: v for k, v in var.encoding.items() if k in _ENCODING_KEYS}
        if name in ds.coords:
            encoding["_FillValue"] = None
        out[name] = encoding
    return out
