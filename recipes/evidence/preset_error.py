"""NIIRS error of ``accurate``, ``fast`` (and ``pybsm``) against an independent edge reference.

Issue 23 item 3. The reference (``recipes/evidence/edge_reference.py``) integrates
the system OTF slices of the public ``xbsm.system_otf`` by a dense trapezoid rule
(2^17 and 2^16 intervals over [0, D/lambda_min], every database wavelength,
Richardson-extrapolated) and turns its RER/EHO into NIIRS with the public GIQE
functions and the method's own SNR, GSD, elevation and noise gain. It uses
nothing of ``xbsm.quadrature`` or ``xbsm.metrics.edge``, so this recipe measures
any tree put on ``PYTHONPATH`` (before and after a quadrature change).

Cases (fixed seed):

- ``random``: at least 400 random valid systems: band 0.4-0.7, 0.55-0.85,
  1.0-1.7, 3-5 or 8-12 um; aperture 0.02-1 m, focal length 0.05-10 m, pitch
  2-30 um (each log-uniform; kept if Q = lambda_min f / (D p) is in 0.02-77, the
  review's range); altitude 100 m - 20 km, ground range 0-100 km, visibility 5
  or 23 km; each of jitter (0.02-3 px rms), drift on both axes (0.1-30 px
  each), one-axis drift along x (1-300 px), wavefront error (0-0.15 waves rms)
  and turbulence (Cn2(1 m) 1e-16 - 1e-13, or HV 5/7's 1.7e-14) present in half
  the cases; obscuration 0.05-0.5 in half; integration time 0.1-50 ms. Drift
  lengths are set on the effective integration time (after the well-fill
  limit), so "px" is the smear the edge sees. A draw is kept if ``accurate``
  runs and its SNR is finite and positive (inside the database, above the
  horizon, target brighter than background).
- ``targeted``: one-axis drift 10-1000 px (Olson NIR, Q = 1.0, and an LWIR
  camera, Q = 0.53); Gaussian jitter from 0.5 to 40 px rms (RER 0.5 down to
  0.01); turbulence-limited long horizontal-ish paths (D 0.3 m, 100 m and 1 km
  altitude, 5-30 km, Cn2 1.7e-14 and 1e-13).

Reported, by the reference's RER on the worse slice (min of x and y: a one-axis
smear counts where its slice is) in bins < 0.05, 0.05-0.1, 0.1-0.2, >= 0.2,
and by method: median / 95th percentile / max |NIIRS - reference| for GIQE 3, 4
and 5, separately for cells flagged ``blur_unresolved`` and unflagged ones, the
share flagged, and the cells where the method is NaN although the reference is
finite (``rer_nonpositive``). ``pybsm`` is compared with a reference of its own
modelling (|OTF|, its filter OTF, ...), for context.

Writes ``docs/benchmarks/preset_error.json`` (``--out`` to change; a run with
fewer than 400 random cases writes to the system's temporary folder unless
``--out`` is given) and prints the markdown table of ``docs/speed_accuracy.md``.
Run from the repository root with the project environment::

    PYTHONPATH=. .venv/bin/python recipes/evidence/preset_error.py [--cases 400]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # recipes/: the shared helpers
sys.path.insert(0, str(HERE))         # edge_reference

import edge_reference as er  # noqa: E402
import numpy as np  # noqa: E402
from _provenance import commit, machine  # noqa: E402

import xbsm  # noqa: E402
import xbsm.examples  # noqa: E402
from xbsm.flags import flag  # noqa: E402

ROOT = HERE.parents[1]
DEFAULT_OUT = ROOT / "docs" / "benchmarks" / "preset_error.json"
SEED = 20261124
METHODS = ("accurate", "fast", "pybsm")
GIQE = (3, 4, 5)
BANDS = ((0.4e-6, 0.7e-6), (0.55e-6, 0.85e-6), (1.0e-6, 1.7e-6), (3.0e-6, 5.0e-6),
         (8.0e-6, 12.0e-6))
Q_RANGE = (0.02, 77.0)
RER_BINS = ((0.0, 0.05, "< 0.05"), (0.05, 0.1, "0.05-0.1"), (0.1, 0.2, "0.1-0.2"),
            (0.2, math.inf, ">= 0.2"))
BLUR = flag("blur_unresolved")
NONPOSITIVE = flag("rer_nonpositive")


def loguniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


# --- cases ------------------------------------------------------------------------------


def draw_case(rng) -> dict:
    """One random system: sensor and scenario keywords, smears in pixels (set later)."""
    band = BANDS[int(rng.integers(len(BANDS)))]
    while True:
        d, f, p = (loguniform(rng, 0.02, 1.0), loguniform(rng, 0.05, 10.0),
                   loguniform(rng, 2e-6, 30e-6))
        q = band[0] * f / (d * p)
        if Q_RANGE[0] <= q <= Q_RANGE[1]:
            break
    ifov = p / f
    half = [rng.uniform() < 0.5 for _ in range(6)]
    jitter_px = loguniform(rng, 0.02, 3.0) if half[0] else 0.0
    drift_px = (loguniform(rng, 0.1, 30.0), loguniform(rng, 0.1, 30.0)) if half[1] else (0, 0)
    one_axis_px = loguniform(rng, 1.0, 300.0) if half[2] else 0.0
    wavefront = float((2 * np.pi * rng.uniform(0.0, 0.15)) ** 2) if half[3] else 0.0
    if half[4]:
        cn2 = 1.7e-14 if rng.uniform() < 0.5 else 10 ** float(rng.uniform(-16, -13))
    else:
        cn2 = 0.0
    sensor = dict(aperture_diameter=d, focal_length=f, pixel_pitch_x=p,
                  wavelength_min=band[0], wavelength_max=band[1],
                  obscuration_ratio=float(rng.uniform(0.05, 0.5)) if half[5] else 0.0,
                  integration_time=loguniform(rng, 1e-4, 0.05), read_noise=10.0, max_well=1e5,
                  jitter_x=jitter_px * ifov, jitter_y=jitter_px * ifov,
                  wavefront_variance=wavefront)
    scenario = dict(altitude=float(rng.uniform(100.0, 20000.0)),
                    ground_range=float(rng.uniform(0.0, 100e3)),
                    visibility=float(rng.choice([5.0, 23.0])), cn2_at_1m=cn2,
                    platform_speed=float(rng.uniform(0.0, 250.0)) if rng.uniform() < 0.5
                    else 0.0)
    return {"kind": "random", "Q": q, "sensor": sensor, "scenario": scenario,
            "drift_px": [drift_px[0] + one_axis_px, drift_px[1]], "jitter_px": jitter_px,
            "one_axis_drift_px": one_axis_px, "turbulence": cn2 > 0}


def olson(**over):
    p = xbsm.examples.olson_sensor_parameters("nir")
    p.update(drift_rate_x=0.0, drift_rate_y=0.0)
    p.update(over)
    return p


def targeted_cases() -> list[dict]:
    """One-axis drift 10-1000 px, jitter down to RER 0.01, turbulence-limited long paths."""
    cases = []
    air = dict(altitude=9000.0, ground_range=10e3, visibility=23.0)
    lwir = dict(aperture_diameter=0.2, focal_length=0.4, pixel_pitch_x=15e-6,
                wavelength_min=8e-6, wavelength_max=12e-6, integration_time=0.005,
                read_noise=10.0, max_well=1e6)
    for name, sensor in (("olson_nir", olson()), ("lwir_q0.53", lwir)):
        q = sensor["wavelength_min"] * sensor["focal_length"] / (
            sensor["aperture_diameter"] * sensor["pixel_pitch_x"])
        for px in (10, 30, 109, 300, 1000):
            cases.append({"kind": "one_axis_drift", "label": f"{name}, x drift {px} px",
                          "Q": q, "sensor": dict(sensor), "scenario": dict(air),
                          "drift_px": [float(px), 0.0], "jitter_px": 0.0,
                          "one_axis_drift_px": float(px), "turbulence": True})
    q = 0.55e-6 * 4.0 / (0.275 * 8e-6)
    for px in (0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 25.0, 40.0):
        s = olson(jitter_x=px * 2e-6, jitter_y=px * 2e-6)
        cases.append({"kind": "jitter", "label": f"olson_nir, jitter {px} px rms", "Q": q,
                      "sensor": s, "scenario": dict(air), "drift_px": [0.0, 0.0],
                      "jitter_px": px, "one_axis_drift_px": 0.0, "turbulence": True})
    long_range = dict(aperture_diameter=0.3, focal_length=3.0, pixel_pitch_x=5e-6,
                      wavelength_min=0.4e-6, wavelength_max=0.7e-6, integration_time=0.002,
                      read_noise=10.0, max_well=1e5)
    for altitude in (100.0, 1000.0):
        for ground in (5e3, 10e3, 20e3, 30e3):
            for cn2 in (1.7e-14, 1e-13):
                cases.append({"kind": "turbulence",
                              "label": f"D 0.3 m visible, {altitude:g} m, {ground / 1e3:g} km, "
                                       f"Cn2 {cn2:g}", "Q": 0.4e-6 * 3.0 / (0.3 * 5e-6),
                              "sensor": dict(long_range),
                              "scenario": dict(altitude=altitude, ground_range=ground,
                                               visibility=23.0, cn2_at_1m=cn2),
                              "drift_px": [0.0, 0.0], "jitter_px": 0.0,
                              "one_axis_drift_px": 0.0, "turbulence": True})
    return cases


def datasets(case, effective_time=None):
    """(sensor, scenario) datasets; drift rates set so that the smear is ``drift_px`` over
    the effective integration time (first call: ``effective_time`` None, no drift)."""
    s = dict(case["sensor"])
    if effective_time is not None:
        ifov = s["pixel_pitch_x"] / s["focal_length"]
        s["drift_rate_x"] = case["drift_px"][0] * ifov / effective_time
        s["drift_rate_y"] = case["drift_px"][1] * ifov / effective_time
    return xbsm.sensor(**s), xbsm.scenario(**case["scenario"])


def prepare(case):
    """Datasets with the drift set, or None if ``accurate`` cannot give a valid SNR here."""
    try:
        out = xbsm.niirs(*datasets(case), method="accurate")
    except ValueError as e:  # e.g. max_frequency_nodes
        return None, str(e).split(";")[0]
    snr, t = float(out["snr"]), float(out["effective_integration_time"])
    if not (np.isfinite(snr) and snr > 0):
        return None, "snr"
    return datasets(case, t), None


# --- one case ---------------------------------------------------------------------------


def evaluate(case, ds, modelling_refs, methods=METHODS) -> dict:
    """Every method's NIIRS, flags and edge terms, and the reference NIIRS behind each."""
    row = {"methods": {}}
    for name in methods:
        with warnings.catch_warnings(record=True) as caught:  # a leaked RuntimeWarning
            warnings.simplefilter("always")
            out = xbsm.niirs(*ds, method=name)
        leaked = "; ".join(str(w.message) for w in caught) or None
        shared = next((k for k in modelling_refs if er.same_reference(*ds, k, name)), None)
        if shared is None:  # accurate and fast share one (same OTF, same edge_otf)
            t0 = time.perf_counter()
            shared = name
            modelling_refs[name] = er.reference_slices(*ds, name)
            modelling_refs[name]["seconds"] = time.perf_counter() - t0
        ref = modelling_refs[shared]
        ref_niirs = er.reference_niirs(ref, out, name)
        levels = np.abs(er.reference_niirs(ref, out, name, "_fine")
                        - er.reference_niirs(ref, out, name, "_coarse"))
        row["methods"][name] = {
            "niirs": out["niirs"].values.tolist(), "flags": out["flags"].values.tolist(),
            "rer_x": float(out["rer_x"]), "rer_y": float(out["rer_y"]),
            "reference_niirs": ref_niirs.tolist(),
            "reference_rer_x": ref["rer_x"], "reference_rer_y": ref["rer_y"],
            "reference_level_difference_rer": ref["level_difference"],
            "reference_level_difference_niirs": float(np.nanmax(levels, initial=0.0)),
            "giqe_composition_check": er.method_niirs_check(out, name),
            "numpy_warning_raised": leaked,
        }
    return row


