"""
A simulated image stack over range
==================================

One reference image seen by a camera at four ground ranges in one call of
:func:`xbsm.simulate_image` (paper Eq. 5-6): reflectance to photoelectrons,
the system blur, resampling to the camera's pixels, noise and the ADC. The
image is a small synthetic scene (bars and a disc) at 0.8 cm ground sampling,
so the script runs in seconds.
"""

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

import xbsm

# %%
# A 128 x 128 reference: three-bar groups of decreasing period and a disc.
y, x = np.mgrid[0:128, 0:128]
image = np.full((128, 128), 60.0)
for left, period in ((8, 8), (48, 6), (84, 4)):
    bars = (x >= left) & (x < left + 5 * period) & (y >= 12) & (y < 60)
    image[bars & (((x - left) // period) % 2 == 0)] = 200.0
image[(x - 64) ** 2 + (y - 94) ** 2 < 22**2] = 160.0
reference = xr.DataArray(image, dims=("y", "x"))
GSD = 0.008   # m, the reference's ground sample distance

# %%
sensor = xbsm.sensor(aperture_diameter=0.2, focal_length=4.0, pixel_pitch_x=10e-6,
                     wavelength_min=0.45e-6, wavelength_max=0.7e-6,
                     integration_time=0.004, read_noise=20.0, max_well=60000.0,
                     bit_depth=12.0)
ranges = xr.DataArray([2000.0, 4000.0, 8000.0, 16000.0], dims="ground_range")
scenario = xbsm.scenario(altitude=3000.0, ground_range=ranges, visibility=23.0)
result = xbsm.simulate_image(reference, sensor, scenario, gsd=GSD, seed=0)
print(result.gsd.round(3).to_pandas())

# %%
# Each range has its own image size (the images share one array, NaN beyond
# ``size_y`` x ``size_x``); each panel shows its image on the reference's
# ground extent.
fig, axes = plt.subplots(1, 5, figsize=(12, 2.9), layout="constrained")
axes[0].imshow(image, cmap="gray", extent=(0, 128 * GSD, 128 * GSD, 0))
axes[0].set_title(f"reference, GSD {GSD * 100:g} cm")
for ax, r in zip(axes[1:], result.ground_range.values):
    one = result.sel(ground_range=r)
    ny, nx = int(one.size_y), int(one.size_x)
    counts = one.counts.values[:ny, :nx]
    ax.imshow(counts, cmap="gray", extent=(0, 128 * GSD, 128 * GSD, 0))
    ax.set_title(f"{r / 1e3:g} km, GSD {float(one.gsd) * 100:.1f} cm")
for ax in axes:
    ax.set_xticks([])
    ax.set_yticks([])
