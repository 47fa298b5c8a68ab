"""Validity flags: one bit per known way a result can be untrustworthy.

Results carry an integer variable ``flags`` with CF ``flag_masks`` and
``flag_meanings`` attributes. A set bit never replaces a value by a silent
NaN: where a value is NaN, a bit says why; where a value is finite but
outside a method's range of validity, a bit says which range.

Every bit belongs to one of three groups, so that one test answers the
question a user has:

- :data:`INVALID`: the number is NaN or may be wrong (no atmosphere data, SNR
  at or below zero, a frequency grid too coarse for the edge integral, the
  database's inconsistent tables above 24.5 km).
  Test with :func:`is_invalid`.
- :data:`CALIBRATION`: the number is computed correctly, but a GIQE is used
  outside the range of images it was fitted or validated on (per version:
  :data:`xbsm.metrics.GIQE_CALIBRATIONS`), or the NIIRS is off the rating
  scale. Test with :func:`is_outside_calibration`.
- :data:`NOTICE`: something the user should know that makes the number
  neither wrong nor extrapolated (a shortened integration time, an
  atmosphere interpolated across the database's altitude gap, a spectral
  curve that covers only part of the band).
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

from ._kernels import apply_kernel
from .atmosphere.database import ALTITUDE_GAP

# bit -> (meaning, description). The meanings are CF flag_meanings words.
FLAGS = MappingProxyType({
    "beyond_database": (
        1,
        "no atmosphere data for this geometry (beyond the horizon or outside the "
        "MODTRAN table); radiometric results are NaN",
    ),
    "atmosphere_sparse": (
        2,
        "atmosphere interpolated across a wide database gap (altitude between "
        f"{ALTITUDE_GAP[0] / 1e3:g} km and {ALTITUDE_GAP[1] / 1e3:g} km)",
    ),
    "well_fill_limited": (
        4,
        "integration time was shortened to keep the well below its fill limit",
    ),
    "snr_out_of_range": (
        8,
        "contrast SNR outside the GIQE calibration range",
    ),
    "rer_out_of_range": (16, "RER outside the GIQE calibration range"),
    "gsd_out_of_range": (32, "GSD outside the GIQE calibration range"),
    "elevation_out_of_range": (64, "elevation angle outside the GIQE calibration range"),
    "undersampled_grid": (
        128,
        "frequency sampling of the chosen method does not resolve the edge-response "
        "integrand (result may be inaccurate)",
    ),
    "niirs_out_of_scale": (256, "NIIRS outside the 0-10 rating scale"),
    "snr_nonpositive": (
        512,
        "contrast SNR at or below zero: GIQE noise terms are undefined; NIIRS is NaN",
    ),
    "q_out_of_range": (
        1024,
        "GIQE 5 only: sampling ratio Q = lambda N / p (lambda the band centre) outside "
        "the 1-2 the GIQE 5 report assumes",
    ),
    "rer_nonpositive": (
        2048,
        "RER at or below zero (a system blurred over many pixels): the GIQE is undefined; "
        "NIIRS is NaN",
    ),
    "blur_unresolved": (
        4096,
        "the edge-response quadrature does not resolve the system OTF: its own error "
        "estimate (Kronrod minus Gauss on both slices, through the GIQE's sensitivity, plus "
        "the error of the OTF's wavelength bins where the method bins them) "
        "allows more NIIRS error than the method's edge_error_tolerance (rules without an "
        "estimate: RER of the worse slice below 0.05); the result may be wrong",
    ),
    "partial_spectral_coverage": (
        8192,
        "a spectral curve of the sensor (quantum efficiency, optics transmission or stray "
        "irradiance) covers only part of the band [wavelength_min, wavelength_max]; it is "
        "taken as zero over the rest",
    ),
    "grd_unresolved": (
        16384,
        "contrast SNR at or below 3 (or NaN): the MTF never reaches the 3/SNR threshold and "
        "no square wave is resolved; GRD is inf (NaN at SNR <= 0), or pyBSM's finite "
        "slant range x 1e12 with method='pybsm'",
    ),
    "upsampled": (
        32768,
        "simulated image more finely sampled than its reference image (the camera is "
        "better than the reference): it lacks detail the camera would record",
    ),
    "image_nonfinite": (
        65536,
        "NaN or infinite pixels in the reference image, set to the image's mean "
        "reflectance before blurring",
    ),
    "image_flat": (
        131072,
        "flat reference image: the percentile or min-max reflectance mapping is undefined; "
        "every pixel maps to the middle of the reflectance range",
    ),
    "image_small": (
        262144,
        "reference image smaller than the blur kernel or than one output pixel: the "
        "reflect padding folds the image over itself, borders are not a faithful simulation",
    ),
    "reference_unresolved": (
        524288,
        "the system OTF exceeds 0.05 at the reference image's Nyquist frequency: the "
        "reference does not resolve what the camera resolves (the simulation lacks detail)",
    ),
    "atmosphere_fallback": (
        1048576,
        "atmosphere_interpolation='same-elevation', 'optical-depth-cubic' or "
        "'extinction-profile' could not follow "
        "the line of sight to "
        "both bracketing altitude tables (horizon or end of a table's coverage): the "
        "atmosphere was interpolated at fixed ground range ('log-linear') instead",
    ),
    "no_thermal_signal": (
        2097152,
        "the target's photoelectrons do not grow with its temperature (zero emissivity, "
        "path transmission or response in the band): NETD, NER and NEI are infinite or NaN",
    ),
    "target_not_standard": (
        4194304,
        "the target is not GIQE's standard one (15% / 7% at 282 K / 280 K): the GIQE was "
        "fitted on imagery rated against that SNR convention, not on this target",
    ),
    "atmosphere_inconsistent": (
        8388608,
        f"altitude above {ALTITUDE_GAP[0] / 1e3:g} km: the database's only higher table "
        f"({ALTITUDE_GAP[1] / 1e3:g} km, nadir) is inconsistent with the {ALTITUDE_GAP[0] / 1e3:g} "
        "km one (GRND_RFLT 1.65-1.88x, SOL_SCAT 1.30-1.61x, TRANS within 1.5 %): "
        "radiometric results may be wrong (contrast SNR 16-22 % too high at 100 km and "
        "37-55 % at 549 km for a camera that does not fill its well)",
    ),
    "bars_unresolved": (
        16777216,
        "the system MTF across the bars is zero or NaN at this bar frequency (beyond the "
        "optics cutoff or at a zero of the OTF): the bars are not transmitted and the MRTD "
        "is infinite (NaN where the MTF is NaN)",
    ),
    "bars_aliased": (
        33554432,
        "bar frequency above the sampling Nyquist frequency 1 / (2 x sample spacing) across "
        "the bars: a sampled imager aliases the bars, and the MRTD formula, which ignores "
        "sampling, is not a threshold for resolving them",
    ),
    "no_reflective_signal": (
        67108864,
        "the scene gives no more photoelectrons than a black surface at its temperature "
        "(no reflected light in the band, or its own emission dominates): the "
        "noise-equivalent contrast and the MRC are infinite or NaN",
    ),
    "visibility_interpolated": (
        134217728,
        "visibility between two of the atmosphere database's visibilities: the spectra were "
        "interpolated in extinction (optical depth linear in 1/visibility, path radiances "
        "linear in the transmission lost) between the two bracketing visibility tables",
    ),
    "outside_acquisition_model": (
        268435456,
        "an input of the target-acquisition model lies outside its stated range (display "
        "luminance outside the photopic range of the eye models): P(task) is extrapolated",
    ),
})

INVALID = ("beyond_database", "undersampled_grid", "snr_nonpositive", "rer_nonpositive",
           "blur_unresolved", "grd_unresolved", "upsampled", "image_nonfinite", "image_small",
           "reference_unresolved", "no_thermal_signal", "atmosphere_inconsistent",
           "bars_unresolved", "bars_aliased", "no_reflective_signal")
"""Bits saying a number is NaN or may be wrong."""

CALIBRATION = (
    "snr_out_of_range",
    "rer_out_of_range",
    "gsd_out_of_range",
    "elevation_out_of_range",
    "q_out_of_range",
    "niirs_out_of_scale",
    "target_not_standard",
    "outside_acquisition_model",
)
"""Bits saying a number is outside a GIQE's calibration (or off the NIIRS scale), or
outside the stated range of the target-acquisition model."""

NOTICE = ("atmosphere_sparse", "well_fill_limited", "partial_spectral_coverage",
          "image_flat", "atmosphere_fallback", "visibility_interpolated")
"""Bits that are neither: information about how a number was obtained."""

INVALID_MASK = sum(FLAGS[name][0] for name in INVALID)
"""OR of the :data:`INVALID` bits (128834177)."""

CALIBRATION_MASK = sum(FLAGS[name][0] for name in CALIBRATION)
"""OR of the :data:`CALIBRATION` bits (272631160)."""


def flag(name: str) -> int:
    """Return the bit of the flag called ``name``."""
    return FLAGS[name][0]


def flag_attrs(long_name: str = "validity flags") -> dict:
    """CF attributes for an integer flag variable using every known bit."""
    return {
        "long_name": long_name,
        "units": "1",
        "flag_masks": _FLAG_MASKS.copy(),  # each result its own array: a user may edit it
        "flag_meanings": _FLAG_MEANINGS,
        "invalid_mask": np.int32(INVALID_MASK),
        "calibration_mask": np.int32(CALIBRATION_MASK),
    }


# the table's CF form, built once (10 us a result, 1 % of a single snr call)
_FLAG_MASKS = np.array([mask for mask, _ in FLAGS.values()], dtype=np.int32)
_FLAG_MASKS.flags.writeable = False
_FLAG_MEANINGS = " ".join(FLAGS)


def set_flag(flags: xr.DataArray, name: str, condition: xr.DataArray) -> xr.DataArray:
    """Return ``flags`` with bit ``name`` set wherever ``condition`` holds."""
    out = apply_kernel(_set_bit, condition, flags, bit=np.int32(flag(name)), dtype=np.int32)
    out.attrs = flag_attrs()
    return out


def _set_bit(condition, flags, *, bit):
    """``flags`` with ``bit`` set where ``condition`` (numpy kernel; xr.where's dim order)."""
    return np.where(condition, flags | bit, flags).astype(np.int32)


def empty_flags(like: xr.DataArray | None = None) -> xr.DataArray:
    """A flag variable with no bit set, broadcast like ``like`` (or a scalar)."""
    if like is None:
        out = xr.DataArray(np.int32(0))
    else:
        out = xr.zeros_like(like, dtype=np.int32)
    return out.assign_attrs(flag_attrs())


def has_flag(flags: xr.DataArray, name: str) -> xr.DataArray:
    """Boolean DataArray: where the bit ``name`` is set."""
    return (flags & np.int32(flag(name))) != 0


def is_invalid(flags: xr.DataArray) -> xr.DataArray:
    """Boolean DataArray: where any :data:`INVALID` bit is set (NaN or possibly wrong)."""
    return (flags & np.int32(INVALID_MASK)) != 0


def is_outside_calibration(flags: xr.DataArray) -> xr.DataArray:
    """Boolean DataArray: where any :data:`CALIBRATION` bit is set (the GIQE is extrapolated)."""
    return (flags & np.int32(CALIBRATION_MASK)) != 0


def decode(flags: xr.DataArray) -> xr.Dataset:
    """One boolean variable per flag meaning: where that bit of ``flags`` is set.

    The bits are read from the variable's own CF attributes, ``flag_masks``
    and ``flag_meanings``, so every flag variable xbsm writes decodes by its
    own table: the model's ``flags`` (the bits of :data:`FLAGS`), ``goal_flags``
    of :func:`xbsm.study.max_range` and :func:`~xbsm.study.min_parameter`,
    ``grd_flags``, ``mtf_flags`` and the flags of image simulation, also when
    read back from NetCDF.

    Parameters
    ----------
    flags : xr.DataArray
        An integer flag variable with ``flag_masks`` and ``flag_meanings``
        attributes (any dims; dask stays lazy). To decode bare integers as the
        model's bits, give them the model's attributes first:
        ``values.assign_attrs(xbsm.flags.flag_attrs())``.

    Returns
    -------
    xr.Dataset
        A boolean variable for every meaning of ``flag_meanings``, on the dims
        of ``flags``. For the model's bits, also ``invalid`` and
        ``outside_calibration`` (any bit of :data:`INVALID` /
        :data:`CALIBRATION`).

    Raises
    ------
    ValueError
        If ``flags`` has no ``flag_masks`` and ``flag_meanings`` (nothing says
        what its bits mean), or they do not pair up one to one.

    Examples
    --------
    >>> import xarray as xr
    >>> raw = xr.DataArray([0, 4 | 512], dims="case").assign_attrs(flag_attrs())
    >>> bits = decode(raw)
    >>> bits.snr_nonpositive.values.tolist(), bits.invalid.values.tolist()
    ([False, True], [False, True])
    """
    meanings, masks = _flag_table(flags)
    described = {}
    for name, mask in zip(meanings, masks, strict=True):
        known = FLAGS.get(name)
        text = known[1] if known is not None and known[0] == mask else name.replace("_", " ")
        described[name] = ((flags & np.int64(mask)) != 0, text)
    if all(FLAGS.get(name, (None,))[0] == mask for name, mask in zip(meanings, masks,
                                                                      strict=True)):
        # the model's own bits (all of them, or a subset): the groups are defined too
        if "invalid" not in described:
            described["invalid"] = (
                is_invalid(flags), "any bit saying the number is NaN or may be wrong")
        if "outside_calibration" not in described:
            described["outside_calibration"] = (
                is_outside_calibration(flags),
                "any bit saying a GIQE is used outside its calibration")
    return xr.Dataset({name: value.assign_attrs(long_name=text, units="1")
                       for name, (value, text) in described.items()})


def _flag_table(flags: xr.DataArray) -> tuple[list, list]:
    """The (meanings, masks) a flag variable declares in its CF attributes, checked."""
    if not isinstance(flags, xr.DataArray):
        raise ValueError(f"flags must be an xarray DataArray; got {type(flags).__name__}")
    attrs = flags.attrs
    name = f"{flags.name!r}" if flags.name is not None else "the variable"
    if "flag_masks" not in attrs or "flag_meanings" not in attrs:
        raise ValueError(
            f"{name} has no CF flag_masks and flag_meanings attributes, so nothing says what "
            "its bits mean; pass a flag variable of an xbsm result (or of its NetCDF file), "
            "or give bare integers the model's table first: "
            "values.assign_attrs(xbsm.flags.flag_attrs())")
    meanings = str(attrs["flag_meanings"]).split()
    masks = [int(m) for m in np.atleast_1d(np.asarray(attrs["flag_masks"]))]
    if len(meanings) != len(masks) or not meanings:
        raise ValueError(f"{name} has {len(masks)} flag_masks but {len(meanings)} "
                         "flag_meanings; CF pairs them one to one")
    return meanings, masks
