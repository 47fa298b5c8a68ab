"""Radiometry: from aperture radiance to photoelectrons (paper Sec. 2.1-2.2).

One physical quantity per public function, broadcasting over ``wavelength`` and
any scenario or sensor dimension. Spectral radiance is in W/(m^2 sr m),
spectral irradiance in W/(m^2 m).

The arithmetic lives in private numpy kernels (plain arrays and plain knobs, no
checks); each public function runs its kernel once through :func:`_apply`, the
xarray boundary that aligns, labels and carries dask. A kernel writes its
operations in the order of the equation it implements, so a result keeps the
rounding and the dimension order that xarray arithmetic on the same equation
would give.

The stage's three steps (aperture radiances, the sensor's band terms, the signal)
each have one array orchestrator (:func:`radiance_arrays`, :func:`sensor_band_arrays`,
:func:`signal_arrays`) with its outputs declared beside it; the labelled doors
(:func:`aperture_radiances`, :func:`sensor_band_terms`, :func:`signal_terms`) run it
through :func:`xbsm._kernels.apply_orchestrator` (``wavelength`` a core dimension, each
output spectral or a band total as declared), and :mod:`xbsm._chain`'s direct applier
runs it on one eager scenario's arrays: the rules are written once.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

from ._kernels import apply_kernel, apply_orchestrator, dataset
from ._metadata import Output, named, outputs
from .constants import CODATA, Constants
from .params import Choice, contract

DATABASE_REFLECTANCE = 0.15
"""Target reflectance used in the MODTRAN database runs (paper Appendix A). [1]"""

GIQE_TARGET = MappingProxyType({"reflectance": 0.15, "temperature": 282.0})
"""GIQE standard target: 15% reflectance at 282 K (IBSM; Leachtenauer et al. 1997)."""
GIQE_BACKGROUND = MappingProxyType({"reflectance": 0.07, "temperature": 280.0})
"""GIQE standard background: 7% reflectance at 280 K."""
TARGETS = ("giqe", "scenario")
"""Whose radiance :func:`aperture_radiances` gives: the GIQE standard target and background
(:data:`GIQE_TARGET`, :data:`GIQE_BACKGROUND`) or the scenario's own."""
EMISSIVE_BAND_START = 2.9e-6
"""Bands starting at or beyond this wavelength use the emissive GIQE target
(reflectance 0, so only the 282 K / 280 K temperature contrast counts). [m]"""


# ---- numpy kernels: plain arrays (broadcast against each other) and plain knobs ----

def _blackbody_kernel(wavelength, temperature, *, h, c, k):
    """Planck spectral radiance, written with exp(-x) so that it underflows to 0."""
    x = h * c / (wavelength * k * temperature)
    return (2.0 * h * c**2.0 / wavelength**5.0) * np.exp(-x) / -np.expm1(-x)


def _total_radiance_kernel(path_thermal, reflectance, wavelength, temperature, transmission,
                           solar_scatter, ground_reflected, *, h, c, k):
    """Paper Eq. 1 on arrays."""
    emitted = (1.0 - reflectance) * _blackbody_kernel(wavelength, temperature, h=h, c=c, k=k)
    return (path_thermal + emitted * transmission + solar_scatter
            + ground_reflected * (reflectance / DATABASE_REFLECTANCE))


def _throughput_kernel(focal_length, aperture_diameter):
    """Projected solid angle of the optics, pi / (1 + 4 F^2)."""
    return np.pi / (1.0 + 4.0 * (focal_length / aperture_diameter) ** 2.0)


def _focal_plane_kernel(radiance, focal_length, aperture_diameter):
    """Irradiance from a radiance filling the pupil, L pi / (1 + 4 F^2), in that order."""
    # (L * pi) / (1 + 4F^2), pyBSM's rounding order: contrast SNRs near 1e-7 are
    # differences of nearly equal counts and keep only that order's bits
    return radiance * np.pi / (1.0 + 4.0 * (focal_length / aperture_diameter) ** 2.0)


def _cold_shield_kernel(focal_length, aperture_diameter, wavelength, temperature, *, h, c, k):
    """Cold shield emission outside the optics' cone, (pi - pi / (1 + 4 F^2)) L_bb(T)."""
    solid = np.pi - _throughput_kernel(focal_length, aperture_diameter)
    return solid * _blackbody_kernel(wavelength, temperature, h=h, c=c, k=k)


def _cold_stop_kernel(emissivity, wavelength, temperature, focal_length, aperture_diameter,
                      *, h, c, k):
    """Cold stop emission through the optics' cone."""
    radiance = emissivity * _blackbody_kernel(wavelength, temperature, h=h, c=c, k=k)
    return _focal_plane_kernel(radiance, focal_length, aperture_diameter)


def _optics_emission_kernel(cold_filter_transmission, emissivity, wavelength, temperature,
                            focal_length, aperture_diameter, *, h, c, k):
    """Warm optics emission through the cold filter and the optics' cone."""
    radiance = (cold_filter_transmission * emissivity
                * _blackbody_kernel(wavelength, temperature, h=h, c=c, k=k))
    return _focal_plane_kernel(radiance, focal_length, aperture_diameter)


def _sensor_irradiance_kernel(focal_length, aperture_diameter, wavelength,
                              cold_shield_temperature, cold_filter_transmission,
                              optics_emissivity, optics_temperature, cold_filter_emissivity,
                              cold_filter_temperature, stray_irradiance, *, h, c, k):
    """Self-emission of cold shield, optics and cold stop, plus stray light (Eq. 2)."""
    f, d, knobs = focal_length, aperture_diameter, {"h": h, "c": c, "k": k}
    return (_cold_shield_kernel(f, d, wavelength, cold_shield_temperature, **knobs)
            + _optics_emission_kernel(cold_filter_transmission, optics_emissivity, wavelength,
                                      optics_temperature, f, d, **knobs)
            + _cold_stop_kernel(cold_filter_emissivity, wavelength, cold_filter_temperature,
                                f, d, **knobs)
            + stray_irradiance)


def _optics_transmission_kernel(cold_filter_transmission, obscuration_ratio, optics):
    """Transmission of cold filter, obscured pupil and optics."""
    return cold_filter_transmission * (1.0 - obscuration_ratio**2) * optics


def _detector_irradiance_kernel(optics_transmission, radiance, focal_length,
                                aperture_diameter, sensor_irradiance):
    """Scene irradiance through the optics plus the sensor's own (Eq. 2)."""
    scene = _focal_plane_kernel(radiance, focal_length, aperture_diameter)
    return optics_transmission * scene + sensor_irradiance


def _photon_rate_kernel(wavelength, quantum_efficiency, width_x, width_y, irradiance, *, h, c):
    """Spectral photoelectron rate, IBSM Eq. 3-42."""
    return (wavelength / (h * c)) * quantum_efficiency * width_x * width_y * irradiance


def _trapezoid_kernel(spectral, wavelength):
    """Trapezoid rule along the last axis (xarray's ``integrate`` formula)."""
    step = wavelength[1:] - wavelength[:-1]
    return (step * 0.5 * (spectral[..., 1:] + spectral[..., :-1])).sum(axis=-1)


