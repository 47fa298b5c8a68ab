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

import numpy as np
import xarray as xr

from .. import params
from .._kernels import apply_kernel, dataset
from .._metadata import named
from ..methods import Method
from . import aperture, defocus, filters, motion, turbulence, wavefront
from .detector import detector_kernel
from .motion import jitter_kernel
from .spectral import _spectral, is_lazy

ORIENTATION = xr.DataArray(["x", "y"], dims="orientation", name="orientation")
"""The two slice directions the GIQE uses: along x (fx = f) and along y (fy = f)."""
_UNIT_X = xr.DataArray([1.0, 0.0], dims="orientation", coords={"orientation": ORIENTATION})
_UNIT_Y = xr.DataArray([0.0, 1.0], dims="orientation", coords={"orientation": ORIENTATION})
_X_AND_Y = np.eye(2)  # the unit vectors as numpy rows (a list costs 3 us a product)
_X_AND_Y.flags.writeable = False

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
        fx, fy_ = (apply_kernel(np.multiply, frequency, unit) for unit in (_UNIT_X, _UNIT_Y))
        radial = frequency
    else:
        fx, fy_ = frequency, fy
        radial = np.hypot(frequency, fy)
    wavelength = spectral_weights["wavelength"]
    wl, w = spectral_bins(wavelength, spectral_weights, method.otf_wavelengths)
    wl = xr.DataArray(np.asarray(wl), dims="wavelength", coords={"wavelength": np.asarray(wl)})
    w = apply_kernel(_normalised, w, core=[["wavelength"]], outputs=[("wavelength",)])
    parts = {
        # sensor quantities, weighted per scenario where they depend on wavelength
        "aperture": _spectral(_aperture_band_kernel, radial, s["aperture_diameter"],
                              s["obscuration_ratio"], s["defocus_opd"], wl, w, blocked=True,
                              # not with a defocus sweep: each block decides in focus or
                              # not on its own W020 values, the shared columns on all of them
                              mono=_aperture_kernel if s["defocus_opd"].size == 1 else None,
                              defocus_otf=_defocus_otf(s["defocus_opd"], method)),
        "turbulence": None,
        "detector": apply_kernel(detector_kernel, s["detector_width_x"], s["focal_length"], fx,
                              s["detector_width_y"], fy_),
        "jitter": apply_kernel(jitter_kernel, s["jitter_x"], fx, s["jitter_y"], fy_),
        "drift": (apply_kernel(_exposure_drift_kernel, s["drift_rate_x"], integration_time,
                               s["tdi_stages"], fx, s["drift_rate_y"], fy_) if fy is not None
                  else _drift_on_slices(s, integration_time, frequency, fx)),
        # in cache-sized blocks only where there is wavefront error to evaluate: without,
        # the kernel is the sum of the weights, at once (a focal-length sweep spent 6 % of
        # its time in 1,000 blocks of that sum)
        "wavefront": _spectral(_wavefront_band_kernel, s["wavefront_variance"],
                               s["wavefront_wavelength"], fx, s["wavefront_correlation_length_x"],
                               fy_, s["wavefront_correlation_length_y"], wl, w,
                               blocked=_has_wavefront_error(s)),
    }
    parts["turbulence"], r0_band = _turbulence(s, sc, radial, wl, w, integration_time,
                                               slant_range, method)
    unfiltered = apply_kernel(_product_kernel, *parts.values())
    fil = _filter(s, fx, fy_, method)
    if _filter_rule(_kernel_of(s), method.filter_otf) is None:
        # times exactly 1: the same numbers, so the same array (no full-size copy)
        system = unfiltered.copy(deep=False)
    else:
        system = apply_kernel(np.multiply, unfiltered, fil,
                              dtype=np.result_type(unfiltered.dtype, fil.dtype))
    return dataset({
        **{name: _otf(part, f"{name} OTF") for name, part in parts.items()},
        "filter": _otf(fil, "post-processing filter OTF"),
        "system_unfiltered": _otf(unfiltered, "system OTF without the filter"),
        "system": _otf(system, "system OTF"),
        "coherence_diameter": named(r0_band, "m", "band-weighted coherence diameter r0"),
    })


