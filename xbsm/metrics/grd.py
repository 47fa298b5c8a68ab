r"""Ground resolved distance (GRD): period of the finest square wave an image resolves.

The input is an OTF or MTF slice along ``frequency`` [cycles/rad], as for
:mod:`xbsm.metrics.edge`; the threshold is the contrast SNR. The ``"pybsm"``
method reproduces pyBSM 0.16.1 with the search in
:mod:`xbsm.metrics.pybsm_numerics`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import flags as _flags
from .._metadata import Output
from ..params import Choice, Spec, Values, contract
from .edge import check_slice
from .pybsm_numerics import np_interp_reversed

__all__ = ["ground_resolved_distance"]


def _first_crossing(mtf, freq, threshold):
    """First frequency where ``mtf`` falls to ``threshold`` (linear interpolation)."""
    below = mtf <= threshold
    crossed = below.cumsum("frequency") > 0
    prev_crossed = crossed.shift(frequency=1, fill_value=False)
    first = crossed & ~prev_crossed
    m1 = mtf.shift(frequency=1)
    f1 = freq.shift(frequency=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = (m1 - threshold) / (m1 - mtf)
    seg = f1 + frac * (freq - f1)
    # a crossing at the first sample: interpolate from the implicit (0, 1)
    f0 = freq.isel(frequency=0)
    m0 = mtf.isel(frequency=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        start = xr.where((f0 > 0) & (m0 < 1.0), f0 * (1.0 - threshold) / (1.0 - m0), f0)
    start = xr.where(threshold >= 1.0, 0.0, start)
    seg = xr.where(freq == f0, start, seg)
    u = xr.where(first, seg, 0.0).sum("frequency")
    any_cross = crossed.any("frequency")
    return xr.where(any_cross, u, freq.max("frequency"))


def _grd_flags(snr: xr.DataArray) -> xr.DataArray:
    """``grd_unresolved`` where SNR <= 3 or NaN, ``snr_nonpositive`` where SNR <= 0."""
    flags = _flags.set_flag(_flags.empty_flags(snr), "grd_unresolved", ~(snr > 3.0))
    flags = _flags.set_flag(flags, "snr_nonpositive", snr <= 0.0)
    return flags.assign_attrs(_flags.flag_attrs("GRD validity flags"))


@contract(Output("grd", "m", "ground resolved distance", references="IBSM Eq. 3-54"),
          ifov=Values(Spec("rad", "instantaneous field of view", low=0.0)),
          slant_range=Values(Spec("m", "slant range", low=0.0, low_open=True)),
          method=Choice(("first_crossing", "pybsm")))
def ground_resolved_distance(otf_slice, snr, ifov, slant_range, *, method="first_crossing"):
    r"""Ground resolved distance: period of the finest resolvable square wave.

    Parameters
    ----------
    otf_slice : xr.DataArray
        OTF or MTF along ``frequency`` (its modulus is used), in increasing
        frequency; OTF(0) = 1 is assumed if the first sample is above 0. [1]
    snr : float or xr.DataArray
        Contrast signal-to-noise ratio. [1]
    ifov : float or xr.DataArray
        Detector IFOV. [rad]
    slant_range : float or xr.DataArray
        Sensor-to-target distance. [m]
    method : {"first_crossing", "pybsm"}
        ``"first_crossing"``: the first frequency at which the MTF falls to
        3/SNR, linearly interpolated; correct for non-monotonic MTFs (a
        contrast-reversed lobe above the threshold is not "resolved"). If the
        MTF never falls to the threshold, the highest sampled frequency is
        used (GRD is then an upper bound). SNR <= 3 gives GRD = inf (nothing
        is resolved); SNR <= 0 gives NaN.
        ``"pybsm"``: pyBSM 0.16.1's rule, ``numpy.interp`` on the reversed MTF
        with frequencies :math:`k\,\Delta f` and a +1e-12 guard; silently
        wrong for non-monotonic MTFs, kept for parity. At 0 < SNR <= 3 it gives
        pyBSM's finite, meaningless value (slant range x 1e12, from its 1e-12
        guard); SNR <= 0 gives NaN (pyBSM raises).

    Returns
    -------
    xr.DataArray
        GRD [m], with the coordinate ``grd_flags`` (on the dims of ``snr``;
        :mod:`xbsm.flags`): ``grd_unresolved`` where SNR <= 3 or NaN (nothing
        is resolved, whatever the method returns) and ``snr_nonpositive``
        where SNR <= 0.

    Notes
    -----
    IBSM Eq. 3-54, with :math:`u_r` the frequency where
    :math:`MTF(u_r) = 3/SNR`:

    .. math:: GRD = R\,\max\left(\frac{1}{u_r},\ 2\theta\right)
    """
    check_slice(otf_slice, None)
    if not np.all(np.diff(np.asarray(otf_slice["frequency"].values)) > 0):
        raise ValueError("otf_slice's frequency coordinate must increase strictly")
    mtf = np.abs(otf_slice.reset_coords(drop=True))
    freq = otf_slice["frequency"].reset_coords(drop=True)
    freq = xr.DataArray(np.asarray(freq), dims="frequency", coords={"frequency": freq.values})
    mtf = mtf.assign_coords(frequency=freq.values)
    snr = xr.DataArray(snr) if not isinstance(snr, xr.DataArray) else snr
    with np.errstate(divide="ignore", invalid="ignore"):
        threshold = 3.0 / snr
    if method == "pybsm":
        n = mtf.sizes["frequency"]
        u_r = np_interp_reversed(mtf, freq, threshold, n) + 1e-12
        with np.errstate(divide="ignore"):
            grd = slant_range * np.maximum(1.0 / u_r, 2.0 * ifov)
        grd = grd.where(snr > 0)  # pyBSM raises at SNR 0; no SNR <= 0 resolves anything
    else:  # "first_crossing"
        u_r = _first_crossing(mtf, freq, threshold)
        with np.errstate(divide="ignore"):
            inv = xr.where(u_r > 0, 1.0 / u_r.where(u_r > 0), np.inf)
        grd = slant_range * np.maximum(inv, 2.0 * ifov)
        grd = grd.where(snr > 0)
    return grd.assign_coords(grd_flags=_grd_flags(snr))
