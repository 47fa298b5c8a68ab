"""The model chain, written once: the stages in data-flow order against an applier (private).

atmosphere -> radiometry (aperture radiances, the sensor's band terms, signal) ->
optics cutoff -> noise -> SNR; then geometry -> edge quadrature -> system OTF on
the x and y slices -> edge terms -> GIQE.

:func:`snr` and :func:`niirs` compose the stages once (:func:`_snr_chain`,
:func:`_niirs_chain`); an applier decides how a stage runs:

- :class:`Direct`, for one eager scenario (no sweep dim, no dask, atmosphere inputs
  in the database's units): each stage's array orchestrator on plain numpy arrays,
  and the result labelled once from the stages' declared outputs. A notebook user,
  an optimizer or a Monte Carlo loop pays for the arithmetic, not for a few hundred
  small DataArrays.
- :class:`Labelled`, for everything else (sweeps, dask): each stage's labelled door,
  its array orchestrator through one ``xr.apply_ufunc`` (or a kernel's, for the few
  stages that have none yet), so that each quantity keeps only the dims it depends on
  (a sensor quantity keeps sensor dims) and dask stays lazy.

Both appliers run the same stage kernels in the same order; ``tests/test_chain.py``
checks that they agree on every pyBSM reference case.
"""

from __future__ import annotations

from contextlib import nullcontext

import numpy as np
import xarray as xr

from . import flags as fl
from . import geometry, noise, params, quadrature, radiometry
from ._kernels import apply_kernel, apply_orchestrator
from ._metadata import Output, dataset_of, declared, outputs, result
from .atmosphere import WAVELENGTH_ATTRS, band_atmosphere, band_atmosphere_arrays
from .metrics import acquisition
from .metrics import edge as edge_
from .metrics import eye as eye_
from .metrics import giqe as giqe_
from .metrics import ttp as ttp_
from .otf import system

_OWN_DIMS = frozenset({"kernel_y", "kernel_x"}
                      | {f"{name}_wavelength" for name in params.SPECTRAL})
"""The parameters' own dims (a sensor curve's wavelengths, the filter kernel's rows and
columns): every other dim is a sweep."""
_ATMOSPHERE_UNITS = (("altitude", "m"), ("ground_range", "m"), ("visibility", "km"))

OUTPUTS = outputs(
    Output("well_fill", "1", "well fill fraction"),
    Output("coherence_diameter", "m", "band-weighted coherence diameter r0"),
)
"""The chain's own outputs (the stages declare theirs)."""

_DECLARED = {**radiometry.SIGNAL_OUTPUTS, **noise.OUTPUTS, **radiometry.SENSITIVITY_OUTPUTS,
             **geometry.VIEW_OUTPUTS,
             **edge_.SLICE_OUTPUTS, **giqe_.OUTPUTS,
             **quadrature.CUTOFF_OUTPUTS, **acquisition.OUTPUTS, **OUTPUTS}


# ---- the composition ---------------------------------------------------------------

def _snr_chain(ap, m, targets: str, *, sensitivity: bool = False):
    """The SNR chain: its result's variables, the band atmosphere and the sensor's band terms.

    The band terms (:data:`radiometry.BAND_OUTPUTS`) give the chains that evaluate OTFs
    their optics limits (the applier's ``optics_limits``: the cutoff D / lambda_min and the
    band's wavelength ratio, where the aperture OTF ends and has its kinks); the SNR alone
    does not need them.

    ``sensitivity``: also the target's NETD, NER and NEI (the noise over the temperature
    derivative of its signal).
    """
    atm = ap.atmosphere(m)
    radiances = ap.radiances(atm, targets, m)
    band = ap.sensor_band(atm, m)
    signal = ap.signal(atm, band, radiances, m)
    noise_ = ap.noise(signal)
    brighter = np.maximum(signal["target_photoelectrons"], signal["background_photoelectrons"])
    flags = ap.flag(atm["flags"], "well_fill_limited", signal["well_fill_scale"] < 1.0)
    if params.partial_spectral_coverage(ap.sensor_dataset):  # one bit for the whole sensor
        flags = ap.flag(flags, "partial_spectral_coverage", True)
    counts = ("effective_integration_time", "target_photoelectrons",
              "background_photoelectrons", "contrast_photoelectrons")
    values = {
        "snr": noise_["snr"],
        "snr_frame": noise_["snr_frame"],
        **{name: signal[name] for name in counts},
        "well_fill": brighter / ap.sensor["max_well"],
        **{name: noise_[name] for name in noise.OUTPUTS if name not in ("snr", "snr_frame")},
        "spectral_weights": signal["spectral_weights"],
        "flags": flags,
    }
    if sensitivity:
        values.update(ap.sensitivity(atm, band, signal, noise_["total_noise"], m))
    return values, atm, band


