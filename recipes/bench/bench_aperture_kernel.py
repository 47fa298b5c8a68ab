"""Benchmark: the polychromatic aperture OTF kernel against an older checkout's, in one process.

Issue 22's optics sweeps (every scenario its own optics) spent about 37 % of an
``xbsm.niirs`` call in the aperture OTF. This times, with CPU time
(``time.process_time``), the chain's aperture band kernel
(``xbsm.otf.system._aperture_band_kernel``) of this checkout against the one of
``--base`` (the ``xbsm/otf/aperture.py`` of that checkout loaded as a module of its
own, its ``circular_aperture_kernel`` followed by the einsum with the weights, as the
chain did before ``circular_aperture_band_kernel``), the two alternating repeat by
repeat (their order swapped every repeat) so that the shared machine's load falls on
both:

- kernel level, ns per (node, wavelength) value: the blocks the chain hands the kernel
  in a 2,000-scenario focal-length sweep of the Olson NIR camera (195 nodes x 5
  scenarios x 31 wavelengths, obscuration 0.4; recorded from an ``xbsm.niirs`` call),
  and fixture case117_mwir_narrow's single scenario (1,680 nodes x 61 wavelengths,
  unobscured, also at obscuration 0.4) in one call, as the chain's direct applier runs
  one scenario, and in ``_in_blocks``'s blocks, as a sweep's would be;
- whole calls, us per scenario: ``xbsm.niirs`` on 2,000-scenario focal-length,
  aperture-diameter and pixel-pitch sweeps (9 km, 20.25 km ground range, 23 km
  visibility, 100 m/s), the chain's kernel swapped between the two; every output
  variable of the two is compared bit for bit.

Medians of ``--repeats``; for the whole calls also the median of the paired ratios.

    python recipes/bench/bench_aperture_kernel.py --base /path/to/old/checkout
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parent))  # bench_single: fixture cases
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))  # pybsm_cases

import xbsm  # noqa: E402
from xbsm.examples import olson_sensor  # noqa: E402
from xbsm.otf import spectral, system  # noqa: E402

SCENARIO = dict(altitude=9000.0, ground_range=20250.0, visibility=23.0, platform_speed=100.0)
SWEEPS = {"focal_length": (2.0, 6.0), "aperture_diameter": (0.1, 0.5),
          "pixel_pitch_x": (4e-6, 16e-6)}
NEW = system._aperture_band_kernel


def base_kernel_from(checkout: Path):
    """The chain's aperture band kernel as ``checkout`` computed it (no defocus)."""
    spec = importlib.util.spec_from_file_location(
        "xbsm.otf._aperture_base", checkout / "xbsm" / "otf" / "aperture.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    last = system._last

    def kernel(radial, aperture_diameter, obscuration_ratio, defocus_opd, wl, w, *,
               defocus_otf=None):
        assert not np.any(defocus_opd)
        mono = module.circular_aperture_kernel(last(np.hypot(radial, 0.0)),
                                               last(aperture_diameter), wl,
                                               last(obscuration_ratio))
        return np.einsum("...k,...k->...", mono, w)
    return kernel


def recorded(sensor, scenario):
    """The arguments the chain hands the aperture band kernel in one ``xbsm.niirs`` call."""
    calls = []

    def spy(*args, **knobs):
        calls.append([np.array(a, copy=True) for a in args])
        return NEW(*args, **knobs)
    system._aperture_band_kernel = spy
    try:
        xbsm.niirs(sensor, scenario)
    finally:
        system._aperture_band_kernel = NEW
    return calls


def sweep_sensor(name, n=2000):
    lo, hi = SWEEPS[name]
    return olson_sensor("nir", **{name: xr.DataArray(np.linspace(lo, hi, n), dims=name)})


def alternate(run, kernels, repeats, per):
    """CPU time of ``run(kernel)`` / ``per`` for each kernel, alternating, ``repeats`` each."""
    times = {k: [] for k in kernels}
    for r in range(repeats):
        for k in (kernels if r % 2 == 0 else kernels[::-1]):
            t0 = time.process_time()
            run(k)
            times[k].append((time.process_time() - t0) / per)
    return times


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", type=Path, required=True, help="the older checkout")
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--scenarios", type=int, default=2000)
    args = parser.parse_args()
    base = base_kernel_from(args.base)
    kernels = (base, NEW)
    sc = xbsm.scenario(**SCENARIO)

    blocks = recorded(sweep_sensor("focal_length", args.scenarios), sc)[::20]
    import pybsm_cases  # noqa: PLC0415  (tests/pybsm_cases.py)
    from bench_single import fixture_case  # noqa: PLC0415
    (mwir,) = recorded(*pybsm_cases.datasets(fixture_case("case117_mwir_narrow")))
    values = sum(b[0].size * b[4].size for b in blocks)
    mwir_values = mwir[0].size * mwir[4].size

    def blocked(eta):
        args_ = [*mwir[:2], eta, *mwir[3:]]
        return lambda k: spectral._in_blocks(*args_, kernel=k, spectral=2, defocus_otf=None)
    cases = {
        "focal-sweep blocks (195, 5) x 31, eta 0.4":
            (lambda k: [k(*b, defocus_otf=None) for b in blocks], values),
        "mwir_narrow (1680,) x 61, eta 0, one call (the chain's)":
            (lambda k: k(*mwir, defocus_otf=None), mwir_values),
        "mwir_narrow (1680,) x 61, eta 0.4, one call":
            (lambda k: k(*mwir[:2], 0.4, *mwir[3:], defocus_otf=None), mwir_values),
        "mwir_narrow (1680,) x 61, eta 0, in a sweep's blocks": (blocked(mwir[2]), mwir_values),
        "mwir_narrow (1680,) x 61, eta 0.4, in a sweep's blocks": (blocked(0.4), mwir_values),
    }
    print("kernel, CPU ns per (node, wavelength) value, median: base -> this checkout")
    for name, (run, n) in cases.items():
        for k in kernels:
            run(k)  # warm-up
        t = alternate(run, kernels, args.repeats, n / 1e9)
        b, m = np.median(t[base]), np.median(t[NEW])
        print(f"  {name}: {b:.2f} -> {m:.2f} ({b / m:.2f}x)", flush=True)

    print("xbsm.niirs, CPU us per scenario, median: base -> this checkout")
    for name in SWEEPS:
        s = sweep_sensor(name, args.scenarios)
        out = {}
        for k in kernels:
            system._aperture_band_kernel = k
            out[k] = xbsm.niirs(s, sc)
        same = all(np.array_equal(out[base][v].values, out[NEW][v].values, equal_nan=True)
                   for v in out[NEW].data_vars)

        def call(k, s=s):
            system._aperture_band_kernel = k
            return xbsm.niirs(s, sc).niirs.values
        t = alternate(call, kernels, args.repeats, args.scenarios / 1e6)
        system._aperture_band_kernel = NEW
        b, m = np.median(t[base]), np.median(t[NEW])
        paired = np.median(np.array(t[base]) / np.array(t[NEW]))
        print(f"  {name}: {b:.0f} -> {m:.0f} ({b / m:.2f}x; paired {paired:.2f}x), "
              f"every output variable identical: {same}", flush=True)


if __name__ == "__main__":
    main()
