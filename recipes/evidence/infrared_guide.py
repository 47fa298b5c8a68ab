"""The numbers of docs/infrared.md's worked MWIR and LWIR example.

For the two cameras of docs/infrared.md (the MWIR camera of issue 25's first trial,
3-5 um, f/4, 15 um pitch, and an LWIR camera, 8-12 um, f/2, 17 um pitch), on a 2 m path
(altitude 2 m, ground range 0, 23 km visibility) with a blackbody scene:

1. NETD against scene temperature, 230-350 K, with the shot-noise-limited NETD
   sqrt(N) / (dN/dT), N all photoelectrons of the pixel (scene, 2 m path,
   self-emission: ``target_photoelectrons``), i.e. without read, dark and quantization
   noise, and the well fill;
2. what each self-emission parameter does to the NETD at 300 K: the cold shield's
   temperature, the warm optics' emissivity (at 293 K), the cold filter's emissivity
   at 77 K and warmer, and its transmission; with the self-emission photoelectrons
   (the square of ``self_emission_noise``) and the well fill;
3. the MRTD across x (default observer: SNR threshold 2.5, eye 0.1 s, 30 Hz, 7:1
   bars) from 0.25 to 12 cycles/mrad;
4. NIIRS (GIQE 4 and 5, standard target: 2 K thermal contrast in these bands) against
   ground range 0-20 km from 1000 m altitude, 23 km visibility, with SNR, GSD, RER and
   the flag bits set.

Writes ``docs/benchmarks/infrared_guide.json`` (``--out`` to change). Run from the
repository root::

    .venv/bin/python recipes/evidence/infrared_guide.py
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from _provenance import commit, machine  # noqa: E402

import xbsm  # noqa: E402
from xbsm.examples import INFRARED_CAMERAS  # noqa: E402
from xbsm.flags import FLAGS, has_flag  # noqa: E402

OUT = HERE.parents[1] / "docs" / "benchmarks" / "infrared_guide.json"
MWIR = dict(INFRARED_CAMERAS["mwir"])  # xbsm.examples
LWIR = dict(INFRARED_CAMERAS["lwir"])  # xbsm.examples
CAMERAS = {"mwir": MWIR, "lwir": LWIR}
LAB = dict(altitude=2.0, ground_range=0.0, visibility=23.0)
TEMPERATURES = np.arange(230.0, 351.0, 10.0)
# one parameter changed at a time from the camera above (which has no optics or cold
# filter emission, a cold filter of transmission 1 and a 77 K cold shield and filter)
VARIANTS = {
    "base": {},
    "cold_shield_120K": dict(cold_shield_temperature=120.0),
    "cold_shield_150K": dict(cold_shield_temperature=150.0),
    "cold_shield_200K": dict(cold_shield_temperature=200.0),
    "optics_emissivity_0.02_293K": dict(optics_emissivity=0.02, optics_temperature=293.0),
    "optics_emissivity_0.05_293K": dict(optics_emissivity=0.05, optics_temperature=293.0),
    "optics_emissivity_0.10_293K": dict(optics_emissivity=0.10, optics_temperature=293.0),
    "cold_filter_emissivity_0.1_77K": dict(cold_filter_emissivity=0.1),
    "cold_filter_emissivity_0.1_200K": dict(cold_filter_emissivity=0.1,
                                            cold_filter_temperature=200.0),
    "cold_filter_emissivity_0.1_293K": dict(cold_filter_emissivity=0.1,
                                            cold_filter_temperature=293.0),
    "cold_filter_transmission_0.9": dict(cold_filter_transmission=0.9),
    "warm_optics_and_filter": dict(optics_emissivity=0.05, optics_temperature=293.0,
                                   cold_filter_emissivity=0.1, cold_filter_transmission=0.9),
}
CYCLES_PER_MRAD = np.arange(0.25, 12.001, 0.25)
GROUND_RANGE = np.arange(0.0, 20001.0, 1000.0)


def rounded(values, digits=6):
    return [float(f"{v:.{digits}g}") for v in np.asarray(values, dtype=float).ravel()]


def netd_against_temperature(camera):
    r = xbsm.netd(xbsm.sensor(**camera), xbsm.scenario(**LAB), temperature=TEMPERATURES)
    blip = np.sqrt(r.target_photoelectrons) / r.signal_derivative
    return {"temperature_K": rounded(TEMPERATURES), "netd_K": rounded(r.netd),
            "shot_noise_limited_netd_K": rounded(blip), "well_fill": rounded(r.well_fill),
            "total_noise_e": rounded(r.total_noise),
            "signal_derivative_e_per_K": rounded(r.signal_derivative)}


def self_emission_effects(camera):
    out = {}
    for name, change in VARIANTS.items():
        r = xbsm.netd(xbsm.sensor(**{**camera, **change}), xbsm.scenario(**LAB),
                      temperature=300.0)
        out[name] = {"change": change, "netd_K": rounded(r.netd)[0],
                     "self_emission_photoelectrons": rounded(r.self_emission_noise ** 2)[0],
                     "scene_photoelectrons": rounded(r.target_photoelectrons)[0],
                     "total_noise_e": rounded(r.total_noise)[0],
                     "well_fill": rounded(r.well_fill)[0],
                     "well_fill_limited": bool(has_flag(r.flags, "well_fill_limited"))}
    return out


def mrtd_curve(camera):
    r = xbsm.mrtd(xbsm.sensor(**camera), xbsm.scenario(**LAB),
                  frequency=CYCLES_PER_MRAD * 1e3).sel(orientation="x")
    ifov = camera["pixel_pitch_x"] / camera["focal_length"]
    return {"frequency_cycles_per_mrad": rounded(CYCLES_PER_MRAD), "mtf": rounded(r.mtf),
            "mrtd_K": rounded(r.mrtd), "bars_aliased": [bool(v) for v in
                                                        has_flag(r.flags, "bars_aliased").values],
            "nyquist_cycles_per_mrad": 0.5 / ifov / 1e3, "netd_frame_K": float(r.netd_frame)}


def niirs_against_range(camera):
    sc = xbsm.scenario(altitude=1000.0, visibility=23.0,
                       ground_range=xr.DataArray(GROUND_RANGE, dims="ground_range"))
    n = xbsm.niirs(xbsm.sensor(**camera), sc)
    bits = {}
    for name in FLAGS:
        where = has_flag(n.flags.sel(giqe=5), name).values
        if where.any():
            bits[name] = [float(g) for g in GROUND_RANGE[where]]
    return {"ground_range_m": rounded(GROUND_RANGE), "altitude_m": 1000.0,
            "niirs_giqe4": rounded(n.niirs.sel(giqe=4), 4),
            "niirs_giqe5": rounded(n.niirs.sel(giqe=5), 4), "snr": rounded(n.snr, 4),
            "gsd_m": rounded(n.gsd, 4), "rer": rounded(n.rer, 4),
            "slant_range_m": rounded(n.slant_range, 6),
            "giqe5_flags_set_at_ground_range_m": bits}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    result = {"machine": machine(), "commit": commit(), "cameras": CAMERAS, "path": LAB}
    for name, camera in CAMERAS.items():
        result[name] = {"netd_against_temperature": netd_against_temperature(camera),
                        "self_emission": self_emission_effects(camera),
                        "mrtd_x": mrtd_curve(camera),
                        "niirs_against_range": niirs_against_range(camera)}
        t = result[name]
        netd = np.round(np.array(t["netd_against_temperature"]["netd_K"]) * 1e3, 1)
        print(f"\n{name}: NETD {netd} mK at {TEMPERATURES} K")
        for variant, v in t["self_emission"].items():
            print(f"  {variant:34s} NETD {v['netd_K'] * 1e3:7.2f} mK  self-emission "
                  f"{v['self_emission_photoelectrons']:10.4g} e-  well {v['well_fill']:.3f}")
        print("  NIIRS (GIQE 5):", t["niirs_against_range"]["niirs_giqe5"])
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
