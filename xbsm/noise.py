"""Noise terms in rms photoelectrons and the contrast signal-to-noise ratio (paper Sec. 2.3)."""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

from . import radiometry
from ._kernels import apply_kernel, apply_orchestrator, dataset
from ._metadata import Output, named, outputs
from .constants import CODATA
from .params import contract

# NumPy kernels (plain arrays in and out, no checks); the public functions below wrap them
# in one ``xr.apply_ufunc`` each, which broadcasts, aligns and carries dask. Like xarray's
# arithmetic, they give IEEE results (inf, NaN) without floating-point warnings.


def _quantization_noise_kernel(well_range, bit_depth):
    with np.errstate(all="ignore"):
        return well_range / (np.sqrt(12) * (2.0**bit_depth - 1.0))


def _shot_noise_kernel(photoelectrons):
    with np.errstate(all="ignore"):
        return np.sqrt(photoelectrons)


def _dark_current_noise_kernel(tdi_stages, dark_current, integration_time):
    with np.errstate(all="ignore"):
        return np.sqrt(tdi_stages * dark_current * integration_time)


def _total_noise_kernel(shot_variance, quantization, read, other):
    with np.errstate(all="ignore"):
        return np.sqrt(shot_variance + quantization**2 + read**2 + other**2)


def _stacked_snr_kernel(frame_stacks, snr):
    with np.errstate(all="ignore"):
        return np.sqrt(frame_stacks) * snr


def _chain_total_kernel(target, background, well_range, bit_depth, read, other):
    """Total noise of the brighter of target and background [rms electrons]."""
    quantization = _quantization_noise_kernel(well_range, bit_depth)
    return _total_noise_kernel(np.maximum(target, background), quantization, read, other)


def _snr_frame_kernel(contrast, target, background, well_range, bit_depth, read, other):
    total = _chain_total_kernel(target, background, well_range, bit_depth, read, other)
    with np.errstate(all="ignore"):
        return contrast / total


def _snr_kernel(frame_stacks, contrast, target, background, well_range, bit_depth, read, other):
    snr_frame = _snr_frame_kernel(contrast, target, background, well_range, bit_depth, read, other)
    return _stacked_snr_kernel(frame_stacks, snr_frame)


def _shot_noise_of_brighter_kernel(target, background):
    return _shot_noise_kernel(np.maximum(target, background))


def _rate_noise_kernel(rate, integration_time, tdi_stages):
    """Shot noise of a photoelectron rate over every TDI stage [rms electrons]."""
    with np.errstate(all="ignore"):
        return np.sqrt(rate * (integration_time * tdi_stages))


def _scene_noise_kernel(target_rate, integration_time, tdi_stages, background_rate, path_rate):
    """Scene noise of the brighter of target and background, less the path term."""
    with np.errstate(all="ignore"):
        exposure = integration_time * tdi_stages
        scene_and_path = np.maximum(np.sqrt(target_rate * exposure),
                                    np.sqrt(background_rate * exposure))
        return np.sqrt(scene_and_path**2 - np.sqrt(path_rate * exposure) ** 2)


@contract(Output("shot_noise", "count", "shot noise"))
def shot_noise(photoelectrons):
    """Photon shot noise of a photoelectron count (Poisson).

    Parameters
    ----------
    photoelectrons : float or xr.DataArray
        Mean photoelectron count. [electrons]

    Returns
    -------
    float or xr.DataArray
        [rms electrons]
    """
    return apply_kernel(_shot_noise_kernel, photoelectrons)


@contract(Output("dark_current_noise", "count", "dark current noise"))
def dark_current_noise(dark_current, integration_time, tdi_stages=1.0):
    """Shot noise of the dark current accumulated over all TDI stages.

    Parameters
    ----------
    dark_current : float or xr.DataArray
        [electrons/s]
    integration_time : float or xr.DataArray
        Integration time per stage. [s]
    tdi_stages : float or xr.DataArray
        [1]

    Returns
    -------
    float or xr.DataArray
        [rms electrons]
    """
    return apply_kernel(_dark_current_noise_kernel, tdi_stages, dark_current, integration_time)


