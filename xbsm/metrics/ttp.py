r"""Target acquisition: the system contrast threshold, the TTP metric and P(task).

The chain of the US Army's target-acquisition models (NVThermIP / NV-IPM heritage),
in data-flow order:

1. :func:`noise_bandwidths`: how much displayed noise the eye sees through its optics
   (:func:`xbsm.metrics.eye.eye_mtf`), the display and the visual channel
   (:func:`xbsm.metrics.eye.visual_channel`), per sensor and display.
2. :func:`system_ctf_kernel`: the system contrast threshold function, the eye's CTF
   at the displayed frequency over the system MTF (pre-sample MTF times the display's),
   raised by the noise the eye sees: temporal noise and, for a sampled imager, the
   aliased signal treated as static noise.
3. :func:`ttp_kernel`: the TTP integral over the frequencies where the target's
   displayed contrast exceeds the threshold, and the limiting frequency (for the
   Johnson criteria).
4. :func:`task_probability` / :func:`johnson_probability`: cycles on target
   V = TTP sqrt(area) / range against the task's V50 (or N50).

Each kernel takes plain arrays (the frequency axis last); :func:`targeting_arrays`
runs 2-3 on one sweep block. :func:`xbsm.target_acquisition` is the public door.
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np
import xarray as xr
from scipy.integrate import trapezoid  # numpy.trapezoid needs numpy 2 (floor 1.24)

from .._kernels import apply_kernel
from .._metadata import Output, declared, outputs
from . import eye as eye_

TASKS = ("detect", "recognize", "identify")
"""The tasks, in order of difficulty."""

CRITERIA = ("ttp", "johnson")
"""How cycles on target are counted: the TTP metric, or Johnson's limiting frequency."""

TTP_V50 = MappingProxyType({
    "vehicles_open_source": MappingProxyType({
        "detect": 2.0, "recognize": 7.5, "identify": 13.0,
        "source": "values used for detection, recognition and identification by MITRE's "
                  "open TTP implementation IRwhaleDetect.m (Apache-2.0, 2025), found with "
                  "the project's search tools; the NVESD tables they come from "
                  "(Vollmerhausen & Jacobs, NVESD TR AMSEL-NV-TR-230, 2004, and later "
                  "NV-IPM documentation) could not be read with those tools, so these are "
                  "a secondary transcription: pass your own V50 for a calibrated target set"}),
})
"""V50 of the TTP metric per task: cycles on target at which half of the observers
perform the task, by target set, each with its source."""

JOHNSON_N50 = MappingProxyType({
    "johnson_1958": MappingProxyType({
        "detect": 1.0, "recognize": 4.0, "identify": 6.4,
        "source": "Johnson, 'Analysis of image forming systems', Image Intensifier "
                  "Symposium, Fort Belvoir, 1958: cycles (line pairs) across the target's "
                  "critical dimension at 50 % probability, as restated throughout the "
                  "literature (e.g. Ratches et al., NVL static performance model, 1975)"}),
    "nvesd_2d": MappingProxyType({
        "detect": 0.75, "recognize": 3.0, "identify": 6.0,
        "source": "the NVESD two-dimensional (sqrt(area)) cycle criteria of ACQUIRE / "
                  "FLIR92 (Driggers, Vollmerhausen et al.; as restated in the "
                  "target-acquisition literature)"}),
})
"""N50 of the Johnson criteria per task (cycles across the characteristic dimension
at the limiting frequency), by set, each with its source."""

OUTPUTS = outputs(
    Output("probability", "1", "probability of performing the task", dims=("task",)),
    Output("cycles_on_target", "1", "cycles on target by the chosen criterion"),
    Output("ttp", "cycles/rad", "targeting task performance metric (geometric mean of x, y)"),
    Output("limiting_frequency", "cycles/rad",
           "highest frequency the target's contrast is above the system threshold"),
    Output("ctf_system", "1", "system contrast threshold function",
           dims=("orientation", "frequency")),
    Output("displayed_target_size", "deg", "angular size of the target at the eye"),
)
"""The target-acquisition outputs, declared."""

TTPF_OFFSET, TTPF_SLOPE = 1.51, 0.24
"""E = 1.51 + 0.24 V / V50 of the TTP metric's probability function (as the issue states
it, after Vollmerhausen & Jacobs, NVESD TR-230, 2004). The later NVESD form, E = 1.5
(US patent 9,152,880, claim 2; MITRE's open ``IRwhaleDetect.m``), is
``task_probability(v, v50, offset=1.5, slope=0.0)``: the same P = 0.5 at V50, lower P
above it (0.739 against 0.799 at 2 V50)."""
JOHNSON_OFFSET, JOHNSON_SLOPE = 2.7, 0.7
"""E = 2.7 + 0.7 N / N50 of the classic Johnson-criteria probability function (NVL 1975)."""


