"""Bad-input sweep: every public entry point against bad and edge-case input.

The measurement behind "no silent wrong answer: every input checked at the
public boundary, every failure named or flagged". Each case calls one public
entry point with one bad or edge-case input and its outcome gets one class:

- ``clear_error``: a ValueError / TypeError raised by xbsm (or argparse for the
  command line) whose message names the user's parameter or knob and either
  states the allowed range or choices (a bracketed interval, ``must``, ``one
  of``, ``at most``...) or, after a colon or semicolon, the fix (``give them
  one length``, ``name the dimension ...``, ``make it with xbsm.sensor(...)``,
  ``evaluate the grid in pieces``). The second form was added after the
  commit-c9fc86a run: errors about dimensions and missing parameters have no
  numeric range to state, and were counted cryptic although they name the
  parameter and tell the user exactly what to do. An error raised outside
  xbsm, or whose message names none of the case's parameters, stays cryptic;
- ``flagged``: a result whose ``flags`` variable marks the problem with a bit
  the same call on valid input does not set (NaN cells must carry a bit);
- ``sensible``: a result that meets the case's oracle (for example: a float32
  input gives the float64 result within 1e-9 relative);
- ``cryptic_error``: any other exception (names no parameter, no range, or is
  raised inside numpy / xarray, or is a KeyError, MergeError, ...);
- ``silent_nan``: a NaN (or inf) output with no flag explaining it;
- ``silent_wrong``: a finite result that fails the case's oracle (an invalid
  input accepted without error or flag, a sweep dimension collapsed or mixed,
  a units attribute ignored, a knob value silently coerced...);
- ``blowup``: a MemoryError under the memory cap, a killed process, or more
  than 60 s.

Every case runs in a forked child process with its address space capped at
3 GB (``RLIMIT_AS``) and a 60 s timeout, so a blow-up is classified instead of
taking the machine down. Parameters and knobs that are accepted are followed
through the model: a bad ``sensor``, ``scenario`` or ``method`` argument is
judged on the ``xbsm.niirs`` result it leads to. Cases are generated from
small tables; each carries its oracle as text in the JSON.

Usage (from the repository root)::

    .venv/bin/python recipes/evidence/bad_input_sweep.py [--out PATH] [--only SUBSTRING]

Writes ``docs/benchmarks/bad_input_sweep.json`` (one row per case: id, entry,
description, oracle, class, message, note) and prints the count per class and
per entry point. ``--only`` runs the cases whose id contains SUBSTRING.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import multiprocessing as mp  # noqa: E402
import re  # noqa: E402
import resource  # noqa: E402
import signal  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
import warnings  # noqa: E402
from collections import Counter, defaultdict  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

import xbsm  # noqa: E402
from xbsm.flags import FLAGS  # noqa: E402
from xbsm.simulate import reflectance_to_photoelectrons  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_OUT = Path("docs/benchmarks/bad_input_sweep.json")
MEMORY_LIMIT = 3 * 1024**3  # bytes of address space per case
TIMEOUT = 60.0  # s per case
RTOL = 1e-9  # "equal to the float64 / reference result"
CLASSES = ("clear_error", "flagged", "sensible", "cryptic_error", "silent_nan",
           "silent_wrong", "blowup")
INF, NAN = math.inf, math.nan
NAN_BITS = FLAGS["beyond_database"][0] | FLAGS["snr_nonpositive"][0]  # bits that explain a NaN

# ---------------------------------------------------------------------------
# Standard inputs (the Olson NIR camera at 9 km, 20 km ground range)

OLSON = dict(
    aperture_diameter=0.275, focal_length=4.0, pixel_pitch_x=8e-6,
    wavelength_min=0.55e-6, wavelength_max=0.85e-6, obscuration_ratio=0.4,
    optics_transmission=0.5, quantum_efficiency=0.71, integration_time=0.03,
    read_noise=25.0, max_well=96000.0, bit_depth=11.9, max_well_fill=0.6,
    jitter_x=0.5e-6, jitter_y=0.5e-6, drift_rate_x=100e-6, drift_rate_y=100e-6,
    dark_current=4.0e3,
)
SCEN = dict(altitude=9000.0, ground_range=20e3, visibility=23.0, platform_speed=100.0)
PYBSM_SENSOR = dict(D=0.275, f=4.0, p_x=8e-6, opt_trans_wavelengths=[0.55e-6, 0.85e-6],
                    optics_transmission=[0.5, 0.5], eta=0.4, int_time=0.03, read_noise=25.0,
                    max_n=96000.0, bit_depth=11.9, max_well_fill=0.6, s_x=0.5e-6, s_y=0.5e-6,
                    da_x=100e-6, da_y=100e-6, dark_current=4.0e3, qe=[0.71, 0.71])
PYBSM_SCENARIO = dict(ihaze=1, altitude=9000.0, ground_range=20e3, aircraft_speed=100.0)


def sen(**over):
    """The Olson sensor with some parameters replaced."""
    return xbsm.sensor(**{**OLSON, **over})


def scn(**over):
    """The standard scenario with some parameters replaced."""
    return xbsm.scenario(**{**SCEN, **over})


S, SC = sen(), scn()


def da(values, dim="case", dtype=float, **attrs):
    """A 1-D sweep DataArray on ``dim`` (no coordinate)."""
    return xr.DataArray(np.asarray(values, dtype=dtype), dims=dim, attrs=attrs)


def otf_slice():
    """System OTF along x of the standard case (for the GRD cases)."""
    return xbsm.system_otf(S, SC)["system"].sel(orientation="x", drop=True)


IFOV = 8e-6 / 4.0


# ---------------------------------------------------------------------------
# Cases


@dataclass
class Case:
    """One bad or edge-case input.

    ``expect`` is the oracle: "reject" (the input is invalid: only an error or
    a flag is right), "same" (the result's ``main`` variable must equal
    ``ref()``'s within 1e-9 relative, with the same dims and sizes) or "check"
    (``check(result)`` returns (class, note)).
    """

    id: str
    entry: str
    desc: str
    call: Callable[[], Any]
    names: tuple = ()
    expect: str = "reject"
    ref: Callable[[], Any] | None = None
    check: Callable[[Any], tuple[str, str]] | None = None
    main: str = "niirs"
    oracle: str = ""
    needs_range: bool = True  # False: naming the parameter (e.g. a file) is enough
    fragment: str | None = None  # a row of the shared table: what its error must say
    error: type = ValueError  # ... and its exception type

    def oracle_text(self):
        if self.oracle:
            return self.oracle
        return {
            "reject": "invalid input: a clear error or a flag; a finite unflagged result is wrong",
            "same": f"{self.main} must equal the reference call's (dims, sizes, 1e-9 relative)",
        }.get(self.expect, "custom check")


CASES: list[Case] = []


def add(*args, **kw):
    CASES.append(Case(*args, **kw))


def slug(value) -> str:
    text = repr(value) if not isinstance(value, str) else value
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", text).strip("_")[:24] or "empty"


# --- xbsm.sensor: value table. Accepted values are followed through xbsm.niirs.
SENSOR_BAD = {
    "aperture_diameter": [-0.1, 0.0, INF, NAN, -INF, None, "abc", 0.275 + 0.1j],
    "focal_length": [-4.0, 0.0, INF, NAN, "4 m"],
    "pixel_pitch_x": [-8e-6, 0.0, INF, NAN],
    "pixel_pitch_y": [0.0, INF],
    "detector_width_x": [0.0, INF, 16e-6],  # wider than the pitch
    "detector_width_y": [INF, -1e-6],
    "wavelength_min": [0.55, 0.0, NAN, -INF, 0.2e-6],  # micrometres given as metres
    "wavelength_max": [0.85, INF, 20e-6, 0.551e-6],  # last: a 1 nm band (valid, interpolated)
    "obscuration_ratio": [1.0, -0.1, NAN],
    "integration_time": [0.0, -0.03, INF, NAN, 1e-15],
    "dark_current": [-1.0, INF, NAN],
    "read_noise": [-25.0, INF],
    "other_noise": [INF, -1.0],
    "max_well": [0.0, INF, 0.5],
    "max_well_fill": [0.0, 1.5, NAN],
    "bit_depth": [0.0, INF, 0.5, 1e6],
    "tdi_stages": [0.0, 0.5, INF, 2.5],
    "frame_stacks": [0.0, INF, 1.5],
    "cold_shield_temperature": [0.0, INF, -70.0],
    "optics_temperature": [INF, 1e6],
    "optics_emissivity": [1.5, NAN],
    "cold_filter_transmission": [1.5, 0.0],
    "cold_filter_temperature": [INF],
    "cold_filter_emissivity": [-0.5],
    "jitter_x": [-1e-6, INF, 10.0],
    "jitter_y": [NAN],
    "drift_rate_x": [INF, NAN, 1e9],
    "drift_rate_y": [-INF],
    "wavefront_variance": [-0.1, INF, 1e6],
    "wavefront_wavelength": [0.0, INF],
    "wavefront_correlation_length_x": [0.0, INF],
    "wavefront_correlation_length_y": [1e-12],
    "optics_transmission": [1.5, -0.5, NAN],
    "quantum_efficiency": [2.0, 0.0, INF],
    "stray_irradiance": [-1.0, INF],
}
# values that are physically odd but valid: the oracle is "no error, finite, flagged or plain"
SENSOR_VALID_EXTREMES = {
    ("detector_width_x", 16e-6), ("wavelength_min", 0.2e-6), ("integration_time", 1e-15),
    ("max_well", 0.5), ("bit_depth", 0.5), ("bit_depth", 1e6), ("tdi_stages", 2.5),
    ("wavelength_max", 0.551e-6), ("bit_depth", INF), ("wavefront_correlation_length_x", INF),
    ("frame_stacks", 1.5), ("optics_temperature", 1e6), ("jitter_x", 10.0),
    ("drift_rate_x", 1e9), ("wavefront_variance", 1e6), ("wavefront_correlation_length_y", 1e-12),
    ("quantum_efficiency", 0.0), ("cold_filter_transmission", 0.0), ("tdi_stages", 0.5),
}


def plausible(result):
    """Oracle for valid extremes: finite where unflagged, or flagged; never an unflagged NaN."""
    return generic_reject(result, "niirs", valid_input=True)


for name, values in SENSOR_BAD.items():
    for value in values:
        valid = (name, value) in SENSOR_VALID_EXTREMES
        add(f"sensor.{name}={slug(value)}", "sensor", f"sensor({name}={value!r}) -> niirs",
            lambda n=name, v=value: xbsm.niirs(sen(**{n: v}), SC), names=(name,),
            expect="check" if valid else "reject", check=plausible if valid else None,
            oracle=("valid extreme: an unflagged NaN or an error naming no parameter is wrong"
                    if valid else ""))
    # note: quantum_efficiency=0 gives zero signal: SNR 0 must be flagged

# Hand-written sensor cases: dtype, strings, units, huge values, dims, spectral curves.
F32 = float(np.float32(0.275))
F16 = float(np.float16(0.275))
SENSOR_SAME = [
    ("float32_scalar", "aperture_diameter=np.float32(0.275)",
     dict(aperture_diameter=np.float32(0.275)), dict(aperture_diameter=F32)),
    ("float16_scalar", "aperture_diameter=np.float16(0.275)",
     dict(aperture_diameter=np.float16(0.275)), dict(aperture_diameter=F16)),
    ("float32_sweep", "focal_length float32 DataArray [3, 4.1] on dim case",
     dict(focal_length=da([3.0, 4.1], dtype=np.float32)),
     dict(focal_length=da([float(np.float32(3.0)), float(np.float32(4.1))]))),
    ("float32_pitch_sweep", "pixel_pitch_x float32 DataArray [8e-6, 1.1e-5]",
     dict(pixel_pitch_x=da([8e-6, 1.1e-5], dtype=np.float32)),
     dict(pixel_pitch_x=da(np.float32([8e-6, 1.1e-5]).astype(float)))),
    ("float16_sweep", "integration_time float16 DataArray [0.03, 0.01]",
     dict(integration_time=da([0.03, 0.01], dtype=np.float16)),
     dict(integration_time=da(np.float16([0.03, 0.01]).astype(float)))),
    ("int_scalar", "focal_length=4 (int)", dict(focal_length=4), dict(focal_length=4.0)),
    ("int_sweep", "tdi_stages int DataArray [1, 2]", dict(tdi_stages=da([1, 2], dtype=int)),
     dict(tdi_stages=da([1.0, 2.0]))),
    ("int_max_well", "max_well=96000 (int), read_noise=25 (int)",
     dict(max_well=96000, read_noise=25), dict(max_well=96000.0, read_noise=25.0)),
    ("bool_tdi", "tdi_stages=True", dict(tdi_stages=True), dict(tdi_stages=1.0)),
    ("numeric_string", "focal_length='4.0' (a string)", dict(focal_length="4.0"),
     dict(focal_length=4.0)),
    ("units_mm", "aperture_diameter 275 with attrs units='mm' (expect 0.275 m)",
     dict(aperture_diameter=da([275.0], units="mm")), dict(aperture_diameter=da([0.275]))),
    ("units_ms", "integration_time 30 with attrs units='ms' (expect 0.03 s)",
     dict(integration_time=da([30.0], units="ms")), dict(integration_time=da([0.03]))),
    ("units_um_pitch", "pixel_pitch_x 8 with attrs units='um' (expect 8e-6 m)",
     dict(pixel_pitch_x=da([8.0], units="um")), dict(pixel_pitch_x=da([8e-6]))),
    ("sweep_with_coord", "focal_length on dim case with coordinate labels [10, 20]",
     dict(focal_length=xr.DataArray([3.0, 4.0], dims="case", coords={"case": [10, 20]})),
     dict(focal_length=xr.DataArray([3.0, 4.0], dims="case", coords={"case": [10, 20]}))),
]
for cid, desc, kw, ref_kw in SENSOR_SAME:
    add(f"sensor.{cid}", "sensor", desc + " -> niirs", lambda kw=kw: xbsm.niirs(sen(**kw), SC),
        names=tuple(kw), expect="same", ref=lambda r=ref_kw: xbsm.niirs(sen(**r), SC),
        oracle="niirs must equal the float64 / SI-converted reference within 1e-9")

# Sweeps on dims named like xbsm's own: the result must equal the same sweep on a safe dim.
COLLIDING_DIMS = ["wavelength", "frequency", "orientation", "fx", "fy", "x", "y", "component",
                  "path", "position", "kernel_x", "quantum_efficiency_wavelength", "reflectance"]


def renamed_ref(build, values, dim, main="niirs"):
    """Reference: the same sweep on dim 'safe_sweep', renamed to ``dim`` after the run."""
    def ref():
        return build(da(values, "safe_sweep"))[main].rename(safe_sweep=dim)
    return ref


for dim in COLLIDING_DIMS:
    add(f"sensor.focal_length.dim_{dim}", "sensor",
        f"focal_length [3, 4] swept on dim {dim!r} -> niirs",
        lambda d=dim: xbsm.niirs(sen(focal_length=da([3.0, 4.0], d)), SC),
        names=("focal_length", dim), expect="same",
        ref=renamed_ref(lambda f: xbsm.niirs(sen(focal_length=f), SC), [3.0, 4.0], dim),
        oracle=f"niirs must carry dim {dim!r} (size 2) equal to the same sweep on a safe dim")
add("sensor.focal_length.dim_giqe", "sensor", "focal_length [3, 3.5, 4] on dim 'giqe' -> niirs",
    lambda: xbsm.niirs(sen(focal_length=da([3.0, 3.5, 4.0], "giqe")), SC),
    names=("focal_length", "giqe"), expect="check",
    check=lambda r: ("silent_wrong", f"sweep merged with the GIQE versions: {dict(r.niirs.sizes)}"),
    oracle="niirs already has dim giqe: any result mixes the sweep with the GIQE versions")
add("sensor.focal_length.dim_wavelength_size1", "sensor",
    "focal_length [4.0] on dim 'wavelength' (size 1) -> niirs",
    lambda: xbsm.niirs(sen(focal_length=da([4.0], "wavelength")), SC),
    names=("focal_length", "wavelength"), expect="same",
    ref=renamed_ref(lambda f: xbsm.niirs(sen(focal_length=f), SC), [4.0], "wavelength"))
add("sensor.focal_length.dim_wavelength_size31", "sensor",
    "focal_length 31 values on dim 'wavelength' (the band's sample count) -> snr",
    lambda: xbsm.snr(sen(focal_length=da(np.linspace(3, 4, 31), "wavelength")), SC),
    names=("focal_length", "wavelength"), expect="same", main="snr",
    ref=renamed_ref(lambda f: xbsm.snr(sen(focal_length=f), SC), np.linspace(3, 4, 31),
                    "wavelength", "snr"))
add("sensor.integration_time.dim_same_name", "sensor",
    "integration_time [0.01, 0.03] on dim 'integration_time' -> niirs",
    lambda: xbsm.niirs(sen(integration_time=da([0.01, 0.03], "integration_time")), SC),
    names=("integration_time",), expect="same",
    ref=renamed_ref(lambda t: xbsm.niirs(sen(integration_time=t), SC), [0.01, 0.03],
                    "integration_time"))
add("sensor.focal_length.dim_same_name", "sensor",
    "focal_length [3, 4] on dim 'focal_length' -> niirs",
    lambda: xbsm.niirs(sen(focal_length=da([3.0, 4.0], "focal_length")), SC),
    names=("focal_length",), expect="same",
    ref=renamed_ref(lambda f: xbsm.niirs(sen(focal_length=f), SC), [3.0, 4.0], "focal_length"))
add("sensor.empty_sweep", "sensor", "focal_length = empty DataArray on dim case -> niirs",
    lambda: xbsm.niirs(sen(focal_length=da([])), SC), names=("focal_length",), expect="check",
    check=lambda r: dim_check(r, "niirs", "case", 0),
    oracle="niirs must carry dim 'case' with size 0 (or a clear error)")
add("sensor.unlabelled_array", "sensor", "focal_length=np.array([3., 4.]) (no dims)",
    lambda: xbsm.niirs(sen(focal_length=np.array([3.0, 4.0])), SC), names=("focal_length",))
add("sensor.2d_unlabelled", "sensor", "aperture_diameter=[[0.2]] nested list",
    lambda: xbsm.niirs(sen(aperture_diameter=[[0.2]]), SC), names=("aperture_diameter",))
add("sensor.complex_sweep", "sensor", "aperture_diameter complex DataArray [0.275+0j, 0.3+0.1j]",
    lambda: xbsm.niirs(sen(aperture_diameter=da([0.275 + 0j, 0.3 + 0.1j], dtype=complex)), SC),
    names=("aperture_diameter",))
add("sensor.huge_pitch", "sensor", "pixel_pitch_x=1.0 (1 m pixels; memory of the quadrature)",
    lambda: xbsm.niirs(sen(pixel_pitch_x=1.0), SC), names=("pixel_pitch_x",), expect="check",
    check=plausible, oracle="valid extreme: finite or flagged, within memory and time")
add("sensor.huge_aperture", "sensor", "aperture_diameter=1000 m",
    lambda: xbsm.niirs(sen(aperture_diameter=1000.0), SC), names=("aperture_diameter",),
    expect="check", check=plausible, oracle="valid extreme: finite or flagged, within memory")
add("sensor.unknown_keyword", "sensor", "sensor(aperture=0.2, ...) misspelt keyword",
    lambda: xbsm.sensor(aperture=0.2, **OLSON), names=("aperture",))
add("sensor.missing_required", "sensor", "sensor() without focal_length",
    lambda: xbsm.sensor(**{k: v for k, v in OLSON.items() if k != "focal_length"}),
    names=("focal_length",))
add("sensor.band_swept", "sensor", "wavelength_min swept DataArray [0.5e-6, 0.55e-6]",
    lambda: xbsm.niirs(sen(wavelength_min=da([0.5e-6, 0.55e-6])), SC), names=("wavelength_min",))
add("sensor.band_reversed", "sensor", "wavelength_min=0.85e-6, wavelength_max=0.55e-6",
    lambda: xbsm.niirs(sen(wavelength_min=0.85e-6, wavelength_max=0.55e-6), SC),
    names=("wavelength_min", "wavelength_max"))
add("sensor.band_in_gap_2.91um", "sensor", "band 2.9-2.91 um (two database samples)",
    lambda: xbsm.niirs(sen(wavelength_min=2.9e-6, wavelength_max=2.91e-6), SC),
    names=("wavelength_min", "wavelength_max"), expect="check", check=plausible,
    oracle="valid extreme (thermal, two samples): finite or flagged")
add("sensor.dask_negative", "sensor", "aperture_diameter dask DataArray [-0.1] (lazy check)",
    lambda: xbsm.niirs(sen(aperture_diameter=da([-0.1]).chunk()), SC).compute(),
    names=("aperture_diameter",))
add("sensor.dask_nan", "sensor", "focal_length dask DataArray [nan, 4]",
    lambda: xbsm.niirs(sen(focal_length=da([NAN, 4.0]).chunk()), SC).compute(),
    names=("focal_length",))

# Filter kernels
KERNELS = [
    ("sum_zero", [[1.0, -1.0]]), ("nan", [[NAN]]), ("empty", [[]]), ("3d", [[[1.0]]]),
    ("string", "sharpen"), ("inf", [[INF, -INF, 1.0]]),
]
for cid, kernel in KERNELS:
    add(f"sensor.filter_kernel.{cid}", "sensor", f"filter_kernel={kernel!r}",
        lambda k=kernel: xbsm.niirs(sen(filter_kernel=k), SC), names=("filter_kernel",))
add("sensor.filter_kernel.wrong_dims", "sensor", "filter_kernel DataArray on dims (a, b)",
    lambda: xbsm.niirs(sen(filter_kernel=xr.DataArray([[1.0]], dims=("a", "b"))), SC),
    names=("filter_kernel",))
add("sensor.filter_kernel.huge", "sensor", "filter_kernel 2001 x 2001 uniform (memory)",
    lambda: xbsm.niirs(sen(filter_kernel=np.full((2001, 2001), 1.0 / 2001**2)), SC),
    names=("filter_kernel",), expect="check", check=plausible,
    oracle="valid but huge: finite or flagged, within memory and time")

# Spectral curves
QE_UM = xr.DataArray([0.55, 0.75, 0.60], dims="wavelength", coords={"wavelength": [0.5, 0.7, 0.9]})
QE_M = QE_UM.assign_coords(wavelength=QE_UM.wavelength * 1e-6)
SPECTRAL = [
    ("qe_in_micrometres", "QE curve with wavelengths in um (misses the band)",
     dict(quantum_efficiency=QE_UM)),
    ("qe_partial_band", "QE curve covering only 0.5-0.6 um of a 0.55-0.85 um band",
     dict(quantum_efficiency=QE_M.isel(wavelength=[0, 1]).assign_coords(
         wavelength=[0.5e-6, 0.6e-6]))),
    ("qe_nan_value", "QE curve with a NaN value",
     dict(quantum_efficiency=QE_M.copy(data=[0.55, NAN, 0.6]))),
    ("qe_decreasing_wl", "QE curve with decreasing wavelengths",
     dict(quantum_efficiency=QE_M.isel(wavelength=[2, 1, 0]))),
    ("qe_no_coord", "QE DataArray on dim wavelength without a coordinate",
     dict(quantum_efficiency=xr.DataArray([0.5, 0.6, 0.7], dims="wavelength"))),
    ("qe_negative_wl", "QE curve at negative wavelengths",
     dict(quantum_efficiency=QE_M.assign_coords(wavelength=-QE_M.wavelength[::-1].values))),
    ("qe_single_point", "QE curve with a single point at 0.7 um",
     dict(quantum_efficiency=QE_M.isel(wavelength=[1]))),
    ("transmission_um", "optics_transmission curve with wavelengths in um",
     dict(optics_transmission=QE_UM)),
    ("stray_um", "stray_irradiance curve with wavelengths in um",
     dict(stray_irradiance=QE_UM * 1e6)),
    ("transmission_partial_band", "optics_transmission curve covering only 0.6-0.9 um of a "
     "0.55-0.85 um band", dict(optics_transmission=QE_M.isel(wavelength=[1, 2]).assign_coords(
         wavelength=[0.6e-6, 0.9e-6]))),
]
PARTIAL_ORACLE = ("legitimate (zero outside the curve's range) but the user must learn it: "
                  "a partial_spectral_coverage flag (or an error); unflagged is wrong")
for cid, desc, kw in SPECTRAL:
    add(f"sensor.spectral.{cid}", "sensor", desc + " -> niirs",
        lambda kw=kw: xbsm.niirs(sen(**kw), SC), names=tuple(kw),
        oracle=PARTIAL_ORACLE if "partial" in cid else "")
add("sensor.spectral.qe_units_um_attr", "sensor",
    "QE curve wavelengths in um with coordinate attrs units='um' -> snr",
    lambda: xbsm.snr(sen(quantum_efficiency=QE_UM.assign_coords(
        wavelength=QE_UM.wavelength.assign_attrs(units="um"))), SC),
    names=("quantum_efficiency",), expect="same", main="snr",
    ref=lambda: xbsm.snr(sen(quantum_efficiency=QE_M), SC),
    oracle="snr must equal the curve given in metres")
add("sensor.spectral.qe_swept_curves", "sensor", "QE curves swept over dim case (2 curves)",
    lambda: xbsm.snr(sen(quantum_efficiency=xr.concat([QE_M, QE_M * 0.5], "case")), SC),
    names=("quantum_efficiency",), expect="check", main="snr",
    check=lambda r: dim_check(r, "snr", "case", 2),
    oracle="snr must carry dim 'case' of size 2")

# --- xbsm.scenario
# (a visibility between the database's 5 and 23 km is interpolated in extinction since
# issue 24, flagged visibility_interpolated: 2 km, below the file's range, is the bad one)
SCENARIO_BAD = {
    "altitude": [-1.0, 0.0, 1.0, 600e3, INF, NAN, "high"],
    "ground_range": [-1.0, 400e3, INF, NAN, -INF],
    "visibility": [2.0, 0.0, INF, NAN, "23 km", 23000.0],
    "platform_speed": [-1.0, INF, NAN],
    "target_reflectance": [1.5, -0.1],
    "target_temperature": [0.0, INF, -10.0],
    "background_reflectance": [NAN],
    "background_temperature": [INF],
    "high_altitude_wind_speed": [-1.0, INF],
    "cn2_at_1m": [-1e-14, INF, NAN],
}
TARGET_PARAMS = ("target_reflectance", "target_temperature", "background_reflectance",
                 "background_temperature")  # used by snr(targets="scenario") only
for name, values in SCENARIO_BAD.items():
    for value in values:
        if name in TARGET_PARAMS:
            add(f"scenario.{name}={slug(value)}", "scenario",
                f"scenario({name}={value!r}) -> snr(targets='scenario')",
                lambda n=name, v=value: xbsm.snr(S, scn(**{n: v}), targets="scenario"),
                names=(name,), main="snr")
        else:
            add(f"scenario.{name}={slug(value)}", "scenario",
                f"scenario({name}={value!r}) -> niirs",
                lambda n=name, v=value: xbsm.niirs(S, scn(**{n: v})), names=(name,))

SCENARIO_EXTREMES = [
    ("beyond_horizon", "altitude 1000 m, ground_range 300 km (beyond the horizon)",
     dict(altitude=1000.0, ground_range=300e3)),
    ("low_far", "altitude 2 m, ground_range 100 km", dict(altitude=2.0, ground_range=100e3)),
    ("database_gap", "altitude 30 km (the sparse 24.5-550 km gap)", dict(altitude=30e3)),
    ("space", "altitude 550 km, ground_range 0", dict(altitude=550e3, ground_range=0.0)),
    ("strong_turbulence", "cn2_at_1m=1e-10 (extreme turbulence)", dict(cn2_at_1m=1e-10)),
    ("hot_target", "target_temperature=5000 K (snr targets='giqe' ignores it)",
     dict(target_temperature=5000.0)),
    ("zero_speed", "platform_speed=0 (hovering)", dict(platform_speed=0.0)),
]
for cid, desc, kw in SCENARIO_EXTREMES:
    add(f"scenario.{cid}", "scenario", desc + " -> niirs",
        lambda kw=kw: xbsm.niirs(S, scn(**kw)), names=tuple(kw), expect="check",
        check=plausible, oracle="valid extreme: finite, or NaN / out-of-range with a flag")

SCENARIO_SAME = [
    ("units_km", "ground_range [20.] with attrs units='km' (expect 20000 m)",
     dict(ground_range=da([20.0], units="km")), dict(ground_range=da([20e3]))),
    ("altitude_units_km", "altitude [9.] with attrs units='km' (expect 9000 m)",
     dict(altitude=da([9.0], units="km")), dict(altitude=da([9000.0]))),
    ("float32_range", "ground_range float32 DataArray [12345.6, 20000]",
     dict(ground_range=da([12345.6, 20e3], dtype=np.float32)),
     dict(ground_range=da(np.float32([12345.6, 20e3]).astype(float)))),
    ("float32_altitude", "altitude=np.float32(9123.4)", dict(altitude=np.float32(9123.4)),
     dict(altitude=float(np.float32(9123.4)))),
    ("int_inputs", "altitude=9000, ground_range=20000, visibility=23 (ints)",
     dict(altitude=9000, ground_range=20000, visibility=23),
     dict(altitude=9000.0, ground_range=20e3, visibility=23.0)),
    ("int_sweep", "ground_range int DataArray [10000, 20000]",
     dict(ground_range=da([10000, 20000], dtype=int)), dict(ground_range=da([10e3, 20e3]))),
    ("numeric_string", "altitude='9000'", dict(altitude="9000"), dict(altitude=9000.0)),
]
for cid, desc, kw, ref_kw in SCENARIO_SAME:
    add(f"scenario.{cid}", "scenario", desc + " -> niirs", lambda kw=kw: xbsm.niirs(S, scn(**kw)),
        names=tuple(kw), expect="same", ref=lambda r=ref_kw: xbsm.niirs(S, scn(**r)),
        oracle="niirs must equal the float64 / SI-converted reference within 1e-9")

for dim in ["wavelength", "frequency", "orientation", "component", "fx", "x", "path",
            "altitude", "visibility"]:
    add(f"scenario.ground_range.dim_{dim}", "scenario",
        f"ground_range [10 km, 20 km] swept on dim {dim!r} -> niirs",
        lambda d=dim: xbsm.niirs(S, scn(ground_range=da([10e3, 20e3], d))),
        names=("ground_range", dim), expect="same",
        ref=renamed_ref(lambda g: xbsm.niirs(S, scn(ground_range=g)), [10e3, 20e3], dim),
        oracle=f"niirs must carry dim {dim!r} (size 2) equal to the same sweep on a safe dim")
add("scenario.altitude.dim_ground_range", "scenario",
    "altitude [8, 9 km] on dim 'ground_range' with scalar ground_range -> niirs",
    lambda: xbsm.niirs(S, scn(altitude=da([8e3, 9e3], "ground_range"))),
    names=("altitude", "ground_range"), expect="same",
    ref=renamed_ref(lambda a: xbsm.niirs(S, scn(altitude=a)), [8e3, 9e3], "ground_range"))
add("scenario.ground_range.dim_giqe", "scenario", "ground_range 3 values on dim 'giqe' -> niirs",
    lambda: xbsm.niirs(S, scn(ground_range=da([0.0, 10e3, 20e3], "giqe"))),
    names=("ground_range", "giqe"), expect="check",
    check=lambda r: ("silent_wrong", f"sweep merged with the GIQE versions: {dict(r.niirs.sizes)}"),
    oracle="niirs already has dim giqe: any result mixes the sweep with the GIQE versions")
add("scenario.empty_sweep", "scenario", "ground_range = empty DataArray on dim case -> niirs",
    lambda: xbsm.niirs(S, scn(ground_range=da([]))), names=("ground_range",), expect="check",
    check=lambda r: dim_check(r, "niirs", "case", 0),
    oracle="niirs must carry dim 'case' with size 0 (or a clear error)")
add("scenario.complex", "scenario", "ground_range=20e3+5e3j",
    lambda: xbsm.niirs(S, scn(ground_range=20e3 + 5e3j)), names=("ground_range",))
add("scenario.none", "scenario", "ground_range=None", lambda: xbsm.niirs(S, scn(ground_range=None)),
    names=("ground_range",))
add("scenario.unknown_keyword", "scenario", "scenario(ground_rang=20e3) misspelt",
    lambda: xbsm.scenario(altitude=9000.0, ground_rang=20e3, visibility=23.0),
    names=("ground_rang",))
add("scenario.visibility_sweep_bad", "scenario", "visibility DataArray [23, 2]",
    lambda: xbsm.niirs(S, scn(visibility=da([23.0, 2.0]))), names=("visibility",))
add("scenario.dask_visibility_bad", "scenario", "visibility dask DataArray [23, 2] (lazy)",
    lambda: xbsm.niirs(S, scn(visibility=da([23.0, 2.0]).chunk())).compute(),
    names=("visibility",))

# --- xbsm.method: every knob. Each method is used for niirs on the standard case.
KNOB_PRESET = {"frequency_samples": "pybsm", "undersampling_threshold": "pybsm"}
METHOD_BAD = {
    "edge_otf": ["imag", "ABS", None, 1],
    "filter_otf": ["x", "DTFT"],
    "edge_rule": ["gaus", "gauss-legendre", None],
    "band_edges": ["interp", ""],
    "atmosphere_interpolation": ["loglinear", "cubic"],
    "turbulence_path_rule": ["simpson", "gauss_legendre"],
    "elevation": ["nadir"],
    "nodes_per_panel": [2.5, 0, -3, NAN, 10**6],
    "panels_per_oscillation": [0.0, -1.0, NAN, INF, 1e6],
    "min_panels": [0, -1, 2.5, 10**9],
    "frequency_samples": [2.5, 0, 1, -101, 100, NAN, 10**6],
    "otf_wavelengths": [-1, 2.5, 1, 10**9],
    "turbulence_path_samples": [0, 1, -5, 2.5],
    "giqe4_noise_coefficient": [NAN, -1.0, INF, "0.344"],
    "undersampling_threshold": [NAN, -1.0],
    "constants": [None, "codata"],
}
# string knobs: the valid choices, to tell a silent coercion from a silent garbage result
KNOB_CHOICES = {
    "edge_otf": ("abs", "real"), "filter_otf": ("pybsm", "dtft"),
    "edge_rule": ("uniform_trapezoid", "gauss_legendre"),
    "band_edges": ("exact", "interpolated"),
    "atmosphere_interpolation": ("linear", "log-linear", "same-elevation"),
    "turbulence_path_rule": ("trapezoid", "gauss-legendre"), "elevation": ("look-down", "target"),
}
KNOB_VALID_EXTREMES = {("otf_wavelengths", 1)}  # one OTF wavelength: crude but documented
CONVERGED_NIIRS = 0.01  # the NIIRS error undersampled_grid promises to flag (methods.py)


def even_grid_check(result):
    """An even ``frequency_samples`` is a valid grid: compare with the converged edge rule.

    pyBSM's slice of an N-point grid ``linspace(-1, 1, N)`` is ``arange(0, 1, 2/(N-1))``:
    for N = 100 that is 50 samples up to 0.99 of the cutoff, as N = 101 gives 50 up to
    0.98. The result is right if it agrees with the same preset using the converged
    Gauss-Legendre edge rule within 0.01 NIIRS (the error ``undersampled_grid`` flags
    beyond), or if it carries ``undersampled_grid``.
    """
    bits = int(np.bitwise_or.reduce(result.flags.values.ravel()))
    if bits & FLAGS["undersampled_grid"][0]:
        return "flagged", "undersampled_grid set"
    ref = xbsm.niirs(S, SC, method=xbsm.method("pybsm", edge_rule="gauss_legendre"))
    err = float(np.max(np.abs(result.niirs - ref.niirs)))
    if err <= CONVERGED_NIIRS:
        return "sensible", f"within {err:.2g} NIIRS of the converged edge rule"
    return "silent_wrong", f"{err:.3g} NIIRS from the converged edge rule, not flagged"


KNOB_CUSTOM = {  # (knob, value) -> (check, oracle)
    ("frequency_samples", 100): (
        even_grid_check,
        "an even grid is valid (50 samples to 0.99 cutoff): niirs within 0.01 of "
        "method('pybsm', edge_rule='gauss_legendre'), or flagged undersampled_grid"),
}
SHARP = sen(filter_kernel=[[-0.25, 1.5, -0.25]])  # filter_otf matters only with a kernel


def knob_case(knob, value):
    preset = KNOB_PRESET.get(knob, "accurate")
    sensor = SHARP if knob == "filter_otf" else S

    def call():
        return xbsm.niirs(sensor, SC, method=xbsm.method(preset, **{knob: value}))

    valid = (knob, value) in KNOB_VALID_EXTREMES

    def check(result):
        cls, note = generic_reject(result, "niirs", valid_input=valid)
        if cls == "silent_wrong" and knob in KNOB_CHOICES:
            for choice in KNOB_CHOICES[knob]:
                other = xbsm.niirs(sensor, SC, method=xbsm.method(preset, **{knob: choice}))
                if np.allclose(result.niirs, other.niirs, rtol=RTOL, atol=0, equal_nan=True):
                    return cls, f"silently treated as {knob}={choice!r}"
        return cls, note

    custom_check, custom_oracle = KNOB_CUSTOM.get((knob, value), (None, None))
    add(f"method.{knob}={slug(value)}", "method",
        f"xbsm.method({preset!r}, {knob}={value!r}) -> niirs", call, names=(knob,),
        expect="check", check=custom_check or check,
        oracle=custom_oracle or ("valid extreme: finite or flagged" if valid else
                                 "invalid knob: a clear error or a flag; a finite result is "
                                 "a silent coercion"))


for knob, values in METHOD_BAD.items():
    for value in values:
        knob_case(knob, value)
add("method.unknown_knob", "method", "xbsm.method('accurate', frequency_sample=1601) typo",
    lambda: xbsm.method("accurate", frequency_sample=1601), names=("frequency_sample",))
add("method.unknown_preset", "method", "xbsm.method('acurate')",
    lambda: xbsm.method("acurate"), names=("method", "acurate"))
add("method.preset_none", "method", "xbsm.method(None)", lambda: xbsm.method(None),
    names=("method",))
add("method.niirs_method_dict", "method", "niirs(s, sc, method={'name': 'fast'})",
    lambda: xbsm.niirs(S, SC, method={"name": "fast"}), names=("method",))
add("method.niirs_method_upper", "method", "niirs(s, sc, method='PYBSM')",
    lambda: xbsm.niirs(S, SC, method="PYBSM"), names=("method",))
add("method.niirs_method_int", "method", "niirs(s, sc, method=1)",
    lambda: xbsm.niirs(S, SC, method=1), names=("method",))
add("method.replace_unknown", "method", "Method.replace(bogus=1)",
    lambda: xbsm.method("fast").replace(bogus=1), names=("bogus",))

# --- xbsm.snr
add("snr.targets_typo", "snr", "snr(s, sc, targets='GIQE')",
    lambda: xbsm.snr(S, SC, targets="GIQE"), names=("targets",), main="snr")
add("snr.targets_none", "snr", "snr(s, sc, targets=None)",
    lambda: xbsm.snr(S, SC, targets=None), names=("targets",), main="snr")
add("snr.swapped_args", "snr", "snr(scenario, sensor) (arguments swapped)",
    lambda: xbsm.snr(SC, S), names=("sensor", "scenario"), main="snr")
add("snr.dict_sensor", "snr", "snr(dict(...), sc) (plain dict)",
    lambda: xbsm.snr(dict(OLSON), SC), names=("sensor",), main="snr")
add("snr.method_bogus", "snr", "snr(s, sc, method='bogus')",
    lambda: xbsm.snr(S, SC, method="bogus"), names=("method",), main="snr")
add("snr.zero_contrast", "snr", "targets='scenario' with target = background (contrast 0)",
    lambda: xbsm.snr(S, scn(target_reflectance=0.1, background_reflectance=0.1,
                            target_temperature=290.0, background_temperature=290.0),
                     targets="scenario"),
    names=(), expect="check", main="snr",
    check=lambda r: (("sensible", "snr == 0") if float(r.snr) == 0.0
                     else ("silent_wrong", f"snr {float(r.snr)!r} != 0")),
    oracle="zero contrast: snr must be exactly 0 (correct, not an error)")
add("snr.qe_in_micrometres", "snr", "QE curve in um (no overlap with the band) -> snr",
    lambda: xbsm.snr(sen(quantum_efficiency=QE_UM), SC), names=("quantum_efficiency",),
    main="snr", oracle="zero signal from a curve that misses the band: error or flag")
add("snr.qe_zero", "snr", "quantum_efficiency=0 -> snr (zero signal)",
    lambda: xbsm.snr(sen(quantum_efficiency=0.0), SC), names=("quantum_efficiency",),
    main="snr", oracle="zero signal: error or flag; an unflagged SNR 0 is wrong")
add("snr.tiny_aperture", "snr", "aperture_diameter=1e-9 -> snr (SNR ~ 0)",
    lambda: xbsm.snr(sen(aperture_diameter=1e-9), SC), names=("aperture_diameter",),
    main="snr", expect="check", check=lambda r: generic_reject(r, "snr", valid_input=True),
    oracle="valid but SNR ~ 0: finite (or flagged)")
add("snr.edited_aperture", "snr", "s.assign(aperture_diameter=-0.1) after validation",
    lambda: xbsm.snr(S.assign(aperture_diameter=-0.1), SC), names=("aperture_diameter",),
    main="snr")
add("snr.edited_qe", "snr", "s.assign(quantum_efficiency=2.0) after validation",
    lambda: xbsm.snr(S.assign(quantum_efficiency=2.0), SC), names=("quantum_efficiency",),
    main="snr")
add("snr.edited_visibility", "snr", "sc.assign(visibility=50.0) after validation",
    lambda: xbsm.snr(S, SC.assign(visibility=50.0)), names=("visibility",), main="snr")
add("snr.edited_range_nan", "snr", "sc.assign(ground_range=nan) after validation",
    lambda: xbsm.snr(S, SC.assign(ground_range=NAN)), names=("ground_range",), main="snr")
add("snr.dropped_variable", "snr", "s.drop_vars('focal_length')",
    lambda: xbsm.snr(S.drop_vars("focal_length"), SC), names=("focal_length",), main="snr")
add("snr.dims_conflict_sizes", "snr",
    "sensor focal_length on dim case (2) and scenario ground_range on dim case (3)",
    lambda: xbsm.snr(sen(focal_length=da([3.0, 4.0])), scn(ground_range=da([0.0, 1e4, 2e4]))),
    names=("focal_length", "ground_range", "case"), main="snr")
add("snr.dims_conflict_labels", "snr",
    "focal_length on dim case labels [0, 1], ground_range on case labels [10, 11]",
    lambda: xbsm.snr(
        sen(focal_length=xr.DataArray([3.0, 4.0], dims="case", coords={"case": [0, 1]})),
        scn(ground_range=xr.DataArray([1e4, 2e4], dims="case", coords={"case": [10, 11]}))),
    names=("focal_length", "ground_range", "case"), main="snr", expect="check",
    check=lambda r: dim_check(r, "snr", "case", 2),
    oracle="snr must carry dim 'case' of size 2 (or a clear error), never an empty join")
add("snr.dims_zip", "snr", "focal_length and ground_range both on dim case (size 2): zipped",
    lambda: xbsm.snr(sen(focal_length=da([3.0, 4.0])), scn(ground_range=da([1e4, 2e4]))),
    names=(), main="snr", expect="same",
    ref=lambda: xr.concat([xbsm.snr(sen(focal_length=f), scn(ground_range=g)).snr
                           for f, g in ((3.0, 1e4), (4.0, 2e4))], "case"),
    oracle="documented zip: snr[case=i] must equal snr(focal_length[i], ground_range[i])")
add("snr.float32_sweep", "snr", "integration_time float32 DataArray [0.01, 0.03] -> snr",
    lambda: xbsm.snr(sen(integration_time=da([0.01, 0.03], dtype=np.float32)), SC),
    names=(), main="snr", expect="same",
    ref=lambda: xbsm.snr(sen(integration_time=da(np.float32([0.01, 0.03]).astype(float))), SC))
add("snr.beyond_horizon", "snr", "altitude 1000 m, ground range 300 km -> snr",
    lambda: xbsm.snr(S, scn(altitude=1000.0, ground_range=300e3)), names=(), main="snr",
    expect="check", check=lambda r: generic_reject(r, "snr", valid_input=True),
    oracle="NaN must carry beyond_database")

# --- xbsm.niirs
add("niirs.tiny_integration_time", "niirs", "integration_time=1e-12 (SNR near 0)",
    lambda: xbsm.niirs(sen(integration_time=1e-12), SC), names=(), expect="check",
    check=plausible, oracle="tiny SNR: large negative NIIRS flagged snr_out_of_range")
add("niirs.qe_zero", "niirs", "quantum_efficiency=0 (SNR exactly 0)",
    lambda: xbsm.niirs(sen(quantum_efficiency=0.0), SC), names=("quantum_efficiency",),
    expect="check", check=plausible, oracle="NaN with snr_nonpositive")
add("niirs.swapped_args", "niirs", "niirs(scenario, sensor)", lambda: xbsm.niirs(SC, S),
    names=("sensor", "scenario"))
add("niirs.none_scenario", "niirs", "niirs(s, None)", lambda: xbsm.niirs(S, None),
    names=("scenario",))
add("niirs.edited_aperture", "niirs", "s.assign(aperture_diameter=-0.1)",
    lambda: xbsm.niirs(S.assign(aperture_diameter=-0.1), SC), names=("aperture_diameter",))
add("niirs.edited_focal_zero", "niirs", "s.assign(focal_length=0.0)",
    lambda: xbsm.niirs(S.assign(focal_length=0.0), SC), names=("focal_length",))
add("niirs.edited_altitude", "niirs", "sc.assign(altitude=-5.0)",
    lambda: xbsm.niirs(S, SC.assign(altitude=-5.0)), names=("altitude",))
# A kernel of another shape cannot be put in with s.assign(filter_kernel=...): xarray itself
# refuses to resize the kernel dims there, before xbsm is called; drop_vars first.
add("niirs.edited_kernel", "niirs",
    "s.drop_vars('filter_kernel').assign(filter_kernel=2x2 NaN kernel)",
    lambda: xbsm.niirs(S.drop_vars("filter_kernel").assign(filter_kernel=xr.DataArray(
        np.full((2, 2), NAN), dims=("kernel_y", "kernel_x"))), SC),
    names=("filter_kernel",))
add("niirs.edited_kernel_sum", "niirs", "s.assign(filter_kernel=[[2.0]]) (sums to 2)",
    lambda: xbsm.niirs(S.assign(filter_kernel=xr.DataArray([[2.0]],
                                                           dims=("kernel_y", "kernel_x"))), SC),
    names=("filter_kernel",))
add("niirs.edited_obscuration", "niirs", "s.assign(obscuration_ratio=1.0)",
    lambda: xbsm.niirs(S.assign(obscuration_ratio=1.0), SC), names=("obscuration_ratio",))
add("niirs.edited_band", "niirs", "s.assign(wavelength_min=0.9e-6) (min > max)",
    lambda: xbsm.niirs(S.assign(wavelength_min=0.9e-6), SC), names=("wavelength_min",))
add("niirs.edited_pitch_sweep", "niirs", "s.assign(pixel_pitch_x=DataArray on dim 'giqe')",
    lambda: xbsm.niirs(S.assign(pixel_pitch_x=da([8e-6, 9e-6, 1e-5], "giqe")), SC),
    names=("pixel_pitch_x", "giqe"), expect="check",
    check=lambda r: ("silent_wrong", f"sweep merged with giqe: {dict(r.niirs.sizes)}"))
add("niirs.dims_conflict_labels", "niirs",
    "focal_length on dim case labels [0, 1], ground_range on case labels [10, 11]",
    lambda: xbsm.niirs(
        sen(focal_length=xr.DataArray([3.0, 4.0], dims="case", coords={"case": [0, 1]})),
        scn(ground_range=xr.DataArray([1e4, 2e4], dims="case", coords={"case": [10, 11]}))),
    names=("focal_length", "ground_range", "case"), expect="check",
    check=lambda r: dim_check(r, "niirs", "case", 2))
add("niirs.dims_conflict_sizes", "niirs", "sensor dim case (2) vs scenario dim case (3)",
    lambda: xbsm.niirs(sen(focal_length=da([3.0, 4.0])), scn(ground_range=da([0.0, 1e4, 2e4]))),
    names=("focal_length", "ground_range", "case"))
add("niirs.orientation_sweep", "niirs", "jitter_x [0.5, 5] urad on dim 'orientation'",
    lambda: xbsm.niirs(sen(jitter_x=da([0.5e-6, 5e-6], "orientation")), SC),
    names=("jitter_x", "orientation"), expect="same",
    ref=renamed_ref(lambda j: xbsm.niirs(sen(jitter_x=j), SC), [0.5e-6, 5e-6], "orientation"))
add("niirs.fast_float32", "niirs", "method='fast', focal_length float32 sweep",
    lambda: xbsm.niirs(sen(focal_length=da([3.0, 4.1], dtype=np.float32)), SC, method="fast"),
    names=(), expect="same",
    ref=lambda: xbsm.niirs(sen(focal_length=da(np.float32([3.0, 4.1]).astype(float))), SC,
                           method="fast"))
add("niirs.pybsm_snr_zero", "niirs", "method='pybsm', quantum_efficiency=0 (SNR 0)",
    lambda: xbsm.niirs(sen(quantum_efficiency=0.0), SC, method="pybsm"),
    names=("quantum_efficiency",), expect="check", check=plausible,
    oracle="NaN with snr_nonpositive")
add("niirs.pybsm_undersampled", "niirs", "method='pybsm', pixel_pitch_x=1e-7 (Q ~ 10)",
    lambda: xbsm.niirs(sen(pixel_pitch_x=1e-7), SC, method="pybsm"), names=(),
    expect="check", check=plausible, oracle="valid extreme: finite or flagged")
add("niirs.pybsm_coarse", "niirs", "method='pybsm', pixel_pitch_x=1e-4 (Q ~ 0.02, undersampled)",
    lambda: xbsm.niirs(sen(pixel_pitch_x=1e-4), SC, method="pybsm"), names=(),
    expect="check",
    check=lambda r: (("flagged", "undersampled_grid set")
                     if (int(np.bitwise_or.reduce(r.flags.values.ravel()))
                         & FLAGS["undersampled_grid"][0])
                     else ("silent_wrong", "no undersampled_grid flag at Q ~ 0.02")),
    oracle="Q ~ 0.02 with 101 samples must carry undersampled_grid")

# --- xbsm.system_otf
OTF_FREQ = [
    ("nan", [0.0, NAN, 1e5]), ("inf", [0.0, INF]), ("empty", []), ("string", "high"),
    ("complex", [0.0, 1e5 + 1j]), ("2d", [[0.0, 1e5]]), ("negative", [-1e5, 0.0, 1e5]),
]
for cid, freq in OTF_FREQ:
    valid = cid in ("negative",)
    add(f"system_otf.frequency_{cid}", "system_otf", f"system_otf(frequency={freq!r})",
        lambda f=freq: xbsm.system_otf(S, SC, frequency=f), names=("frequency",), main="system",
        expect="check" if cid in ("negative", "empty") else "reject",
        check=(lambda r: even_check(r)) if valid else (  # noqa: PLW0108 - defined below
            lambda r: dim_check(r, "system", "frequency", 0)),
        oracle=("the OTF is even: OTF(-f) must equal OTF(f)" if valid else
                "empty: result with frequency size 0 or a clear error" if cid == "empty" else ""))
add("system_otf.frequency_float32", "system_otf", "frequency float32 array [0, 1e4, 1.23e5]",
    lambda: xbsm.system_otf(S, SC, frequency=np.float32([0.0, 1e4, 1.23e5])),
    names=(), main="system", expect="same",
    ref=lambda: xbsm.system_otf(S, SC, frequency=np.float32([0.0, 1e4, 1.23e5]).astype(float)))
add("system_otf.frequency_int", "system_otf", "frequency int array [0, 10000, 100000]",
    lambda: xbsm.system_otf(S, SC, frequency=np.array([0, 10000, 100000])),
    names=(), main="system", expect="same",
    ref=lambda: xbsm.system_otf(S, SC, frequency=np.array([0.0, 1e4, 1e5])))
add("system_otf.frequency_huge", "system_otf", "frequency with 2e7 samples (memory)",
    lambda: xbsm.system_otf(S, SC, frequency=np.linspace(0.0, 5e5, 20_000_000)),
    names=("frequency",), main="system", expect="check",
    check=lambda r: ("sensible", "computed within memory and time"),
    oracle="large but valid: compute within memory and time or a clear error")
for dim in ("wavelength", "orientation", "giqe", "component"):
    add(f"system_otf.frequency_dim_{dim}", "system_otf",
        f"frequency DataArray [0, 1e4, 1e5] on dim {dim!r}",
        lambda d=dim: xbsm.system_otf(S, SC, frequency=xr.DataArray([0.0, 1e4, 1e5], dims=d)),
        names=("frequency", dim), main="system", expect="check",
        check=lambda r, d=dim: dim_check(r, "system", d, 3, also={"orientation": 2}
                                         if d != "orientation" else None),
        oracle=f"system must carry dim {dim!r} (3) and orientation (2)")
add("system_otf.fy_without_frequency", "system_otf", "system_otf(fy=DataArray) without frequency",
    lambda: xbsm.system_otf(S, SC, fy=xr.DataArray([0.0, 1e4], dims="fy")),
    names=("fy", "frequency"), main="system", expect="check",
    check=lambda r: dim_check(r, "system", "fy", 2),
    oracle="fy alone: a 2-D grid carrying fy (2) or a clear error")
add("system_otf.fy_same_dim", "system_otf", "frequency and fy both on dim 'f' (zipped diagonal)",
    lambda: xbsm.system_otf(S, SC, frequency=xr.DataArray([0.0, 1e5], dims="f"),
                            fy=xr.DataArray([0.0, 1e5], dims="f")),
    names=("fy", "frequency"), main="system", expect="check",
    check=lambda r: dim_check(r, "system", "f", 2),
    oracle="system must carry dim 'f' of size 2")
add("system_otf.fy_nan", "system_otf", "fy DataArray [nan, 1e4] on dim fy",
    lambda: xbsm.system_otf(S, SC, frequency=xr.DataArray([0.0, 1e4], dims="fx"),
                            fy=xr.DataArray([NAN, 1e4], dims="fy")),
    names=("fy",), main="system")
add("system_otf.fy_list", "system_otf", "fy=[0, 1e4] plain list",
    lambda: xbsm.system_otf(S, SC, frequency=xr.DataArray([0.0, 1e4], dims="fx"), fy=[0.0, 1e4]),
    names=("fy",), main="system", expect="check",
    check=lambda r: dim_check(r, "system", "fy", 2),
    oracle="a plain list for fy: result on a fy dim (2) or a clear error")
add("system_otf.method_bogus", "system_otf", "system_otf(method='exact')",
    lambda: xbsm.system_otf(S, SC, method="exact"), names=("method",), main="system")
add("system_otf.beyond_horizon", "system_otf", "system_otf beyond the horizon (1 km, 300 km)",
    lambda: xbsm.system_otf(S, scn(altitude=1000.0, ground_range=300e3)), names=(),
    main="system", expect="check", check=lambda r: generic_reject(r, "system", valid_input=True),
    oracle="valid geometry: finite OTF, or NaN with a flag")
add("system_otf.qe_in_micrometres", "system_otf", "QE curve in um -> system_otf",
    lambda: xbsm.system_otf(sen(quantum_efficiency=QE_UM), SC), names=("quantum_efficiency",),
    main="system", oracle="no signal in the band: the spectral weighting is undefined")
add("system_otf.sweep_dim_frequency", "system_otf", "focal_length [3, 4] on dim 'frequency'",
    lambda: xbsm.system_otf(sen(focal_length=da([3.0, 4.0], "frequency")), SC),
    names=("focal_length", "frequency"), main="system", expect="check",
    check=lambda r: ("silent_wrong", f"sweep merged with the frequencies: {dict(r.system.sizes)}"),
    oracle="system already has dim frequency: any result mixes the sweep and the frequencies")
add("system_otf.sweep_dim_fx", "system_otf", "pixel_pitch_x [8, 10] um on dim 'fx' with a 2-D grid",
    lambda: xbsm.system_otf(sen(pixel_pitch_x=da([8e-6, 1e-5], "fx")), SC,
                            frequency=xr.DataArray([0.0, 1e4, 1e5], dims="fx"),
                            fy=xr.DataArray([0.0, 1e4], dims="fy")),
    names=("pixel_pitch_x", "fx"), main="system", expect="check",
    check=lambda r: ("silent_wrong", f"sweep merged with the fx axis: {dict(r.system.sizes)}"))

# --- reflectance_to_photoelectrons (xbsm.simulate.reflectance_to_photoelectrons)
R2P = "reflectance_to_photoelectrons"


def r2p(**kw):
    return reflectance_to_photoelectrons(S, SC, **kw)


R2P_BAD = [
    ("reflectance_negative", dict(reflectance=[-0.1, 0.5]), ("reflectance",)),
    ("reflectance_above_1", dict(reflectance=[0.5, 1.5]), ("reflectance",)),
    ("reflectance_nan", dict(reflectance=[NAN, 0.5]), ("reflectance",)),
    ("reflectance_inf", dict(reflectance=[0.5, INF]), ("reflectance",)),
    ("reflectance_string", dict(reflectance="grey"), ("reflectance",)),
    ("reflectance_2d", dict(reflectance=[[0.1, 0.2]]), ("reflectance",)),
    ("temperature_negative", dict(temperature=-5.0), ("temperature",)),
    ("temperature_zero", dict(temperature=0.0), ("temperature",)),
    ("temperature_nan", dict(temperature=NAN), ("temperature",)),
    ("integration_time_negative", dict(integration_time=-1.0), ("integration_time",)),
    ("integration_time_zero", dict(integration_time=0.0), ("integration_time",)),
    ("integration_time_inf", dict(integration_time=INF), ("integration_time",)),
    ("method_bogus", dict(method="bogus"), ("method",)),
]
for cid, kw, names in R2P_BAD:
    add(f"r2p.{cid}", R2P, f"reflectance_to_photoelectrons({kw})", lambda kw=kw: r2p(**kw),
        names=names, main="photoelectrons")
add("r2p.reflectance_empty", R2P, "reflectance=[] (empty)", lambda: r2p(reflectance=[]),
    names=("reflectance",), main="photoelectrons", expect="check",
    check=lambda r: dim_check(r, "photoelectrons", "reflectance", 0),
    oracle="photoelectrons over reflectance of size 0, or a clear error")
add("r2p.reflectance_dim_wavelength", R2P, "reflectance DataArray [0.1, 0.9] on dim 'wavelength'",
    lambda: r2p(reflectance=xr.DataArray([0.1, 0.9], dims="wavelength")),
    names=("reflectance", "wavelength"), main="photoelectrons", expect="check",
    check=lambda r: dim_check(r, "photoelectrons", "wavelength", 2))
add("r2p.reflectance_dim_other", R2P, "reflectance DataArray [0.1, 0.9] on dim 'case'",
    lambda: r2p(reflectance=da([0.1, 0.9])), names=("reflectance",), main="photoelectrons",
    expect="check", check=lambda r: dim_check(r, "photoelectrons", "case", 2),
    oracle="photoelectrons must carry the user's dim 'case' (2)")
add("r2p.reflectance_float32", R2P, "reflectance float32 [0.1, 0.33, 0.9]",
    lambda: r2p(reflectance=np.float32([0.1, 0.33, 0.9])), names=(), main="photoelectrons",
    expect="same", ref=lambda: r2p(reflectance=np.float32([0.1, 0.33, 0.9]).astype(float)))
add("r2p.integration_time_dim_reflectance", R2P, "integration_time DataArray on dim 'reflectance'",
    lambda: r2p(integration_time=xr.DataArray([0.01, 0.03], dims="reflectance")),
    names=("integration_time", "reflectance"), main="photoelectrons")
add("r2p.qe_in_micrometres", R2P, "QE curve in um (zero signal)",
    lambda: reflectance_to_photoelectrons(sen(quantum_efficiency=QE_UM), SC),
    names=("quantum_efficiency",), main="photoelectrons")
add("r2p.beyond_horizon", R2P, "altitude 1000 m, ground range 300 km",
    lambda: reflectance_to_photoelectrons(S, scn(altitude=1000.0, ground_range=300e3)),
    names=(), main="photoelectrons", expect="check",
    check=lambda r: generic_reject(r, "photoelectrons", valid_input=True))

# --- pybsm_compat
PB_SENSOR = [
    ("int_tme", dict(int_tme=0.03), ("int_tme",)),
    ("qe_wavelengths_without_qe", dict(qe=None, qe_wavelengths=[0.4e-6, 0.5e-6]),
     ("qe_wavelengths", "qe")),
    ("qe_length_mismatch", dict(qe=[0.7, 0.7, 0.7]), ("qe", "qe_wavelengths")),
    ("band_in_micrometres", dict(opt_trans_wavelengths=[0.55, 0.85]),
     ("opt_trans_wavelengths", "wavelength_min")),
    ("band_single", dict(opt_trans_wavelengths=[0.55e-6], optics_transmission=[0.5]),
     ("opt_trans_wavelengths",)),
    ("band_decreasing", dict(opt_trans_wavelengths=[0.85e-6, 0.55e-6]),
     ("opt_trans_wavelengths",)),
    ("w_x_zero", dict(w_x=0.0), ("w_x", "detector_width_x")),
    ("w_x_nan", dict(w_x=NAN), ("w_x", "detector_width_x")),
    ("D_negative", dict(D=-0.275), ("D", "aperture_diameter")),
    ("other_noise_nan", dict(other_noise=[NAN]), ("other_noise",)),
    ("other_noise_negative", dict(other_noise=[-5.0]), ("other_noise",)),
    ("transmission_mismatch", dict(optics_transmission=[0.5, 0.5, 0.5]),
     ("optics_transmission", "opt_trans_wavelengths")),
    ("n_tdi_zero", dict(n_tdi=0), ("n_tdi", "tdi_stages")),
    ("qe_wavelengths_um", dict(qe_wavelengths=[0.55, 0.85]), ("qe_wavelengths", "qe")),
    ("missing_D", dict(D=None), ("D",)),
    ("p_y_string", dict(p_y="8e-6 m"), ("p_y", "pixel_pitch_y")),
]
for cid, over, names in PB_SENSOR:
    def pb_call(over=over):
        kw = {**PYBSM_SENSOR, **over}
        kw = {k: v for k, v in kw.items() if not (v is None and k in ("qe", "D"))}
        return xbsm.niirs(xbsm.pybsm_compat.sensor(**kw), SC, method="pybsm")
    add(f"pybsm_compat.sensor.{cid}", "pybsm_compat.sensor",
        f"pybsm_compat.sensor(**olson, {over}) -> niirs(method='pybsm')", pb_call, names=names)
add("pybsm_compat.sensor.float32_D", "pybsm_compat.sensor", "D=np.float32(0.275)",
    lambda: xbsm.niirs(xbsm.pybsm_compat.sensor(**{**PYBSM_SENSOR, "D": np.float32(0.275)}), SC),
    names=(), expect="same",
    ref=lambda: xbsm.niirs(xbsm.pybsm_compat.sensor(**{**PYBSM_SENSOR, "D": F32}), SC))
add("pybsm_compat.sensor.int_n_tdi", "pybsm_compat.sensor", "n_tdi=2 (int)",
    lambda: xbsm.niirs(xbsm.pybsm_compat.sensor(**{**PYBSM_SENSOR, "n_tdi": 2}), SC),
    names=(), expect="same",
    ref=lambda: xbsm.niirs(xbsm.pybsm_compat.sensor(**{**PYBSM_SENSOR, "n_tdi": 2.0}), SC))

PB_SCENARIO = [
    ("ihaze_3", dict(ihaze=3), ("ihaze",)),
    ("ihaze_string", dict(ihaze="1"), ("ihaze",)),
    ("ihaze_sweep_bad", dict(ihaze=xr.DataArray([1, 3], dims="case")), ("ihaze",)),
    ("ihaze_nan", dict(ihaze=NAN), ("ihaze",)),
    ("aircraft_sped", dict(aircraft_sped=100.0), ("aircraft_sped",)),
    ("missing_altitude", dict(altitude=None), ("altitude",)),
    ("ground_range_negative", dict(ground_range=-1.0), ("ground_range",)),
    ("ha_wind_speed_negative", dict(ha_wind_speed=-1.0), ("ha_wind_speed",
                                                          "high_altitude_wind_speed")),
    ("altitude_km", dict(altitude=9.0), ("altitude",)),
]
for cid, over, names in PB_SCENARIO:
    def pbs_call(over=over):
        kw = {**PYBSM_SCENARIO, **over}
        kw = {k: v for k, v in kw.items() if v is not None}
        return xbsm.niirs(S, xbsm.pybsm_compat.scenario(**kw), method="pybsm")
    add(f"pybsm_compat.scenario.{cid}", "pybsm_compat.scenario",
        f"pybsm_compat.scenario(ihaze=1, altitude=9000, ..., {over}) -> niirs", pbs_call,
        names=names,
        expect="check" if cid == "altitude_km" else "reject",
        check=plausible if cid == "altitude_km" else None,
        oracle="9 m altitude is valid (the user meant km): finite or flagged, never unflagged NaN"
        if cid == "altitude_km" else "")
add("pybsm_compat.scenario.ihaze_float", "pybsm_compat.scenario", "ihaze=1.0 (float)",
    lambda: xbsm.niirs(S, xbsm.pybsm_compat.scenario(**{**PYBSM_SCENARIO, "ihaze": 1.0})),
    names=(), expect="same",
    ref=lambda: xbsm.niirs(S, xbsm.pybsm_compat.scenario(**PYBSM_SCENARIO)))
add("pybsm_compat.scenario.interp_string", "pybsm_compat.scenario", "interp='yes' (ignored knob)",
    lambda: xbsm.niirs(S, xbsm.pybsm_compat.scenario(**{**PYBSM_SCENARIO, "interp": "yes"})),
    names=(), expect="same",
    ref=lambda: xbsm.niirs(S, xbsm.pybsm_compat.scenario(**PYBSM_SCENARIO)),
    oracle="interp is documented as ignored: result must equal the default")

# --- atmosphere_at / open_atmosphere
ATM_BAD = [
    ("altitude_negative", dict(altitude=-1.0), ("altitude",)),
    ("altitude_nan", dict(altitude=NAN), ("altitude",)),
    ("altitude_inf", dict(altitude=INF), ("altitude",)),
    ("ground_range_far", dict(ground_range=400e3), ("ground_range",)),
    ("ground_range_nan", dict(ground_range=NAN), ("ground_range",)),
    ("visibility_50", dict(visibility=50.0), ("visibility",)),
    ("visibility_nan", dict(visibility=NAN), ("visibility",)),
    ("interpolation_cubic", dict(interpolation="cubic"), ("interpolation",)),
    ("exact_off_node", dict(interpolation="exact", ground_range=20500.0), ("ground_range",)),
    ("bounds_outside", dict(wavelength_bounds=(20e-6, 30e-6)), ("wavelength_bounds",)),
    ("bounds_reversed", dict(wavelength_bounds=(1e-6, 0.5e-6)), ("wavelength_bounds",)),
    ("bounds_nan", dict(wavelength_bounds=(NAN, NAN)), ("wavelength_bounds",)),
    ("bounds_um", dict(wavelength_bounds=(0.55, 0.85)), ("wavelength_bounds",)),
    ("altitude_none", dict(altitude=None), ("altitude",)),
    ("altitude_dim_wavelength", dict(altitude=xr.DataArray([9e3, 1e4], dims="wavelength")),
     ("altitude", "wavelength")),
    ("altitude_complex", dict(altitude=9000.0 + 1j), ("altitude",)),
    ("altitude_string_da", dict(altitude=xr.DataArray(["9000"], dims="case")), ("altitude",)),
]


def atm(**kw):
    args = dict(altitude=9000.0, ground_range=20e3, visibility=23.0)
    args.update(kw)
    return xbsm.atmosphere_at(args.pop("altitude"), args.pop("ground_range"),
                              args.pop("visibility"), **args)


for cid, kw, names in ATM_BAD:
    add(f"atmosphere_at.{cid}", "atmosphere_at", f"atmosphere_at({kw})",
        lambda kw=kw: atm(**kw), names=names, main="transmission")
add("atmosphere_at.beyond_horizon", "atmosphere_at", "altitude 1000 m, ground_range 300 km",
    lambda: atm(altitude=1000.0, ground_range=300e3), names=(), main="transmission",
    expect="check", check=lambda r: generic_reject(r, "transmission", valid_input=True),
    oracle="NaN spectra must carry beyond_database")
add("atmosphere_at.float32", "atmosphere_at", "ground_range float32 DataArray [12345.6]",
    lambda: atm(ground_range=da([12345.6], dtype=np.float32)), names=(), main="transmission",
    expect="same", ref=lambda: atm(ground_range=da(np.float32([12345.6]).astype(float))))
add("atmosphere_at.units_km", "atmosphere_at", "ground_range [20.] with attrs units='km'",
    lambda: atm(ground_range=da([20.0], units="km")), names=("ground_range",),
    main="transmission", expect="same", ref=lambda: atm(ground_range=da([20e3])))
add("atmosphere_at.empty", "atmosphere_at", "ground_range empty DataArray on dim case",
    lambda: atm(ground_range=da([])), names=("ground_range",), main="transmission",
    expect="check", check=lambda r: dim_check(r, "transmission", "case", 0))
add("atmosphere_at.dim_component", "atmosphere_at", "ground_range on dim 'component'",
    lambda: atm(ground_range=xr.DataArray([1e4, 2e4], dims="component")),
    names=("ground_range", "component"), main="transmission")
add("open_atmosphere.missing_file", "open_atmosphere", "open_atmosphere('no_such_file.nc')",
    lambda: xbsm.open_atmosphere("no_such_file.nc"), names=("no_such_file.nc",),
    main="transmission", oracle="a clear error naming the file", needs_range=False)
add("open_atmosphere.not_netcdf", "open_atmosphere", "open_atmosphere(<the README.md file>)",
    lambda: xbsm.open_atmosphere(str(ROOT / "README.md")), names=("README.md",),
    main="transmission", oracle="a clear error naming the file", needs_range=False)
add("open_atmosphere.chunks_bogus", "open_atmosphere", "open_atmosphere(chunks='bogus')",
    lambda: xbsm.open_atmosphere(chunks="bogus"), names=("chunks",), main="transmission",
    oracle="a clear error naming chunks")

# --- metrics.ground_resolved_distance
GRD = "metrics.ground_resolved_distance"


def grd(snr, method="pybsm", ifov=IFOV, slant=21e3, otf=None):
    return xbsm.metrics.ground_resolved_distance(otf if otf is not None else otf_slice(), snr,
                                                 ifov, slant, method=method)


def nothing_resolved(result):
    """GRD at SNR <= 3: inf / NaN, or pyBSM's finite number carrying grd_unresolved."""
    value = np.asarray(result, dtype=float)
    flags = result.coords.get("grd_flags") if isinstance(result, xr.DataArray) else None
    flagged = flags is not None and bool(np.all(
        (np.asarray(flags) & FLAGS["grd_unresolved"][0]) != 0))
    if flagged:
        return "flagged", f"GRD {value.ravel()[:1]} m with grd_unresolved"
    if np.all(np.isnan(value) | np.isinf(value)):
        return "sensible", f"GRD {value.ravel()[:1]} (nothing resolved)"
    return "silent_wrong", f"finite GRD {value.ravel()[:1]} m though nothing can be resolved"


GRD_NOTHING = [("snr0_pybsm", 0.0, "pybsm"), ("snr0_first", 0.0, "first_crossing"),
               ("snr_negative_pybsm", -1.0, "pybsm"), ("snr_tiny_pybsm", 1e-12, "pybsm"),
               ("snr_2_pybsm", 2.0, "pybsm"), ("snr_nan_pybsm", NAN, "pybsm"),
               ("snr_2_first", 2.0, "first_crossing")]
for cid, snr_value, method in GRD_NOTHING:
    add(f"grd.{cid}", GRD, f"ground_resolved_distance(otf, snr={snr_value}, method={method!r})",
        lambda s=snr_value, m=method: grd(s, m), names=("snr",), expect="check",
        check=nothing_resolved, main="grd",
        oracle="SNR <= 3: MTF never reaches 3/SNR > 1, nothing is resolved: GRD must be "
        "inf/NaN or carry grd_unresolved")
add("grd.method_bogus", GRD, "method='PYBSM'", lambda: grd(10.0, "PYBSM"), names=("method",),
    main="grd")
add("grd.slant_negative", GRD, "slant_range=-21e3", lambda: grd(10.0, slant=-21e3),
    names=("slant_range",), main="grd")
add("grd.ifov_negative", GRD, "ifov=-2e-6", lambda: grd(10.0, ifov=-IFOV),
    names=("ifov",), main="grd")
add("grd.no_frequency_dim", GRD, "otf_slice on dim 'f' (no 'frequency')",
    lambda: grd(10.0, otf=otf_slice().rename(frequency="f")), names=("otf_slice", "frequency"),
    main="grd")
add("grd.decreasing_frequency", GRD, "otf_slice with decreasing frequency (first_crossing)",
    lambda: grd(10.0, "first_crossing", otf=otf_slice().isel(frequency=slice(None, None, -1))),
    names=("otf_slice", "frequency"), main="grd", expect="same",
    ref=lambda: grd(10.0, "first_crossing"),
    oracle="GRD must equal the increasing-frequency result (or a clear error)")

# --- issue 20: image simulation, measurement, spectral curves and geometry
SIM_IMAGE = np.add.outer(np.arange(48.0), np.arange(48.0))
SIM_IMAGE[16:32, 16:32] = 200.0
SIM_GSD = 0.011  # reference GSD: about 4 reference pixels per camera pixel [m]


def simulated(image=SIM_IMAGE, **kw):
    return xbsm.simulate_image(image, S, SC, gsd=SIM_GSD, noise=False, **kw)


def stacked(dim):
    return xr.DataArray(np.stack([SIM_IMAGE, SIM_IMAGE]), dims=(dim, "y", "x"))


def rgba():
    rgb = np.stack([SIM_IMAGE, 0.5 * SIM_IMAGE, 0.25 * SIM_IMAGE], axis=-1)
    return np.concatenate([rgb, np.full(SIM_IMAGE.shape + (1,), 255.0)], axis=-1)


def rgba_check(result):
    """Alpha dropped: three bands, the RGB image's own reflectance, recorded in the attrs."""
    rgb = simulated(rgba()[..., :3])
    if result.sizes.get("band") != 3 or result.attrs.get("alpha") != "dropped":
        return "silent_wrong", f"bands {result.sizes.get('band')}, attrs alpha " \
            f"{result.attrs.get('alpha')!r}: alpha simulated as a colour band"
    shift = float(np.abs(result["reflectance"] - rgb["reflectance"]).max())
    if shift:
        return "silent_wrong", f"RGB reflectance moved by {shift:.3g} by the alpha channel"
    return "sensible", "alpha dropped (attrs alpha='dropped'), RGB as without it"


def slanted_edge(clip=None):
    """A 64 x 64 edge tilted 5 degrees, Gaussian blur 1.5 px, values 0 to 1."""
    y, x = np.indices((64, 64), dtype=float)
    d = (x - 31.5 - np.tan(np.radians(5.0)) * (y - 31.5)) * np.cos(np.radians(5.0))
    edge = 0.5 * (1.0 + np.vectorize(math.erf)(d / (1.5 * math.sqrt(2.0))))
    return edge if clip is None else np.clip(edge, *clip)


def measure_flag_check(name):
    def check(result):
        if bool(np.all(result["flags"] & xbsm.measure.flag(name))):
            return "flagged", f"flag {name}"
        return "silent_wrong", f"no {name} flag: the result is taken as valid"
    return check


def value_check(expected, what):
    def check(result):
        values = np.asarray([float(r) for r in result])
        same = np.all((values == expected) | (np.isnan(values) & np.isnan(expected)))
        return (("sensible", what) if same else
                ("silent_wrong", f"got {values.tolist()}; expected {expected} ({what})"))
    return check


for cid, kw, names in [
    ("reflectance_range_none", dict(reflectance_range=None), ("reflectance_range",)),
    ("reflectance_range_one_value", dict(reflectance_range=(0.5,)), ("reflectance_range",)),
    ("reflectance_range_three_values", dict(reflectance_range=(0.1, 0.5, 0.9)),
     ("reflectance_range",)),
]:
    add(f"simulate_image.{cid}", "simulate_image", f"simulate_image(..., {kw})",
        lambda kw=kw: simulated(**kw), names=names, main="counts")
for cid, image, names in [
    ("empty_image", np.zeros((0, 0)), ("image",)),
    ("image_without_columns", np.zeros((48, 0)), ("image",)),
    ("stack_dim_x_input", stacked("x_input"), ("image", "x_input")),
    ("stack_dim_psf_y", stacked("psf_y"), ("image", "psf_y")),
    ("stack_dim_counts", stacked("counts"), ("image", "counts")),
]:
    add(f"simulate_image.{cid}", "simulate_image", f"simulate_image({cid.replace('_', ' ')})",
        lambda image=image: simulated(image), names=names, main="counts")
add("simulate_image.rgba", "simulate_image", "RGBA numpy image (alpha 255 everywhere)",
    lambda: simulated(rgba()), main="counts", expect="check", check=rgba_check,
    oracle="alpha is not a colour: dropped (recorded), RGB reflectance as without it")

add("measure.slanted_edge_mtf.clipped", "measure.slanted_edge_mtf",
    "edge clipped at 20 % and 80 % of its step", lambda: xbsm.measure.slanted_edge_mtf(
        slanted_edge((0.2, 0.8))), main="mtf", expect="check",
    check=measure_flag_check("edge_clipped"),
    oracle="clipping raises the MTF (0.13 at Nyquist for a true 1e-5): flag edge_clipped")
add("measure.slanted_edge_mtf.saturated_uint8", "measure.slanted_edge_mtf",
    "8-bit edge saturated at 255", lambda: xbsm.measure.slanted_edge_mtf(
        np.clip(np.round(400.0 * slanted_edge() - 100.0), 0, 255).astype(np.uint8)),
    main="mtf", expect="check", check=measure_flag_check("edge_clipped"),
    oracle="saturation is clipping: flag edge_clipped")
add("measure.slanted_edge_mtf.strided_roi", "measure.slanted_edge_mtf",
    "roi=(slice(None), slice(None, None, 2))", lambda: xbsm.measure.slanted_edge_mtf(
        slanted_edge(), roi=(slice(None), slice(None, None, 2))), names=("roi",), main="mtf")
add("measure.slanted_edge_mtf.strided_view", "measure.slanted_edge_mtf",
    "DataArray with pixel coordinates sliced [::2]", lambda: xbsm.measure.slanted_edge_mtf(
        xr.DataArray(slanted_edge(), dims=("y", "x"),
                     coords={"y": np.arange(64), "x": np.arange(64)})[::2]),
    names=("image",), main="mtf")
add("measure.flat_noise.edge_in_region", "measure.flat_noise",
    "an edge inside the region, 1 % noise", lambda: xbsm.measure.flat_noise(
        slanted_edge() + np.random.default_rng(0).normal(0.0, 0.01, (64, 64))),
    main="noise", expect="check", check=measure_flag_check("region_not_flat"),
    oracle="the edge is not noise: flag region_not_flat")
add("measure.flat_noise.strided_region", "measure.flat_noise",
    "region=(slice(0, 40, 2), slice(0, 20))", lambda: xbsm.measure.flat_noise(
        slanted_edge(), region=(slice(0, 40, 2), slice(0, 20))), names=("region",),
    main="noise")

add("radiometry.resample_spectral.empty_curve", "radiometry.resample_spectral",
    "quantum_efficiency curve without samples", lambda: xbsm.radiometry.resample_spectral(
        xr.DataArray(np.array([]), dims="quantum_efficiency_wavelength",
                     coords={"quantum_efficiency_wavelength": np.array([])}),
        xr.DataArray([0.6e-6], dims="wavelength"), "quantum_efficiency"),
    names=("quantum_efficiency",), main="quantum_efficiency")

add("geometry.zero_slant_range_equal_heights", "geometry",
    "nadir_angle and altitude_along_path at slant range 0, sensor and target at 9 km",
    lambda: (xbsm.geometry.nadir_angle(0.0, 9000.0, 9000.0),
             xbsm.geometry.altitude_along_path(0.0, 0.0, 9000.0, 9000.0)),
    main="nadir_angle", expect="check",
    check=value_check(np.array([math.pi / 2, 9000.0]), "the limits pi/2 and the height"),
    oracle="coincident points: the limits as the path shrinks (documented)")
add("geometry.zero_slant_range_below_sensor", "geometry",
    "nadir_angle and altitude_along_path at slant range 0, sensor at 9 km, target at 0",
    lambda: (xbsm.geometry.nadir_angle(0.0, 9000.0),
             xbsm.geometry.altitude_along_path(0.0, 0.0, 9000.0)),
    main="nadir_angle", expect="check",
    check=value_check(np.array([NAN, NAN]), "NaN: no such line of sight (documented)"),
    oracle="no triangle (slant range below the height difference): NaN, documented")

# --- command line (run as a subprocess; {tmp} is a fresh temporary folder)
CLI = [
    ("no_args", [], ("command",), "reject"),
    ("unknown_command", ["frobnicate"], ("frobnicate", "command"), "reject"),
    ("bad_method", ["olson", "--method", "fastest"], ("--method", "fastest"), "reject"),
    ("method_upper", ["olson", "--method", "PYBSM"], ("--method", "PYBSM"), "reject"),
    ("missing_method_value", ["olson", "--method"], ("--method",), "reject"),
    ("unknown_flag", ["olson", "--bogus"], ("--bogus",), "reject"),
    ("extra_positional", ["olson", "--out", "{tmp}/o", "extra"], ("extra",), "reject"),
    ("out_is_file", ["olson", "--out", "{tmp}/file.txt"], ("--out", "file.txt"), "reject"),
    ("empty_method", ["olson", "--method", ""], ("--method",), "reject"),
    ("missing_out_value", ["olson", "--out"], ("--out",), "reject"),
]


def cli_case(cid, argv, names, expect, needs_range=True):
    add(f"cli.{cid}", "cli", "python -m xbsm.cli " + " ".join(argv),
        lambda: argv, names=names, expect=expect, main="cli", needs_range=needs_range,
        oracle="argparse-style usage error naming the argument and the choices" if needs_range
        else "an error (no traceback) naming the file")


for cid, argv, names, expect in CLI:
    cli_case(cid, argv, names, expect)
cli_case("run_missing_study", ["run", "{tmp}/no_such_study.toml"], ("no_such_study.toml",),
         "reject", needs_range=False)


# --- the shared bad-input table (tests/bad_input_table.py, which tests/test_bad_inputs.py
# asserts row by row): an error row is clear when its error says the row's fragment; a
# result row is flagged or sensible when the row's check passes.
sys.path.insert(0, str(ROOT / "tests"))
from bad_input_table import ERROR_ROWS, RESULT_ROWS  # noqa: E402

for row_id, call, error, fragment in ERROR_ROWS:
    add(f"table.{row_id}", "shared table", f"tests/bad_input_table.py row {row_id}", call,
        fragment=fragment, error=error, oracle=f"{error.__name__} saying {fragment!r}")


def _row_check(check, what):
    def judge(result):
        if not check(result):
            return "silent_wrong", f"fails the row's check: {what}"
        return ("flagged" if "flag" in what else "sensible"), what
    return judge


for row_id, call, check, what in RESULT_ROWS:
    add(f"table.{row_id}", "shared table", f"tests/bad_input_table.py row {row_id}", call,
        expect="check", check=_row_check(check, what), oracle=what)


# ---------------------------------------------------------------------------
# Classification

RANGE_RE = re.compile(
    r"\[[^\]]*,[^\]]*\]|\([^)]*,[^)]*\)|\{|\bmust\b|\bone of\b|choose from|\bknown\b|allowed"
    r"|\bwithin\b|\bbetween\b|\brequired\b|\bexpected\b|\bnearest\b|did you mean"
    r"|\bat (most|least)\b",
    re.IGNORECASE,
)
# the fix, stated after a colon or semicolon (the second form of a clear error; docstring)
FIX_RE = re.compile(
    r"[:;]\s*(give|name the|rename|make it with|evaluate|use|pass|drop)\b", re.IGNORECASE)
MEMORY_RE = re.compile(r"Unable to allocate|too big|maximum (possible|supported) size", re.I)
CRYPTIC_TYPES = ("MergeError", "AlignmentError")
CLEAR_TYPES = (ValueError, TypeError, FileNotFoundError)
# main variable -> (flag bits, non-finite variables) of the entry's result on valid input
BASE: dict[str, tuple[int, set]] = {}


def main_of(result, main):
    if isinstance(result, xr.Dataset):
        return result[main]
    return result


def dim_check(result, main, dim, size, also=None):
    """Oracle: ``main`` carries ``dim`` with ``size`` (and the dims in ``also``)."""
    arr = main_of(result, main)
    want = {dim: size, **(also or {})}
    for d, n in want.items():
        if arr.sizes.get(d) != n:
            return "silent_wrong", f"expected dim {d!r} of size {n}; got {dict(arr.sizes)}"
    if size and not np.all(np.isfinite(arr.values)):
        return generic_reject(result, main, valid_input=True)
    return "sensible", f"dims {dict(arr.sizes)}"


def even_check(result):
    system = result["system"]
    f = system["frequency"].values
    neg, pos = system.sel(frequency=f[0]), system.sel(frequency=-f[0])
    if np.allclose(neg, pos, rtol=RTOL, atol=1e-15, equal_nan=False):
        return "sensible", "OTF(-f) == OTF(f)"
    return "silent_wrong", (f"OTF(-f) = {neg.values.ravel()[:2]} != "
                            f"OTF(f) = {pos.values.ravel()[:2]}")


def bit_names(bits):
    return [name for name, (bit, _) in FLAGS.items() if bits & bit]


def generic_reject(result, main, valid_input=False):
    """Classify a result of (in)valid input: flagged, silent_nan or silent_wrong/sensible."""
    ds = result if isinstance(result, xr.Dataset) else main_of(result, main).to_dataset(name=main)
    base_bits, base_nonfinite = BASE.get(main, (0, set()))
    values = ds[main]
    if np.iscomplexobj(values.values):
        return "silent_wrong", f"complex {main} ({values.dtype}) returned"
    flags = ds["flags"] if "flags" in ds else None
    all_bits = 0
    if flags is not None and flags.size:
        all_bits = int(np.bitwise_or.reduce(flags.values.ravel()))
    new_bits = all_bits & ~base_bits
    bad_vars = []
    for name, var in ds.data_vars.items():
        if name == "flags" or name in base_nonfinite or not np.issubdtype(var.dtype, np.number):
            continue
        if np.iscomplexobj(var.values):
            return "silent_wrong", f"complex {name} returned"
        mask = ~np.isfinite(var)
        if bool(mask.any()):
            if flags is None:
                bad_vars.append((name, "no flags"))
                continue
            explain = (flags & (new_bits | NAN_BITS)) != 0
            try:
                m, e = xr.broadcast(mask, explain)
                unexplained = bool((m & ~e).any())
            except Exception:  # noqa: BLE001 - dims that cannot broadcast
                unexplained = not bool(explain.any())
            if unexplained:
                kind = "NaN" if bool(np.isnan(var).any()) else "inf"
                bad_vars.append((name, kind))
    if bad_vars:
        return "silent_nan", "non-finite without a flag: " + ", ".join(
            f"{n} ({k})" for n, k in bad_vars[:4])
    nonfinite_main = not bool(np.all(np.isfinite(values)))
    if new_bits:
        return "flagged", "new flag bits: " + ", ".join(bit_names(new_bits)) + (
            " (with NaN)" if nonfinite_main else "")
    if valid_input:
        return "sensible", "finite, no new flag"
    return "silent_wrong", "invalid input accepted: finite result, no new flag"


def compare(result, ref, main):
    a, b = main_of(result, main), main_of(ref, main)
    if set(a.dims) != set(b.dims) or any(a.sizes[d] != b.sizes[d] for d in b.dims):
        return "silent_wrong", f"dims {dict(a.sizes)}; expected {dict(b.sizes)}"
    a = a.transpose(*b.dims)
    if np.iscomplexobj(a.values):
        return "silent_wrong", f"complex result ({a.dtype})"
    va, vb = np.asarray(a.values, dtype=float), np.asarray(b.values, dtype=float)
    if np.allclose(va, vb, rtol=RTOL, atol=0, equal_nan=True):
        return "sensible", f"equal to the reference (dtype {a.dtype})"
    nan_a, nan_b = np.isnan(va), np.isnan(vb)
    if np.any(nan_a != nan_b):
        return "silent_wrong", (f"NaN pattern differs from the reference: {int(nan_a.sum())} NaN "
                                f"vs {int(nan_b.sum())} expected of {va.size}")
    both = ~nan_a & (vb != 0)
    rel = float(np.max(np.abs(va[both] - vb[both]) / np.abs(vb[both]))) if both.any() else INF
    return "silent_wrong", f"differs from the reference: max relative difference {rel:.3g}"


def raised_by_xbsm(exc):
    frames = traceback.extract_tb(exc.__traceback__)
    return bool(frames) and f"{os.sep}xbsm{os.sep}" in frames[-1].filename


def classify_error(case, exc):
    text = str(exc)
    message = f"{type(exc).__name__}: {text}"
    if isinstance(exc, MemoryError) or MEMORY_RE.search(text):
        return "blowup", message, "memory"
    if case.fragment is not None:  # a row of the shared table: its fragment is the oracle
        if isinstance(exc, case.error) and case.fragment in text and raised_by_xbsm(exc):
            return "clear_error", message, ""
        return "cryptic_error", message, f"does not say {case.fragment!r}"
    named = any(n and n in text for n in case.names)
    ranged = (bool(RANGE_RE.search(text)) or bool(FIX_RE.search(text))
              or not case.needs_range)
    if (isinstance(exc, CLEAR_TYPES) and type(exc).__name__ not in CRYPTIC_TYPES
            and raised_by_xbsm(exc) and named and ranged):
        return "clear_error", message, ""
    why = []
    if type(exc).__name__ in CRYPTIC_TYPES or not isinstance(exc, CLEAR_TYPES):
        why.append(type(exc).__name__)
    if not raised_by_xbsm(exc):
        frames = traceback.extract_tb(exc.__traceback__)
        where = Path(frames[-1].filename).parent.name if frames else "?"
        where = "by Python at the call" if where == Path(__file__).parent.name else f"in {where}"
        why.append(f"raised outside xbsm ({where})")
    if not named:
        why.append("names none of " + "/".join(case.names) if case.names else "no parameter")
    if not ranged:
        why.append("no allowed range or fix")
    return "cryptic_error", message, "; ".join(why)


def evaluate(case):
    """Run one case (in the child) and return (class, message, note)."""
    import dask

    dask.config.set(scheduler="synchronous")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = case.call()
        except Exception as exc:  # noqa: BLE001 - every failure is data here
            cls, message, note = classify_error(case, exc)
        else:
            if case.expect == "same":
                cls, note = compare(result, case.ref(), case.main)
            elif case.expect == "check":
                cls, note = case.check(result)
            elif isinstance(result, (xr.Dataset, xr.DataArray)):
                cls, note = generic_reject(result, case.main)
            else:
                cls = "silent_wrong"
                note = f"invalid input accepted: returned {type(result).__name__}"
            message = ""
    seen = sorted({f"{w.category.__name__}: {w.message}"[:80] for w in caught
                   if not issubclass(w.category, (DeprecationWarning, FutureWarning))})
    if seen:
        note = (note + "; " if note else "") + "warnings: " + " | ".join(seen[:2])
    return cls, message, note


def _child(case, conn):
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    try:
        conn.send(evaluate(case))
    except MemoryError:
        conn.send(("blowup", "MemoryError", "memory (outside the call)"))
    except BaseException as exc:  # noqa: BLE001 - a harness failure must not be silent
        conn.send(("harness_error", f"{type(exc).__name__}: {exc}", traceback.format_exc()[-300:]))
    conn.close()


def clean(text):
    """Strip machine-specific paths (the checkout, temporary folders) from a message."""
    text = text.replace(str(ROOT), "<repo>")
    return re.sub(re.escape(tempfile.gettempdir()) + r"/[^/'\s]+", "<tmp>", text)


def run_forked(case):
    ctx = mp.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(case, send))
    start = time.perf_counter()
    proc.start()
    send.close()
    got = recv.poll(TIMEOUT)
    if got:
        try:
            out = recv.recv()
        except EOFError:
            got = False
    proc.join(1.0 if got else 0.0)
    if proc.is_alive():
        os.kill(proc.pid, signal.SIGKILL)
        proc.join()
    elapsed = time.perf_counter() - start
    if not got:
        if elapsed >= TIMEOUT:
            return "blowup", "", f"timeout after {TIMEOUT:.0f} s", elapsed
        return "blowup", "", f"child died (exit code {proc.exitcode})", elapsed
    return (*out, elapsed)


