"""Visibility x aerosol model with engine-generated tables: NIIRS against range (6S).

The must-show study of issue 24: the Olson camera's red band (``xbsm.examples``,
0.50-0.66 um, the paper's example camera) on its Sec. 3 flight (9 km altitude), at
visibilities 50, 23, 10, 5 and 2 km, with 6S's continental and maritime aerosol models,
every other 6S setting the shipped database's conditions in 6S's terms
(``SixSSettings()``).

``generate``
    Runs 6S (``xbsm.atmosphere.sixs.generate_database``) for each aerosol model on the
    grid altitude 9 km x :data:`GROUND_RANGES` (0-40 km; 40 km is a 77.5 degree view
    zenith) x :data:`VISIBILITIES`, at the default grid's 0.01 um samples that cover the
    red band (``sixs.band_wavelengths(0.50e-6, 0.66e-6)``: 17 wavelengths, each table
    exactly the default grid's table at those wavelengths), on 2 processes, resumable
    (finished chunks in ``recipes/_cache``); stacks the two files along an
    ``aerosol_model`` dimension (6S's codes: 1 continental, 2 maritime) with
    ``from_tables`` and writes ``tests/data/sixs_visibility_aerosol.nc`` (about 30 kB),
    timing the generation per table.
``study``
    Runs ``recipes/studies/visibility_aerosol.toml`` through the public study path
    (``xbsm.study.parse``/``run`` inside ``use_database`` on that file, as
    ``xbsm run --atmosphere FILE`` does), draws NIIRS (GIQE 5) against ground range per
    visibility for each aerosol model into ``docs/figures/engine_visibility_study.png``
    and writes ``docs/benchmarks/engine_visibility_study.json`` (the NIIRS table, whether
    it falls with visibility at every range, and the generation time).

Needs the extra ``sixs``. Run from the repository root::

    python recipes/evidence/engine_visibility_study.py generate
    python recipes/evidence/engine_visibility_study.py study
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "recipes"))

from _provenance import commit, machine  # noqa: E402

import xbsm.atmosphere as atm  # noqa: E402
from xbsm import study  # noqa: E402
from xbsm.atmosphere import sixs  # noqa: E402
from xbsm.examples import OLSON_BANDS  # noqa: E402

CUBE = ROOT / "tests" / "data" / "sixs_visibility_aerosol.nc"
CACHE = ROOT / "recipes" / "_cache" / "engine_visibility_study"
STUDY = ROOT / "recipes" / "studies" / "visibility_aerosol.toml"
OUT = ROOT / "docs" / "benchmarks" / "engine_visibility_study.json"
FIGURE = ROOT / "docs" / "figures" / "engine_visibility_study.png"
ALTITUDES = [9000.0]
GROUND_RANGES = [0.0, 2000.0, 5000.0, 10000.0, 15000.0, 20000.0, 30000.0, 40000.0]
VISIBILITIES = [50.0, 23.0, 10.0, 5.0, 2.0]
MODELS = {1: "Continental", 2: "Maritime"}  # 6S's AeroProfile codes
WORKERS = 2


def load() -> list:
    return [round(x, 2) for x in os.getloadavg()]


def generate() -> dict:
    lo, hi, _ = OLSON_BANDS["red"]
    wavelength = sixs.band_wavelengths(lo, hi)
    CACHE.mkdir(parents=True, exist_ok=True)
    files, timing = [], {}
    for model in MODELS.values():
        path = CACHE / f"{model.lower()}.nc"
        settings = sixs.SixSSettings(aerosol_model=model)
        before = load()
        start = time.perf_counter()
        if not path.exists():
            sixs.generate_database(path, altitude=ALTITUDES, ground_range=GROUND_RANGES,
                                   visibility=VISIBILITIES, wavelength=wavelength,
                                   settings=settings, workers=WORKERS, progress=True,
                                   title=f"6S, {model} aerosols, Olson red band")
            seconds = time.perf_counter() - start
            tables = len(ALTITUDES) * len(GROUND_RANGES) * len(VISIBILITIES)
            timing[model] = {"seconds": seconds, "tables": tables,
                             "seconds_per_table": seconds / tables,
                             "runs_per_table": int(wavelength.size),
                             "load_before": before, "load_after": load()}
            print(model, timing[model], flush=True)
        files.append(path)
    values, attrs = [], None
    for path in files:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            values.append(np.asarray(ds["atmosphere"].transpose(*atm.DIMS).values))
            attrs = attrs or dict(ds.attrs)
            wl = ds["wavelength"].values
    attrs["sixs_aerosol_model"] = "the aerosol_model coordinate: 1 Continental, 2 Maritime"
    attrs["title"] = ("6S: Olson red band, 9 km, visibility x aerosol model "
                      "(recipes/evidence/engine_visibility_study.py)")
    cube = atm.from_tables(np.stack(values), conditions={"aerosol_model": list(MODELS)},
                           visibility=VISIBILITIES, altitude=ALTITUDES,
                           ground_range=GROUND_RANGES, wavelength=wl, attrs=attrs,
                           coordinate_attrs={"aerosol_model": {
                               "flag_values": np.int32(list(MODELS)),
                               "flag_meanings": "continental maritime"}})
    atm.write_database(cube, CUBE)
    atm.check_supported(CUBE)
    print(f"wrote {CUBE} ({CUBE.stat().st_size} bytes)")
    if timing:
        (CACHE / "timing.json").write_text(json.dumps(timing, indent=1))
    return timing


def run_study() -> dict:
    with atm.use_database(CUBE):
        spec = study.parse(STUDY.read_text(), STUDY.name)
        result = study.run(spec)
    niirs = result["niirs"]
    if "giqe" in niirs.dims:
        niirs = niirs.sel(giqe=5)
    niirs = niirs.transpose("aerosol_model", "ground_range", "visibility")
    steps = niirs.diff("visibility")  # visibility falls along the dim
    report = {
        "cube": str(CUBE.relative_to(ROOT)), "cube_bytes": CUBE.stat().st_size,
        "study": str(STUDY.relative_to(ROOT)),
        "visibility_km": VISIBILITIES, "ground_range_m": GROUND_RANGES,
        "aerosol_model": MODELS,
        "niirs_giqe5": {MODELS[int(m)]: np.round(niirs.sel(aerosol_model=m).values, 4).tolist()
                        for m in niirs["aerosol_model"].values},
        "niirs_falls_as_visibility_falls_everywhere": bool((steps < 0).all()),
        "largest_step": float(steps.max()),
        "flags_set": sorted({int(f) for f in np.unique(result["flags"].values)}),
    }
    timing_file = CACHE / "timing.json"
    if timing_file.exists():
        report["generation"] = json.loads(timing_file.read_text())
    report["machine"], report["commit"] = machine(), commit()
    OUT.write_text(json.dumps(report, indent=1) + "\n")
    figure(niirs)
    print(json.dumps({k: report[k] for k in ("niirs_falls_as_visibility_falls_everywhere",
                                             "largest_step")}))
    return report


def figure(niirs):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, code in zip(axes, niirs["aerosol_model"].values, strict=True):
        for v in niirs["visibility"].values:
            ax.plot(niirs["ground_range"] / 1e3,
                    niirs.sel(aerosol_model=code, visibility=v), marker="o", label=f"{v:g} km")
        ax.set_title(f"6S {MODELS[int(code)].lower()} aerosols")
        ax.set_xlabel("ground range (km)")
        ax.grid(alpha=0.3)
        off = niirs.sel(aerosol_model=code).where(niirs.sel(aerosol_model=code) < 0)
        for g, v in zip(*np.nonzero(np.isfinite(off.values)), strict=True):  # off the axis
            ax.annotate(f"{float(off[g, v]):.0f}", (float(niirs["ground_range"][g]) / 1e3, 0.2),
                        ha="center", fontsize=8, color="C4")
        ax.set_ylim(0, 10.5)
    axes[0].set_ylabel("NIIRS (GIQE 5; values below 0 written at the axis)")
    axes[1].legend(title="visibility")
    fig.suptitle("Olson camera, red band, 9 km altitude: 6S-generated tables")
    fig.tight_layout()
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(FIGURE, dpi=100)


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "all"
    if what in ("generate", "all"):
        generate()
    if what in ("study", "all"):
        run_study()