def _niirs_chain(ap, m, calibration, targets: str = "giqe") -> dict:
    """The NIIRS chain: the SNR chain, the viewing geometry, the edge terms, the GIQE."""
    r, atm, band = _snr_chain(ap, m, targets)
    view = ap.view(m)
    edges = _edge_chain(ap, r, atm, ap.optics_limits(atm, band), view, m)
    s = ap.sensor
    metrics = ap.giqe(
        rer=edges["rer"], eho=edges["eho"], rer_x=edges["rer_unfiltered_x"],
        rer_y=edges["rer_unfiltered_y"], gsd_x=view["gsd_x"], gsd_y=view["gsd_y"],
        snr=r["snr"], elevation=view["elevation_angle"], noise_gain=ap.noise_gain(),
        # GIQE 5's Q = lambda N / p at the band centre, per orientation (flags only)
        q=ap.sampling_q(0.5 * (s["wavelength_min"] + s["wavelength_max"]),
                        s["aperture_diameter"], edges["ifov"]),
        noise_coefficient=m.giqe4_noise_coefficient, calibration=calibration)
    flags = metrics["flags"] | r["flags"] | edges["flags"]
    if targets != "giqe":  # the GIQE was fitted on SNRs of its standard target only
        flags = ap.flag(flags, "target_not_standard", np.logical_not(
            radiometry.standard_target(targets, s["wavelength_min"], ap.scenario)))
    hidden = ("flags", "ifov", "rer_unfiltered_x", "rer_unfiltered_y")
    return {
        "niirs": metrics["niirs"],
        **{name: r[name] for name in r if name not in ("spectral_weights", "flags")},
        **{name: value for name, value in edges.items() if name not in hidden},
        **{name: metrics[name] for name in giqe_.OUTPUTS if name != "niirs"},
        **{name: view[name] for name in ("slant_range", "elevation_angle")},
        "flags": flags,
    }


def _edge_chain(ap, r, atm, optics, view, m) -> dict:
    """RER and EHO of the system OTF on the x and y slices, at the method's quadrature nodes."""
    ifov_x, ifov_y = view["ifov_x"], view["ifov_y"]
    cutoff = optics["cutoff_frequency"]
    s = ap.sensor
    # the widest blur whose OTF has lobes (a sensor quantity, so that a sweep over scenarios
    # shares one rule): the drift angle over the nominal exposure (the well-fill limit only
    # shortens it, widening the sinc's lobes) or the defocus blur circle 8 W020 / D
    drift = (np.maximum(abs(s["drift_rate_x"]), abs(s["drift_rate_y"]))
             * s["integration_time"] * s["tdi_stages"])
    lobe_width = np.maximum(drift, 8.0 * s["defocus_opd"] / s["aperture_diameter"])
    # and where the aperture OTF has kinks: its pieces at both ends of the band
    nodes, weights = ap.edge_nodes(cutoff, ifov_x, ifov_y, lobe_width,
                                   s["obscuration_ratio"], optics["band_wavelength_ratio"], m)
    otf = ap.system_slices(nodes, atm, r["spectral_weights"], r["effective_integration_time"],
                           view["slant_range"], m)
    ifov = ap.orientations(ifov_x, ifov_y)
    unfiltered = None if ap.sensor["filter_kernel"].shape == (1, 1) else otf["system_unfiltered"]
    terms = ap.slice_terms(otf["system"], unfiltered, ifov, weights, m.edge_otf)
    coarse = False
    if m.edge_rule == "uniform_trapezoid":
        coarse = ap.undersampled(nodes, cutoff, ifov_x, ifov_y, m.undersampling_threshold)
    flags = ap.flag(ap.no_flags(), "undersampled_grid", coarse)
    if "edge_error" in terms:
        # the rule's own estimate, both slices through the GIQE's sensitivity (issue 23),
        # and what the OTF's wavelength bins (otf_wavelengths > 0) may add, which no
        # quadrature estimate sees
        binning = edge_.binning_niirs_error(terms["rer_unfiltered_x"],
                                            terms["rer_unfiltered_y"], otf["binning_error"])
        unresolved = terms["edge_error"] + binning > m.edge_error_tolerance
        terms = {name: terms[name] for name in terms if name != "edge_error"}
    else:
        # on the worse slice: a one-axis smear leaves the geometric mean above the
        # threshold while its own slice is not resolved
        unresolved = np.minimum(terms["rer_x"], terms["rer_y"]) < quadrature.UNRESOLVED_RER
    flags = ap.flag(flags, "blur_unresolved", unresolved)
    return {**terms, "coherence_diameter": otf["coherence_diameter"],
            "cutoff_frequency": cutoff, "ifov": ifov, "flags": flags}