# --- statistics -------------------------------------------------------------------------


def _summary(e):
    e = np.asarray(e, float)
    if e.size == 0:
        return {"cells": 0}
    return {"cells": int(e.size), "median": float(np.median(e)),
            "p95": float(np.percentile(e, 95)), "max": float(np.max(e))}


def table(rows, methods=METHODS):
    """Statistics by reference RER bin (worse slice), method, flagged/unflagged, GIQE."""
    out = {}
    for name in methods:
        per = [r["methods"][name] for r in rows]
        worse = np.array([min(p["reference_rer_x"], p["reference_rer_y"]) for p in per])
        niirs = np.array([p["niirs"] for p in per], float)           # (case, giqe)
        ref = np.array([p["reference_niirs"] for p in per], float)
        flags = np.array([p["flags"] for p in per], np.int64)
        err = np.abs(niirs - ref)
        blur = (flags & BLUR) != 0
        own = np.array([p["reference_level_difference_niirs"] for p in per])
        out[name] = {}
        for lo, hi, label in RER_BINS:
            inbin = (worse >= lo) & (worse < hi)
            cell = {"cases": int(inbin.sum()),
                    "reference_level_difference_niirs_max": float(own[inbin].max())
                    if inbin.any() else None,
                    "share_flagged": float(blur[inbin].any(axis=1).mean()) if inbin.any()
                    else None}
            for group, sel in (("unflagged", ~blur), ("flagged", blur)):
                g = {}
                for k, v in enumerate(GIQE):
                    m = inbin & sel[:, k] & np.isfinite(ref[:, k])
                    finite = m & np.isfinite(niirs[:, k])
                    g[str(v)] = {**_summary(err[finite, k]),
                                 "nan_cells": int((m & ~np.isfinite(niirs[:, k])).sum()),
                                 "rer_nonpositive_cells": int(
                                     (m & ((flags[:, k] & NONPOSITIVE) != 0)).sum())}
                cell[group] = g
            out[name][label] = cell
    return out