def task_probability(cycles, v50, offset=TTPF_OFFSET, slope=TTPF_SLOPE):
    r"""Probability of performing a task from cycles on target (target transfer function).

    .. math:: P = \frac{(V/V_{50})^E}{1 + (V/V_{50})^E},\qquad E = 1.51 + 0.24\,V/V_{50}

    ``cycles`` V >= 0 and ``v50`` > 0 broadcast (arrays or DataArrays); P in [0, 1),
    0 at V = 0, 0.5 at V = V50. [1]
    """
    ratio = cycles / v50
    exponent = offset + slope * ratio
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        # (r^E) / (1 + r^E) = 1 / (1 + exp(-E ln r)): no overflow, 0 at r = 0, 1 at r = inf
        return 1.0 / (1.0 + np.exp(-exponent * np.log(ratio)))


def johnson_probability(cycles, n50):
    r"""Probability of a task by the Johnson criteria [1].

    .. math:: P = \frac{(N/N_{50})^E}{1 + (N/N_{50})^E},\qquad E = 2.7 + 0.7\,N/N_{50}
    """
    return task_probability(cycles, n50, JOHNSON_OFFSET, JOHNSON_SLOPE)


def noise_bandwidths(frequency, spacing, magnification, luminance):
    r"""The eye's noise bandwidths through display and eye, on plain arrays.

    Parameters
    ----------
    frequency : ndarray
        Object-space frequencies, on the last axis, each in (0, inf). [cycles/rad]
    spacing : ndarray
        Angular sample spacing across the frequency. [rad]
    magnification : ndarray
        Angle at the eye over angle in object space. [1]
    luminance : float
        Display luminance. [cd/m^2]

    Returns
    -------
    channel : ndarray
        :math:`Q_c(\xi) = \int_0^{1/\delta} |B(\xi'/\xi)\,H_d(\xi')\,H_{eye}(\xi'/M)|^2
        d\xi'` on the frequency axis [cycles/rad].
    full : ndarray
        :math:`Q_f = \int_0^{1/\delta} |H_d(\eta)\,H_{eye}(\eta/M)|^2 d\eta`, the
        bandwidth along the other axis (no channel across it) [cycles/rad].

    Notes
    -----
    H_d(xi) = sinc(delta xi), the display's rectangular pixel (one display pixel per
    sample); H_eye from :func:`xbsm.metrics.eye.eye_mtf` at a 10 deg field. The
    integrals run over one period of the sampled noise spectrum, as NVThermIP
    integrates to the sampling frequency. Quadrature: Q_f by 96-node Gauss-Legendre;
    Q_c in u = ln(xi' / xi), where B^2 = exp(-4.4 u^2) is a Gaussian of width 0.34, by
    the trapezoidal rule on 241 nodes over -3 <= u <= 3 (B^2 < 1e-17 beyond), which
    converges like Gauss-Hermite for the smooth rest of the integrand.
    """
    spacing = np.asarray(spacing, dtype=float)[..., None]
    magnification = np.asarray(magnification, dtype=float)[..., None]
    top = 1.0 / spacing
    to_cpd = math.pi / 180.0

    def gain(nodes, spacing, magnification):
        value = (np.sinc(spacing * nodes)
                 * eye_.eye_mtf(nodes / magnification * to_cpd, luminance)) ** 2
        return np.where(nodes * spacing <= 1.0, value, 0.0)

    x, w = np.polynomial.legendre.leggauss(96)
    nodes = 0.5 * top * (x + 1.0)
    full = 0.5 * top[..., 0] * np.sum(w * gain(nodes, spacing, magnification), axis=-1)
    u = np.linspace(-3.0, 3.0, 241)
    frequency = np.asarray(frequency, dtype=float)[..., :, None]       # (..., n, 1)
    stretched = frequency * np.exp(u)                                  # (..., n, 241)
    integrand = np.exp(-2.0 * eye_.CHANNEL_WIDTH * u * u) * stretched * gain(
        stretched, spacing[..., None], magnification[..., None])
    channel = trapezoid(integrand, u, axis=-1)
    return channel, full


