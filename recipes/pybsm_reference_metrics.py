"""Write pyBSM 0.16.1 reference values for tests/metrics/test_metrics.py.

Run from the repository root with the pyBSM environment (never imported by
xbsm; how to make it: ``recipes/README.md``)::

    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python recipes/pybsm_reference_metrics.py

It draws random inputs with a fixed seed, evaluates pyBSM's metric functions
on them and writes ``tests/fixtures/pybsm_metrics.npz`` (inputs and outputs)
plus ``tests/fixtures/pybsm_metrics.json`` (provenance).
"""

from __future__ import annotations

import json
import pathlib
import platform

import numpy as np
from _pybsm_env import pybsm_required

with pybsm_required():
    import pybsm
    from pybsm.metrics import functional as fm
    from pybsm.otf import functional as fo

OUT = pathlib.Path(__file__).resolve().parents[1] / "tests" / "fixtures"
SEED = 20240611


def smooth_mtf(rng, n, kind):
    """A plausible |OTF| slice of n samples from f = 0 up to just below cutoff."""
    r = np.arange(n) / n
    q = rng.uniform(0.05, 2.0)  # lambda F / p
    eps = rng.choice([0.0, 0.4])
    r_c = np.clip(r, 0, 1)
    ap = (2 / np.pi) * (np.arccos(r_c) - r_c * np.sqrt(1 - r_c**2))
    det = np.sinc(r / q)  # detector zero at f = 1/ifov, cutoff*ifov = 1/Q
    jit = np.exp(-2 * np.pi**2 * (rng.uniform(0, 0.4) / q) ** 2 * r**2)
    h = ap * det * jit * (1 - eps * r)
    if kind == "noisy":  # non-monotonic, to exercise the EHO / GRD branches
        h = h + rng.uniform(-0.15, 0.15, n) * (r > 0)
    return np.abs(h)


def main():
    rng = np.random.default_rng(SEED)
    out = {}

    # slice sample counts of pyBSM grids
    counts = {}
    for n_grid in (101, 1601):
        otf = np.ones((n_grid, n_grid))
        counts[n_grid] = int(fo.slice_otf(otf=otf, ang=0.0).size)
    out["slice_grid_sizes"] = np.array(list(counts))
    out["slice_counts"] = np.array(list(counts.values()))

    # edge_response on arbitrary slices: groups of fixed (n, df)
    for g, (n, df) in enumerate([(50, 11000.0), (2, 1.0), (801, 687.5), (50, 1883.5616438356228)]):
        m = 6 if n > 100 else 40
        slices = rng.uniform(-0.3, 1.2, (m, n))
        ifov = rng.uniform(0.2, 3.0, m) / (n * df)
        pos = rng.uniform(-3.5, 3.5, m)
        er = [
            fm.edge_response(pixel_pos=pos[i], mtf_slice=slices[i], df=df, ifov=ifov[i])
            for i in range(m)
        ]
        out[f"er{g}_slices"] = slices
        out[f"er{g}_df"] = np.array(df)
        out[f"er{g}_ifov"] = ifov
        out[f"er{g}_pos"] = pos
        out[f"er{g}_value"] = np.array(er)

    # RER, EHO, GRD on plausible and on noisy MTFs (101 grid: 50 samples)
    for kind in ("smooth", "noisy"):
        m, n = 60, 50
        cutoff = rng.uniform(1e5, 1e6)
        df = (np.linspace(-1.0, 1.0, 101) * cutoff)[1] - (np.linspace(-1.0, 1.0, 101) * cutoff)[0]
        slices = np.stack([smooth_mtf(rng, n, kind) for _ in range(m)])
        ifov = rng.uniform(0.05, 2.0, m) / cutoff
        snr = rng.uniform(1.0, 200.0, m)
        slant = rng.uniform(1e3, 1e5, m)
        out[f"{kind}_cutoff"] = np.array(cutoff)
        out[f"{kind}_df"] = np.array(df)
        out[f"{kind}_slices"] = slices
        out[f"{kind}_ifov"] = ifov
        out[f"{kind}_snr"] = snr
        out[f"{kind}_slant_range"] = slant
        out[f"{kind}_rer"] = np.array(
            [
                fm.relative_edge_response(mtf_slice=s, df=df, ifov=i)
                for s, i in zip(slices, ifov, strict=True)
            ]
        )
        out[f"{kind}_eho"] = np.array(
            [
                fm.edge_height_overshoot(mtf_slice=s, df=df, ifov=i)
                for s, i in zip(slices, ifov, strict=True)
            ]
        )
        out[f"{kind}_grd"] = np.array(
            [
                fm.ground_resolved_distance(mtf_slice=s, df=df, snr=sn, ifov=i, slant_range=sr)
                for s, i, sn, sr in zip(slices, ifov, snr, slant, strict=True)
            ]
        )

    # GIQE 3 / 4 / 5 closed forms
    m = 300
    rer = rng.uniform(0.1, 1.5, m)
    rer2 = rng.uniform(0.1, 1.5, m)
    gsd = rng.uniform(0.02, 3.0, m)
    eho = rng.uniform(0.5, 1.9, m)
    ng = rng.uniform(1.0, 20.0, m)
    snr = rng.uniform(0.5, 300.0, m)
    elev = rng.uniform(0.05, np.pi / 2, m)
    out.update(
        giqe_rer=rer,
        giqe_rer2=rer2,
        giqe_gsd=gsd,
        giqe_eho=eho,
        giqe_ng=ng,
        giqe_snr=snr,
        giqe_elev=elev,
    )
    out["giqe3"] = np.array(
        [
            fm.giqe3(rer=a, gsd=b, eho=c, ng=d, snr=e)
            for a, b, c, d, e in zip(rer, gsd, eho, ng, snr, strict=True)
        ]
    )
    g4 = [
        fm.giqe4(rer=a, gsd=b, eho=c, ng=d, snr=e, elev_angle=f)
        for a, b, c, d, e, f in zip(rer, gsd, eho, ng, snr, elev, strict=True)
    ]
    out["giqe4"] = np.array([x[0] for x in g4])
    out["giqe4_gsd_gp"] = np.array([x[1] for x in g4])
    g5 = [
        fm.giqe5(rer_1=a, rer_2=b, gsd=c, snr=d, elev_angle=e)
        for a, b, c, d, e in zip(rer, rer2, gsd, snr, elev, strict=True)
    ]
    out["giqe5"] = np.array([x[0] for x in g5])
    out["giqe5_gsd_w"] = np.array([x[1] for x in g5])
    out["giqe5_rer"] = np.array([x[2] for x in g5])

    OUT.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(OUT / "pybsm_metrics.npz", **out)
    meta = {
        "generator": "recipes/pybsm_reference_metrics.py",
        "pybsm_version": getattr(pybsm, "__version__", "0.16.1"),
        "numpy_version": np.__version__,
        "python": platform.python_version(),
        "seed": SEED,
        "slice_counts": {str(k): v for k, v in counts.items()},
        "keys": sorted(out),
    }
    (OUT / "pybsm_metrics.json").write_text(json.dumps(meta, indent=2) + "\n")
    print("wrote", OUT / "pybsm_metrics.npz", "keys:", len(out))


if __name__ == "__main__":
    main()