def _otf(out: xr.DataArray, long_name: str) -> xr.DataArray:
    """A freshly computed OTF with its CF attributes (set in place: nobody else holds it)."""
    out.attrs = {"units": "1", "long_name": long_name}
    return out


def _turbulence(s, sc, radial, wl, w, integration_time, slant_range, method: Method):
    """Polychromatic turbulence OTF and band r0: path r0 at 1 um, scaled, wind-blended, weighted.

    Scenarios without turbulence (``cn2_at_1m`` = 0 or ``cn2_multiplier`` = 0) get an OTF
    of 1 and an infinite r0.
    """
    cn2, multiplier = sc["cn2_at_1m"], sc["cn2_multiplier"]
    r0_ref = apply_kernel(_turbulent_path_kernel, sc["high_altitude_wind_speed"], slant_range,
                       sc["altitude"], cn2, sc["cn2_tropopause"], sc["cn2_upper_air"],
                       multiplier,
                       nodes=turbulence.path_nodes(method.turbulence_path_samples,
                                                    method.turbulence_path_rule),
                       form=method.geometry, profile=_profile(sc))
    on = apply_kernel(_turbulent_kernel, cn2, multiplier, dtype=bool)
    otf = _spectral(_turbulence_band_kernel, on, radial, r0_ref, integration_time,
                    s["tdi_stages"], sc["platform_speed"], s["aperture_diameter"], wl, w)
    r0_band = _spectral(_band_r0_kernel, on, r0_ref, wl, w)
    return otf, r0_band


def _profile(sc):
    """(heights, Cn2) of the scenario's ``cn2_profile`` table, or None (Hufnagel-Valley)."""
    if "cn2_profile" not in sc.variables:
        return None
    return params.table_values(params.cn2_table(sc["cn2_profile"]))


def _turbulent_kernel(cn2, multiplier):
    """Where the scenario has turbulence (numpy; ``cn2 > 0`` alone at multiplier 1)."""
    return (cn2 > 0) & (multiplier > 0)


def _last(a):
    """``a`` as an array with a new last axis (for broadcasting against wavelength)."""
    return np.asarray(a)[..., None]


def _aperture_band_kernel(radial, aperture_diameter, obscuration_ratio, defocus_opd, wl, w, *,
                          defocus_otf):
    """Aperture OTF weighted over the last (wavelength) axis by normalised ``w`` (numpy).

    With defocus (W020 = ``defocus_opd`` > 0 anywhere) the aperture's OTF is the
    defocused one of :func:`xbsm.otf.defocus.defocused_aperture_kernel` by the model
    ``defocus_otf``; without, the in-focus OTF as it always was (to the bit). Either is
    ``np.einsum("...k,...k->...", _aperture_kernel(...), w)`` to the bit.
    """
    if not np.any(defocus_opd):
        # the weighted sum taken as it is evaluated (the same contraction, row by row)
        return aperture.circular_aperture_band_kernel(_last(np.hypot(radial, 0.0)),
                                                      _last(aperture_diameter), wl,
                                                      _last(obscuration_ratio), w)
    return np.einsum("...k,...k->...", _aperture_kernel(
        radial, aperture_diameter, obscuration_ratio, defocus_opd, wl,
        defocus_otf=defocus_otf), w)


def _aperture_kernel(radial, aperture_diameter, obscuration_ratio, defocus_opd, wl, *,
                     defocus_otf):
    """The monochromatic aperture OTF that :func:`_aperture_band_kernel` weights (numpy)."""
    if np.any(defocus_opd):
        return defocus.defocused_aperture_kernel(
            _last(np.hypot(radial, 0.0)), _last(aperture_diameter), wl,
            _last(obscuration_ratio), _last(defocus_opd), defocus_otf)
    return aperture.circular_aperture_kernel(_last(np.hypot(radial, 0.0)),
                                             _last(aperture_diameter), wl,
                                             _last(obscuration_ratio))


