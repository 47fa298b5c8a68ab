"""The open engine (6S) against the shipped MODTRAN 5.2.1 tables at the database's conditions.

At the conditions of the pyBSM paper's Appendix A in 6S's terms
(``xbsm.atmosphere.sixs.SixSSettings()``: mid-latitude summer, continental aerosols at
23 and 5 km visibility, sun zenith 50 deg, 90 deg azimuth from the line of sight, 23 August,
15 % target on green vegetation), this recipe

1. generates 6S tables with ``generate_database`` at every database altitude up to 24.5 km
   and the ground ranges 0, 10 and 30 km (those within the database's coverage and 6S's
   80-degree view-zenith limit), both visibilities, at the 14 :data:`WAVELENGTHS` (0.05 um
   apart to 0.7 um, then 0.8, 0.9, 1.0, 1.3, 1.6, 2.0, 2.5 um: the cost of 6S, 0.4-2 s a
   wavelength on a loaded 2-core machine, sets the sampling; a "band mean" is the
   trapezoid mean over these samples for both engines, not the true band average);
2. compares band means (trapezoid over the same wavelengths for both) of TRANS, SOL_SCAT
   (the solar path radiance) and GRND_RFLT with the shipped tables over visible
   (0.4-0.7 um), red (0.6-0.7), NIR (0.7-1.0) and SWIR (1.0-2.5): median, 95th percentile
   and worst relative difference, per visibility and band; and the share of the
   database's path radiance that is thermal (PTH_THRML, which 6S sets to zero);
3. runs ``xbsm.niirs`` on the Olson camera (``xbsm.examples``, red and NIR bands, 9 km
   altitude, ground ranges 0, 10 and 30 km, both visibilities) once on a 6S cube and once
   on the shipped tables cut to the same grid (altitudes 8, 9, 10 km; ranges 0, 10, 30 km;
   0.50-0.86 um every 0.04 um, samples of the database's grid) through
   ``from_tables``/``use_database``, so the two differ only in the engine: SNR ratio and
   NIIRS difference (GIQE 5);
4. times 6S: seconds per run and per table (221 wavelengths, 0.3-2.5 um at 0.01 um),
   and estimates a 20-altitude x 40-range x 3-visibility cube on 2 cores from the
   measured time per run and from the validation's throughput (the cube itself would take
   days on this shared machine).

Writes ``docs/benchmarks/engine_validation.json``. Needs the extra ``sixs``. Run from the
repository root::

    python recipes/evidence/engine_validation.py [--work DIR]  # DIR keeps finished chunks
    python recipes/evidence/engine_validation.py --table   # docs/atmosphere.md's tables
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import xbsm  # noqa: E402
import xbsm.atmosphere as atm  # noqa: E402
from xbsm.atmosphere import sixs  # noqa: E402
from xbsm.examples import olson_scenario, olson_sensor  # noqa: E402

trapezoid = getattr(np, "trapezoid", None) or np.trapz  # numpy < 2: trapz
OUT = Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "engine_validation.json"
WAVELENGTHS = 1e-6 * np.array([0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.80, 0.90, 1.00,
                               1.30, 1.60, 2.00, 2.50])
GROUND_RANGES = np.array([0.0, 10000.0, 30000.0])
BANDS = {"visible 0.4-0.7 um": (0.4e-6, 0.7e-6), "red 0.6-0.7 um": (0.6e-6, 0.7e-6),
         "NIR 0.7-1.0 um": (0.7e-6, 1.0e-6), "SWIR 1.0-2.5 um": (1.0e-6, 2.5e-6)}
COMPONENTS = ("TRANS", "SOL_SCAT", "GRND_RFLT")
OLSON_ALTITUDES = np.array([8000.0, 9000.0, 10000.0])
OLSON_RANGES = np.array([0.0, 10000.0, 30000.0])
OLSON_WAVELENGTHS = 1e-6 * np.round(np.arange(0.50, 0.8601, 0.04), 2)


def shipped(altitude, ground_range, wavelength):
    """The shipped tables on a sub-grid, in the file's units (NaN where absent)."""
    with xr.open_dataset(atm.database_path(), engine="netcdf4") as ds:
        cube = ds["atmosphere"].sel(altitude=altitude, ground_range=ground_range,
                                    visibility=[23.0, 5.0])
        index = np.rint((wavelength * 1e6 - 0.3) / 0.01).astype(int)  # the 0.01 um grid
        return cube.isel(wavelength=index).load()


def band_mean(values, wavelength, lo, hi):
    """Trapezoid mean over the samples within [lo, hi] along the last axis."""
    inside = (wavelength >= lo * (1 - 1e-9)) & (wavelength <= hi * (1 + 1e-9))
    w = wavelength[inside]
    return trapezoid(values[..., inside], w, axis=-1) / (w[-1] - w[0])


