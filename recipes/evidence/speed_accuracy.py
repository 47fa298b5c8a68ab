"""Speed against accuracy of xbsm's numerical methods, with pyBSM 0.16.1 on the same chart.

For four representative systems, every method preset and a range of knob
settings, this recipe measures

- the median wall time of one ``xbsm.niirs`` call on a sweep of scenarios
  (default 172: altitudes 3 and 9 km x the 43 database ground ranges
  0-60 km x visibility 23 and 5 km; ``--quick``: 9 km only, 86), divided by the number of scenarios;
- the NIIRS error: max |NIIRS - reference| over the sweep, for GIQE 3, 4 and
  5 separately (scenarios where the reference is NaN are skipped and counted);

against a *reference* that is 16x finer in every numerical knob and models
exactly what the method under test models, so that the error is numerical:

- ``REFERENCE["accurate"]`` for ``accurate``, ``fast`` and their knob
  variants: ``method("accurate", nodes_per_panel=40, panels_per_oscillation=4,
  min_panels=32, otf_wavelengths=0, turbulence_path_samples=1024)`` (4 x 4 =
  16x the frequency nodes of ``accurate`` at every Q, every database
  wavelength, 16x the r0 path nodes);
- ``REFERENCE["pybsm"]`` for pyBSM's uniform trapezoid rule at any N and for
  pyBSM itself: ``method("pybsm", edge_rule="gauss_legendre", <the same fine
  knobs>, turbulence_path_rule="gauss-legendre")``: |OTF|, look-down
  elevation, GIQE 4 coefficient 0.334, exact (snapped) band edges, linear
  atmosphere and pyBSM's constants and filter OTF, but converged quadrature.

Each reference is checked against the same rule at 4x (half the nodes and
panels in each direction); that difference is reported as the reference's own
error estimate.

pyBSM itself is timed per scenario (``niirs`` + ``niirs5``, with Sensor and
Scenario construction) on a random sample of the sweep, in its own
environment (``$PYBSM_PYTHON``, ``NUMBA_NUM_THREADS=1``) through
``recipes/_pybsm_runner.py``, in the same run.

The modelling differences between presets (not numerical errors) are reported
separately: |OTF| vs OTF in the edge response, look-down vs target elevation,
GIQE 4 noise coefficient 0.334 vs 0.344, each switched alone on ``accurate``
(max and median over the cells with SNR >= 2, the GIQE's calibration floor).

A second study sweeps Q = lambda_min F / p from 0.02 to 2 (focal length, 31
values) for pyBSM's uniform rule at N = 101 ... 1601 and records its NIIRS
error against the pybsm reference as a function of the samples per
oscillation of sin(2 pi f ifov x) at x = 3 px, the quantity that
``undersampling_threshold`` is compared with; it also records the error of
the ``accurate`` and ``fast`` presets against the accurate reference at
every Q.

Outputs: ``docs/benchmarks/speed_accuracy.json``,
``docs/figures/speed_accuracy.png`` (error vs time per scenario),
``docs/figures/speed_accuracy_threshold.png`` (error vs samples per
oscillation). ``docs/speed_accuracy.md`` quotes them.

Run from the repository root with the project environment; pyBSM's own
environment is made on first use, or ``$PYBSM_PYTHON`` names one (about 6 min
on a 2-core machine; ``--quick`` about 2 min; see ``recipes/README.md``)::

    .venv/bin/python recipes/evidence/speed_accuracy.py [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

import numpy as np
import xarray as xr
from _provenance import machine

import xbsm
from xbsm.atmosphere import VISIBILITIES
from xbsm.flags import has_flag
from xbsm.model import niirs
from xbsm.quadrature import pybsm_slice_count

HERE = Path(__file__).resolve().parent
DOCS = HERE.parents[1] / "docs"
GIQE = (3, 4, 5)

GROUND_RANGES = np.concatenate([[0.0, 100.0, 500.0], np.arange(1000.0, 20001.0, 1000.0),
                                np.arange(22000.0, 60001.0, 2000.0)])
ALTITUDES = (3000.0, 9000.0)
IHAZE = {23.0: 1, 5.0: 2}

_OLSON = dict(D=0.275, f=4.0, p_x=8e-6, eta=0.4, int_time=0.03, read_noise=25.0, max_n=96000.0,
              bit_depth=11.9, max_well_fill=0.6, s_x=5e-7, s_y=5e-7, da_x=1e-4, da_y=1e-4,
              dark_current=1e-5 * 64e-12 / 1.60217662e-19,
              opt_trans_wavelengths=[0.55e-6, 0.85e-6], qe=[0.71, 0.71],
              qe_wavelengths=[0.55e-6, 0.85e-6], optics_transmission=[0.5, 0.5])
SYSTEMS = {
    "well_sampled": dict(
        label="Olson NIR camera (paper Table 2), Q = 1.0",
        pybsm=dict(_OLSON)),
    "q0.3": dict(
        label="Olson NIR, f = 1.2 m, Q = 0.30",
        pybsm=dict(_OLSON, f=1.2, s_x=0.25 * 8e-6 / 1.2, s_y=0.25 * 8e-6 / 1.2)),
    "q0.05": dict(
        label="D = 10 cm, F/1.5, 16 um pixels, NIR, Q = 0.052",
        pybsm=dict(_OLSON, D=0.1, f=0.15, p_x=16e-6, eta=0.0,
                   s_x=0.25 * 16e-6 / 0.15, s_y=0.25 * 16e-6 / 0.15,
                   dark_current=1e-5 * 256e-12 / 1.60217662e-19)),
    "lwir": dict(
        label="LWIR 8-12 um, D = 20 cm, F/2, 15 um pixels, Q = 1.07",
        pybsm=dict(D=0.2, f=0.4, p_x=15e-6, eta=0.0, int_time=2e-3, read_noise=100.0,
                   max_n=2e7, bit_depth=14.0, max_well_fill=0.8, s_x=0.25 * 15e-6 / 0.4,
                   s_y=0.25 * 15e-6 / 0.4, da_x=1e-4, da_y=1e-4, dark_current=0.0,
                   opt_trans_wavelengths=[8e-6, 12e-6], qe=[0.6, 0.6],
                   qe_wavelengths=[8e-6, 12e-6], optics_transmission=[0.8, 0.8],
                   cold_shield_temperature=77.0, optics_temperature=270.0,
                   optics_emissivity=0.05, cold_filter_transmission=0.9,
                   cold_filter_temperature=77.0, cold_filter_emissivity=0.02)),
}

FINE = dict(nodes_per_panel=40, panels_per_oscillation=4.0, min_panels=32, otf_wavelengths=0,
            turbulence_path_samples=1024)
"""16x the frequency nodes of "accurate" (4x nodes per panel x 4x panels), every
wavelength, 16x its r0 path nodes."""
HALF = dict(nodes_per_panel=20, panels_per_oscillation=2.0, min_panels=16, otf_wavelengths=0,
            turbulence_path_samples=256)
"""4x "accurate": the reference's self-check."""
REFERENCE = {
    "accurate": xbsm.method("accurate", **FINE),
    "pybsm": xbsm.method("pybsm", edge_rule="gauss_legendre",
                         turbulence_path_rule="gauss-legendre", **FINE),
}
REFERENCE_HALF = {
    "accurate": xbsm.method("accurate", **HALF),
    "pybsm": xbsm.method("pybsm", edge_rule="gauss_legendre",
                         turbulence_path_rule="gauss-legendre", **HALF),
}