def aliasing_ratio(frequency, mtf, spacing):
    r"""Power of the pre-sample MTF above the Nyquist frequency over that below it [1].

    .. math:: R = \frac{\int_{1/(2\delta)}^{1/\delta} |H_{pre}|^2\,d\xi}
        {\int_0^{1/(2\delta)} |H_{pre}|^2\,d\xi}

    The signal above Nyquist folds back into the band as spurious response.
    ``frequency``: the 1-D increasing grid (H_pre = 1 at 0 is added before it);
    ``mtf``: (..., n); ``spacing``: (...). Trapezoidal on the grid, with the integral's
    ends at Nyquist and twice Nyquist placed exactly in their intervals (the trapezoid
    of the linear interpolant), so the error is O(h^2).
    """
    grid = np.concatenate([[0.0], np.asarray(frequency, dtype=float).reshape(-1)])
    power = np.abs(np.asarray(mtf, dtype=float)) ** 2
    power = np.concatenate([np.ones(power.shape[:-1] + (1,)), power], axis=-1)
    steps = 0.5 * np.diff(grid) * (power[..., 1:] + power[..., :-1])
    cumulative = np.concatenate([np.zeros(power.shape[:-1] + (1,)), np.cumsum(steps, -1)],
                                axis=-1)

    def integral_to(x):
        x = np.broadcast_to(x, power.shape[:-1])[..., None]
        i = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, grid.size - 2)
        x = np.minimum(x, grid[-1])
        g0, g1 = grid[i], grid[i + 1]
        p0 = np.take_along_axis(power, i, -1)
        p1 = np.take_along_axis(power, i + 1, -1)
        px = p0 + (p1 - p0) * (x - g0) / (g1 - g0)
        return (np.take_along_axis(cumulative, i, -1) + 0.5 * (x - g0) * (p0 + px))[..., 0]

    nyquist = 0.5 / np.asarray(spacing, dtype=float)
    below = integral_to(nyquist)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (integral_to(2.0 * nyquist) - below) / below


def system_ctf_kernel(frequency, mtf, spacing, magnification, channel, full, snr,
                      field_size, aliasing, *, luminance, contrast, eye, eyes,
                      noise_constant, eye_integration_time, frame_rate):
    r"""System contrast threshold function on plain arrays, shape (..., 2, n).

    Axis -2 is the orientation (x, y), axis -1 the frequency. ``mtf``: pre-sample
    system MTF; ``spacing``, ``magnification``, ``full``: per orientation (..., 2);
    ``channel``: (..., 2, n); ``snr``: single-frame contrast SNR of the target; ``field_size``
    [deg]; ``aliasing``: :func:`aliasing_ratio` summed over x and y (0: no aliasing
    noise).

    .. math::

        \mathrm{CTF_{sys}}(\xi) = \frac{\mathrm{CTF}_{eye}(\xi / M)}{H_{pre}(\xi) H_d(\xi)}
        \sqrt{1 + \alpha^2\left(\rho^2 + \rho_A^2\right) Q_c(\xi)\, Q_f'}

    with rho^2 = (2 C / SNR)^2 delta_x delta_y / F_R the temporal noise spectral density
    of the displayed contrast (C the displayed target contrast: the display gain puts the
    target-background difference at C, so one frame's pixel noise is 2 C / SNR in
    contrast), rho_A^2 = C^2 R delta_x delta_y t_e the aliased signal as static noise
    (Vollmerhausen, Driggers & Wilson, JOSA A 25(8), 2008, in xbsm's reading:
    spurious power R of :func:`aliasing_ratio` spread as white noise, not averaged over
    frames), alpha the eye's noise constant, Q_f' the full bandwidth across.
    """
    frequency = np.asarray(frequency, dtype=float)
    spacing = np.asarray(spacing, dtype=float)
    magnification = np.asarray(magnification, dtype=float)
    display = np.sinc(spacing[..., None] * frequency)
    transfer = np.abs(mtf) * display
    to_cpd = math.pi / 180.0
    threshold = eye_.eye_ctf(frequency / magnification[..., None] * to_cpd, luminance,
                             np.asarray(field_size)[..., None, None], eye, eyes)
    area = spacing[..., 0] * spacing[..., 1]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        temporal = (2.0 * contrast / np.abs(snr)) ** 2 * area / frame_rate
        static = contrast ** 2 * np.asarray(aliasing) * area * eye_integration_time
        across = np.asarray(full)[..., ::-1]                          # the other axis
        density = (temporal + static)[..., None, None]
        factor = np.sqrt(1.0 + noise_constant ** 2 * density * channel * across[..., None])
        out = threshold * factor / transfer
    return np.where(transfer > 0.0, out, np.inf)


