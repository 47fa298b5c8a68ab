"""Build ``atmosphere.nc`` from the MODTRAN 5.2.1 database shipped with pyBSM 0.16.1.

Run from the repository root with the project environment (see ``recipes/README.md``)::

    .venv/bin/python recipes/build_atmosphere.py            # build + fixture
    .venv/bin/python recipes/build_atmosphere.py --check    # build twice, compare sha256
    .venv/bin/python recipes/build_atmosphere.py --verify-shipped  # rebuild, compare with
                                                            # the committed atmosphere.nc

What it does
------------
1. ``pip download --no-deps pybsm==0.16.1`` into ``recipes/_cache/`` (gitignored) and
   checks the wheel's sha256. The wheel is read as a zip file; pyBSM is never installed
   or imported.
2. Reads ``pybsm/atms/fileDecoder.csv`` (index, altitude [km], ground range [km], IHAZE)
   and every ``pybsm/atms/<index>.bin`` (float32, 1371 wavelengths x 5 columns, stored
   column by column, i.e. Fortran order).
3. Builds the cube with the public builder, :func:`xbsm.atmosphere.from_tables` (which
   validates it: docs/atmosphere.md, "The database file"), and writes it with
   :func:`xbsm.atmosphere.write_database`: ONE NetCDF4/HDF5 file with a single data
   variable ``atmosphere`` on dims (visibility, altitude, ground_range, component,
   wavelength). The values are the raw float32 numbers of the .bin files, bit for bit,
   in the database's native units (TRANS unitless, radiances W/(sr cm^2 um)); cells
   with no database entry (beyond the horizon; 550 km above ground range 0) are NaN.
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

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the worktree's xbsm, also when run without PYTHONPATH

from xbsm.atmosphere import from_tables, write_database  # noqa: E402

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


def shipped_cube(altitude, ground_range, ihaze, cube):
    """The shipped database as :func:`xbsm.atmosphere.from_tables` builds it (validated)."""
    wavelength = 1e-6 * np.linspace(0.3, 14.0, N_WAVELENGTH)  # exactly pyBSM's grid
    visibility = np.array([IHAZE_VISIBILITY_KM[int(h)] for h in ihaze])
    attrs = {
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
    }
    return from_tables(
        cube, visibility=visibility, altitude=altitude, ground_range=ground_range,
        wavelength=wavelength, ihaze=ihaze,
        ihaze_meanings=["rural_23km_visibility", "rural_5km_visibility"],
        component_units=COMPONENT_UNITS, component_long_names=COMPONENT_LONG_NAMES,
        attrs=attrs,
        coordinate_attrs={
            "altitude": {"comment": "32.5 m is stored as in fileDecoder.csv (0.0325 km); "
                                    "pyBSM documents it as 32.55 m"},
            "wavelength": {"comment": "exactly 1e-6 * numpy.linspace(0.3, 14.0, 1371), the "
                                      "grid pyBSM 0.16.1 attaches to the database"},
        },
        variable_attrs={
            "long_name": "MODTRAN 5.2.1 path transmittance and radiance components "
                         "(raw database values)",
            "units_by_component": "see component_units: TRANS 1; PTH_THRML, SURF_EMIS, "
                                  "SOL_SCAT, GRND_RFLT W sr-1 cm-2 um-1",
            "comment": "Raw float32 values of pyBSM 0.16.1's pybsm/atms/*.bin files, bit for "
                       "bit, in the database's native units (no units attribute because the "
                       "units differ by component; see component_units). Multiply radiances "
                       "by 1e10 (pyBSM divides the float32 value by float32(1e-10)) for "
                       "W m-2 sr-1 m-1; xbsm.open_atmosphere does this. NaN: no database "
                       "entry (beyond the horizon, or above ground range 0 at 550 km).",
        },
    )


def write_netcdf(path: Path, altitude, ground_range, ihaze, cube, complevel: int = 4) -> None:
    """Write the CF-compliant cube through the public builder (deterministic)."""
    write_database(shipped_cube(altitude, ground_range, ihaze, cube), path,
                   complevel=complevel)


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


def _contents(path: Path) -> dict:
    """Every variable's bytes, dtype, dims, chunks, filters and attributes, in file order."""
    import netCDF4

    with netCDF4.Dataset(path) as nc:
        nc.set_auto_maskandscale(False)
        out = {"": [(k, repr(nc.getncattr(k))) for k in nc.ncattrs()],
               "_NCProperties": nc.getncattr("_NCProperties")}
        for name, var in nc.variables.items():
            data = var[...]
            raw = data.tobytes() if data.dtype != object else repr(list(data)).encode()
            out[name] = (str(var.dtype), var.dimensions,
                         [(k, repr(var.getncattr(k))) for k in var.ncattrs()],
                         var.chunking(), var.filters(), hashlib.sha256(raw).hexdigest())
    return out


def verify_shipped(altitude, ground_range, ihaze, cube, complevel: int) -> int:
    """Rebuild through the public builder and compare with the committed atmosphere.nc."""
    shipped = ROOT / "atmosphere.nc"
    with tempfile.TemporaryDirectory() as tmp:
        again = Path(tmp) / "atmosphere.nc"
        write_netcdf(again, altitude, ground_range, ihaze, cube, complevel)
        same_file = sha256_file(again) == sha256_file(shipped)
        mine, theirs = _contents(again), _contents(shipped)
    libraries = mine.pop("_NCProperties"), theirs.pop("_NCProperties")
    print(f"rebuilt with {libraries[0]}; {shipped.name} written with {libraries[1]}")
    print(f"sha256 {'identical' if same_file else 'DIFFERENT'}; variables and attributes "
          f"{'identical' if mine == theirs else 'DIFFERENT'}")
    for name in sorted(set(mine) | set(theirs)):
        if mine.get(name) != theirs.get(name):
            print(f"  differs: {name or 'global attributes'}")
    return 0 if mine == theirs and (same_file or libraries[0] != libraries[1]) else 1


def main(argv=None) -> int:
    """Build atmosphere.nc and the checksum fixture (``--check``: build twice, compare)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=ROOT / "atmosphere.nc")
    parser.add_argument("--fixture", type=Path,
                        default=ROOT / "tests" / "fixtures" / "atmosphere_checksums.json")
    parser.add_argument("--complevel", type=int, default=4)
    parser.add_argument("--check", action="store_true",
                        help="also build a second copy in a temporary folder and compare sha256")
    parser.add_argument("--verify-shipped", action="store_true",
                        help="only rebuild into a temporary folder and compare with the "
                             "committed atmosphere.nc (sha256, else every variable's bytes and "
                             "every attribute)")
    args = parser.parse_args(argv)

    altitude, ground_range, ihaze, cube, raw = read_database(fetch_wheel())
    if args.verify_shipped:
        return verify_shipped(altitude, ground_range, ihaze, cube, args.complevel)
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