def configurations(quick):
    """(label, family, reference key, method) for every point on the chart."""
    out = [("preset pybsm (N = 101)", "preset", "pybsm", xbsm.method("pybsm")),
           ("preset fast", "preset", "accurate", xbsm.method("fast")),
           ("preset accurate", "preset", "accurate", xbsm.method("accurate"))]
    for n in ((201, 401, 1601) if quick else (201, 401, 801, 1601, 3201)):
        out.append((f"pybsm rule N = {n}", "pybsm frequency_samples", "pybsm",
                    xbsm.method("pybsm", frequency_samples=n)))
    gl = ((4, 4, 1.0), (6, 4, 1.0), (10, 8, 0.5)) if quick else (
        (4, 4, 1.0), (6, 4, 1.0), (6, 4, 0.5), (8, 8, 1.0), (10, 8, 0.5), (16, 8, 1.0))
    for npp, mp, ppo in gl:
        out.append((f"gauss_legendre {npp} x max({mp}, {ppo:g}/osc)", "gauss_legendre knobs",
                    "accurate", xbsm.method("accurate", nodes_per_panel=npp, min_panels=mp,
                                            panels_per_oscillation=ppo)))
    for nw in ((4, 8) if quick else (4, 8, 16)):
        out.append((f"otf_wavelengths = {nw}", "otf_wavelengths", "accurate",
                    xbsm.method("accurate", otf_wavelengths=nw)))
    out.append(("candidate fast: 8 x max(8, 1/osc), 16 wavelengths", "candidate", "accurate",
                xbsm.method("fast", nodes_per_panel=8, min_panels=8, otf_wavelengths=16)))
    for ns in ((8,) if quick else (8, 16, 32)):
        out.append((f"turbulence_path_samples = {ns}", "turbulence_path_samples", "accurate",
                    xbsm.method("accurate", turbulence_path_samples=ns)))
    return out


