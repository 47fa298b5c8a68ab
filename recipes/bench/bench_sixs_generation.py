"""What a 6S table costs, where the time goes, and what the speedups buy (issue 24).

Measures, on this machine (load averages printed and recorded; 2 cores shared with other
jobs), interleaving the variants so that a change of load hits them alike:

1. **One 6S run**: Py6S's ``run`` (input file, shell, parsing) against the bare binary
   fed the same input file on standard input: the share of a run that is start-up and
   Python rather than 6S's own radiative transfer (medians of 15).
2. **One table** (9 km, 10 km ground range, 23 km visibility, the default 221
   wavelengths 0.3-2.5 um): the code before this change (``sixs.py`` of commit
   :data:`BEFORE`, loaded from git), and now with ``workers=1`` and ``workers=2`` (the
   wavelengths shared among 2 processes); medians of :data:`REPEATS`, and a check that all
   three give the same array bit for bit.
3. **One band-only table**: the Olson red band's 17 default-grid samples
   (``sixs.band_wavelengths(0.50e-6, 0.66e-6)``, an explicit option; the default is
   unchanged), ``workers=1`` and ``2``.
4. **A part of the 20-altitude x 40-range x 3-visibility cube**, generated whole with
   ``generate_database(workers=2)`` at the default wavelengths: 8 tables (visibility 23 km;
   altitudes 150 m, 2 km, 9 km; ranges 0, 0.5, 5 km inside the 80-degree limit), and the
   cube's time **extrapolated** from that part's seconds per table: for 2400 tables (every
   table computed) and for the database's first 20 altitudes x first 40 ground ranges
   (those inside the 80-degree view-zenith limit; the rest cost nothing).

Writes ``docs/benchmarks/bench_sixs_generation.json``. Needs the extra ``sixs``::

    python recipes/bench/bench_sixs_generation.py

``--band-cube`` instead generates the **whole** 20-altitude x 40-range x 3-visibility cube
(the database's first 20 altitudes and 40 ground ranges; visibilities 23, 10 and 5 km) on
one camera band, the Olson red band's 17 default-grid samples, with
``generate_database(workers=2)``: measured, not extrapolated. Its finished slabs are kept
in ``--work`` (default ``xbsm-band-cube.parts`` in the system's temporary folder), so an
interrupted run resumes; the wall time of every session of the run is recorded. The file
is then opened as an xbsm database and used for a NIIRS, and the result goes to
``docs/benchmarks/bench_sixs_band_cube.json``::

    python recipes/bench/bench_sixs_generation.py --band-cube
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "recipes"))

from _provenance import commit, machine  # noqa: E402

from xbsm.atmosphere import sixs  # noqa: E402
from xbsm.atmosphere.database import ALTITUDES, GROUND_RANGES  # noqa: E402
from xbsm.examples import OLSON_BANDS  # noqa: E402

OUT = ROOT / "docs" / "benchmarks" / "bench_sixs_generation.json"
BEFORE = "5dd322b"  # main's sixs.py before the speedups: one 6S process at a time
REPEATS = 3
TABLE = dict(altitude=9000.0, ground_range=10000.0, visibility=23.0)


def load() -> list:
    return [round(x, 2) for x in os.getloadavg()]


def before_module():
    """``xbsm.atmosphere.sixs`` as of :data:`BEFORE`, imported beside today's."""
    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{BEFORE}:xbsm/atmosphere/sixs.py"],
                            check=True, capture_output=True, text=True).stdout
    path = Path(tempfile.mkdtemp()) / "sixs_before.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("xbsm.atmosphere._sixs_before", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def per_run(n=15) -> dict:
    from Py6S import Wavelength

    settings = sixs.SixSSettings()
    zenith = float(sixs.view_zenith(TABLE["altitude"], TABLE["ground_range"]))
    s = sixs._wrapper(settings, TABLE["altitude"], zenith, TABLE["visibility"], None)
    s.wavelength = Wavelength(0.55)
    text = Path(s.write_input_file()).read_text()
    py6s, bare = [], []
    for _ in range(n):
        t = time.perf_counter()
        sixs._run(s, 0.55)
        py6s.append(time.perf_counter() - t)
        t = time.perf_counter()
        subprocess.run([s.sixs_path], input=text, capture_output=True, text=True, check=True)
        bare.append(time.perf_counter() - t)
    m_py6s, m_bare = float(np.median(py6s)), float(np.median(bare))
    return {"py6s_run_s_median": m_py6s, "bare_binary_s_median": m_bare,
            "start_up_and_python_share": (m_py6s - m_bare) / m_py6s, "n": n}


