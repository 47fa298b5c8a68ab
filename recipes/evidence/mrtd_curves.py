"""MRTD of the MWIR and LWIR example cameras and MRC of the Olson camera: docs/infrared.md's tables.

1. ``xbsm.mrtd`` of the two cameras of docs/infrared.md's NETD table (a 2 m path,
   300 K blackbody background, default observer: SNR threshold 2.5, eye 0.1 s, 30 Hz,
   7:1 bars) at bar frequencies in cycles/mrad, horizontal (x) and vertical (y), with
   the MTF across the bars and the flags (``A``: bars_aliased, ``U``:
   bars_unresolved); the low-frequency slope MRTD / f against the formula's constant
   times the NETD; the frequency at which the MRTD reaches 1 K.
2. ``xbsm.mrc`` of the Olson NIR camera (``xbsm.examples``) looking down from 9 km at
   ground range 0, 23 km visibility, on its 7 % background.
3. The cost of one ``mrtd`` call of 64 frequencies (median of 5; load average printed).

Run from the repository root::

    .venv/bin/python recipes/evidence/mrtd_curves.py
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

import xbsm
from xbsm.examples import INFRARED_CAMERAS, olson_scenario, olson_sensor
from xbsm.flags import has_flag
from xbsm.metrics.acquisition import bar_constant

MWIR = dict(INFRARED_CAMERAS["mwir"])  # xbsm.examples
LWIR = dict(INFRARED_CAMERAS["lwir"])  # xbsm.examples
LAB = dict(altitude=2.0, ground_range=0.0, visibility=23.0)
CYCLES_PER_MRAD = np.array([0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0])


def marks(flags) -> str:
    out = ""
    if bool(has_flag(flags, "bars_aliased")):
        out += "A"
    if bool(has_flag(flags, "bars_unresolved")):
        out += "U"
    return out


def mrtd_table(name, camera):
    s, sc = xbsm.sensor(**camera), xbsm.scenario(**LAB)
    r = xbsm.mrtd(s, sc, frequency=CYCLES_PER_MRAD * 1e3)
    ifov = camera["pixel_pitch_x"] / camera["focal_length"]
    print(f"\n{name}: NETD (one frame) {float(r.netd_frame) * 1e3:.1f} mK, sample spacing "
          f"{ifov * 1e3:.4f} mrad, Nyquist {0.5 / ifov / 1e3:.2f} cycles/mrad, optics cutoff "
          f"{camera['aperture_diameter'] / camera['wavelength_min'] / 1e3:.2f} cycles/mrad")
    print("| f [cycles/mrad] | MTF x | MRTD x [K] | MTF y | MRTD y [K] |")
    print("|---|---|---|---|---|")
    for i, f in enumerate(CYCLES_PER_MRAD):
        cells = []
        for o in ("x", "y"):
            c = r.isel(frequency=i).sel(orientation=o)
            cells += [f"{float(c.mtf):.3f}", f"{float(c.mrtd):.4g} {marks(c.flags)}".strip()]
        print(f"| {f:g} | " + " | ".join(cells) + " |")
    slope = bar_constant() * 2.5 * float(r.netd_frame) * ifov / math.sqrt(0.1 * 30.0)
    low = float(xbsm.mrtd(s, sc, frequency=[1e-3]).mrtd.sel(orientation="x").squeeze())
    print(f"low-frequency slope MRTD/f: {low / 1e-3:.6e} "
          f"K rad (formula {slope:.6e}: pi^2/(4 sqrt 7) x 2.5 x NETD x ifov / sqrt(3))")
    nyquist = xbsm.mrtd(s, sc, frequency=[0.5 / ifov]).mrtd.sel(orientation="x").squeeze()
    print(f"MRTD at Nyquist: {float(nyquist):.4f} K")
    top = 0.999 * camera["aperture_diameter"] / camera["wavelength_min"]
    fine = xbsm.mrtd(s, sc, frequency=np.linspace(1.0, top, 4000)).sel(orientation="x")
    above = np.nonzero(fine.mrtd.values >= 1.0)[0]
    if above.size:
        print(f"MRTD reaches 1 K at {float(fine.frequency[above[0]]) / 1e3:.2f} cycles/mrad")
    return s, sc


def mrc_table():
    s = olson_sensor()
    sc = olson_scenario(ground_range=0.0, visibility=23.0)
    f = np.array([10.0, 25.0, 50.0, 100.0, 150.0, 200.0, 250.0, 300.0])  # cycles/mrad
    r = xbsm.mrc(s, sc, frequency=f * 1e3)
    ifov = float(s.pixel_pitch_x / s.focal_length)
    print(f"\nOlson NIR camera (examples), 9 km nadir, 23 km visibility, background "
          f"{float(sc.background_reflectance):.2f}: noise-equivalent contrast "
          f"{float(r.noise_equivalent_contrast):.4f}, Nyquist {0.5 / ifov / 1e3:.1f} "
          "cycles/mrad")
    print("| f [cycles/mrad] | MTF x | MRC x | MTF y | MRC y |")
    print("|---|---|---|---|---|")
    for i, fi in enumerate(f):
        cells = []
        for o in ("x", "y"):
            c = r.isel(frequency=i).sel(orientation=o)
            cells += [f"{float(c.mtf):.3f}", f"{float(c.mrc):.4g} {marks(c.flags)}".strip()]
        print(f"| {fi:g} | " + " | ".join(cells) + " |")


def cost(s, sc):
    xbsm.mrtd(s, sc)
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        xbsm.mrtd(s, sc)
        times.append(time.perf_counter() - t0)
    print(f"\nmrtd (64 frequencies, one scenario): median {np.median(times) * 1e3:.1f} ms "
          f"(load average {os.getloadavg()[0]:.2f})")


if __name__ == "__main__":
    s, sc = mrtd_table("MWIR 3-5 um, f/4, 15 um", MWIR)
    mrtd_table("LWIR 8-12 um, f/2, 17 um", LWIR)
    mrc_table()
    cost(s, sc)
