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
    CONDITION_RTOL,
    CONDITIONS,
    LONG_NAMES,
    UNITS,
    VARIABLES,
    database_path,
    database_wavelengths,
    describe_conditions,
    listed,
    load_database,
    visibility_range,
)
from .rules import INTERPOLATIONS, RULES, bracket, fixed_range, interpolate

__all__ = [
    "RELATIVE_EDGE_TOLERANCE",
    "WAVELENGTH_ATTRS",
    "across_visibility",
    "atmosphere_at",
    "band_atmosphere",
    "band_atmosphere_arrays",
    "band_wavelengths",
    "condition_inputs",
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


def _validate(altitude, ground_range, visibility, rule, db, conditions=()):
    """Raise ValueError for inputs outside the database domain (numpy arrays).

    ``conditions`` holds the values of each of ``db.conditions``, in its order.
    """
    checks = (
        ("altitude", altitude, db.altitude, "m"),
        ("ground_range", ground_range, db.ground_range, "m"),
    )
    for name, values, nodes, units in checks:
        bad = ~((values >= nodes[0]) & (values <= nodes[-1]))
        if bad.any():
            raise ValueError(
                f"{name} must be within [{nodes[0]:g}, {nodes[-1]:g}] {units} (the "
                f"atmosphere database's range); got {float(values[bad].flat[0])!r}"
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
    bad = ~((visibility >= db.visibility[-1]) & (visibility <= db.visibility[0]))
    if bad.any():
        raise ValueError(f"visibility must be within {visibility_range(db.visibility)}; got "
                         f"{float(visibility[bad].flat[0])!r}")
    if rule.nodes_only:
        off = ~np.isin(visibility, db.visibility)
        if off.any():
            raise ValueError(
                f"visibility={float(visibility[off].flat[0])!r} km is not a database node "
                f"(interpolation={rule.name!r}); the database holds "
                + ", ".join(f"{v:g}" for v in db.visibility) + " km")
    for (name, held), values in zip(db.conditions, conditions, strict=True):
        bad = ~_held(values, held)
        if bad.any():
            raise ValueError(f"{name} must be one of {listed(name, held)}; got "
                             f"{float(values[bad].flat[0])!r}")


def _holdings(db) -> str:
    """Text listing every condition ``db`` holds (:func:`describe_conditions`)."""
    return describe_conditions({**dict(db.conditions), "visibility": db.visibility})


def _held(values, held):
    """Where ``values`` equal one of ``held`` within :data:`CONDITION_RTOL`."""
    return np.isclose(values[..., None], held, rtol=CONDITION_RTOL, atol=0.0).any(axis=-1)


def _condition_sets(conditions, db, n):
    """Offset of each scenario's set of conditions in the cube's first axis (numpy)."""
    index = np.zeros(n, dtype=np.intp)
    for (_, held), values in zip(db.conditions, conditions, strict=True):
        nearest = np.abs(values.ravel()[:, None] - held).argmin(axis=1)
        index = index * held.size + nearest
    return index * db.visibility.size


def condition_inputs(conditions, db) -> list:
    """The value of each condition of ``db``, in its order, from a name -> value mapping.

    A condition the database holds with one value may be omitted; one it holds with more
    must be given; a condition it does not hold is refused. The messages list what the
    database holds.
    """
    conditions = dict(conditions or {})
    held = dict(db.conditions)
    for name in conditions:
        if name not in held:
            raise ValueError(
                f"{name}: the atmosphere database in use holds no {name} dimension (it holds "
                f"{_holdings(db)}); use a database generated for several {name} values "
                "(xbsm.atmosphere.use_database) or leave it out")
    out = []
    for name, values in db.conditions:
        if name in conditions:
            out.append(conditions[name])
        elif values.size == 1:
            out.append(float(values[0]))
        else:
            raise ValueError(
                f"the atmosphere database in use holds {name} = {listed(name, values)}: give "
                f"the scenario parameter {name} (it holds {_holdings(db)})")
    return out


class _Located(NamedTuple):
    """Flat scenarios at one visibility table each, located in the database (numpy).

    ``vis`` is each scenario's set of conditions (the cube's first axis), ``alt`` and ``gr``
    the :func:`~xbsm.atmosphere.rules.bracket` of each altitude and ground range,
    ``complete`` where all four fixed-range tables exist, ``along`` the line-of-sight
    tables (``_sight.Sight``, its ``usable`` also requiring those four) or None for a
    fixed-range rule.
    """

    altitude: np.ndarray
    vis: np.ndarray
    alt: tuple
    gr: tuple
    complete: np.ndarray
    along: object


class _Scenarios(NamedTuple):
    """Validated flat scenarios, located at their visibility tables.

    Each is located at its (larger) bracketing visibility's table (``primary``); those
    between two visibilities (indices ``between``, ``weight`` the lower visibility's weight
    in 1/visibility) also at the lower one (``secondary``, or None).
    """

    shape: tuple
    primary: _Located
    secondary: _Located | None
    between: np.ndarray
    weight: np.ndarray


def _located(altitude, ground_range, vis, rule, db) -> _Located:
    """Flat scenarios' brackets and line-of-sight tables at the tables ``vis``."""
    alt = bracket(altitude, db.altitude, log=rule.log_altitude)
    gr = bracket(ground_range, db.ground_range)
    (a0, a1, _), (g0, g1, _), p = alt, gr, db.present
    complete = p[vis, a0, g0] & p[vis, a1, g0] & p[vis, a0, g1] & p[vis, a1, g1]
    along = None
    if rule.line_of_sight:
        along = along_sight(altitude, ground_range, vis, alt, db, rule)
        # never finite where others are NaN
        along = along._replace(usable=along.usable & complete)
    return _Located(altitude, vis, alt, gr, complete, along)


def _scenarios(altitude, ground_range, visibility, rule, db, conditions=()) -> _Scenarios:
    """Validated flat inputs with their brackets and line-of-sight tables.

    Visibility is bracketed in its inverse (extinction grows as 1/visibility, Koschmieder):
    on a database visibility the scenario has one table set and no ``secondary``.
    """
    arrays = np.broadcast_arrays(altitude, ground_range, visibility, *conditions)
    altitude, ground_range, visibility, *conditions = (
        np.asarray(a, dtype=np.float64) for a in arrays)
    _validate(altitude, ground_range, visibility, rule, db, conditions)
    shape = altitude.shape
    altitude, ground_range = altitude.ravel(), ground_range.ravel()
    sets = _condition_sets(conditions, db, altitude.size)
    v0, v1, weight = bracket(1.0 / visibility.ravel(), 1.0 / db.visibility)
    primary = _located(altitude, ground_range, sets + v0, rule, db)
    between = np.flatnonzero(weight > 0.0)
    secondary = None
    if between.size:
        secondary = _located(altitude[between], ground_range[between],
                             sets[between] + v1[between], rule, db)
    return _Scenarios(shape, primary, secondary, between, weight[between])


def _located_flags(located):
    """Validity flags of flat located scenarios (numpy)."""
    altitude, _, _, _, complete, along = located
    out = np.where(complete, 0, flag("beyond_database"))
    sparse = (altitude > ALTITUDE_GAP[0]) & (altitude < ALTITUDE_GAP[1])
    out |= np.where(sparse, flag("atmosphere_sparse"), 0)
    # the 550 km tables are not a continuation of the 24.5 km ones (docs/atmosphere.md)
    out |= np.where(altitude > ALTITUDE_GAP[0], flag("atmosphere_inconsistent"), 0)
    if along is not None:
        fallback = complete & ~along.usable & (altitude <= ALTITUDE_GAP[0])
        out |= np.where(fallback, flag("atmosphere_fallback"), 0)
    return out


def _flags_of(scenarios):
    """Validity flags of each scenario from its :func:`_scenarios` brackets (numpy)."""
    out = _located_flags(scenarios.primary)
    if scenarios.secondary is not None:
        out[scenarios.between] |= (_located_flags(scenarios.secondary)
                                   | flag("visibility_interpolated"))
    return out.astype(np.int32).reshape(scenarios.shape)


def _atmosphere_kernel(altitude, ground_range, visibility, *conditions_and_wavelength, path,
                       interpolation, window):
    """Each component's spectrum and the validity flags of every scenario (numpy kernel).

    After ``visibility`` come the values of the database's conditions, in its order, then
    ``wavelength``, which only gives the last axis of the spectra (it is the window's);
    ``path`` is the resolved database file (resolved where the graph is built, so that a
    dask worker reads the file of the caller's :func:`~xbsm.atmosphere.use_database`), or
    None for the default one.
    """
    *conditions, _ = conditions_and_wavelength
    db = load_database(path)
    rule = RULES[interpolation]
    scenarios = _scenarios(altitude, ground_range, visibility, rule, db, conditions)
    spectra = _spectra_of(db, scenarios, rule, window)
    # each component's spectra (views; np.moveaxis costs a single scenario 5 us)
    return (*(spectra[..., k, :] for k in range(spectra.shape[-2])), _flags_of(scenarios))


def interpolate_database(db, altitude, ground_range, visibility, interpolation,
                         window=slice(None), conditions=None):
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
    conditions : dict, optional
        Condition name -> value(s) for a database with condition dims (as for
        :func:`atmosphere_at`).

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
    values = condition_inputs(conditions, db)
    scenarios = _scenarios(altitude, ground_range, visibility, rule, db, values)
    return _spectra_of(db, scenarios, rule, window)


def across_visibility(near, far, weight):
    """The spectra between two visibility tables: the rule in extinction (numpy).

    Parameters
    ----------
    near, far : numpy.ndarray
        (scenario, component, wavelength) at the larger and the smaller bracketing
        visibility ``V0 > V1``, each already interpolated in altitude and ground range.
    weight : numpy.ndarray
        (scenario,) ``w = (1/V - 1/V0) / (1/V1 - 1/V0)``: the weight of ``far`` in the
        extinction coordinate 1/visibility.

    Returns
    -------
    numpy.ndarray
        TRANS, SURF_EMIS and GRND_RFLT (attenuated along the path) log-linear in ``w``:
        ``ln T = (1 - w) ln T0 + w ln T1``, the optical depth at fixed path linear in
        extinction (linear where a value is 0); PTH_THRML and SOL_SCAT linear in the
        fraction of the transmission lost, ``u = (T0 - T) / (T0 - T1)`` per wavelength
        (``w`` where ``T0 == T1``), so that a path radiance of Koschmieder's airlight form
        ``L = L_inf (1 - T)`` is reproduced exactly.
    """
    out = np.empty_like(near)
    out[:, ALONG_PATH] = interpolate(near[:, ALONG_PATH], far[:, ALONG_PATH], weight, "log")
    t0, t1, t = near[:, 0], far[:, 0], out[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        lost = np.clip((t0 - t) / (t0 - t1), 0.0, 1.0)
    lost = np.where(t0 != t1, lost, weight[:, None])
    near_path, far_path = near[:, ACROSS_PATH], far[:, ACROSS_PATH]
    out[:, ACROSS_PATH] = near_path + lost[:, None, :] * (far_path - near_path)
    return out


def _spectra_of(db, scenarios, rule, window):
    """Spectra at each scenario from its :func:`_scenarios` brackets (numpy)."""
    out = _located_spectra(db, scenarios.primary, rule, window)
    if scenarios.secondary is not None:
        far = _located_spectra(db, scenarios.secondary, rule, window)
        out[scenarios.between] = across_visibility(out[scenarios.between], far,
                                                   scenarios.weight)
    return out.reshape(scenarios.shape + out.shape[-2:])


def _located_spectra(db, located, rule, window):
    """Flat spectra (scenario, component, wavelength) at located scenarios (numpy)."""
    _, vis, alt, gr, _, along = located
    cube = db.cube[..., window]
    profile = profile_of(db, window) if rule.profile else None
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
    return out


WAVELENGTH_ATTRS = MappingProxyType({"units": "m", "long_name": "wavelength",
                                     "standard_name": "radiation_wavelength"})
"""The attributes of the ``wavelength`` coordinate of every spectral result."""

_INPUT_UNITS = MappingProxyType({"altitude": "m", "ground_range": "m", "visibility": "km"})


def _as_input(value, name):
    """Convert a float or DataArray input to a float64 DataArray in the database's units."""
    units = _INPUT_UNITS[name] if name in _INPUT_UNITS else CONDITIONS[name][0]
    if not isinstance(value, xr.DataArray):
        value = xr.DataArray(np.asarray(value))
    for dim in ("wavelength", "component"):
        if dim in value.dims:
            raise ValueError(f"{name} must not have the dimension {dim!r}")
    if value.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be a real number or an xr.DataArray of real numbers; "
                         f"got dtype {value.dtype}")
    return in_units(name, value.astype(np.float64), units)


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
                  wavelength_bounds=None, path=None, conditions=None) -> xr.Dataset:
    """Atmospheric transmittance and path radiances for each scenario.

    Parameters
    ----------
    altitude : float or xr.DataArray
        Sensor altitude above ground level, within [2, 550000]. [m]
    ground_range : float or xr.DataArray
        Ground range from the sensor nadir point to the target, within [0, 300000]. [m]
    visibility : float or xr.DataArray
        Meteorological range within the database's smallest and largest visibility (the
        shipped one: 5 to 23 km, generated at 23, MODTRAN IHAZE 1, and 5, IHAZE 2);
        between two of the database's visibilities the spectra are interpolated in
        extinction (:func:`across_visibility`) and flagged ``visibility_interpolated``. [km]
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
    conditions : dict, optional
        For a database with condition dims (:data:`~xbsm.atmosphere.database.CONDITIONS`):
        name -> float or xr.DataArray, each one of the values the database holds (in that
        condition's units); a condition the database holds with a single value may be left
        out. A condition the database does not hold is refused.

    Returns
    -------
    xr.Dataset
        float64 ``transmission`` [1], ``path_thermal``, ``surface_emission``,
        ``solar_scatter``, ``ground_reflected`` [W m-2 sr-1 m-1] on the union of
        the input dimensions plus ``wavelength``, and int32 ``flags`` (CF flag
        variable; ``beyond_database`` where the spectra are NaN,
        ``atmosphere_sparse`` between 24.5 km and 550 km, ``atmosphere_inconsistent``
        above 24.5 km, ``atmosphere_fallback`` where a line-of-sight rule fell back
        to ``"log-linear"``, ``visibility_interpolated`` between two database
        visibilities).

    Raises
    ------
    ValueError
        An input outside the database domain (a visibility outside its range, a condition
        value it does not hold: the message lists what it holds), an off-node input with
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
    inputs += [_as_input(value, name) for (name, _), value in
               zip(db.conditions, condition_inputs(conditions, db), strict=True)]
    if not any(a.chunks is not None for a in inputs):
        # eager inputs: fail at the call, not inside the kernel
        arrays = [np.asarray(a.values) for a in inputs]  # each checked on its own dims
        _validate(*arrays[:3], rule, db, arrays[3:])

    wl = xr.DataArray(wavelength, dims="wavelength", attrs=dict(WAVELENGTH_ATTRS))
    wl = wl.assign_coords(wavelength=wl)
    *spectra, flags = apply_kernel(
        _atmosphere_kernel, *inputs, wl, core=[[]] * len(inputs) + [["wavelength"]],
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
        source=f"{db.title or 'atmosphere database'} ({database_path(path).name})",
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
    if band_edges not in ("exact", "interpolated"):
        raise ValueError(f"band_edges must be 'exact' or 'interpolated'; got {band_edges!r}")
    grid = database_wavelengths(path)
    tol = RELATIVE_EDGE_TOLERANCE
    if wavelength_min < grid[0] * (1 - tol) or wavelength_max > grid[-1] * (1 + tol):
        # only a user's file can cover less than the parameters' limits (the shipped one
        # spans them): refused rather than integrated over part of the band
        raise ValueError(
            f"the band [wavelength_min, wavelength_max] = [{wavelength_min:g}, "
            f"{wavelength_max:g}] m reaches outside the atmosphere database's wavelengths "
            f"[{grid[0]:g}, {grid[-1]:g}] m; use a file that covers the band")
    if band_edges == "exact":
        return None, (wavelength_min, wavelength_max)
    inside = grid[(grid > wavelength_min * (1 + tol)) & (grid < wavelength_max * (1 - tol))]
    lo_index = max(np.searchsorted(grid, wavelength_min * (1 + tol), side="right") - 1, 0)
    hi_index = min(np.searchsorted(grid, wavelength_max * (1 - tol)), grid.size - 1)
    # numpy.isclose's test with atol 0, on two scalars (isclose costs 14 us a call)
    lo_near = abs(grid[lo_index] - wavelength_min) <= tol * abs(wavelength_min)
    hi_near = abs(grid[hi_index] - wavelength_max) <= tol * abs(wavelength_max)
    lo = grid[lo_index] if lo_near else wavelength_min
    hi = grid[hi_index] if hi_near else wavelength_max
    samples = np.concatenate([[lo], inside, [hi]])
    return samples, (grid[lo_index], grid[hi_index])


def band_atmosphere(altitude, ground_range, visibility, wavelength_min, wavelength_max, *,
                    interpolation, band_edges, path=None, conditions=None) -> xr.Dataset:
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
    conditions : dict, optional
        As for :func:`atmosphere_at`.

    Returns
    -------
    xr.Dataset
        Atmosphere components over ``wavelength`` and the scenario dims, plus ``flags``.
    """
    samples, bounds = band_wavelengths(float(wavelength_min), float(wavelength_max),
                                       band_edges, path)
    atm = atmosphere_at(altitude, ground_range, visibility, interpolation=interpolation,
                        wavelength_bounds=bounds, path=path, conditions=conditions)
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
                           *, interpolation, band_edges, conditions=None) -> dict | None:
    """:func:`band_atmosphere` of one eager scenario on plain arrays, or None.

    Returns ``wavelength``, the spectra of :data:`VARIABLES` over it and ``flags``; None
    for a band that spans fewer than two database wavelengths, or conditions the database
    does not match (:func:`band_atmosphere` raises the error). The inputs are in the
    database's units and already checked; ``conditions`` as for :func:`atmosphere_at`.
    """
    samples, bounds = band_wavelengths(float(wavelength_min), float(wavelength_max),
                                       band_edges)
    db = load_database()
    window = _wavelength_window(db.wavelength, bounds)
    wavelength = db.wavelength[window]
    if wavelength.size < 2:
        return None
    try:
        values = condition_inputs(conditions, db)
    except ValueError:
        return None
    *spectra, flags = _atmosphere_kernel(altitude, ground_range, visibility, *values,
                                         wavelength, path=None, interpolation=interpolation,
                                         window=window)
    if samples is not None and not np.array_equal(samples, wavelength):
        spectra = [np.interp(samples, wavelength, s) for s in spectra]
        wavelength = samples
    return {"wavelength": wavelength, **dict(zip(VARIABLES, spectra, strict=True)),
            "flags": flags}
