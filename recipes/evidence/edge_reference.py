"""An edge-response reference computed independently of xbsm's edge quadrature (issue 23).

What xbsm provides here is only the *model*: the system OTF along the x and y
slices, from the public :func:`xbsm.system_otf` (filtered and unfiltered, every
database wavelength, a converged r0 path rule), and the GIQE equations from the
public :mod:`xbsm.metrics` functions. Nothing from :mod:`xbsm.quadrature`,
:mod:`xbsm.metrics.edge` or the chain's edge stage is used, so the same code
measures the package before and after a change of its quadrature: put the tree
to be measured on ``PYTHONPATH``.

The edge response (IBSM Eq. 3-63; the OTF slices of these systems are real)

    ER(x) = 1/2 + (1/pi) int_0^F H(f) sin(2 pi f ifov x) / f df,   F = D / lambda_min,

is integrated by the trapezoid rule on a uniform grid of ``intervals`` (2^17 by
default) intervals over [0, F] and on every other node of it (2^16), with the
f = 0 limit 2 pi ifov x H(0) of the integrand, then Richardson-extrapolated
(the trapezoid error is c h^2 + O(h^4) for an integrand smooth enough):
R = (4 T(h) - T(2h)) / 3. The difference between the two trapezoid levels is
kept as the reference's own error estimate (an upper bound on R's error
wherever the h^2 term dominates). RER = ER(+1/2) - ER(-1/2); EHO from the edge
response at 1, 1.25, ..., 3 px (IBSM Eq. 3-60 as corrected by Leachtenauer et
al. 1997: ER(1.25) if strictly rising, else the maximum).

Functions:

- :func:`same_reference`: whether two methods model the same OTF (one reference serves both);
- :func:`edge_integrals`: the rule on plain samples (used by the tests on closed forms);
- :func:`reference_slices`: RER and EHO of one sensor + scenario under a method's
  modelling (its ``edge_otf`` convention, ``|OTF|`` or the OTF);
- :func:`reference_niirs`: NIIRS by GIQE 3, 4, 5 from reference RER/EHO and the
  method's own SNR, GSD, elevation and noise gain (an ``xbsm.niirs`` result).
"""

from __future__ import annotations

import numpy as np

import xbsm

INTERVALS = 2**17
"""Intervals of the finer trapezoid level over [0, D / lambda_min]."""
RER_POSITIONS = np.array([-0.5, 0.5])
"""IBSM Eq. 3-61: RER = ER(+1/2 px) - ER(-1/2 px)."""
EHO_POSITIONS = np.arange(1.0, 3.0 + 1e-9, 0.25)
"""IBSM Eq. 3-60: edge response 1 to 3 px from the edge, every 1/4 px."""
POSITIONS = np.concatenate([RER_POSITIONS, EHO_POSITIONS])
CHUNK_ELEMENTS = 3_000_000
"""Largest frequencies x band wavelengths of one :func:`xbsm.system_otf` call (memory)."""
PATH_SAMPLES = 1024
"""r0 path nodes of the reference modelling (Gauss-Legendre; accurate uses 64)."""
PROBE_FREQUENCIES = 64
"""Frequencies at which :func:`same_reference` compares two methods' OTF slices."""


def same_reference(sensor, scenario, m1, m2) -> bool:
    """Whether methods ``m1`` and ``m2`` have the same reference on this system.

    True when their edge_otf conventions agree and the system OTF slices of their
    :func:`reference_method` agree exactly at :data:`PROBE_FREQUENCIES` frequencies in
    (0, D/lambda_min): the reference depends on nothing else. (A list of "numerical"
    knobs would go stale as the package gains quadrature knobs.)
    """
    m1, m2 = xbsm.method(m1), xbsm.method(m2)
    if m1.edge_otf != m2.edge_otf:
        return False
    fmax = float(sensor["aperture_diameter"]) / float(sensor["wavelength_min"])
    f = fmax * (np.arange(PROBE_FREQUENCIES) + 0.5) / PROBE_FREQUENCIES
    a, b = (xbsm.system_otf(sensor, scenario, f, method=reference_method(m)) for m in (m1, m2))
    return all(np.array_equal(a[k].values, b[k].values, equal_nan=True)
               for k in ("system", "system_unfiltered"))


