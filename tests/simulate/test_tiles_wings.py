"""The tiled kernel's wings (issue 26): the halo chosen from the kernel's energy and the
wings beyond it given the image's mean, against the untiled result as the reference.

The untiled path (``tile_size`` larger than the image) multiplies the whole image's
spectrum by the OTF: no kernel truncation, the reference here. The tiled path keeps the
middle (2 halo + 1)^2 samples of the kernel; the halo doubles from 4 cores until the
wings beyond it hold at most ``TILE_WING_TOLERANCE`` (2e-3) of the kernel's sum, and
the missing sum is given the image's mean reflectance. What remains is the wings
times the image's departure from its mean (at most 2e-3 of the reflectance range), and
near the borders the untiled path's own boundary: it reflects the image by one core
only and its wings beyond that wrap around to the opposite side.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_tiles import scene, simulate

from xbsm.simulate import tiles


@pytest.fixture(scope="module")
def large():
    """A 1200 x 1200 scene untiled (the reference) and in 256-pixel tiles, noiseless."""
    img = scene(1200, 1200)
    whole = simulate(img, noise=False, outputs=("blurred", "psf"))
    part = simulate(img, noise=False, tile_size=256, outputs=("blurred", "psf"))
    return whole, part


def _max_difference(whole, part, border):
    """Largest |tiled - untiled| / the untiled peak, ``border`` camera pixels from the edges
    of each range's image (its valid size)."""
    peak = float(np.abs(whole.blurred).max())
    worst = 0.0
    for g in range(whole.sizes["ground_range"]):
        ref = whole.blurred.isel(ground_range=g).values
        ny, nx = int(whole.size_y[g]), int(whole.size_x[g])
        diff = np.abs(part.blurred.isel(ground_range=g).values - ref)[:ny, :nx]
        worst = max(worst, float(diff[border: ny - border, border: nx - border].max()))
    return worst / peak


def test_the_halo_grows_until_the_wings_hold_at_most_the_tolerance(large):
    _, part = large
    wing = 1.0 - part.psf.sum(("psf_y", "psf_x"))
    # the visible camera at 4 mm GSD: 4 cores (96 pixels) leave 0.5-0.7 % in the wings
    # (the aperture's Airy wings fall as 1 / radius), 384 pixels 0.14-0.20 %
    assert part.psf.sizes["psf_x"] == 2 * 384 + 1
    assert float(wing.max()) <= tiles.TILE_WING_TOLERANCE
    assert float(wing.min()) > 0.5 * tiles.TILE_WING_TOLERANCE


def test_tiled_equals_untiled_to_the_wings_times_the_contrast(large):
    whole, part = large
    assert np.array_equal(np.isnan(part.blurred), np.isnan(whole.blurred))
    # measured: 2.6e-4 of the peak 80 camera pixels from the borders (3.2e-3 before the
    # energy halo and the mean fill: a 96-pixel kernel normalised to sum one), 5.8e-4 at
    # 40, 1.1e-3 at 20
    assert _max_difference(whole, part, 80) < 4e-4
    assert _max_difference(whole, part, 40) < 8e-4
    # at the borders the untiled reference wraps its wings around the image: 4.1e-3
    assert _max_difference(whole, part, 0) < 5e-3


def test_a_flat_image_is_unchanged_by_the_mean_fill():
    # every pixel the mean: the wings' share is the same value, the image stays flat
    out = simulate(np.full((300, 280), 120.0), noise=False, tile_size=64,
                   reflectance=([0.0, 255.0], [0.0, 1.0]), outputs=("blurred",))
    whole = simulate(np.full((300, 280), 120.0), noise=False,
                     reflectance=([0.0, 255.0], [0.0, 1.0]), outputs=("blurred",))
    np.testing.assert_allclose(out.blurred, whole.blurred, rtol=1e-12)