def ttp_kernel(frequency, ctf, contrast):
    r"""TTP integral and limiting frequency of each orientation, on plain arrays.

    .. math:: \mathrm{TTP} = \int_{C > \mathrm{CTF_{sys}}}
        \sqrt{\frac{C}{\mathrm{CTF_{sys}}(\xi)}}\,d\xi

    Trapezoidal on the grid (which starts at xi = 0, where the integrand is 0, before
    the first node), with the end of each interval where C > CTF_sys found by linear
    interpolation of C / CTF_sys to 1, so that the jump of the integrand from 1 to 0 is
    integrated exactly for a piecewise-linear ratio. Returns (ttp, limit) over (..., 2):
    [cycles/rad]; the limit is the highest frequency with C >= CTF_sys (0 if none).
    """
    frequency = np.asarray(frequency, dtype=float)
    grid = np.concatenate([[0.0], frequency])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = contrast / np.asarray(ctf)
    ratio = np.where(np.isfinite(ratio), ratio, 0.0)
    ratio = np.concatenate([np.zeros(ratio.shape[:-1] + (1,)), ratio], axis=-1)
    a, b = ratio[..., :-1], ratio[..., 1:]
    step = np.diff(grid)
    above_a, above_b = a >= 1.0, b >= 1.0
    root_a, root_b = np.sqrt(np.where(above_a, a, 0.0)), np.sqrt(np.where(above_b, b, 0.0))
    full = 0.5 * step * (root_a + root_b)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a - 1.0) / (a - b)                 # where the linear ratio crosses 1
    down = 0.5 * step * t * (root_a + 1.0)      # above at the start, below at the end
    up = 0.5 * step * (1.0 - t) * (1.0 + root_b)
    pieces = np.where(above_a & above_b, full,
                      np.where(above_a, down, np.where(above_b, up, 0.0)))
    ttp = pieces.sum(axis=-1)
    crossing = np.where(above_a & ~above_b, grid[:-1] + t * step,
                        np.where(above_b, grid[1:], 0.0))
    return ttp, crossing.max(axis=-1)


def targeting_arrays(frequency, mtf, spacing, magnification, channel, full, snr, slant_range,
                     size, *, luminance, contrast, eye, eyes, noise_constant,
                     eye_integration_time, frame_rate, aliasing, with_ctf=False):
    """TTP, limiting frequency and cycles on target of one block of scenarios.

    The orchestrator of steps 2-3 on plain arrays (orientation and frequency the last
    two axes of ``mtf``). Returns (ttp, limit, ttp_cycles, johnson_cycles): the
    geometric means over x and y [cycles/rad], then cycles on target [1]; with
    ``with_ctf`` also the system CTF (..., 2, n) and the field size at the eye [deg].
    """
    magnification = np.asarray(magnification, dtype=float)
    geometric = np.sqrt(magnification[..., 0] * magnification[..., 1])
    field = np.degrees(geometric * size / slant_range)
    ratio = aliasing_ratio(frequency, mtf, spacing).sum(-1) if aliasing else 0.0
    ctf = system_ctf_kernel(frequency, mtf, spacing, magnification, channel, full, snr,
                            field, ratio, luminance=luminance, contrast=contrast, eye=eye,
                            eyes=eyes, noise_constant=noise_constant,
                            eye_integration_time=eye_integration_time,
                            frame_rate=frame_rate)
    per_axis, limits = ttp_kernel(frequency, ctf, contrast)
    known = np.isfinite(snr) & np.all(np.isfinite(mtf), axis=(-2, -1))  # NaN stays NaN
    ttp = np.where(known, np.sqrt(per_axis[..., 0] * per_axis[..., 1]), np.nan)
    limit = np.where(known, np.sqrt(limits[..., 0] * limits[..., 1]), np.nan)
    out = (ttp, limit, ttp * size / slant_range, limit * size / slant_range)
    return out + (ctf, field) if with_ctf else out


