"""The xarray boundary of the numpy kernels (xbsm._kernels).

``apply_kernel`` is ``xr.apply_ufunc`` with arithmetic's join (without copies when the
indexes agree) and quiet floating-point exceptions; the reference for every case below
is ``xr.apply_ufunc`` itself with the same arguments (join "inner" as arithmetic,
attributes of the first argument), so each assertion says: the boundary gives xarray's
own answer.
"""

from __future__ import annotations

import dask.array as dsa
import numpy as np
import pytest
import xarray as xr

from xbsm._kernels import apply_kernel, apply_orchestrator, dataset
from xbsm._metadata import Output


def _coord(name, values, units):
    return xr.DataArray(values, dims=name, attrs={"units": units, "long_name": name})


def _reference(kernel, *args, core=None, outputs=((),), sizes=None):
    return xr.apply_ufunc(kernel, *args, input_core_dims=core,
                          output_core_dims=[list(o) for o in outputs], join="inner",
                          keep_attrs="override", dask="parallelized",
                          output_dtypes=[float] * len(outputs),
                          dask_gufunc_kwargs={"allow_rechunk": True,
                                              "output_sizes": dict(sizes or {})})


G = _coord("ground_range", [1.0, 2.0, 3.0], "m")
V = _coord("visibility", [5.0, 23.0], "km")
W = _coord("wavelength", [0.5e-6, 0.6e-6, 0.7e-6, 0.8e-6], "m")
A = xr.DataArray(np.arange(6.0).reshape(3, 2), dims=("ground_range", "visibility"),
                 coords={"ground_range": G, "visibility": V, "label": "olson"},
                 attrs={"units": "s"})
B = xr.DataArray(np.linspace(1.0, 2.0, 8).reshape(2, 4), dims=("visibility", "wavelength"),
                 coords={"visibility": V, "wavelength": W})
C = xr.DataArray([2.0, 3.0, 4.0], dims="ground_range", coords={"ground_range": G})


def _sum_last(a, b):
    return a * b.sum(axis=-1)


def _two(a, b):
    return a + b, a * b


def _spread(a):
    return np.stack([a, 2 * a, 3 * a], axis=-1)


CASES = {
    # elementwise, dims in order of first appearance, a scalar coordinate carried
    "elementwise": (np.multiply, (A, C), {}),
    # the second argument misses a leading and has a trailing dim of its own
    "middle_dims": (np.add, (C, B.isel(wavelength=0, drop=True)), {}),
    # a transposed argument is laid out in broadcast order
    "transposed": (np.subtract, (A, A.transpose()), {}),
    # a core dim reduced by the kernel
    "core": (_sum_last, (A, B), {"core": [[], ["wavelength"]]}),
    # two outputs
    "two_outputs": (_two, (A, 2.0), {"outputs": ((), ())}),
    # a new output dim with its size
    "new_dim": (_spread, (C,), {"outputs": [("giqe",)], "sizes": {"giqe": 3}}),
    # a Variable among DataArrays, and Variables alone
    "variable": (np.multiply, (A, C.variable), {}),
    "variables_only": (np.multiply, (A.variable, C.variable), {}),
}


@pytest.mark.parametrize("name", CASES)
def test_eager_results_equal_apply_ufunc(name):
    kernel, args, options = CASES[name]
    want = _reference(kernel, *args, **options)
    got = apply_kernel(kernel, *args, **options)
    for g, w in zip(got if isinstance(got, tuple) else (got,),
                    want if isinstance(want, tuple) else (want,), strict=True):
        xr.testing.assert_identical(g, w)


def test_plain_arguments_give_plain_results():
    # no labelled argument: the kernel's own return value, as xr.apply_ufunc gives
    assert apply_kernel(np.multiply, 2.0, 3.0) == 6.0


def test_misaligned_arguments_join_inner_as_arithmetic():
    # indexes that differ take xarray's path: the inner join of arithmetic (A * shifted)
    shifted = C.assign_coords(ground_range=[2.0, 3.0, 4.0])
    got = apply_kernel(np.multiply, A, shifted)
    xr.testing.assert_identical(got, (A * shifted).assign_attrs(A.attrs))
    assert list(got["ground_range"].values) == [2.0, 3.0]


