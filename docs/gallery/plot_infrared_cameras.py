"""
Infrared cameras: NETD, MRTD and NIIRS against range
====================================================

The MWIR and LWIR cameras of the infrared guide (docs/infrared.md): a cooled
3-5 um camera at f/4 with 15 um pixels and an 8-12 um camera at f/2 with 17 um
pixels, both with 77 K cold shield and cold filter. Three questions an
infrared designer asks first: how the NETD changes with the scene's
temperature, the four-bar MRTD against bar frequency (the classic static
performance model: SNR threshold 2.5, eye 0.1 s, 30 Hz, 7:1 bars; no display
or eye MTF), and the GIQE NIIRS of the standard target (2 K thermal contrast in
these bands) against ground range from 1000 m altitude.
"""

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

import xbsm
from xbsm.examples import INFRARED_CAMERAS

MWIR = dict(INFRARED_CAMERAS["mwir"])  # xbsm.examples
LWIR = dict(INFRARED_CAMERAS["lwir"])  # xbsm.examples
CAMERAS = {"MWIR 3-5 um, f/4": MWIR, "LWIR 8-12 um, f/2": LWIR}
lab = xbsm.scenario(altitude=2.0, ground_range=0.0, visibility=23.0)   # a 2 m path

# %%
# NETD against the scene's temperature (a blackbody on a 2 m path). The
# dashed lines are the shot-noise-limited NETD sqrt(N) / (dN/dT), N all the
# pixel's photoelectrons (scene, path, self-emission): the NETD without read,
# dark and quantization noise. The MWIR camera's NETD rises steeply in cold
# scenes, where its few photoelectrons leave quantization and read noise a
# larger share; the LWIR camera stays near its shot-noise limit.
temperature = np.arange(230.0, 351.0, 5.0)
fig, left = plt.subplots(figsize=(6, 4), layout="constrained")
for (name, camera), color in zip(CAMERAS.items(), ("C0", "C3"), strict=True):
    r = xbsm.netd(xbsm.sensor(**camera), lab, temperature=temperature)
    limit = np.sqrt(r.target_photoelectrons) / r.signal_derivative
    left.plot(temperature, 1e3 * r.netd, color=color, label=name)
    left.plot(temperature, 1e3 * limit, color=color, ls="--", lw=0.9)
    print(f"{name}: NETD at 300 K {1e3 * float(r.netd.sel(temperature=300.0)):.1f} mK, "
          f"shot-noise limit {1e3 * float(limit.sel(temperature=300.0)):.1f} mK")
left.set_xlabel("scene temperature [K]")
left.set_ylabel("NETD [mK]")
left.set_ylim(0.0, 120.0)
left.set_title("NETD (dashed: shot-noise limit)")
left.legend()

# %%
# MRTD across the bars against bar frequency. The dotted verticals are the
# Nyquist frequencies 1 / (2 IFOV); above them the bars alias and ``mrtd``
# sets the flag ``bars_aliased`` (drawn thin).
frequency = np.linspace(0.1, 11.0, 221)   # cycles/mrad
fig, middle = plt.subplots(figsize=(6, 4), layout="constrained")
for (name, camera), color in zip(CAMERAS.items(), ("C0", "C3"), strict=True):
    r = xbsm.mrtd(xbsm.sensor(**camera), lab, frequency=frequency * 1e3).sel(orientation="x")
    aliased = xbsm.flags.has_flag(r.flags, "bars_aliased").values
    middle.semilogy(frequency[~aliased], r.mrtd.values[~aliased], color=color, label=name)
    middle.semilogy(frequency[aliased], r.mrtd.values[aliased], color=color, lw=0.7)
    nyquist = 0.5 * camera["focal_length"] / camera["pixel_pitch_x"] / 1e3
    middle.axvline(nyquist, color=color, ls=":", lw=0.8)
middle.set_xlabel("bar frequency [cycles/mrad]")
middle.set_ylabel("MRTD [K]")
middle.set_ylim(1e-3, 10.0)
middle.set_title("MRTD, bars along x (dotted: Nyquist)")
middle.legend()

# %%
# GIQE 5 NIIRS of the standard target against ground range, from 1000 m. The
# GIQE was fitted on visible imagery, and every cell here is outside its
# calibration (``xbsm.flags.is_outside_calibration``): the RER of these cameras,
# 0.544-0.549, is just above GIQE 5's calibrated 0.31-0.54 at every range, and the
# GSD, elevation angle and SNR leave their ranges at some ranges. The
# values extrapolate the equation: they compare the two cameras with each other,
# not with rated imagery.
ground_range = xr.DataArray(np.arange(0.0, 20001.0, 500.0), dims="ground_range")
far = xbsm.scenario(altitude=1000.0, ground_range=ground_range, visibility=23.0)
fig, right = plt.subplots(figsize=(6, 4), layout="constrained")
for (name, camera), color in zip(CAMERAS.items(), ("C0", "C3"), strict=True):
    n = xbsm.niirs(xbsm.sensor(**camera), far).sel(giqe=5)
    right.plot(ground_range / 1e3, n.niirs, color=color, label=name)
    outside = xbsm.flags.is_outside_calibration(n.flags)
    print(f"{name}: NIIRS {float(n.niirs.sel(ground_range=10e3)):.2f} at 10 km; "
          f"{int(outside.sum())} of {outside.size} cells outside the GIQE calibration")
right.set_xlabel("ground range [km]")
right.set_ylabel("NIIRS (GIQE 5)")
right.set_ylim(0.0, 10.0)
right.set_title("NIIRS from 1000 m (outside calibration)")
right.legend()
plt.show()