def run_cli(case):
    argv = case.call()
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "file.txt").write_text("not a folder\n")
        argv = [a.replace("{tmp}", tmp) for a in argv]
        start = time.perf_counter()
        try:
            proc = subprocess.run(
                [sys.executable, "-m", "xbsm.cli", *argv], capture_output=True, text=True,
                timeout=TIMEOUT, cwd=tmp,
                preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS,
                                                      (MEMORY_LIMIT, MEMORY_LIMIT)))
        except subprocess.TimeoutExpired:
            return "blowup", "", f"timeout after {TIMEOUT:.0f} s", time.perf_counter() - start
        elapsed = time.perf_counter() - start
    err = proc.stderr.strip()
    last = err.splitlines()[-1] if err else ""
    if proc.returncode < 0:
        return "blowup", last, f"killed by signal {-proc.returncode}", elapsed
    if proc.returncode == 0:
        return "silent_wrong", "", "exit status 0 for bad arguments", elapsed
    if "Traceback" in err:
        return "cryptic_error", last, f"traceback, exit status {proc.returncode}", elapsed
    named = any(n in err for n in case.names)
    if case.needs_range and proc.returncode == 2 and "usage:" in err and named and (
            RANGE_RE.search(err)):
        return "clear_error", last, "", elapsed
    if not case.needs_range and named:  # a file argument: naming it is enough
        return "clear_error", last, "", elapsed
    return "cryptic_error", last, f"exit status {proc.returncode}", elapsed