def _photoelectrons_chain(ap, m, reflectance, temperature, integration_time) -> dict:
    """Image simulation's radiometry: photoelectrons of Lambertian targets by reflectance.

    The SNR chain's radiometry (band atmosphere, aperture radiances, the sensor's band
    terms, the signal stage) with every reflectance as the target, then image
    simulation's well rule: one scale for the whole reflectance axis.
    """
    atm = ap.atmosphere(m)
    sc = ap.scenario  # its background: the signal stage's other radiance, unused here
    targets = {"target_reflectance": reflectance, "target_temperature": temperature,
               "background_reflectance": sc["background_reflectance"],
               "background_temperature": sc["background_temperature"]}
    radiances = ap.radiances(atm, "scenario", m, scenario=targets)
    band = ap.sensor_band(atm, m)
    signal = ap.signal(atm, band, radiances, m, noise_rates=False)
    counts = ap.reflectance_counts(signal, integration_time)
    return {**{name: counts[name] for name in ("photoelectrons", "effective_integration_time",
                                              "spectral_weights")},
            "flags": ap.flag(atm["flags"], "well_fill_limited",
                             counts["well_fill_scale"] < 1.0)}


# ---- the doors ---------------------------------------------------------------------

def snr(sensor: xr.Dataset, scenario: xr.Dataset, m, targets: str) -> xr.Dataset:
    """:func:`xbsm.snr` on checked inputs and a resolved method."""
    ap = applier(sensor, scenario)
    with ap.errors():
        values, atm, _ = _snr_chain(ap, m, targets)
        return ap.result(values, atm, m, targets=targets)


def netd(sensor: xr.Dataset, scenario: xr.Dataset, m) -> xr.Dataset:
    """:func:`xbsm.netd` on checked inputs (the scene in the scenario's target) and a method."""
    ap = applier(sensor, scenario)
    with ap.errors():
        values, atm, _ = _snr_chain(ap, m, "scenario", sensitivity=True)
        flags = ap.flag(values["flags"], "no_thermal_signal",
                        ~(values["signal_derivative"] > 0.0))
        contrast = ("snr", "snr_frame", "contrast_photoelectrons", "background_photoelectrons")
        values = {name: value for name, value in values.items() if name not in contrast}
        return ap.result({**values, "flags": flags}, atm, m)


def _bars_chain(ap, m, values, noise_equivalent, frequency, knobs) -> dict:
    """The bar-pattern threshold of ``noise_equivalent`` through the system MTF across bars.

    ``values``: the SNR chain's result for the uniform scene (its spectral weights and
    integration time give the OTF); ``frequency``: checked bar frequencies, None for 64
    up to the finer axis' Nyquist frequency.
    """
    s, sc = ap.sensor, ap.scenario
    spacing_x = s["pixel_pitch_x"] / s["focal_length"]
    spacing_y = s["pixel_pitch_y"] / s["focal_length"]
    if frequency is None:
        nyquist = 0.5 / float(np.minimum(spacing_x, spacing_y).min())
        frequency = np.linspace(0.0, nyquist, 65)[1:]
    frequency = params.frequencies("frequency", params.labelled("frequency", frequency,
                                                                "frequency"))
    if "frequency" in frequency.coords:
        frequency["frequency"].attrs.update(units="cycles/rad", long_name="bar frequency")
    slant = geometry.slant_range(sc["ground_range"], sc["altitude"], form=m.geometry)
    otf = system.system_components(
        s, sc, frequency, spectral_weights=system.otf_weights(values["spectral_weights"]),
        integration_time=values["effective_integration_time"], slant_range=slant, method=m)
    mtf = abs(otf["system_unfiltered"])
    threshold = acquisition.minimum_resolvable(noise_equivalent, mtf, spacing_x, spacing_y,
                                               **knobs)
    flags = ap.flag(values["flags"], "bars_unresolved", ~(mtf > 0.0))
    nyquist = 0.5 / ap.orientations(spacing_x, spacing_y)
    flags = ap.flag(flags, "bars_aliased", mtf["frequency"] > nyquist * (1.0 + 1e-12))
    return {"threshold": threshold, "mtf": mtf, "flags": flags}