def xbsm_inputs(system, altitudes):
    kw = dict(SYSTEMS[system]["pybsm"])
    sensor = xbsm.pybsm_compat.sensor(**kw)
    scenario = xbsm.scenario(
        altitude=xr.DataArray(list(altitudes), dims="altitude"),
        ground_range=xr.DataArray(GROUND_RANGES, dims="ground_range"),
        visibility=xr.DataArray(list(VISIBILITIES), dims="visibility"),
    )
    return sensor, scenario


def errors(values, reference):
    """Max |error| per GIQE version over the sweep (giqe is the last axis after moving)."""
    out = {}
    for k, g in enumerate(GIQE):
        ref = reference[k]
        got = values[k]
        finite = np.isfinite(ref)
        diff = np.abs(got[finite] - ref[finite])
        out[str(g)] = float(np.max(np.where(np.isnan(diff), np.inf, diff)))
    return out


def pybsm_cases(system, sample):
    kw = dict(SYSTEMS[system]["pybsm"])
    post = {"optics_transmission": kw.pop("optics_transmission")}
    cases = []
    for alt, gr, vis in sample:
        cases.append({"sensor": dict(kw, name=system, post=post),
                      "scenario": {"name": "s", "ihaze": IHAZE[vis], "altitude": alt,
                                   "ground_range": gr}})
    return cases