def fmt(x):
    if x is None:
        return "-"
    if x == 0:
        return "0"
    return f"{x:.1e}" if x < 0.1 else f"{x:.2g}"


def markdown(stats, methods=METHODS):
    """The table of docs/speed_accuracy.md: one row per method, bin and flag state."""
    lines = ["| method | reference RER (worse slice) | cases | flagged | cells | GIQE 3 "
             "median / p95 / max | GIQE 4 median / p95 / max | GIQE 5 median / p95 / max "
             "| NaN | reference's own |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name in methods:
        for _, _, label in RER_BINS:
            cell = stats[name][label]
            share = cell["share_flagged"]
            for group in ("unflagged", "flagged"):
                g = cell[group]
                if all(g[str(v)]["cells"] == 0 and g[str(v)]["nan_cells"] == 0 for v in GIQE):
                    continue
                parts = []
                for v in GIQE:
                    s = g[str(v)]
                    parts.append("-" if s["cells"] == 0 else
                                 f"{fmt(s['median'])} / {fmt(s['p95'])} / {fmt(s['max'])}")
                nan = sum(g[str(v)]["nan_cells"] for v in GIQE)
                lines.append(f"| `{name}` | {label} | {cell['cases']} | "
                             f"{'-' if share is None else f'{100 * share:.0f} %'} | {group} "
                             f"({max(g[str(v)]['cells'] + g[str(v)]['nan_cells'] for v in GIQE)})"
                             f" | {' | '.join(parts)} | {nan} | "
                             f"{fmt(cell['reference_level_difference_niirs_max'])} |")
    return "\n".join(lines)


def worst_unflagged(rows, cases, name, count=8):
    """The cases with the largest unflagged error of a method."""
    found = []
    for r, c in zip(rows, cases, strict=True):
        p = r["methods"][name]
        for k, v in enumerate(GIQE):
            e = abs(p["niirs"][k] - p["reference_niirs"][k])
            if not p["flags"][k] & BLUR and np.isfinite(p["reference_niirs"][k]):
                e = math.inf if not np.isfinite(e) else e
                found.append((e, v, c, p))
    found.sort(key=lambda t: -t[0])
    return [{"error": e, "giqe": v, "kind": c["kind"], "label": c.get("label"),
             "Q": c["Q"], "drift_px": c["drift_px"], "jitter_px": c["jitter_px"],
             "reference_rer_x": p["reference_rer_x"], "reference_rer_y": p["reference_rer_y"],
             "rer_x": p["rer_x"], "rer_y": p["rer_y"], "flags": p["flags"]}
            for e, v, c, p in found[:count]]


def jsonable(x):
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def write_json(path, result):
    """``result`` as strict JSON: indented, except one line per entry of ``cases`` (size)."""
    result = jsonable(result)
    cases = result.pop("cases", [])
    text = json.dumps(result, indent=1)
    rows = ",\n  ".join(json.dumps(c, separators=(",", ":")) for c in cases)
    text = text[:-2] + f',\n "cases": [\n  {rows}\n ]\n}}\n' if cases else text + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


# --- main -------------------------------------------------------------------------------


def run(cases, label, methods=METHODS):
    rows, kept, rejected, t0 = [], [], {}, time.perf_counter()
    for case in cases:
        ds, why = prepare(case)
        if ds is None:
            rejected[why] = rejected.get(why, 0) + 1
            continue
        rows.append(evaluate(case, ds, {}, methods))
        kept.append(case)
        if len(kept) % 50 == 0:
            print(f"  {label}: {len(kept)} cases ({time.perf_counter() - t0:.0f} s)",
                  flush=True)
    return rows, kept, rejected


def draw_random(n, rng):
    rows, kept, rejected, draws = [], [], {}, 0
    t0 = time.perf_counter()
    while len(kept) < n:
        case = draw_case(rng)
        draws += 1
        ds, why = prepare(case)
        if ds is None:
            rejected[why] = rejected.get(why, 0) + 1
            continue
        rows.append(evaluate(case, ds, {}))
        kept.append(case)
        if len(kept) % 50 == 0:
            print(f"  random: {len(kept)}/{n} cases, {draws} draws "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)
    return rows, kept, rejected, draws


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=400, help="random valid systems (400)")
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    out_path = args.out or (DEFAULT_OUT if args.cases >= 400 else
                            Path(tempfile.gettempdir()) / "xbsm_preset_error" / "preset_error.json")
    t_start = time.perf_counter()
    load_start = os.getloadavg()
    git = commit(Path(xbsm.__file__).resolve().parents[1])  # the tree measured
    git["xbsm_path"] = str(Path(xbsm.__file__).resolve().parent)
    print(f"xbsm from {Path(xbsm.__file__).parent}; load {load_start[0]:.2f}", flush=True)
    rng = np.random.default_rng(args.seed)
    rows, cases, rejected, draws = draw_random(args.cases, rng)
    t_rows, t_cases, t_rejected = run(targeted_cases(), "targeted")
    every_rows, every_cases = rows + t_rows, cases + t_cases

    stats = {"random": table(rows), "targeted": table(t_rows), "all": table(every_rows)}
    by_kind = {}
    for kind in ("one_axis_drift", "jitter", "turbulence"):
        sel = [r for r, c in zip(t_rows, t_cases, strict=True) if c["kind"] == kind]
        by_kind[kind] = table(sel)
    checks = {
        "giqe_composition_max": max(r["methods"][m]["giqe_composition_check"]
                                    for r in every_rows for m in METHODS),
        "reference_level_difference_rer_max": max(
            r["methods"][m]["reference_level_difference_rer"] for r in every_rows
            for m in METHODS),
        "reference_level_difference_niirs_max": max(
            r["methods"][m]["reference_level_difference_niirs"] for r in every_rows
            for m in METHODS),
        "numpy_warnings": sum(bool(r["methods"][m]["numpy_warning_raised"])
                              for r in every_rows for m in METHODS),
    }
    md = markdown(stats["all"])
    print("\n" + md + "\n")
    for name in METHODS:
        w = worst_unflagged(every_rows, every_cases, name, 3)
        print(f"worst unflagged {name}: " + "; ".join(
            f"{x['error']:.2g} (GIQE {x['giqe']}, {x['kind']}, ref RER "
            f"{min(x['reference_rer_x'], x['reference_rer_y']):.3g})" for x in w))
    print("checks:", checks)
    result = {
        "description": __doc__.split("\n\n")[0],
        "command": f"PYTHONPATH=. python recipes/evidence/preset_error.py --cases {args.cases}",
        "git": git, "machine": machine(), "load_average_at_start": load_start,
        "seed": args.seed, "random_cases": len(cases), "random_draws": draws,
        "rejected_draws": rejected, "targeted_cases": len(t_cases),
        "targeted_rejected": t_rejected,
        "reference": {"intervals": er.INTERVALS, "path_samples": er.PATH_SAMPLES,
                      "rule": "trapezoid on 2^17 and 2^16 uniform intervals over "
                              "[0, D/lambda_min], Richardson-extrapolated; every database "
                              "wavelength; the method's edge_otf convention"},
        "bins": "reference RER of the worse slice, min(rer_x, rer_y) (filtered system)",
        "error": "|NIIRS - reference NIIRS| per cell (case x GIQE); NaN cells (method NaN, "
                 "reference finite) counted apart",
        "checks": checks,
        "stats": stats, "targeted_by_kind": by_kind, "markdown": md,
        "worst_unflagged": {m: worst_unflagged(every_rows, every_cases, m) for m in METHODS},
        "cases": [{k: v for k, v in c.items()} | {"results": r["methods"]}
                  for c, r in zip(every_cases, every_rows, strict=True)],
    }
    result["runtime_s"] = time.perf_counter() - t_start
    result["load_average_at_end"] = os.getloadavg()
    write_json(out_path, result)
    print(f"wrote {out_path} in {result['runtime_s']:.0f} s")


if __name__ == "__main__":
    main()