def mrtd(sensor: xr.Dataset, scenario: xr.Dataset, m, frequency, knobs: dict) -> xr.Dataset:
    """:func:`xbsm.mrtd` on checked inputs (the scene in the scenario's target) and knobs.

    ``frequency``: checked bar frequencies, None for the default grid. Sweep-only (the
    labelled applier): the SNR chain with the scene's NETD, the system OTF on the bar
    frequencies, then the bar-pattern threshold.
    """
    ap = Labelled(sensor, scenario)
    values, atm, _ = _snr_chain(ap, m, "scenario", sensitivity=True)
    values["flags"] = ap.flag(values["flags"], "no_thermal_signal",
                              ~(values["signal_derivative"] > 0.0))
    bars = _bars_chain(ap, m, values, values["netd_frame"], frequency, knobs)
    kept = ("netd", "netd_frame", "signal_derivative", "target_photoelectrons",
            "effective_integration_time", "total_noise")
    out = {"mrtd": bars["threshold"], "mtf": bars["mtf"],
           **{name: values[name] for name in kept}, "flags": bars["flags"]}
    return ap.result(out, atm, m, **{name: float(value) for name, value in knobs.items()})


def mrc(sensor: xr.Dataset, scenario: xr.Dataset, m, frequency, knobs: dict) -> xr.Dataset:
    """:func:`xbsm.mrc` on checked inputs (the scene as target, black as background), knobs.

    The background is a black surface at the scene's temperature. The contrast
    photoelectrons of the scene against black are N(r) - N(0) = r dN/dr (the
    photoelectrons are linear in reflectance), the signal of a unit Weber contrast; the
    noise is the scene's (the brighter), so the noise-equivalent contrast is 1 / snr_frame.
    """
    ap = Labelled(sensor, scenario)
    values, atm, _ = _snr_chain(ap, m, "scenario")
    nec = values["total_noise"] / values["contrast_photoelectrons"]
    contrast = values["contrast_photoelectrons"]
    values["flags"] = ap.flag(values["flags"], "no_reflective_signal", ~(contrast > 0.0))
    nec = xr.where(contrast <= 0.0, np.inf, nec)  # NaN stays NaN (beyond the database)
    bars = _bars_chain(ap, m, values, nec, frequency, knobs)
    kept = ("target_photoelectrons", "effective_integration_time", "total_noise")
    out = {"mrc": bars["threshold"], "mtf": bars["mtf"], "noise_equivalent_contrast": nec,
           "reflectance_signal": values["contrast_photoelectrons"],
           **{name: values[name] for name in kept}, "flags": bars["flags"]}
    return ap.result(out, atm, m, **{name: float(value) for name, value in knobs.items()})


def niirs(sensor: xr.Dataset, scenario: xr.Dataset, m, calibration,
          targets: str = "giqe") -> xr.Dataset:
    """:func:`xbsm.niirs` on checked inputs, a resolved method and calibration."""
    ap = applier(sensor, scenario)
    with ap.errors():
        values = _niirs_chain(ap, m, calibration, targets)
        return ap.result(values, None, m, flags="NIIRS validity flags")