def edge_integrals(otf, fmax, ifov, positions=POSITIONS):
    """Edge response by the trapezoid rule at two levels, and its Richardson extrapolation.

    Parameters
    ----------
    otf : array_like, (..., n + 1)
        Real OTF samples at f = k fmax / n, k = 0..n (n even). [1]
    fmax : float
        Upper limit of the integral. [cycles/rad]
    ifov : float or array_like
        Broadcasts against ``otf``'s leading axes. [rad]
    positions : array_like
        Distances from the edge. [px]

    Returns
    -------
    fine, coarse, extrapolated : ndarray, (..., positions)
        ER by the trapezoid on n and on n / 2 intervals, and (4 fine - coarse) / 3.
    """
    otf = np.asarray(otf)
    if np.iscomplexobj(otf):
        if np.max(np.abs(otf.imag)) > 1e-12 * max(1.0, float(np.max(np.abs(otf.real)))):
            raise ValueError("edge_integrals handles real OTF slices only")
        otf = otf.real
    n = otf.shape[-1] - 1
    if n < 2 or n % 2:
        raise ValueError(f"otf needs an even number of intervals; got {n}")
    f = np.linspace(0.0, fmax, n + 1)
    ifov = np.asarray(ifov, dtype=float)[..., None, None]           # (..., 1, 1)
    x = np.asarray(positions, dtype=float)[:, None]                  # (P, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        kernel = np.sin(2.0 * np.pi * f * ifov * x) / f              # (..., P, n + 1)
    kernel[..., 0] = 2.0 * np.pi * ifov[..., 0] * x[:, 0]            # the f = 0 limit
    out = []
    for step in (1, 2):
        h = fmax / n * step
        w = np.full(n // step + 1, h)
        w[0] = w[-1] = h / 2
        integral = np.einsum("...k,...pk->...p", otf[..., ::step] * w, kernel[..., ::step])
        out.append(0.5 + integral / np.pi)
    fine, coarse = out
    return fine, coarse, (4.0 * fine - coarse) / 3.0


def _eho(er):
    """EHO from ER at :data:`EHO_POSITIONS` (last axis)."""
    rising = (np.diff(er, axis=-1) > 0).all(axis=-1)
    return np.where(rising, er[..., 1], er.max(axis=-1))


def edge_terms(er):
    """RER and EHO from ER at :data:`POSITIONS` (last axis)."""
    return er[..., 1] - er[..., 0], _eho(er[..., 2:])


def _band_wavelengths(sensor) -> int:
    lo, hi = float(sensor["wavelength_min"]), float(sensor["wavelength_max"])
    return int(round((hi - lo) / 10e-9)) + 2


def reference_method(m):
    """Method ``m``'s modelling with converged OTF numerics: every database wavelength,
    :data:`PATH_SAMPLES` Gauss-Legendre r0 path nodes."""
    return xbsm.method(xbsm.method(m), otf_wavelengths=0,
                       turbulence_path_samples=PATH_SAMPLES,
                       turbulence_path_rule="gauss-legendre")


def otf_slices(sensor, scenario, m, intervals=INTERVALS):
    """System OTF slices (filtered, unfiltered) on (orientation x/y, n + 1) over [0, D/lambda_min].

    Returns (filtered, unfiltered, fmax). Through :func:`xbsm.system_otf` in chunks of
    frequencies (memory), with :func:`reference_method`'s numerics.
    """
    ref = reference_method(m)
    fmax = float(sensor["aperture_diameter"]) / float(sensor["wavelength_min"])
    f = np.linspace(0.0, fmax, intervals + 1)
    chunk = max(1024, CHUNK_ELEMENTS // _band_wavelengths(sensor))
    filtered = np.empty((2, f.size))
    unfiltered = np.empty((2, f.size))
    for start in range(0, f.size, chunk):
        part = slice(start, min(f.size, start + chunk))
        out = xbsm.system_otf(sensor, scenario, f[part], method=ref)
        for name, into in (("system", filtered), ("system_unfiltered", unfiltered)):
            v = out[name].transpose("orientation", "frequency").sel(orientation=["x", "y"])
            into[:, part] = v.values.real if np.iscomplexobj(v.values) else v.values
    return filtered, unfiltered, fmax


def reference_slices(sensor, scenario, m, intervals=INTERVALS) -> dict:
    """Reference RER and EHO of one sensor and scenario under method ``m``'s modelling.

    Returns a dict of floats: ``rer_x``, ``rer_y``, ``eho_x``, ``eho_y``,
    ``rer_unfiltered_x``, ``rer_unfiltered_y`` (Richardson-extrapolated), the same keys
    with ``_fine`` and ``_coarse`` (the two trapezoid levels), and ``level_difference``
    (the largest |fine - coarse| over the six).
    """
    m = xbsm.method(m)
    filtered, unfiltered, fmax = otf_slices(sensor, scenario, m, intervals)
    if m.edge_otf == "abs":
        filtered, unfiltered = np.abs(filtered), np.abs(unfiltered)
    ifov = np.array([float(sensor["pixel_pitch_x"]), float(sensor["pixel_pitch_y"])]) / float(
        sensor["focal_length"])
    out = {}
    for label, otf in (("", filtered), ("unfiltered_", unfiltered)):
        for level, er in zip(("_fine", "_coarse", ""), edge_integrals(otf, fmax, ifov),
                             strict=True):
            rer, eho = edge_terms(er)
            for k, o in enumerate("xy"):
                out[f"rer_{label}{o}{level}"] = float(rer[k])
                if not label:
                    out[f"eho_{o}{level}"] = float(eho[k])
    keys = [k for k in out if not k.endswith(("_fine", "_coarse"))]
    out["level_difference"] = max(abs(out[k + "_fine"] - out[k + "_coarse"]) for k in keys)
    return out


def reference_niirs(ref: dict, result, m, level: str = "") -> np.ndarray:
    """NIIRS (GIQE 3, 4, 5) from reference edge terms and a method's own SNR, GSD, elevation.

    Parameters
    ----------
    ref : dict
        From :func:`reference_slices`.
    result : xr.Dataset
        ``xbsm.niirs(sensor, scenario, method=m)`` of one scenario (its ``snr``, ``gsd``,
        ``gsd_w``, ``elevation_angle`` and ``noise_gain``).
    m : str or Method
        The method (its GIQE 4 noise coefficient).
    level : {"", "_fine", "_coarse"}
        Which reference values: extrapolated, or one of the trapezoid levels.

    Returns
    -------
    ndarray, (3,)
        Through the public :func:`xbsm.metrics.giqe3`, ``giqe4`` and ``giqe5``.
    """
    m = xbsm.method(m)
    g = {k: float(result[k]) for k in ("snr", "gsd", "gsd_w", "elevation_angle", "noise_gain")}
    el = g["elevation_angle"]
    gsd_x = g["gsd_w"] * np.sin(el) ** 0.25  # GIQE 5 uses gsd_x (gsd_w = gsd_x / sin^1/4)
    rx, ry = ref["rer_x" + level], ref["rer_y" + level]
    ex, ey = ref["eho_x" + level], ref["eho_y" + level]
    with np.errstate(invalid="ignore"):
        rer = float(np.sqrt(rx * ry)) if (rx > 0 and ry > 0) else np.nan
        eho = float(np.sqrt(ex * ey))
    n3 = xbsm.metrics.giqe3(rer=rer, gsd=g["gsd"], eho=eho, snr=g["snr"],
                            noise_gain=g["noise_gain"])["niirs"]
    n4 = xbsm.metrics.giqe4(rer=rer, gsd=g["gsd"], eho=eho, snr=g["snr"], elevation=el,
                            noise_gain=g["noise_gain"],
                            noise_coefficient=m.giqe4_noise_coefficient)["niirs"]
    n5 = xbsm.metrics.giqe5(rer_x=ref["rer_unfiltered_x" + level],
                            rer_y=ref["rer_unfiltered_y" + level], gsd=gsd_x, snr=g["snr"],
                            elevation=el)["niirs"]
    return np.array([float(n3), float(n4), float(n5)])


def method_niirs_check(result, m) -> float:
    """Largest |NIIRS| difference between ``result`` and the public GIQE functions fed with
    the result's own edge terms: checks that :func:`reference_niirs` composes the GIQE as
    the chain does (no post-processing filter: the unfiltered RER is the filtered one)."""
    own = {f"{k}_{o}": float(result[f"{k}_{o}"]) for k in ("rer", "eho") for o in "xy"}
    own.update(rer_unfiltered_x=own["rer_x"], rer_unfiltered_y=own["rer_y"])
    mine = reference_niirs(own, result, m)
    theirs = result["niirs"].values
    both = np.isfinite(mine) & np.isfinite(theirs)
    if (np.isfinite(mine) != np.isfinite(theirs)).any():
        return np.inf
    return float(np.max(np.abs(mine[both] - theirs[both]), initial=0.0))