def _rate_kernel(wavelength, quantum_efficiency, width_x, width_y, irradiance, *, h, c):
    """Band-integrated photoelectron rate of a spectral irradiance (last axis)."""
    spectral = _photon_rate_kernel(wavelength, quantum_efficiency, width_x, width_y,
                                   irradiance, h=h, c=c)
    return _trapezoid_kernel(spectral, wavelength)


def _scene_kernel(wavelength, quantum_efficiency, width_x, width_y, optics_transmission,
                  radiance, focal_length, aperture_diameter, sensor_irradiance, *, h, c,
                  scene=True):
    """Spectral and band photoelectron rate of a scene radiance; and without the sensor's own.

    ``scene`` False: the last is None (not computed).
    """
    irradiance = _detector_irradiance_kernel(optics_transmission, radiance, focal_length,
                                             aperture_diameter, sensor_irradiance)
    detector = (wavelength, quantum_efficiency, width_x, width_y)
    spectral = _photon_rate_kernel(*detector, irradiance, h=h, c=c)
    scene = (_rate_kernel(*detector, irradiance - sensor_irradiance, h=h, c=c) if scene
             else None)
    return spectral, _trapezoid_kernel(spectral, wavelength), scene


def _path_rate_kernel(wavelength, quantum_efficiency, width_x, width_y, optics_transmission,
                      path_thermal, solar_scatter, focal_length, aperture_diameter, *, h, c):
    """Band photoelectron rate of the path radiance through the optics."""
    path = optics_transmission * _focal_plane_kernel(path_thermal + solar_scatter,
                                                     focal_length, aperture_diameter)
    return _rate_kernel(wavelength, quantum_efficiency, width_x, width_y, path, h=h, c=c)


def _well_fill_kernel(photoelectrons, max_well_fill, max_well):
    """Scale factor (<= 1) that keeps the count under the well-fill limit."""
    limit = max_well_fill * max_well
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(photoelectrons > limit, limit / photoelectrons, 1.0)


def _full_counts_kernel(rate, dark_current, integration_time, tdi_stages):
    """Photoelectrons of one integration before any well limit (pyBSM's operation order)."""
    return (rate + dark_current) * integration_time * tdi_stages


def _counts_kernel(target_rate, dark_current, integration_time, tdi_stages, background_rate,
                   max_well_fill, max_well):
    """Counts of target and background after the well-fill limit (pyBSM's operation order)."""
    full_target = _full_counts_kernel(target_rate, dark_current, integration_time, tdi_stages)
    full_background = _full_counts_kernel(background_rate, dark_current, integration_time,
                                          tdi_stages)
    scale = _well_fill_kernel(np.maximum(full_target, full_background), max_well_fill,
                              max_well)
    target, background = scale * full_target, scale * full_background
    return target, background, target - background, scale * integration_time, scale