# ---------------------------------------------------------------------------


def baselines():
    """Flag bits and non-finite variables of each entry's result on valid input."""
    results = {
        "niirs": xbsm.niirs(S, SC),
        "snr": xbsm.snr(S, SC),
        "system": xbsm.system_otf(S, SC),
        "photoelectrons": reflectance_to_photoelectrons(S, SC),
        "transmission": xbsm.atmosphere_at(9000.0, 20e3, 23.0),
    }
    for method in ("fast", "pybsm"):  # warm caches before forking
        xbsm.niirs(S, SC, method=method)
    for main, ds in results.items():
        bits = int(np.bitwise_or.reduce(ds["flags"].values.ravel())) if "flags" in ds else 0
        nonfinite = {n for n, v in ds.data_vars.items()
                     if np.issubdtype(v.dtype, np.number) and not bool(np.isfinite(v).all())}
        BASE[main] = (bits, nonfinite)


def source_state():
    """Which xbsm ran: its git commit, uncommitted files under xbsm/, a hash of its sources."""
    import hashlib

    package = Path(xbsm.__file__).resolve().parent
    digest = hashlib.sha256()
    for file in sorted(package.rglob("*.py")):
        digest.update(file.relative_to(package).as_posix().encode())
        digest.update(file.read_bytes())

    def git(*args):
        try:
            return subprocess.run(["git", "-C", str(package.parent), *args], capture_output=True,
                                  text=True, check=True).stdout.rstrip("\n")
        except (OSError, subprocess.CalledProcessError):
            return None

    status = git("status", "--porcelain", "--", "xbsm")
    return {
        "commit": git("rev-parse", "--short", "HEAD") or "unknown (not a git checkout)",
        "uncommitted_xbsm_files": None if status is None else [
            line[3:] for line in status.splitlines()],
        "xbsm_sources_sha256": digest.hexdigest()[:16],
    }