def timed(f, **kw):
    t = time.perf_counter()
    out = f(**kw)
    return time.perf_counter() - t, out


def per_table() -> dict:
    old = before_module()
    variants = {"before (one process)": (old.sixs_table, {}),
                "now, workers=1": (sixs.sixs_table, {"workers": 1}),
                "now, workers=2": (sixs.sixs_table, {"workers": 2})}
    times = {k: [] for k in variants}
    tables = {}
    for _ in range(REPEATS):
        for name, (f, kw) in variants.items():
            s, tables[name] = timed(f, **TABLE, **kw)
            times[name].append(s)
            print(name, round(s, 2), load(), flush=True)
    ref = tables["before (one process)"]
    out = {name: {"seconds": t, "median_s": float(np.median(t)),
                  "bit_identical_to_before": bool(np.array_equal(tables[name], ref,
                                                                 equal_nan=True))}
           for name, t in times.items()}
    lo, hi, _ = OLSON_BANDS["red"]
    band = sixs.band_wavelengths(lo, hi)
    full = sixs.DEFAULT_WAVELENGTHS
    where = np.searchsorted(full, band)
    band_times = {1: [], 2: []}
    for _ in range(5):
        for w in (1, 2):
            s, t = timed(sixs.sixs_table, **TABLE, wavelength=band, workers=w)
            band_times[w].append(s)
    out["red band only (17 wavelengths)"] = {
        f"workers={w}": {"seconds": t, "median_s": float(np.median(t))}
        for w, t in band_times.items()}
    out["red band only (17 wavelengths)"]["equal_to_the_full_table_at_its_wavelengths"] = bool(
        np.array_equal(t, ref[:, where]))
    return out


def cube_part() -> dict:
    grid = dict(altitude=[150.0, 2000.0, 9000.0], ground_range=[0.0, 500.0, 5000.0],
                visibility=[23.0])
    inside = int((sixs.view_zenith(np.array(grid["altitude"])[:, None],
                                   np.array(grid["ground_range"])[None, :]) <= 80.0).sum())
    work = Path(tempfile.mkdtemp())
    before = load()
    t = time.perf_counter()
    sixs.generate_database(work / "part.nc", workers=2, **grid)
    seconds = time.perf_counter() - t
    shutil.rmtree(work)
    per_table_s = seconds / inside
    a = np.asarray(ALTITUDES[:20])
    g = np.asarray(GROUND_RANGES[:40])
    database_inside = int((sixs.view_zenith(a[:, None], g[None, :]) <= 80.0).sum()) * 3
    return {
        "part": grid, "part_tables_computed": inside, "part_wall_s": seconds,
        "part_s_per_table_2_processes": per_table_s,
        "load_before": before, "load_after": load(),
        "cube_20x40x3_all_2400_tables_hours_extrapolated": 2400 * per_table_s / 3600,
        "cube_database_grid": {"altitudes_m": a.tolist(), "ground_ranges_m": g.tolist(),
                               "tables_inside_80_deg": database_inside,
                               "hours_extrapolated": database_inside * per_table_s / 3600},
        "note": "EXTRAPOLATED, not run whole: the part's wall seconds per computed table "
                "(2 processes, the default 221 wavelengths) times the cube's tables",
    }


BAND_CUBE_OUT = ROOT / "docs" / "benchmarks" / "bench_sixs_band_cube.json"
BAND_CUBE_VISIBILITIES = [23.0, 10.0, 5.0]


