"""MODTRAN 5.2.1 atmosphere database: the lazy cube and per-scenario interpolation.

The database (pyBSM 0.16.1's 3430 MODTRAN runs, see ``NOTICE``) is one NetCDF
file, ``atmosphere.nc``, with a float32 variable ``atmosphere`` on the dims
(visibility, altitude, ground_range, component, wavelength) in the database's
native units. :func:`open_atmosphere` opens it lazily in SI units;
:func:`atmosphere_at` returns the five spectra for any number of scenarios.

Interpolation between database nodes (``interpolation=``):

``"exact"``
    Database nodes only; any other altitude or ground range raises ``ValueError``.
``"linear"``
    pyBSM 0.16.1's ``load_database_atmosphere`` rule, bit for bit: linear in
    altitude at the two bracketing ground ranges, then linear in ground range.
``"log-linear"``
    The same two steps on the logarithm of each value (transmittance falls
    exponentially with path length), with the altitude weight linear in
    log(altitude); linear in the value where a bracketing value is zero.
``"same-elevation"``
    Transmittance, surface emission and ground-reflected radiance (the components
    attenuated along the path) are interpolated between the two altitude tables
    along paths of the same elevation angle at the target: each table is read,
    log-linearly in ground range, at the ground range where its line of sight
    leaves the target at the scenario's angle; the logarithms are then combined
    with the weight of the extra optical path of an exponential atmosphere
    (scale height :data:`SCALE_HEIGHT`) over a spherical Earth. The path
    radiances use ``"log-linear"``. Where a same-elevation point leaves a table's
    coverage (the horizon, 300 km) and above 24.5 km the rule falls back to
    ``"log-linear"`` and sets the ``atmosphere_fallback`` flag (not at 24.5-550 km).
``"optical-depth-cubic"``
    As ``"same-elevation"``, but the logarithm of TRANS, SURF_EMIS and GRND_RFLT
    (-ln TRANS is the line of sight's optical depth) is a monotone cubic (PCHIP
    slopes) in the same optical-path coordinate through the two bracketing tables
    and one more table beyond each, read at the same elevation angle; for TRANS the
    ground (optical depth 0) is the node below the lowest table. An outer table
    that is missing, above 24.5 km, beyond its coverage or zero (TRANS at the
    database floor) gives a one-sided slope (the secant without either outer
    table); the bracketing tables, the path radiances, the fallback and its flag
    are ``"same-elevation"``'s, and so is the value where a bracketing value is zero.
``"extinction-profile"`` (default of the ``accurate`` and ``fast`` presets, so of :func:`atmosphere_at`)
    ``"optical-depth-cubic"`` with its increment over the lower bracketing table scaled
    so that, straight down, it equals the vertical optical depth of an extinction
    profile built from the tables' nadir columns: in each interval between tables,
    ln(extinction) is a line between end values that lean to the smoother side
    (Akima's weights) plus a quadratic bulge that makes the interval's mean right, so a
    boundary layer that stays uniform and then drops inside an interval is followed.
    Where the profile cannot be built (TRANS 0 at the database floor) the factor is 1.
    Nodes, fallback and flags are ``"optical-depth-cubic"``'s.

The leave-one-out errors behind these choices are in ``docs/atmosphere.md``.

At a database node every option returns the stored value exactly. Where a
bracketing table is missing (beyond the horizon of the lower altitude, or above
ground range 0 between 24.5 km and 550 km) the spectra are NaN and the
``beyond_database`` flag is set. Altitudes strictly between 24.5 km and 550 km
are interpolated only at ground range 0 and carry the ``atmosphere_sparse`` flag.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import NamedTuple

import netCDF4
import numpy as np
import xarray as xr
from scipy.special import erfcx

from ._kernels import apply_kernel, dataset
from ._metadata import named
from .constants import EARTH_RADIUS
from .flags import flag, flag_attrs
from .geometry import slant_range, target_elevation_angle
from .quadrature import legendre_nodes
from .units import in_units

__all__ = [
    "COMPONENTS",
    "INTERPOLATIONS",
    "SCALE_HEIGHT",
    "VARIABLES",
    "atmosphere_at",
    "band_atmosphere",
    "band_wavelengths",
    "database_path",
    "database_wavelengths",
    "open_atmosphere",
]

#: MODTRAN tape 7 columns, in database order.
COMPONENTS = ("TRANS", "PTH_THRML", "SURF_EMIS", "SOL_SCAT", "GRND_RFLT")
#: Names of the variables returned by :func:`atmosphere_at`, one per component.
VARIABLES = (
    "transmission",
    "path_thermal",
    "surface_emission",
    "solar_scatter",
    "ground_reflected",
)
_LONG_NAMES = (
    "atmospheric transmittance along the path",
    "path thermal radiance (atmospheric emission and scattering)",
    "surface emission radiance at the sensor (target at 299 K, reflectance 0.15)",
    "path solar scattered radiance",
    "ground reflected solar radiance at the sensor (reflectance 0.15)",
)
_SI_UNITS = ("1", "W m-2 sr-1 m-1", "W m-2 sr-1 m-1", "W m-2 sr-1 m-1", "W m-2 sr-1 m-1")
#: pyBSM's conversion W/(sr cm^2 um) -> W/(m^2 sr m): the float32 value divided by
#: float32(1e-10) in float32 (NumPy 2 keeps float32 for float32 / Python float).
_DIVISOR = np.array([1.0, 1e-10, 1e-10, 1e-10, 1e-10], dtype=np.float32)
_DIVISOR.flags.writeable = False
#: interpolation -> (value rule in altitude, altitude coordinate, value rule in ground range)
_RULES = MappingProxyType({
    "exact": ("linear", "altitude", "linear"),
    "linear": ("linear", "altitude", "linear"),
    "log-linear": ("log", "log_altitude", "log"),
    "same-elevation": ("log", "log_altitude", "log"),  # the path radiances and the fallback
    "optical-depth-cubic": ("log", "log_altitude", "log"),  # likewise
    "extinction-profile": ("log", "log_altitude", "log"),  # likewise
})
#: Interpolations that follow the line of sight between altitude tables.
_ALONG_SIGHT = ("same-elevation", "optical-depth-cubic", "extinction-profile")
#: Those among them that use the cubic through four tables.
_CUBIC = ("optical-depth-cubic", "extinction-profile")
#: Components that the line-of-sight rules interpolate along it (indices of
#: TRANS, SURF_EMIS, GRND_RFLT: attenuated along the path; the path radiances are not).
_ALONG_PATH = (0, 2, 4)
_ACROSS_PATH = (1, 3)  # PTH_THRML, SOL_SCAT: path radiances, at fixed ground range
#: Scale height of the extinction profile behind the line-of-sight rules' altitude coordinate:
#: 2 km is the best of 0.5-3 km in the altitude leave-one-out (docs/atmosphere.md). [m]
SCALE_HEIGHT = 2000.0
#: Accepted values of ``interpolation``.
INTERPOLATIONS = tuple(_RULES)
_GAP = (24500.0, 550000.0)  # altitudes with no table in between [m]
_FILE_CHUNKS = MappingProxyType({})  # xarray: use the file's chunks
#: Values per component gathered at a time in the kernel: a block's temporaries (~0.5 MB
#: each) stay in cache; 2**16 is 1.5-2x faster per scenario than 2**21 (measured).
_BLOCK = 1 << 16
#: Gauss-Legendre nodes of the extinction profile's integrals (its exponent is a quadratic
#: with coefficients below 10 on this database: 12 nodes solve for it, 8 integrate it, both
#: to double precision).
_PROFILE_FIT_NODES, _PROFILE_NODES = 12, 8


def database_path(path=None) -> Path:
    """Path of the atmosphere database file.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Explicit file. Default: ``xbsm/data/atmosphere.nc`` (installed wheel),
        else ``atmosphere.nc`` at the top of a source checkout.

    Returns
    -------
    pathlib.Path
        Resolved path of an existing file.
    """
    if path is None:
        return _default_database()
    return _existing([Path(path)])


@functools.cache
def _default_database() -> Path:
    """The packaged database, found once per process."""
    here = Path(__file__).resolve().parent
    return _existing([here / "data" / "atmosphere.nc", here.parent / "atmosphere.nc"])


def _existing(candidates) -> Path:
    """The first existing file of ``candidates``, resolved."""
    for candidate in candidates:
        if candidate.is_file():
            return candidate.resolve()
    raise FileNotFoundError(
        "atmosphere database not found; looked for "
        + ", ".join(str(c) for c in candidates)
        + " (build it with recipes/build_atmosphere.py)"
    )


def open_atmosphere(path=None, chunks=_FILE_CHUNKS) -> xr.Dataset:
    """MODTRAN 5.2.1 atmosphere database in SI units, opened lazily.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Database file; see :func:`database_path`.
    chunks : dict, str, int or None
        Passed to :func:`xarray.open_dataset`. Default: the file's chunks, one
        dask chunk per (visibility, altitude). ``None`` loads numpy arrays.

    Returns
    -------
    xr.Dataset
        Variable ``atmosphere`` (float32) on (visibility, altitude, ground_range,
        component, wavelength); per-component units in the coordinate
        ``component_units``: transmittance [1], radiances [W m-2 sr-1 m-1].
        NaN where the database has no entry.

    Notes
    -----
    Radiances are converted exactly as pyBSM 0.16.1 does, ``raw / float32(1e-10)``
    in float32, so the numbers are bit-identical to pyBSM's. Transmittance is the
    stored value.
    """
    file = str(database_path(path))
    _load_database(file)  # a clear error for a file that is not the database
    if isinstance(chunks, MappingProxyType):
        with netCDF4.Dataset(file) as nc:
            chunks = dict(zip(nc["atmosphere"].dimensions, nc["atmosphere"].chunking(),
                              strict=True))
    # open without dask, load the small coordinates, then chunk only the cube, so
    # that reading coordinates never needs a dask compute
    ds = xr.open_dataset(file, engine="netcdf4", chunks=None)
    ds = ds.assign_coords({name: ds[name].load() for name in ds.coords})
    try:
        raw = ds["atmosphere"] if chunks is None else ds["atmosphere"].chunk(chunks)
    except (TypeError, ValueError) as err:
        raise ValueError(
            "chunks must be None, 'auto', a byte size such as '64MB', an int (the chunk size "
            "along every dimension) or a dict from dimension names (visibility, altitude, "
            f"ground_range, component, wavelength) to chunk sizes; got {chunks!r}") from err
    divisor = xr.DataArray(_DIVISOR, dims="component")
    si = (raw / divisor).astype(np.float32)
    si.attrs = {
        "long_name": "MODTRAN 5.2.1 path transmittance and radiance components",
        "comment": "units by component in component_units; radiances are the database's "
                   "W sr-1 cm-2 um-1 divided by float32(1e-10) in float32 (pyBSM's rule); "
                   "NaN where the database has no entry",
    }
    ds = ds.assign(atmosphere=si)
    return ds.assign_coords(
        component_units=("component", np.array(_SI_UNITS, dtype=object),
                         ds["component_units"].attrs),
    )


@dataclass(frozen=True)
class _Database:
    """The whole database as numpy arrays (SI, float32)."""

    visibility: np.ndarray  # [km]
    altitude: np.ndarray  # [m]
    ground_range: np.ndarray  # [m]
    wavelength: np.ndarray  # [m]
    cube: np.ndarray  # (visibility, altitude, ground_range, component, wavelength)
    present: np.ndarray  # (visibility, altitude, ground_range) bool

    @functools.cached_property
    def extinction_profile(self) -> _ExtinctionProfile:
        """The vertical extinction between the tables (computed once per database)."""
        return _extinction_profile(self)


@functools.lru_cache(maxsize=4)
def _load_database(path: str) -> _Database:
    """Read the database into memory once per process (no dask involved)."""
    try:
        with netCDF4.Dataset(path) as nc:
            nc.set_auto_maskandscale(False)
            cube = nc["atmosphere"][...]
            coords = {name: np.asarray(nc[name][...], dtype=np.float64)
                      for name in ("visibility", "altitude", "ground_range", "wavelength")}
    except OSError as err:
        raise ValueError(f"path {path!r} is not an xbsm atmosphere database: it cannot be "
                         "read as a NetCDF file (the database is the NetCDF file "
                         "recipes/build_atmosphere.py writes)") from err
    except RuntimeError as err:  # HDF5's own checks failed: a truncated or bit-flipped file
        raise ValueError(f"atmosphere database {path} is damaged (NetCDF/HDF error: {err}): "
                         "reinstall xbsm or rebuild it with recipes/build_atmosphere.py") from None
    except (KeyError, IndexError) as err:
        raise ValueError(f"path {path!r} is not an xbsm atmosphere database: it lacks the "
                         "variable 'atmosphere' or its coordinates (visibility, altitude, "
                         "ground_range, wavelength) that recipes/build_atmosphere.py "
                         "writes") from err
    cube = np.ascontiguousarray(cube, dtype=np.float32)
    cube /= _DIVISOR[:, None]  # float32 / float32: pyBSM's bits; NaN stays NaN
    present = ~np.isnan(cube[:, :, :, 0, 0])
    cube.setflags(write=False)
    present.setflags(write=False)
    return _Database(cube=cube, present=present, **coords)


def database_wavelengths(path=None) -> np.ndarray:
    """Wavelength samples of the atmosphere database, 0.3-14 um every 10 nm [m].

    Parameters
    ----------
    path : str or os.PathLike, optional
        Database file; see :func:`database_path`.

    Returns
    -------
    numpy.ndarray
        The ``wavelength`` coordinate (read once per process with the database). [m]
    """
    return _load_database(str(database_path(path))).wavelength


class _ExtinctionProfile(NamedTuple):
    """Vertical extinction between the altitude tables, from their nadir columns.

    Interval ``i`` spans ``heights[i]`` to ``heights[i + 1]`` (the ground, then every
    table up to 24.5 km). Inside it the extinction is proportional to
    ``exp(slope * s + bulge * s * (1 - s))``, ``s`` the fraction of the interval's height,
    with ``mean`` that function's mean over the interval; ``exists`` where the profile
    could be built. Arrays (visibility, interval, wavelength); ``depth`` (visibility,
    height, wavelength) is the nadir optical depth at each height.
    """

    heights: np.ndarray
    depth: np.ndarray
    slope: np.ndarray
    bulge: np.ndarray
    mean: np.ndarray
    exists: np.ndarray

    def window(self, window) -> _ExtinctionProfile:
        """The profile at the wavelengths ``window``."""
        return self._replace(**{f: getattr(self, f)[..., window] for f in self._fields[1:]})


def _interval_ends(mean):
    """Extinction at the bottom and top of each interval from the intervals' means.

    Akima's weights: at the node between intervals ``i - 1`` and ``i`` the value leans to
    the side whose means change less (``|k[i+1] - k[i]|`` weighs ``k[i-1]``,
    ``|k[i-1] - k[i-2]|`` weighs ``k[i]``), so a layer of uniform extinction keeps its
    value up to its edge; the plain average where both weights are 0. Beyond the first
    and last interval the end means are repeated. ``mean`` (visibility, interval,
    wavelength).
    """
    last = mean.shape[1] - 1
    i = np.arange(last + 1)

    def k(j):
        return mean[:, np.clip(j, 0, last)]

    def at_node(below2, below, above, above2):
        lean_below, lean_above = np.abs(above2 - above), np.abs(below - below2)
        total = lean_below + lean_above
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(total > 0.0, (lean_below * below + lean_above * above) / total,
                            0.5 * (below + above))

    return at_node(k(i - 2), k(i - 1), k(i), k(i + 1)), at_node(k(i - 1), k(i), k(i + 1),
                                                                   k(i + 2))


def _extinction_profile(db) -> _ExtinctionProfile:
    """The extinction profile of ``"extinction-profile"`` from ``db``'s nadir columns.

    The nadir entry of each table gives the vertical optical depth from the ground,
    -ln TRANS, so each interval's mean extinction is known; the extinction at its ends
    comes from :func:`_interval_ends`. Inside, ln(extinction) is the straight line between
    the ends plus ``bulge * s * (1 - s)``, with ``bulge`` solved (Newton) so the mean is
    the interval's: a boundary layer that stays uniform and then drops inside an interval
    gets a positive bulge. Where a mean or an end is not positive and finite (TRANS 0 at
    the database floor) or the solve does not converge, ``exists`` is False. Only the
    tables in ``db`` are used (the leave-one-out recipe removes some).
    """
    tables = db.altitude <= _GAP[0]
    heights = np.concatenate(([0.0], db.altitude[tables]))
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = -np.log(db.cube[:, tables, 0, 0, :].astype(np.float64))
        depth = np.concatenate((np.zeros_like(depth[:, :1]), depth), axis=1)
        mean = np.diff(depth, axis=1) / np.diff(heights)[:, None]
        bottom, top = _interval_ends(mean)
        exists = np.isfinite(mean + bottom + top) & (mean > 0.0) & (bottom > 0.0) & (top > 0.0)
        slope = np.where(exists, np.log(top / bottom), 0.0)
        relative = np.where(exists, mean / bottom, 1.0)  # the mean of exp(slope s + bulge ...)
    nodes, weights = legendre_nodes(_PROFILE_FIT_NODES)
    s = 0.5 * (nodes + 1.0)
    s_bulge, weights = s * (1.0 - s), 0.5 * weights
    bulge = np.zeros_like(slope)
    for _ in range(40):  # convex and increasing in the bulge: Newton from 0 (about 6 steps)
        g = np.exp(slope[..., None] * s + bulge[..., None] * s_bulge)
        miss = g @ weights - relative
        converged = np.abs(miss) <= 1e-12 * relative
        if converged.all():
            break
        bulge = np.clip(bulge - miss / ((g * s_bulge) @ weights), -30.0, 30.0)
    exists &= converged
    return _ExtinctionProfile(heights, depth, slope, np.where(exists, bulge, 0.0), relative,
                              exists)


def _bracket(values, nodes, log=False):
    """Lower/upper node index and weight of the upper node (0 exactly on a node).

    The weight is ``(x - x0) / (x1 - x0)``, pyBSM's expression, with ``x`` the
    value itself or, if ``log``, its logarithm.
    """
    lower = np.maximum(np.searchsorted(nodes, values, side="right") - 1, 0)  # <= size - 1
    on_node = nodes[lower] == values
    upper = np.where(on_node, lower, np.minimum(lower + 1, nodes.size - 1))
    x, x0, x1 = values, nodes[lower], nodes[upper]
    if log:
        x, x0, x1 = np.log(x), np.log(x0), np.log(x1)
    span = np.where(on_node, 1.0, x1 - x0)
    weight = np.where(on_node, 0.0, (x - x0) / span)
    return lower, upper, weight


def _interp(low, high, weight, rule):
    """One interpolation step between two gathered spectra (weight of ``high``).

    Linear: ``(1 - w) * low + w * high``, pyBSM's expression and operation order.
    Log: ``low * exp(w * (log(high) - log(low)))`` where both are positive, which
    returns ``low`` exactly when ``w == 0`` or ``high is low``; linear elsewhere.
    """
    w = weight[..., None, None]
    if rule == "linear":
        return (1.0 - w) * low + w * high
    positive = (low > 0.0) & (high > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_step = np.log(high) - np.log(low)
        logged = low * np.exp(w * log_step)
    if positive.all():
        return logged
    return np.where(positive, logged, (1.0 - w) * low + w * high)


def _ln_interp(low, high, weight):
    """Natural logarithm of ``_interp(low, high, weight, "log")``, without its exp."""
    w = weight[..., None, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        ln_low, ln_high = np.log(low), np.log(high)
        out = ln_low + w * (ln_high - ln_low)
        linear = ~((low > 0.0) & (high > 0.0))
        if linear.any():
            np.log((1.0 - w) * low + w * high, out=out, where=linear)
    return out


def _nearest_nodes(value, nodes):
    """Text naming the database nodes on either side of ``value``."""
    i = int(np.searchsorted(nodes, value))
    around = nodes[max(i - 1, 0): i + 1]
    return " and ".join(f"{n:g}" for n in around)


def _validate(altitude, ground_range, visibility, interpolation, db):
    """Raise ValueError for inputs outside the database domain (numpy arrays)."""
    checks = (
        ("altitude", altitude, db.altitude, "m"),
        ("ground_range", ground_range, db.ground_range, "m"),
    )
    for name, values, nodes, units in checks:
        bad = ~((values >= nodes[0]) & (values <= nodes[-1]))
        if bad.any():
            raise ValueError(
                f"{name} must be within [{nodes[0]:g}, {nodes[-1]:g}] {units} (the MODTRAN "
                f"database range); got {float(values[bad].flat[0])!r}"
            )
        if interpolation == "exact":
            off = ~np.isin(values, nodes)
            if off.any():
                value = values[off].flat[0]
                raise ValueError(
                    f"{name}={float(value)!r} {units} is not a database node "
                    f"(interpolation='exact'); nearest nodes: "
                    f"{_nearest_nodes(value, nodes)} {units}"
                )
    bad = ~np.isin(visibility, db.visibility)
    if bad.any():
        raise ValueError(
            "visibility must be one of "
            + ", ".join(f"{v:g}" for v in db.visibility)
            + f" km (MODTRAN IHAZE 1, 2); got {float(visibility[bad].flat[0])!r}"
        )


def _locate(altitude, ground_range, visibility, db, log_altitude=False):
    """Visibility index and the altitude / ground-range brackets of each scenario."""
    vis = np.searchsorted(-db.visibility, -visibility)  # visibility is descending
    alt = _bracket(altitude, db.altitude, log=log_altitude)
    gr = _bracket(ground_range, db.ground_range)
    return vis, alt, gr


def _ground_range_at_elevation(sin_elevation, cos_elevation, altitude):
    """Ground range at which a sensor at ``altitude`` sees the target at a given elevation.

    The elevation angle is measured at the target (on the ground), the Earth is a
    sphere; numpy kernel, result in [m]. The slant range solves
    ``(R + h)^2 = R^2 + s^2 + 2 R s sin(e)`` in the form without cancellation,
    ``s = h (2R + h) / (sqrt(R^2 sin^2 e + h (2R + h)) + R sin e)``; the central angle
    is ``atan2(s cos e, R + s sin e)``.
    """
    above = altitude * (2.0 * EARTH_RADIUS + altitude)
    rise = EARTH_RADIUS * sin_elevation
    slant = above / (np.sqrt(rise * rise + above) + rise)
    return EARTH_RADIUS * np.arctan2(slant * cos_elevation,
                                     EARTH_RADIUS + slant * sin_elevation)


def _optical_path_above(altitude, sin_elevation):
    """Optical path above ``altitude`` of a line of sight from the ground (numpy kernel).

    For extinction ``exp(-z / H)`` and the thin-shell path element
    ``dz / sqrt(sin^2 e + 2 z / R)``, the optical depth between two heights is
    proportional to the difference of this function (``H`` = :data:`SCALE_HEIGHT`):
    ``erfcx(sqrt(k (sin^2 e + 2 h / R))) exp(-h / H)`` with ``k = R / (2 H)``.
    """
    k = EARTH_RADIUS / (2.0 * SCALE_HEIGHT)
    inside = k * (sin_elevation * sin_elevation + 2.0 * altitude / EARTH_RADIUS)
    return erfcx(np.sqrt(inside)) * np.exp(-altitude / SCALE_HEIGHT)


class _Nadir(NamedTuple):
    """The cubic's four tables seen from straight above (``"extinction-profile"``).

    ``x`` (scenario, 4) the nodes' optical-path coordinate at nadir, ``weight`` the
    scenario's weight in it, ``outer`` (scenario, 3) as :class:`_Sight`'s, ``position``
    the scenario's fraction of the height between the bracketing tables.
    """

    x: np.ndarray
    weight: np.ndarray
    outer: np.ndarray
    position: np.ndarray


class _Sight(NamedTuple):
    """The line-of-sight rules' tables of each scenario (numpy arrays).

    ``tables`` holds the altitude index and the ground-range bracket ``(a, g0, g1, wg)``,
    each (scenario, table), of the tables read at the scenario's target elevation angle:
    the lower and upper brackets, then for the cubic rules the table below and
    the table above them. ``weight`` is the scenario's altitude weight in the
    optical-path coordinate, ``usable`` where both brackets can be read along the line of
    sight. For the cubic, ``outer`` (scenario, 3) says whether each outer table is usable
    and whether the lower outer node is the ground, and ``x`` (scenario, 4) is the
    optical-path coordinate of the four nodes; both None for ``"same-elevation"``.
    ``nadir`` is the same stencil at nadir for ``"extinction-profile"``, else None.
    """

    tables: tuple
    weight: np.ndarray
    usable: np.ndarray
    outer: np.ndarray | None
    x: np.ndarray | None
    nadir: _Nadir | None

    def block(self, s: slice) -> _Sight:
        """The scenarios ``s`` of every field."""
        nadir = None if self.nadir is None else _Nadir(*(f[s] for f in self.nadir))
        return _Sight(tuple(t[s] for t in self.tables), self.weight[s], self.usable[s],
                      *(None if f is None else f[s] for f in (self.outer, self.x)), nadir)


def _along_sight(altitude, ground_range, vis, alt, db, interpolation):
    """Tables, weight and usability of the line-of-sight rules (numpy kernel).

    Each table is read where a sensor at its altitude sees the target at the scenario's
    elevation angle (on an altitude node and at nadir, at the scenario's own ground
    range). A bracketing table without such a point (beyond the horizon or the
    coverage, no entry) makes the scenario fall back to the fixed-range rule; an outer
    table without one, or missing (below the lowest table, above 24.5 km), is left
    out of the cubic (a one-sided slope).
    """
    a0, a1, _ = alt
    cubic = interpolation in _CUBIC
    top = db.altitude.size - 1
    elevation = target_elevation_angle(slant_range(ground_range, altitude), altitude)
    sin_e, cos_e = np.sin(elevation)[:, None], np.cos(elevation)[:, None]
    index = np.stack((a0, a1, a0 - 1, a1 + 1) if cubic else (a0, a1), axis=1)
    a = np.minimum(np.maximum(index, 0), top)
    node = db.altitude[a]
    same = (node == altitude[:, None]) | (ground_range == 0.0)[:, None]
    g = np.where(same, ground_range[:, None], _ground_range_at_elevation(sin_e, cos_e, node))
    last = db.ground_range[-1]
    g0, g1, wg = _bracket(np.minimum(g, last), db.ground_range)
    covered = ((g <= last) & db.present[vis[:, None], a, g0] & db.present[vis[:, None], a, g1]
               & (elevation > 0.0)[:, None])
    usable = covered[:, 0] & covered[:, 1] & (db.altitude[a1] <= _GAP[0])
    # optical path above each node: lower bracket, the scenario, upper bracket (, below,
    # above; the ground is the lower outer node below the lowest table)
    heights = [node[:, 0], altitude, node[:, 1]]
    ground = a0 == 0
    if cubic:
        heights += [np.where(ground, 0.0, node[:, 2]), node[:, 3]]
    heights = np.stack(heights, axis=1)
    x, weight = _optical_path_nodes(heights, sin_e, a0 == a1)
    if not cubic:
        return _Sight((a, g0, g1, wg), weight, usable, None, None, None)
    exists = (~ground, (index[:, 3] <= top) & (node[:, 3] <= _GAP[0]))
    outer = np.stack((exists[0] & covered[:, 2], exists[1] & covered[:, 3], ground), axis=1)
    nadir = None
    if interpolation == "extinction-profile":
        x_up, weight_up = _optical_path_nodes(heights, np.ones_like(sin_e), a0 == a1)
        with np.errstate(divide="ignore", invalid="ignore"):  # 0 / 0 on a node
            position = np.where(a0 == a1, 0.0,
                                (altitude - node[:, 0]) / (node[:, 1] - node[:, 0]))
        nadir = _Nadir(x_up, weight_up, np.stack((*exists, ground), axis=1), position)
    return _Sight((a, g0, g1, wg), weight, usable, outer, x, nadir)


def _optical_path_nodes(heights, sin_e, on_node):
    """Optical-path coordinate of the cubic's nodes and the scenario's weight in it.

    ``heights`` (scenario, 3 or 5): lower bracket, the scenario, upper bracket (, the
    node below, the node above). Returns the coordinate (scenario, 4) of below, lower,
    upper, above (None with three heights) and the weight (0 on a node).
    """
    path = _optical_path_above(heights, sin_e)
    with np.errstate(divide="ignore", invalid="ignore"):
        weight = np.where(on_node, 0.0, (path[:, 0] - path[:, 1]) / (path[:, 0] - path[:, 2]))
    x = -path[:, [3, 0, 2, 4]] if heights.shape[1] == 5 else None
    return x, weight


def _pchip_interior_slope(h_left, h_right, s_left, s_right):
    """PCHIP derivative at a node between two intervals (numpy kernel).

    The Fritsch-Butland weighted harmonic mean of the secants (scipy's); 0 at a local
    extremum.
    """
    w1, w2 = 2.0 * h_right + h_left, h_right + 2.0 * h_left
    d = (w1 + w2) / (w1 / s_left + w2 / s_right)
    return np.where(s_left * s_right > 0.0, d, 0.0)  # same sign, neither zero


def _pchip_end_slope(h_near, h_far, s_near, s_far):
    """PCHIP derivative at the end node of two intervals (numpy kernel).

    scipy's shape-preserving three-point formula.
    """
    d = ((2.0 * h_near + h_far) * s_near - h_near * s_far) / (h_near + h_far)
    d = np.where(d * s_near > 0.0, d, 0.0)  # against the secant's sign, or zero: 0
    # where the far secant changes sign (or is 0), at most 3 times the near one
    overshoot = (s_near * s_far <= 0.0) & (np.abs(d) > 3.0 * np.abs(s_near))
    return np.where(overshoot, 3.0 * s_near, d)


def _cubic_increment(y, x, t, left, right):
    """Monotone cubic Hermite increment over ``y[1]`` at weight ``t`` of [x1, x2] (numpy).

    ``y`` and ``x`` are the four nodes (below, lower bracket, upper bracket, above);
    PCHIP slopes from the outer nodes where ``left`` / ``right``, one-sided where only
    one of them is, the secant without either. All arguments broadcast together.
    """
    h0, h1, h2 = x[1] - x[0], x[2] - x[1], x[3] - x[2]
    rise = y[2] - y[1]
    s0, s1, s2 = (y[1] - y[0]) / h0, rise / h1, (y[3] - y[2]) / h2
    d1 = np.where(left, _pchip_interior_slope(h0, h1, s0, s1),
                  np.where(right, _pchip_end_slope(h1, h2, s1, s2), s1))
    d2 = np.where(right, _pchip_interior_slope(h1, h2, s1, s2),
                  np.where(left, _pchip_end_slope(h1, h0, s1, s0), s1))
    t2, t3 = t * t, t * t * t
    return (t3 - 2.0 * t2 + t) * h1 * d1 + (-2.0 * t3 + 3.0 * t2) * rise + (t3 - t2) * h1 * d2


@np.errstate(divide="ignore", invalid="ignore", over="ignore")
def _optical_depth_cubic(base, low, high, beyond, sight, on_node, scale=None):
    """The cubic rules' values of TRANS, SURF_EMIS, GRND_RFLT (numpy kernel).

    ``base`` is ``"same-elevation"``'s result (scenario, component, wavelength); ``low``
    and ``high`` the bracketing tables' same-elevation spectra, ``beyond`` the
    logarithms of the outer tables' (below, above); ``sight`` the scenarios'
    :class:`_Sight` (its ``outer``, ``x`` and ``weight``).

    The logarithm of each value (-ln TRANS is the line of sight's optical depth, 0 at
    the ground) is a monotone cubic Hermite (PCHIP) between the brackets with slopes
    from the outer nodes: one-sided where an outer node is missing, unusable or has a
    zero value (TRANS at the database floor), the secant without either. For TRANS the
    ground is the lower outer node below the lowest table; SURF_EMIS and GRND_RFLT have
    no ground node. ``scale`` (scenario, wavelength), if given, multiplies the increment
    (``"extinction-profile"``). Returns ``low * exp(increment)``; on an altitude node,
    and where the result is not finite and positive (a zero bracketing value), ``base``.
    """
    usable = sight.outer
    ground = usable[:, 2, None, None]
    along_trans = np.zeros(base.shape[1:], dtype=bool)
    along_trans[0] = True  # TRANS is the first of _ALONG_PATH
    y0 = np.where(ground & along_trans, 0.0, beyond[0])
    left = np.where(along_trans, usable[:, 0, None, None] | ground,
                    usable[:, 0, None, None]) & np.isfinite(y0)
    right = usable[:, 1, None, None] & np.isfinite(beyond[1])
    step = _cubic_increment((y0, np.log(low), np.log(high), beyond[1]),
                            [sight.x[:, k, None, None] for k in range(4)],
                            sight.weight[:, None, None], left, right)
    if scale is not None:
        step *= scale[:, None, :]
    value = low * np.exp(step)
    good = ~on_node[:, None, None] & np.isfinite(value) & (value > 0.0)
    return np.where(good, value, base)


def _profile_scale(vis, a, nadir, profile):
    """``"extinction-profile"``'s factor on the cubic's increment (scenario, wavelength).

    Straight down, the extinction profile (:func:`_extinction_profile`) gives the optical
    depth between the lower bracketing table and the scenario's altitude; the factor is
    that over the cubic's own value at nadir (the same four tables' nadir entries, the
    same coordinate at sin e = 1). 1 on a node and where the profile does not exist or
    the factor is not finite and positive. ``a`` (table, scenario) as in
    :func:`_line_of_sight`; ``profile`` at the kernel's wavelengths. The factor depends
    on the visibility and the altitude only, so it is computed once for each distinct
    pair (a sweep over ground range shares it).
    """
    if vis.size < 2:
        return _nadir_factor(vis, a, nadir, profile)
    key = np.stack((vis, a[0], a[1], nadir.position))
    _, first, inverse = np.unique(key, axis=1, return_index=True, return_inverse=True)
    if first.size == vis.size:
        return _nadir_factor(vis, a, nadir, profile)
    factor = _nadir_factor(vis[first], a[:, first], _Nadir(*(f[first] for f in nadir)), profile)
    return factor[inverse.reshape(-1)]


@np.errstate(divide="ignore", invalid="ignore", over="ignore")
def _nadir_factor(vis, a, nadir, profile):
    """:func:`_profile_scale` of each scenario given."""
    # ln of nadir TRANS (table, scenario, wavelength); a table above 24.5 km (only ever an
    # outer one, left out of the cubic) reads the last height's
    ln_t = -profile.depth[vis, np.minimum(a + 1, profile.heights.size - 1)]
    outer = nadir.outer
    ground = outer[:, 2, None]
    y0 = np.where(ground, 0.0, ln_t[2])
    step = _cubic_increment((y0, ln_t[0], ln_t[1], ln_t[3]),
                            [nadir.x[:, k, None] for k in range(4)], nadir.weight[:, None],
                            (outer[:, 0, None] | ground) & np.isfinite(y0),
                            outer[:, 1, None] & np.isfinite(ln_t[3]))
    # the profile's intervals start at the ground; from 24.5 km up the scenario is on a
    # node or falls back, so any interval will do
    interval = np.minimum(a[0] + 1, profile.slope.shape[1] - 1)
    slope, bulge, mean, exists = (f[vis, interval] for f in (profile.slope, profile.bulge,
                                                             profile.mean, profile.exists))
    nodes, weights = legendre_nodes(_PROFILE_NODES)
    position = nadir.position[:, None]
    s = 0.5 * position[..., None] * (nodes + 1.0)  # Gauss-Legendre on [0, position]
    inside = np.exp(slope[..., None] * s + bulge[..., None] * (s * (1.0 - s))) @ weights
    fraction = 0.5 * position * inside / mean  # of the interval's nadir optical depth
    factor = fraction * (ln_t[1] - ln_t[0]) / step
    return np.where(exists & np.isfinite(factor) & (factor > 0.0), factor, 1.0)


def _scenarios(altitude, ground_range, visibility, interpolation, db):
    """Validated flat inputs with their brackets and line-of-sight tables.

    Also where all four fixed-range tables exist; the line-of-sight part (a
    :class:`_Sight`, its ``usable`` also requiring those four) is None for other rules.
    """
    altitude, ground_range, visibility = (
        np.asarray(a, dtype=np.float64) for a in
        np.broadcast_arrays(altitude, ground_range, visibility))
    _validate(altitude, ground_range, visibility, interpolation, db)
    shape = altitude.shape
    altitude, ground_range = altitude.ravel(), ground_range.ravel()
    vis, alt, gr = _locate(altitude, ground_range, visibility.ravel(), db,
                           log_altitude=_RULES[interpolation][1] == "log_altitude")
    (a0, a1, _), (g0, g1, _), p = alt, gr, db.present
    complete = p[vis, a0, g0] & p[vis, a1, g0] & p[vis, a0, g1] & p[vis, a1, g1]
    along = None
    if interpolation in _ALONG_SIGHT:
        along = _along_sight(altitude, ground_range, vis, alt, db, interpolation)
        # never finite where others are NaN
        along = along._replace(usable=along.usable & complete)
    return shape, altitude, vis, alt, gr, complete, along


def _flags_of(scenarios):
    """Validity flags of each scenario from its :func:`_scenarios` brackets (numpy)."""
    shape, altitude, _, _, _, complete, along = scenarios
    out = np.where(complete, 0, flag("beyond_database"))
    sparse = (altitude > _GAP[0]) & (altitude < _GAP[1])
    out |= np.where(sparse, flag("atmosphere_sparse"), 0)
    if along is not None:
        fallback = complete & ~along.usable & (altitude <= _GAP[0])
        out |= np.where(fallback, flag("atmosphere_fallback"), 0)
    return out.astype(np.int32).reshape(shape)


def _atmosphere_kernel(altitude, ground_range, visibility, wavelength, *, path, interpolation,
                       window):
    """Each component's spectrum and the validity flags of every scenario (numpy kernel).

    ``wavelength`` only gives the last axis of the spectra (it is the window's).
    """
    db = _load_database(path)
    scenarios = _scenarios(altitude, ground_range, visibility, interpolation, db)
    spectra = _spectra_of(db, scenarios, interpolation, window)
    return (*np.moveaxis(spectra, -2, 0), _flags_of(scenarios))


def _interpolate_database(db, altitude, ground_range, visibility, interpolation, window):
    """Spectra of ``db`` at each scenario, shape (..., component, wavelength).

    ``db`` is a :class:`_Database`, possibly with tables removed (the leave-one-out
    recipe does that).
    """
    scenarios = _scenarios(altitude, ground_range, visibility, interpolation, db)
    return _spectra_of(db, scenarios, interpolation, window)


def _gather(cube, vis, a, g, components):
    """Spectra (..., component, wavelength) of the tables ``(vis, a, g)`` as float64.

    ``a`` and ``g`` may carry a leading axis of tables before the scenario axis.
    """
    spectra = cube[vis, a, g]  # whole (component, wavelength) blocks: the fastest gather
    if components is not None:
        spectra = spectra[..., components, :]
    return spectra.astype(np.float64)


def _fixed_range(cube, vis, alt, gr, rules, components=None):
    """Altitude at both bracketing ground ranges first, then ground range (pyBSM's order)."""
    (a0, a1, wa), (g0, g1, wg) = alt, gr
    ranges = np.stack((g0, g1))
    by_range = _interp(_gather(cube, vis, a0, ranges, components),
                       _gather(cube, vis, a1, ranges, components), np.stack((wa, wa)), rules[0])
    return _interp(by_range[0], by_range[1], wg, rules[1])


def _line_of_sight(cube, vis, sight, fixed_range, profile=None):
    """TRANS, SURF_EMIS, GRND_RFLT of the line-of-sight rules (numpy kernel).

    Ground range log-linear inside each table, then altitude along the line of sight:
    log-linear in the optical-path coordinate (``"same-elevation"``) or the cubic
    (``"optical-depth-cubic"``, :func:`_optical_depth_cubic`; ``"extinction-profile"``
    scales its increment by :func:`_profile_scale` of ``profile``).
    ``fixed_range(components, where)`` gives the fixed-range rule's values, taken where
    the line of sight leaves a table.
    """
    a, g0, g1, wg = (t.T for t in sight.tables)  # (table, scenario)
    brackets = slice(0, 2)
    low, high = _interp(_gather(cube, vis, a[brackets], g0[brackets], _ALONG_PATH),
                        _gather(cube, vis, a[brackets], g1[brackets], _ALONG_PATH),
                        wg[brackets], "log")
    out = _interp(low, high, sight.weight, "log")
    if sight.x is not None:
        outer = slice(2, 4)
        beyond = _ln_interp(_gather(cube, vis, a[outer], g0[outer], _ALONG_PATH),
                            _gather(cube, vis, a[outer], g1[outer], _ALONG_PATH), wg[outer])
        scale = None if sight.nadir is None else _profile_scale(vis, a, sight.nadir, profile)
        out = _optical_depth_cubic(out, low, high, beyond, sight, a[0] == a[1], scale)
    fallback = ~sight.usable
    if fallback.any():  # the fixed-range rule where the line of sight leaves a table
        out[fallback] = fixed_range(_ALONG_PATH, fallback)
    return out


def _spectra_of(db, scenarios, interpolation, window):
    """Spectra at each scenario from its :func:`_scenarios` brackets (numpy)."""
    shape, _, vis, alt, gr, _, along = scenarios
    alt_rule, _, gr_rule = _RULES[interpolation]
    cube = db.cube[..., window]
    profile = None
    if along is not None and along.nadir is not None:
        profile = db.extinction_profile.window(window)
    n_comp, n_wl = cube.shape[-2:]
    out = np.empty((vis.size, n_comp, n_wl), dtype=np.float64)
    step = max(1, _BLOCK // max(1, n_comp * n_wl))
    for start in range(0, vis.size, step):  # blocks of scenarios bound the memory
        s = slice(start, start + step)

        def fixed_range(components, where=slice(None), s=s):
            return _fixed_range(cube, vis[s][where], [b[s][where] for b in alt],
                                [b[s][where] for b in gr], (alt_rule, gr_rule), components)

        if along is None:
            out[s] = fixed_range(None)
            continue
        out[s][:, _ACROSS_PATH] = fixed_range(_ACROSS_PATH)
        out[s][:, _ALONG_PATH] = _line_of_sight(cube, vis[s], along.block(s), fixed_range,
                                                profile)
    return out.reshape(shape + (n_comp, n_wl))


WAVELENGTH_ATTRS = MappingProxyType({"units": "m", "long_name": "wavelength",
                                     "standard_name": "radiation_wavelength"})
"""The attributes of the ``wavelength`` coordinate of every spectral result."""

_INPUT_UNITS = MappingProxyType({"altitude": "m", "ground_range": "m", "visibility": "km"})


def _as_input(value, name):
    """Convert a float or DataArray input to a float64 DataArray in the database's units."""
    if not isinstance(value, xr.DataArray):
        value = xr.DataArray(np.asarray(value))
    for dim in ("wavelength", "component"):
        if dim in value.dims:
            raise ValueError(f"{name} must not have the dimension {dim!r}")
    if value.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be a real number or an xr.DataArray of real numbers; "
                         f"got dtype {value.dtype}")
    return in_units(name, value.astype(np.float64), _INPUT_UNITS[name])


def _wavelength_window(wavelength, bounds):
    """Slice of wavelengths ``lo <= w <= hi`` (exact float comparison)."""
    if bounds is None:
        return slice(None)
    lo, hi = (float(b) for b in bounds)
    index = np.flatnonzero((wavelength >= lo) & (wavelength <= hi))
    if index.size == 0:
        raise ValueError(
            f"wavelength_bounds must contain a database wavelength in "
            f"[{wavelength[0]:g}, {wavelength[-1]:g}] m; got ({lo!r}, {hi!r})"
        )
    return slice(int(index[0]), int(index[-1]) + 1)


def atmosphere_at(altitude, ground_range, visibility, *, interpolation=None,
                  wavelength_bounds=None, path=None) -> xr.Dataset:
    """Atmospheric transmittance and path radiances for each scenario.

    Parameters
    ----------
    altitude : float or xr.DataArray
        Sensor altitude above ground level, within [2, 550000]. [m]
    ground_range : float or xr.DataArray
        Ground range from the sensor nadir point to the target, within [0, 300000]. [m]
    visibility : float or xr.DataArray
        Meteorological range: 23 (MODTRAN IHAZE 1) or 5 (IHAZE 2). [km]
    interpolation : {"extinction-profile", "optical-depth-cubic", "same-elevation", \
"log-linear", "linear", "exact"}, optional
        Rule between database nodes; see the module docstring. Default: the rule of the
        default ``accurate`` preset, ``xbsm.method().atmosphere_interpolation``
        ("extinction-profile"), so that the spectra are the ones :func:`xbsm.snr` and
        :func:`xbsm.niirs` use by default. The ``pybsm`` preset's rule is "linear"
        (``xbsm.method("pybsm").atmosphere_interpolation``).
    wavelength_bounds : tuple of float, optional
        ``(lo, hi)``: keep the database wavelengths ``lo <= w <= hi`` (exact float
        comparison, as pyBSM selects a band); only these are interpolated. [m]
    path : str or os.PathLike, optional
        Database file; see :func:`database_path`.

    Returns
    -------
    xr.Dataset
        float64 ``transmission`` [1], ``path_thermal``, ``surface_emission``,
        ``solar_scatter``, ``ground_reflected`` [W m-2 sr-1 m-1] on the union of
        the input dimensions plus ``wavelength``, and int32 ``flags`` (CF flag
        variable; ``beyond_database`` where the spectra are NaN,
        ``atmosphere_sparse`` between 24.5 km and 550 km, ``atmosphere_fallback``
        where a line-of-sight rule fell back to ``"log-linear"``).

    Raises
    ------
    ValueError
        An input outside the database domain, an off-node input with
        ``interpolation="exact"``, or an unknown ``interpolation``. With
        dask-backed inputs the values are checked when the result is computed.

    Notes
    -----
    Inputs may carry any dimensions, including ones named like the database
    dimensions (``ground_range``, ``altitude``, ``visibility``). Dask-backed
    inputs give dask-backed results; nothing is computed until asked. The
    database itself is read into memory once per process (netCDF4, no dask).
    """
    if interpolation is None:
        from .methods import PRESETS  # methods imports this module

        interpolation = PRESETS["accurate"].atmosphere_interpolation
    if interpolation not in _RULES:
        raise ValueError(
            f"interpolation must be one of {', '.join(map(repr, INTERPOLATIONS))}; "
            f"got {interpolation!r}"
        )
    file = str(database_path(path))
    db = _load_database(file)
    window = _wavelength_window(db.wavelength, wavelength_bounds)
    wavelength = db.wavelength[window]
    inputs = [_as_input(altitude, "altitude"), _as_input(ground_range, "ground_range"),
              _as_input(visibility, "visibility")]
    if not any(a.chunks is not None for a in inputs):
        # eager inputs: fail at the call, not inside the kernel
        _validate(*(np.asarray(a.values) for a in inputs), interpolation, db)

    wl = xr.DataArray(wavelength, dims="wavelength", attrs=dict(WAVELENGTH_ATTRS))
    wl = wl.assign_coords(wavelength=wl)
    *spectra, flags = apply_kernel(
        _atmosphere_kernel, *inputs, wl, core=[[], [], [], ["wavelength"]],
        outputs=[("wavelength",)] * len(COMPONENTS) + [()],
        dtype=[np.float64] * len(COMPONENTS) + [np.int32],
        path=file, interpolation=interpolation, window=window)
    described = zip(VARIABLES, _LONG_NAMES, _SI_UNITS, strict=True)
    data = {name: named(values, units, long_name)
            for values, (name, long_name, units) in zip(spectra, described, strict=True)}
    flags.attrs = flag_attrs("atmosphere validity flags")
    out = dataset({**data, "flags": flags})
    return out.assign_attrs(
        source="MODTRAN 5.2.1 database of pyBSM 0.16.1 (xbsm atmosphere.nc)",
        interpolation=interpolation,
    )


RELATIVE_EDGE_TOLERANCE = 1e-9
"""Band edges closer than this (relative) to a database wavelength are on it."""


def band_wavelengths(wavelength_min: float, wavelength_max: float, band_edges: str,
                     path=None):
    """Wavelengths at which a band is sampled, and the database bounds to load.

    Parameters
    ----------
    wavelength_min, wavelength_max : float
        Band edges. [m]
    band_edges : str
        "exact" (pyBSM: database samples w with min <= w <= max by float
        comparison) or "interpolated" (the band's own edges plus every database
        sample strictly inside).
    path : str or os.PathLike, optional
        Database file; see :func:`database_path`.

    Returns
    -------
    tuple
        (wavelengths to sample as np.ndarray or None for "exact",
        (low, high) database bounds to load).
    """
    if band_edges == "exact":
        return None, (wavelength_min, wavelength_max)
    if band_edges != "interpolated":
        raise ValueError(f"band_edges must be 'exact' or 'interpolated'; got {band_edges!r}")
    grid = database_wavelengths(path)
    tol = RELATIVE_EDGE_TOLERANCE
    inside = grid[(grid > wavelength_min * (1 + tol)) & (grid < wavelength_max * (1 - tol))]
    lo_index = max(np.searchsorted(grid, wavelength_min * (1 + tol), side="right") - 1, 0)
    hi_index = min(np.searchsorted(grid, wavelength_max * (1 - tol)), grid.size - 1)
    lo_near = np.isclose(grid[lo_index], wavelength_min, rtol=tol, atol=0)
    hi_near = np.isclose(grid[hi_index], wavelength_max, rtol=tol, atol=0)
    lo = grid[lo_index] if lo_near else wavelength_min
    hi = grid[hi_index] if hi_near else wavelength_max
    samples = np.concatenate([[lo], inside, [hi]])
    return samples, (grid[lo_index], grid[hi_index])


def band_atmosphere(altitude, ground_range, visibility, wavelength_min, wavelength_max, *,
                    interpolation, band_edges, path=None) -> xr.Dataset:
    """Atmosphere over a sensor's band for every scenario.

    Parameters
    ----------
    altitude, ground_range, visibility : float or xr.DataArray
        As for :func:`atmosphere_at`. [m, m, km]
    wavelength_min, wavelength_max : float
        Band edges. [m]
    interpolation : str
        As for :func:`atmosphere_at`.
    band_edges : {"exact", "interpolated"}
        As for :func:`band_wavelengths`.
    path : str or os.PathLike, optional
        Database file; see :func:`database_path`.

    Returns
    -------
    xr.Dataset
        Atmosphere components over ``wavelength`` and the scenario dims, plus ``flags``.
    """
    samples, bounds = band_wavelengths(float(wavelength_min), float(wavelength_max),
                                       band_edges, path)
    atm = atmosphere_at(altitude, ground_range, visibility, interpolation=interpolation,
                        wavelength_bounds=bounds, path=path)
    if atm.sizes["wavelength"] < 2:
        raise ValueError(
            "the band [wavelength_min, wavelength_max] must span at least two database "
            f"wavelengths (10 nm apart); got {bounds}"
        )
    if samples is not None and (
        samples.size != atm.sizes["wavelength"]
        or not np.array_equal(samples, atm["wavelength"].values)
    ):
        band_flags = atm["flags"]
        atm = atm.drop_vars("flags").interp(wavelength=samples)
        atm["flags"] = band_flags
    return atm


def band_atmosphere_arrays(altitude, ground_range, visibility, wavelength_min, wavelength_max,
                           *, interpolation, band_edges) -> dict | None:
    """:func:`band_atmosphere` of one eager scenario on plain arrays, or None.

    Returns ``wavelength``, the spectra of :data:`VARIABLES` over it and ``flags``; None
    for a band that spans fewer than two database wavelengths (:func:`band_atmosphere`
    raises the error). The inputs are in the database's units and already checked.
    """
    samples, bounds = band_wavelengths(float(wavelength_min), float(wavelength_max),
                                       band_edges)
    file = str(database_path())
    db = _load_database(file)
    window = _wavelength_window(db.wavelength, bounds)
    wavelength = db.wavelength[window]
    if wavelength.size < 2:
        return None
    *spectra, flags = _atmosphere_kernel(altitude, ground_range, visibility, wavelength,
                                         path=file, interpolation=interpolation, window=window)
    if samples is not None and not np.array_equal(samples, wavelength):
        spectra = [np.interp(samples, wavelength, s) for s in spectra]
        wavelength = samples
    return {"wavelength": wavelength, **dict(zip(VARIABLES, spectra, strict=True)),
            "flags": flags}
