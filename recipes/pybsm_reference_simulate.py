"""Write tests/fixtures/pybsm_simulate.npz: pyBSM 0.16.1's noiseless image simulation.

Run from the repository root with the pyBSM environment (how to make it:
``recipes/README.md``)::

    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python recipes/pybsm_reference_simulate.py

Two synthetic scenes made by a fixed formula (:func:`scene`: a gradient, a
slanted edge, a bright square and a dark bar; 64 x 64 and a non-square 48 x 64)
go through:

- ``pybsm.simulation.simulate_image`` (the functional path: percentile mapping
  of the reference image, 1501^2 OTF grid, ``otf_to_psf``, ``correlate`` in
  mirror mode, ``zoom`` resampling) for visible, MWIR and LWIR cameras, with
  turbulence, jitter and drift, a 3 x 3 sharpening kernel, at two ranges;
- the ``ImageSimulator`` classes with ``add_noise=False`` and
  ``use_reflectance=True`` (min-max mapping to reflectance 0.05-0.95):
  ``SystemOTFSimulator`` (``pad_fftconvolve``, PIL bilinear resampling) and
  each single-mechanism simulator (jitter, circular aperture, detector,
  defocus, turbulence), each also with ``gsd=None`` (no resampling: the kernel
  at the OTF grid's own spacing ``1 / (1501 df)``, stored as ``native_angle``).

Each case stores the true image (photoelectrons on the reference grid), the
blurred and resampled image and the blur kernel pyBSM built (and, for the
classes, ``blurred_native`` and ``psf_native`` of ``gsd=None``), with its inputs
as JSON (``cases``). The noisy images depend on pyBSM's random streams and are
not stored. No random numbers; about 1 min (the 1501^2 OTFs).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from _pybsm_env import pybsm_required

with pybsm_required():
    import pybsm
    from pybsm.simulation import RefImage, Scenario, Sensor, simulate_image
    from pybsm.simulation import image_simulator as sims

OUT = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "pybsm_simulate.npz"

SHARPEN = [[0.0, -0.25, 0.0], [-0.25, 2.0, -0.25], [0.0, -0.25, 0.0]]

# pyBSM Sensor keywords (xbsm.pybsm_compat.sensor takes the same)
VISIBLE = dict(name="visible", D=0.2, f=4.0, p_x=10e-6, eta=0.3, int_time=0.004,
               opt_trans_wavelengths=[0.45e-6, 0.70e-6], qe_wavelengths=[0.45e-6, 0.70e-6],
               qe=[0.7, 0.6], read_noise=20.0, max_n=60000.0, bit_depth=12.0,
               dark_current=200.0)
MWIR = dict(name="mwir", D=0.15, f=0.6, p_x=15e-6, int_time=0.002,
            opt_trans_wavelengths=[3.0e-6, 5.0e-6], read_noise=50.0, max_n=2.0e6,
            bit_depth=14.0)
LWIR = dict(name="lwir", D=0.1, f=0.3, p_x=17e-6, int_time=0.001,
            opt_trans_wavelengths=[8.0e-6, 12.0e-6], read_noise=80.0, max_n=5.0e6,
            bit_depth=14.0)


def scene(rows: int, cols: int) -> np.ndarray:
    """The synthetic reference image: gradient, 5 degree slanted edge, square, dark bar."""
    y, x = np.mgrid[0:rows, 0:cols].astype(float)
    img = 40.0 + 1.5 * x + 0.5 * y
    angle = np.deg2rad(5.0)
    img += 90.0 * ((x - 0.55 * cols) * np.cos(angle) + (y - 0.5 * rows) * np.sin(angle) > 0)
    img[int(0.6 * rows):int(0.8 * rows), int(0.15 * cols):int(0.35 * cols)] = 230.0
    img[int(0.15 * rows):int(0.25 * rows), int(0.1 * cols):int(0.9 * cols)] *= 0.3
    return img


def flat_slant_range(scenario_kw: dict) -> float:
    return float(np.sqrt(scenario_kw["altitude"] ** 2 + scenario_kw["ground_range"] ** 2))


def reference_gsd(sensor_kw: dict, scenario_kw: dict, ratio: float) -> float:
    """Reference-image GSD: the camera's (mean pitch / f times the flat slant range) / ratio."""
    ifov = sensor_kw["p_x"] / sensor_kw["f"]
    return ifov * flat_slant_range(scenario_kw) / ratio


def build(sensor_kw: dict, scenario_kw: dict):
    kw = dict(sensor_kw)
    for key in ("opt_trans_wavelengths", "qe", "qe_wavelengths", "filter_kernel"):
        if key in kw:
            kw[key] = np.asarray(kw[key], dtype=float)
    kernel = kw.pop("filter_kernel", None)
    sensor = Sensor(**kw)
    if kernel is not None:
        sensor.filter_kernel = kernel
    return sensor, Scenario(**scenario_kw)


