"""The public doors of the model chain: snr, netd, mrtd, mrc, niirs and system_otf.

Each checks its inputs, resolves the method and enters :mod:`xbsm._chain`, which
composes the stages (parameters -> atmosphere -> radiometry -> noise -> (OTF ->
GIQE)) once. The results are datasets of named intermediate results; every sweep
dimension of the inputs is kept.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import _chain, metrics, params
from .methods import method as resolve_method
from .metrics import acquisition
from .params import POSITIVE, Choice, Either, Instance, Resolved, Spec, check_inputs, contract
from .radiometry import TARGETS, check_target_set, targets_on_scenario

_METHOD = Resolved(resolve_method)
_TARGETS = Either(Choice(TARGETS), Instance(xr.Dataset, "a target set from "
                                            "xbsm.radiometry.target_set(...)"))


def _targets(sensor: xr.Dataset, scenario: xr.Dataset, targets):
    """Checked inputs, with a target set's targets put on the scenario's background."""
    check_inputs(sensor, scenario)
    if isinstance(targets, str):
        return scenario, targets
    scenario = targets_on_scenario(scenario, check_target_set("targets", targets))
    check_inputs(sensor, scenario)  # each target's reflectance in [0, 1]
    return scenario, "scenario"


@contract(method=_METHOD, targets=_TARGETS)
def snr(sensor: xr.Dataset, scenario: xr.Dataset, method="accurate", *, targets="giqe"):
    """Contrast signal-to-noise ratio and its breakdown (paper Sec. 2.2-2.3, Figure 4).

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    scenario : xr.Dataset
        From :func:`xbsm.scenario`.
    method : str or Method
        "accurate" (default), "fast" or "pybsm", or a :class:`xbsm.methods.Method`.
    targets : {"giqe", "scenario"} or xr.Dataset
        "giqe": the GIQE standard target and background (15% / 7% at 282 K /
        280 K; reflectance 0 in bands starting at or beyond 2.9 um), as the
        NIIRS chain uses; "scenario": the scenario's own reflectances and
        temperatures; or a target set (:func:`xbsm.radiometry.target_set`,
        :func:`xbsm.radiometry.standard_targets`): each target on the scenario's
        background, over dim ``target``.

    Returns
    -------
    xr.Dataset
        ``snr`` (after frame stacking), ``snr_frame``, ``effective_integration_time``,
        ``target_photoelectrons``, ``background_photoelectrons``,
        ``contrast_photoelectrons``, ``well_fill``, every noise term
        (``shot_noise``, ``scene_noise``, ``path_noise``, ``self_emission_noise``,
        ``dark_current_noise``, ``quantization_noise``, ``read_noise``,
        ``other_noise``, ``total_noise``), ``spectral_weights`` (the target's
        spectral photoelectron rate, which weights the OTFs, paper Eq. 3) and
        ``flags``.
    """
    scenario, targets = _targets(sensor, scenario, targets)
    return _chain.snr(sensor, scenario, method, targets)


@contract(method=_METHOD)
def netd(sensor: xr.Dataset, scenario: xr.Dataset, method="accurate", *, temperature=300.0,
         reflectance=0.0):
    """Noise-equivalent temperature difference, radiance and irradiance of a uniform scene.

    The temperature difference of the scene that gives a contrast SNR of 1 (after frame
    stacking, as :func:`snr`'s): the SNR chain's total noise over the temperature
    derivative of the scene's photoelectrons, both at ``temperature``.

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    scenario : xr.Dataset
        From :func:`xbsm.scenario`: the path (its transmission, path radiance and
        scattered sunlight); its own target and background are replaced by the scene.
    method : str or Method
        "accurate" (default), "fast" or "pybsm", or a :class:`xbsm.methods.Method`.
    temperature : float, array_like or xr.DataArray
        Scene temperature, in (0, inf); a 1-D sequence sweeps on dim ``temperature``. [K]
    reflectance : float or xr.DataArray
        Scene reflectance in [0, 1]; its emissivity is 1 - ``reflectance`` (default 0:
        a blackbody). [1]

    Returns
    -------
    xr.Dataset
        ``netd`` and ``netd_frame`` [K]; ``ner``, the noise-equivalent band radiance at
        the aperture, and ``ner_target``, leaving the scene [W m-2 sr-1]; ``nei``, the
        noise-equivalent band irradiance at the entrance pupil [W m-2];
        ``signal_derivative`` [count K-1]; the scene's ``target_photoelectrons``,
        ``effective_integration_time``, ``well_fill``, every noise term and
        ``spectral_weights`` as :func:`snr` gives them; ``flags``
        (``well_fill_limited`` where the integration time was shortened,
        ``no_thermal_signal`` where the signal does not grow with temperature).

    Notes
    -----
    The noise is the chain's total (:func:`xbsm.noise.noise_terms`): shot noise of the
    scene's photoelectrons, which include the path radiance, scattered sunlight,
    the sensor's self-emission and stray light, and dark current; quantization, read and
    other noise; :func:`xbsm.radiometry.noise_equivalent_terms` gives the formulas.
    NER and NEI are the band-integrated radiance and irradiance changes, with the
    spectral shape of the Planck derivative at ``temperature``, that give SNR 1.
    """
    return _chain.netd(sensor, _scene(sensor, scenario, temperature, reflectance), method)


def _scene(sensor, scenario, temperature, reflectance) -> xr.Dataset:
    """The checked scenario with its target and background replaced by a uniform scene."""
    if not isinstance(temperature, xr.DataArray) and np.ndim(temperature):
        temperature = params.labelled("temperature", temperature, "temperature")
    temperature = params.argument("temperature", temperature, ("temperature",))
    reflectance = params.argument("reflectance", reflectance)
    check_inputs(sensor, scenario)
    scene = {"target_temperature": temperature, "background_temperature": temperature,
             "target_reflectance": reflectance, "background_reflectance": reflectance}
    scenario = scenario.assign({name: value.assign_attrs(scenario[name].attrs)
                                for name, value in scene.items()})
    check_inputs(sensor, scenario)
    return scenario


_OBSERVER = {
    "snr_threshold": Spec("1", "threshold SNR of the just-resolved bars", **POSITIVE),
    "eye_integration_time": Spec("s", "integration time of the eye", **POSITIVE),
    "frame_rate": Spec("Hz", "displayed frame rate", **POSITIVE),
    "bar_aspect": Spec("1", "bar length over bar width", low=1.0),
}


@contract(method=_METHOD, **_OBSERVER)
def mrtd(sensor: xr.Dataset, scenario: xr.Dataset, frequency=None, method="accurate", *,
         temperature=300.0, reflectance=0.0, snr_threshold=acquisition.SNR_THRESHOLD,
         eye_integration_time=acquisition.EYE_INTEGRATION_TIME,
         frame_rate=acquisition.FRAME_RATE, bar_aspect=acquisition.BAR_ASPECT):
    r"""Minimum resolvable temperature difference of four-bar targets against bar frequency.

    The classic static-performance-model MRTD of the sensor alone (no display, no eye
    MTF, no eye contrast threshold): the single-frame NETD of :func:`netd` for the
    uniform scene at ``temperature``, through the system MTF of :func:`system_otf`
    (without the post-processing filter) across the bars, averaged by the observer over
    one bar and ``eye_integration_time`` (:func:`xbsm.metrics.acquisition.minimum_resolvable`).

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    scenario : xr.Dataset
        From :func:`xbsm.scenario`: the path to the bars (a 2 m path for a laboratory
        MRTD); its own target and background are replaced by the scene.
    frequency : array_like or xr.DataArray, optional
        Bar frequencies (one over the period of a bar and a space), in [0, inf) on dim
        ``frequency``. Default: 64 frequencies up to the Nyquist frequency
        1 / (2 pitch / focal length) of the finer axis. [cycles/rad]
    method : str or Method
        "accurate" (default), "fast" or "pybsm", or a :class:`xbsm.methods.Method`.
    temperature : float, array_like or xr.DataArray
        Temperature of the bars' background, in (0, inf); a 1-D sequence sweeps on dim
        ``temperature``. [K]
    reflectance : float or xr.DataArray
        Scene reflectance in [0, 1] (emissivity 1 - reflectance). [1]
    snr_threshold : float
        SNR at which the observer just resolves the bars, in (0, inf); default 2.5. [1]
    eye_integration_time : float
        Time over which the eye adds frames, in (0, inf); default 0.1 s. [s]
    frame_rate : float
        Rate of independent displayed frames, in (0, inf); default 30 Hz. Stacked frames
        (``frame_stacks``) are not counted again: the NETD used is the single frame's. [Hz]
    bar_aspect : float
        Bar length over bar width, in [1, inf); default 7 (the standard four-bar
        target). [1]

    Returns
    -------
    xr.Dataset
        ``mrtd`` [K] and ``mtf`` (the system MTF across the bars) over ``orientation``
        (x: bars modulated along x; y: along y), ``frequency`` and every sweep dim;
        the scene's ``netd``, ``netd_frame``, ``signal_derivative``,
        ``target_photoelectrons``, ``effective_integration_time``, ``total_noise``;
        ``flags`` (those of :func:`netd`, ``bars_unresolved`` where the MTF is 0 and the
        MRTD inf, ``bars_aliased`` above the Nyquist frequency across the bars). The
        observer's knobs are attributes.

    Notes
    -----
    .. math::

        \mathrm{MRTD}(f) = \frac{\pi^2}{4\sqrt{7}}\,\mathrm{SNR_{th}}\,
        \mathrm{NETD}\,\frac{f}{\mathrm{MTF}(f)}
        \sqrt{\frac{\alpha\,\beta}{t_e\,F_R}}

    alpha, beta the angular sample spacings (pitch / focal length), t_e the eye's
    integration time, F_R the frame rate. This is the classic form
    pi^2 / (4 sqrt(14)) SNR_th NETD f sqrt(alpha beta / (t_e F_R delta_f tau)) / MTF
    (Ratches et al., NVL static performance model, 1975; reproduced in Holst,
    *Electro-Optical Imaging System Performance*, and in FLIR92 / NVTherm) for a
    staring detector, whose integrate-and-dump noise bandwidth gives delta_f tau = 1/2.
    The derivation and its assumptions are in
    :func:`xbsm.metrics.acquisition.minimum_resolvable`; the equation numbers of those
    texts could not be checked with the search tools available to this project. As
    f -> 0, MRTD / f -> (pi^2 / (4 sqrt 7)) SNR_th NETD sqrt(alpha beta / (t_e F_R)):
    without an eye model the MRTD falls to 0 at low frequency, where a measured one
    rises.
    """
    scenario = _scene(sensor, scenario, temperature, reflectance)
    knobs = {"snr_threshold": snr_threshold, "eye_integration_time": eye_integration_time,
             "frame_rate": frame_rate, "bar_aspect": bar_aspect}
    return _chain.mrtd(sensor, scenario, method, _bar_frequencies(frequency), knobs)


def _bar_frequencies(frequency):
    """Bar frequencies as given (None: the chain's default), each in [0, inf) cycles/rad."""
    if frequency is None:
        return None
    frequency = params.labelled("frequency", frequency, "frequency")
    bad = ~(frequency >= 0.0)  # NaN too
    if bool(bad.any()):
        raise ValueError("frequency must be in [0, inf) cycles/rad; got "
                         f"{frequency.values[bad.values][0]!r}")
    return frequency


@contract(method=_METHOD, **_OBSERVER)
def mrc(sensor: xr.Dataset, scenario: xr.Dataset, frequency=None, method="accurate", *,
        snr_threshold=acquisition.SNR_THRESHOLD,
        eye_integration_time=acquisition.EYE_INTEGRATION_TIME,
        frame_rate=acquisition.FRAME_RATE, bar_aspect=acquisition.BAR_ASPECT):
    r"""Minimum resolvable contrast of four-bar targets against bar frequency.

    The reflective-band counterpart of :func:`mrtd`: the same bar-pattern threshold
    with the scene's single-frame noise-equivalent contrast in place of the NETD. The
    scene is the scenario's background (its reflectance r and temperature); the
    contrast is the Weber contrast (r_bars - r) / r of the bars' reflectance against it,
    at the scene (the path's transmission and radiance lower it on the way, as in
    :func:`snr`).

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    scenario : xr.Dataset
        From :func:`xbsm.scenario`: the path and the scene (``background_reflectance``,
        ``background_temperature``); its target is not used.
    frequency : array_like or xr.DataArray, optional
        Bar frequencies in [0, inf) on dim ``frequency``; default as :func:`mrtd`.
        [cycles/rad]
    method : str or Method
        "accurate" (default), "fast" or "pybsm", or a :class:`xbsm.methods.Method`.
    snr_threshold, eye_integration_time, frame_rate, bar_aspect : float
        The observer, as for :func:`mrtd` (defaults 2.5, 0.1 s, 30 Hz, 7).

    Returns
    -------
    xr.Dataset
        ``mrc`` [1] and ``mtf`` [1] over ``orientation`` and ``frequency`` and every sweep
        dim; ``noise_equivalent_contrast`` [1] (one frame, one pixel);
        ``reflectance_signal`` [count], the scene's photoelectrons over a black
        surface's; ``target_photoelectrons`` (the scene's), ``effective_integration_time``,
        ``total_noise``; ``flags`` (``bars_unresolved``, ``bars_aliased``,
        ``no_reflective_signal`` where the scene is no brighter than black: MRC inf).

    Notes
    -----
    .. math::

        \mathrm{MRC}(f) = \frac{\pi^2}{4\sqrt{7}}\,\mathrm{SNR_{th}}\,
        \mathrm{NEC}\,\frac{f}{\mathrm{MTF}(f)}\sqrt{\frac{\alpha\,\beta}{t_e\,F_R}},
        \qquad \mathrm{NEC} = \frac{\sigma}{N(r) - N(0)}

    sigma the scene's total noise, N the photoelectrons of a surface of reflectance r
    at the scene's temperature (linear in r, so N(r) - N(0) = r dN/dr, the signal of
    a unit Weber contrast). The derivation is :func:`mrtd`'s with contrast for
    temperature; no published MRC formula of this form could be found with the
    project's search tools (published MRC definitions are measurement procedures), so
    this is xbsm's analogue, not a transcription. No display or eye model.
    """
    check_inputs(sensor, scenario)
    black = {"target_temperature": scenario["background_temperature"],
             "target_reflectance": scenario["background_reflectance"],
             "background_reflectance": xr.zeros_like(scenario["background_reflectance"])}
    scenario = scenario.assign({name: value.assign_attrs(scenario[name].attrs)
                                for name, value in black.items()})
    check_inputs(sensor, scenario)
    knobs = {"snr_threshold": snr_threshold, "eye_integration_time": eye_integration_time,
             "frame_rate": frame_rate, "bar_aspect": bar_aspect}
    return _chain.mrc(sensor, scenario, method, _bar_frequencies(frequency), knobs)


@contract(method=_METHOD, calibration=Resolved(metrics.giqe_calibrations), targets=_TARGETS)
def niirs(sensor: xr.Dataset, scenario: xr.Dataset, method="accurate", *, calibration=None,
          targets="giqe"):
    """Predicted NIIRS by GIQE 3, 4 and 5 with every intermediate (paper Sec. 3).

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    scenario : xr.Dataset
        From :func:`xbsm.scenario`.
    method : str or Method
        "accurate" (default), "fast" or "pybsm", or a :class:`xbsm.methods.Method`.
    calibration : mapping of int to GiqeCalibration, optional
        GIQE calibration ranges for the flags, by version, e.g.
        ``{5: xbsm.metrics.GIQE5_CALIBRATION.replace(snr=(2, 130))}``; versions
        left out keep :data:`xbsm.metrics.GIQE_CALIBRATIONS`. Changes flags only.
    targets : {"giqe", "scenario"} or xr.Dataset
        Whose contrast SNR the GIQE reads, as for :func:`snr`. Default the GIQE's
        standard target, on which the GIQE was fitted; any other target (the
        scenario's, where it differs from the standard, or a target set) sets
        ``target_not_standard``, a calibration flag, on every ``giqe``.

    Returns
    -------
    xr.Dataset
        ``niirs`` over ``giqe`` = 3, 4, 5; ``snr`` (after frame stacking);
        ``rer`` and ``eho`` (geometric means of the x and y slices, as GIQE 3
        and 4 use), ``rer_x``, ``rer_y``, ``eho_x``, ``eho_y``, ``rer_giqe5``
        (GIQE 5's (max min^2)^(1/3) of the unfiltered system); ``gsd``
        (geometric mean, image plane), ``gsd_gp`` (GIQE 4 ground plane),
        ``gsd_w`` (GIQE 5); ``noise_gain``; ``effective_integration_time``;
        ``slant_range``; ``elevation_angle``; ``coherence_diameter``;
        ``cutoff_frequency``; the SNR breakdown of :func:`snr` (photoelectrons,
        noise terms, ``snr_frame``, ``well_fill``); ``flags`` over ``giqe``.

    Notes
    -----
    The chain: :func:`snr` gives the SNR, the integration time and the
    spectral weights; :func:`xbsm.otf.system.system_components` the system OTF on the
    x and y slices at the nodes of the method's edge-response quadrature;
    :mod:`xbsm.metrics` the edge terms and the GIQE. GIQE 5 uses the system
    without the post-processing filter (as pyBSM's ``niirs5``), GIQE 3 and 4
    with it, with its noise gain.
    """
    scenario, targets = _targets(sensor, scenario, targets)
    return _chain.niirs(sensor, scenario, method, calibration, targets)


@contract(method=_METHOD)
def system_otf(sensor: xr.Dataset, scenario: xr.Dataset, frequency=None, method="accurate",
               *, fy=None):
    """System OTF and every component for a sensor in a scenario (paper Figure 5).

    Parameters
    ----------
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario`.
    frequency : xr.DataArray or array_like, optional
        Slice frequencies along x and y (dim ``frequency``), or with ``fy`` the
        x frequencies of a 2-D grid. Default: 201 points from 0 to the optics
        cutoff D / lambda_min. [cycles/rad]
    method : str or Method
        As for :func:`niirs`.
    fy : xr.DataArray, optional
        y frequencies of a 2-D grid (dims of your choice, e.g. ``fy``, ``fx``). [cycles/rad]

    Returns
    -------
    xr.Dataset
        ``aperture``, ``turbulence``, ``detector``, ``jitter``, ``drift``,
        ``wavefront``, ``filter``, ``system``, ``system_unfiltered``,
        ``coherence_diameter``; slices carry an ``orientation`` dim (x, y);
        ``flags`` (those of the radiometry: ``beyond_database`` where the spectral
        weights, and so the polychromatic OTFs, are undefined).
    """
    check_inputs(sensor, scenario)
    return _chain.system_otf(sensor, scenario, method, frequency, fy)


def _task_table(v50, criterion):
    """The V50 (N50) of each task: a table by name, or a mapping of task -> value > 0."""
    from .metrics import ttp
    tables = ttp.JOHNSON_N50 if criterion == "johnson" else ttp.TTP_V50
    if v50 is None:
        v50 = next(iter(tables))
    if isinstance(v50, str):
        if v50 not in tables:
            raise ValueError(f"v50 must name one of {sorted(tables)} for criterion "
                             f"{criterion!r}, or map tasks to values; got {v50!r}")
        return tables[v50]
    if not hasattr(v50, "items") or not v50:
        raise ValueError("v50 must be a table name or a mapping of task -> cycles; got "
                         f"{type(v50).__name__}")
    table = {}
    for task, value in v50.items():
        if task not in ttp.TASKS:
            raise ValueError(f"v50 tasks must be among {ttp.TASKS}; got {task!r}")
        table[task] = Spec("1", "cycles on target at P = 0.5", **POSITIVE).check(
            f"v50[{task!r}]", value)
    return table


@contract(method=_METHOD, criterion=Choice(("ttp", "johnson")),
          eye=Choice(("vollmerhausen", "barten")),
          eyes=Spec("1", "eyes viewing", low=1, high=2, whole=True),
          display_luminance=Spec("cd/m2", "mean display luminance", **POSITIVE),
          displayed_contrast=Spec("1", "displayed target contrast", low=0.0, high=1.0,
                                  low_open=True),
          display_pixel_pitch=Spec("m", "display pixel pitch", **POSITIVE),
          viewing_distance=Spec("m", "viewing distance", **POSITIVE),
          eye_integration_time=Spec("s", "integration time of the eye", **POSITIVE),
          frame_rate=Spec("Hz", "displayed frame rate", **POSITIVE),
          noise_constant=Spec("Hz0.5", "eye noise calibration constant", **POSITIVE),
          frequencies=Spec("1", "frequencies of the TTP grid", low=16, whole=True))
def target_acquisition(sensor: xr.Dataset, scenario: xr.Dataset, targets,
                       method="accurate", *, criterion="ttp", v50=None,
                       eye="vollmerhausen", eyes=2, display_luminance=34.26,
                       displayed_contrast=0.2, display_pixel_pitch=0.25e-3,
                       viewing_distance=0.5, eye_integration_time=0.1, frame_rate=30.0,
                       aliasing=True, noise_constant=169.6, frequencies=96):
    r"""Probability of detecting, recognising and identifying targets (the TTP metric).

    The observer of the US Army's target-acquisition models looking at a display of
    the camera's image: the system contrast threshold function (the eye's CTF through
    the system and display MTF, raised by the noise the eye sees, aliasing included),
    the Targeting Task Performance metric, cycles on target and the probability of
    each task (:mod:`xbsm.metrics.ttp`, :mod:`xbsm.metrics.eye`). Sweep
    ``ground_range`` (or anything else) for P against range.

    Parameters
    ----------
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario`; the scenario's background
        is the targets' background.
    targets : xr.Dataset
        A target set (:func:`xbsm.radiometry.target_set`,
        :func:`xbsm.radiometry.standard_targets`): size (characteristic dimension) and
        thermal or reflectance contrast of each target, on dim ``target``.
    method : str or Method
        As for :func:`niirs`.
    criterion : {"ttp", "johnson"}
        Cycles on target by the TTP metric (default), or by the Johnson criteria (the
        limiting frequency, the highest at which the target's contrast exceeds the
        system threshold, times size over range).
    v50 : str or mapping, optional
        V50 (N50 for Johnson) per task: a table name of
        :data:`xbsm.metrics.ttp.TTP_V50` / :data:`~xbsm.metrics.ttp.JOHNSON_N50`
        (default the first) or a mapping such as ``{"identify": 20.0}``, each value in
        (0, inf). [1]
    eye : {"vollmerhausen", "barten"}
        The eye model (:data:`xbsm.metrics.eye.EYE_MODELS`).
    eyes : int
        1 or 2 eyes viewing.
    display_luminance : float
        Mean display luminance, in (0, inf); default 34.26 cd/m^2 (10 fL). Outside the
        photopic range [3, 1e4] sets ``outside_acquisition_model``. [cd/m^2]
    displayed_contrast : float
        Contrast of the target on the display, in (0, 1]: the display's gain puts the
        target-background difference at this contrast (as NV-IPM's gain and level with
        a desired contrast); default 0.2. [1]
    display_pixel_pitch, viewing_distance : float
        One sensor sample per display pixel of this pitch, seen from this distance: the
        magnification is (pitch / distance) / (pixel pitch / focal length). [m]
    eye_integration_time, frame_rate : float
        The eye's integration time [s] (0.1) and the frame rate [Hz] (30).
    aliasing : bool
        Treat the aliased signal of the sampled imager as noise (default True).
    noise_constant : float
        The eye's noise calibration constant alpha, in (0, inf); default 169.6. [Hz^0.5]
    frequencies : int
        Points of the frequency grid, up to the sampling frequency 1 / (pitch / focal
        length), at least 16; default 96. [1]

    Returns
    -------
    xr.Dataset
        ``probability`` over ``task`` (detect, recognize, identify) and every sweep dim;
        ``cycles_on_target``, ``ttp`` and ``limiting_frequency`` [cycles/rad],
        ``ctf_system`` and ``mtf`` (pre-sample system MTF) over ``orientation`` and
        ``frequency``, ``displayed_target_size`` [deg], ``slant_range`` [m],
        ``snr_frame``, ``flags``. The observer's knobs are attributes.

    Notes
    -----
    .. math::

        \mathrm{TTP} = \int_{C > \mathrm{CTF_{sys}}}\sqrt{C / \mathrm{CTF_{sys}}(\xi)}\,
        d\xi,\quad V = \mathrm{TTP}\,\sqrt{A} / R,\quad
        P = \frac{(V/V_{50})^E}{1 + (V/V_{50})^E},\ E = 1.51 + 0.24\,V/V_{50}

    TTP is the geometric mean of its x and y integrals. The formulas, their sources
    and their checks are in the documentation page target_acquisition.md.
    """
    check_inputs(sensor, scenario)
    targets = check_target_set("targets", targets)
    table = _task_table(v50, criterion)
    scenario = targets_on_scenario(scenario, targets)
    check_inputs(sensor, scenario)
    knobs = {"display_pixel_angle": display_pixel_pitch / viewing_distance,
             "luminance": float(display_luminance), "contrast": float(displayed_contrast),
             "eye": eye, "eyes": int(eyes), "noise_constant": float(noise_constant),
             "eye_integration_time": float(eye_integration_time),
             "frame_rate": float(frame_rate), "aliasing": bool(aliasing)}
    return _chain.target_acquisition(sensor, scenario, method, targets[
        "characteristic_dimension"], table, criterion, int(frequencies), knobs)