def system_otf(sensor: xr.Dataset, scenario: xr.Dataset, m, frequency, fy) -> xr.Dataset:
    """:func:`xbsm.system_otf` on checked inputs, a resolved method and checked frequencies.

    ``frequency`` None: 201 points from 0 to the optics cutoff D / lambda_min.
    """
    ap = Labelled(sensor, scenario)
    r, atm, band = _snr_chain(ap, m, "giqe")
    optics = ap.optics_limits(atm, band)
    if frequency is None:
        frequency = np.linspace(0.0, float(optics["cutoff_frequency"].max()), 201)
    frequency = params.frequencies("frequency", params.labelled("frequency", frequency,
                                                                "frequency"))
    if "frequency" in frequency.coords:
        frequency["frequency"].attrs.update(units="cycles/rad", long_name="spatial frequency")
    if fy is not None:
        fy = params.frequencies("fy", fy)
    slant = geometry.slant_range(scenario["ground_range"], scenario["altitude"], form=m.geometry)
    out = system.system_components(
        sensor, scenario, frequency, spectral_weights=system.otf_weights(r["spectral_weights"]),
        integration_time=r["effective_integration_time"], slant_range=slant, method=m, fy=fy)
    return result({**out.data_vars, "flags": r["flags"]}, m)


def target_acquisition(sensor: xr.Dataset, scenario: xr.Dataset, m, size, table, criterion,
                       count: int, knobs: dict) -> xr.Dataset:
    """:func:`xbsm.target_acquisition` on checked inputs (each target on the scenario).

    The SNR chain of the targets (their single-frame contrast SNR), the pre-sample system
    MTF on ``count`` frequencies up to the finest sampling frequency, then the observer
    (:func:`xbsm.metrics.ttp.targeting`) and P(task) by ``criterion`` from ``table``.
    """
    ap = Labelled(sensor, scenario)
    with ap.errors():
        values, atm, _ = _snr_chain(ap, m, "scenario")
        s, sc = ap.sensor, ap.scenario
        spacing = ap.orientations(s["pixel_pitch_x"] / s["focal_length"],
                                  s["pixel_pitch_y"] / s["focal_length"])
        grid = np.linspace(0.0, 1.0 / float(spacing.min()), count + 1)[1:]
        frequency = xr.DataArray(grid, dims="frequency", coords={"frequency": grid})
        frequency["frequency"].attrs.update(units="cycles/rad", long_name="spatial frequency")
        slant = geometry.slant_range(sc["ground_range"], sc["altitude"], form=m.geometry)
        otf = system.system_components(
            s, sc, frequency, spectral_weights=system.otf_weights(values["spectral_weights"]),
            integration_time=values["effective_integration_time"], slant_range=slant,
            method=m)
        mtf = abs(otf["system_unfiltered"]).transpose(..., "orientation", "frequency")
        mtf = mtf.assign_attrs(units="1", long_name="pre-sample system MTF")
        terms = ttp_.targeting(frequency, mtf, spacing, values["snr_frame"], slant, size,
                               **knobs)
        cycles = terms.pop("johnson_cycles" if criterion == "johnson" else "ttp_cycles")
        terms.pop("ttp_cycles", None)
        terms.pop("johnson_cycles", None)
        cycles = cycles.assign_attrs(ttp_.OUTPUTS["cycles_on_target"].attrs())
        flags = values["flags"]
        photopic = eye_.PHOTOPIC_LUMINANCE
        if not photopic[0] <= knobs["luminance"] <= photopic[1]:
            flags = ap.flag(flags, "outside_acquisition_model", True)
        out = {"probability": ttp_.probabilities(cycles, table, criterion),
               "cycles_on_target": cycles, **terms, "mtf": mtf,
               "slant_range": slant.assign_attrs(units="m", long_name="slant range"),
               "snr_frame": values["snr_frame"], "flags": flags}
        out["flags"] = out["flags"].astype(np.int32).assign_attrs(fl.flag_attrs())
        return result(out, m, criterion=criterion,
                      **{k: (v if isinstance(v, str) else float(v)) for k, v in knobs.items()})


def reflectance_to_photoelectrons(sensor: xr.Dataset, scenario: xr.Dataset, m, reflectance,
                                  temperature, integration_time) -> xr.Dataset:
    """:func:`xbsm.simulate.reflectance_to_photoelectrons` on checked arguments."""
    values = _photoelectrons_chain(Labelled(sensor, scenario), m, reflectance, temperature,
                                   integration_time)
    return result(values, m)


