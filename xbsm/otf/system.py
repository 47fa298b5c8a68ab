"""The system OTF of a sensor in a scenario: every component and their product.

The components follow pyBSM's ``common_OTFs`` (paper Table 1 and Eq. 3):
aperture x turbulence x detector x jitter x drift x wavefront x filter. Each
is computed on the dimensions it depends on and nothing more: the aperture,
detector, jitter, wavefront and filter OTFs are sensor quantities; only the
turbulence (path r0, integration time, platform speed) and the drift
(integration time) and the spectral weights (atmosphere) bring in scenario
dimensions. Radially symmetric components (aperture, turbulence) are
evaluated once on the radial frequency and shared by the x and y slices.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._contract import contract
from .._metadata import named
from ..methods import Method
from . import aperture, detector, filters, motion, turbulence, wavefront

ORIENTATION = xr.DataArray(["x", "y"], dims="orientation", name="orientation")
"""The two slice directions the GIQE uses: along x (fx = f) and along y (fy = f)."""
_UNIT_X = xr.DataArray([1.0, 0.0], dims="orientation", coords={"orientation": ORIENTATION})
_UNIT_Y = xr.DataArray([0.0, 1.0], dims="orientation", coords={"orientation": ORIENTATION})

COMPONENTS = ("aperture", "turbulence", "detector", "jitter", "drift", "wavefront", "filter")


def otf_weights(spectral_weights: xr.DataArray) -> xr.DataArray:
    """Spectral weights for the polychromatic OTFs (paper Eq. 3).

    Parameters
    ----------
    spectral_weights : xr.DataArray
        The target's spectral photoelectron rate over ``wavelength`` (from :func:`xbsm.snr`).
        [s-1 m-1]

    Returns
    -------
    xr.DataArray
        Non-negative weights over ``wavelength``. Non-positive rates count as zero;
        cells with no usable weight at all (beyond the database: their SNR is NaN and
        flagged ``beyond_database``) get uniform weights, so that the OTF stays finite
        while the NIIRS is NaN. [s-1 m-1]
    """
    weights = spectral_weights.where(spectral_weights > 0, 0.0)
    usable = weights.sum("wavelength") > 0
    return named(xr.where(usable, weights, 1.0), "s-1 m-1",
                 "spectral weights of the polychromatic OTFs")


def spectral_bins(wavelength: xr.DataArray, weights: xr.DataArray, count: int):
    """Group the band into at most ``count`` contiguous bins for the polychromatic OTFs.

    Parameters
    ----------
    wavelength : xr.DataArray
        Band wavelengths. [m]
    weights : xr.DataArray
        Spectral weights over ``wavelength``. [any]
    count : int
        Largest number of bins; 0 keeps every wavelength.

    Returns
    -------
    wavelength, weights : xr.DataArray
        Bin-centre wavelengths (the mean of each bin's wavelengths) and summed weights.
    """
    n = wavelength.sizes["wavelength"]
    if count <= 0 or count >= n:
        return wavelength, weights
    labels = np.minimum((np.arange(n) * count) // n, count - 1)
    group = xr.DataArray(labels, dims="wavelength", name="bin")
    centres = wavelength.groupby(group).mean().rename(bin="wavelength")
    summed = weights.groupby(group).sum().rename(bin="wavelength")
    if summed.chunks is not None:  # the groupby leaves one chunk per bin; keep the band whole
        summed = summed.chunk({"wavelength": -1})
    return centres.values, summed.assign_coords(wavelength=centres.values)


def system_components(sensor: xr.Dataset, scenario: xr.Dataset, frequency: xr.DataArray, *,
                      spectral_weights: xr.DataArray, integration_time, slant_range,
                      method: Method, fy: xr.DataArray | None = None) -> xr.Dataset:
    """Every OTF component of the system and their product (paper Table 1, Eq. 3, Figure 5).

    Parameters
    ----------
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario`.
    frequency : xr.DataArray
        Either radial slice frequencies (dim ``frequency``; the result gains an
        ``orientation`` dim for the x and y slices) or, with ``fy``, the x
        frequencies of a 2-D grid. [cycles/rad]
    spectral_weights : xr.DataArray
        Spectral photoelectron rate over ``wavelength`` (from :func:`xbsm.snr`). [any]
    integration_time : float or xr.DataArray
        Integration time per TDI stage after the well-fill limit. [s]
    slant_range : float or xr.DataArray
        [m]
    method : Method
        Knobs ``filter_otf``, ``otf_wavelengths``, ``turbulence_path_samples``,
        ``turbulence_path_rule``.
    fy : xr.DataArray, optional
        The y frequencies of a 2-D grid. [cycles/rad]

    Returns
    -------
    xr.Dataset
        ``aperture``, ``turbulence``, ``detector``, ``jitter``, ``drift``,
        ``wavefront``, ``filter``, their product ``system``, ``system_unfiltered``
        (the product without the post-processing filter, which GIQE 5 uses) and
        ``coherence_diameter`` (the band-weighted r0). [1]
    """
    s, sc = sensor, scenario
    if fy is None:
        fx, fy_ = frequency * _UNIT_X, frequency * _UNIT_Y
        radial = frequency
    else:
        fx, fy_ = frequency, fy
        radial = np.hypot(frequency, fy)
    zero = xr.zeros_like(radial)
    wavelength = spectral_weights["wavelength"]
    wl, w = spectral_bins(wavelength, spectral_weights, method.otf_wavelengths)
    wl = xr.DataArray(np.asarray(wl), dims="wavelength", coords={"wavelength": np.asarray(wl)})
    w = w / w.sum("wavelength")
    diameter = s["aperture_diameter"]

    # sensor quantities: evaluated once per sensor, then weighted per scenario
    mono_aperture = aperture.circular_aperture(radial, zero, wl, diameter, s["obscuration_ratio"])
    ap = contract(mono_aperture, w, "wavelength")
    mono_wavefront = wavefront.random_phase_wavefront(
        fx, fy_, wl, s["wavefront_variance"], s["wavefront_correlation_length_x"],
        s["wavefront_correlation_length_y"], s["wavefront_wavelength"],
    )
    wav = contract(mono_wavefront, w, "wavelength")
    det = detector.detector(fx, fy_, s["detector_width_x"], s["detector_width_y"],
                            s["focal_length"])
    jit = motion.jitter(fx, fy_, s["jitter_x"], s["jitter_y"])
    exposure = integration_time * s["tdi_stages"]
    dri = motion.drift(fx, fy_, s["drift_rate_x"] * exposure, s["drift_rate_y"] * exposure)
    fil = _filter(s, fx, fy_, method)

    # turbulence: path r0 at 1 um, scaled per wavelength, blended by wind, weighted
    cn2 = sc["cn2_at_1m"]
    turbulent = cn2 > 0
    r0_ref = turbulence.slant_path_coherence_diameter(
        slant_range, sc["altitude"], 0.0, sc["high_altitude_wind_speed"],
        xr.where(turbulent, cn2, 1.0e-14), path_samples=method.turbulence_path_samples,
        rule=method.turbulence_path_rule, geometry_form=method.geometry,
    )
    turb = turbulence.polychromatic_turbulence(
        radial, zero, wl, w, diameter, r0_ref, exposure, sc["platform_speed"])
    turb = xr.where(turbulent, turb, 1.0)
    r0_band = named(xr.where(
        turbulent, turbulence.band_coherence_diameter(r0_ref, wl, w), np.inf
    ), "m", "band-weighted coherence diameter r0")

    parts = {
        "aperture": named(ap, "1", "aperture OTF"),
        "turbulence": named(turb, "1", "turbulence OTF"),
        "detector": named(det, "1", "detector OTF"),
        "jitter": named(jit, "1", "jitter OTF"),
        "drift": named(dri, "1", "drift OTF"),
        "wavefront": named(wav, "1", "wavefront OTF"),
    }
    unfiltered = math.prod(parts.values())
    parts["filter"] = named(fil, "1", "post-processing filter OTF")
    out = xr.Dataset(parts)
    out["system_unfiltered"] = named(unfiltered, "1", "system OTF without the filter")
    out["system"] = named(unfiltered * fil, "1", "system OTF")
    out["coherence_diameter"] = r0_band
    return out


def _filter(sensor, fx, fy, method: Method):
    """The post-processing filter OTF, or exactly 1 when there is no filter."""
    kernel = sensor["filter_kernel"]
    identity = kernel.shape == (1, 1) and float(kernel[0, 0]) == 1.0
    # pyBSM 0.16.1 skips kernels with a single row (common_OTFs: shape[0] > 1)
    pybsm_skips = method.filter_otf == "pybsm" and kernel.sizes["kernel_y"] == 1
    if identity or pybsm_skips:
        return xr.ones_like(fx * fy)
    ifov_x = sensor["pixel_pitch_x"] / sensor["focal_length"]
    ifov_y = sensor["pixel_pitch_y"] / sensor["focal_length"]
    if method.filter_otf == "pybsm":
        if ifov_x.ndim:
            raise ValueError(
                "method filter_otf='pybsm' cannot sweep pixel_pitch_x or focal_length "
                "with a filter kernel; use filter_otf='dtft'"
            )
        return filters.sharpening_filter(fx, fy, kernel.values, float(ifov_x), method="pybsm")
    return filters.sharpening_filter(fx, fy, kernel.values, ifov_x, ifov_y, method="dtft")