def functional_case(sensor_kw, scenario_kw, image, ratio):
    """pyBSM's simulate_image (noise-free outputs) and the PSF it blurs with."""
    gsd = reference_gsd(sensor_kw, scenario_kw, ratio)
    sensor, scenario = build(sensor_kw, scenario_kw)
    true_img, blur_img, _ = simulate_image(ref_img=RefImage(img=image, gsd=gsd),
                                           sensor=sensor, scenario=scenario, rng=1)
    # the same OTF and PSF through the simulator class (same grid, weights, slant range)
    sensor, scenario = build(sensor_kw, scenario_kw)
    sim = sims.SystemOTFSimulator(sensor=sensor, scenario=scenario, use_reflectance=True,
                                  reflectance_range=np.array([0.05, 0.95]))
    psf = sim._get_psf_cached(gsd=gsd)
    return gsd, true_img, blur_img, psf


def simulator_case(kind, sensor_kw, scenario_kw, image, ratio):
    """An ImageSimulator subclass without noise, reflectance mode 0.05-0.95."""
    gsd = reference_gsd(sensor_kw, scenario_kw, ratio)
    sensor, scenario = build(sensor_kw, scenario_kw)
    sim = getattr(sims, kind)(sensor=sensor, scenario=scenario, add_noise=False,
                              use_reflectance=True, reflectance_range=np.array([0.05, 0.95]))
    true_img, blur_img, _ = sim.simulate_image(image, gsd)
    psf = sim._get_psf_cached(gsd=gsd)
    _, native_img, _ = sim.simulate_image(image, None)  # gsd=None: no resampling
    native = dict(blurred_native=native_img, psf_native=sim._get_psf_cached(use_default=True),
                  native_angle=1.0 / (sim.uu.shape[0] * sim._df))
    return gsd, true_img, blur_img, psf, native


def cases() -> list[dict]:
    near = dict(name="near", ihaze=1, altitude=3000.0, ground_range=4000.0, cn2_at_1m=0.0)
    far = dict(name="far", ihaze=1, altitude=3000.0, ground_range=10000.0,
               aircraft_speed=50.0)
    ir = dict(name="ir", ihaze=2, altitude=2000.0, ground_range=3000.0, cn2_at_1m=0.0)
    low = dict(name="low", ihaze=1, altitude=500.0, ground_range=2000.0, cn2_at_1m=5e-14,
               ha_wind_speed=10.0)
    shaky = dict(VISIBLE, name="visible_shaky", s_x=1.5e-6, s_y=1.0e-6, da_x=2e-4, da_y=1e-4,
                 filter_kernel=SHARPEN)
    jittery = dict(VISIBLE, name="visible_jitter", s_x=2e-6, s_y=1e-6)
    out = [
        dict(id="visible_near", path="functional", sensor=VISIBLE, scenario=near, image="a",
             ratio=3.0),
        dict(id="visible_far_turbulence", path="functional", sensor=VISIBLE, scenario=far,
             image="a", ratio=2.5),
        dict(id="mwir", path="functional", sensor=MWIR, scenario=ir, image="a", ratio=3.0),
        dict(id="visible_sharpened_jitter_drift", path="functional", sensor=shaky,
             scenario=near, image="a", ratio=3.0),
        dict(id="lwir_turbulence_nonsquare", path="functional", sensor=LWIR, scenario=low,
             image="b", ratio=2.5),
        dict(id="system_simulator_nonsquare", path="SystemOTFSimulator", sensor=jittery,
             scenario=far, image="b", ratio=2.5),
    ]
    for kind in ("JitterSimulator", "CircularApertureSimulator", "DetectorSimulator",
                 "DefocusSimulator", "TurbulenceApertureSimulator"):
        out.append(dict(id=kind, path=kind, sensor=jittery, scenario=far, image="a", ratio=2.5))
    return out


def main() -> None:
    images = {"a": scene(64, 64), "b": scene(48, 64)}
    data: dict[str, np.ndarray] = {
        "pybsm_version": np.array(getattr(pybsm, "__version__", "0.16.1")),
        "image/a": images["a"], "image/b": images["b"],
    }
    table = cases()
    for case in table:
        args = (case["sensor"], case["scenario"], images[case["image"]], case["ratio"])
        if case["path"] == "functional":
            gsd, true_img, blur_img, psf = functional_case(*args)
        else:
            gsd, true_img, blur_img, psf, native = simulator_case(case["path"], *args)
            case["native_angle"] = native.pop("native_angle")
            data.update({f"{case['id']}/{key}": value for key, value in native.items()})
        case["gsd"] = gsd
        data[f"{case['id']}/ideal"] = true_img
        data[f"{case['id']}/blurred"] = blur_img
        data[f"{case['id']}/psf"] = psf
        print(f"{case['id']}: psf {psf.shape}, output {blur_img.shape}", flush=True)
    data["cases"] = np.array(json.dumps(table))
    np.savez_compressed(OUT, **data)
    print(f"wrote {OUT} ({OUT.stat().st_size / 1e3:.0f} kB)")


if __name__ == "__main__":
    main()