def run_system(system, args, rng):
    altitudes = (9000.0,) if args.quick else ALTITUDES
    sensor, scenario = xbsm_inputs(system, altitudes)
    n_scen = len(altitudes) * GROUND_RANGES.size * len(VISIBILITIES)
    print(f"\n== {system}: {SYSTEMS[system]['label']} ({n_scen} scenarios)", flush=True)

    def run(method):
        """One xbsm.niirs call: its wall time and the NIIRS values (dims as returned)."""
        t0 = time.perf_counter()
        values = niirs(sensor, scenario, method)["niirs"].values
        return time.perf_counter() - t0, values

    dims = niirs(sensor, scenario, "pybsm")["niirs"].dims
    order = [dims.index(d) for d in ("giqe", "altitude", "ground_range", "visibility")]

    def canonical(values):
        return np.transpose(values, order).reshape(3, -1)

    refs, ref_times, self_check = {}, {}, {}
    for key in REFERENCE:
        seconds, values = run(REFERENCE[key])
        refs[key] = canonical(values)
        ref_times[key] = seconds / n_scen
        _, half = run(REFERENCE_HALF[key])
        self_check[key] = errors(canonical(half), refs[key])
        print(f"reference {key}: {seconds:.1f} s; |ref - ref(4x)| = {self_check[key]}",
              flush=True)
    nan_counts = {key: int(np.sum(~np.isfinite(v))) for key, v in refs.items()}

    configs = configurations(args.quick)
    values = {}
    for label, _, _, method in configs:  # one call each: the values, and the warm-up
        values[label] = canonical(niirs(sensor, scenario, method)["niirs"].values)
    # timing in rounds over every configuration, so that load from other processes on a
    # shared machine spreads over all of them instead of hitting a few; median per point
    times = {label: [] for label, *_ in configs}
    for _ in range(args.repeats):
        for label, _, _, method in configs:
            t0 = time.perf_counter()
            niirs(sensor, scenario, method)["niirs"].values  # noqa: B018
            times[label].append(time.perf_counter() - t0)
    points = []
    for label, family, ref_key, method in configs:
        seconds = statistics.median(times[label])
        err = errors(values[label], refs[ref_key])
        points.append({"label": label, "family": family, "reference": ref_key,
                       "method": method.name,
                       "knobs": {k: getattr(method, k) for k in (
                           "edge_rule", "frequency_samples", "nodes_per_panel", "min_panels",
                           "panels_per_oscillation", "otf_wavelengths",
                           "turbulence_path_samples")},
                       "time_per_scenario_s": seconds / n_scen, "sweep_time_s": seconds,
                       "sweep_times_s": times[label], "error": err})
        print(f"{label:42s} {seconds / n_scen * 1e3:7.3f} ms/scenario  "
              + "  ".join(f"G{g} {err[str(g)]:.2e}" for g in GIQE), flush=True)

    # modelling differences, each switched alone on "accurate"; statistics over the cells
    # inside the GIQE's SNR range (>= 2): at SNR -> 0 any G/SNR change is unbounded
    acc_ds = niirs(sensor, scenario, "accurate")
    acc = canonical(acc_ds["niirs"].values)
    snr_ok = (acc_ds["snr"].transpose("altitude", "ground_range", "visibility").values
              .reshape(-1) >= 2.0)
    modelling = {"cells_with_snr_at_least_2": int(snr_ok.sum()), "cells": int(snr_ok.size)}
    for name, knobs in (("|OTF| instead of OTF (edge_otf='abs')", dict(edge_otf="abs")),
                        ("look-down instead of target elevation", dict(elevation="look-down")),
                        ("GIQE 4 coefficient 0.334 instead of 0.344",
                         dict(giqe4_noise_coefficient=0.334)),
                        ("all pyBSM modelling (reference pybsm - reference accurate)", None)):
        if knobs is None:
            diff = np.abs(refs["pybsm"] - refs["accurate"])
        else:
            _, other = run(xbsm.method("accurate", **knobs))
            diff = np.abs(canonical(other) - acc)
        modelling[name] = {str(g): {"max": float(np.nanmax(diff[k][snr_ok])),
                                    "median": float(np.nanmedian(diff[k][snr_ok])),
                                    "max_all_cells": float(np.nanmax(diff[k]))}
                           for k, g in enumerate(GIQE)}

    # pyBSM itself, on a sample of the sweep
    flat = [(a, gr, v) for a in altitudes for gr in GROUND_RANGES for v in VISIBILITIES]
    pick = sorted(rng.choice(len(flat), size=min(args.pybsm_sample, len(flat)), replace=False))
    pyb = None
    if not args.no_pybsm:
        from _pybsm_runner import run_pybsm

        got = run_pybsm("niirs", pybsm_cases(system, [flat[i] for i in pick]))
        values = np.asarray(got["values"], dtype=float).T  # (giqe, sample)
        xbsm_101 = next(p for p in points if p["label"].startswith("preset pybsm"))
        _, preset = run(xbsm.method("pybsm"))
        preset = canonical(preset)[:, pick]
        pyb = {"sample_size": len(pick),
               "time_per_scenario_s": statistics.median(got["times"]),
               "error": errors(values, refs["pybsm"][:, pick]),
               "max_abs_difference_to_xbsm_pybsm_preset": float(np.nanmax(np.abs(
                   values - preset))),
               "xbsm_pybsm_preset_error_on_sample": errors(preset, refs["pybsm"][:, pick]),
               "xbsm_pybsm_preset_error_on_sweep": xbsm_101["error"]}
        print(f"pyBSM 0.16.1: {pyb['time_per_scenario_s'] * 1e3:.1f} ms/scenario (median of "
              f"{len(pick)}), error {pyb['error']}, |pyBSM - xbsm pybsm| = "
              f"{pyb['max_abs_difference_to_xbsm_pybsm_preset']:.1e}", flush=True)

    lam_min = SYSTEMS[system]["pybsm"]["opt_trans_wavelengths"][0]
    p = SYSTEMS[system]["pybsm"]
    return {"label": SYSTEMS[system]["label"],
            "Q_at_lambda_min": lam_min * p["f"] / p["D"] / p["p_x"],
            "pybsm_kwargs": p, "scenarios": n_scen,
            "reference_time_per_scenario_s": ref_times,
            "reference_self_check": self_check, "reference_nan_cells": nan_counts,
            "points": points, "pybsm": pyb, "modelling": modelling}