def single_scenario(sensor: xr.Dataset, scenario: xr.Dataset) -> dict | None:
    """Every parameter of a single eager scenario as a numpy array; None for anything else.

    The datasets must already have passed :func:`xbsm.params.check_inputs`.
    """
    values = {}
    for ds in (sensor, scenario):
        for name, variable in ds.variables.items():
            data = variable.data
            if not isinstance(data, np.ndarray) or not _OWN_DIMS.issuperset(variable.dims):
                return None
            values[name] = data
    if sensor.variables["filter_kernel"].dims != ("kernel_y", "kernel_x"):
        return None  # an edited kernel in the other order: the labelled door transposes it
    for name, units in _ATMOSPHERE_UNITS:
        if scenario.variables[name].attrs.get("units", units) != units:
            return None
    return values


def applier(sensor: xr.Dataset, scenario: xr.Dataset):
    """:class:`Direct` for a single eager scenario, else :class:`Labelled`."""
    p = single_scenario(sensor, scenario)
    return Labelled(sensor, scenario) if p is None else Direct(sensor, scenario, p)


def _conditions_of(scenario) -> dict:
    """The atmosphere conditions a scenario (Dataset or dict of arrays) gives, by name."""
    return {name: scenario[name] for name in params.CONDITION_SPECS if name in scenario}


# ---- the appliers ------------------------------------------------------------------

class Labelled:
    """Each stage through its labelled door: sweeps keep their dims, dask stays lazy."""

    def __init__(self, sensor: xr.Dataset, scenario: xr.Dataset):
        self.sensor = self.sensor_dataset = sensor
        self.scenario = scenario

    @staticmethod
    def errors():
        """Floating-point errors as the kernels' boundary handles them."""
        return nullcontext()

    def atmosphere(self, m) -> xr.Dataset:
        s, sc = self.sensor, self.scenario
        return band_atmosphere(sc["altitude"], sc["ground_range"], sc["visibility"],
                               s["wavelength_min"], s["wavelength_max"],
                               interpolation=m.atmosphere_interpolation, band_edges=m.band_edges,
                               conditions=_conditions_of(sc))

    def radiances(self, atm, targets, m, scenario=None):
        sc = self.scenario if scenario is None else scenario
        return radiometry.aperture_radiances(atm, sc, targets, self.sensor["wavelength_min"],
                                             m.constants)

    def sensor_band(self, atm, m):
        return radiometry.sensor_band_terms(self.sensor, atm["wavelength"], m.constants)

    def signal(self, atm, band, radiances, m, noise_rates=True):
        return radiometry.signal_terms(self.sensor, atm, *radiances, m.constants, band=band,
                                       noise_rates=noise_rates)

    def optics_limits(self, atm, band):
        s = self.sensor
        return quadrature.band_optics_limits(
            s["aperture_diameter"], atm["wavelength"], band["quantum_efficiency"],
            band["optics_transmission"], s["wavelength_min"])

    def noise(self, signal):
        return noise.noise_terms(signal, self.sensor)

    def sensitivity(self, atm, band, signal, total_noise, m):
        return radiometry.noise_equivalent_terms(self.sensor, self.scenario, atm, band, signal,
                                                 total_noise, m.constants)

    def reflectance_counts(self, signal, integration_time):
        s = self.sensor
        return apply_orchestrator(
            radiometry.reflectance_counts_arrays, radiometry.REFLECTANCE_COUNT_OUTPUTS,
            signal["target_rate"], signal["spectral_weights"], s["dark_current"],
            integration_time, s["tdi_stages"], s["max_well"],
            core=[["reflectance"], ["reflectance", "wavelength"], [], [], [], []])

    @staticmethod
    def flag(flags, name: str, condition):
        return fl.set_flag(flags, name, condition)

    @staticmethod
    def no_flags():
        return xr.DataArray(np.int32(0))

    def view(self, m):
        s, sc = self.sensor, self.scenario
        return geometry.viewing_geometry(
            sc["ground_range"], sc["altitude"], s["pixel_pitch_x"], s["pixel_pitch_y"],
            s["focal_length"], elevation=m.elevation, form=m.geometry)

    @staticmethod
    def edge_nodes(cutoff, ifov_x, ifov_y, lobe_width, obscuration_ratio, wavelength_ratio, m):
        # a drift (or defocus) swept on dims of its own gets the rule of its largest value:
        # finer than each needs, but one rule, so that the optics OTF is not evaluated per
        # drift
        own = [d for d in lobe_width.dims
               if d not in {*cutoff.dims, *ifov_x.dims, *ifov_y.dims}]
        if own:
            lobe_width = lobe_width.max(own)
        return quadrature.edge_nodes(cutoff, ifov_x, ifov_y, lobe_width, obscuration_ratio,
                                     wavelength_ratio, **m.edge_quadrature_knobs())

    def system_slices(self, nodes, atm, spectral_weights, integration_time, slant_range, m):
        # the weights carry their wavelengths; ``atm`` is for the direct applier's arrays
        otf = system.system_components(
            self.sensor, self.scenario, nodes, spectral_weights=system.otf_weights(
                spectral_weights), integration_time=integration_time,
            slant_range=slant_range, method=m)
        binning = 0.0  # every wavelength: no binning error
        if m.otf_wavelengths > 0:
            binning = apply_kernel(system.binning_error_kernel, spectral_weights,
                                   spectral_weights["wavelength"],
                                   core=[["wavelength"], ["wavelength"]],
                                   count=m.otf_wavelengths)
        return otf.assign(binning_error=binning)

    @staticmethod
    def orientations(x, y):
        return xr.concat([x, y], dim="orientation").assign_coords(orientation=["x", "y"])

    slice_terms = staticmethod(edge_.slice_terms)
    undersampled = staticmethod(quadrature.undersampled)
    giqe = staticmethod(giqe_.giqe_by_version)
    sampling_q = staticmethod(giqe_.sampling_q)

    def noise_gain(self):
        return noise.noise_gain(self.sensor["filter_kernel"])

    @staticmethod
    def result(values: dict, atm, m, *, flags=None, **attrs) -> xr.Dataset:
        """The result Dataset; ``flags``: the long name of NIIRS-style int32 flags."""
        out = {name: value if name == "flags" else declared(value, _DECLARED[name])
               for name, value in values.items()}
        if flags is not None:
            out["flags"] = out["flags"].astype(np.int32).assign_attrs(fl.flag_attrs(flags))
        return result(out, m, **attrs)


