"""Radiometry: from aperture radiance to photoelectrons (paper Sec. 2.1-2.2).

One physical quantity per function; plain xarray arithmetic that broadcasts
over ``wavelength`` and any scenario or sensor dimension. Spectral radiance is
in W/(m^2 sr m), spectral irradiance in W/(m^2 m).
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

from ._metadata import named
from .constants import CODATA, Constants

DATABASE_REFLECTANCE = 0.15
"""Target reflectance used in the MODTRAN database runs (paper Appendix A). [1]"""

GIQE_TARGET = MappingProxyType({"reflectance": 0.15, "temperature": 282.0})
"""GIQE standard target: 15% reflectance at 282 K (IBSM; Leachtenauer et al. 1997)."""
GIQE_BACKGROUND = MappingProxyType({"reflectance": 0.07, "temperature": 280.0})
"""GIQE standard background: 7% reflectance at 280 K."""
EMISSIVE_BAND_START = 2.9e-6
"""Bands starting at or beyond this wavelength use the emissive GIQE target
(reflectance 0, so only the 282 K / 280 K temperature contrast counts). [m]"""


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
    h, c, k = constants.planck, constants.speed_of_light, constants.boltzmann
    x = h * c / (wavelength * k * temperature)
    out = (2.0 * h * c**2.0 / wavelength**5.0) * np.exp(-x) / -np.expm1(-x)
    return named(out, "W m-2 sr-1 m-1", "blackbody spectral radiance")


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
    wavelength = atmosphere["wavelength"]
    emitted = (1.0 - reflectance) * blackbody_radiance(wavelength, temperature, constants)
    out = (
        atmosphere["path_thermal"]
        + emitted * atmosphere["transmission"]
        + atmosphere["solar_scatter"]
        + atmosphere["ground_reflected"] * (reflectance / DATABASE_REFLECTANCE)
    )
    return named(out, "W m-2 sr-1 m-1", "spectral radiance at the aperture")


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
    out = atmosphere["path_thermal"] + atmosphere["solar_scatter"]
    return named(out, "W m-2 sr-1 m-1", "path spectral radiance")


def is_emissive_band(wavelength_min) -> bool:
    """Whether the GIQE uses its emissive (thermal) target for this band."""
    return bool(wavelength_min >= EMISSIVE_BAND_START)


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
    out = total_radiance(atmosphere, reflectance, standard["temperature"], constants)
    return named(out, "W m-2 sr-1 m-1", "GIQE standard spectral radiance")


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
    out = np.pi / (1.0 + 4.0 * (focal_length / aperture_diameter) ** 2.0)
    return named(out, "sr", "focal-plane throughput factor")


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
    # (L * pi) / (1 + 4F^2), pyBSM's rounding order: contrast SNRs near 1e-7 are
    # differences of nearly equal counts and keep only that order's bits
    out = radiance * np.pi / (1.0 + 4.0 * (focal_length / aperture_diameter) ** 2.0)
    return named(out, "W m-2 m-1", "focal-plane spectral irradiance")


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
    solid = np.pi - throughput_factor(aperture_diameter, focal_length)
    out = solid * blackbody_radiance(wavelength, cold_shield_temperature, constants)
    return named(out, "W m-2 m-1", "cold shield self-emission irradiance")


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
    radiance = cold_filter_emissivity * blackbody_radiance(
        wavelength, cold_filter_temperature, constants
    )
    out = focal_plane_irradiance(radiance, aperture_diameter, focal_length)
    return named(out, "W m-2 m-1", "cold stop self-emission irradiance")


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
    radiance = (
        cold_filter_transmission
        * optics_emissivity
        * blackbody_radiance(wavelength, optics_temperature, constants)
    )
    out = focal_plane_irradiance(radiance, aperture_diameter, focal_length)
    return named(out, "W m-2 m-1", "optics self-emission irradiance")


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
    wavelength = irradiance["wavelength"]
    out = (
        (wavelength / (constants.planck * constants.speed_of_light))
        * quantum_efficiency
        * detector_width_x
        * detector_width_y
        * irradiance
    )
    return named(out, "s-1 m-1", "spectral photoelectron rate")


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
    out = spectral.integrate("wavelength")
    units = spectral.attrs.get("units")
    if units is None:
        return out
    if units.endswith(" m-1"):
        units = units[: -len(" m-1")]
    else:
        units = "m" if units == "1" else f"{units} m"
    return named(out, units, f"band-integrated {spectral.attrs.get('long_name', 'quantity')}")


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
    out = dark_current_density * detector_width_x * detector_width_y / constants.elementary_charge
    return named(out, "s-1", "dark current")


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
    limit = max_well_fill * max_well
    with np.errstate(divide="ignore", invalid="ignore"):
        out = xr.where(photoelectrons > limit, limit / photoelectrons, 1.0)
    return named(out, "1", "well-fill integration time scale")


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
    """
    dim = f"{name}_wavelength"
    if dim not in values.dims:
        return values
    source = values[dim].values

    def _interp(curve, target):
        return np.interp(target, source, curve, left=0.0, right=0.0)

    out = xr.apply_ufunc(
        _interp,
        values,
        wavelength,
        input_core_dims=[[dim], ["wavelength"]],
        output_core_dims=[["wavelength"]],
        vectorize=True,
        dask="parallelized",
        output_dtypes=[float],
    )
    return out.assign_coords(wavelength=wavelength).assign_attrs(values.attrs)


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
    if targets == "giqe":
        emissive = is_emissive_band(float(wavelength_min))
        return tuple(giqe_radiance(atmosphere, standard, emissive, constants)
                     for standard in (GIQE_TARGET, GIQE_BACKGROUND))
    return tuple(total_radiance(atmosphere, scenario[f"{surface}_reflectance"],
                                scenario[f"{surface}_temperature"], constants)
                 for surface in ("target", "background"))


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
        shield, optics and cold stop, plus stray light) [W m-2 m-1] (paper Eq. 2).
    """
    s = sensor
    diameter, focal = s["aperture_diameter"], s["focal_length"]
    optics = (s["cold_filter_transmission"] * (1.0 - s["obscuration_ratio"] ** 2)
              * resample_spectral(s["optics_transmission"], wavelength, "optics_transmission"))
    self_emission = (
        cold_shield_self_emission(wavelength, s["cold_shield_temperature"], diameter, focal,
                                  constants)
        + optics_self_emission(wavelength, s["optics_temperature"], s["optics_emissivity"],
                               s["cold_filter_transmission"], diameter, focal, constants)
        + cold_stop_self_emission(wavelength, s["cold_filter_temperature"],
                                  s["cold_filter_emissivity"], diameter, focal, constants)
    )
    sensor_irradiance = self_emission + resample_spectral(s["stray_irradiance"], wavelength,
                                                          "stray_irradiance")
    return xr.Dataset({
        "optics_transmission": named(optics, "1", "optics transmission on the band"),
        "quantum_efficiency": named(
            resample_spectral(s["quantum_efficiency"], wavelength, "quantum_efficiency"),
            "1", "quantum efficiency on the band"),
        "sensor_irradiance": named(sensor_irradiance, "W m-2 m-1",
                                   "self-emission and stray focal-plane spectral irradiance"),
    })


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
    scene = focal_plane_irradiance(radiance, sensor["aperture_diameter"], sensor["focal_length"])
    out = band["optics_transmission"] * scene + band["sensor_irradiance"]
    return named(out, "W m-2 m-1", "focal-plane spectral irradiance")


def signal_terms(sensor: xr.Dataset, atmosphere: xr.Dataset, target_radiance,
                 background_radiance, constants=CODATA, *, band=None) -> xr.Dataset:
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

    Returns
    -------
    xr.Dataset
        ``target_photoelectrons``, ``background_photoelectrons``,
        ``contrast_photoelectrons`` [count]; ``effective_integration_time`` after the
        well-fill limit [s]; ``well_fill_scale`` [1]; ``spectral_weights``, the
        target's spectral photoelectron rate [s-1 m-1]; and the band photoelectron
        rates the noise terms need: ``path_rate``, ``target_scene_rate``,
        ``background_scene_rate`` (scene plus path, without the sensor's own
        irradiance) and ``sensor_rate`` [s-1].
    """
    s, k = sensor, constants
    if band is None:
        band = sensor_band_terms(s, atmosphere["wavelength"], k)
    other = band["sensor_irradiance"]

    def rate(irradiance):
        return band_integral(photon_detection_rate(
            irradiance, band["quantum_efficiency"], s["detector_width_x"],
            s["detector_width_y"], k))

    target_irradiance = detector_irradiance(target_radiance, band, s)
    background_irradiance = detector_irradiance(background_radiance, band, s)
    spectral = photon_detection_rate(target_irradiance, band["quantum_efficiency"],
                                     s["detector_width_x"], s["detector_width_y"], k)
    t, stages = s["integration_time"], s["tdi_stages"]  # pyBSM's operation order (parity)
    full_target = (band_integral(spectral) + s["dark_current"]) * t * stages
    full_background = (rate(background_irradiance) + s["dark_current"]) * t * stages
    scale = well_fill_scale(np.maximum(full_target, full_background), s["max_well"],
                            s["max_well_fill"])
    n_target, n_background = scale * full_target, scale * full_background
    path = band["optics_transmission"] * focal_plane_irradiance(
        path_radiance(atmosphere), s["aperture_diameter"], s["focal_length"])
    return xr.Dataset({
        "target_photoelectrons": named(n_target, "count", "target photoelectrons"),
        "background_photoelectrons": named(n_background, "count", "background photoelectrons"),
        "contrast_photoelectrons": named(n_target - n_background, "count",
                                         "contrast photoelectrons"),
        "effective_integration_time": named(scale * s["integration_time"], "s",
                                   "integration time after the well-fill limit"),
        "well_fill_scale": scale,
        "spectral_weights": named(spectral, "s-1 m-1", "target spectral photoelectron rate"),
        "path_rate": named(rate(path), "s-1", "path radiance photoelectron rate"),
        "target_scene_rate": named(rate(target_irradiance - other), "s-1",
                                   "target scene and path photoelectron rate"),
        "background_scene_rate": named(rate(background_irradiance - other), "s-1",
                                       "background scene and path photoelectron rate"),
        "sensor_rate": named(rate(other), "s-1", "self-emission and stray photoelectron rate"),
    })