def _defocus_otf(defocus_opd, method: Method):
    """The method's defocus model; a non-zero W020 without one is refused."""
    if method.defocus_otf is None and bool(np.any(np.asarray(defocus_opd) != 0)):
        raise ValueError(
            f"method {method.name!r} has no defocus model (defocus_otf=None: pyBSM's chain "
            "has no defocus term) but the sensor's defocus_opd is non-zero; use "
            "method='accurate' or xbsm.method('pybsm', defocus_otf='hopkins')")
    return method.defocus_otf


def _has_wavefront_error(s) -> bool:
    """Whether the sensor may have wavefront error (True when lazy: not computed to find out)."""
    variance = s["wavefront_variance"]
    return is_lazy(variance) or bool(np.any(variance.values != 0))


def _wavefront_band_kernel(variance, variance_wavelength, fx, length_x, fy, length_y, wl, w):
    """Random-phase wavefront OTF weighted over the last (wavelength) axis (numpy).

    Without wavefront error (every variance 0, as in most sensors) each monochromatic
    OTF is exp(-0) = 1 exactly, and the weighted sum is the sum of the weights.
    """
    if not np.any(variance):
        shape = np.broadcast_shapes(*(np.shape(a) for a in (
            variance, variance_wavelength, fx, length_x, fy, length_y)), np.shape(w)[:-1])
        # the sum as the product with ones sums it, so that the result is the same to the bit
        total = np.einsum("...k,...k->...", np.ones(np.shape(w)[-1]), w)
        return np.array(np.broadcast_to(total, shape))
    mono = wavefront.random_phase_kernel(_last(variance), _last(variance_wavelength), wl,
                                          _last(fx), _last(length_x), _last(fy), _last(length_y))
    return np.einsum("...k,...k->...", mono, w)


def _wavefront_slices(p, nodes, wl, w):
    """:func:`_wavefront_band_kernel` on the x and y slices: (frequency, orientation) (numpy).

    Each slice on its own 1-D nodes (on the x slice fy = 0, on the y slice fx = 0, so each
    holds half the (node, wavelength) values of the pair); one evaluation for both where
    the correlation lengths are equal (the slices are then equal to the bit: (f/L)^2 + 0
    and 0 + (f/L)^2).
    """
    variance, reference = p["wavefront_variance"], p["wavefront_wavelength"]
    length_x, length_y = p["wavefront_correlation_length_x"], p["wavefront_correlation_length_y"]
    x = _wavefront_band_kernel(variance, reference, nodes, length_x, 0.0, length_y, wl, w)
    if np.array_equal(length_x, length_y):
        return np.stack([x, x], axis=-1)
    y = _wavefront_band_kernel(variance, reference, 0.0, length_x, nodes, length_y, wl, w)
    return np.stack([x, y], axis=-1)


def _exposure_drift_kernel(drift_rate_x, integration_time, tdi_stages, fx, drift_rate_y, fy):
    """Drift OTF over the exposure of all TDI stages (numpy)."""
    exposure = integration_time * tdi_stages
    return motion.drift_kernel(drift_rate_x * exposure, fx, drift_rate_y * exposure, fy)


def _exposure_drift_slices_kernel(drift_rate_x, integration_time, tdi_stages, frequency,
                                  drift_rate_y):
    """:func:`_exposure_drift_kernel` on the x and y slices, orientation last (numpy)."""
    exposure = integration_time * tdi_stages
    return motion.drift_slices_kernel(drift_rate_x * exposure, drift_rate_y * exposure,
                                      frequency)