class Direct:
    """Each stage's array orchestrator on plain arrays; the result labelled once."""

    def __init__(self, sensor: xr.Dataset, scenario: xr.Dataset, p: dict):
        self.sensor = self.scenario = p
        self.sensor_dataset = sensor
        self._labelled = Labelled(sensor, scenario)

    @staticmethod
    def errors():
        """IEEE results without warnings, as the labelled doors give them."""
        return np.errstate(all="ignore")

    def atmosphere(self, m) -> dict:
        p = self.sensor
        atm = band_atmosphere_arrays(p["altitude"], p["ground_range"], p["visibility"],
                                     p["wavelength_min"], p["wavelength_max"],
                                     interpolation=m.atmosphere_interpolation,
                                     band_edges=m.band_edges, conditions=_conditions_of(p))
        return self._labelled.atmosphere(m) if atm is None else atm  # the door raises

    def radiances(self, atm, targets, m, scenario=None):
        p = self.sensor
        surfaces = radiometry.surfaces(targets, p["wavelength_min"],
                                       p if scenario is None else scenario)
        out = radiometry.radiance_arrays(*radiometry.radiance_inputs(atm, surfaces),
                                         **radiometry.planck_knobs(m.constants))
        return out["target_radiance"], out["background_radiance"]

    def sensor_band(self, atm, m):
        p, wavelength = self.sensor, atm["wavelength"]
        curves = {name: radiometry.curve_on_band(p, name, wavelength)
                  for name in radiometry.SPECTRAL_CURVES}
        return radiometry.sensor_band_arrays(
            *radiometry.sensor_band_inputs(p, wavelength, curves),
            **radiometry.planck_knobs(m.constants))

    def signal(self, atm, band, radiances, m, noise_rates=True):
        k = m.constants
        return radiometry.signal_arrays(
            *radiometry.signal_inputs(self.sensor, atm, band, radiances), h=k.planck,
            c=k.speed_of_light, noise_rates=noise_rates)

    def optics_limits(self, atm, band):
        p = self.sensor
        return quadrature.band_cutoff_arrays(p["aperture_diameter"], atm["wavelength"],
                                             band["quantum_efficiency"],
                                             band["optics_transmission"], p["wavelength_min"])

    def noise(self, signal):
        return noise.noise_arrays(*noise.noise_inputs(self.sensor, signal))

    def sensitivity(self, atm, band, signal, total_noise, m):
        p = self.sensor
        return radiometry.sensitivity_arrays(
            *radiometry.sensitivity_inputs(p, p, atm, band, signal, total_noise),
            **radiometry.planck_knobs(m.constants))

    @staticmethod
    def flag(flags, name: str, condition):
        return flags | np.where(condition, fl.flag(name), 0)

    @staticmethod
    def no_flags():
        return np.int32(0)

    def view(self, m):
        p = self.sensor
        return geometry.viewing_arrays(p["altitude"], p["ground_range"], p["pixel_pitch_x"],
                                       p["pixel_pitch_y"], p["focal_length"],
                                       elevation=m.elevation, form=m.geometry)

    @staticmethod
    def edge_nodes(cutoff, ifov_x, ifov_y, lobe_width, obscuration_ratio, wavelength_ratio, m):
        nodes, weights, sine, error = quadrature.edge_rule_arrays(
            cutoff, ifov_x, ifov_y, lobe_width, obscuration_ratio, wavelength_ratio,
            **m.edge_quadrature_knobs())
        return nodes, (weights, sine, error)

    def system_slices(self, nodes, atm, spectral_weights, integration_time, slant_range, m):
        unfiltered, filtered, r0 = system.system_slice_arrays(
            self.sensor, nodes, atm["wavelength"], spectral_weights, integration_time,
            slant_range, m)
        binning = 0.0  # every wavelength: no binning error
        if m.otf_wavelengths > 0:
            binning = system.binning_error_kernel(spectral_weights, atm["wavelength"],
                                                  count=m.otf_wavelengths)
        return {"system": filtered, "system_unfiltered": unfiltered, "coherence_diameter": r0,
                "binning_error": binning}

    @staticmethod
    def orientations(x, y):
        return np.array([x, y])

    @staticmethod
    def slice_terms(filtered, unfiltered, ifov, weights, edge_otf):
        weights, sine, error = weights
        return edge_.slice_terms_arrays(filtered, unfiltered, weights, sine, ifov, edge_otf,
                                        error_weights=error)

    @staticmethod
    def undersampled(nodes, cutoff, ifov_x, ifov_y, threshold):
        return quadrature.undersampled_arrays(nodes.size, cutoff, ifov_x, ifov_y, threshold)

    giqe = staticmethod(giqe_.giqe_arrays)
    @staticmethod
    def sampling_q(wavelength, aperture_diameter, ifov):
        return giqe_.sampling_q_arrays(wavelength, aperture_diameter, ifov)["q"]

    def noise_gain(self):
        return noise.noise_gain_arrays(self.sensor["filter_kernel"])["noise_gain"]

    @staticmethod
    def result(values: dict, atm, m, *, flags="validity flags", **attrs) -> xr.Dataset:
        """The result Dataset, labelled from the stages' declarations."""
        variables = {}
        for name, value in values.items():
            if name == "flags":
                dims = ("giqe",) if np.ndim(value) else ()
                variables[name] = xr.Variable(dims, np.asarray(value, dtype=np.int32),
                                              fl.flag_attrs(flags))
            else:
                o = _DECLARED[name]
                # fastpath: the float64 array as it is (xarray's own constructors pass it
                # so); its checks were 3.5 % of a single snr call's instructions
                variables[name] = xr.Variable(o.dims, np.asarray(value, dtype=float), o.attrs(),
                                              fastpath=True)
        coords = {}
        if "spectral_weights" in variables:
            coords["wavelength"] = xr.Variable("wavelength", atm["wavelength"],
                                               dict(WAVELENGTH_ATTRS))
        if "niirs" in variables:
            coords["giqe"] = xr.Variable("giqe", list(giqe_.GIQE_VERSIONS),
                                         dict(giqe_.GIQE_VERSION_ATTRS))
        return dataset_of(variables, coords, {"method": m.describe(), **attrs})