@contract(Output("quantization_noise", "count", "quantization noise"))
def quantization_noise(well_range, bit_depth):
    r"""Quantization noise of an ADC spanning ``well_range`` electrons.

    Parameters
    ----------
    well_range : float or xr.DataArray
        Electrons between the smallest and largest code. [electrons]
    bit_depth : float or xr.DataArray
        [bits]

    Returns
    -------
    float or xr.DataArray
        [rms electrons]

    Notes
    -----
    One code step over the uniform-error standard deviation, implicit in IBSM Eq. 3-47:

    .. math:: \sigma_q = \frac{N_{range}}{\sqrt{12}\,(2^b - 1)}
    """
    return apply_kernel(_quantization_noise_kernel, well_range, bit_depth)


_GAIN_OUTPUTS = outputs(Output("noise_gain", "1", "noise gain", carries=("sensor",)))
"""What :func:`noise_gain_arrays` returns."""


@contract(_GAIN_OUTPUTS["noise_gain"])
def noise_gain(kernel: xr.DataArray):
    r"""Noise gain of a post-processing kernel (Leachtenauer et al. 1997).

    Parameters
    ----------
    kernel : xr.DataArray
        Kernel with dims ``kernel_y``, ``kernel_x``, summing to one. [1]

    Returns
    -------
    xr.DataArray
        :math:`\sqrt{\sum k^2}`. [1]

    Notes
    -----
    The kernel's sum is checked (to 1e-9) where the sensor is built, not here
    with exact float equality: [0.7, 0.2, 0.1] sums to 0.9999999999999999.
    """
    out = apply_orchestrator(noise_gain_arrays, _GAIN_OUTPUTS, kernel,
                             core=[["kernel_y", "kernel_x"]])
    return out["noise_gain"]


def noise_gain_arrays(kernel) -> dict:
    """:func:`noise_gain` of plain (..., kernel_y, kernel_x) arrays, as ``noise_gain``."""
    return {"noise_gain": np.sqrt((kernel**2).sum(axis=(-2, -1)))}


@contract(Output("total_noise", "count", "total noise"))
def total_noise(shot_variance, quantization, read, other):
    """Root-sum-square of the independent noise terms.

    Parameters
    ----------
    shot_variance : xr.DataArray
        Shot-noise variance of the brighter of target and background (includes
        dark current and self-emission electrons). [electrons^2]
    quantization, read, other : float or xr.DataArray
        rms noise terms. [rms electrons]

    Returns
    -------
    xr.DataArray
        [rms electrons]
    """
    return apply_kernel(_total_noise_kernel, shot_variance, quantization, read, other)


@contract(Output("stacked_snr", "1", "contrast signal-to-noise ratio"))
def stacked_snr(snr, frame_stacks):
    """SNR after adding ``frame_stacks`` independent frames (grows as the square root).

    Parameters
    ----------
    snr : xr.DataArray
        Single-frame SNR. [1]
    frame_stacks : float or xr.DataArray
        [1]

    Returns
    -------
    xr.DataArray
        [1]
    """
    return apply_kernel(_stacked_snr_kernel, frame_stacks, snr)



def noise_terms(signal: xr.Dataset, sensor: xr.Dataset) -> xr.Dataset:
    """Noise terms of one integration and the contrast SNR, by name (paper Sec. 2.3).

    Parameters
    ----------
    signal : xr.Dataset
        From :func:`xbsm.radiometry.signal_terms`.
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.

    Returns
    -------
    xr.Dataset
        ``shot_noise``, ``scene_noise``, ``path_noise``, ``self_emission_noise``,
        ``dark_current_noise``, ``quantization_noise``, ``read_noise``,
        ``other_noise``, ``total_noise`` [count, rms electrons]; ``snr_frame`` and
        ``snr`` (after frame stacking) [1].

    Notes
    -----
    The total combines the shot noise of the brighter of target and background
    (which includes dark current, path and self-emission) with quantization, read
    and other noise in quadrature; the scene, path and self-emission terms are its
    breakdown (paper Figure 4). The scene term is that of the brighter of target and
    background, without the sensor's own irradiance, less the path term.
    """
    return dataset(apply_orchestrator(noise_arrays, OUTPUTS, *noise_inputs(sensor, signal)))


