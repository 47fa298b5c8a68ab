"""Build ``atmosphere.nc`` from the MODTRAN 5.2.1 database shipped with pyBSM 0.16.1.

Run from the repository root with the project environment (see ``recipes/README.md``)::

    .venv/bin/python recipes/build_atmosphere.py            # build + fixture
    .venv/bin/python recipes/build_atmosphere.py --check    # build twice, compare sha256

What it does
------------
1. ``pip download --no-deps pybsm==0.16.1`` into ``recipes/_cache/`` (gitignored) and
   checks the wheel's sha256. The wheel is read as a zip file; pyBSM is never installed
   or imported.
2. Reads ``pybsm/atms/fileDecoder.csv`` (index, altitude [km], ground range [km], IHAZE)
   and every ``pybsm/atms/<index>.bin`` (float32, 1371 wavelengths x 5 columns, stored
   column by column, i.e. Fortran order).
3. Writes ONE NetCDF4/HDF5 file with a single data variable ``atmosphere`` on dims
   (visibility, altitude, ground_range, component, wavelength). The values are the raw
   float32 numbers of the .bin files, bit for bit, in the database's native units
   (TRANS unitless, radiances W/(sr cm^2 um)); cells with no database entry (beyond the
   horizon; 550 km above ground range 0) are NaN.
4. Writes ``tests/fixtures/atmosphere_checksums.json``: per (visibility, altitude) slab,
   the number of ground ranges present, the decoder index of the first file, the
   sha256 of the concatenated raw bytes and a crc32 per spectrum, plus a few raw values.
   ``tests/atmosphere/test_atmosphere.py`` uses it to prove that the cube holds all 3430 spectra bit
   for bit and nothing else.

Layout and chunking
-------------------
The storage order (component, wavelength) of one spectrum equals the byte order of its
.bin file (Fortran order of a 1371 x 5 array is component-major), so the sha256 of
``cube[v, a, g].tobytes()`` is the sha256 of the .bin file. One chunk is one
(visibility, altitude) slab: 97 ground ranges x 5 components x 1371 wavelengths
x 4 bytes = 2.66 MB uncompressed, 48 chunks in all. That is the unit in which the
interpolation kernel and a lazy dask reader touch the data (a scenario needs whole
spectra at a few neighbouring altitudes), it is big enough for zlib to find the
smooth spectral structure (shuffle + deflate work on contiguous spectra of one
component) and small enough for a dask task. Slabs beyond the horizon are mostly NaN
and compress to almost nothing.

Determinism
-----------
No timestamps in the attributes; the file is written with netCDF4-python in a fixed
order. netCDF-C creates HDF5 objects with modification-time tracking switched off
(``H5Pset_obj_track_times(..., 0)``), so two builds with the same library versions are
byte-identical; ``--check`` proves it by building twice into a temporary folder. The
``_NCProperties`` attribute records the netCDF-C and HDF5 versions, so a build with
other library versions can differ in those bytes (the data are unchanged).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import tempfile
import zipfile
import zlib
from decimal import Decimal
from pathlib import Path

import netCDF4
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / "recipes" / "_cache" / "pybsm_wheel"
WHEEL_NAME = "pybsm-0.16.1-py3-none-any.whl"
WHEEL_SHA256 = "ad910922d0a33c033db2f29f0c80ebbfebe2870142c788de10bf5e8b74945ee9"

N_WAVELENGTH = 1371
COMPONENTS = ["TRANS", "PTH_THRML", "SURF_EMIS", "SOL_SCAT", "GRND_RFLT"]
COMPONENT_UNITS = ["1", "W sr-1 cm-2 um-1", "W sr-1 cm-2 um-1", "W sr-1 cm-2 um-1",
                   "W sr-1 cm-2 um-1"]
COMPONENT_LONG_NAMES = [
    "total transmittance along the path (MODTRAN TRANS)",
    "path thermal radiance: atmospheric emission and scattering (MODTRAN PTH THRML)",
    "surface emission radiance transmitted to the sensor (MODTRAN SURF EMIS)",
    "path solar scattered radiance (MODTRAN SOL SCAT)",
    "ground reflected solar radiance, reflectance 0.15 (MODTRAN GRND RFLT)",
]
IHAZE_VISIBILITY_KM = {1: 23.0, 2: 5.0}

# Appendix A of LeMaster & Eismann (2017) and pybsm/atms/atmosphere_README.txt.
MODTRAN_ATTRS = {
    "modtran_version": "5.2.1",
    "modtran_GNDALT": "0.0 (ground altitude, km MSL)",
    "modtran_H2": "0.0 (target altitude, km MSL)",
    "modtran_PARM1": "90 (azimuth between sensor line of sight and sun, degrees)",
    "modtran_PARM2": "50 (solar zenith angle, degrees)",
    "modtran_DV": "0.01 (spectral sampling, um)",
    "modtran_FWHM": "0.02 (slit function full width at half maximum, um)",
    "modtran_VIS": "0 (visibility inherited from IHAZE)",
    "modtran_IHAZE": "1 = rural extinction, 23 km visibility; 2 = rural extinction, 5 km "
                     "visibility",
    "modtran_MODEL": "2 (mid-latitude summer, 45 degrees North)",
    "modtran_H2OSTR": "1 (water vapour scaling)",
    "modtran_ICLD": "0 (no clouds)",
    "modtran_IDAY": "236 (day of year, 23 August)",
    "modtran_IMULT": "1 (multiple scattering on)",
    "modtran_RAINRT": "0 (no rain)",
    "modtran_ISOURC": "0 (extraterrestrial source is the sun)",
    "modtran_TPTEMP": "299 (target temperature, K)",
    "modtran_AATEMP": "297 (background temperature, K)",
    "modtran_SURREFt": "constant, 15% (target reflectance)",
    "modtran_SURREFb": "Mixed Forest (background reflectance)",
}


def fetch_wheel() -> Path:
    """Download the pyBSM 0.16.1 wheel (once) and check its sha256."""
    wheel = CACHE / WHEEL_NAME
    if not wheel.exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        subprocess.run(
            [sys.executable, "-m", "pip", "download", "--no-deps", "pybsm==0.16.1",
             "-d", str(CACHE)],
            check=True,
        )
    digest = hashlib.sha256(wheel.read_bytes()).hexdigest()
    if digest != WHEEL_SHA256:
        raise RuntimeError(f"{wheel} has sha256 {digest}, expected {WHEEL_SHA256}")
    return wheel


def km_to_m(text: str) -> float:
    """Exact decimal km -> m (0.0325 km -> 32.5 m, not 32.500000000000004)."""
    return float(Decimal(text.strip()) * 1000)


def read_database(wheel: Path):
    """Return coordinates, the raw cube and the decoder rows."""
    with zipfile.ZipFile(wheel) as zf:
        lines = zf.read("pybsm/atms/fileDecoder.csv").decode("ascii").strip().splitlines()
        rows = []
        for line in lines[1:]:
            index, alt_km, gr_km, ihaze = line.rstrip(",").split(",")
            rows.append((int(index), km_to_m(alt_km), km_to_m(gr_km), int(ihaze)))
        if len(rows) != 3430 or sorted(r[0] for r in rows) != list(range(1, 3431)):
            raise RuntimeError("unexpected fileDecoder.csv content")
        altitude = np.array(sorted({r[1] for r in rows}), dtype=np.float64)
        ground_range = np.array(sorted({r[2] for r in rows}), dtype=np.float64)
        ihaze = np.array(sorted({r[3] for r in rows}), dtype=np.int32)
        cube = np.full(
            (ihaze.size, altitude.size, ground_range.size, len(COMPONENTS), N_WAVELENGTH),
            np.nan, dtype=np.float32,
        )
        raw = {}
        for index, alt, gr, hz in rows:
            data = zf.read(f"pybsm/atms/{index}.bin")
            if len(data) != 4 * 5 * N_WAVELENGTH:
                raise RuntimeError(f"{index}.bin has {len(data)} bytes")
            spectrum = np.frombuffer(data, dtype="<f4").reshape((N_WAVELENGTH, 5), order="F")
            v = int(np.searchsorted(ihaze, hz))
            a = int(np.searchsorted(altitude, alt))
            g = int(np.searchsorted(ground_range, gr))
            cube[v, a, g] = spectrum.T  # (component, wavelength): the file's byte order
            raw[(v, a, g)] = (index, data)
    return altitude, ground_range, ihaze, cube, raw


def write_netcdf(path: Path, altitude, ground_range, ihaze, cube, complevel: int = 4) -> None:
    """Write the CF-compliant cube (deterministically: fixed order, no timestamps)."""
    wavelength = 1e-6 * np.linspace(0.3, 14.0, N_WAVELENGTH)  # exactly pyBSM's grid
    visibility = np.array([IHAZE_VISIBILITY_KM[int(h)] for h in ihaze])
    with netCDF4.Dataset(path, "w", format="NETCDF4") as nc:
        nc.setncatts({
            "Conventions": "CF-1.10",
            "title": "MODTRAN 5.2.1 radiative-transfer database of pyBSM 0.16.1 "
                     "(sunny day, mid-latitude summer, rural aerosols)",
            "source": "MODTRAN 5.2.1 runs distributed with pyBSM 0.16.1 "
                      "(pybsm/atms/<index>.bin and fileDecoder.csv in "
                      f"{WHEEL_NAME}, sha256 {WHEEL_SHA256})",
            "institution": "Air Force Research Laboratory, Sensors Directorate (data); "
                           "Kitware, Inc. (pyBSM maintainer)",
            "references": "LeMaster, D. A. and Eismann, M. T., pyBSM: A Python package for "
                          "modeling imaging systems, Proc. SPIE 10204 (2017), Appendix A; "
                          "https://github.com/Kitware/pybsm",
            "license": "Apache-2.0 (data from pyBSM 0.16.1, https://github.com/Kitware/pybsm;"
                       " see NOTICE)",
            "history": "recipes/build_atmosphere.py (xbsm): raw float32 spectra copied bit "
                       "for bit from the pyBSM 0.16.1 wheel; no values changed",
            "comment": "Altitude 32.5 m is the decoder's 0.0325 km; pyBSM 0.16.1 docstrings "
                       "and load_database_atmosphere call it 32.55 m. The nadir space table "
                       "is 550 km in the decoder (atmosphere_README.txt says 500 km); it "
                       "exists only at ground range 0. Ground ranges stop at the "
                       "spherical-Earth horizon of each altitude; missing cells are NaN.",
            "surface_reflectance_of_database": 0.15,
            **MODTRAN_ATTRS,
        })
        nc.createDimension("visibility", visibility.size)
        nc.createDimension("altitude", altitude.size)
        nc.createDimension("ground_range", ground_range.size)
        nc.createDimension("component", len(COMPONENTS))
        nc.createDimension("wavelength", wavelength.size)

        var = nc.createVariable("visibility", "f8", ("visibility",))
        var.setncatts({"units": "km", "long_name": "meteorological range (visibility)",
                       "standard_name": "visibility_in_air"})
        var[:] = visibility
        var = nc.createVariable("ihaze", "i4", ("visibility",))
        var.setncatts({"units": "1", "long_name": "MODTRAN IHAZE aerosol model code",
                       "flag_values": ihaze.astype(np.int32),
                       "flag_meanings": "rural_23km_visibility rural_5km_visibility"})
        var[:] = ihaze
        var = nc.createVariable("altitude", "f8", ("altitude",))
        var.setncatts({"units": "m", "long_name": "sensor altitude above ground level",
                       "standard_name": "height", "positive": "up",
                       "comment": "32.5 m is stored as in fileDecoder.csv (0.0325 km); "
                                  "pyBSM documents it as 32.55 m"})
        var[:] = altitude
        var = nc.createVariable("ground_range", "f8", ("ground_range",))
        var.setncatts({"units": "m",
                       "long_name": "ground range from the sensor nadir point to the target",
                       "comment": "great-circle distance on the spherical Earth"})
        var[:] = ground_range
        var = nc.createVariable("component", str, ("component",))
        var.setncatts({"long_name": "MODTRAN tape 7 column name"})
        var[:] = np.array(COMPONENTS, dtype=object)
        var = nc.createVariable("component_units", str, ("component",))
        var.setncatts({"long_name": "units of the component (UDUNITS string)"})
        var[:] = np.array(COMPONENT_UNITS, dtype=object)
        var = nc.createVariable("component_long_name", str, ("component",))
        var.setncatts({"long_name": "description of the component"})
        var[:] = np.array(COMPONENT_LONG_NAMES, dtype=object)
        var = nc.createVariable("wavelength", "f8", ("wavelength",))
        var.setncatts({"units": "m", "long_name": "wavelength",
                       "standard_name": "radiation_wavelength",
                       "comment": "exactly 1e-6 * numpy.linspace(0.3, 14.0, 1371), the grid "
                                  "pyBSM 0.16.1 attaches to the database"})
        var[:] = wavelength

        var = nc.createVariable(
            "atmosphere", "f4",
            ("visibility", "altitude", "ground_range", "component", "wavelength"),
            zlib=True, complevel=complevel, shuffle=True, fill_value=np.float32(np.nan),
            chunksizes=(1, 1, ground_range.size, len(COMPONENTS), wavelength.size),
        )
        var.setncatts({
            "long_name": "MODTRAN 5.2.1 path transmittance and radiance components "
                         "(raw database values)",
            "coordinates": "ihaze component_units component_long_name",
            "units_by_component": "see component_units: TRANS 1; PTH_THRML, SURF_EMIS, "
                                  "SOL_SCAT, GRND_RFLT W sr-1 cm-2 um-1",
            "comment": "Raw float32 values of pyBSM 0.16.1's pybsm/atms/*.bin files, bit for "
                       "bit, in the database's native units (no units attribute because the "
                       "units differ by component; see component_units). Multiply radiances "
                       "by 1e10 (pyBSM divides the float32 value by float32(1e-10)) for "
                       "W m-2 sr-1 m-1; xbsm.open_atmosphere does this. NaN: no database "
                       "entry (beyond the horizon, or above ground range 0 at 550 km).",
        })
        var[:] = cube


def sha256_file(path: Path) -> str:
    """Hex sha256 of a file."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def write_fixture(path: Path, altitude, ground_range, ihaze, cube, raw) -> None:
    """Checksums per slab and per spectrum plus a few raw values, for the tests."""
    slabs = []
    for v in range(ihaze.size):
        for a in range(altitude.size):
            present = [g for g in range(ground_range.size) if (v, a, g) in raw]
            if present != list(range(len(present))):
                raise RuntimeError("ground ranges of a slab are not a prefix of the grid")
            indices = [raw[(v, a, g)][0] for g in present]
            if indices != list(range(indices[0], indices[0] + len(indices))):
                raise RuntimeError("decoder indices of a slab are not consecutive")
            blob = b"".join(raw[(v, a, g)][1] for g in present)
            slabs.append({
                "ihaze": int(ihaze[v]),
                "altitude": float(altitude[a]),
                "n_ground_range": len(present),
                "first_file_index": indices[0],
                "sha256": hashlib.sha256(blob).hexdigest(),
                "crc32": [f"{zlib.crc32(raw[(v, a, g)][1]):08x}" for g in present],
            })
    rng = np.random.default_rng(20170410)  # fixed seed: the fixture is reproducible
    keys = sorted(raw)
    samples = []
    for k in rng.choice(len(keys), size=12, replace=False):
        v, a, g = keys[int(k)]
        c = int(rng.integers(5))
        w = int(rng.integers(N_WAVELENGTH))
        value = cube[v, a, g, c, w]
        samples.append({
            "file": f"{raw[(v, a, g)][0]}.bin", "ihaze": int(ihaze[v]),
            "altitude": float(altitude[a]), "ground_range": float(ground_range[g]),
            "component": COMPONENTS[c], "wavelength_index": w,
            "float32_hex": value.tobytes().hex(), "value": float(value),
        })
    fixture = {
        "comment": "Made by recipes/build_atmosphere.py from the pyBSM 0.16.1 wheel. Per "
                   "(ihaze, altitude) slab: the number of ground ranges present (a prefix "
                   "of the grid), the decoder index of its first .bin file, the sha256 of "
                   "the concatenated raw .bin bytes in ground-range order and the crc32 of "
                   "each .bin file. samples: raw float32 values (little-endian hex).",
        "wheel_sha256": WHEEL_SHA256,
        "n_spectra": len(raw),
        "slabs": slabs,
        "samples": samples,
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(fixture, indent=1) + "\n")