def _interp_kernel(curve, target, *, source):
    """``np.interp(target, source, row, left=0, right=0)`` for every row of ``curve`` at once.

    ``curve`` varies along its last axis, sampled at the increasing ``source``; the
    result varies along its last axis at ``target``. Same formula and rounding as
    ``np.interp``: exact on the nodes, ``slope * (x - x_j) + y_j`` between them.
    """
    target = np.asarray(target)
    inside = (target >= source[0]) & (target <= source[-1])
    node = np.clip(np.searchsorted(source, target, side="right") - 1, 0, source.size - 1)
    on_node = target == source[node]
    if source.size == 1:
        return np.where(on_node, curve[..., node], 0.0)
    low = np.minimum(node, source.size - 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (curve[..., low + 1] - curve[..., low]) / (source[low + 1] - source[low])
        between = slope * (target - source[low]) + curve[..., low]
    return np.where(inside, np.where(on_node, curve[..., node], between), 0.0)


# ---- the xarray boundary ------------------------------------------------------------

def _apply(kernel, args, *, wavelength=None, spectral=(True,), **knobs):
    """Run a numpy kernel once over its arguments, broadcast and labelled as xarray would.

    Parameters
    ----------
    kernel : callable
        Plain numpy function of ``args`` (positionally) and ``knobs``.
    args : sequence of float or xr.DataArray
        In the order in which their operands appear in the kernel's equation: that
        order gives the results their dimension order (xarray arithmetic's rule).
    wavelength : xr.DataArray, optional
        The band's wavelengths. When given and an argument varies with them (or is a
        sensor curve), ``wavelength`` is a core dimension: the kernel sees it as the
        last axis of every argument (length 1 where one does not vary with it) and
        may integrate over it.
    curves : sequence of (int, str)
        Position in ``args`` and parameter name of each argument that may be a sensor
        curve over ``<name>_wavelength``; a curve reaches the kernel resampled onto
        ``wavelength`` (:func:`resample_spectral`'s rule).
    spectral : sequence of bool
        One per kernel output: whether it keeps ``wavelength`` (else a band total).

    Returns
    -------
    xr.DataArray, float or tuple of them
        With the attributes of the first argument (callers name their results); inputs
        backed by dask give lazy dask results.
    """
    core = [["wavelength"] if "wavelength" in getattr(a, "dims", ()) else [] for a in args]
    if wavelength is None or not any(core):
        return apply_kernel(kernel, *args, outputs=[()] * len(spectral), **knobs)

    def over_wavelength(*arrays):
        *arrays, _ = arrays
        return kernel(*(a if core[i] else np.asarray(a)[..., np.newaxis]
                        for i, a in enumerate(arrays)), **knobs)

    out = apply_kernel(over_wavelength, *args, wavelength, core=[*core, ["wavelength"]],
                       outputs=[("wavelength",) if s else () for s in spectral])
    order = _dimension_order(args)
    outs = tuple(o.transpose(*order) if s and o.dims != order else o
                 for o, s in zip(out if isinstance(out, tuple) else (out,), spectral,
                                 strict=True))
    return outs if len(outs) > 1 else outs[0]


def _dimension_order(args):
    """Dimensions in order of first appearance, ``wavelength`` last if no argument has it."""
    order = {}
    for a in args:
        order.update(dict.fromkeys(getattr(a, "dims", ())))
    order.setdefault("wavelength")
    return tuple(order)


def planck_knobs(constants: Constants) -> dict:
    """The constants the kernels take, as plain floats."""
    return {"h": constants.planck, "c": constants.speed_of_light, "k": constants.boltzmann}


# ---- public functions ----------------------------------------------------------------

@contract(Output("blackbody_radiance", "W m-2 sr-1 m-1", "blackbody spectral radiance"))
def blackbody_radiance(wavelength, temperature, constants: Constants = CODATA):
    r"""Blackbody spectral radiance (Planck's law).

    Parameters
    ----------
    wavelength : float or xr.DataArray
        Wavelength. [m]
    temperature : float or xr.DataArray
        Temperature. [K]
    constants : Constants
        Physical constants.

    Returns
    -------
    float or xr.DataArray
        Spectral radiance. [W m-2 sr-1 m-1]

    Notes
    -----
    .. math:: L = \frac{2hc^2}{\lambda^5}\frac{e^{-x}}{1 - e^{-x}},\quad
              x = \frac{hc}{\lambda k T}

    IBSM Eq. 3-35. Written with :math:`e^{-x}` so that it underflows
    gracefully to 0 instead of overflowing when :math:`\lambda T` is small.
    """
    return _apply(_blackbody_kernel, (wavelength, temperature), **planck_knobs(constants))


@contract(Output("total_radiance", "W m-2 sr-1 m-1", "spectral radiance at the aperture"))
def total_radiance(atmosphere: xr.Dataset, reflectance, temperature, constants=CODATA):
    r"""Spectral radiance at the aperture from a Lambertian target (paper Eq. 1).

    Parameters
    ----------
    atmosphere : xr.Dataset
        ``transmission``, ``path_thermal``, ``solar_scatter`` and
        ``ground_reflected`` for the path, from :func:`xbsm.atmosphere.atmosphere_at`.
    reflectance : float or xr.DataArray
        Target reflectance. [1]
    temperature : float or xr.DataArray
        Target temperature. [K]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.DataArray
        Aperture spectral radiance. [W m-2 sr-1 m-1]

    Notes
    -----
    .. math:: L_{ap} = L_{pt} + (1 - r) L_{bb}(T)\,\tau + L_{ss} + L_{tr}\,r / r_{db}

    with :math:`r_{db} = 0.15`, the database reflectance. The database's
    SURF_EMIS column is not used: the target's own emission is
    :math:`(1-r)L_{bb}\tau`.
    """
    a = atmosphere
    out = _apply(_total_radiance_kernel, (
        a["path_thermal"], reflectance, a["wavelength"], temperature, a["transmission"],
        a["solar_scatter"], a["ground_reflected"]), **planck_knobs(constants))
    return out


@contract(Output("path_radiance", "W m-2 sr-1 m-1", "path spectral radiance"))
def path_radiance(atmosphere: xr.Dataset):
    """Spectral radiance added by the path: thermal emission plus scattered sunlight.

    Parameters
    ----------
    atmosphere : xr.Dataset
        Atmosphere for the path.

    Returns
    -------
    xr.DataArray
        Path spectral radiance. [W m-2 sr-1 m-1]
    """
    return atmosphere["path_thermal"] + atmosphere["solar_scatter"]


def is_emissive_band(wavelength_min) -> bool:
    """Whether the GIQE uses its emissive (thermal) target for this band."""
    return bool(wavelength_min >= EMISSIVE_BAND_START)


@contract(Output("giqe_radiance", "W m-2 sr-1 m-1", "GIQE standard spectral radiance"))
def giqe_radiance(atmosphere: xr.Dataset, standard: dict, emissive: bool, constants=CODATA):
    """Aperture radiance of a GIQE standard surface (target or background).

    Parameters
    ----------
    atmosphere : xr.Dataset
        Atmosphere for the path.
    standard : mapping
        :data:`GIQE_TARGET` (15%, 282 K) or :data:`GIQE_BACKGROUND` (7%, 280 K).
    emissive : bool
        Use the emissive convention (reflectance 0, temperature kept).
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.DataArray
        [W m-2 sr-1 m-1]
    """
    reflectance = 0.0 if emissive else standard["reflectance"]
    return total_radiance(atmosphere, reflectance, standard["temperature"], constants)


@contract(Output("throughput_factor", "sr", "focal-plane throughput factor"))
def throughput_factor(aperture_diameter, focal_length):
    """Projected solid angle of the optics seen from the focal plane, pi / (1 + 4 F^2).

    Parameters
    ----------
    aperture_diameter : float or xr.DataArray
        [m]
    focal_length : float or xr.DataArray
        [m]

    Returns
    -------
    float or xr.DataArray
        [sr]

    Notes
    -----
    Schott's form of IBSM Eq. 3-34, valid for fast optics too (paper Eq. 2).
    """
    return _apply(_throughput_kernel, (focal_length, aperture_diameter))


@contract(Output("focal_plane_irradiance", "W m-2 m-1", "focal-plane spectral irradiance"))
def focal_plane_irradiance(radiance, aperture_diameter, focal_length):
    r"""Focal-plane spectral irradiance from a radiance filling the pupil.

    Parameters
    ----------
    radiance : xr.DataArray
        Spectral radiance. [W m-2 sr-1 m-1]
    aperture_diameter, focal_length : float or xr.DataArray
        [m]

    Returns
    -------
    xr.DataArray
        [W m-2 m-1]

    Notes
    -----
    .. math:: E = L\,\frac{\pi}{1 + 4 (f/D)^2}
    """
    return _apply(_focal_plane_kernel, (radiance, focal_length, aperture_diameter))


@contract(Output("cold_shield_self_emission", "W m-2 m-1", "cold shield self-emission irradiance"))
def cold_shield_self_emission(wavelength, cold_shield_temperature, aperture_diameter,
                              focal_length, constants=CODATA):
    r"""Focal-plane irradiance from the cold shield outside the optics' cone.

    Parameters
    ----------
    wavelength : xr.DataArray
        [m]
    cold_shield_temperature : float or xr.DataArray
        [K]
    aperture_diameter, focal_length : float or xr.DataArray
        [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.DataArray
        [W m-2 m-1]

    Notes
    -----
    .. math:: E = \left(\pi - \frac{\pi}{1 + 4F^2}\right) L_{bb}(T_{cs})
    """
    out = _apply(_cold_shield_kernel, (focal_length, aperture_diameter, wavelength,
                                       cold_shield_temperature), **planck_knobs(constants))
    return out


@contract(Output("cold_stop_self_emission", "W m-2 m-1", "cold stop self-emission irradiance"))
def cold_stop_self_emission(wavelength, cold_filter_temperature, cold_filter_emissivity,
                            aperture_diameter, focal_length, constants=CODATA):
    """Focal-plane irradiance emitted by the cold filter / cold stop.

    Parameters
    ----------
    wavelength : xr.DataArray
        [m]
    cold_filter_temperature : float or xr.DataArray
        [K]
    cold_filter_emissivity : float or xr.DataArray
        [1]
    aperture_diameter, focal_length : float or xr.DataArray
        [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.DataArray
        [W m-2 m-1]
    """
    out = _apply(_cold_stop_kernel, (cold_filter_emissivity, wavelength, cold_filter_temperature,
                                     focal_length, aperture_diameter),
                 **planck_knobs(constants))
    return out


@contract(Output("optics_self_emission", "W m-2 m-1", "optics self-emission irradiance"))
def optics_self_emission(wavelength, optics_temperature, optics_emissivity,
                         cold_filter_transmission, aperture_diameter, focal_length,
                         constants=CODATA):
    """Focal-plane irradiance emitted by the warm optics, seen through the cold filter.

    Parameters
    ----------
    wavelength : xr.DataArray
        [m]
    optics_temperature : float or xr.DataArray
        [K]
    optics_emissivity, cold_filter_transmission : float or xr.DataArray
        [1]
    aperture_diameter, focal_length : float or xr.DataArray
        [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.DataArray
        [W m-2 m-1]
    """
    out = _apply(_optics_emission_kernel, (cold_filter_transmission, optics_emissivity,
                                           wavelength, optics_temperature, focal_length,
                                           aperture_diameter), **planck_knobs(constants))
    return out


@contract(Output("photon_detection_rate", "s-1 m-1", "spectral photoelectron rate"))
def photon_detection_rate(irradiance, quantum_efficiency, detector_width_x,
                          detector_width_y, constants=CODATA):
    r"""Spectral photoelectron generation rate of one detector (IBSM Eq. 3-42).

    Parameters
    ----------
    irradiance : xr.DataArray
        Focal-plane spectral irradiance, with a ``wavelength`` coordinate. [W m-2 m-1]
    quantum_efficiency : float or xr.DataArray
        [1]
    detector_width_x, detector_width_y : float or xr.DataArray
        Active detector widths. [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.DataArray
        Spectral rate. [electrons s-1 m-1]

    Notes
    -----
    .. math:: \frac{dN}{d\lambda} = \frac{\lambda}{hc}\,\eta(\lambda)\,w_x w_y\,E(\lambda)
    """
    out = _apply(_photon_rate_kernel, (irradiance["wavelength"], quantum_efficiency,
                                       detector_width_x, detector_width_y, irradiance),
                 h=constants.planck, c=constants.speed_of_light)
    return out


def band_integral(spectral: xr.DataArray) -> xr.DataArray:
    """Integral over ``wavelength`` by the trapezoid rule on the database samples.

    Parameters
    ----------
    spectral : xr.DataArray
        A spectral density with a ``wavelength`` coordinate. [X m-1]

    Returns
    -------
    xr.DataArray
        [X]; ``units`` and ``long_name`` follow from the integrand's, when it has them.
    """
    wavelength = spectral["wavelength"]
    out = _apply(_trapezoid_kernel, (spectral, wavelength), wavelength=wavelength,
                 spectral=(False,))
    units = spectral.attrs.get("units")
    if units is None:
        return out
    if units.endswith(" m-1"):
        units = units[: -len(" m-1")]
    else:
        units = "m" if units == "1" else f"{units} m"
    return named(out, units, f"band-integrated {spectral.attrs.get('long_name', 'quantity')}")


@contract(Output("dark_current", "s-1", "dark current"))
def dark_current_from_density(dark_current_density, detector_width_x, detector_width_y,
                              constants=CODATA):
    """Dark current of one detector from a dark current density.

    Parameters
    ----------
    dark_current_density : float or xr.DataArray
        [A m-2]
    detector_width_x, detector_width_y : float or xr.DataArray
        [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    float or xr.DataArray
        Dark current. [electrons/s]
    """
    return dark_current_density * detector_width_x * detector_width_y / constants.elementary_charge


@contract(Output("well_fill_scale", "1", "well-fill integration time scale"))
def well_fill_scale(photoelectrons, max_well, max_well_fill):
    """Factor (<= 1) that shortens the integration so the well stays below its fill limit.

    Parameters
    ----------
    photoelectrons : xr.DataArray
        Largest photoelectron count expected at the maximum integration time. [electrons]
    max_well : float or xr.DataArray
        Well capacity. [electrons]
    max_well_fill : float or xr.DataArray
        Allowed fill fraction. [1]

    Returns
    -------
    xr.DataArray
        Scale factor for integration time and counts. [1]
    """
    return _apply(_well_fill_kernel, (photoelectrons, max_well_fill, max_well))


def curve_on_band(p, name: str, wavelength):
    """:func:`resample_spectral` on plain arrays (``p``: the sensor's parameters by name)."""
    dim = f"{name}_wavelength"
    if dim not in p:
        return p[name]
    return _interp_kernel(p[name], wavelength, source=p[dim])


def resample_spectral(values, wavelength: xr.DataArray, name: str):
    """Put a sensor's spectral curve onto the model's wavelengths.

    A scalar stays a scalar. A curve over ``<name>_wavelength`` is interpolated
    linearly and is zero outside its own wavelength range (pyBSM's rule).

    Parameters
    ----------
    values : xr.DataArray
        The sensor dataset's variable ``name``.
    wavelength : xr.DataArray
        Target wavelengths. [m]
    name : str
        Parameter name (gives the private wavelength dimension).

    Returns
    -------
    xr.DataArray

    Raises
    ------
    ValueError
        If the curve has no samples.
    """
    dim = f"{name}_wavelength"
    if dim not in values.dims:
        return values
    if values.sizes[dim] == 0:
        raise ValueError(f"{name} is an empty curve: give at least one sample over "
                         f"'{dim}' (or a scalar)")
    out = xr.apply_ufunc(
        _interp_kernel, values, wavelength, kwargs={"source": values[dim].values},
        input_core_dims=[[dim], ["wavelength"]], output_core_dims=[["wavelength"]],
        keep_attrs=True, dask="parallelized", output_dtypes=[float])
    if "wavelength" not in out.coords:
        out = out.assign_coords(wavelength=wavelength)
    return out


@contract(targets=Choice(TARGETS))
def aperture_radiances(atmosphere: xr.Dataset, scenario: xr.Dataset, targets: str,
                       wavelength_min, constants=CODATA):
    """Aperture radiance of the target and of its background (paper Eq. 1).

    Parameters
    ----------
    atmosphere : xr.Dataset
        Atmosphere over the band.
    scenario : xr.Dataset
        From :func:`xbsm.scenario` (its reflectances and temperatures, for ``"scenario"``).
    targets : {"giqe", "scenario"}
        The GIQE standard target and background, or the scenario's own.
    wavelength_min : float
        Band start (selects the emissive GIQE target from 2.9 um). [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    target, background : xr.DataArray
        [W m-2 sr-1 m-1]
    """
    out = apply_orchestrator(
        radiance_arrays, RADIANCE_OUTPUTS,
        *radiance_inputs(atmosphere, surfaces(targets, wavelength_min, scenario)),
        core=(_BAND,) * 9, **planck_knobs(constants))
    return out["target_radiance"], out["background_radiance"]


def sensor_band_terms(sensor: xr.Dataset, wavelength: xr.DataArray,
                      constants=CODATA) -> xr.Dataset:
    """What the sensor contributes on the band: throughput, QE and its own irradiance.

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    wavelength : xr.DataArray
        The band's wavelengths. [m]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.Dataset
        ``optics_transmission`` (with the cold filter and the central obscuration) [1],
        ``quantum_efficiency`` [1] and ``sensor_irradiance`` (self-emission of the cold
        shield, optics and cold stop, plus stray light) [W m-2 m-1] (paper Eq. 2). The
        first two keep ``wavelength`` where the sensor's curves vary with it.
    """
    curves = {name: resample_spectral(sensor[name], wavelength, name)  # once each, here
              for name in SPECTRAL_CURVES}
    return dataset(apply_orchestrator(
        sensor_band_arrays, BAND_OUTPUTS, *sensor_band_inputs(sensor, wavelength, curves),
        core=(_BAND,) * 13, **planck_knobs(constants)))


@contract(Output("detector_irradiance", "W m-2 m-1", "focal-plane spectral irradiance"))
def detector_irradiance(radiance, band: xr.Dataset, sensor: xr.Dataset):
    """Focal-plane spectral irradiance from a scene radiance plus the sensor's own (Eq. 2).

    Parameters
    ----------
    radiance : xr.DataArray
        Aperture spectral radiance. [W m-2 sr-1 m-1]
    band : xr.Dataset
        From :func:`sensor_band_terms`.
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.

    Returns
    -------
    xr.DataArray
        [W m-2 m-1]
    """
    out = _apply(_detector_irradiance_kernel, (
        band["optics_transmission"], radiance, sensor["focal_length"],
        sensor["aperture_diameter"], band["sensor_irradiance"]))
    return out


def signal_terms(sensor: xr.Dataset, atmosphere: xr.Dataset, target_radiance,
                 background_radiance, constants=CODATA, *, band=None,
                 noise_rates=True) -> xr.Dataset:
    """Photoelectrons of target and background in one integration, by name (Sec. 2.2).

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    atmosphere : xr.Dataset
        Atmosphere over the band (its path radiance feeds the path noise).
    target_radiance, background_radiance : xr.DataArray
        Aperture spectral radiances, from :func:`aperture_radiances`. [W m-2 sr-1 m-1]
    constants : Constants
        Physical constants.
    band : xr.Dataset, optional
        :func:`sensor_band_terms` on the atmosphere's wavelengths, if the caller has it.
    noise_rates : bool
        Also the band rates only the noise terms need (:data:`NOISE_RATES`); image
        simulation does without them.

    Returns
    -------
    xr.Dataset
        ``target_photoelectrons``, ``background_photoelectrons``,
        ``contrast_photoelectrons`` [count]; ``effective_integration_time`` after the
        well-fill limit [s]; ``well_fill_scale`` [1]; ``spectral_weights``, the
        target's spectral photoelectron rate [s-1 m-1]; and the band photoelectron
        rates: ``target_rate`` (the target's, the sensor's own irradiance included,
        without dark current) and those the noise terms need, ``path_rate``,
        ``target_scene_rate``, ``background_scene_rate`` (scene plus path, without the
        sensor's own irradiance) and ``sensor_rate`` [s-1].
    """
    if band is None:
        band = sensor_band_terms(sensor, atmosphere["wavelength"], constants)
    declared = (SIGNAL_OUTPUTS if noise_rates else
                {name: o for name, o in SIGNAL_OUTPUTS.items() if name not in NOISE_RATES})
    return dataset(apply_orchestrator(
        signal_arrays, declared,
        *signal_inputs(sensor, atmosphere, band, (target_radiance, background_radiance)),
        core=_SIGNAL_CORE, h=constants.planck, c=constants.speed_of_light,
        noise_rates=bool(noise_rates)))


# ---- the stage's array orchestrators (one eager scenario: xbsm._chain's direct applier;
# ---- sweeps and dask: the doors above, through apply_orchestrator) ----------------------

_BAND = ("wavelength",)
SPECTRAL_CURVES = ("optics_transmission", "quantum_efficiency", "stray_irradiance")
"""The sensor's parameters that may be curves over wavelength (resampled onto the band)."""

_TARGET_RADIANCE = ("path_thermal", "target_reflectance", "wavelength", "target_temperature",
                    "transmission", "solar_scatter", "ground_reflected")
RADIANCE_OUTPUTS = outputs(  # each on the dims of paper Eq. 1's operands, in their order
    Output("target_radiance", "W m-2 sr-1 m-1", "spectral radiance at the aperture",
           _BAND, inputs=_TARGET_RADIANCE),
    Output("background_radiance", "W m-2 sr-1 m-1", "spectral radiance at the aperture",
           _BAND, inputs=tuple(n.replace("target", "background") for n in _TARGET_RADIANCE)),
)
"""What :func:`radiance_arrays` and :func:`aperture_radiances` return."""


def surfaces(targets: str, wavelength_min, scenario) -> tuple:
    """Reflectance and temperature of target and background (``aperture_radiances``' rule).

    The GIQE standard target and background (the emissive convention from
    :data:`EMISSIVE_BAND_START`) or the scenario's own, as
    ``((target reflectance, temperature), (background reflectance, temperature))``.
    """
    if targets == "giqe":
        emissive = is_emissive_band(float(wavelength_min))
        return tuple((0.0 if emissive else standard["reflectance"], standard["temperature"])
                     for standard in (GIQE_TARGET, GIQE_BACKGROUND))
    return tuple((scenario[f"{s}_reflectance"], scenario[f"{s}_temperature"])
                 for s in ("target", "background"))


def radiance_inputs(atm, pairs: tuple) -> tuple:
    """The arguments of :func:`radiance_arrays`, in order.

    From the band atmosphere (a mapping by name) and :func:`surfaces`' pairs.
    """
    (target_reflectance, target_temperature), (background_reflectance,
                                                background_temperature) = pairs
    return (atm["path_thermal"], atm["wavelength"], atm["transmission"],
            atm["solar_scatter"], atm["ground_reflected"], target_reflectance,
            target_temperature, background_reflectance, background_temperature)


def radiance_arrays(path_thermal, wavelength, transmission, solar_scatter, ground_reflected,
                    target_reflectance, target_temperature, background_reflectance,
                    background_temperature, *, h, c, k) -> dict:
    """:data:`RADIANCE_OUTPUTS` on plain arrays: paper Eq. 1 for target and background."""
    atm = (wavelength, transmission, solar_scatter, ground_reflected)

    def eq1(reflectance, temperature):
        w, tau, scatter, reflected = atm
        return _total_radiance_kernel(path_thermal, reflectance, w, temperature, tau, scatter,
                                      reflected, h=h, c=c, k=k)

    return {"target_radiance": eq1(target_reflectance, target_temperature),
            "background_radiance": eq1(background_reflectance, background_temperature)}


_OWN_IRRADIANCE = ("focal_length", "aperture_diameter", "wavelength", "cold_shield_temperature",
                   "cold_filter_transmission", "optics_emissivity", "optics_temperature",
                   "cold_filter_emissivity", "cold_filter_temperature", "stray_irradiance")
BAND_OUTPUTS = outputs(
    Output("optics_transmission", "1", "optics transmission on the band", _BAND,
           ("sensor",), inputs=("cold_filter_transmission", "obscuration_ratio",
                                "optics_transmission")),
    Output("quantum_efficiency", "1", "quantum efficiency on the band", _BAND,
           ("sensor",), inputs=("quantum_efficiency",)),
    Output("sensor_irradiance", "W m-2 m-1",
           "self-emission and stray focal-plane spectral irradiance", _BAND,
           ("sensor",), inputs=_OWN_IRRADIANCE),
)
"""What :func:`sensor_band_arrays` and :func:`sensor_band_terms` return."""


def sensor_band_inputs(sensor, wavelength, curves) -> tuple:
    """The arguments of :func:`sensor_band_arrays`, in order.

    From the sensor's parameters (a mapping by name), the band's wavelengths and the
    sensor's :data:`SPECTRAL_CURVES` resampled onto them (by name).
    """
    s = sensor
    return (s["cold_filter_transmission"], s["obscuration_ratio"],
            curves["optics_transmission"], s["focal_length"], s["aperture_diameter"],
            wavelength, s["cold_shield_temperature"], s["optics_emissivity"],
            s["optics_temperature"], s["cold_filter_emissivity"], s["cold_filter_temperature"],
            curves["stray_irradiance"], curves["quantum_efficiency"])


def sensor_band_arrays(cold_filter_transmission, obscuration_ratio, optics_transmission,
                       focal_length, aperture_diameter, wavelength, cold_shield_temperature,
                       optics_emissivity, optics_temperature, cold_filter_emissivity,
                       cold_filter_temperature, stray_irradiance, quantum_efficiency,
                       *, h, c, k) -> dict:
    """:data:`BAND_OUTPUTS` on plain arrays (the curves already on the band)."""
    optics = _optics_transmission_kernel(cold_filter_transmission, obscuration_ratio,
                                         optics_transmission)
    own = _sensor_irradiance_kernel(
        focal_length, aperture_diameter, wavelength, cold_shield_temperature,
        cold_filter_transmission, optics_emissivity, optics_temperature,
        cold_filter_emissivity, cold_filter_temperature, stray_irradiance, h=h, c=c, k=k)
    return {"optics_transmission": optics, "quantum_efficiency": quantum_efficiency,
            "sensor_irradiance": own}


# each output on the dims of the arguments its rule reads, in the order it reads them
_DETECTOR = ("wavelength", "quantum_efficiency", "detector_width_x", "detector_width_y",
             "optics_transmission")
_LENS = ("focal_length", "aperture_diameter")
_TARGET = (*_DETECTOR, "target_radiance", *_LENS, "sensor_irradiance")
_BACKGROUND = (*_DETECTOR, "background_radiance", *_LENS, "sensor_irradiance")
_COUNTS = (*_TARGET, "dark_current", "integration_time", "tdi_stages", *_BACKGROUND,
           "max_well_fill", "max_well")
SIGNAL_OUTPUTS = outputs(  # the first five in the order _counts_kernel returns them
    Output("target_photoelectrons", "count", "target photoelectrons", inputs=_COUNTS),
    Output("background_photoelectrons", "count", "background photoelectrons", inputs=_COUNTS),
    Output("contrast_photoelectrons", "count", "contrast photoelectrons", inputs=_COUNTS),
    Output("effective_integration_time", "s", "integration time after the well-fill limit",
           inputs=_COUNTS),
    Output("well_fill_scale", "1", "well-fill integration time scale", inputs=_COUNTS),
    Output("spectral_weights", "s-1 m-1", "target spectral photoelectron rate", _BAND,
           inputs=_TARGET),
    Output("target_rate", "s-1", "target photoelectron rate", inputs=_TARGET),
    Output("path_rate", "s-1", "path radiance photoelectron rate",
           inputs=(*_DETECTOR, "path_thermal", "solar_scatter", *_LENS)),
    Output("target_scene_rate", "s-1", "target scene and path photoelectron rate",
           inputs=_TARGET),
    Output("background_scene_rate", "s-1", "background scene and path photoelectron rate",
           inputs=_BACKGROUND),
    Output("sensor_rate", "s-1", "self-emission and stray photoelectron rate",
           carries=("sensor",), inputs=(*_DETECTOR[:4], "sensor_irradiance")),
)
"""What :func:`signal_arrays` and :func:`signal_terms` return."""
_COUNT_NAMES = tuple(SIGNAL_OUTPUTS)[:5]
NOISE_RATES = ("path_rate", "target_scene_rate", "background_scene_rate", "sensor_rate")
"""The band rates of :data:`SIGNAL_OUTPUTS` that only the noise terms read."""
_SPECTRAL_INPUTS = frozenset((*_TARGET, *_BACKGROUND, "path_thermal", "solar_scatter"))


def signal_inputs(sensor, atm, band, radiances) -> tuple:
    """The arguments of :func:`signal_arrays`, in order.

    From the sensor's parameters, the band atmosphere and the band terms
    (:data:`BAND_OUTPUTS`), each a mapping by name, and the (target, background)
    aperture radiances.
    """
    s = sensor
    target, background = radiances
    return (atm["wavelength"], band["quantum_efficiency"], s["detector_width_x"],
            s["detector_width_y"], band["optics_transmission"], target, background,
            s["focal_length"], s["aperture_diameter"], band["sensor_irradiance"],
            s["dark_current"], s["integration_time"], s["tdi_stages"], s["max_well_fill"],
            s["max_well"], atm["path_thermal"], atm["solar_scatter"])


def signal_arrays(wavelength, quantum_efficiency, detector_width_x, detector_width_y,
                  optics_transmission, target_radiance, background_radiance, focal_length,
                  aperture_diameter, sensor_irradiance, dark_current, integration_time,
                  tdi_stages, max_well_fill, max_well, path_thermal, solar_scatter,
                  *, h, c, noise_rates=True) -> dict:
    """:data:`SIGNAL_OUTPUTS` on plain arrays, from :func:`sensor_band_arrays`' band terms.

    The spectral arguments (``wavelength`` and every argument of the scene, path and
    sensor rates) vary along their last axis (or are constant: length 1 or 0-d); the
    others are band quantities. ``noise_rates`` False: without :data:`NOISE_RATES`.
    """
    hc = {"h": h, "c": c}
    detector = (wavelength, quantum_efficiency, detector_width_x, detector_width_y,
                optics_transmission)
    lens = (focal_length, aperture_diameter)
    (weights, target_rate, target_scene), (_, background_rate, background_scene) = (
        _scene_kernel(*detector, radiance, *lens, sensor_irradiance, scene=noise_rates, **hc)
        for radiance in (target_radiance, background_radiance))
    counts = _counts_kernel(target_rate, dark_current, integration_time, tdi_stages,
                            background_rate, max_well_fill, max_well)
    out = {**dict(zip(_COUNT_NAMES, counts, strict=True)), "spectral_weights": weights,
           "target_rate": target_rate}
    if noise_rates:
        out.update({
            "path_rate": _path_rate_kernel(*detector, path_thermal, solar_scatter, *lens, **hc),
            "target_scene_rate": target_scene, "background_scene_rate": background_scene,
            "sensor_rate": _rate_kernel(*detector[:4], sensor_irradiance, **hc)})
    return out


_SIGNAL_CORE = tuple(_BAND if name in _SPECTRAL_INPUTS else ()
                     for name in signal_arrays.__code__.co_varnames[:17])


_EXPOSURE = ("target_rate", "dark_current", "integration_time", "tdi_stages", "max_well")
REFLECTANCE_COUNT_OUTPUTS = outputs(
    Output("photoelectrons", "count", "photoelectrons per pixel", ("reflectance",),
           inputs=_EXPOSURE),
    Output("effective_integration_time", "s", "integration time after the well limit",
           inputs=("integration_time", *_EXPOSURE)),
    Output("spectral_weights", "1", "normalised spectral photoelectron rate", _BAND,
           inputs=("spectral_weights",)),
    Output("well_fill_scale", "1", "well-fill integration time scale", inputs=_EXPOSURE),
)
"""What :func:`reflectance_counts_arrays` returns."""


def reflectance_counts_arrays(target_rate, spectral_weights, dark_current, integration_time,
                              tdi_stages, max_well) -> dict:
    """:data:`REFLECTANCE_COUNT_OUTPUTS` on plain arrays: image simulation's well rule.

    The counts of Lambertian targets of many reflectances in one integration, scaled by
    one factor so that the brightest fills the well at most, then capped at it (pyBSM's
    ``reflectance_to_photoelectrons``); and the brightest target's spectral rate
    normalised to a peak of 1. ``target_rate`` (the signal stage's) varies with
    reflectance along its last axis, ``spectral_weights`` along its last two
    (reflectance, wavelength); the others are band quantities.
    """
    dark, time, stages, well = (np.asarray(a)[..., np.newaxis] for a in (
        dark_current, integration_time, tdi_stages, max_well))
    counts = _full_counts_kernel(target_rate, dark, time, stages)
    saturation = np.fmax.reduce(counts, axis=-1) / max_well  # NaN-skipping maximum
    scale = np.where(saturation > 1.0, 1.0 / saturation, 1.0)
    brightest = spectral_weights[..., -1, :]
    return {"photoelectrons": np.minimum(counts * scale[..., np.newaxis], well),
            "effective_integration_time": integration_time * scale,
            "spectral_weights": brightest / np.fmax.reduce(brightest, axis=-1, keepdims=True),
            "well_fill_scale": scale}


# ---- noise-equivalent temperature difference, radiance and irradiance --------------------

def _blackbody_derivative_kernel(wavelength, temperature, *, h, c, k):
    """Temperature derivative of Planck's law, dL/dT = L (x / T) / (1 - e^-x)."""
    x = h * c / (wavelength * k * temperature)
    radiance = _blackbody_kernel(wavelength, temperature, h=h, c=c, k=k)
    return radiance * (x / temperature) / -np.expm1(-x)


_SENSITIVITY = ("wavelength", "quantum_efficiency", "detector_width_x", "detector_width_y",
                "optics_transmission", "transmission", "target_reflectance",
                "target_temperature", "focal_length", "aperture_diameter")
_NOISE_EQUIVALENT = (*_SENSITIVITY, "effective_integration_time", "tdi_stages",
                     "total_noise")
SENSITIVITY_OUTPUTS = outputs(
    Output("signal_derivative", "count K-1",
           "temperature derivative of the target photoelectrons of one frame",
           inputs=(*_SENSITIVITY, "effective_integration_time", "tdi_stages")),
    Output("netd_frame", "K", "single-frame noise-equivalent temperature difference",
           inputs=_NOISE_EQUIVALENT),
    Output("netd", "K", "noise-equivalent temperature difference after frame stacking",
           inputs=(*_NOISE_EQUIVALENT, "frame_stacks")),
    Output("ner", "W m-2 sr-1",
           "noise-equivalent band radiance at the aperture after frame stacking",
           inputs=(*_NOISE_EQUIVALENT, "frame_stacks")),
    Output("ner_target", "W m-2 sr-1",
           "noise-equivalent band radiance leaving the target after frame stacking",
           inputs=(*_NOISE_EQUIVALENT, "frame_stacks")),
    Output("nei", "W m-2",
           "noise-equivalent band irradiance at the entrance pupil after frame stacking",
           inputs=(*_NOISE_EQUIVALENT, "frame_stacks")),
)
"""What :func:`sensitivity_arrays` and :func:`noise_equivalent_terms` return."""
_SENSITIVITY_CORE = tuple(_BAND if name in _SENSITIVITY else ()  # the integrand's arguments
                          for name in (*_NOISE_EQUIVALENT, "frame_stacks"))


def sensitivity_inputs(sensor, scenario, atm, band, signal, total_noise) -> tuple:
    """The arguments of :func:`sensitivity_arrays`, in order.

    From the sensor's and the scenario's parameters, the band atmosphere, the band terms
    (:data:`BAND_OUTPUTS`) and the signal stage's outputs (each a mapping by name), and
    the noise stage's ``total_noise``.
    """
    s, sc = sensor, scenario
    return (atm["wavelength"], band["quantum_efficiency"], s["detector_width_x"],
            s["detector_width_y"], band["optics_transmission"], atm["transmission"],
            sc["target_reflectance"], sc["target_temperature"], s["focal_length"],
            s["aperture_diameter"], signal["effective_integration_time"], s["tdi_stages"],
            total_noise, s["frame_stacks"])


def sensitivity_arrays(wavelength, quantum_efficiency, detector_width_x, detector_width_y,
                       optics_transmission, transmission, target_reflectance,
                       target_temperature, focal_length, aperture_diameter,
                       effective_integration_time, tdi_stages, total_noise, frame_stacks,
                       *, h, c, k) -> dict:
    """:data:`SENSITIVITY_OUTPUTS` on plain arrays: NETD, NER and NEI of the target.

    The target's temperature derivative of paper Eq. 1 (its emission, (1 - r) dL_bb/dT,
    through the path transmission) goes through the same optics, detector and band
    integral as its signal (:func:`signal_arrays`); the noise is the noise stage's
    total. The spectral arguments vary along their last axis (or are constant).
    """
    emitted = (1.0 - target_reflectance) * _blackbody_derivative_kernel(
        wavelength, target_temperature, h=h, c=c, k=k)  # at the target [W m-2 sr-1 m-1 K-1]
    at_aperture = emitted * transmission
    irradiance = optics_transmission * _focal_plane_kernel(at_aperture, focal_length,
                                                           aperture_diameter)
    rate = _rate_kernel(wavelength, quantum_efficiency, detector_width_x, detector_width_y,
                        irradiance, h=h, c=c)  # [s-1 K-1]
    derivative = rate * effective_integration_time * tdi_stages
    with np.errstate(divide="ignore", invalid="ignore"):
        netd_frame = total_noise / derivative
    netd = netd_frame / np.sqrt(frame_stacks)
    ner = netd * _trapezoid_kernel(at_aperture, wavelength)
    # the pupil irradiance that, collected by the whole pupil (pi D^2 / 4, the obscuration
    # is in the optics transmission) onto one detector, gives the photoelectrons of the
    # radiance ner filling the detector's field (pi / (1 + 4 F^2) its throughput)
    # (on the wavelength axis: the sensor's band arguments come with a length-1 one)
    pupil = 4.0 * detector_width_x * detector_width_y / (aperture_diameter**2.0
                                                         + 4.0 * focal_length**2.0)
    nei = netd * _trapezoid_kernel(at_aperture * pupil, wavelength)
    return {"signal_derivative": derivative, "netd_frame": netd_frame, "netd": netd,
            "ner": ner, "ner_target": netd * _trapezoid_kernel(emitted, wavelength),
            "nei": nei}


def noise_equivalent_terms(sensor: xr.Dataset, scenario: xr.Dataset, atmosphere: xr.Dataset,
                           band: xr.Dataset, signal: xr.Dataset, total_noise,
                           constants=CODATA) -> xr.Dataset:
    r"""Noise-equivalent temperature difference, radiance and irradiance of the target.

    Parameters
    ----------
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario` (the target's reflectance and
        temperature).
    atmosphere : xr.Dataset
        Atmosphere over the band (its ``transmission``).
    band : xr.Dataset
        From :func:`sensor_band_terms`.
    signal : xr.Dataset
        From :func:`signal_terms` (its ``effective_integration_time``).
    total_noise : xr.DataArray
        From :func:`xbsm.noise.noise_terms`. [count]
    constants : Constants
        Physical constants.

    Returns
    -------
    xr.Dataset
        ``signal_derivative`` [count K-1], ``netd_frame`` and ``netd`` [K], ``ner`` (at
        the aperture) and ``ner_target`` (leaving the target) [W m-2 sr-1], ``nei`` (at
        the entrance pupil) [W m-2].

    Notes
    -----
    .. math:: \mathrm{NETD} = \frac{\sigma}{\sqrt{n_f}\,\partial N / \partial T},\qquad
       \frac{\partial N}{\partial T} = t\,n_{TDI}\int \frac{\lambda}{hc}\,\eta\,w_x w_y\,
       \tau_o \frac{\pi}{1 + 4F^2}\,\tau_a (1 - r)\frac{\partial L_{bb}}{\partial T}\,
       d\lambda

    with :math:`\sigma` the total noise, :math:`n_f` the frame stacks; NER is NETD times
    the band integral of :math:`\tau_a (1 - r)\,\partial L_{bb}/\partial T` (without
    :math:`\tau_a` at the target), NEI is NER times
    :math:`4 w_x w_y / (D^2 + 4 f^2)`.
    """
    return dataset(apply_orchestrator(
        sensitivity_arrays, SENSITIVITY_OUTPUTS,
        *sensitivity_inputs(sensor, scenario, atmosphere, band, signal, total_noise),
        core=_SENSITIVITY_CORE, **planck_knobs(constants)))


# ---- targets: the GIQE's standard one, the scenario's, or a set of one's own --------------

TARGET_SETS = MappingProxyType({
    "nato_image_intensifier_gen2": MappingProxyType({
        "characteristic_dimension": 2.3, "thermal_contrast": 0.0, "reflectance_contrast": 0.25,
        "source": "NATO STANAG on the nominal static range of image intensifier systems, "
                  "para. 6 (target 2.3 x 2.3 m, initial contrast C0 = 0.25 for 2nd "
                  "generation), as reproduced at https://nippon.zaidan.info/seikabutsu/1998/"
                  "00222/contents/099.htm"}),
    "nato_image_intensifier_gen3": MappingProxyType({
        "characteristic_dimension": 2.3, "thermal_contrast": 0.0, "reflectance_contrast": 0.4,
        "source": "as nato_image_intensifier_gen2 (C0 = 0.4 for 3rd generation)"}),
    "imo_night_vision": MappingProxyType({
        "characteristic_dimension": 1.5**0.5, "thermal_contrast": 1.0,
        "reflectance_contrast": 0.25,
        "source": "IMO performance standard for night vision equipment for high-speed craft, "
                  "5.2.6 (target 1.5 m high x 1 m wide; contrast at most 0.25 in the visual "
                  "and near infrared, temperature difference at most 1 K), as reproduced at "
                  "https://nippon.zaidan.info/seikabutsu/1998/00226/contents/021.htm"}),
})
"""Published standard targets: characteristic dimension sqrt(area) [m], thermal contrast
(target minus background temperature) [K], reflectance contrast (Weber contrast of the
reflectances, (r_t - r_b) / r_b, the standards' initial contrast read so) [1], and the
source. :func:`target_set` makes a set of one's own."""

_TARGET_SPECS = MappingProxyType({
    "characteristic_dimension": ("m", "target characteristic dimension, sqrt(area)", 0.0),
    "thermal_contrast": ("K", "target minus background temperature", -np.inf),
    "reflectance_contrast": ("1", "target reflectance contrast (r_t - r_b) / r_b", -1.0),
})


def target_set(characteristic_dimension, thermal_contrast=0.0, reflectance_contrast=0.0, *,
               names=None) -> xr.Dataset:
    """A set of targets as data, on dim ``target``: for ``targets=`` of snr and niirs.

    Parameters
    ----------
    characteristic_dimension : float or array_like
        Square root of the target's area, in (0, inf). [m]
    thermal_contrast : float or array_like
        Target temperature minus the background's (the scenario's
        ``background_temperature``), finite. [K]
    reflectance_contrast : float or array_like
        Weber contrast of the reflectances, (r_t - r_b) / r_b, in [-1, inf), with r_b the
        scenario's ``background_reflectance``. [1]
    names : sequence of str, optional
        The targets' names (the ``target`` coordinate); default 0, 1, ...

    Returns
    -------
    xr.Dataset
        ``characteristic_dimension``, ``thermal_contrast``, ``reflectance_contrast`` over
        ``target``, each with ``units`` and ``long_name``.
    """
    values = {"characteristic_dimension": characteristic_dimension,
              "thermal_contrast": thermal_contrast, "reflectance_contrast": reflectance_contrast}
    arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=float))
                                   for v in values.values()))
    for (name, (units, _, low)), array in zip(_TARGET_SPECS.items(), arrays, strict=True):
        if array.ndim != 1:
            raise ValueError(f"{name} must be a number or a 1-D sequence; got shape "
                             f"{array.shape}")
        bad = ~np.isfinite(array) | (array <= low if name == "characteristic_dimension"
                                     else array < low)
        if np.any(bad):
            interval = "(0, inf)" if low == 0.0 else f"[{low:g}, inf)"
            raise ValueError(f"{name} must be finite and lie in {interval} {units}; got "
                             f"{array[bad][0]!r}")
    labels = list(range(arrays[0].size)) if names is None else list(names)
    if len(labels) != arrays[0].size:
        raise ValueError(f"names must give one name per target ({arrays[0].size}); got "
                         f"{len(labels)}")
    return xr.Dataset(
        {name: ("target", array, {"units": units, "long_name": long_name})
         for (name, (units, long_name, _)), array in zip(_TARGET_SPECS.items(), arrays,
                                                           strict=True)},
        coords={"target": labels}, attrs={"xbsm_kind": "target_set"})


