"""User-defined OTF tables."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar

from xbsm.otf.user import user_defined

RHO = np.linspace(0, 1e6, 11)


def radial_table(values=None, **extra):
    values = 1 - RHO / 1e6 if values is None else values
    return xr.DataArray(values, dims="frequency", coords={"frequency": RHO}, **extra)


def test_radial_table_is_interpolated_linearly_in_radial_frequency():
    fx, fy = polar(np.linspace(0, 1e6, 37))
    out = user_defined(fx, fy, radial_table())
    np.testing.assert_allclose(out, 1 - np.hypot(fx, fy) / 1e6, atol=1e-15)
    assert set(out.dims) == {"frequency", "orientation"}
    assert out.attrs["units"] == "1"


def test_outside_rules():
    fx, fy = polar([0.5e6, 2e6], orientation=[0.0])
    table = radial_table()
    np.testing.assert_allclose(user_defined(fx, fy, table).squeeze(), [0.5, 0.0])
    assert np.isnan(user_defined(fx, fy, table, outside="nan").squeeze()[1])
    with pytest.raises(ValueError, match="outside the table"):
        user_defined(fx, fy, table, outside="error")


def test_extra_table_dims_and_complex_values_are_kept():
    wl = xr.DataArray([0.5e-6, 1e-6], dims="wavelength")
    table = radial_table() * xr.DataArray([1.0, 0.5j], dims="wavelength", coords={"wavelength": wl})
    fx, fy = polar(np.linspace(0, 1e6, 5))
    out = user_defined(fx, fy, table)
    assert set(out.dims) == {"frequency", "orientation", "wavelength"}
    np.testing.assert_allclose(
        out.isel(wavelength=1), 0.5j * (1 - np.hypot(fx, fy) / 1e6), atol=1e-15
    )


def test_two_dimensional_table_is_bilinear():
    x = np.linspace(-1e6, 1e6, 21)
    y = np.linspace(-2e6, 2e6, 41)
    table = xr.DataArray(
        1 + 2e-7 * x[:, None] - 1e-7 * y[None, :], dims=("fx", "fy"), coords={"fx": x, "fy": y}
    )
    fx = xr.DataArray(np.linspace(-0.9e6, 0.9e6, 7), dims="fx")
    fy = xr.DataArray(np.linspace(-1.5e6, 1.5e6, 5), dims="fy")
    out = user_defined(fx, fy, table)
    np.testing.assert_allclose(out.transpose("fx", "fy"), 1 + 2e-7 * fx - 1e-7 * fy, atol=1e-14)


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 1e6, 20))
    check_lazy(user_defined, (fx.chunk(5), fy.chunk(5), radial_table()), (fx, fy, radial_table()))


@pytest.mark.parametrize(
    ("table", "outside", "match"),
    [
        (radial_table(), "clip", "outside"),
        (xr.DataArray([1.0, 0.5], dims="rho", coords={"rho": [0, 1]}), "zero", "dimension"),
        (radial_table(RHO[::-1] * 0 + 1).assign_coords(frequency=RHO[::-1]), "zero", "increasing"),
        (np.ones(3), "zero", "DataArray"),
    ],
)
def test_bad_tables_raise(table, outside, match):
    f = xr.DataArray([0.0])
    with pytest.raises(ValueError, match=match):
        user_defined(f, f, table, outside=outside)
