"""Defocus models against Hopkins' exact OTF: the numbers docs/otf.md quotes.

For a clear circular pupil with defocus wavefront coefficient W020 (in waves at the
wavelength), on the normalised frequency s = 2 rho lambda / D in [0, 2] (2001 points):

1. Hopkins' series (``xbsm.otf.aperture.hopkins_kernel``) and the annular pupil's
   OTF built from it (``xbsm.otf.defocus.annular_defocus_kernel``) against an
   independent reference, the pupil autocorrelation as a one-dimensional integral (the
   phase difference of the sheared pupils is linear in x, so the y-integral over the
   overlap is its chord length; scipy ``quad`` with a cosine weight, on the pieces
   between the chord's kinks); and the error a shortcut for obscured pupils would make
   (the obscured in-focus OTF times Hopkins' clear-pupil ratio).
2. IBSM's Gaussian (``model="gaussian"``: the in-focus OTF times exp(-pi^2 w^2 rho^2 / 4)
   with w = 0.62 d, d = 8 W020 / D the geometric blur-circle diameter) and the
   geometric disk (``model="geometric"``) against Hopkins: largest and rms difference;
   the Gaussian size w / d that fits Hopkins best in least squares, and the one that
   matches Hopkins' 50 % MTF frequency, with their errors.
3. The chain: GIQE NIIRS of the Olson NIR camera (obscuration 0.4, 10 km) with
   defocus, by model; the edge rule's convergence with defocus; and the cost of a
   ``niirs`` call with and without defocus (median of repeated calls; the load
   average is printed).

Run from the repository root::

    .venv/bin/python recipes/evidence/defocus_models.py
"""

from __future__ import annotations

import os
import time

import numpy as np
from scipy.integrate import quad
from scipy.optimize import minimize_scalar
from scipy.special import j1

import xbsm
import xbsm.flags
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.otf.aperture import circular_aperture_kernel, hopkins_kernel
from xbsm.otf.defocus import annular_defocus_kernel

WAVES = (0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0)
S = np.linspace(0.0, 2.0, 2001)
IBSM = 0.62


def chord(x, s, eta):
    """Chord length at abscissa x of the overlap of two annuli (radius 1, hole eta) at +-s/2."""
    length = np.inf
    low = 0.0
    for u in (x + s / 2, x - s / 2):
        if abs(u) > 1:
            return 0.0
        length = min(length, np.sqrt(1 - u * u))
        low = max(low, np.sqrt(max(eta * eta - u * u, 0.0)))
    return 2 * max(0.0, length - low)


def pupil_autocorrelation(s, waves, eta=0.0):
    """OTF of an annular pupil with defocus W020 = ``waves``: the 1-D chord integral.

    H(s) = int L(x) cos(a x) dx / (pi (1 - eta^2)), a = 4 pi W020 s (the sheared phases
    2 pi W020 ((x + s/2)^2 - (x - s/2)^2) differ by a x); L is even in x.
    """
    if s >= 2:
        return 0.0
    a = 4 * np.pi * waves * s
    kinks = {0.0, 1 - s / 2}
    for c in (eta - s / 2, -eta + s / 2, eta + s / 2, -eta - s / 2, 1 - s / 2, -1 + s / 2):
        if 0 < c < 1 - s / 2:
            kinks.add(c)
    edges = sorted(kinks)
    total = 0.0
    for lo, hi in zip(edges[:-1], edges[1:], strict=False):
        if a == 0:
            total += quad(chord, lo, hi, args=(s, eta), epsabs=1e-14, limit=200)[0]
        else:
            total += quad(chord, lo, hi, args=(s, eta), weight="cos", wvar=a, epsabs=1e-14,
                          limit=200)[0]
    return 2 * total / (np.pi * (1 - eta * eta))


def clear(s):
    """In-focus OTF of the clear pupil at s = 2 rho lambda / D."""
    return circular_aperture_kernel(s / 2, 1.0, 1.0, 0.0)


