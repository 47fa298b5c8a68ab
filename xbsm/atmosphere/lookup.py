"""The public lookup: the database's spectra and validity flags at any scenarios.

:func:`atmosphere_at` labels the numpy kernel that validates the scenarios, brackets them
in the database, applies the named rule (:data:`~xbsm.atmosphere.rules.RULES`) and sets
the flags; :func:`interpolate_database` is the same interpolation on plain arrays of any
:class:`~xbsm.atmosphere.database.Database`; :func:`band_atmosphere` and
:func:`band_atmosphere_arrays` sample a sensor's band.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import xarray as xr

from .._kernels import apply_kernel, dataset
from .._metadata import named
from ..flags import flag, flag_attrs
from ..units import in_units
from ._profile import profile_of
from ._sight import ACROSS_PATH, ALONG_PATH, along_sight, line_of_sight
from .database import (
    ALTITUDE_GAP,
    COMPONENTS,
    LONG_NAMES,
    UNITS,
    VARIABLES,
    VISIBILITIES,
    database_path,
    database_wavelengths,
    load_database,
)
from .rules import INTERPOLATIONS, RULES, bracket, fixed_range

__all__ = [
    "RELATIVE_EDGE_TOLERANCE",
    "WAVELENGTH_ATTRS",
    "atmosphere_at",
    "band_atmosphere",
    "band_atmosphere_arrays",
    "band_wavelengths",
    "interpolate_database",
]

#: Values per component gathered at a time in the kernel: a block's temporaries (~0.5 MB
#: each) stay in cache; 2**16 is 1.5-2x faster per scenario than 2**21 (measured).
_BLOCK = 1 << 16


def _nearest_nodes(value, nodes):
    """Text naming the database nodes on either side of ``value``."""
    i = int(np.searchsorted(nodes, value))
    around = nodes[max(i - 1, 0): i + 1]
    return " and ".join(f"{n:g}" for n in around)


def _rule(interpolation):
    """The :class:`~xbsm.atmosphere.rules.Rule` named ``interpolation``."""
    rule = RULES.get(interpolation) if isinstance(interpolation, str) else None
    if rule is None:
        raise ValueError(
            f"interpolation must be one of {', '.join(map(repr, INTERPOLATIONS))}; "
            f"got {interpolation!r}"
        )
    return rule


def _validate(altitude, ground_range, visibility, rule, db):
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
        if rule.nodes_only:
            off = ~np.isin(values, nodes)
            if off.any():
                value = values[off].flat[0]
                raise ValueError(
                    f"{name}={float(value)!r} {units} is not a database node "
                    f"(interpolation={rule.name!r}); nearest nodes: "
                    f"{_nearest_nodes(value, nodes)} {units}"
                )
    bad = ~np.isin(visibility, db.visibility)
    if bad.any():
        codes = " (MODTRAN IHAZE 1, 2)" if tuple(db.visibility) == VISIBILITIES else ""
        raise ValueError(
            "visibility must be one of "
            + ", ".join(f"{v:g}" for v in db.visibility)
            + f" km{codes}; got {float(visibility[bad].flat[0])!r}"
        )


class _Scenarios(NamedTuple):
    """Validated flat scenarios, located in the database (numpy arrays).

    ``alt`` and ``gr`` are the :func:`~xbsm.atmosphere.rules.bracket` of each altitude and
    ground range, ``complete`` where all four fixed-range tables exist, ``along`` the
    line-of-sight tables (``_sight.Sight``, its ``usable`` also requiring those four) or
    None for a fixed-range rule.
    """

    shape: tuple
    altitude: np.ndarray
    vis: np.ndarray
    alt: tuple
    gr: tuple
    complete: np.ndarray
    along: object


def _scenarios(altitude, ground_range, visibility, rule, db) -> _Scenarios:
    """Validated flat inputs with their brackets and line-of-sight tables."""
    altitude, ground_range, visibility = (
        np.asarray(a, dtype=np.float64) for a in
        np.broadcast_arrays(altitude, ground_range, visibility))
    _validate(altitude, ground_range, visibility, rule, db)
    shape = altitude.shape
    altitude, ground_range = altitude.ravel(), ground_range.ravel()
    vis = np.searchsorted(-db.visibility, -visibility.ravel())  # visibility is descending
    alt = bracket(altitude, db.altitude, log=rule.log_altitude)
    gr = bracket(ground_range, db.ground_range)
    (a0, a1, _), (g0, g1, _), p = alt, gr, db.present
    complete = p[vis, a0, g0] & p[vis, a1, g0] & p[vis, a0, g1] & p[vis, a1, g1]
    along = None
    if rule.line_of_sight:
        along = along_sight(altitude, ground_range, vis, alt, db, rule)
        # never finite where others are NaN
        along = along._replace(usable=along.usable & complete)
    return _Scenarios(shape, altitude, vis, alt, gr, complete, along)


def _flags_of(scenarios):
    """Validity flags of each scenario from its :func:`_scenarios` brackets (numpy)."""
    shape, altitude, _, _, _, complete, along = scenarios
    out = np.where(complete, 0, flag("beyond_database"))
    sparse = (altitude > ALTITUDE_GAP[0]) & (altitude < ALTITUDE_GAP[1])
    out |= np.where(sparse, flag("atmosphere_sparse"), 0)
    # the 550 km tables are not a continuation of the 24.5 km ones (docs/atmosphere.md)
    out |= np.where(altitude > ALTITUDE_GAP[0], flag("atmosphere_inconsistent"), 0)
    if along is not None:
        fallback = complete & ~along.usable & (altitude <= ALTITUDE_GAP[0])
        out |= np.where(fallback, flag("atmosphere_fallback"), 0)
    return out.astype(np.int32).reshape(shape)


def _atmosphere_kernel(altitude, ground_range, visibility, wavelength, *, path, interpolation,
                       window):
    """Each component's spectrum and the validity flags of every scenario (numpy kernel).

    ``wavelength`` only gives the last axis of the spectra (it is the window's); ``path``
    is the resolved database file (resolved where the graph is built, so that a dask
    worker reads the file of the caller's :func:`~xbsm.atmosphere.use_database`), or
    None for the default one.
    """
    db = load_database(path)
    rule = RULES[interpolation]
    scenarios = _scenarios(altitude, ground_range, visibility, rule, db)
    spectra = _spectra_of(db, scenarios, rule, window)
    return (*np.moveaxis(spectra, -2, 0), _flags_of(scenarios))


def interpolate_database(db, altitude, ground_range, visibility, interpolation,
                         window=slice(None)):
    """Spectra of a database at each scenario, on plain arrays (numpy kernel).

    What :func:`atmosphere_at` computes, without labels or flags, for any
    :class:`~xbsm.atmosphere.database.Database`: the one :func:`load_database` reads, or
    a copy with tables left out (the leave-one-out recipe rebuilds a table from its
    neighbours this way).

    Parameters
    ----------
    db : Database
        The database.
    altitude, ground_range, visibility : float or numpy.ndarray
        Scenarios, broadcast together, in ``db``'s coverage. [m, m, km]
    interpolation : str
        One of :data:`~xbsm.atmosphere.rules.INTERPOLATIONS`.
    window : slice
        Wavelength indices of ``db`` to interpolate (default: all).

    Returns
    -------
    numpy.ndarray
        float64 (..., component, wavelength): the five components of
        :data:`~xbsm.atmosphere.database.COMPONENTS` in SI units, NaN beyond the database.

    Raises
    ------
    ValueError
        An unknown ``interpolation`` or a scenario outside ``db``'s coverage.
    """
    rule = _rule(interpolation)
    scenarios = _scenarios(altitude, ground_range, visibility, rule, db)
    return _spectra_of(db, scenarios, rule, window)


def _spectra_of(db, scenarios, rule, window):
    """Spectra at each scenario from its :func:`_scenarios` brackets (numpy)."""
    shape, _, vis, alt, gr, _, along = scenarios
    cube = db.cube[..., window]
    profile = profile_of(db).window(window) if rule.profile else None
    n_comp, n_wl = cube.shape[-2:]
    out = np.empty((vis.size, n_comp, n_wl), dtype=np.float64)
    step = max(1, _BLOCK // max(1, n_comp * n_wl))
    for start in range(0, vis.size, step):  # blocks of scenarios bound the memory
        s = slice(start, start + step)

        def fixed(components, where=slice(None), s=s):
            return fixed_range(cube, vis[s][where], [b[s][where] for b in alt],
                               [b[s][where] for b in gr], rule.value, components)

        if along is None:
            out[s] = fixed(None)
            continue
        out[s][:, ACROSS_PATH] = fixed(ACROSS_PATH)
        out[s][:, ALONG_PATH] = line_of_sight(cube, vis[s], along.block(s), fixed, profile)
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
        ``atmosphere_sparse`` between 24.5 km and 550 km, ``atmosphere_inconsistent``
        above 24.5 km, ``atmosphere_fallback`` where a line-of-sight rule fell back
        to ``"log-linear"``).

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
        from ..methods import PRESETS  # methods imports this module (its rule names)

        interpolation = PRESETS["accurate"].atmosphere_interpolation
    rule = _rule(interpolation)
    db = load_database(path)  # also checks the file at the call
    window = _wavelength_window(db.wavelength, wavelength_bounds)
    wavelength = db.wavelength[window]
    inputs = [_as_input(altitude, "altitude"), _as_input(ground_range, "ground_range"),
              _as_input(visibility, "visibility")]
    if not any(a.chunks is not None for a in inputs):
        # eager inputs: fail at the call, not inside the kernel
        _validate(*(np.asarray(a.values) for a in inputs), rule, db)

    wl = xr.DataArray(wavelength, dims="wavelength", attrs=dict(WAVELENGTH_ATTRS))
    wl = wl.assign_coords(wavelength=wl)
    *spectra, flags = apply_kernel(
        _atmosphere_kernel, *inputs, wl, core=[[], [], [], ["wavelength"]],
        outputs=[("wavelength",)] * len(COMPONENTS) + [()],
        dtype=[np.float64] * len(COMPONENTS) + [np.int32],
        path=str(database_path(path)), interpolation=interpolation,
        window=window)
    described = zip(VARIABLES, LONG_NAMES, UNITS, strict=True)
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
    db = load_database()
    window = _wavelength_window(db.wavelength, bounds)
    wavelength = db.wavelength[window]
    if wavelength.size < 2:
        return None
    *spectra, flags = _atmosphere_kernel(altitude, ground_range, visibility, wavelength,
                                         path=None, interpolation=interpolation, window=window)
    if samples is not None and not np.array_equal(samples, wavelength):
        spectra = [np.interp(samples, wavelength, s) for s in spectra]
        wavelength = samples
    return {"wavelength": wavelength, **dict(zip(VARIABLES, spectra, strict=True)),
            "flags": flags}