def standard_targets(*names: str) -> xr.Dataset:
    """The published standard targets of :data:`TARGET_SETS` (all by default) as a set.

    Parameters
    ----------
    *names : str
        Keys of :data:`TARGET_SETS`.

    Returns
    -------
    xr.Dataset
        As :func:`target_set`, with each target's ``source`` as a coordinate.
    """
    names = names or tuple(TARGET_SETS)
    unknown = [n for n in names if n not in TARGET_SETS]
    if unknown:
        raise ValueError(f"target set names must be among {sorted(TARGET_SETS)}; got "
                         f"{unknown[0]!r}")
    rows = [TARGET_SETS[n] for n in names]
    out = target_set(*([row[key] for row in rows] for key in _TARGET_SPECS), names=names)
    return out.assign_coords(source=("target", [row["source"] for row in rows]))


def check_target_set(name: str, value) -> xr.Dataset:
    """``value`` if it is a target set (:func:`target_set`), else a ValueError naming ``name``."""
    if not (isinstance(value, xr.Dataset) and value.attrs.get("xbsm_kind") == "target_set"):
        raise ValueError(f"{name} must be one of {', '.join(map(repr, TARGETS))} or a target "
                         "set from xbsm.radiometry.target_set(...) or standard_targets(...); "
                         f"got {type(value).__name__}")
    return value