def gaussian(s, waves, k):
    """In-focus OTF times the Gaussian of size w = k d (pi w rho = k a, a = 4 pi W s)."""
    return clear(s) * np.exp(-((k * 4 * np.pi * waves * s) ** 2) / 4)


def disk(s, waves):
    """In-focus OTF times the blur disk's 2 J1(a) / a (a = pi d rho = 4 pi W s)."""
    a = 4 * np.pi * waves * s
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(a == 0, 1.0, 2 * j1(a) / a)
    return clear(s) * out


def rms(x):
    return float(np.sqrt(np.mean(x**2)))


def section_reference():
    print("## 1. The exact OTF against the pupil autocorrelation (1-D chord integral)\n")
    print("| pupil | W020 [waves] | points | largest difference |")
    print("|---|---|---|---|")
    s = np.linspace(0.0, 1.999, 81)
    for eta in (0.0, 0.2, 0.4, 0.6, 0.9):
        worst = 0.0
        for waves in (0.05, 0.25, 1.0, 4.0, 10.0):
            ref = np.array([pupil_autocorrelation(v, waves, eta) for v in s])
            got = annular_defocus_kernel(s, waves, eta) if eta else hopkins_kernel(s, waves)
            worst = max(worst, float(np.max(np.abs(got - ref))))
        kind = f"annular, eta {eta:g}" if eta else "clear (Hopkins' series)"
        print(f"| {kind} | 0.05-10 | 5 x 81 | {worst:.1e} |")
    print()
    print("Why obscured pupils get their own autocorrelation: the obscured in-focus OTF "
          "times Hopkins' clear-pupil ratio (defocused / in focus) against the exact "
          "annular OTF, largest |error| over s:\n")
    print("| W020 [waves] | eta 0.2 | eta 0.4 | eta 0.6 |")
    print("|---|---|---|---|")
    s = np.linspace(0.0, 1.99, 100)
    for waves in (0.1, 0.25, 0.5, 1.0, 2.0):
        row = []
        for eta in (0.2, 0.4, 0.6):
            exact = annular_defocus_kernel(s, waves, eta)
            obscured = circular_aperture_kernel(s / 2, 1.0, 1.0, eta)
            approx = obscured * hopkins_kernel(s, waves) / clear(s)
            row.append(f"{np.max(np.abs(approx - exact)):.3f}")
        print(f"| {waves:g} | " + " | ".join(row) + " |")
    print()


def gaussian_row(waves):
    """One row of the Gaussian table: errors of IBSM's size, the disk, and the fitted sizes."""
    h = hopkins_kernel(S, waves)
    ibsm = gaussian(S, waves, IBSM) - h
    geo = disk(S, waves) - h
    k_ls = minimize_scalar(lambda k: float(np.sum((gaussian(S, waves, k) - h) ** 2)),
                           bounds=(0.05, 2.0), method="bounded", options={"xatol": 1e-8}).x
    best = gaussian(S, waves, k_ls) - h
    i = np.nonzero(h < 0.5)[0][0]
    s50 = np.array([S[i - 1] + (0.5 - h[i - 1]) * (S[i] - S[i - 1]) / (h[i] - h[i - 1])])
    k50 = minimize_scalar(lambda k: (gaussian(s50, waves, k)[0] - 0.5) ** 2,
                          bounds=(0.0, 2.0), method="bounded", options={"xatol": 1e-10}).x
    at50 = np.max(np.abs(gaussian(S, waves, k50) - h))
    return (f"| {waves:g} | {np.max(np.abs(ibsm)):.3f} / {rms(ibsm):.3f} | "
            f"{np.max(np.abs(geo)):.3f} / {rms(geo):.3f} | {k_ls:.3f} | "
            f"{np.max(np.abs(best)):.3f} / {rms(best):.3f} | {k50:.3f} | {at50:.3f} |")


