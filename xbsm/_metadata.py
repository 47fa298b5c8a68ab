"""One way to attach CF metadata to a result (private).

Every public output carries CF ``units`` and ``long_name`` (ARCHITECTURE.md,
Conventions). :func:`named` sets exactly those (plus any extras such as
``references``) and drops whatever attributes xarray carried over from the
operands: arithmetic keeps the attributes of its inputs, so without this a
photoelectron rate computed as ``wavelength / (h c) * ...`` inherits the
wavelength's ``standard_name: radiation_wavelength``. Coordinates keep their
own attributes. :func:`described` does the same with the first line of a
function's docstring as the ``long_name`` (the rule in :mod:`xbsm.otf`).
"""

from __future__ import annotations

import xarray as xr


def named(out, units: str, long_name: str, **extra):
    """``out`` with exactly the CF ``units``, ``long_name`` and ``extra`` attributes.

    Parameters
    ----------
    out : xr.DataArray or float
        A result. Anything that is not a DataArray (a plain float from plain
        float inputs) is returned unchanged.
    units : str
        UDUNITS string, e.g. ``"m"``, ``"count"``, ``"1"``.
    long_name : str
        What the quantity is.
    **extra : str
        Further attributes (e.g. ``references``).

    Returns
    -------
    xr.DataArray or float
        A shallow copy; the input's attributes are not modified.
    """
    if not isinstance(out, xr.DataArray):
        return out
    out = out.copy(deep=False)
    out.attrs = {"units": units, "long_name": long_name, **extra}
    return out


def long_name_of(func) -> str:
    """The first line of ``func``'s docstring, without its final full stop."""
    return func.__doc__.strip().splitlines()[0].rstrip(".")


def described(out, func, units: str = "1", **extra):
    """:func:`named` with the first docstring line of ``func`` as the ``long_name``."""
    return named(out, units, long_name_of(func), **extra)