def _drift_on_slices(s, integration_time, frequency, fx):
    """The drift OTF on the slices, labelled as :func:`_exposure_drift_kernel` labels it.

    The same numbers with half the sincs (:func:`motion.drift_slices_kernel`); its dims
    in the order the two-axis kernel's arguments give them (``fx`` is ``frequency``
    times the x unit vector).
    """
    args = (s["drift_rate_x"], integration_time, s["tdi_stages"], frequency, s["drift_rate_y"])
    out = apply_kernel(_exposure_drift_slices_kernel, *args, outputs=[("orientation",)],
                       sizes={"orientation": ORIENTATION.size})
    order = []
    for arg in (*args[:3], fx, args[4]):
        order += [dim for dim in getattr(arg, "dims", ()) if dim not in order]
    return out.transpose(*order).assign_coords(orientation=ORIENTATION)


def _turbulent_path_kernel(wind_speed, slant_range, altitude, cn2, tropopause=5.94e-53,
                           upper_air=2.7e-16, multiplier=1.0, *, nodes, form, profile=None):
    """Path r0 at 1 um of a target on the ground; a stand-in Cn2 where there is none (numpy)."""
    cn2 = np.where(cn2 > 0, cn2, 1.0e-14)
    multiplier = np.where(multiplier > 0, multiplier, 1.0)
    return turbulence.slant_path_kernel(turbulence.REFERENCE_WAVELENGTH, wind_speed,
                                         slant_range, altitude, 0.0, cn2, tropopause,
                                         upper_air, multiplier, nodes=nodes, form=form,
                                         profile=profile)


def _turbulence_band_kernel(cn2, radial, r0_ref, integration_time, tdi_stages, speed, diameter,
                            wl, w):
    """Wind-blended turbulence OTF weighted over wavelength; 1 where cn2 = 0 (numpy)."""
    otf = turbulence.polychromatic_kernel(
        np.hypot(radial, 0.0), r0_ref, integration_time * tdi_stages, speed, diameter,
        turbulence.REFERENCE_WAVELENGTH, wl, w)
    return np.where(cn2 > 0, otf, 1.0)


def _band_r0_kernel(cn2, r0_ref, wl, w):
    """Band-weighted r0; infinite where cn2 = 0 (numpy)."""
    r0 = turbulence.band_kernel(r0_ref, turbulence.REFERENCE_WAVELENGTH, wl, w)
    return np.where(cn2 > 0, r0, np.inf)


def _normalised(weights):
    """Weights over the last axis scaled to sum to one (numpy)."""
    return weights / weights.sum(axis=-1, keepdims=True)


def _product_kernel(*factors):
    """The factors' product, left to right (the bits of ``math.prod``), in one buffer.

    Once the product has its full shape it is one array of ours, in the memory layout of
    the full-size factor (the drift OTF of a study chunk: 50,000 scenarios x 2 slices x
    195 nodes, 156 MB), and every factor multiplies into it; the smaller factors are
    first copied into that layout, so the large arrays are read and written in order (the
    strided product took 0.11 s of such a chunk, in order 0.03 s, and one 156 MB array
    instead of one per factor).
    """
    shape = np.broadcast_shapes(*(np.shape(f) for f in factors))
    template = next((f for f in factors if isinstance(f, np.ndarray) and f.shape == shape
                     and f.ndim > 1), None)
    product, owned = factors[0], False
    for factor in factors[1:]:
        if owned and np.result_type(product, factor) == product.dtype:
            np.multiply(product, _in_layout(factor, template), out=product)
        elif template is not None and np.broadcast_shapes(np.shape(product),
                                                          np.shape(factor)) == shape:
            out = np.empty_like(template, dtype=np.result_type(product, factor))
            product = np.multiply(_in_layout(product, template), _in_layout(factor, template),
                                  out=out)
            owned = True
        else:
            product = product * factor
    return product


def _in_layout(a, template: np.ndarray):
    """``a`` (broadcastable to ``template``) copied into ``template``'s memory order.

    Size 1 along the axes it broadcasts on; a scalar or a full-size array as it is.
    """
    if np.ndim(a) == 0 or (isinstance(a, np.ndarray) and a.shape == template.shape):
        return a
    a = np.reshape(a, (1,) * (template.ndim - np.ndim(a)) + np.shape(a))
    view = template[tuple(slice(0, 1) if n == 1 else slice(None) for n in a.shape)]
    out = np.empty_like(view, dtype=a.dtype)
    out[...] = a
    return out