def section_gaussian():
    print("## 2. Gaussian and geometric disk against Hopkins (clear pupil, s in [0, 2])\n")
    print("w is the Gaussian's size (PSF 1/e diameter), d = 8 W020 / D the geometric "
          "blur-circle diameter; IBSM's w = 0.62 d. Errors are OTF differences "
          "(largest / rms over s).\n")
    print("| W020 [waves] | IBSM Gaussian max / rms | geometric disk max / rms | "
          "least-squares w / d | its max / rms | w / d at Hopkins' 50 % MTF | its max |")
    print("|---|---|---|---|---|---|---|")
    for waves in WAVES:
        print(gaussian_row(waves))
    print()


def median_time(func, repeat=21):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        func()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def section_chain():
    print("## 3. The chain: Olson NIR camera (D 0.275 m, obscuration 0.4), 10 km, 23 km "
          "visibility\n")
    sc = olson_scenario(ground_range=10e3, visibility=23.0)
    lam = 0.7e-6  # W020 quoted in waves at 0.7 um, the band's middle
    print("GIQE 4 NIIRS (accurate) against W020 [waves at 0.7 um]:\n")
    print("| W020 [waves] | hopkins | geometric | gaussian (IBSM) |")
    print("|---|---|---|---|")
    for waves in (0.0, 0.1, 0.25, 0.5, 1.0, 2.0):
        s = olson_sensor("nir", defocus_opd=waves * lam)
        row = [float(xbsm.niirs(s, sc, method=xbsm.method("accurate", defocus_otf=m))
                     .niirs.sel(giqe=4)) for m in ("hopkins", "geometric", "gaussian")]
        print(f"| {waves:g} | " + " | ".join(f"{v:.3f}" for v in row) + " |")
    print()
    fine = xbsm.method("accurate", min_panels=256, nodes_per_panel=20,
                       panels_per_oscillation=4.0)
    print("Edge-rule convergence with defocus (hopkins): GIQE 4 NIIRS of accurate and fast "
          "minus that of a much finer rule (min_panels 256, 20 nodes per panel, 4 panels "
          "per oscillation), the RER and whether blur_unresolved is set (accurate / fast):\n")
    print("| W020 [waves] | accurate - fine | fast - fine | RER | blur_unresolved |")
    print("|---|---|---|---|---|")
    for waves in (0.25, 1.0, 2.0, 4.0, 8.0, 16.0):
        s = olson_sensor("nir", defocus_opd=waves * lam)
        acc, fast, ref = (xbsm.niirs(s, sc, method=m) for m in ("accurate", "fast", fine))
        g4 = [float(r.niirs.sel(giqe=4)) for r in (acc, fast, ref)]
        unresolved = ["yes" if bool(xbsm.flags.has_flag(r.flags.sel(giqe=4), "blur_unresolved"))
                      else "no" for r in (acc, fast)]
        print(f"| {waves:g} | {g4[0] - g4[2]:.1e} | {g4[1] - g4[2]:.1e} | "
              f"{float(acc.rer):.3f} | {' / '.join(unresolved)} |")
    print()
    print(f"Cost of one niirs call (median of 21; load average {os.getloadavg()[0]:.2f}):\n")
    print("| method | no defocus [ms] | W020 0.25 waves [ms] | 1 wave | 4 waves |")
    print("|---|---|---|---|---|")
    for m in ("accurate", "fast"):
        row = []
        for waves in (0.0, 0.25, 1.0, 4.0):
            s = olson_sensor("nir", defocus_opd=waves * lam)
            xbsm.niirs(s, sc, method=m)  # warm
            row.append(1e3 * median_time(lambda s=s, m=m: xbsm.niirs(s, sc, method=m)))
        print(f"| {m} | " + " | ".join(f"{v:.1f}" for v in row) + " |")
    print()


if __name__ == "__main__":
    section_reference()
    section_gaussian()
    section_chain()