def band_cube(work: Path) -> None:
    """The whole 20 x 40 x 3 cube on the red band, timed; resumable through ``work``."""
    import xarray as xr

    import xbsm
    from xbsm.atmosphere import use_database
    from xbsm.examples import olson_scenario, olson_sensor

    lo, hi, _ = OLSON_BANDS["red"]
    band = sixs.band_wavelengths(lo, hi)
    a, g = np.asarray(ALTITUDES[:20]), np.asarray(GROUND_RANGES[:40])
    inside = int((sixs.view_zenith(a[:, None], g[None, :]) <= 80.0).sum())
    log = work.with_suffix(".sessions.json")
    sessions = json.loads(log.read_text()) if log.exists() else []
    path = work.with_suffix(".nc")
    written = path.exists() and sessions and not work.exists()  # only the report failed
    if not written:
        start = {"load_start": load(), "slabs_done_before": len(list(work.glob("*.npy")))
                 if work.exists() else 0}
        t = time.perf_counter()
        try:
            sixs.generate_database(path, altitude=a.tolist(), ground_range=g.tolist(),
                                   visibility=BAND_CUBE_VISIBILITIES, wavelength=band,
                                   work_dir=work, workers=2, title="20 x 40 x 3 cube, Olson "
                                   "red band (bench_sixs_generation)")
        finally:
            sessions.append({**start, "wall_s": time.perf_counter() - t, "load_end": load()})
            log.write_text(json.dumps(sessions, indent=1))
    wall = sum(x["wall_s"] for x in sessions)
    # the cube is a database xbsm reads: NIIRS of the Olson red camera at 9 km, 10 km range
    sensor = olson_sensor("red")
    with use_database(path):
        niirs = xbsm.niirs(sensor, olson_scenario(ground_range=10000.0, visibility=xr.DataArray(
            BAND_CUBE_VISIBILITIES, dims="visibility")))
    niirs = {str(v): float(niirs.niirs.sel(visibility=v, giqe=5)) for v in BAND_CUBE_VISIBILITIES}
    report = {
        "what": "MEASURED: the whole cube generated on 2 processes (generate_database, "
                "workers=2), the Olson red band's 17 wavelengths",
        "altitudes_m": a.tolist(), "ground_ranges_m": g.tolist(),
        "visibilities_km": BAND_CUBE_VISIBILITIES,
        "wavelengths_m": band.tolist(), "tables": 2400, "tables_inside_80_deg": 3 * inside,
        "six_s_runs": 3 * inside * band.size, "sessions": sessions,
        "wall_s": wall, "wall_h": wall / 3600, "s_per_computed_table": wall / (3 * inside),
        "file_bytes": path.stat().st_size,
        "giqe5_niirs_olson_red_9km_alt_10km_range_by_visibility": niirs,
        "machine": machine(), "commit": commit(),
    }
    BAND_CUBE_OUT.write_text(json.dumps(report, indent=1) + "\n")
    log.unlink()  # the run is whole: the next one starts its own sessions
    print(json.dumps({k: v for k, v in report.items() if k not in
                      ("altitudes_m", "ground_ranges_m", "wavelengths_m", "machine")}, indent=1))


def main():
    if "--band-cube" in sys.argv:
        work = Path(sys.argv[sys.argv.index("--work") + 1]) if "--work" in sys.argv \
            else Path(tempfile.gettempdir()) / "xbsm-band-cube.parts"
        band_cube(work)
        return
    report = {"load_start": load(), "per_run": per_run()}
    print(report, flush=True)
    report["per_table"] = per_table()
    print(json.dumps(report["per_table"], indent=1), flush=True)
    report["cube"] = cube_part()
    report["load_end"] = load()
    report["machine"], report["commit"] = machine(), commit()
    OUT.write_text(json.dumps(report, indent=1) + "\n")
    print(json.dumps(report["cube"], indent=1))


if __name__ == "__main__":
    main()