def generated(path, **grid):
    """Generate ``path`` on 2 threads unless a run with ``--work`` already did; wall time."""
    clock = path.with_suffix(".wall_s.json")
    if not path.exists():
        started = time.perf_counter()
        sixs.generate_database(path, workers=2, progress=True,
                               work_dir=path.with_suffix(".parts"), **grid)
        clock.write_text(json.dumps(time.perf_counter() - started))
    return json.loads(clock.read_text())


def vertical_depths(engine, modtran):
    """-ln TRANS at 0.55 um straight down from 24.5 km: the column each code holds."""
    out = {}
    for name, cube in (("sixs", engine), ("modtran", modtran)):
        trans = cube.sel(component="TRANS", altitude=24500.0, ground_range=0.0)
        trans = trans.isel(wavelength=int(np.argmin(np.abs(WAVELENGTHS - 0.55e-6))))
        for vis in (23.0, 5.0):
            out[f"{name} {vis:g} km"] = round(float(-np.log(trans.sel(visibility=vis))), 4)
    return out


def validation(work):
    altitude = np.array([a for a in atm.ALTITUDES if a <= 24500.0])
    path = Path(work) / "sixs_validation.nc"
    seconds = generated(path, altitude=altitude, ground_range=GROUND_RANGES,
                        visibility=[23.0, 5.0], wavelength=WAVELENGTHS)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        engine = ds["atmosphere"].load()
    modtran = shipped(altitude, GROUND_RANGES, WAVELENGTHS)
    present = np.isfinite(engine.isel(component=0, wavelength=0).values) & \
        np.isfinite(modtran.isel(component=0, wavelength=0).values)
    stats = {}
    for band, (lo, hi) in BANDS.items():
        for vis_i, vis in enumerate((23.0, 5.0)):
            for comp in COMPONENTS:
                e = band_mean(engine.sel(component=comp).values, WAVELENGTHS, lo, hi)
                m = band_mean(modtran.sel(component=comp).values, WAVELENGTHS, lo, hi)
                ok = present[vis_i]
                rel = (e[vis_i][ok] - m[vis_i][ok]) / m[vis_i][ok]
                worst = rel[np.argmax(np.abs(rel))]
                stats[f"{comp} | {band} | {vis:g} km"] = {
                    "median_abs": round(float(np.median(np.abs(rel))), 4),
                    "p95_abs": round(float(np.percentile(np.abs(rel), 95)), 4),
                    "worst": round(float(worst), 4),
                    "median_signed": round(float(np.median(rel)), 4),
                    "tables": int(ok.sum())}
            th = band_mean(modtran.sel(component="PTH_THRML").values, WAVELENGTHS, lo, hi)
            ss = band_mean(modtran.sel(component="SOL_SCAT").values, WAVELENGTHS, lo, hi)
            share = th[vis_i][present[vis_i]] / (th + ss)[vis_i][present[vis_i]]
            stats[f"PTH_THRML share of MODTRAN path radiance | {band} | {vis:g} km"] = {
                "max": float(f"{share.max():.3g}")}
    stats["vertical optical depth at 0.55 um from 24.5 km (-ln TRANS)"] = vertical_depths(
        engine, modtran)
    return stats, {"tables": int(present.sum()), "runs": int(present.sum()) * WAVELENGTHS.size,
                   "wall_s": round(seconds, 1)}


def olson(work):
    engine_path = Path(work) / "sixs_olson.nc"
    seconds = generated(engine_path, altitude=OLSON_ALTITUDES, ground_range=OLSON_RANGES,
                        visibility=[23.0, 5.0], wavelength=OLSON_WAVELENGTHS)
    with xr.open_dataset(atm.database_path(), engine="netcdf4") as ds:
        attrs = dict(ds.attrs)
    cut = atm.from_tables(shipped(OLSON_ALTITUDES, OLSON_RANGES, OLSON_WAVELENGTHS)
                          .transpose(*atm.DIMS).values,
                          visibility=[23.0, 5.0], altitude=OLSON_ALTITUDES,
                          ground_range=OLSON_RANGES, wavelength=OLSON_WAVELENGTHS,
                          attrs=attrs)
    modtran_path = atm.write_database(cut, Path(work) / "modtran_cut.nc")
    scen = olson_scenario(ground_range=xr.DataArray(OLSON_RANGES, dims="ground_range"),
                          visibility=xr.DataArray([23.0, 5.0], dims="visibility"))
    out = {}
    for band in ("red", "nir"):
        results = {}
        for name, p in (("modtran", modtran_path), ("sixs", engine_path)):
            with atm.use_database(p):
                results[name] = xbsm.niirs(olson_sensor(band), scen).compute()
        m, e = results["modtran"], results["sixs"]
        for vis in (23.0, 5.0):
            for g in OLSON_RANGES:
                sel = dict(visibility=vis, ground_range=g)
                key = f"{band} | {vis:g} km | ground range {g / 1e3:g} km"
                out[key] = {
                    "snr_modtran": round(float(m.snr.sel(sel)), 2),
                    "snr_sixs": round(float(e.snr.sel(sel)), 2),
                    "snr_ratio": round(float(e.snr.sel(sel) / m.snr.sel(sel)), 4),
                    "niirs5_modtran": round(float(m.niirs.sel({**sel, "giqe": 5})), 3),
                    "niirs5_difference": round(
                        float((e.niirs - m.niirs).sel({**sel, "giqe": 5})), 3)}
    return out, {"tables": 18, "wall_s": round(seconds, 1)}


