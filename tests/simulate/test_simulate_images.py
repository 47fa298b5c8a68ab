"""simulate_images in batches (issue 26): images of one shape, dtype and GSD simulated as
one stack give exactly the results of simulate_image on each image alone.

The reference of every comparison is ``xbsm.simulate_image`` on the one image with its
seed (the per-image path that the pyBSM parity and closed-form tests of
tests/simulate/test_simulate.py check); the batched path must reproduce it to the bit.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from test_tiles import GSD, SCENARIO, SENSOR, scene

import xbsm
from xbsm.simulate import image as image_module
from xbsm.simulate import simulate_images


def _rgb(k, rows=90, cols=120, alpha=False):
    planes = [scene(rows, cols, seed=k + j) for j in range(4 if alpha else 3)]
    return np.clip(np.stack(planes, axis=-1), 0, 255).astype(np.uint8)


def _mixed():
    """Three grey 80 x 80, two RGB, two RGBA, one grey of another size, one of another
    dtype and one DataArray: four batches of several images and three alone."""
    grey = [scene(80, 80, seed=k) for k in range(3)]
    return [grey[0], _rgb(0), grey[1], _rgb(5), _rgb(1, alpha=True), scene(100, 70),
            _rgb(7, alpha=True), grey[2], grey[2].astype(np.float32),
            xr.DataArray(scene(80, 80, seed=9), dims=("y", "x"), name="named")]


@pytest.fixture
def calls(monkeypatch):
    """The stacks simulate_images hands to the per-call simulation: their image counts."""
    sizes = []
    real = image_module._simulate

    def counting(image, *args, **kwargs):
        sizes.append(image.sizes.get("stack", 1) if hasattr(image, "sizes") else 1)
        return real(image, *args, **kwargs)

    monkeypatch.setattr(image_module, "_simulate", counting)
    return sizes


@pytest.mark.parametrize("method", ["accurate", "fast", "pybsm"])
def test_a_batch_equals_each_image_simulated_alone(method, calls):
    images = _mixed()
    seeds = [7 * k + 1 for k in range(len(images))]
    out = simulate_images(images, SENSOR, SCENARIO, gsd=GSD, seeds=seeds, method=method)
    # grey 80 x 80 float64 (3 images), RGB (2), RGBA (2); the rest alone
    assert sorted(calls) == [1, 1, 1, 2, 2, 3]
    calls.clear()
    for image, seed, result in zip(images, seeds, out, strict=True):
        alone = xbsm.simulate_image(image, SENSOR, SCENARIO, gsd=GSD, seed=seed,
                                    method=method)
        if np.ndim(image) == 3 and np.shape(image)[-1] == 4:
            # a list labels an RGBA array's channels (R, G, B kept); a lone array has none
            assert list(result.band.values) == ["R", "G", "B"]
            result = result.drop_vars("band")
        # every variable, coordinate and attribute, to the bit (the sweep over two
        # ground ranges numbers the noise streams as the call alone does)
        xr.testing.assert_identical(result, alone)


def test_images_of_a_batch_get_their_own_noise():
    image = scene(80, 80)
    out = simulate_images([image, image, image], SENSOR, SCENARIO, gsd=GSD, seeds=[1, 2, 1],
                          outputs=("noisy",))
    assert np.array_equal(out[0].noisy, out[2].noisy, equal_nan=True)
    assert not np.array_equal(out[0].noisy, out[1].noisy, equal_nan=True)


def test_batches_are_split_by_size_and_give_the_same_results(monkeypatch, calls):
    images = [scene(80, 80, seed=k) for k in range(5)]
    whole = simulate_images(images, SENSOR, SCENARIO, gsd=GSD, seed=4, outputs=("counts",))
    monkeypatch.setattr(image_module, "BATCH_PIXELS", 2 * 80 * 80)
    calls.clear()
    split = simulate_images(images, SENSOR, SCENARIO, gsd=GSD, seed=4, outputs=("counts",))
    assert calls == [2, 2, 1]
    for a, b in zip(whole, split, strict=True):
        xr.testing.assert_identical(a, b)


def test_images_larger_than_a_tile_are_simulated_alone_in_tiles(calls):
    images = [scene(150, 120, seed=k) for k in range(2)]
    out = simulate_images(images, SENSOR, SCENARIO, gsd=GSD, seed=2, noise=False,
                          tile_size=64, outputs=("blurred",))
    assert calls == [1, 1]
    tiled = xbsm.simulate_image(images[1], SENSOR, SCENARIO, gsd=GSD, noise=False,
                                tile_size=64, outputs=("blurred",))
    # equal but for the attributes (the seed differs; not Dataset.drop_attrs: xarray
    # 2023.12, the floor, lacks it)
    xr.testing.assert_equal(out[1], tiled)


def test_the_seeds_are_checked():
    images = [scene(80, 80)] * 2
    with pytest.raises(ValueError, match=r"seeds must give one seed per image \(2\); got 1"):
        simulate_images(images, SENSOR, SCENARIO, gsd=GSD, seeds=[1])
    with pytest.raises(ValueError, match=r"seeds\[1\] must be a non-negative whole number"):
        simulate_images(images, SENSOR, SCENARIO, gsd=GSD, seeds=[1, -2])
    with pytest.raises(ValueError, match="seed .* or seeds .*, not both"):
        simulate_images(images, SENSOR, SCENARIO, gsd=GSD, seed=1, seeds=[1, 2])


def test_the_upsampled_warning_is_the_callers_when_asked(recwarn):
    # 20 mm reference pixels are coarser than the camera's (about 12 mm at 4 km)
    images = [scene(80, 80, seed=k) for k in range(3)]
    out = simulate_images(images, SENSOR, SCENARIO, gsd=0.02, seed=1, warn_upsampled=False)
    assert not [w for w in recwarn if "finely sampled" in str(w.message)]
    assert all(bool(xbsm.flags.has_flag(r.flags, "upsampled").any()) for r in out)