_SENSOR_INPUTS = ("frame_stacks", "tdi_stages", "max_well", "bit_depth", "read_noise",
                  "other_noise", "dark_current")
_SIGNAL_INPUTS = ("effective_integration_time", "target_photoelectrons",
                  "background_photoelectrons", "contrast_photoelectrons", "target_scene_rate",
                  "background_scene_rate", "path_rate", "sensor_rate")


def noise_inputs(sensor, signal) -> tuple:
    """The arguments of :func:`noise_arrays`, in order.

    From the sensor's parameters and the signal stage's outputs
    (:data:`xbsm.radiometry.SIGNAL_OUTPUTS`), each a mapping by name.
    """
    return (*(sensor[name] for name in _SENSOR_INPUTS),
            *(signal[name] for name in _SIGNAL_INPUTS))


# each output keeps the dims of the arguments its rule reads, in the order it reads them
_TOTAL = ("target_photoelectrons", "background_photoelectrons", "max_well", "bit_depth",
          "read_noise", "other_noise")
_EXPOSURE = ("effective_integration_time", "tdi_stages")
OUTPUTS = outputs(
    Output("snr", "1", "contrast signal-to-noise ratio after frame stacking",
           inputs=("frame_stacks", "contrast_photoelectrons", *_TOTAL)),
    Output("snr_frame", "1", "single-frame contrast signal-to-noise ratio",
           inputs=("contrast_photoelectrons", *_TOTAL)),
    Output("shot_noise", "count", "shot noise", inputs=_TOTAL[:2]),
    Output("scene_noise", "count", "scene noise",
           inputs=("target_scene_rate", *_EXPOSURE, "background_scene_rate", "path_rate")),
    Output("path_noise", "count", "path radiance noise", inputs=("path_rate", *_EXPOSURE)),
    Output("self_emission_noise", "count", "self-emission and stray-light noise",
           inputs=("sensor_rate", *_EXPOSURE)),
    Output("dark_current_noise", "count", "dark current noise",
           inputs=("tdi_stages", "dark_current", "effective_integration_time")),
    Output("quantization_noise", "count", "quantization noise", carries=("sensor",),
           inputs=("max_well", "bit_depth")),
    Output("read_noise", "count", "read noise", carries=("sensor",), inputs=("read_noise",)),
    Output("other_noise", "count", "other noise", carries=("sensor",), inputs=("other_noise",)),
    Output("total_noise", "count", "total noise", inputs=_TOTAL),
)
"""What :func:`noise_arrays` and :func:`noise_terms` return. [count: rms electrons]"""


def noise_arrays(frame_stacks, tdi_stages, max_well, bit_depth, read_noise, other_noise,
                 dark_current, effective_integration_time, target_photoelectrons,
                 background_photoelectrons, contrast_photoelectrons, target_scene_rate,
                 background_scene_rate, path_rate, sensor_rate) -> dict:
    """The noise stage on plain arrays: every output of :data:`OUTPUTS`, by name.

    The sensor's parameters and the signal stage's outputs, by their names (in the order
    :func:`noise_inputs` gives them).
    """
    time, tdi = effective_integration_time, tdi_stages
    target, background = target_photoelectrons, background_photoelectrons
    chain = (target, background, max_well, bit_depth, read_noise, other_noise)
    return {
        "snr": _snr_kernel(frame_stacks, contrast_photoelectrons, *chain),
        "snr_frame": _snr_frame_kernel(contrast_photoelectrons, *chain),
        "shot_noise": _shot_noise_of_brighter_kernel(target, background),
        "scene_noise": _scene_noise_kernel(target_scene_rate, time, tdi, background_scene_rate,
                                           path_rate),
        "path_noise": _rate_noise_kernel(path_rate, time, tdi),
        "self_emission_noise": _rate_noise_kernel(sensor_rate, time, tdi),
        "dark_current_noise": _dark_current_noise_kernel(tdi, dark_current, time),
        "quantization_noise": _quantization_noise_kernel(max_well, bit_depth),
        "read_noise": read_noise,
        "other_noise": other_noise,
        "total_noise": _chain_total_kernel(*chain),
    }