def summarize(rows):
    counts = Counter(r["class"] for r in rows)
    per_entry: dict[str, Counter] = defaultdict(Counter)
    for r in rows:
        per_entry[r["entry"]][r["class"]] += 1
    short = {"clear_error": "clear", "flagged": "flag", "sensible": "ok",
             "cryptic_error": "cryptic", "silent_nan": "s_nan", "silent_wrong": "s_wrong",
             "blowup": "blowup"}
    classes = [c for c in CLASSES] + sorted(set(counts) - set(CLASSES))
    print(f"\n{len(rows)} cases")
    for c in classes:
        print(f"  {c:14s} {counts.get(c, 0):4d}")
    head = f"{'entry point':36s}" + "".join(f"{short.get(c, c)[:8]:>9s}" for c in classes)
    print("\n" + head + f"{'total':>8s}")
    for entry, c in per_entry.items():
        print(f"{entry:36s}" + "".join(f"{c.get(k, 0):9d}" for k in classes)
              + f"{sum(c.values()):8d}")
    return {c: counts.get(c, 0) for c in classes}, {e: dict(c) for e, c in per_entry.items()}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help=f"JSON output (default {DEFAULT_OUT})")
    parser.add_argument("--only", default="", help="run only the cases whose id contains this")
    args = parser.parse_args(argv)
    ids = [c.id for c in CASES]
    dup = [i for i, n in Counter(ids).items() if n > 1]
    if dup:
        raise SystemExit(f"duplicate case ids: {dup}")
    cases = [c for c in CASES if args.only in c.id]
    print(f"{len(cases)} of {len(CASES)} cases; memory cap {MEMORY_LIMIT / 1024**3:.0f} GB, "
          f"timeout {TIMEOUT:.0f} s per case")
    state = source_state()
    print(f"xbsm at commit {state['commit']}; uncommitted files under xbsm/: "
          f"{state['uncommitted_xbsm_files']}; sources sha256 {state['xbsm_sources_sha256']}")
    baselines()
    rows = []
    t0 = time.perf_counter()
    for i, case in enumerate(cases, 1):
        if case.entry == "cli":
            cls, message, note, elapsed = run_cli(case)
        else:
            cls, message, note, elapsed = run_forked(case)
        rows.append({"id": case.id, "entry": case.entry, "description": case.desc,
                     "oracle": case.oracle_text(), "class": cls,
                     "message": clean(message)[:200], "note": clean(note)[:300],
                     "seconds": round(elapsed, 2)})
        print(f"[{i:3d}/{len(cases)}] {cls:13s} {elapsed:6.1f}s  {case.id}"
              + (f"  -- {note[:90]}" if note and cls not in ("clear_error", "sensible") else ""),
              flush=True)
    counts, per_entry = summarize(rows)
    after = source_state()
    changed = after["xbsm_sources_sha256"] != state["xbsm_sources_sha256"]
    if changed:
        print(f"WARNING: xbsm's sources changed during the run: {after}")
    out = {
        "description": ("bad-input sweep of xbsm's public entry points"
                        " (recipes/evidence/bad_input_sweep.py)"),
        **state,
        "sources_changed_during_run": changed,
        "commit_at_end": after["commit"],
        "xbsm_version": xbsm.__version__,
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "xarray": xr.__version__,
        "memory_limit_bytes": MEMORY_LIMIT,
        "timeout_s": TIMEOUT,
        "only": args.only or None,
        "runtime_s": round(time.perf_counter() - t0, 1),
        "counts": counts,
        "per_entry": per_entry,
        "cases": rows,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