def main(argv=None) -> int:
    """Build atmosphere.nc and the checksum fixture (``--check``: build twice, compare)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=ROOT / "atmosphere.nc")
    parser.add_argument("--fixture", type=Path,
                        default=ROOT / "tests" / "fixtures" / "atmosphere_checksums.json")
    parser.add_argument("--complevel", type=int, default=4)
    parser.add_argument("--check", action="store_true",
                        help="also build a second copy in a temporary folder and compare sha256")
    args = parser.parse_args(argv)

    altitude, ground_range, ihaze, cube, raw = read_database(fetch_wheel())
    write_netcdf(args.output, altitude, ground_range, ihaze, cube, args.complevel)
    write_fixture(args.fixture, altitude, ground_range, ihaze, cube, raw)
    digest = sha256_file(args.output)
    print(f"{args.output}: {args.output.stat().st_size} bytes, sha256 {digest}")
    if args.check:
        with tempfile.TemporaryDirectory() as tmp:
            again = Path(tmp) / "atmosphere.nc"
            write_netcdf(again, altitude, ground_range, ihaze, cube, args.complevel)
            digest2 = sha256_file(again)
        print(f"rebuild sha256 {digest2}: {'identical' if digest2 == digest else 'DIFFERENT'}")
        if digest2 != digest:
            return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