def q_sweep(args):
    """Error of pyBSM's uniform rule against the pybsm reference as a function of Q."""
    qs = np.geomspace(0.02, 2.0, 9 if args.quick else 31)
    sizes = (101, 401) if args.quick else (101, 201, 401, 801, 1601)
    scenario = xbsm.scenario(altitude=9000.0,
                             ground_range=xr.DataArray([0.0, 10000.0, 30000.0],
                                                       dims="ground_range"),
                             visibility=23.0)
    out = {"Q": qs.tolist(), "grid_sizes": list(sizes), "systems": {}}
    variants = {
        "olson": dict(_OLSON),
        "sharp (no jitter, drift or turbulence)": dict(_OLSON, s_x=0.0, s_y=0.0, da_x=0.0,
                                                        da_y=0.0),
    }
    for name, kw in variants.items():
        sc = scenario if "sharp" not in name else scenario.assign(
            cn2_at_1m=xr.zeros_like(scenario["cn2_at_1m"]))
        rows = []
        for q in qs:
            focal = q * kw["D"] * kw["p_x"] / kw["opt_trans_wavelengths"][0]
            s = xbsm.pybsm_compat.sensor(**dict(kw, f=focal))
            ref = niirs(s, sc, REFERENCE["pybsm"])["niirs"].transpose("giqe", ...).values
            ref_acc = niirs(s, sc, REFERENCE["accurate"])["niirs"].transpose("giqe", ...).values
            row = {"Q": float(q), "by_grid": {}, "presets": {}}
            for preset in ("accurate", "fast"):
                got = niirs(s, sc, preset)["niirs"].transpose("giqe", ...).values
                err = np.abs(got - ref_acc).reshape(3, -1)
                row["presets"][preset] = {str(g): float(np.nanmax(err[k]))
                                          for k, g in enumerate(GIQE)}
            for n in sizes:
                r = niirs(s, sc, xbsm.method("pybsm", frequency_samples=n))
                # the flag's own measure: slice samples / (cutoff * ifov * 3 px)
                spo = pybsm_slice_count(n) * q / 3.0
                err = np.abs(r["niirs"].transpose("giqe", ...).values - ref).reshape(3, -1)
                row["by_grid"][str(n)] = {
                    "samples_per_oscillation": spo,
                    "flagged_now": bool(has_flag(r["flags"], "undersampled_grid").any()),
                    "error": {str(g): float(np.nanmax(err[k])) for k, g in enumerate(GIQE)}}
            rows.append(row)
        out["systems"][name] = rows
        print(f"Q sweep {name}: done", flush=True)
    return out


RECOMMENDED_THRESHOLD = 2.0
"""undersampling_threshold recommended from the Q sweep (docs/speed_accuracy.md): the
largest samples per oscillation with a NIIRS error above 0.01 was 1.33; every point at
>= 2 was within 6.3e-3."""


def envelope(qs, starts=(1.0, 1.25, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 16.0)):
    """Max error of the pybsm rule over every point with at least s samples per oscillation."""
    out = []
    for s in starts:
        errs = {str(g): 0.0 for g in GIQE}
        count = 0
        for rows in qs["systems"].values():
            for row in rows:
                for v in row["by_grid"].values():
                    if v["samples_per_oscillation"] >= s:
                        count += 1
                        for g in GIQE:
                            errs[str(g)] = max(errs[str(g)], v["error"][str(g)])
        out.append({"samples_per_oscillation_at_least": s, "points": count, "max_error": errs})
    return out


def threshold_from(qs, bound):
    """Smallest samples/oscillation s such that every point with >= s is within ``bound``."""
    pts = []
    for rows in qs["systems"].values():
        for row in rows:
            for v in row["by_grid"].values():
                pts.append((v["samples_per_oscillation"], max(v["error"].values())))
    pts.sort()
    bad = [s for s, e in pts if e > bound]
    return (max(bad) if bad else 0.0), pts


