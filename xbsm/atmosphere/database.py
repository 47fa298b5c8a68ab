"""The atmosphere database file, its facts, and the cube in memory.

The database (pyBSM 0.16.1's 3430 MODTRAN 5.2.1 runs, see ``NOTICE``) is one NetCDF
file, ``atmosphere.nc``, with a float32 variable ``atmosphere`` on the dims
(visibility, altitude, ground_range, component, wavelength) in the database's native
units; another database may put condition dims (:data:`CONDITIONS`) before them.
This module is the one place that knows the file: where it is
(:func:`database_path`), its facts (the nodes of each coordinate, the limits that
follow from them, the components and their units), how to open it lazily in SI
units (:func:`open_atmosphere`) and how to read it into memory once per process
(:func:`load_database`). ``params``, ``examples`` and the flag texts take the facts
from here; ``tests/atmosphere/test_atmosphere.py`` checks them against the file.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import os
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
import xarray as xr

from .._netcdf import LOCK, netcdf_file, open_dataset

__all__ = [
    "ALTITUDES",
    "ALTITUDE_GAP",
    "ALTITUDE_RANGE",
    "COMPONENTS",
    "CONDITIONS",
    "GROUND_RANGES",
    "GROUND_RANGE_RANGE",
    "IHAZE",
    "LONG_NAMES",
    "SURFACE_REFLECTANCE",
    "UNITS",
    "VARIABLES",
    "VISIBILITIES",
    "WAVELENGTH_MAX",
    "WAVELENGTH_MIN",
    "Database",
    "check_supported",
    "database_conditions",
    "database_path",
    "database_visibilities",
    "database_wavelengths",
    "describe_conditions",
    "listed",
    "load_database",
    "open_atmosphere",
    "use_database",
    "visibility_range",
]

# ---- the facts (pyBSM 0.16.1's database, paper Appendix A; tests check them against the file)

#: MODTRAN tape 7 columns, in database order.
COMPONENTS = ("TRANS", "PTH_THRML", "SURF_EMIS", "SOL_SCAT", "GRND_RFLT")
#: Names of the variables returned by :func:`xbsm.atmosphere.atmosphere_at`, one per component.
VARIABLES = (
    "transmission",
    "path_thermal",
    "surface_emission",
    "solar_scatter",
    "ground_reflected",
)
#: ``long_name`` of each of :data:`VARIABLES`.
LONG_NAMES = (
    "atmospheric transmittance along the path",
    "path thermal radiance (atmospheric emission and scattering)",
    "surface emission radiance at the sensor (target at 299 K, reflectance 0.15)",
    "path solar scattered radiance",
    "ground reflected solar radiance at the sensor (reflectance 0.15)",
)
#: SI ``units`` of each of :data:`VARIABLES`.
UNITS = ("1", "W m-2 sr-1 m-1", "W m-2 sr-1 m-1", "W m-2 sr-1 m-1", "W m-2 sr-1 m-1")
#: Visibilities of the database, in its order (MODTRAN IHAZE 1 and 2). [km]
VISIBILITIES = (23.0, 5.0)
#: MODTRAN IHAZE code of each of :data:`VISIBILITIES` (the file's ``ihaze`` coordinate).
IHAZE = (1, 2)
#: Sensor altitudes of the database's tables. [m]
ALTITUDES = (2.0, 32.5, 75.0, 150.0, 225.0, 500.0, *np.arange(1000.0, 12001.0, 1000.0).tolist(),
             14000.0, 16000.0, 18000.0, 20000.0, 24500.0, 550000.0)
#: Ground ranges of the database's tables. [m]
GROUND_RANGES = (0.0, 100.0, 500.0, *np.arange(1000.0, 20001.0, 1000.0).tolist(),
                 *np.arange(22000.0, 80001.0, 2000.0).tolist(),
                 *np.arange(85000.0, 300001.0, 5000.0).tolist())
#: Sensor altitudes covered by the database. [m]
ALTITUDE_RANGE = (ALTITUDES[0], ALTITUDES[-1])
#: Ground ranges covered by the database. [m]
GROUND_RANGE_RANGE = (GROUND_RANGES[0], GROUND_RANGES[-1])
#: The altitudes with no table in between (24.5 km and 550 km): above the first, only ground
#: range 0 is interpolated, and the line-of-sight rules fall back to fixed ground range. [m]
ALTITUDE_GAP = (ALTITUDES[-2], ALTITUDES[-1])
#: Surface reflectance of the database's GRND_RFLT (the file's attribute
#: ``surface_reflectance_of_database``); the radiometry rescales GRND_RFLT by the target's
#: reflectance over it (its own constant ``xbsm.radiometry.DATABASE_REFLECTANCE``, which a
#: test checks equal to this).
SURFACE_REFLECTANCE = 0.15
#: The conditions a database file may hold as dimensions besides ``visibility``: name ->
#: (units, long_name). Each is a 1-d coordinate of the file, strictly increasing, placed
#: before ``visibility`` in the ``atmosphere`` variable's dims; each is a scenario parameter of
#: the same name (:func:`xbsm.scenario`) that must be one of the file's values. Codes
#: (``aerosol_model``, ``atmosphere_profile``) are whole numbers whose meanings the file
#: names in the coordinate's CF ``flag_values`` / ``flag_meanings``.
CONDITIONS = MappingProxyType({
    "aerosol_model": ("1", "aerosol model code (e.g. MODTRAN IHAZE: 1 rural, 4 maritime, "
                           "5 urban, 6 tropospheric; the file names its codes)"),
    "atmosphere_profile": ("1", "model atmosphere code (e.g. MODTRAN MODEL: 1 tropical, "
                                "2 mid-latitude summer, 3 mid-latitude winter, 4 sub-arctic "
                                "summer, 5 sub-arctic winter, 6 US standard 1976)"),
    "sun_zenith": ("rad", "solar zenith angle at the target"),
    "sun_azimuth": ("rad", "solar azimuth angle relative to the line of sight"),
    "day_of_year": ("1", "day of the year (Earth-Sun distance)"),
    "ground_altitude": ("m", "altitude of the target (ground) above sea level"),
})
#: Relative tolerance within which a scenario's condition equals one of the file's values
#: (a value converted from degrees twice the same way is equal; one typed differently is not).
CONDITION_RTOL = 1e-9
#: Shortest wavelength of the database. [m]
WAVELENGTH_MIN = 0.3e-6
#: Longest wavelength of the database. [m]
WAVELENGTH_MAX = 14.0e-6

#: pyBSM's conversion W/(sr cm^2 um) -> W/(m^2 sr m): the float32 value divided by
#: float32(1e-10) in float32 (NumPy 2 keeps float32 for float32 / Python float).
_DIVISOR = np.array([1.0, 1e-10, 1e-10, 1e-10, 1e-10], dtype=np.float32)
_DIVISOR.flags.writeable = False
_FILE_CHUNKS = MappingProxyType({})  # xarray: use the file's chunks


#: The database file :func:`use_database` made the default in this context (None: the
#: packaged one).
_ACTIVE = contextvars.ContextVar("xbsm_atmosphere_database", default=None)


def database_path(path=None) -> Path:
    """Path of the atmosphere database file.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Explicit file. Default: the file of the enclosing :func:`use_database`, else
        ``xbsm/data/atmosphere.nc`` (installed wheel), else ``atmosphere.nc`` at the top
        of a source checkout.

    Returns
    -------
    pathlib.Path
        Resolved path of an existing file.
    """
    if path is None:
        return _ACTIVE.get() or _default_database()
    return _existing([Path(path)])


@contextlib.contextmanager
def use_database(path):
    """Make another atmosphere database file the default inside a ``with`` block.

    Every function that reads the database without an explicit ``path`` (``xbsm.snr``,
    ``xbsm.niirs``, :func:`~xbsm.atmosphere.atmosphere_at`, studies and their provenance)
    uses ``path`` inside the block; the file is validated on entry
    (:func:`~xbsm.atmosphere.validate_database`) and checked against what the code
    supports (:func:`check_supported`); :func:`xbsm.scenario` then accepts any visibility
    between the file's smallest and largest (interpolated in extinction between them) and
    the values of its other conditions (:data:`CONDITIONS`), each a scenario parameter
    of its own name. The setting is a context variable: it holds in
    this thread (and in dask graphs built inside the block, which carry the resolved
    path), not in threads started elsewhere.

    Parameters
    ----------
    path : str or os.PathLike
        A file :func:`~xbsm.atmosphere.write_database` wrote.

    Yields
    ------
    pathlib.Path
        The resolved file.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        A file that breaks the database contract or that the code does not support yet.

    Examples
    --------
    >>> with xbsm.atmosphere.use_database("my_tables.nc"):  # doctest: +SKIP
    ...     result = xbsm.snr(sensor, scenario)
    """
    resolved = _existing([Path(path)])
    check_supported(resolved)
    token = _ACTIVE.set(resolved)
    try:
        yield resolved
    finally:
        _ACTIVE.reset(token)


def check_supported(path) -> None:
    """Raise ValueError if a valid database file needs what the code does not do yet.

    The parameter limits (:mod:`xbsm.params`) and the flags are the shipped database's:
    a file is supported where its coordinates lie inside them. Checked: the file is a
    valid database (:func:`~xbsm.atmosphere.validate_database`: any positive
    visibilities and any of the :data:`CONDITIONS` as further dimensions); altitudes within
    :data:`ALTITUDE_RANGE` and none strictly between the two of :data:`ALTITUDE_GAP`
    (the flags ``atmosphere_sparse`` and ``atmosphere_inconsistent`` and the
    line-of-sight rules' limit are that gap's); ground ranges within
    :data:`GROUND_RANGE_RANGE`; wavelengths within [:data:`WAVELENGTH_MIN`,
    :data:`WAVELENGTH_MAX`] (the band-edge limits); at least two wavelengths; the
    attribute ``surface_reflectance_of_database`` equal to :data:`SURFACE_REFLECTANCE`
    (0.15, :data:`xbsm.radiometry.DATABASE_REFLECTANCE`).

    Parameters
    ----------
    path : str or os.PathLike
        The database file.

    Raises
    ------
    ValueError
        Naming the coordinate, its values and what is supported.
    """
    from .tables import validate_database  # tables imports this module

    load_database(path)  # a clear error for a file that is not a database at all
    # the process's one handle of the file (xbsm._netcdf.open_dataset), not closed here:
    # closing it would close it under every other dataset reading the same file
    with LOCK:
        ds = open_dataset(path).load()
    validate_database(ds)
    altitude, ground_range, wavelength = (
        np.asarray(ds[name].values, dtype=np.float64)
        for name in ("altitude", "ground_range", "wavelength"))
    limits = (("altitude", altitude, ALTITUDE_RANGE, "m"),
              ("ground_range", ground_range, GROUND_RANGE_RANGE, "m"),
              ("wavelength", wavelength, (WAVELENGTH_MIN, WAVELENGTH_MAX), "m"))
    for name, values, (lo, hi), units in limits:
        if values[0] < lo or values[-1] > hi:
            raise ValueError(
                f"{path}: coordinate {name} spans [{values[0]:g}, {values[-1]:g}] {units}; xbsm "
                f"supports only [{lo:g}, {hi:g}] {units} yet (the parameter limits are the "
                "shipped database's)")
    with netcdf_file(path) as nc:
        reflectance = float(nc.getncattr("surface_reflectance_of_database"))
    if reflectance != SURFACE_REFLECTANCE:
        raise ValueError(
            f"{path}: attribute surface_reflectance_of_database is {reflectance!r}; xbsm "
            f"rescales GRND_RFLT by the target reflectance over {SURFACE_REFLECTANCE!r} "
            "(xbsm.radiometry.DATABASE_REFLECTANCE) and supports no other value yet")
    gap = altitude[(altitude > ALTITUDE_GAP[0]) & (altitude < ALTITUDE_GAP[1])]
    if gap.size:
        raise ValueError(
            f"{path}: altitude {gap[0]:g} m lies between {ALTITUDE_GAP[0]:g} m and "
            f"{ALTITUDE_GAP[1]:g} m; xbsm does not support tables there yet (its flags and "
            "line-of-sight rules assume the shipped database's gap)")
    if wavelength.size < 2:
        raise ValueError(f"{path}: coordinate wavelength has {wavelength.size} value(s); a "
                         "band needs at least two")


@functools.cache
def _default_database() -> Path:
    """The packaged database, found once per process."""
    package = Path(__file__).resolve().parent.parent
    return _existing([package / "data" / "atmosphere.nc", package.parent / "atmosphere.nc"])


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
    load_database(file)  # a clear error for a file that is not the database
    if isinstance(chunks, MappingProxyType):
        with netcdf_file(file) as nc:
            chunks = dict(zip(nc["atmosphere"].dimensions, nc["atmosphere"].chunking(),
                              strict=True))
    # open without dask, load the small coordinates, then chunk only the cube, so
    # that reading coordinates never needs a dask compute; under xbsm's lock, which the
    # lazy reads of the cube take too (xarray reads metadata outside its own: xbsm._netcdf)
    # (one handle of the file per process however many datasets are open: _netcdf.open_dataset)
    with LOCK:
        ds = open_dataset(file)
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
        component_units=("component", np.array(UNITS, dtype=object),
                         ds["component_units"].attrs),
    )


@dataclass(frozen=True, eq=False)  # compared and hashed by identity (a cache key)
class Database:
    """The whole database as numpy arrays (SI, float32), as :func:`load_database` reads it.

    A copy with tables left out (``dataclasses.replace`` with a subset of ``altitude``
    and the matching slices of ``cube`` and ``present``) is a database too: the
    leave-one-out recipe interpolates such copies with
    :func:`xbsm.atmosphere.interpolate_database`. The first axis of ``cube`` and
    ``present`` is the visibility axis, or with :attr:`conditions` the flattened sets of
    (conditions..., visibility).
    """

    visibility: np.ndarray  # [km]
    altitude: np.ndarray  # [m]
    ground_range: np.ndarray  # [m]
    wavelength: np.ndarray  # [m]
    cube: np.ndarray  # (set, altitude, ground_range, component, wavelength)
    present: np.ndarray  # (set, altitude, ground_range) bool
    #: The file's conditions besides visibility, ``((name, values), ...)`` in the file's
    #: order (:data:`CONDITIONS`); empty for the shipped database. The cube's first axis
    #: runs over the sets of conditions in C order of (conditions..., visibility): set
    #: ``i`` is ``numpy.unravel_index(i, (*sizes of the conditions, visibility.size))``, so
    #: without conditions it is the visibility axis.
    conditions: tuple = ()
    #: The file's ``title`` attribute: what made it (MODTRAN, 6S, a user's tables).
    title: str = ""


def load_database(path=None) -> Database:
    """The database in memory, read once per process (netCDF4, no dask).

    Parameters
    ----------
    path : str or os.PathLike, optional
        Database file (default: the packaged one, found once); see :func:`database_path`.

    Returns
    -------
    Database
        Coordinates (float64) and the cube in SI units (float32, read-only), converted as
        :func:`open_atmosphere` converts it; ``present`` where a table has an entry.

    Raises
    ------
    ValueError
        A file that is not a readable xbsm atmosphere database.
    """
    file = database_path(path)
    return _read(str(file), _stamp(file))


def _stamp(file: Path):
    """Size and modification time of ``file``: a rewritten file is read again."""
    try:
        stat = os.stat(file)
    except OSError:
        return None
    return stat.st_size, stat.st_mtime_ns


@functools.lru_cache(maxsize=4)
def _read(path: str, stamp=None) -> Database:
    """Read the database file ``path`` into memory (once per process, path and stamp)."""
    try:
        with netcdf_file(path) as nc:
            nc.set_auto_maskandscale(False)
            cube = nc["atmosphere"][...]
            coords = {name: np.asarray(nc[name][...], dtype=np.float64)
                      for name in ("visibility", "altitude", "ground_range", "wavelength")}
            conditions = tuple((name, np.asarray(nc[name][...], dtype=np.float64))
                               for name in nc["atmosphere"].dimensions[:-5])
            title = str(getattr(nc, "title", ""))
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
    cube = cube.reshape(-1, *cube.shape[-4:])  # the sets of conditions: one axis
    cube /= _DIVISOR[:, None]  # float32 / float32: pyBSM's bits; NaN stays NaN
    present = ~np.isnan(cube[:, :, :, 0, 0])
    cube.setflags(write=False)
    present.setflags(write=False)
    return Database(cube=cube, present=present, conditions=conditions, title=title, **coords)


def database_visibilities(path=None) -> tuple:
    """Visibilities of the atmosphere database in use, in its order [km].

    Parameters
    ----------
    path : str or os.PathLike, optional
        Database file; see :func:`database_path` (default: the one in use).

    Returns
    -------
    tuple of float
        The file's ``visibility`` coordinate (read without the cube, once per file).
    """
    file = database_path(path)
    return _visibilities(str(file), _stamp(file))


@functools.lru_cache(maxsize=4)
def _visibilities(path: str, stamp=None) -> tuple:
    """The ``visibility`` coordinate of ``path`` (or :func:`load_database`'s error)."""
    try:
        with netcdf_file(path) as nc:
            return tuple(float(v) for v in np.asarray(nc["visibility"][...], dtype=np.float64))
    except (OSError, RuntimeError, KeyError, IndexError):
        return tuple(float(v) for v in load_database(path).visibility)  # raises the error


def database_conditions(path=None) -> dict:
    """The conditions of the atmosphere database in use: name -> values it holds.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Database file; see :func:`database_path` (default: the one in use).

    Returns
    -------
    dict
        ``{"visibility": (...), **{condition: (...)}}``: the file's visibilities [km] and
        the values of each of its :data:`CONDITIONS` dimensions (in its units), in the
        file's order.
    """
    file = database_path(path)
    return dict(_conditions(str(file), _stamp(file)))


@functools.lru_cache(maxsize=4)
def _conditions(path: str, stamp=None) -> tuple:
    """``((name, values), ...)`` of ``path``: its visibility and condition coordinates."""
    try:
        with netcdf_file(path) as nc:
            names = (*nc["atmosphere"].dimensions[:-5], "visibility")
            return tuple((name, tuple(float(v) for v in np.asarray(nc[name][...], dtype=float)))
                         for name in names)
    except (OSError, RuntimeError, KeyError, IndexError):
        db = load_database(path)  # raises the error
        return (*((name, tuple(map(float, values))) for name, values in db.conditions),
                ("visibility", tuple(map(float, db.visibility))))


def visibility_range(visibilities) -> str:
    """Text giving the visibilities a database accepts: its range and what it holds.

    Parameters
    ----------
    visibilities : sequence of float
        The database's visibilities, in its (decreasing) order. [km]
    """
    visibilities = tuple(float(v) for v in visibilities)
    lo, hi = min(visibilities), max(visibilities)
    codes = " (MODTRAN IHAZE 1, 2)" if visibilities == VISIBILITIES else ""
    held = ", ".join(f"{v:g}" for v in visibilities)
    between = ("; between them the tables are interpolated in extinction"
               if len(visibilities) > 1 else "")
    return (f"[{lo:g}, {hi:g}] km: the atmosphere database holds {held} km{codes}"
            f"{between}")


def listed(name, values) -> str:
    """The values of condition ``name`` with its units, e.g. ``1, 4 [1]``."""
    return ", ".join(f"{float(v):.10g}" for v in values) + f" [{CONDITIONS[name][0]}]"


def describe_conditions(held) -> str:
    """Text listing the conditions a database holds.

    Parameters
    ----------
    held : dict
        As :func:`database_conditions` returns it.
    """
    parts = [f"visibility within {visibility_range(held['visibility'])}"]
    parts += [f"{name} one of {listed(name, values)}" for name, values in held.items()
              if name != "visibility"]
    return "; ".join(parts)


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
    return load_database(path).wavelength
