"""Target-acquisition figures of merit: minimum resolvable temperature difference and contrast.

The bar-pattern threshold of the classic static performance model (Ratches et al.,
NVL 1975; its FLIR92 / NVTherm descendants): the temperature difference of a
four-bar target, bars ``bar_aspect`` (7) times as long as they are wide, at which an
observer who integrates the displayed noise over one bar and over the eye's
integration time sees the bars at a signal-to-noise ratio ``snr_threshold``. With a
noise-equivalent contrast in place of the NETD, the same threshold is the minimum
resolvable contrast (MRC) of reflective bands.

Only the sensor is modelled: no display MTF, no eye MTF and no eye contrast
threshold (issue 25 item 3), so the MRTD falls to 0 with the bar frequency instead of
rising at low frequencies as a measured one does.
"""

from __future__ import annotations

import math

import numpy as np

from .._kernels import apply_kernel
from .._metadata import Output, outputs

BAR_ASPECT = 7.0
"""Length over width of each bar of the standard MRTD four-bar target."""
SNR_THRESHOLD = 2.5
"""Default threshold SNR at which the bars are just resolved."""
EYE_INTEGRATION_TIME = 0.1
"""Default integration time of the eye. [s]"""
FRAME_RATE = 30.0
"""Default displayed frame rate. [Hz]"""

OUTPUTS = outputs(
    Output("mrtd", "K", "minimum resolvable temperature difference",
           dims=("orientation", "frequency")),
    Output("mtf", "1", "system MTF across the bars", dims=("orientation", "frequency")),
    Output("mrc", "1", "minimum resolvable contrast", dims=("orientation", "frequency")),
    Output("noise_equivalent_contrast", "1",
           "noise-equivalent Weber contrast of the scene in one frame"),
    Output("reflectance_signal", "count",
           "photoelectrons of the scene over those of a black surface"),
)
"""The MRTD's outputs, declared."""


def bar_constant(bar_aspect=BAR_ASPECT) -> float:
    """The MRTD's constant pi^2 / (4 sqrt(bar_aspect)): 0.93259 for 7:1 bars.

    Equal to the classic pi^2 / (4 sqrt(14)) times sqrt(1 / (delta_f tau)) with the
    integrate-and-dump noise bandwidth delta_f = 1 / (2 tau) of a staring detector.
    """
    return math.pi ** 2 / (4.0 * math.sqrt(bar_aspect))


def minimum_resolvable_kernel(noise_equivalent, mtf, frequency, sample_area, *, snr_threshold,
                              eye_integration_time, frame_rate, bar_aspect):
    """The bar-pattern threshold on plain arrays; inf where the MTF is at or below zero."""
    spread = np.sqrt(sample_area / (eye_integration_time * frame_rate))
    numerator = (bar_constant(bar_aspect) * snr_threshold * noise_equivalent * frequency
                 * spread)
    mtf = np.abs(mtf)
    return np.where(mtf > 0.0, numerator / np.where(mtf > 0.0, mtf, 1.0), np.inf)


def minimum_resolvable(noise_equivalent, mtf, sample_spacing_x, sample_spacing_y, *,
                       snr_threshold=SNR_THRESHOLD, eye_integration_time=EYE_INTEGRATION_TIME,
                       frame_rate=FRAME_RATE, bar_aspect=BAR_ASPECT):
    r"""Minimum resolvable temperature difference of four-bar targets against bar frequency.

    Parameters
    ----------
    noise_equivalent : float or xr.DataArray
        Single-frame, single-pixel noise-equivalent temperature difference (NETD) [K];
        or noise-equivalent contrast, for the MRC [1].
    mtf : xr.DataArray
        System OTF (its modulus is used) across the bars, on dims ``orientation`` (x:
        bars modulated along x, y: along y) and ``frequency`` (its coordinate: the bar
        frequency, one over the bar-plus-space period). [1]
    sample_spacing_x, sample_spacing_y : float or xr.DataArray
        Angular sample spacing (pixel pitch over focal length) along x and y. [rad]
    snr_threshold : float
        SNR at which the bars are just resolved. [1]
    eye_integration_time : float
        Time over which the eye adds displayed frames. [s]
    frame_rate : float
        Rate of independent displayed frames. [Hz]
    bar_aspect : float
        Bar length over bar width (7 for the standard target). [1]

    Returns
    -------
    xr.DataArray
        MRTD over ``orientation``, ``frequency`` and the inputs' dims; inf where the
        MTF is at or below zero. [K] (MRC [1] from a noise-equivalent contrast)

    Notes
    -----
    .. math::

        \mathrm{MRTD}(f) = \frac{\pi^2}{4\sqrt{a}}\,\mathrm{SNR_{th}}\,
        \mathrm{NETD}\,\frac{f}{|\mathrm{OTF}(f)|}
        \sqrt{\frac{\alpha\,\beta}{t_e\,F_R}}

    with a = ``bar_aspect``, alpha and beta the sample spacings, t_e the eye's
    integration time and F_R the frame rate. Derivation: the square-wave bars of
    temperature difference dT differ, bar against space and after the MTF, by the
    fundamental's 8 / pi^2 dT MTF(f); one bar (width 1 / (2 f), length a / (2 f))
    covers a / (4 f^2 alpha beta) samples in each of t_e F_R frames, over which the
    eye averages the white single-frame noise NETD. Setting the ratio to SNR_th gives
    the equation. It is the classic static-performance-model form
    pi^2 / (4 sqrt(14)) SNR_th NETD f sqrt(alpha beta / (t_e F_R delta_f tau)) / MTF
    (Ratches et al. 1975, as reproduced by Holst, *Electro-Optical Imaging System
    Performance*, and in the FLIR92 / NVTherm lineage) with the staring detector's
    delta_f tau = 1 / 2; the equation numbers of those texts could not be checked
    with the search tools available to this project. No display or eye MTF.
    """
    out = apply_kernel(minimum_resolvable_kernel, noise_equivalent, mtf, mtf["frequency"],
                       sample_spacing_x * sample_spacing_y, snr_threshold=snr_threshold,
                       eye_integration_time=eye_integration_time, frame_rate=frame_rate,
                       bar_aspect=bar_aspect)
    return out.assign_attrs(OUTPUTS["mrtd"].attrs())
