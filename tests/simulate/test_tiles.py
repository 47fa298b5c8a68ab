"""Large images in tiles (xbsm.simulate.tiles): exact statistics, seamless tiles, the guard."""

from __future__ import annotations

import dask.array as da
import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import flags as fl
from xbsm.simulate import camera, tiles

# The visible camera of tests/simulate/test_simulate.py: a 4 mm reference GSD is about
# 3 reference pixels per camera pixel at 3 km altitude and 4 km ground range.
SENSOR = xbsm.sensor(aperture_diameter=0.2, focal_length=4.0, pixel_pitch_x=10e-6,
                     wavelength_min=0.45e-6, wavelength_max=0.7e-6, integration_time=0.004,
                     read_noise=20.0, max_well=60000.0, bit_depth=12.0)
SCENARIO = xbsm.scenario(altitude=3000.0, ground_range=xr.DataArray([2000.0, 4000.0],
                                                                    dims="ground_range"),
                         visibility=23.0, cn2_at_1m=0.0)
GSD = 0.004


def scene(rows=300, cols=260, seed=0):
    """A bright rectangle on a dark ground, a textured corner and pixel noise (0-255)."""
    rng = np.random.default_rng(seed)
    img = np.full((rows, cols), 40.0)
    img[rows // 6: rows // 2, cols // 4: cols // 2] = 220.0
    img[rows // 2:, cols // 2:] = rng.integers(0, 256, (rows - rows // 2, cols - cols // 2))
    return img + rng.normal(0.0, 5.0, img.shape)


def simulate(image, **kwargs):
    kwargs.setdefault("gsd", GSD)
    kwargs.setdefault("seed", 0)
    return xbsm.simulate_image(image, SENSOR, SCENARIO, **kwargs)


def _stats(values, strip=997):
    stat, bits = tiles._image_statistics(
        values, kind="percentile", low=0.05, high=0.95, pixel_low=None, pixel_high=None,
        pixels=None, reflectances=None, strip=strip)
    return stat, bits


@pytest.mark.parametrize("kind", ["normal", "bytes", "lognormal", "ties", "nan"])
def test_streaming_percentiles_equal_numpy_nanpercentile_to_the_bit(kind):
    rng = np.random.default_rng(11)
    for n in (1, 2, 7, 5000, 150_000):
        if kind == "normal":
            values = rng.normal(size=n)
        elif kind == "bytes":
            values = rng.integers(0, 256, n).astype(float)
        elif kind == "lognormal":
            values = np.exp(5 * rng.normal(size=n))
        elif kind == "ties":
            values = np.round(rng.normal(size=n), 1)
        else:
            values = np.where(rng.random(n) < 0.01, np.nan, rng.normal(size=n))
        stat, _ = _stats(values.reshape(1, -1))
        p1, p2 = np.nanpercentile(values, (0.2, 99.8))  # the reference: numpy itself
        flat = not p2 > p1
        assert stat[0] == (0.0 if flat else p1)
        assert stat[1] == (0.95 - 0.05) / (1.0 if flat else p2 - p1)


def test_tiles_join_without_seams_whatever_the_tile_size():
    img = scene()
    results = [simulate(img, tile_size=t, noise=False) for t in (64, 100, 257)]
    for other in results[1:]:
        assert float(np.abs(other.blurred - results[0].blurred).max()
                     / np.abs(results[0].blurred).max()) < 1e-13
        assert other.attrs["seed"] == results[0].attrs["seed"]
    assert np.isnan(results[0].blurred).sum() == np.isnan(results[1].blurred).sum()


def test_tiled_differs_from_untiled_by_the_kernel_wings_only():
    """The untiled blur is the whole periodic kernel, the tiled one the middle
    (2 halo + 1)^2 samples, its wings beyond given the image's mean: their difference
    is the wings' energy beyond the halo times the image's contrast, and the untiled
    path's own boundary on this small image (tests/simulate/test_tiles_wings.py
    bounds it inside a large one; docs/simulate.md)."""
    img = scene()
    whole = simulate(img, noise=False)
    errors = []
    for tile in (64, 128):
        part = simulate(img, noise=False, tile_size=tile)
        assert np.array_equal(part.reflectance, whole.reflectance)  # the same mapping
        assert np.array_equal(part.ideal, whole.ideal)
        assert np.array_equal(np.isnan(part.blurred), np.isnan(whole.blurred))
        errors.append(float(np.abs(part.blurred - whole.blurred).max()
                            / np.abs(whole.blurred).max()))
    assert max(errors) < 4e-3
    # the wings beyond the untiled kernel's window hold 1.3 % of its energy
    wing = 1.0 - whole.psf.sum(("psf_y", "psf_x"))
    assert float(wing.max()) > max(errors)


def test_the_tiled_kernel_sums_to_one_less_its_wings_and_is_shared_by_every_image_size():
    small = simulate(scene(300, 260), noise=False, tile_size=64)
    large = simulate(scene(420, 380, seed=1), noise=False, tile_size=64)
    wing = 1.0 - small.psf.sum(("psf_y", "psf_x"))  # given the image's mean by the tiles
    assert float(wing.max()) <= tiles.TILE_WING_TOLERANCE and float(wing.min()) > 0
    assert np.array_equal(small.psf, large.psf)  # one kernel per optics and sampling
    finer = simulate(scene(300, 260), noise=False, tile_size=64, gsd=GSD / 2)
    assert finer.psf.shape != small.psf.shape


def test_flat_image_stays_flat_in_tiles_and_is_flagged():
    out = simulate(np.full((200, 180), 77.0), noise=False, tile_size=64)
    valid = out.blurred.isel(ground_range=0).dropna("y", how="all").dropna("x", how="all")
    np.testing.assert_allclose(valid, float(valid[0, 0]), rtol=1e-12)
    assert (fl.has_flag(out.flags, "image_flat")).all()


def test_nonfinite_pixels_are_flagged_and_filled_as_untiled():
    img = scene()
    img[5, 7] = np.nan
    img[100, 40] = np.inf
    part, whole = simulate(img, noise=False, tile_size=64), simulate(img, noise=False)
    assert fl.has_flag(part.flags, "image_nonfinite").all()
    # the fill is the image's mean reflectance, summed strip by strip: rounding only
    np.testing.assert_allclose(part.reflectance, whole.reflectance, rtol=1e-14, atol=0)
    assert np.isfinite(part.blurred.isel(ground_range=0, y=slice(0, 50), x=slice(0, 50))).all()


def test_tiled_noise_counts_and_dtype_follow_the_same_path():
    img = scene()
    part = simulate(img, tile_size=64, outputs=("counts",), counts_dtype="uint16")
    again = simulate(img, tile_size=64, outputs=("counts",), counts_dtype="uint16")
    assert part.counts.dtype == np.uint16 and np.array_equal(part.counts, again.counts)
    assert set(part.data_vars) >= {"counts", "flags", "scale_x"}
    assert "reflectance" not in part and "ideal" not in part


def test_noise_drawn_in_strips_is_the_one_call_stream():
    """camera draws Poisson then normal noise strip by strip; numpy's generator is
    sequential, so this equals one call over the image (the draws of the untiled code)."""
    rng = np.random.default_rng(3)
    mean = rng.uniform(-5.0, 3000.0, size=(1500, 1700))
    mean[5, 7] = np.nan
    out = camera._noise_kernel(mean, np.array(3.0), np.array(0), 12345)
    gen = np.random.default_rng(np.random.SeedSequence(12345, spawn_key=(0,)))
    valid = np.isfinite(mean)
    draw = gen.poisson(np.where(valid, np.maximum(mean, 0.0), 0.0)) + np.minimum(
        np.where(valid, mean, 0.0), 0.0)
    expected = np.where(valid, draw + gen.normal(0.0, 3.0, mean.shape), np.nan)
    assert mean.size > camera._STRIP  # more than one strip
    assert np.array_equal(out, expected, equal_nan=True)


def test_dask_tiled_equals_eager_and_stays_lazy(no_compute):
    img = xr.DataArray(np.stack([scene(), scene(seed=2)]), dims=("image", "y", "x"))
    lazy = simulate(img.chunk({"image": 1}), tile_size=64, noise=False)
    assert lazy.blurred.chunks is not None
    with pytest.raises(RuntimeError):
        lazy.blurred.values  # noqa: B018  (the no_compute scheduler refuses)


def test_dask_tiled_result_equals_eager():
    img = xr.DataArray(np.stack([scene(), scene(seed=2)]), dims=("image", "y", "x"))
    lazy = simulate(img.chunk({"image": 1}), tile_size=64, noise=False).compute()
    eager = simulate(img, tile_size=64, noise=False)
    assert np.array_equal(lazy.blurred, eager.blurred, equal_nan=True)


def test_a_lazy_image_too_large_for_memory_is_refused_before_allocation():
    # 100,000 x 100,000 float64: 80 GB of input, once asking for a 40 GiB OTF grid
    big = xr.DataArray(da.zeros((100_000, 100_000), chunks=(10_000, 10_000)),
                       dims=("y", "x"), name="mosaic")
    with pytest.raises(MemoryError, match=r"image 'mosaic' \(100000 x 100000 reference "
                       r"pixels\) needs about [\d.]+ GiB, [\d.]+ GiB available"):
        simulate(big, gsd=0.0005)  # camera images of up to 5546 x 5546 pixels


def test_an_eager_request_beyond_the_memory_available_is_refused(monkeypatch):
    monkeypatch.setattr(tiles, "available_memory", lambda: 1 << 20)
    with pytest.raises(MemoryError, match=r"image \(unnamed\) \(300 x 260 reference pixels\) "
                       r"needs about [\d.]+ GiB, 0.0 GiB available") as info:
        simulate(scene())
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("tile", [0, 63, 100.0, True, "big"])
def test_bad_tile_size_is_refused_naming_the_range(tile):
    with pytest.raises(ValueError, match=r"tile_size must be a whole number of pixels in "
                       r"\[64, inf\)"):
        simulate(scene(80, 80), tile_size=tile)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16, bool])