def _ones_kernel(fx, fy):
    return np.ones(np.broadcast_shapes(np.shape(fx), np.shape(fy)))


def _sampled_filter_kernel(fy, pixel_pitch_y, focal_length, fx, pixel_pitch_x, *, kernel):
    """The sharpening filter at the detector's sample spacing (numpy)."""
    return filters.dtft_filter_kernel(fy, pixel_pitch_y / focal_length, fx,
                                       pixel_pitch_x / focal_length, kernel=kernel)


def _filter_rule(kernel: np.ndarray, filter_otf: str):
    """How the filter OTF is made: ``filter_otf``, or None for exactly 1 (no filter).

    ``kernel`` is (kernel_y, kernel_x). pyBSM 0.16.1 skips kernels with a single row
    (common_OTFs: shape[0] > 1).
    """
    identity = kernel.shape == (1, 1) and kernel[0, 0] == 1.0
    return None if identity or (filter_otf == "pybsm" and kernel.shape[0] == 1) else filter_otf


def _kernel_of(sensor) -> np.ndarray:
    """The sensor's filter kernel as (kernel_y, kernel_x) floats."""
    return np.asarray(sensor["filter_kernel"].transpose("kernel_y", "kernel_x").values,
                      dtype=float)


def _filter(sensor, fx, fy, method: Method):
    """The post-processing filter OTF, or exactly 1 when there is no filter."""
    k = _kernel_of(sensor)
    if _filter_rule(k, method.filter_otf) is None:
        return apply_kernel(_ones_kernel, fx, fy)
    pitch_x, pitch_y, focal = (sensor[n] for n in ("pixel_pitch_x", "pixel_pitch_y",
                                                   "focal_length"))
    if method.filter_otf == "pybsm":
        if pitch_x.ndim or focal.ndim:
            raise ValueError(
                "method filter_otf='pybsm' cannot sweep pixel_pitch_x or focal_length "
                "with a filter kernel; use filter_otf='dtft'"
            )
        return apply_kernel(filters.pybsm_filter_kernel, fx, fy, kernel=k,
                         ifov=float(pitch_x) / float(focal))
    return apply_kernel(_sampled_filter_kernel, fy, pitch_y, focal, fx, pitch_x, kernel=k,
                     dtype=complex)


# ---- the stage on plain arrays (one eager scenario; xbsm._chain's direct applier) ----