#: The sources of the sensor's own focal-plane irradiance (paper Eq. 2), their noise
#: variables and long names: what :func:`self_emission_noise_terms` splits
#: ``self_emission_noise`` into.
SELF_EMISSION_SOURCES = MappingProxyType({
    "cold_shield_noise": "cold-shield self-emission noise",
    "optics_emission_noise": "optics self-emission noise",
    "cold_filter_emission_noise": "cold-filter (cold stop) self-emission noise",
    "stray_light_noise": "stray-light noise",
})


def _share_noise_kernel(total, *rates):
    """Each rate's share of a Poisson noise: sqrt(rate / sum) x total (0 where nothing)."""
    whole = sum(rates)
    with np.errstate(invalid="ignore", divide="ignore"):
        return tuple(np.where(whole > 0, total * np.sqrt(np.clip(rate, 0.0, None) / whole), 0.0)
                     for rate in rates)


def self_emission_noise_terms(self_emission_noise, sensor: xr.Dataset,
                              wavelength: xr.DataArray, constants=CODATA) -> xr.Dataset:
    r"""Self-emission and stray-light noise split by source.

    The sources are the cold shield, the warm optics, the cold filter (cold
    stop) and stray light (paper Eq. 2).

    The sensor's own photoelectrons are Poisson: their variance is the sum of
    each source's photoelectrons, so each source's noise is the total noise
    times the square root of its share of the band-integrated photoelectron
    rate. The four terms add in quadrature to ``self_emission_noise``.

    Parameters
    ----------
    self_emission_noise : xr.DataArray
        From :func:`xbsm.snr` (or :func:`noise_terms`). [count]
    sensor : xr.Dataset
        From :func:`xbsm.sensor`: temperatures, emissivities, cold-filter
        transmission, stray irradiance, quantum efficiency, optics.
    wavelength : xr.DataArray
        The band's wavelengths (the ``wavelength`` coordinate of :func:`xbsm.snr`,
        or any grid spanning the band). [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.Dataset
        ``cold_shield_noise``, ``optics_emission_noise``,
        ``cold_filter_emission_noise``, ``stray_light_noise`` [count, rms electrons].

    Notes
    -----
    .. math:: \sigma_i = \sigma_{\mathrm{self}}\sqrt{N_i / \textstyle\sum_j N_j},
       \qquad N_i \propto \int \frac{\lambda}{hc}\,\eta(\lambda)\,E_i(\lambda)\,d\lambda

    with :math:`E_i` the focal-plane irradiance of each source (paper Eq. 2).
    """
    s = sensor
    lens = (s["aperture_diameter"], s["focal_length"])
    irradiances = (
        radiometry.cold_shield_self_emission(wavelength, s["cold_shield_temperature"], *lens,
                                             constants),
        radiometry.optics_self_emission(wavelength, s["optics_temperature"],
                                        s["optics_emissivity"], s["cold_filter_transmission"],
                                        *lens, constants),
        radiometry.cold_stop_self_emission(wavelength, s["cold_filter_temperature"],
                                           s["cold_filter_emissivity"], *lens, constants),
        xr.zeros_like(wavelength, dtype=float) + radiometry.resample_spectral(
            s["stray_irradiance"], wavelength, "stray_irradiance"),
    )
    qe = radiometry.resample_spectral(s["quantum_efficiency"], wavelength, "quantum_efficiency")
    rates = [radiometry.band_integral(radiometry.photon_detection_rate(
        irradiance.assign_coords(wavelength=wavelength), qe, s["detector_width_x"],
        s["detector_width_y"], constants)) for irradiance in irradiances]
    parts = xr.apply_ufunc(_share_noise_kernel, self_emission_noise, *rates,
                           output_core_dims=[[]] * len(rates), dask="parallelized",
                           output_dtypes=[float] * len(rates))
    return dataset({name: named(part, "count", long_name)
                    for (name, long_name), part in zip(SELF_EMISSION_SOURCES.items(), parts,
                                                       strict=True)})
