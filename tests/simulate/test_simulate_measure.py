"""Model, simulate, measure, compare: simulated images measured with xbsm.measure.

A slanted edge simulated by ``xbsm.simulate_image`` is measured with the ISO
12233 slanted-edge method and compared with the model's system MTF
(``xbsm.system_otf``, the x slice for a near-vertical edge) below Nyquist; a
flat simulated image's noise is compared with the model's prediction; the RER
measured on the simulated edge is compared with the RER of the NIIRS chain.
"""

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm.measure import flat_noise, slanted_edge_mtf

SCENARIO = xbsm.scenario(altitude=3000.0, ground_range=4000.0, visibility=23.0, cn2_at_1m=0.0)
SLANT = 5000.0  # m: altitude 3 km, ground range 4 km (flat-earth 5 km; curved 5.0007 km)
#: reference pixels per camera pixel: fine enough that the reference's own sampling costs
#: under 0.003 of MTF below the camera's Nyquist
RATIO = 4


def camera(pitch):
    return xbsm.sensor(aperture_diameter=0.2, focal_length=4.0, pixel_pitch_x=pitch,
                       wavelength_min=0.45e-6, wavelength_max=0.7e-6, integration_time=0.004,
                       read_noise=20.0, max_well=60000.0, bit_depth=12.0)


def slanted_step(n, angle_deg=5.0, sub=4):
    """A step from reflectance 0.2 to 0.6 along a line 5 degrees off vertical, each
    reference pixel the mean of sub x sub point samples."""
    y, x = (np.mgrid[0:n * sub, 0:n * sub] + 0.5) / sub
    inside = (x - n / 2 - (y - n / 2) * np.tan(np.radians(angle_deg))) > 0
    return xr.DataArray(0.2 + 0.4 * inside.reshape(n, sub, n, sub).mean(axis=(1, 3)),
                        dims=("y", "x"))


def measured_against_model(pitch, n):
    sensor = camera(pitch)
    ifov = pitch / 4.0
    out = xbsm.simulate_image(slanted_step(n), sensor, SCENARIO, gsd=ifov * SLANT / RATIO,
                              noise=False, reflectance="identity")
    measured = slanted_edge_mtf(out.blurred)
    f = measured.frequency.values
    below = (f > 0) & (f <= 0.5)
    model = xbsm.system_otf(sensor, SCENARIO, frequency=xr.DataArray(f[below] / ifov,
                                                                     dims="frequency"))
    error = np.abs(measured.mtf.values[below] - model.system.sel(orientation="x").values)
    return error.max(), float(measured.rer), float(xbsm.niirs(sensor, SCENARIO).rer_x)


@pytest.mark.parametrize(("pitch", "n", "bound"), [
    # Q = lambda F / p = 2.9 (well sampled, 159 camera pixels: the Airy pattern's wings,
    # which drop the diffraction MTF linearly near f = 0, need a wide region; measured 0.016)
    (4e-6, 640, 0.02),
    # Q = 0.57 (undersampled, 79 camera pixels; measured 0.018)
    (20e-6, 320, 0.05),
])
def test_simulated_slanted_edge_measures_the_model_mtf(pitch, n, bound):
    error, rer_measured, rer_chain = measured_against_model(pitch, n)
    assert error < bound
    # the RER measured on the simulated edge against the NIIRS chain's (x slice):
    # 0.284 / 0.2855 (Q 2.9) and 0.720 / 0.730 (Q 0.57; sampling phase matters there)
    assert rer_measured == pytest.approx(rer_chain, abs=0.015)


def test_flat_region_noise_is_the_predicted_noise():
    # no dark current: shot noise (Poisson: variance = mean photoelectrons) and read noise
    # add in quadrature; the noisy image before quantization is what the camera's
    # electrons are, so its standard deviation must be sqrt(mean + read_noise^2)
    sensor = camera(10e-6)
    flat = xr.DataArray(np.full((400, 400), 0.4), dims=("y", "x"))
    out = xbsm.simulate_image(flat, sensor, SCENARIO, gsd=2.5e-6 * SLANT / RATIO, noise=True,
                              seed=1, reflectance="identity")
    measured = flat_noise(out.noisy)
    predicted = np.sqrt(float(out.blurred.mean()) + 20.0**2)
    assert float(measured["noise"]) == pytest.approx(predicted, rel=0.05)  # measured 0.4 %
    assert float(measured["mean"]) == pytest.approx(float(out.blurred.mean()), rel=0.01)