def timing():
    settings = sixs.SixSSettings()
    per_run = []
    for _ in range(5):
        started = time.perf_counter()
        sixs.sixs_table(9000.0, 10000.0, 23.0, wavelength=[0.65e-6], settings=settings)
        per_run.append(time.perf_counter() - started)
    run_s = float(np.median(per_run))
    table_s = run_s * sixs.DEFAULT_WAVELENGTHS.size
    cube_tables = 20 * 40 * 3
    return {"seconds_per_run_median": round(run_s, 3),
            "seconds_per_table_221_wavelengths_estimated": round(table_s, 1),
            "cube_20x40x3_tables": cube_tables,
            "cube_20x40x3_2_cores_hours_estimated": round(cube_tables * table_s / 2 / 3600, 1),
            "note": "estimated from the median time of one 6S run (aircraft at 9 km, one "
                    "wavelength) times 221 wavelengths a table, over 2 worker threads (each "
                    "runs the 6S binary in its own process); not run whole (days on this "
                    "shared machine)",
            "load_average_before": [round(x, 2) for x in os.getloadavg()]}


def markdown(result) -> str:
    """The tables of docs/atmosphere.md from the JSON (``--table``)."""
    rows = ["| band | visibility | component | median abs | 95th pct abs | worst | median "
            "(signed) |", "|---|---|---|---|---|---|---|"]
    for key, v in result["band_statistics"].items():
        parts = [p.strip() for p in key.split("|")]
        if len(parts) == 3 and parts[0] in COMPONENTS:
            comp, band, vis = parts
            rows.append(f"| {band} | {vis} | {comp} | {v['median_abs']:.1%} | "
                        f"{v['p95_abs']:.1%} | {v['worst']:+.1%} | {v['median_signed']:+.1%} |")
    rows += ["", "| band | visibility | ground range | SNR MODTRAN | SNR 6S | ratio | NIIRS 5 "
             "MODTRAN | NIIRS 6S - MODTRAN |", "|---|---|---|---|---|---|---|---|"]
    for key, v in result["olson_camera_niirs"].items():
        band, vis, rng = (p.strip() for p in key.split("|"))
        rows.append(f"| {band} | {vis} | {rng.replace('ground range ', '')} | "
                    f"{v['snr_modtran']:.1f} | {v['snr_sixs']:.1f} | {v['snr_ratio']:.3f} | "
                    f"{v['niirs5_modtran']:.2f} | {v['niirs5_difference']:+.3f} |")
    return "\n".join(rows)


def main():
    if "--table" in sys.argv:
        print(markdown(json.loads(OUT.read_text())))
        return
    from _provenance import commit, machine

    work_arg = sys.argv[sys.argv.index("--work") + 1] if "--work" in sys.argv else None
    with tempfile.TemporaryDirectory() as scratch:
        work = work_arg or scratch
        time_before = timing()
        stats, validation_run = validation(work)
        snr, olson_run = olson(work)
    per_second = validation_run["runs"] / validation_run["wall_s"]  # measured on 2 threads
    validation_run["runs_per_second_2_threads"] = round(per_second, 2)
    time_before["cube_20x40x3_2_cores_hours_from_validation_throughput"] = round(
        20 * 40 * 3 * sixs.DEFAULT_WAVELENGTHS.size / per_second / 3600, 1)
    result = {
        "what": "6S (xbsm.atmosphere.sixs, default SixSSettings) against the shipped MODTRAN "
                "5.2.1 tables at Appendix A conditions; relative difference (6S - MODTRAN) / "
                "MODTRAN of band means",
        "engine": sixs.engine_versions(),
        "wavelengths_um": [round(float(w) * 1e6, 2) for w in WAVELENGTHS],
        "ground_ranges_m": GROUND_RANGES.tolist(),
        "band_statistics": stats,
        "olson_camera_niirs": snr,
        "timing": {**time_before, "validation_cube": validation_run, "olson_cubes": olson_run,
                   "load_average_after": [round(x, 2) for x in os.getloadavg()]},
        "machine": machine(), "commit": commit(),
    }
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