def targets_on_scenario(scenario: xr.Dataset, targets: xr.Dataset) -> xr.Dataset:
    """The scenario with each target of a set on its background, over dim ``target``.

    The target's temperature is the background's plus the thermal contrast, its
    reflectance the background's times one plus the reflectance contrast; the background
    stays the scenario's.
    """
    out = scenario.assign(
        target_temperature=scenario["background_temperature"] + targets["thermal_contrast"],
        target_reflectance=scenario["background_reflectance"]
        * (1.0 + targets["reflectance_contrast"]))
    for name in ("target_temperature", "target_reflectance"):
        out[name].attrs = dict(scenario[name].attrs)
    return out


def standard_target(targets: str, wavelength_min, scenario):
    """Whether the target and background are the GIQE's standard ones (:func:`surfaces`).

    True for ``"giqe"``; for ``"scenario"``, where the scenario's four values equal the
    standard's (the emissive convention from :data:`EMISSIVE_BAND_START`). [bool]
    """
    if targets == "giqe":
        return np.True_
    given = surfaces(targets, wavelength_min, scenario)
    standard = surfaces("giqe", wavelength_min, scenario)
    same = [value == expected for pair, reference in zip(given, standard, strict=True)
            for value, expected in zip(pair, reference, strict=True)]
    return same[0] & same[1] & same[2] & same[3]
