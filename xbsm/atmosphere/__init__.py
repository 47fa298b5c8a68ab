"""MODTRAN 5.2.1 atmosphere database: the lazy cube and per-scenario interpolation.

The database (pyBSM 0.16.1's 3430 MODTRAN runs, see ``NOTICE``) is one NetCDF
file, ``atmosphere.nc``, with a float32 variable ``atmosphere`` on the dims
(visibility, altitude, ground_range, component, wavelength) in the database's
native units. :func:`open_atmosphere` opens it lazily in SI units;
:func:`atmosphere_at` returns the five spectra for any number of scenarios.

The package, in data-flow order: :mod:`~xbsm.atmosphere.database` (the file, its facts,
the cube in memory), :mod:`~xbsm.atmosphere.rules` (the dispatch table of named rules and
the fixed-range steps), the private line-of-sight machinery, optical-depth cubic and
extinction profile, and :mod:`~xbsm.atmosphere.lookup` (:func:`atmosphere_at`,
:func:`band_atmosphere`, :func:`interpolate_database`); :mod:`~xbsm.atmosphere.tables`
builds, validates and writes a database file from anyone's tables
(:func:`from_tables`, :func:`write_database`), and :func:`use_database` makes such a
file the default inside a ``with`` block; :mod:`~xbsm.atmosphere.modtran` reads MODTRAN's
tape7 / ``.7sc`` outputs into such tables and writes the MODTRAN 6 JSON cases of a grid
(:func:`read_tape7`, :func:`tables_from_runs`, :func:`modtran_inputs`); and
:mod:`~xbsm.atmosphere.sixs` generates such files with the open radiative-transfer code 6S
(optional extra ``sixs``; its names stay in that submodule). Every public name of the
other modules is importable from ``xbsm.atmosphere``, on first use (PEP 562), so that
:mod:`xbsm.params` and :mod:`xbsm.flags` can read the database's facts without importing
the interpolation.

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
``"extinction-profile"`` (default of :func:`atmosphere_at` and the ``accurate``, ``fast`` presets)
    ``"optical-depth-cubic"`` with its increment over the lower bracketing table scaled
    so that, straight down, it equals the vertical optical depth of an extinction
    profile built from the tables' nadir columns: in each interval between tables,
    ln(extinction) is a line between end values that lean to the smoother side
    (Akima's weights) plus a quadratic bulge that makes the interval's mean right, so a
    boundary layer that stays uniform and then drops inside an interval is followed.
    Where the profile cannot be built (TRANS 0 at the database floor) the factor is 1.
    Nodes, fallback and flags are ``"optical-depth-cubic"``'s.

The leave-one-out errors behind these choices are in ``docs/atmosphere.md``.

Between two of the database's visibilities, each rule runs at both bracketing
visibility tables and the two are combined in extinction
(:func:`~xbsm.atmosphere.lookup.across_visibility`: ln TRANS, SURF_EMIS, GRND_RFLT linear
in 1/visibility, the path radiances linear in the transmission lost), flagged
``visibility_interpolated``. A database may hold other conditions as dims
(:data:`~xbsm.atmosphere.database.CONDITIONS`); a scenario selects one of their values
(``conditions=``), never between them.

At a database node every option returns the stored value exactly. Where a
bracketing table is missing (beyond the horizon of the lower altitude, or above
ground range 0 between 24.5 km and 550 km) the spectra are NaN and the
``beyond_database`` flag is set. Altitudes strictly between 24.5 km and 550 km
are interpolated only at ground range 0 and carry the ``atmosphere_sparse`` flag; every
altitude above 24.5 km carries the invalid ``atmosphere_inconsistent`` flag (the 550 km
tables are not a continuation of the 24.5 km ones: ``docs/atmosphere.md``).
"""

import importlib

#: Public name -> the submodule that defines it (a submodule is its own entry).
_PUBLIC = {
    "database": "database",
    "rules": "rules",
    "lookup": "lookup",
    "tables": "tables",
    "modtran": "modtran",
    "sixs": "sixs",  # the open engine 6S (optional extra 'sixs'); its names stay in it
    **{name: "database" for name in (
        "ALTITUDES", "ALTITUDE_GAP", "ALTITUDE_RANGE", "COMPONENTS", "GROUND_RANGES",
        "GROUND_RANGE_RANGE", "IHAZE", "LONG_NAMES", "SURFACE_REFLECTANCE", "UNITS",
        "VARIABLES", "VISIBILITIES",
        "WAVELENGTH_MAX", "WAVELENGTH_MIN", "Database", "database_path",
        "database_wavelengths", "load_database", "open_atmosphere", "use_database",
        "check_supported", "database_visibilities", "CONDITIONS", "CONDITION_RTOL",
        "database_conditions", "describe_conditions", "listed", "visibility_range")},
    **{name: "rules" for name in ("INTERPOLATIONS", "RULES", "SCALE_HEIGHT", "Rule")},
    **{name: "lookup" for name in (
        "RELATIVE_EDGE_TOLERANCE", "WAVELENGTH_ATTRS", "atmosphere_at", "band_atmosphere",
        "band_atmosphere_arrays", "band_wavelengths", "interpolate_database",
        "across_visibility", "condition_inputs")},
    **{name: "modtran" for name in (
        "APPENDIX_A", "MODTRAN6_KEYS", "modtran_inputs", "read_modtran_csv", "read_tape7",
        "tables_from_runs")},
    **{name: "tables" for name in (
        "DIMS", "FILE_UNITS", "REQUIRED_ATTRS", "from_tables", "horizon", "validate_database",
        "write_database")},
}

__all__ = list(_PUBLIC)


def __getattr__(name):
    source = _PUBLIC.get(name)
    if source is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module = importlib.import_module(f".{source}", __name__)
    value = module if source == name else getattr(module, name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *__all__})