def knob_table(method):
    """Every knob of a Method as JSON-able values (constants by their repr)."""
    return {k: (getattr(method, k) if k != "constants" else repr(method.constants))
            for k in method.knobs()}


def plot(result, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    systems = list(result["systems"])
    fig, axes = plt.subplots(3, len(systems), figsize=(4.2 * len(systems), 10), squeeze=False,
                             sharex="col")
    style = {"preset": ("k", "o"), "pybsm frequency_samples": ("tab:red", "s"),
             "gauss_legendre knobs": ("tab:blue", "^"), "otf_wavelengths": ("tab:green", "v"),
             "turbulence_path_samples": ("tab:purple", "D"), "candidate": ("tab:cyan", "P")}
    floor = 1e-12
    for col, name in enumerate(systems):
        data = result["systems"][name]
        for row, g in enumerate(GIQE):
            ax = axes[row][col]
            for fam, (color, marker) in style.items():
                pts = [p for p in data["points"] if p["family"] == fam]
                if not pts:
                    continue
                x = [p["time_per_scenario_s"] for p in pts]
                y = [max(p["error"][str(g)], floor) for p in pts]
                ax.scatter(x, y, c=color, marker=marker, s=60 if fam == "preset" else 28,
                           label=fam, zorder=3 if fam == "preset" else 2)
                if fam == "preset":
                    for p, xi, yi in zip(pts, x, y, strict=True):
                        ax.annotate(p["label"].replace("preset ", ""), (xi, yi), fontsize=7,
                                    xytext=(4, 3), textcoords="offset points")
            if data["pybsm"]:
                ax.scatter([data["pybsm"]["time_per_scenario_s"]],
                           [max(data["pybsm"]["error"][str(g)], floor)], marker="*", s=160,
                           c="tab:orange", label="pyBSM 0.16.1 (per scenario)", zorder=4)
            ax.axhline(1e-3, color="0.6", lw=0.8, ls="--")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.25)
            if row == 0:
                ax.set_title(f"{name}: Q = {data['Q_at_lambda_min']:.2f}", fontsize=10)
            if col == 0:
                ax.set_ylabel(f"GIQE {g}: max |NIIRS error|")
            if row == 2:
                ax.set_xlabel("time per scenario [s]")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=6, fontsize=8)
    fig.suptitle("xbsm.niirs: NIIRS error vs time per scenario (reference: 16x finer knobs, "
                 "same modelling; errors below 1e-12 drawn at 1e-12; dashed: 1e-3)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.04, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_threshold(qs, path, current, chosen):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), sharey=True)
    markers = {"olson": "o", "sharp (no jitter, drift or turbulence)": "^"}
    palette = ["tab:red", "tab:orange", "tab:green", "tab:blue", "tab:purple"]
    colors = {str(n): palette[i % len(palette)] for i, n in enumerate(qs["grid_sizes"])}
    for k, g in enumerate(GIQE):
        ax = axes[k]
        for name, rows in qs["systems"].items():
            for n in qs["grid_sizes"]:
                x = [r["by_grid"][str(n)]["samples_per_oscillation"] for r in rows]
                y = [max(r["by_grid"][str(n)]["error"][str(g)], 1e-12) for r in rows]
                ax.plot(x, y, marker=markers[name], color=colors[str(n)], lw=0.8, ms=4,
                        label=f"N = {n}, {name}" if k == 0 else None)
        for level in (0.01, 0.05):
            ax.axhline(level, color="0.5", ls=":", lw=0.8)
        ax.axvline(current, color="k", ls="--", lw=0.8,
                   label=f"current {current:g}" if k == 0 else None)
        ax.axvline(chosen, color="tab:red", ls="-", lw=0.8,
                   label=f"recommended {chosen:g}" if k == 0 else None)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"GIQE {g}")
        ax.set_xlabel("samples per oscillation at 3 px (slice samples x Q / 3)")
        ax.grid(True, which="both", alpha=0.25)
    axes[0].set_ylabel("max |NIIRS - reference pybsm| (pyBSM modelling)")
    fig.suptitle("pyBSM's uniform rule (N x N grid) vs the converged pybsm reference, "
                 "Q = 0.02 ... 2; dotted: 0.01 and 0.05 NIIRS", fontsize=10)
    fig.legend(loc="lower center", ncol=6, fontsize=7)
    fig.tight_layout(rect=(0, 0.12, 1, 0.95))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="short run (~2 min)")
    parser.add_argument("--repeats", type=int, default=None,
                        help="timed calls per point (median; default 3, quick 1)")
    parser.add_argument("--pybsm-sample", type=int, default=None,
                        help="scenarios per system timed in pyBSM (default 16, quick 4)")
    parser.add_argument("--no-pybsm", action="store_true", help="skip pyBSM")
    parser.add_argument("--systems", nargs="*", default=list(SYSTEMS))
    parser.add_argument("--out-dir", default=None,
                        help="where to write benchmarks/*.json and figures/*.png (default: "
                             "docs/, or a temporary directory with --quick)")
    args = parser.parse_args()
    if args.repeats is None:
        args.repeats = 1 if args.quick else 3
    if args.pybsm_sample is None:
        args.pybsm_sample = 4 if args.quick else 16
    rng = np.random.default_rng(20260101)
    t_start = time.perf_counter()
    result = {
        "load_average_at_start": os.getloadavg(),
        "description": __doc__.split("\n\n")[0],
        "command": "python recipes/evidence/speed_accuracy.py" + (" --quick" if args.quick else ""),
        "quick": args.quick, "repeats": args.repeats, "machine": machine(),
        "timing": "median wall time of one xbsm.niirs call on the whole sweep (after a "
                  "warm-up call; timed in rounds over all configurations) divided by the "
                  "number of scenarios; pyBSM: median per "
                  "scenario of niirs() + niirs5() incl. Sensor/Scenario construction, "
                  "NUMBA_NUM_THREADS=1, in its own process",
        "error": "max over the sweep of |NIIRS - reference| per GIQE version, cells where "
                 "the reference is NaN skipped",
        "reference": {key: knob_table(m) for key, m in REFERENCE.items()},
        "reference_self_check": {key: {"nodes_per_panel": m.nodes_per_panel,
                                       "panels_per_oscillation": m.panels_per_oscillation,
                                       "min_panels": m.min_panels,
                                       "turbulence_path_samples": m.turbulence_path_samples}
                                 for key, m in REFERENCE_HALF.items()},
        "scenarios": {"altitude_m": list((9000.0,) if args.quick else ALTITUDES),
                      "ground_range_m": GROUND_RANGES.tolist(),
                      "visibility_km": list(VISIBILITIES)},
        "systems": {},
    }
    for system in args.systems:
        result["systems"][system] = run_system(system, args, rng)
    result["q_sweep"] = q_sweep(args)
    result["threshold"] = {}
    for bound in (0.01, 0.05):
        s, _ = threshold_from(result["q_sweep"], bound)
        result["threshold"][str(bound)] = {
            "largest_samples_per_oscillation_with_error_above": s,
            "note": "flag below a threshold above this value to flag every point whose "
                    "max NIIRS error (GIQE 3, 4, 5) exceeds the bound"}
    result["threshold"]["envelope"] = envelope(result["q_sweep"])
    result["threshold"]["recommended"] = RECOMMENDED_THRESHOLD
    result["runtime_s"] = time.perf_counter() - t_start
    result["load_average_at_end"] = os.getloadavg()
    root = Path(args.out_dir) if args.out_dir else (
        Path(tempfile.gettempdir()) / "xbsm_speed_accuracy" if args.quick else DOCS)
    (root / "benchmarks").mkdir(parents=True, exist_ok=True)
    (root / "figures").mkdir(parents=True, exist_ok=True)
    out = root / "benchmarks" / "speed_accuracy.json"
    out.write_text(json.dumps(result, indent=1, default=float) + "\n")
    plot(result, root / "figures" / "speed_accuracy.png")
    plot_threshold(result["q_sweep"], root / "figures" / "speed_accuracy_threshold.png",
                   xbsm.method("pybsm").undersampling_threshold, RECOMMENDED_THRESHOLD)
    print(f"\nwrote {out} in {result['runtime_s']:.0f} s")


if __name__ == "__main__":
    main()
