"""Anyone's tables as an atmosphere database: build, validate and write the cube.

The database file is a contract (``docs/atmosphere.md``, "The database file"): one
float32 variable ``atmosphere`` on (visibility, altitude, ground_range, component,
wavelength), optionally after condition dims
(:data:`~xbsm.atmosphere.database.CONDITIONS`), in the file's units (TRANS ``1``,
radiances ``W sr-1 cm-2 um-1``), NaN where a table has no entry.
:func:`from_tables` turns arrays (or a DataArray) into that cube as
an :class:`xarray.Dataset` and validates it; :func:`validate_database` checks a cube (one
:func:`from_tables` made, or the file opened with :func:`xarray.open_dataset`) and names
the coordinate or the cell that breaks the contract; :func:`write_database` writes it as
``recipes/build_atmosphere.py`` writes the shipped ``atmosphere.nc``: a fixed order, no
timestamps, one zlib chunk per (visibility, altitude) slab. The shipped file rebuilt
through :func:`write_database` is byte-identical to it (``tests/atmosphere/test_tables.py``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from .._netcdf import netcdf_file
from ..constants import EARTH_RADIUS
from .database import COMPONENTS, CONDITIONS

__all__ = [
    "DIMS",
    "FILE_UNITS",
    "REQUIRED_ATTRS",
    "from_tables",
    "horizon",
    "validate_database",
    "write_database",
]

#: Dims of the ``atmosphere`` variable, in the file's order.
DIMS = ("visibility", "altitude", "ground_range", "component", "wavelength")
#: Units of each of :data:`~xbsm.atmosphere.database.COMPONENTS` in the file (UDUNITS).
FILE_UNITS = ("1", "W sr-1 cm-2 um-1", "W sr-1 cm-2 um-1", "W sr-1 cm-2 um-1",
              "W sr-1 cm-2 um-1")
#: Global attributes every database file carries: what it is, where its numbers come
#: from, and the surface reflectance its GRND_RFLT was computed for (xbsm rescales
#: GRND_RFLT by the target's reflectance over this value).
REQUIRED_ATTRS = ("title", "source", "surface_reflectance_of_database")
#: Units of each coordinate in the file.
_COORD_UNITS = {"visibility": "km", "altitude": "m", "ground_range": "m", "wavelength": "m"}
_COORD_ATTRS = {
    "visibility": {"units": "km", "long_name": "meteorological range (visibility)",
                   "standard_name": "visibility_in_air"},
    "altitude": {"units": "m", "long_name": "sensor altitude above ground level",
                 "standard_name": "height", "positive": "up"},
    "ground_range": {"units": "m",
                     "long_name": "ground range from the sensor nadir point to the target",
                     "comment": "great-circle distance on the spherical Earth"},
    "wavelength": {"units": "m", "long_name": "wavelength",
                   "standard_name": "radiation_wavelength"},
}
#: Wavelengths a database may hold: metres, so a grid in micrometres is caught. [m]
_WAVELENGTH_LIMITS = (1e-7, 1e-4)
#: A table may reach past the geometric horizon as far as the horizon of standard
#: refraction (an Earth of 4/3 the radius: sqrt(4/3) = 1.155 x as far), which a
#: radiative-transfer code with refraction may trace; a table further out is an error.
_REFRACTED_RADIUS = 4.0 / 3.0
_ORDER = ("visibility", "ihaze", "altitude", "ground_range", "component", "component_units",
          "component_long_name", "wavelength")


def horizon(altitude, radius_factor=1.0):
    """Ground range of the spherical-Earth horizon seen from ``altitude`` [m].

    The sphere's radius is :data:`xbsm.constants.EARTH_RADIUS` times ``radius_factor``
    (4/3: the effective Earth of standard refraction). [m]
    """
    altitude = np.asarray(altitude, dtype=np.float64)
    radius = EARTH_RADIUS * radius_factor
    return radius * np.arccos(radius / (radius + altitude))


def from_tables(tables, *, visibility=None, altitude=None, ground_range=None,
                wavelength=None, ihaze=None, ihaze_meanings=None, component_units=FILE_UNITS,
                component_long_names=None, attrs=None, variable_attrs=None,
                coordinate_attrs=None, conditions=None) -> xr.Dataset:
    """An atmosphere cube in the database file's schema, validated.

    Parameters
    ----------
    tables : numpy.ndarray or xr.DataArray
        float32-representable values on (conditions..., visibility, altitude,
        ground_range, component, wavelength), components in the order of
        :data:`~xbsm.atmosphere.database.COMPONENTS` (TRANS, PTH_THRML, SURF_EMIS,
        SOL_SCAT, GRND_RFLT), in ``component_units``; NaN (the whole spectrum) where a
        table has no entry. A DataArray with those dims may carry the coordinates (the
        keyword arguments then default to them) and ``attrs`` (the conditions).
        The leading condition dims, if any, are ``conditions``' (or the DataArray's).
    visibility : sequence of float
        Meteorological range of each table set, strictly decreasing. [km]
    altitude : sequence of float
        Sensor altitudes above ground, strictly increasing. [m]
    ground_range : sequence of float
        Ground ranges from nadir to the target, strictly increasing, from 0. [m]
    wavelength : sequence of float
        Wavelength grid, strictly increasing, in metres. [m]
    ihaze : sequence of int, optional
        MODTRAN IHAZE (aerosol model) code of each visibility: the ``ihaze``
        coordinate; with ``ihaze_meanings`` (one word per code) its CF flag attributes.
    component_units : sequence of str
        Units of each component; must be :data:`FILE_UNITS` (the reader converts
        radiances to SI by dividing by float32(1e-10)): convert W m-2 sr-1 m-1 to the
        file's units by multiplying by 1e-10.
    component_long_names : sequence of str, optional
        Description of each component (the ``component_long_name`` coordinate).
    attrs : dict, optional
        Global attributes: :data:`REQUIRED_ATTRS` and the conditions that generated the
        tables (e.g. ``modtran_*`` settings), in the order they are to be written; they
        update the DataArray's own ``attrs`` (which are taken as global attributes too).
    variable_attrs : dict, optional
        Attributes of the ``atmosphere`` variable (default: a ``long_name``).
    coordinate_attrs : dict, optional
        Coordinate name -> attributes added to (or replacing) its standard ones (units,
        long_name...), e.g. a ``comment``; units cannot be changed. A code condition
        (``aerosol_model``, ``atmosphere_profile``) names its codes here with CF
        ``flag_values`` and ``flag_meanings``.
    conditions : dict, optional
        Condition name (one of :data:`~xbsm.atmosphere.database.CONDITIONS`) -> its
        values, strictly increasing, in that condition's units, in the order of the leading
        dims of ``tables``: each becomes a dimension of the cube that a scenario selects by
        the parameter of the same name. Default: none (or a DataArray's leading dims).

    Returns
    -------
    xr.Dataset
        ``atmosphere`` (float32) and its coordinates as the file holds them.

    Raises
    ------
    ValueError
        Anything :func:`validate_database` rejects, or a shape that does not match the
        coordinates.
    """
    given = {"visibility": visibility, "altitude": altitude, "ground_range": ground_range,
             "wavelength": wavelength}
    conditions = dict(conditions or {})
    values, coords, ihaze, merged_attrs = _read_input(tables, given, ihaze, attrs, conditions)
    dims = (*conditions, *DIMS)
    cube = _float32_cube(values, coords, dims)
    ds_coords = _cube_coordinates(coords, component_units, component_long_names, ihaze,
                                  ihaze_meanings, coordinate_attrs, conditions)
    var_attrs = dict(variable_attrs or {
        "long_name": "path transmittance and radiance components (raw values in the file's "
                     "units)"})
    ds = xr.Dataset({"atmosphere": (dims, cube, var_attrs)}, coords=ds_coords,
                    attrs=merged_attrs)
    validate_database(ds)
    return ds


def _read_input(tables, given, ihaze, attrs, conditions):
    """Values, numeric coordinates, IHAZE codes and global attributes of the input.

    A DataArray's own coordinates and attributes fill what :func:`from_tables` was not given;
    its leading dims are conditions (added to ``conditions`` in place).
    """
    merged_attrs = {}
    if isinstance(tables, xr.DataArray):
        leading = tables.dims[:-len(DIMS)] if len(tables.dims) > len(DIMS) else ()
        if tables.dims[len(leading):] != DIMS or (conditions and tuple(conditions) != leading):
            raise ValueError(f"tables must have the dims {(*conditions, *DIMS)} in this "
                             f"order; got {tables.dims}")
        for name in leading:
            if name not in conditions and name in tables.coords:
                conditions[name] = tables[name].values
        missing = [name for name in leading if name not in conditions]
        if missing:
            raise ValueError(f"tables' condition dim(s) {', '.join(missing)} need coordinates")
        for name in given:
            if given[name] is None and name in tables.coords:
                given[name] = tables[name].values
        if ihaze is None and "ihaze" in tables.coords:
            ihaze = tables["ihaze"].values
        merged_attrs.update(tables.attrs)
        values = tables.values
    else:
        values = np.asarray(tables)
    merged_attrs.update(attrs or {})
    missing = [name for name, value in given.items() if value is None]
    if missing:
        raise ValueError(f"from_tables needs the coordinate(s) {', '.join(missing)} (as "
                         "keyword arguments or coordinates of the DataArray)")
    unknown = [name for name in conditions if name not in CONDITIONS]
    if unknown:
        raise ValueError(f"conditions must be among {', '.join(CONDITIONS)}; got "
                         f"{', '.join(map(repr, unknown))}")
    coords = {name: np.asarray(value, dtype=np.float64) for name, value in given.items()}
    coords.update({name: np.asarray(value, dtype=np.float64)
                   for name, value in conditions.items()})
    return values, coords, ihaze, merged_attrs


def _float32_cube(values, coords, dims=DIMS):
    """``values`` as float32, once their shape matches ``coords`` and every value fits."""
    if values.ndim != len(dims):
        raise ValueError(f"tables must have {len(dims)} dims {dims}; got shape {values.shape}")
    expected = tuple(len(COMPONENTS) if dim == "component" else coords[dim].size
                     for dim in dims)
    if values.shape != expected:
        raise ValueError(f"tables has shape {values.shape}; the coordinates give {expected} "
                         f"({', '.join(dims)})")
    if values.dtype.kind != "f":
        raise ValueError(f"tables must be floating point; got dtype {values.dtype}")
    cube = values.astype(np.float32)
    with np.errstate(over="ignore", invalid="ignore"):
        overflow = np.isfinite(values) & ~np.isfinite(cube)
    if overflow.any():
        raise ValueError(f"tables value at {_cell(np.argwhere(overflow)[0], coords, dims)} "
                         "does not fit in float32")
    return cube


def _cube_coordinates(coords, component_units, component_long_names, ihaze, ihaze_meanings,
                      coordinate_attrs, conditions=()):
    """The cube's coordinates with their attributes, as the file holds them."""
    ds_coords = {name: (name, coords[name], {"units": CONDITIONS[name][0],
                                             "long_name": CONDITIONS[name][1]})
                 for name in conditions}
    ds_coords.update({name: (name, coords[name], dict(_COORD_ATTRS[name]))
                      for name in ("visibility", "altitude", "ground_range", "wavelength")})
    ds_coords["component"] = ("component", np.array(COMPONENTS, dtype=object),
                              {"long_name": "MODTRAN tape 7 column name"})
    ds_coords["component_units"] = ("component", np.array(list(component_units), dtype=object),
                                    {"long_name": "units of the component (UDUNITS string)"})
    if component_long_names is not None:
        ds_coords["component_long_name"] = (
            "component", np.array(list(component_long_names), dtype=object),
            {"long_name": "description of the component"})
    if ihaze is not None:
        codes = np.asarray(ihaze, dtype=np.int32)
        ihaze_attrs = {"units": "1", "long_name": "MODTRAN IHAZE aerosol model code"}
        if ihaze_meanings is not None:
            ihaze_attrs.update(flag_values=codes, flag_meanings=" ".join(ihaze_meanings))
        ds_coords["ihaze"] = ("visibility", codes, ihaze_attrs)
    for name, extra in (coordinate_attrs or {}).items():
        if name not in ds_coords:
            raise ValueError(f"coordinate_attrs names {name!r}, not a coordinate of the cube "
                             f"({', '.join(ds_coords)})")
        ds_coords[name][2].update(extra)
    return ds_coords


def _cell(index, coords, dims=DIMS):
    """Text naming the cell ``index`` of the cube by its coordinates.

    With conditions, ``index`` may start with the flattened set of (conditions...,
    visibility) (as :func:`_check_values` indexes), named here by each condition.
    """
    conditions = list(dims[:-len(DIMS)])
    if conditions and len(index) <= len(DIMS):
        sizes = [coords[name].size for name in (*conditions, "visibility")]
        index = (*np.unravel_index(int(index[0]), sizes), *index[1:])
    parts = []
    for dim, i in zip(dims, index, strict=False):
        i = int(i)
        if dim == "component":
            parts.append(f"component={COMPONENTS[i]}")
        elif dim == "wavelength":
            parts.append(f"wavelength={float(np.asarray(coords[dim])[i]):.6g}")
        else:
            parts.append(f"{dim}={float(np.asarray(coords[dim])[i])!r}")
    return "(" + ", ".join(parts) + ")"


def _strict(name, values, decreasing=False):
    """Raise unless ``values`` is a finite, strictly monotone 1-d array."""
    if values.ndim != 1 or values.size == 0:
        raise ValueError(f"coordinate {name} must be a non-empty 1-d array; got shape "
                         f"{values.shape}")
    if not np.isfinite(values).all():
        i = int(np.flatnonzero(~np.isfinite(values))[0])
        raise ValueError(f"coordinate {name} must be finite; {name}[{i}] is {float(values[i])!r}")
    step = np.diff(values)
    bad = step >= 0 if decreasing else step <= 0
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        order = "decreasing" if decreasing else "increasing"
        raise ValueError(f"coordinate {name} must be strictly {order}; {name}[{i}] = "
                         f"{float(values[i])!r} then {name}[{i + 1}] = {float(values[i + 1])!r}")


def validate_database(cube: xr.Dataset) -> None:
    """Raise ValueError naming what breaks the database contract, else return None.

    Checks: the variable ``atmosphere`` (float32) on :data:`DIMS`; the coordinates strictly
    monotone (visibility decreasing, the others increasing), finite, in their units
    (visibility > 0 km, altitude > 0 m, ground range from 0 m, wavelength in metres);
    components :data:`~xbsm.atmosphere.database.COMPONENTS` in :data:`FILE_UNITS`;
    :data:`REQUIRED_ATTRS`; each (visibility, altitude, ground range) cell either wholly
    finite or wholly NaN; at each (visibility, altitude) the present ground ranges a prefix
    of the grid that does not pass the horizon (standard refraction, :func:`horizon` with
    ``radius_factor=4/3``); TRANS in [0, 1] and
    radiances >= 0 where present.

    Parameters
    ----------
    cube : xr.Dataset
        As :func:`from_tables` returns it or :func:`xarray.open_dataset` reads the file.

    Raises
    ------
    ValueError
        The first violation found, naming the coordinate or the cell.
    """
    if "atmosphere" not in cube.data_vars:
        raise ValueError("the database must hold the variable 'atmosphere'")
    var = cube["atmosphere"]
    conditions = var.dims[:-len(DIMS)] if len(var.dims) > len(DIMS) else ()
    if var.dims[len(conditions):] != DIMS or any(c not in CONDITIONS for c in conditions):
        raise ValueError(f"variable atmosphere must have the dims {DIMS}, optionally after "
                         f"conditions among {', '.join(CONDITIONS)}; got {var.dims}")
    if var.dtype != np.float32:
        raise ValueError(f"variable atmosphere must be float32; got {var.dtype}")
    coords = _condition_coordinates(cube, conditions)
    for name, units in _COORD_UNITS.items():
        if name not in cube.coords:
            raise ValueError(f"the database lacks the coordinate {name}")
        got = cube[name].attrs.get("units")
        if got != units:
            raise ValueError(f"coordinate {name} must have units {units!r}; got {got!r}")
        coords[name] = np.asarray(cube[name].values, dtype=np.float64)
        _strict(name, coords[name], decreasing=name == "visibility")
    lows = {"visibility": (0.0, False), "altitude": (0.0, False), "ground_range": (0.0, True)}
    for name, (low, closed) in lows.items():
        first = coords[name].min()
        if first < low or (first == low and not closed):
            raise ValueError(f"coordinate {name} must be {'>=' if closed else '>'} {low:g} "
                             f"{_COORD_UNITS[name]}; got {float(first)!r}")
    lo, hi = _WAVELENGTH_LIMITS
    w = coords["wavelength"]
    if w[0] < lo or w[-1] > hi:
        raise ValueError(f"coordinate wavelength must be in metres, within [{lo:g}, {hi:g}] m; "
                         f"got [{float(w[0])!r}, {float(w[-1])!r}] (micrometres? multiply by 1e-6)")
    components = [str(c) for c in np.asarray(cube["component"].values)]
    if components != list(COMPONENTS):
        raise ValueError(f"coordinate component must be {list(COMPONENTS)}; got {components}")
    units = ([str(u) for u in np.asarray(cube["component_units"].values)]
             if "component_units" in cube.coords else None)
    if units != list(FILE_UNITS):
        raise ValueError(f"coordinate component_units must be {list(FILE_UNITS)} (radiances in "
                         f"W sr-1 cm-2 um-1 = 1e-10 x W m-2 sr-1 m-1); got {units}")
    missing = [name for name in REQUIRED_ATTRS if name not in cube.attrs]
    if missing:
        raise ValueError(f"the database lacks the global attribute(s) {', '.join(missing)}: "
                         "say what the tables are, where they come from and the surface "
                         "reflectance of GRND_RFLT")
    reflectance = cube.attrs["surface_reflectance_of_database"]
    if not (isinstance(reflectance, (float, np.floating)) and 0.0 < reflectance <= 1.0):
        raise ValueError("attribute surface_reflectance_of_database must be a float in (0, 1]; "
                         f"got {reflectance!r}")
    _check_values(np.asarray(var.values), coords, var.dims)


def _condition_coordinates(cube, conditions):
    """Each condition's coordinate: present, in its units, finite, strictly increasing."""
    coords = {}
    for name in conditions:
        units = CONDITIONS[name][0]
        if name not in cube.coords:
            raise ValueError(f"the database lacks the coordinate {name} of its condition dim")
        got = cube[name].attrs.get("units")
        if got != units:
            raise ValueError(f"coordinate {name} must have units {units!r}; got {got!r}")
        coords[name] = np.asarray(cube[name].values, dtype=np.float64)
        _strict(name, coords[name])
        if units == "1" and not np.array_equal(coords[name], np.round(coords[name])):
            raise ValueError(f"coordinate {name} holds codes: whole numbers; got "
                             f"{coords[name].tolist()}")
    return coords


def _check_values(values, coords, dims=DIMS):
    """The cells: whole, a prefix up to the horizon, TRANS in [0, 1], radiances >= 0."""
    values = values.reshape(-1, *values.shape[-4:])  # the sets of conditions: one axis
    finite = np.isfinite(values)
    present = finite.all(axis=(3, 4))
    partial = finite.any(axis=(3, 4)) & ~present
    if partial.any():
        v, a, g = np.argwhere(partial)[0]
        c, k = np.argwhere(~finite[v, a, g])[0]
        raise ValueError(f"a table is either wholly present or wholly NaN; the cell "
                         f"{_cell((v, a, g, c, k), coords, dims)} is NaN (or infinite) in a table "
                         "that has values")
    reach = horizon(coords["altitude"], _REFRACTED_RADIUS)
    ground_range = coords["ground_range"]
    for v in range(present.shape[0]):
        for a in range(present.shape[1]):
            row = present[v, a]
            n = int(row.argmin()) if not row.all() else row.size
            if row[n:].any():
                g = n + int(row[n:].argmax())
                raise ValueError(
                    "the ground ranges of each (visibility, altitude) must be a prefix of the "
                    f"grid (NaN beyond); at {_cell((v, a), coords, dims)} ground_range="
                    f"{float(ground_range[n])!r} is missing but ground_range="
                    f"{float(ground_range[g])!r} is present")
            if n and ground_range[n - 1] > reach[a]:
                raise ValueError(
                    f"at {_cell((v, a), coords, dims)} ground_range="
                    f"{float(ground_range[n - 1])!r} m is "
                    f"beyond the horizon ({reach[a]:.6g} m with standard refraction, an Earth "
                    f"of radius 4/3 x {EARTH_RADIUS:g} m): a sensor cannot see it; make it NaN")
    trans = values[:, :, :, 0]
    bad = finite[:, :, :, 0] & ~((trans >= 0.0) & (trans <= 1.0))
    if bad.any():
        v, a, g, k = np.argwhere(bad)[0]
        raise ValueError(f"TRANS must be within [0, 1]; {float(trans[v, a, g, k])!r} at "
                         f"{_cell((v, a, g, 0, k), coords, dims)}")
    bad = finite[:, :, :, 1:] & (values[:, :, :, 1:] < 0.0)
    if bad.any():
        v, a, g, c, k = np.argwhere(bad)[0]
        raise ValueError(f"radiances must be >= 0; {float(values[v, a, g, c + 1, k])!r} at "
                         f"{_cell((v, a, g, c + 1, k), coords, dims)}")


def _var_attrs(da):
    """Attributes of ``da`` as the file stores them (no xarray encoding keys)."""
    return {k: v for k, v in da.attrs.items() if k not in ("_FillValue", "coordinates")}


def write_database(cube: xr.Dataset, path, *, complevel: int = 4) -> Path:
    """Validate ``cube`` and write it as an atmosphere database file, deterministically.

    The layout is the shipped file's: NETCDF4 (HDF5), the global attributes in the
    cube's order, the dims in :data:`DIMS` order, then the coordinates (visibility, ihaze,
    altitude, ground_range, component, component_units, component_long_name, wavelength:
    those present) and ``atmosphere`` last, each variable's attributes in the cube's order
    (``atmosphere``'s ``coordinates`` after its ``long_name``); ``atmosphere`` is float32,
    zlib (``complevel``) with shuffle, fill value NaN, one chunk per (visibility, altitude).
    No timestamps are written, so the same cube with the same netCDF-C and HDF5 versions
    gives the same bytes.

    Parameters
    ----------
    cube : xr.Dataset
        As :func:`from_tables` returns it (or the file opened with xarray).
    path : str or os.PathLike
        File to write (replaced if it exists).
    complevel : int
        zlib level, 1-9 (the shipped file: 4).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        A cube :func:`validate_database` rejects, or ``complevel`` outside 1-9.
    """
    if not (isinstance(complevel, int) and 1 <= complevel <= 9):
        raise ValueError(f"complevel must be an integer in [1, 9]; got {complevel!r}")
    validate_database(cube)
    path = Path(path)
    dims = cube["atmosphere"].dims  # the conditions, if any, then DIMS
    sizes = [cube.sizes[d] for d in dims]
    order = (*dims[:-len(DIMS)], *_ORDER)
    # in memory before the file is opened: a lazy read inside netcdf_file would wait for
    # the lock the writing holds
    cube = cube.compute()
    with netcdf_file(path, "w", format="NETCDF4") as nc:
        nc.setncatts(dict(cube.attrs))
        for dim, size in zip(dims, sizes, strict=True):
            nc.createDimension(dim, size)
        for name in order:
            if name not in cube.variables:
                continue
            da = cube[name]
            if da.dtype.kind in "OUS":
                var = nc.createVariable(name, str, da.dims)
                var.setncatts(_var_attrs(da))
                var[:] = np.array([str(s) for s in da.values], dtype=object)
            else:
                kind = "i4" if da.dtype.kind in "iu" else "f8"
                var = nc.createVariable(name, kind, da.dims)
                var.setncatts(_var_attrs(da))
                var[:] = da.values
        var = nc.createVariable("atmosphere", "f4", dims, zlib=True, complevel=complevel,
                                shuffle=True, fill_value=np.float32(np.nan),
                                chunksizes=(*(1,) * (len(dims) - 3), *sizes[-3:]))
        attrs = _var_attrs(cube["atmosphere"])
        auxiliary = [n for n in _ORDER if n in cube.coords and n not in dims]
        ordered = {"long_name": attrs.pop("long_name")} if "long_name" in attrs else {}
        if auxiliary:
            ordered["coordinates"] = " ".join(auxiliary)
        var.setncatts({**ordered, **attrs})
        var[:] = np.asarray(cube["atmosphere"].values, dtype=np.float32)
    return path