def targeting(frequency, mtf, spacing, snr, slant_range, size, *, display_pixel_angle,
              luminance, contrast, eye, eyes, noise_constant, eye_integration_time,
              frame_rate, aliasing):
    """Labelled steps 1-3: noise bandwidths, system CTF, TTP and cycles on target.

    ``mtf`` and ``spacing`` carry the dim ``orientation`` (x, y); ``frequency`` is 1-D on
    ``frequency``; ``snr`` (single frame), ``slant_range`` [m] and ``size`` [m] broadcast.
    The magnification is ``display_pixel_angle`` over ``spacing`` (one display pixel per
    sample). Returns a dict of labelled DataArrays (see :data:`OUTPUTS`), without
    ``probability``.
    """
    magnification = display_pixel_angle / spacing
    channel, full = apply_kernel(noise_bandwidths, frequency, spacing, magnification,
                                 core=[["frequency"], [], []], outputs=[["frequency"], []],
                                 luminance=luminance)
    knobs = {"luminance": luminance, "contrast": contrast, "eye": eye, "eyes": eyes,
             "noise_constant": noise_constant, "eye_integration_time": eye_integration_time,
             "frame_rate": frame_rate, "aliasing": aliasing}
    pair, both = ["orientation"], ["orientation", "frequency"]
    ttp, limit, cycles, johnson, ctf, field = apply_kernel(
        _targeting_block, frequency, mtf, spacing, magnification, channel, full, snr,
        slant_range, size, core=[["frequency"], both, pair, pair, both, pair, [], [], []],
        outputs=[[], [], [], [], both, []], **knobs)
    return {"ttp": declared(ttp, OUTPUTS["ttp"]),
            "limiting_frequency": declared(limit, OUTPUTS["limiting_frequency"]),
            "ttp_cycles": cycles, "johnson_cycles": johnson,
            "ctf_system": declared(ctf, OUTPUTS["ctf_system"]),
            "displayed_target_size": declared(field, OUTPUTS["displayed_target_size"])}


def _targeting_block(frequency, mtf, spacing, magnification, channel, full, snr,
                     slant_range, size, **knobs):
    """:func:`targeting_arrays` with the system CTF and the field size.

    Every output on the block's whole broadcast shape (as ``apply_ufunc`` requires).
    """
    frequency = np.asarray(frequency).reshape(-1)
    shape = np.broadcast_shapes(np.shape(mtf)[:-2], np.shape(channel)[:-2], np.shape(snr),
                                np.shape(slant_range), np.shape(size),
                                np.shape(spacing)[:-1], np.shape(magnification)[:-1],
                                np.shape(full)[:-1])
    out = targeting_arrays(frequency, mtf, spacing, magnification, channel, full, snr,
                           slant_range, size, with_ctf=True, **knobs)
    return tuple(np.broadcast_to(a, shape + np.shape(a)[len(np.shape(a)) - core:])
                 for a, core in zip(out, (0, 0, 0, 0, 2, 0), strict=True))


def probabilities(cycles, table, criterion="ttp") -> xr.DataArray:
    """P(task) over dim ``task`` from cycles on target and a table of V50 (or N50).

    ``table``: a mapping task -> V50 (extra keys such as ``source`` ignored) or a
    DataArray on dim ``task``.
    """
    if not isinstance(table, xr.DataArray):
        tasks = [t for t in TASKS if t in table]
        table = xr.DataArray([float(table[t]) for t in tasks], dims="task",
                             coords={"task": tasks})
    law = johnson_probability if criterion == "johnson" else task_probability
    return declared(law(cycles, table), OUTPUTS["probability"])


def cycles_for_probability(probability, v50, criterion="ttp"):
    r"""Cycles on target at which a task reaches ``probability`` (inverse of P(task)) [1].

    Solves P(V) = p for V by bisection on V / V50 in (0, 50] (P rises monotonically
    with V), to 1e-12 relative; ``probability`` in (0, 1), arrays broadcast.
    """
    offset, slope = ((JOHNSON_OFFSET, JOHNSON_SLOPE) if criterion == "johnson"
                     else (TTPF_OFFSET, TTPF_SLOPE))
    target = np.asarray(probability, dtype=float)
    low, high = np.zeros_like(target), np.full_like(target, 50.0)
    for _ in range(60):
        middle = 0.5 * (low + high)
        below = task_probability(middle, 1.0, offset, slope) < target
        low, high = np.where(below, middle, low), np.where(below, high, middle)
    return 0.5 * (low + high) * np.asarray(v50, dtype=float)


def johnson_range(critical_dimension, cycles, sample_spacing):
    r"""Range at which a target spans ``cycles`` cycles at the sampling Nyquist limit [m].

    .. math:: R = \frac{d_c}{2\,N\,\delta}

    The geometric "pixels on target" form of the Johnson criteria (two samples per
    cycle), with d_c the critical dimension [m], N the cycles and delta the angular
    sample spacing (pitch / focal length) [rad]; no blur, noise or eye.
    """
    return critical_dimension / (2.0 * cycles * sample_spacing)