def test_integer_images_are_counted_once_to_the_same_percentiles(dtype):
    rng = np.random.default_rng(5)
    top = 2 if dtype is bool else 200
    values = rng.integers(0, top, (700, 900)).astype(dtype)
    stat, _ = _stats(values, strip=10_000)
    p1, p2 = np.nanpercentile(values.astype(float), (0.2, 99.8))  # numpy on floats
    assert stat[0] == p1 and stat[1] == (0.95 - 0.05) / (p2 - p1)


def test_a_list_of_mixed_sizes_keeps_one_kernel_per_sampling_and_warns_once():
    """Item 5 of issue 26: mixed sizes and channel counts in one run; a camera finer than
    some references is one warning for the run and a flag on each such image."""
    from xbsm.simulate import simulate_images

    rgb = np.stack([scene(90, 120), scene(90, 120, seed=3), scene(90, 120, seed=4)], axis=-1)
    images = [scene(80, 80), scene(120, 96), rgb, scene(100, 70), scene(300, 260)]
    # 20 mm reference pixels are coarser than the camera's (about 12 mm at 4 km): upsampled
    gsds = [GSD, GSD, GSD, 0.02, GSD]
    with pytest.warns(UserWarning, match=r"1 of 5 images \(indices 3\) are more finely "
                      r"sampled") as record:
        out = simulate_images(images, SENSOR, SCENARIO, gsd=gsds, seed=9, noise=False,
                              tile_size=256)
    assert sum("more finely sampled" in str(w.message) for w in record) == 1
    assert [bool(fl.has_flag(r.flags, "upsampled").any()) for r in out] == [
        False, False, False, True, False]
    assert "band" in out[2].reflectance.dims and out[2].counts.shape[-1] > 0
    # one kernel per optical state and reference sampling: the same GSD gives the same
    # kernel whatever the image's size (up to the aliasing of its far wings on each
    # image's own Fourier grid: 2.3e-6 of the peak measured here), the coarser reference
    # a narrower one in reference pixels
    same = [r.psf.isel(ground_range=0) for r in out[:3]]
    for other in same[1:]:
        half = min(other.sizes["psf_x"], same[0].sizes["psf_x"]) // 2
        a, b = (k.sel(psf_y=slice(-half, half), psf_x=slice(-half, half)) for k in
                (same[0], other))
        assert float(np.abs(a - b).max()) < 1e-5 * float(a.max())
    assert out[3].psf.sizes["psf_x"] < out[0].psf.sizes["psf_x"]
    # each image's seed is recorded and regenerates it alone
    alone = xbsm.simulate_image(images[1], SENSOR, SCENARIO, gsd=GSD, noise=False,
                                seed=int(out[1].attrs["seed"]))
    assert np.array_equal(alone.counts, out[1].counts, equal_nan=True)


def test_a_list_names_the_image_that_cannot_fit(monkeypatch):
    from xbsm.simulate import simulate_images

    monkeypatch.setattr(tiles, "available_memory", lambda: 1 << 20)
    named = xr.DataArray(scene(), dims=("y", "x"), name="harbour.png")
    with pytest.raises(MemoryError, match=r"image '#0' \(80 x 80"):
        simulate_images([scene(80, 80), named], SENSOR, SCENARIO, gsd=GSD)
    with pytest.raises(MemoryError, match=r"image 'harbour.png' \(300 x 260"):
        simulate_images([named], SENSOR, SCENARIO, gsd=GSD)


def test_a_tiled_rgb_stack_maps_all_channels_together_as_untiled():
    rng = np.random.default_rng(0)
    img = xr.DataArray(rng.integers(0, 256, (2, 150, 170, 3)).astype(np.uint8),
                       dims=("image", "y", "x", "band"))
    whole, part = simulate(img, noise=False), simulate(img, noise=False, tile_size=64)
    assert part.blurred.dims == whole.blurred.dims
    assert np.array_equal(part.reflectance, whole.reflectance)
    assert float(np.abs(part.blurred - whole.blurred).max() / np.abs(whole.blurred).max()) < 4e-3
