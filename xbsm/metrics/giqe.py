r"""NIIRS from the General Image Quality Equation, versions 3, 4 and 5.

Each version has a calibration (:class:`GiqeCalibration`): the ranges of SNR,
RER, GSD, elevation (and for GIQE 5 the ground-plane GSD and the sampling
ratio Q) over which it was fitted or validated. The GIQE functions return the
prediction with flags (:mod:`xbsm.flags`) set where an input or the prediction
is outside the version's calibration. RER and EHO come from
:mod:`xbsm.metrics.edge`.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import xarray as xr

from xbsm import flags as _flags

from .._kernels import apply_kernel, apply_orchestrator, dataset
from .._metadata import Output, named, outputs
from ..params import Instance, Pair, Spec, contract

__all__ = [
    "GIQE_VERSIONS",
    "giqe_by_version",
    "GIQE3_CALIBRATION",
    "GIQE4_CALIBRATION",
    "GIQE5_CALIBRATION",
    "GIQE_CALIBRATIONS",
    "GIQE_REFERENCES",
    "INCH",
    "GiqeCalibration",
    "giqe3",
    "giqe4",
    "giqe5",
    "giqe5_rer",
    "giqe_calibrations",
    "giqe_flags",
    "sampling_q",
]

INCH = 0.0254
"""One inch, the GSD unit inside every GIQE. [m]"""

GIQE_REFERENCES = MappingProxyType({
    3: "IBSM Eq. 3-56",
    4: "Leachtenauer et al., Applied Optics 36(32):8322, 1997",
    5: "Harrington et al., NGA, General Image Quality Equation (GIQE) Version 5.0, 2015, Eq. 2",
})
"""The published source of each GIQE version's equation, by version (read-only): the
``references`` attribute of its ``niirs``."""


_GSD_W_REFERENCE = "Harrington et al., NGA GIQE 5.0, 2015, Eq. 5"
_RER5_REFERENCE = "Harrington et al., NGA GIQE 5.0, 2015, Eq. 7"


def _da(x):
    return x if isinstance(x, xr.DataArray) else xr.DataArray(x)


@dataclass(frozen=True)
class GiqeCalibration:
    """Ranges of the image attributes over which one GIQE version was fitted or validated.

    Every range is a ``(low, high)`` pair, inclusive, or ``None`` (not tested).
    A value outside its range, or NaN, sets the matching bit of
    :data:`xbsm.flags.CALIBRATION`. A range is tested only where the GIQE
    function is given the quantity (:func:`xbsm.niirs` gives them all).

    Attributes
    ----------
    snr : tuple of float or None
        Contrast SNR range. [1]
    rer : tuple of float or None
        RER range (the RER the equation uses: the geometric mean for GIQE 3
        and 4, the weighted RER of :func:`giqe5_rer` for GIQE 5). [1]
    gsd : tuple of float or None
        GSD range (the GSD the equation uses: ``gsd`` for GIQE 3, ground-plane
        ``gsd_gp`` for GIQE 4, elevation-weighted ``gsd_w`` for GIQE 5). [m]
    elevation : tuple of float or None
        Elevation-angle range, within [0, pi/2]. [rad]
    niirs : tuple of float or None
        Range of the prediction. [1]
    source : str
        Where the numbers come from (a summary; docs/flags.md has each limit).
    gsd_ground_plane : tuple of float or None
        Ground-plane GSD range, GSD / sqrt(sin(elevation)) (GIQE 5 only:
        GIQE 4's ``gsd`` already is ground-plane). [m]
    q : tuple of float or None
        Range of the sampling ratio Q = lambda N / p (:func:`sampling_q`;
        GIQE 5 only). [1]

    Notes
    -----
    Instances are immutable; derive a variant with :meth:`replace`, e.g.
    ``GIQE5_CALIBRATION.replace(snr=(4.1, np.inf))``. Invalid ranges raise
    a ``ValueError`` naming the field.
    """

    snr: tuple | None
    rer: tuple | None
    gsd: tuple | None
    elevation: tuple | None
    niirs: tuple | None = (0.0, 10.0)
    source: str = ""
    gsd_ground_plane: tuple | None = None
    q: tuple | None = None

    def __post_init__(self):
        for name, rule in RANGE_RULES.items():
            object.__setattr__(self, name, rule.check(name, getattr(self, name)))
        if not isinstance(self.source, str):
            raise ValueError(f"source must be a str; got {type(self.source).__name__}")

    def replace(self, **changes) -> GiqeCalibration:
        """A copy with some ranges changed (validated like the constructor)."""
        unknown = sorted(set(changes) - set(RANGE_RULES) - {"source"})
        if unknown:
            raise ValueError(
                f"unknown GiqeCalibration field(s) {unknown}; fields are "
                f"{', '.join(RANGE_RULES)}, source"
            )
        return dataclasses.replace(self, **changes)


#: The declared rule of each calibration range (params words): None, or a (low, high) pair
#: with low <= high inside the quantity's own interval (the elevation in radians, up to
#: pi/2 and its rounding).
RANGE_RULES = MappingProxyType({
    name: Pair(spec, equal=True, optional=True) for name, spec in {
        "snr": Spec("1", "contrast SNR", low=0.0),
        "rer": Spec("1", "relative edge response", low=0.0),
        "gsd": Spec("m", "ground sample distance", low=0.0),
        "elevation": Spec("rad", "elevation angle", 0.0, np.pi / 2 + 1e-12),
        "niirs": Spec("1", "NIIRS"),
        "gsd_ground_plane": Spec("m", "ground-plane GSD", low=0.0),
        "q": Spec("1", "sampling ratio Q", low=0.0),
    }.items()})


# Each limit below has its source on the line before it. "Unverified" means
# the number is not traced to a primary source; docs/flags.md says so too.
#
# GIQE 4 (Leachtenauer et al., Appl. Opt. 36(32), 8322, 1997).
GIQE4_CALIBRATION = GiqeCalibration(
    # SNR 2-130, RER 0.2-1.3, GSD 3-80 in: the GIQE 4 development ranges as
    # widely quoted (e.g. Fiete 2010). UNVERIFIED against the 1997 paper
    # itself (its abstract gives no ranges).
    snr=(2.0, 130.0),
    rer=(0.2, 1.3),
    gsd=(3 * INCH, 80 * INCH),
    # 25-90 deg: NGA, "General Image Quality Equation (GIQE) Version 5.0"
    # (Harrington et al., 16 Sep 2015), its summary of GIQE 4: fitted on images
    # at elevations 25-90 deg.
    elevation=(np.deg2rad(25.0), np.pi / 2),
    # 0-10: the NIIRS rating scale as xbsm words it (not a fitted range).
    niirs=(0.0, 10.0),
    source="SNR/RER/GSD: Leachtenauer et al. 1997 as quoted (unverified); "
    "elevation: NGA GIQE 5 report 2015 (GIQE 4 fitted at 25-90 deg)",
)

# GIQE 3 (IBSM Eq. 3-56). No published GIQE 3 range is known.
GIQE3_CALIBRATION = GiqeCalibration(
    # GIQE 4's SNR, RER and GSD ranges reused. UNVERIFIED for GIQE 3.
    snr=GIQE4_CALIBRATION.snr,
    rer=GIQE4_CALIBRATION.rer,
    gsd=GIQE4_CALIBRATION.gsd,
    # Not tested: GIQE 3 has no elevation term and no published elevation range
    # (set one with .replace(elevation=...) if wanted).
    elevation=None,
    niirs=(0.0, 10.0),
    source="GIQE 4 SNR/RER/GSD ranges reused (unverified: no published GIQE 3 range "
    "found); elevation not tested",
)

# GIQE 5: NGA, "General Image Quality Equation (GIQE) Version 5.0", Harrington,
# Blanchard, Salacain, Smith, Amanik, 16 Sep 2015 (public release; a copy is in
# the Kitware/pybsm repository, docs/GIQE-5_for_Public_Release.pdf).
GIQE5_CALIBRATION = GiqeCalibration(
    # SNR 4.1-26.7: span of the report's validation data (it adds that SNR
    # below 5 "should be used with caution").
    snr=(4.1, 26.7),
    # RER 0.31-0.54: span of the validation data (RER as the equation uses it).
    rer=(0.31, 0.54),
    # GSD_W 3.3-34.4 in: span of the validation data (elevation-weighted GSD).
    gsd=(3.3 * INCH, 34.4 * INCH),
    # 8.5-90 deg: the report's conclusions (its validation data span 8.9-87.3).
    elevation=(np.deg2rad(8.5), np.pi / 2),
    # 0-10: the NIIRS rating scale as xbsm words it (not a fitted range).
    niirs=(0.0, 10.0),
    source="NGA GIQE 5 report (Harrington et al. 2015): validation-data spans, "
    "elevation from its conclusions, Q from its sampling assumption",
    # Ground-plane GSD 3.3-55.3 in: span of the validation data.
    gsd_ground_plane=(3.3 * INCH, 55.3 * INCH),
    # Q 1-2: the report assumes 1 <= Q <= 2; Q > 2 is "a pure extrapolation".
    q=(1.0, 2.0),
)

GIQE_CALIBRATIONS = MappingProxyType(
    {3: GIQE3_CALIBRATION, 4: GIQE4_CALIBRATION, 5: GIQE5_CALIBRATION}
)
"""The default calibration of each GIQE version, by version (read-only)."""


def giqe_calibrations(calibration=None):
    """Complete and validate a per-version calibration table.

    Parameters
    ----------
    calibration : mapping of int to GiqeCalibration, optional
        Calibrations for some of the GIQE versions 3, 4 and 5; the versions
        left out keep :data:`GIQE_CALIBRATIONS`.

    Returns
    -------
    types.MappingProxyType
        A read-only ``{3: ..., 4: ..., 5: ...}``.
    """
    if calibration is None:
        return GIQE_CALIBRATIONS
    form = ("calibration must be a mapping from GIQE version (3, 4 or 5) to "
            "xbsm.metrics.GiqeCalibration, e.g. {5: GIQE5_CALIBRATION.replace(snr=(2, 130))}")
    if not isinstance(calibration, Mapping):
        raise ValueError(f"{form}; got {type(calibration).__name__}")
    out = dict(GIQE_CALIBRATIONS)
    for version, cal in calibration.items():
        if version not in GIQE_CALIBRATIONS:
            raise ValueError(f"{form}; got version {version!r}")
        if not isinstance(cal, GiqeCalibration):
            raise ValueError(f"{form}; got {type(cal).__name__} for version {version}")
        if version != 5 and (cal.q is not None or cal.gsd_ground_plane is not None):
            raise ValueError(
                f"calibration[{version}]: q and gsd_ground_plane apply to GIQE 5 only; "
                f"they must be None for GIQE {version}"
            )
        out[version] = cal
    return MappingProxyType(out)


_CALIBRATION = Instance(GiqeCalibration, "an xbsm.metrics.GiqeCalibration (e.g. "
                        "GIQE5_CALIBRATION.replace(...))")


# ---------------------------------------------------------------------------- kernels
# Plain NumPy in and out, no checks, no xarray: the arithmetic of every GIQE function runs
# here once per call, over arrays that ``xr.apply_ufunc`` has aligned and broadcast; the
# public functions below only label the results (and carry dask). Like xarray's arithmetic,
# the kernels give IEEE results (inf, NaN) without floating-point warnings; NaN marks what
# the flags report.


def _sampling_q_kernel(wavelength, aperture_diameter, ifov):
    with np.errstate(all="ignore"):
        return wavelength / (aperture_diameter * ifov)


def _geometric_mean_kernel(a, b):
    with np.errstate(all="ignore"):
        return np.sqrt(a * b)


def _ground_plane_kernel(gsd, elevation, power):
    """GSD / sin(elevation)^power; NaN where sin(elevation) <= 0."""
    return _over_sine(gsd, np.sin(elevation), power)


def _over_sine(gsd, sin_el, power):
    """:func:`_ground_plane_kernel` from the sine of the elevation."""
    with np.errstate(all="ignore"):
        out = gsd / (sin_el**power)
    return np.where(sin_el > 0, out, np.nan)


def _giqe3_kernel(rer, gsd, eho, noise_gain, snr):
    with np.errstate(all="ignore"):
        # log10(RER) - log10(GSD) rather than log10(RER / GSD): no underflow for tiny RER
        niirs = (
            11.81 + 3.32 * (np.log10(rer) - np.log10(gsd / INCH)) - 1.48 * eho - noise_gain / snr
        )
    return np.where((snr > 0) & (rer > 0) & (gsd > 0) & np.isfinite(niirs), niirs, np.nan)


def _giqe4_kernel(rer, gsd, elevation, eho, noise_gain, snr, noise_coefficient):
    sin_el = np.sin(elevation)
    return _giqe4_on_ground(rer, gsd, sin_el, _over_sine(gsd, sin_el, 0.5), eho, noise_gain,
                            snr, noise_coefficient)


def _giqe4_on_ground(rer, gsd, sin_el, gsd_gp, eho, noise_gain, snr, noise_coefficient):
    """:func:`_giqe4_kernel` from the sine of the elevation and the ground-plane GSD."""
    c1 = np.where(rer >= 0.9, 3.32, 3.16)
    c2 = np.where(rer >= 0.9, 1.559, 2.817)
    with np.errstate(all="ignore"):
        niirs = (
            10.251
            - c1 * np.log10(gsd_gp / INCH)
            + c2 * np.log10(rer)
            - 0.656 * eho
            - noise_coefficient * noise_gain / snr
        )
    keep = (snr > 0) & (rer > 0) & (gsd > 0) & (sin_el > 0) & np.isfinite(niirs)
    return np.where(keep, niirs, np.nan)


def _giqe5_rer_kernel(rer_x, rer_y):
    hi, lo = np.maximum(rer_x, rer_y), np.minimum(rer_x, rer_y)
    with np.errstate(all="ignore"):
        rer = (hi * lo**2.0) ** (1.0 / 3.0)
    # squaring the poorer slice would hide its sign: a slice at or below zero (or NaN)
    # leaves GIQE 5 undefined, as it does GIQE 3 and 4's geometric mean
    return np.where(lo > 0, rer, np.nan)


def _giqe5_kernel(gsd, elevation, snr, rer_x, rer_y):
    sin_el = np.sin(elevation)
    return _giqe5_on_ground(gsd, sin_el, _over_sine(gsd, sin_el, 0.25), snr,
                            _giqe5_rer_kernel(rer_x, rer_y))


def _giqe5_on_ground(gsd, sin_el, gsd_w, snr, rer):
    """:func:`_giqe5_kernel` from the sine of the elevation, GIQE 5's GSD and RER."""
    with np.errstate(all="ignore"):
        log_rer = np.log10(rer)
        niirs = (
            9.57
            - 3.32 * np.log10(gsd_w / INCH)
            + 3.32 * (1 - np.exp(-1.9 / snr)) * log_rer
            - 2.0 * log_rer**4.0
            - 1.8 / snr
        )
    keep = (snr > 0) & (rer > 0) & (gsd > 0) & (sin_el > 0) & np.isfinite(niirs)
    return np.where(keep, niirs, np.nan)


def _giqe_terms(gsd_x, gsd_y, elevation, rer_x, rer_y) -> dict:
    """What the three GIQEs share: the elevation's sine, the GSDs and GIQE 5's RER."""
    sin_el = np.sin(elevation)
    gsd = _geometric_mean_kernel(gsd_x, gsd_y)
    return {"sin_el": sin_el, "gsd": gsd, "gsd_gp": _over_sine(gsd, sin_el, 0.5),
            "gsd_w": _over_sine(gsd_x, sin_el, 0.25), "rer5": _giqe5_rer_kernel(rer_x, rer_y)}


def _niirs_of_terms(t, rer, gsd_x, eho, noise_gain, snr, noise_coefficient):
    """NIIRS by GIQE 3, 4 and 5 along a new last axis, from :func:`_giqe_terms`.

    GIQE 5 on ``gsd_x``, as pyBSM's niirs5.
    """
    niirs3 = _giqe3_kernel(rer, t["gsd"], eho, noise_gain, snr)
    niirs4 = _giqe4_on_ground(rer, t["gsd"], t["sin_el"], t["gsd_gp"], eho, noise_gain, snr,
                              noise_coefficient)
    niirs5 = _giqe5_on_ground(gsd_x, t["sin_el"], t["gsd_w"], snr, t["rer5"])
    return np.stack(np.broadcast_arrays(niirs3, niirs4, niirs5), axis=-1)


def _condition(kind, value, lo, hi):
    """Where ``value`` fails one calibration test (NaN fails every test but "nonpositive")."""
    if kind == "nonpositive":
        return value <= 0
    if kind == "not_positive":
        return ~(value > 0)
    outside = ~((value >= lo) & (value <= hi))
    return outside.any(axis=-1) if kind == "any_outside" else outside  # any: over orientation


def _flags_kernel(*arrays, tests, versions):
    """int32 flag bits of one or more GIQE versions.

    ``tests`` holds one ``(version, bit, kind, lo, hi, array index, column)`` per test (kind
    as in :func:`_condition`; ``column`` picks that version's NIIRS from a last axis);
    ``versions`` is None for one result, else the number of versions along a new last axis.
    """
    bits = [np.int32(0)] * (versions or 1)

    def tested(index, column):
        return arrays[index] if column is None else arrays[index][..., column]

    # the tests of a value (not over orientations) all at once, on the values broadcast
    # together along a new first axis: a test at a time cost six small numpy calls (22
    # tests: 250 us of a single niirs call, 90 us this way)
    plain = tuple(t for t in tests if t[2] != "any_outside")
    if plain:
        values = np.array(np.broadcast_arrays(*(tested(*t[5:]) for t in plain)))
        along = (len(plain),) + (1,) * (values.ndim - 1)
        fields, by_version = _plain_tests(plain, len(bits))
        low, high, nonpositive, not_positive, bit = (f.reshape(along) for f in fields)
        hit = np.where(nonpositive, _condition("nonpositive", values, low, high),
                       np.where(not_positive, _condition("not_positive", values, low, high),
                                _condition("outside", values, low, high)))
        flagged = np.where(hit, bit, np.int32(0))
        for version, mine in enumerate(by_version):
            if mine:
                bits[version] = bits[version] | np.bitwise_or.reduce(flagged[mine], axis=0)
    for version, bit, kind, lo, hi, index, column in tests:
        if kind == "any_outside":
            hit = _condition(kind, tested(index, column), lo, hi)
            bits[version] = bits[version] | np.where(hit, np.int32(bit), np.int32(0))
    if versions is None:
        return bits[0]
    return np.stack(np.broadcast_arrays(*bits), axis=-1)


@functools.lru_cache(maxsize=64)
def _plain_tests(plain: tuple, n_versions: int) -> tuple:
    """:func:`_flags_kernel`'s tests of a value as arrays along the tests, built once.

    Returns ((low, high, nonpositive, not_positive, bit), and for each version the indices
    of its tests); the arrays are read-only (shared by every call with these tests).
    """
    fields = (np.array([t[3] for t in plain]), np.array([t[4] for t in plain]),
              np.array([t[2] == "nonpositive" for t in plain]),
              np.array([t[2] == "not_positive" for t in plain]),
              np.array([t[1] for t in plain], dtype=np.int32))
    for field in fields:
        field.flags.writeable = False
    by_version = tuple([j for j, t in enumerate(plain) if t[0] == version]
                       for version in range(n_versions))
    return fields, by_version


# ---------------------------------------------------------------- the xarray layer




def _dims_in_order(*dims):
    """Dimension names in order of first appearance (the order xarray broadcasting gives)."""
    return tuple(dict.fromkeys(d for group in dims for d in group))


def _version_tests(calibration, values, version=0, niirs_column=None, q_per_orientation=None):
    """The arrays one GIQE version's flags test, and the tests, in :func:`giqe_flags`'s order.

    ``values`` maps snr, rer, gsd, gsd_ground_plane, elevation, q and niirs to DataArrays
    (or None: not tested). ``q`` is tested over its orientations (any outside) when it has
    an ``orientation`` dim, or when ``q_per_orientation`` says so for a plain array.
    Returns (arrays, tests) with tests as :func:`_flags_kernel` takes them, the array
    index standing for an entry of ``arrays``.
    """
    checks = [("snr_nonpositive", "snr", "nonpositive", (0.0, 0.0)),
              ("rer_nonpositive", "rer", "not_positive", (0.0, 0.0))]
    for name, key in (("snr_out_of_range", "snr"), ("rer_out_of_range", "rer"),
                      ("gsd_out_of_range", "gsd"), ("gsd_out_of_range", "gsd_ground_plane"),
                      ("elevation_out_of_range", "elevation"), ("q_out_of_range", "q"),
                      ("niirs_out_of_scale", "niirs")):
        lo_hi = getattr(calibration, key)
        if values.get(key) is not None and lo_hi is not None:
            per_orientation = (q_per_orientation if q_per_orientation is not None
                               else "orientation" in getattr(values[key], "dims", ()))
            kind = "any_outside" if key == "q" and per_orientation else "outside"
            checks.append((name, key, kind, lo_hi))
    arrays, tests = [], []
    for name, key, kind, (lo, hi) in checks:
        arrays.append(values[key])
        column = niirs_column if key == "niirs" else None
        tests.append((version, _flags.flag(name), kind, lo, hi, len(arrays) - 1, column))
    return arrays, tests


def _label_flags(arrays, tests, versions=None, long_name="GIQE validity flags"):
    """One ``apply_ufunc`` of :func:`_flags_kernel` over the tested arrays (each passed once)."""
    unique, where = [], {}
    for array in arrays:
        where.setdefault(id(array), len(unique))
        if where[id(array)] == len(unique):
            unique.append(array)
    tests = tuple((*t[:5], where[id(arrays[t[5]])], t[6]) for t in tests)
    core = [[] for _ in unique]
    for _, _, kind, _, _, index, column in tests:
        core[index] = (["orientation"] if kind == "any_outside"
                       else ["giqe"] if column is not None else [])
    out = apply_kernel(_flags_kernel, *unique, core=core, outputs=[("giqe",) if versions else ()],
                       sizes={"giqe": versions} if versions else None, dtype=np.int32,
                       tests=tests, versions=versions)
    out.attrs = _flags.flag_attrs(long_name)
    return out


_Q_OUTPUTS = outputs(Output("q", "1", "sampling ratio Q = lambda N / p"))
"""What :func:`sampling_q_arrays` returns."""


@contract(_Q_OUTPUTS["q"])
def sampling_q(wavelength, aperture_diameter, ifov):
    r"""Sampling ratio Q of an optics and detector: wavelength x f-number / pixel pitch.

    Parameters
    ----------
    wavelength : float or xr.DataArray
        Wavelength (for a band, the GIQE 5 flag uses the band centre). [m]
    aperture_diameter : float or xr.DataArray
        Entrance-pupil diameter. [m]
    ifov : float or xr.DataArray
        Instantaneous field of view of one pixel, pitch / focal length. [rad]

    Returns
    -------
    xr.DataArray
        Q. [1]

    Notes
    -----
    .. math:: Q = \frac{\lambda N}{p} = \frac{\lambda}{D\,\mathrm{IFOV}}

    NGA GIQE 5 report (2015), which assumes 1 <= Q <= 2.
    """
    return apply_orchestrator(sampling_q_arrays, _Q_OUTPUTS, wavelength, aperture_diameter,
                              ifov)["q"]


@contract(calibration=_CALIBRATION)
def giqe_flags(*, snr, rer, gsd, elevation=None, niirs=None, calibration=GIQE4_CALIBRATION,
               gsd_ground_plane=None, q=None):
    """Flag GIQE inputs and predictions outside a calibration.

    Parameters
    ----------
    snr : float or xr.DataArray
        Contrast SNR. [1]
    rer : float or xr.DataArray
        RER as used by the equation. [1]
    gsd : float or xr.DataArray
        GSD as used by the equation. [m]
    elevation : float or xr.DataArray, optional
        Elevation angle. [rad]
    niirs : float or xr.DataArray, optional
        The prediction. [1]
    calibration : GiqeCalibration
        Ranges to test against (default: GIQE 4's).
    gsd_ground_plane : float or xr.DataArray, optional
        Ground-plane GSD. [m]
    q : float or xr.DataArray, optional
        Sampling ratio Q. With an ``orientation`` dimension, a cell is flagged
        where any orientation is outside. [1]

    Returns
    -------
    xr.DataArray
        int32 bits from :mod:`xbsm.flags`: ``snr_out_of_range``,
        ``rer_out_of_range``, ``gsd_out_of_range`` (``gsd`` or
        ``gsd_ground_plane``), ``elevation_out_of_range``,
        ``q_out_of_range``, ``niirs_out_of_scale`` (all in
        :data:`xbsm.flags.CALIBRATION`) and ``snr_nonpositive`` (in
        :data:`xbsm.flags.INVALID`). NaN inputs count as out of range. A
        range that is ``None`` in ``calibration``, or whose quantity is not
        given, is not tested.
    """
    values = {"snr": snr, "rer": rer, "gsd": gsd, "gsd_ground_plane": gsd_ground_plane,
              "elevation": elevation, "q": q, "niirs": niirs}
    values = {key: None if value is None else _da(value) for key, value in values.items()}
    return _label_flags(*_version_tests(calibration, values))


@contract(calibration=_CALIBRATION)
def giqe3(*, rer, gsd, eho, snr, noise_gain=1.0, calibration=GIQE3_CALIBRATION,
          elevation=None):
    r"""NIIRS from the General Image Quality Equation version 3.

    Parameters
    ----------
    rer : float or xr.DataArray
        Geometric-mean relative edge response. [1]
    gsd : float or xr.DataArray
        Geometric-mean ground sample distance. [m]
    eho : float or xr.DataArray
        Geometric-mean edge height overshoot. [1]
    snr : float or xr.DataArray
        Contrast signal-to-noise ratio. [1]
    noise_gain : float or xr.DataArray, optional
        Noise gain G of the sharpening kernel (1 without sharpening). [1]
    calibration : GiqeCalibration, optional
        Ranges used for the flags (default :data:`GIQE3_CALIBRATION`).
    elevation : float or xr.DataArray, optional
        Elevation angle, used only for the flags (GIQE 3 has no elevation
        term; the default calibration does not test it). [rad]

    Returns
    -------
    xr.Dataset
        ``niirs`` [1] (NaN where SNR <= 0, RER <= 0 or GSD <= 0) and
        ``flags``.

    Notes
    -----
    IBSM Eq. 3-56 (paper Eq. 4), GSD in inches:

    .. math::

        NIIRS = 11.81 + 3.32\log_{10}\frac{RER}{GSD} - 1.48\,EHO - \frac{G}{SNR}
    """
    rer, gsd, eho, snr, noise_gain = map(_da, (rer, gsd, eho, snr, noise_gain))
    niirs = named(apply_kernel(_giqe3_kernel, rer, gsd, eho, noise_gain, snr), "1",
                  "NIIRS (GIQE 3)", references=GIQE_REFERENCES[3])
    values = {"snr": snr, "rer": rer, "gsd": gsd, "niirs": niirs,
              "elevation": None if elevation is None else _da(elevation)}
    return dataset({"niirs": niirs, "flags": _label_flags(*_version_tests(calibration, values))})


@contract(calibration=_CALIBRATION)
def giqe4(
    *,
    rer,
    gsd,
    eho,
    snr,
    elevation,
    noise_gain=1.0,
    noise_coefficient=0.344,
    calibration=GIQE4_CALIBRATION,
):
    r"""NIIRS from the General Image Quality Equation version 4.

    Parameters
    ----------
    rer : float or xr.DataArray
        Geometric-mean relative edge response. [1]
    gsd : float or xr.DataArray
        Geometric-mean image-plane ground sample distance. [m]
    eho : float or xr.DataArray
        Geometric-mean edge height overshoot. [1]
    snr : float or xr.DataArray
        Contrast signal-to-noise ratio. [1]
    elevation : float or xr.DataArray
        Elevation angle of the sensor seen from the target. [rad]
    noise_gain : float or xr.DataArray, optional
        Noise gain G. [1]
    noise_coefficient : float, optional
        Coefficient of G/SNR: 0.344 in Leachtenauer et al. (1997); pyBSM
        0.16.1 uses 0.334. [1]
    calibration : GiqeCalibration, optional
        Ranges used for the flags, GSD tested on ``gsd_gp`` (default
        :data:`GIQE4_CALIBRATION`).

    Returns
    -------
    xr.Dataset
        ``niirs`` [1], ``gsd_gp`` [m] and ``flags``. NIIRS is NaN where SNR,
        RER, GSD or sin(elevation) is not positive.

    Notes
    -----
    Leachtenauer et al., Appl. Opt. 36(32), 8322 (1997), GSD in inches:

    .. math::

        GSD_{gp} = GSD / \sqrt{\sin\epsilon}

        NIIRS = 10.251 - a\log_{10}GSD_{gp} + b\log_{10}RER - 0.656\,H
                - c\,G/SNR

    with (a, b) = (3.32, 1.559) for RER >= 0.9 and (3.16, 2.817) otherwise
    (a 0.11 NIIRS step at RER = 0.9 is part of the published fit).
    """
    rer, gsd, eho, snr, elevation, noise_gain = map(
        _da, (rer, gsd, eho, snr, elevation, noise_gain)
    )
    gsd_gp = named(apply_kernel(_ground_plane_kernel, gsd, elevation, power=0.5), "m",
                   "ground-plane geometric-mean GSD", references=GIQE_REFERENCES[4])
    niirs = named(apply_kernel(_giqe4_kernel, rer, gsd, elevation, eho, noise_gain, snr,
                         noise_coefficient=noise_coefficient),
                  "1", "NIIRS (GIQE 4)", references=GIQE_REFERENCES[4])
    values = {"snr": snr, "rer": rer, "gsd": gsd_gp, "elevation": elevation, "niirs": niirs}
    fl = _label_flags(*_version_tests(calibration, values))
    return dataset({"niirs": niirs, "gsd_gp": gsd_gp, "flags": fl})


@contract(Output("rer_giqe5", "1", "GIQE 5 weighted relative edge response",
                 references=_RER5_REFERENCE))
def giqe5_rer(rer_x, rer_y):
    r"""GIQE 5 combined RER of two orthogonal axes.

    Parameters
    ----------
    rer_x, rer_y : float or xr.DataArray
        RER along the two image axes. [1]

    Returns
    -------
    xr.DataArray
        Combined RER; NaN where either slice is not positive (squaring the poorer
        slice would otherwise hide its sign). [1]

    Notes
    -----
    NGA GIQE 5 (2015), weighting the poorer axis twice:

    .. math:: RER = \left(\max(R_x, R_y)\,\min(R_x, R_y)^2\right)^{1/3}
    """
    return apply_kernel(_giqe5_rer_kernel, _da(rer_x), _da(rer_y))


@contract(calibration=_CALIBRATION)
def giqe5(*, rer_x, rer_y, gsd, snr, elevation, calibration=GIQE5_CALIBRATION, q=None):
    r"""NIIRS from the NGA General Image Quality Equation version 5.

    Parameters
    ----------
    rer_x, rer_y : float or xr.DataArray
        RER along the two image axes (e.g. along- and cross-scan). [1]
    gsd : float or xr.DataArray
        Image-plane ground sample distance. [m]
    snr : float or xr.DataArray
        Contrast signal-to-noise ratio. [1]
    elevation : float or xr.DataArray
        Elevation angle of the sensor seen from the target. [rad]
    calibration : GiqeCalibration, optional
        Ranges used for the flags, tested on ``rer``, ``gsd_w`` and the
        ground-plane GSD / sqrt(sin(elevation)) (default
        :data:`GIQE5_CALIBRATION`).
    q : float or xr.DataArray, optional
        Sampling ratio Q = lambda N / p (:func:`sampling_q`), used only for
        the ``q_out_of_range`` flag; not tested when omitted. With an
        ``orientation`` dimension, flagged where any orientation is outside. [1]

    Returns
    -------
    xr.Dataset
        ``niirs`` [1], ``gsd_w`` [m], ``rer`` [1] and ``flags``. NIIRS is NaN
        (and ``rer_nonpositive`` set) where either RER slice is not positive, and NaN
        where SNR, GSD or sin(elevation) is not positive.

    Notes
    -----
    NGA GIQE 5 (16 Sep 2015), GSD in inches:

    .. math::

        GSD_w = GSD / (\sin\epsilon)^{1/4}

        NIIRS = 9.57 - 3.32\log_{10}GSD_w
                + 3.32\,(1 - e^{-1.9/SNR})\log_{10}RER
                - 2\,(\log_{10}RER)^4 - 1.8/SNR
    """
    rer_x, rer_y, gsd, snr, elevation = map(_da, (rer_x, rer_y, gsd, snr, elevation))
    rer = giqe5_rer(rer_x, rer_y)
    gsd_w = named(apply_kernel(_ground_plane_kernel, gsd, elevation, power=0.25), "m",
                  "elevation-weighted GSD", references=_GSD_W_REFERENCE)
    niirs = named(apply_kernel(_giqe5_kernel, gsd, elevation, snr, rer_x, rer_y), "1",
                  "NIIRS (GIQE 5)", references=GIQE_REFERENCES[5])
    fl = _label_flags(*_version_tests(calibration, _giqe5_tested(
        calibration, snr=snr, rer=rer, gsd=gsd, gsd_w=gsd_w, elevation=elevation, q=q,
        niirs=niirs)))
    return dataset({"niirs": niirs, "gsd_w": gsd_w, "rer": rer, "flags": fl})


def _giqe5_tested(calibration, *, snr, rer, gsd, gsd_w, elevation, q, niirs):
    """What GIQE 5's flags test: its RER, gsd_w and the ground-plane GSD of ``gsd``."""
    gsd_gp = None
    if calibration.gsd_ground_plane is not None:  # GSD / sqrt(sin(elevation))
        gsd_gp = apply_kernel(_ground_plane_kernel, gsd, elevation, power=0.5)
    return {"snr": snr, "rer": rer, "gsd": gsd_w, "gsd_ground_plane": gsd_gp,
            "elevation": elevation, "q": None if q is None else _da(q), "niirs": niirs}


#: The GIQE versions :func:`giqe_by_version` evaluates, in order along ``giqe``.
GIQE_VERSIONS = (3, 4, 5)


def giqe_by_version(*, rer, eho, rer_x, rer_y, gsd_x, gsd_y, snr, elevation, noise_gain, q,
                    noise_coefficient, calibration) -> xr.Dataset:
    """NIIRS by GIQE 3, 4 and 5 along a ``giqe`` dimension, with flags and GSD terms.

    Parameters
    ----------
    rer, eho : xr.DataArray
        Geometric-mean RER and EHO of the system with its filter (GIQE 3 and 4). [1]
    rer_x, rer_y : xr.DataArray
        RER along x and y of the system without its filter (GIQE 5). [1]
    gsd_x, gsd_y : xr.DataArray
        Image-plane GSD along x and y. [m]
    snr : xr.DataArray
        Contrast SNR. [1]
    elevation : xr.DataArray
        GIQE elevation angle. [rad]
    noise_gain : float or xr.DataArray
        Noise gain of the post-processing filter. [1]
    q : xr.DataArray
        GIQE 5's sampling ratio lambda N / p (flags only). [1]
    noise_coefficient : float
        GIQE 4's noise coefficient (0.344; pyBSM uses 0.334). [1]
    calibration : mapping of int to GiqeCalibration
        From :func:`giqe_calibrations`.

    Returns
    -------
    xr.Dataset
        ``niirs`` and ``flags`` over ``giqe``; ``rer_giqe5`` [1]; ``gsd`` (geometric
        mean), ``gsd_gp`` (GIQE 4 ground plane), ``gsd_w`` (GIQE 5) [m];
        ``noise_gain`` [1].
    """
    if q is not None and "orientation" not in getattr(q, "dims", ()):
        q = _da(q).expand_dims(orientation=1, axis=-1)  # one orientation: tested as it is
    args = (rer, eho, rer_x, rer_y, gsd_x, gsd_y, snr, elevation, noise_gain, q)
    out = apply_orchestrator(giqe_arrays, _ALL_OUTPUTS, *args,
                             core=[[]] * (len(args) - 1) + [["orientation"]],
                             sizes={"giqe": len(GIQE_VERSIONS)},
                             noise_coefficient=noise_coefficient, calibration=calibration)
    out["niirs"] = out["niirs"].transpose("giqe", ...).assign_coords(giqe=_versions())
    flags = out["flags"]
    dims = _flags_dims(calibration, dict(zip(_GIQE_INPUTS, args, strict=True)))
    flags = flags.isel(dict.fromkeys(set(flags.dims) - set(dims), 0), drop=True)
    out["flags"] = flags.transpose(*dims)
    out["flags"].attrs = _flags.flag_attrs("GIQE validity flags")
    return dataset(out)


GIQE_VERSION_ATTRS = MappingProxyType({"long_name": "GIQE version"})
"""The attributes of the ``giqe`` coordinate."""


def _versions() -> xr.DataArray:
    """The ``giqe`` coordinate."""
    return xr.DataArray(list(GIQE_VERSIONS), dims="giqe", name="giqe",
                        attrs=dict(GIQE_VERSION_ATTRS))


OUTPUTS = outputs(
    Output("niirs", "1", "National Imagery Interpretability Rating Scale", ("giqe",),
           references="; ".join(f"GIQE {v}: {GIQE_REFERENCES[v]}" for v in GIQE_VERSIONS)),
    Output("rer_giqe5", "1", "GIQE 5 relative edge response", references=_RER5_REFERENCE),
    Output("gsd", "m", "ground sample distance (geometric mean)"),
    Output("gsd_gp", "m", "ground-plane geometric-mean GSD", references=GIQE_REFERENCES[4]),
    Output("gsd_w", "m", "elevation-weighted GSD", references=_GSD_W_REFERENCE),
    Output("noise_gain", "1", "noise gain of the filter", carries=("sensor",)),
)
"""What :func:`giqe_by_version` and :func:`giqe_arrays` return besides ``flags``."""

# each output keeps the dims of the arguments its rule reads, in the order it reads them
_GIQE_INPUTS = ("rer", "eho", "rer_x", "rer_y", "gsd_x", "gsd_y", "snr", "elevation",
                "noise_gain", "q")
_NIIRS_INPUTS = ("rer", "gsd_x", "gsd_y", "eho", "noise_gain", "snr", "elevation", "rer_x",
                 "rer_y")
_ALL_OUTPUTS = outputs(
    OUTPUTS["niirs"]._replace(inputs=_NIIRS_INPUTS),
    # the flags' own dims are those of what each version tests (_flags_dims)
    Output("flags", "1", "GIQE validity flags", ("giqe",), dtype=np.int32),
    OUTPUTS["rer_giqe5"]._replace(inputs=("rer_x", "rer_y")),
    OUTPUTS["gsd"]._replace(inputs=("gsd_x", "gsd_y")),
    OUTPUTS["gsd_gp"]._replace(inputs=("gsd_x", "gsd_y", "elevation")),
    OUTPUTS["gsd_w"]._replace(inputs=("gsd_x", "elevation")),
    OUTPUTS["noise_gain"]._replace(inputs=("noise_gain",)),
)


def sampling_q_arrays(wavelength, aperture_diameter, ifov) -> dict:
    """:func:`sampling_q` on plain arrays, as ``q``."""
    return {"q": _sampling_q_kernel(wavelength, aperture_diameter, ifov)}


def giqe_arrays(rer, eho, rer_x, rer_y, gsd_x, gsd_y, snr, elevation, noise_gain, q, *,
                noise_coefficient, calibration) -> dict:
    """:func:`giqe_by_version` on plain arrays (``q`` over orientation on its last axis)."""
    terms = _giqe_terms(gsd_x, gsd_y, elevation, rer_x, rer_y)  # once for all three
    gsd, gsd_gp, gsd_w, rer5 = (terms[name] for name in ("gsd", "gsd_gp", "gsd_w", "rer5"))
    niirs = _niirs_of_terms(terms, rer, gsd_x, eho, noise_gain, snr, noise_coefficient)
    gsd5_gp = (None if calibration[5].gsd_ground_plane is None
               else _over_sine(gsd_x, terms["sin_el"], 0.5))
    tested = (
        {"snr": snr, "rer": rer, "gsd": gsd, "elevation": elevation, "niirs": niirs},
        {"snr": snr, "rer": rer, "gsd": gsd_gp, "elevation": elevation, "niirs": niirs},
        {"snr": snr, "rer": rer5, "gsd": gsd_w, "gsd_ground_plane": gsd5_gp,
         "elevation": elevation, "q": q, "niirs": niirs})
    arrays, tests, _ = _tests_by_version(calibration, tested, q_per_orientation=True)
    flags = _flags_kernel(*(np.asarray(a) for a in arrays),
                          tests=tests, versions=len(GIQE_VERSIONS))
    return {"niirs": niirs, "flags": flags, "rer_giqe5": rer5, "gsd": gsd, "gsd_gp": gsd_gp,
            "gsd_w": gsd_w, "noise_gain": noise_gain}


def _tests_by_version(calibration, tested, q_per_orientation=None):
    """Every GIQE version's tested arrays and tests, numbered for one :func:`_flags_kernel`.

    ``tested[i]`` holds what version ``GIQE_VERSIONS[i]`` tests (its NIIRS being column i
    of the ``niirs`` over ``giqe``). Returns (arrays, tests, the version index of each).
    """
    arrays, tests, versions = [], [], []
    for i, (version, values) in enumerate(zip(GIQE_VERSIONS, tested, strict=True)):
        version_arrays, version_tests = _version_tests(calibration[version], values, i, i,
                                                       q_per_orientation)
        tests += [(*t[:5], t[5] + len(arrays), t[6]) for t in version_tests]
        arrays += version_arrays
        versions += [i] * len(version_arrays)
    return arrays, tests, versions


class _Dims(NamedTuple):
    """What the flags' dims need of a tested quantity: its dims."""

    dims: tuple


def _flags_dims(calibration, given) -> tuple:
    """The dims of :func:`giqe_by_version`'s flags from those of its arguments ``given``.

    Each version's flags carry the dims of what it tests, in the order in which its tests
    meet them (its NIIRS: in the order its equation broadcasts them), ``giqe`` first, as
    if each version were flagged alone and concatenated; then any other dim of a tested
    quantity, in the order the tested quantities have them.
    """
    def of(*names):
        return _Dims(_dims_in_order(*(getattr(given[n], "dims", ()) for n in names)))

    rer, snr, elevation, gsd = of("rer"), of("snr"), of("elevation"), of("gsd_x", "gsd_y")
    gsd_gp, gsd_w = of("gsd_x", "gsd_y", "elevation"), of("gsd_x", "elevation")
    niirs = _Dims(("giqe", *of(*_NIIRS_INPUTS).dims))
    rer5, q = of("rer_x", "rer_y"), None if given["q"] is None else of("q")
    gsd5_gp = gsd_w if calibration[5].gsd_ground_plane is not None else None
    tested = (
        {"snr": snr, "rer": rer, "gsd": gsd, "elevation": elevation, "niirs": niirs},
        {"snr": snr, "rer": rer, "gsd": gsd_gp, "elevation": elevation, "niirs": niirs},
        {"snr": snr, "rer": rer5, "gsd": gsd_w, "gsd_ground_plane": gsd5_gp,
         "elevation": elevation, "q": q, "niirs": niirs})
    niirs_dims = ((rer, gsd, of("eho"), of("noise_gain"), snr),
                  (rer, gsd_gp, of("eho"), of("noise_gain"), snr), (gsd_w, snr, rer5))
    arrays, tests, versions = _tests_by_version(calibration, tested, q_per_orientation=True)
    order, every = [], []
    for i, array, test in zip(versions, arrays, tests, strict=True):
        core = ("orientation" if test[2] == "any_outside"
                else "giqe" if test[6] is not None else None)
        own = [d for d in array.dims if d != core]
        every.append(own)
        order += [a.dims for a in niirs_dims[i]] if test[6] is not None else [own]
    kept = _dims_in_order(*every)
    return ("giqe", *(d for d in _dims_in_order(*order) if d in kept),
            *(d for d in kept if d not in _dims_in_order(*order)))