def test_conflicting_coordinate_follows_xarray():
    # a non-index coordinate with two values: xarray's merge decides (drops it)
    other = C.assign_coords(label=("ground_range", ["a", "b", "c"]))
    xr.testing.assert_identical(apply_kernel(np.multiply, A, other),
                                _reference(np.multiply, A, other))


def test_dask_arguments_stay_lazy_and_equal_eager():
    lazy = A.chunk({"ground_range": 1})
    got = apply_kernel(np.multiply, lazy, C)
    assert got.chunks == ((1, 1, 1), (2,))
    xr.testing.assert_identical(got.compute(), apply_kernel(np.multiply, A, C))
    assert isinstance(got.data, dsa.Array)


def test_floating_point_exceptions_give_ieee_results_without_warnings():
    # pytest turns warnings into errors here: 1/0 must give inf silently, as arithmetic does
    zero = xr.DataArray([0.0, 1.0], dims="x")
    out = apply_kernel(np.divide, 1.0, zero)
    assert np.isinf(out[0]) and out[1] == 1.0


def test_dataset_equals_xarray_for_variables_sharing_coordinates(monkeypatch):
    # reference: xarray's own constructor on the same variables
    variables = {"a": A, "b": B, "c": C}
    want = xr.Dataset(variables)
    monkeypatch.setattr(xr.Dataset, "__init__", _only_from_variables(xr.Dataset.__init__))
    xr.testing.assert_identical(dataset(variables), want)


def _only_from_variables(init):
    def guarded(self, data_vars=None, coords=None, attrs=None):
        # the shortcut passes Variables, never DataArrays to be aligned
        assert all(not isinstance(v, xr.DataArray) for v in (data_vars or {}).values())
        init(self, data_vars, coords, attrs)
    return guarded


def test_dataset_keeps_the_described_coordinate():
    # a coordinate carried without attributes by one variable and with them by another:
    # the result describes it (the stages' outputs name their coordinates once)
    bare = C.assign_coords(ground_range=G.values)
    out = dataset({"bare": bare, "described": C})
    assert out["ground_range"].attrs == {"units": "m", "long_name": "ground_range"}


def test_dataset_leaves_disagreements_to_xarray():
    # different ground ranges: xarray's outer join, as xr.Dataset gives
    shifted = C.assign_coords(ground_range=[2.0, 3.0, 4.0])
    xr.testing.assert_identical(dataset({"a": C, "b": shifted}),
                                xr.Dataset({"a": C, "b": shifted}))


# ---- apply_orchestrator: a core dim that some arguments lack, spectral and band outputs ----


def _band_orchestrator(scale, spectrum, wavelength):
    """A spectral product and its band total (a plain numpy orchestrator)."""
    spectral = scale * spectrum * wavelength
    return {"spectral": spectral, "total": spectral.sum(axis=-1), "scale": scale * spectrum}


_BAND_OUTPUTS = {
    "spectral": Output("spectral", "1", "spectral", ("wavelength",),
                       inputs=("scale", "spectrum", "wavelength")),
    "total": Output("total", "1", "total", inputs=("scale", "spectrum", "wavelength")),
    "scale": Output("scale", "1", "scale", ("wavelength",), inputs=("scale", "spectrum")),
}


@pytest.mark.parametrize("spectrum", [B, 1.5], ids=["curve", "number"])
def test_orchestrator_core_dim_that_an_argument_lacks_is_a_length_one_axis(spectrum):
    # reference: the same equations in xarray arithmetic; A has no wavelength and reaches the
    # orchestrator with a length-1 axis; an output on wavelength that none of its inputs
    # varies along (a spectrum given as one number) is labelled without it
    band = ["wavelength"]
    out = apply_orchestrator(_band_orchestrator, _BAND_OUTPUTS, A, spectrum, W,
                             core=[band, band, band])
    expected = A * spectrum * W
    xr.testing.assert_allclose(out["spectral"], expected.transpose(*out["spectral"].dims))
    assert out["spectral"].dims == ("ground_range", "visibility", "wavelength")
    xr.testing.assert_allclose(out["total"], expected.sum("wavelength"))
    assert "wavelength" not in out["total"].dims
    scale = A * spectrum
    assert out["scale"].dims == scale.dims
    np.testing.assert_array_equal(out["scale"].values, scale.values)
