"""
Noise breakdown (paper Figure 4)
================================

Every noise term of one integration of the Olson camera (near-infrared band)
at 9 km altitude, 20 km ground range and 5 km visibility, the scenario of the
paper's Figure 4. :func:`xbsm.snr` returns the terms by name; their squares add
up to the total.
"""

import numpy as np

import xbsm

# %%
sensor = xbsm.examples.olson_sensor("nir")
scenario = xbsm.scenario(altitude=9000.0, ground_range=20e3, visibility=5.0,
                         platform_speed=100.0)
r = xbsm.snr(sensor, scenario)

for name in ("scene_noise", "path_noise", "self_emission_noise", "dark_current_noise",
             "shot_noise", "quantization_noise", "read_noise", "total_noise"):
    print(f"{name:22s} {float(r[name]):8.1f} {r[name].attrs['units']}")
print(f"contrast SNR {float(r.snr):.2f}")

# %%
# The shot noise is the root-sum-square of its four sources; the total adds
# the quantization, read and other noise.
total = np.sqrt(r.shot_noise**2 + r.quantization_noise**2 + r.read_noise**2
                + r.other_noise**2)
np.testing.assert_allclose(total, r.total_noise, rtol=1e-9)

# %%
ax = xbsm.plot.noise_breakdown(r)
ax.figure.set_size_inches(7, 4)