def _band_weights_arrays(spectral_weights, wavelength, count: int):
    """:func:`otf_weights`, :func:`spectral_bins` and their normalisation on plain arrays."""
    weights = np.where(spectral_weights > 0, spectral_weights, 0.0)
    if not weights.sum() > 0:
        weights = np.ones_like(weights)
    n = wavelength.size
    if 0 < count < n:
        labels = np.minimum((np.arange(n) * count) // n, count - 1)
        wavelength = np.bincount(labels, wavelength) / np.bincount(labels)
        weights = np.bincount(labels, weights)
    return wavelength, weights / weights.sum()


def binning_error_kernel(spectral_weights, wavelength, *, count: int):
    r"""Relative error the polychromatic OTFs' wavelength bins make in the mean 1/lambda.

    A system the optics limit has an RER close to the integral of its polychromatic
    aperture OTF, which is :math:`\propto \sum_i w_i / \lambda_i`; the bins
    (:func:`spectral_bins`: bin-centre wavelengths, summed weights) replace it by
    :math:`\sum_b W_b / \bar\lambda_b`. Their relative difference bounds the RER error
    the binning makes there (measured on the random systems of
    ``recipes/evidence/preset_error.py``: at or above the RER error of ``fast``'s 24 bins
    on every system examined, 2e-5 to 3e-4); where the detector or a blur limits the
    system instead, the binning matters less.

    Parameters
    ----------
    spectral_weights : numpy.ndarray
        Spectral photoelectron rates, wavelength on the last axis (non-positive ones count
        as zero). [any]
    wavelength : numpy.ndarray
        The band's wavelengths (1-D). [m]
    count : int
        Bins (the method's ``otf_wavelengths``); 0 or at least the band's size: no bins.

    Returns
    -------
    numpy.ndarray
        [1]; 0 without bins or without a positive weight.
    """
    weights = np.where(spectral_weights > 0, spectral_weights, 0.0)
    wavelength = np.asarray(wavelength, dtype=float)
    n = wavelength.shape[-1]
    if not 0 < count < n:
        return np.zeros(weights.shape[:-1])
    labels = np.minimum((np.arange(n) * count) // n, count - 1)
    members = (labels[:, None] == np.arange(count)).astype(float)  # (wavelength, bin)
    centres = (wavelength @ members) / members.sum(axis=0)
    full = (weights / wavelength).sum(axis=-1)
    binned = ((weights @ members) / centres).sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(full > 0, np.abs(binned / full - 1.0), 0.0)


def _filter_arrays(p, fx, fy, method: Method):
    """:func:`_filter` on plain arrays."""
    kernel = p["filter_kernel"]
    rule = _filter_rule(kernel, method.filter_otf)
    if rule is None:
        return np.ones(fx.shape)
    if rule == "pybsm":
        return filters.pybsm_filter_kernel(fx, fy, kernel=kernel,
                                            ifov=p["pixel_pitch_x"] / p["focal_length"])
    return _sampled_filter_kernel(fy, p["pixel_pitch_y"], p["focal_length"], fx,
                                  p["pixel_pitch_x"], kernel=kernel)


def system_slice_arrays(p, nodes, wavelength, spectral_weights, integration_time, slant_range,
                        method: Method):
    """Unfiltered and filtered system OTF on the x and y slices, and the band r0 (arrays).

    As :func:`system_components` for one eager scenario (``p``: its sensor and scenario
    parameters), with the ``nodes`` (frequency) along the first axis and orientation
    (x, y) along the second.
    """
    fx, fy = nodes[:, None] * _X_AND_Y[0], nodes[:, None] * _X_AND_Y[1]
    wl, w = _band_weights_arrays(spectral_weights, wavelength, method.otf_wavelengths)
    r0_ref = _turbulent_path_kernel(
        p["high_altitude_wind_speed"], slant_range, p["altitude"], p["cn2_at_1m"],
        p["cn2_tropopause"], p["cn2_upper_air"], p["cn2_multiplier"],
        nodes=turbulence.path_nodes(method.turbulence_path_samples,
                                     method.turbulence_path_rule),
        form=method.geometry)
    cn2 = _turbulent_kernel(p["cn2_at_1m"], p["cn2_multiplier"])
    radial = [
        _aperture_band_kernel(nodes, p["aperture_diameter"], p["obscuration_ratio"],
                              p["defocus_opd"], wl, w,
                              defocus_otf=_defocus_otf(p["defocus_opd"], method)),
        _turbulence_band_kernel(cn2, nodes, r0_ref, integration_time, p["tdi_stages"],
                                p["platform_speed"], p["aperture_diameter"], wl, w)]
    sliced = [
        detector_kernel(p["detector_width_x"], p["focal_length"], fx, p["detector_width_y"],
                         fy),
        jitter_kernel(p["jitter_x"], fx, p["jitter_y"], fy),
        _exposure_drift_slices_kernel(p["drift_rate_x"], integration_time, p["tdi_stages"],
                                      nodes, p["drift_rate_y"]),
        _wavefront_slices(p, nodes, wl, w)]
    unfiltered = _product_kernel(*(r[:, None] for r in radial), *sliced)
    r0 = _band_r0_kernel(cn2, r0_ref, wl, w)
    return unfiltered, unfiltered * _filter_arrays(p, fx, fy, method), r0
