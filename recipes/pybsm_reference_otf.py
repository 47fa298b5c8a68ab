"""Write tests/fixtures/pybsm_otf.npz: pyBSM 0.16.1 OTF values on a small grid of arguments.

Run from the repository root with the pyBSM environment (how to make it:
``recipes/README.md``)::

    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python recipes/pybsm_reference_otf.py

The file is deterministic (no random numbers) and small (< 200 kB). Keys are
``<case>/<field>``; every input needed to repeat the call is stored next to
its output, so tests/otf/test_pybsm_parity.py can call xbsm with the same
arguments. pyBSM's numba kernels take only 2-D float64 ``u``, ``v``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from _pybsm_env import pybsm_required

with pybsm_required():
    import pybsm
    from pybsm.geospatial import altitude_along_slant_path
    from pybsm.otf import functional as otf

OUT = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "pybsm_otf.npz"


def grid(limit, n=15):
    """Square (v, u) grid over +/- limit, including 0; u varies along axis 1."""
    f = np.linspace(-limit, limit, n)
    u, v = np.meshgrid(f, 0.9 * f)
    return np.ascontiguousarray(u), np.ascontiguousarray(v)


def main() -> None:
    version = getattr(pybsm, "__version__", "0.16.1")
    data: dict[str, np.ndarray] = {"pybsm_version": np.array(version)}

    def put(case, **fields):
        for key, value in fields.items():
            data[f"{case}/{key}"] = np.asarray(value)

    # Circular aperture (IBSM 3-20), obscured and unobscured.
    D = 0.275
    lams = np.array([0.5e-6, 1.0e-6, 4.0e-6])
    etas = np.array([0.0, 0.2, 0.5, 0.9])
    u, v = grid(1.1 * D / lams[0], 21)
    out = np.array(
        [
            [otf.circular_aperture_OTF(u=u, v=v, lambda0=lam, D=D, eta=eta) for eta in etas]
            for lam in lams
        ]
    )
    put("aperture", u=u, v=v, wavelength=lams, aperture_diameter=D, obscuration_ratio=etas, otf=out)

    # Spectral weighting of the aperture OTF (paper Eq. 3).
    wl = np.linspace(0.5e-6, 0.66e-6, 17)
    weights = np.exp(-(((wl - 0.58e-6) / 0.05e-6) ** 2)) + 0.1
    u, v = grid(1.1 * D / wl[0])
    out = otf.weighted_by_wavelength(
        wavelengths=wl,
        weights=weights,
        my_function=lambda lam: otf.circular_aperture_OTF(u=u, v=v, lambda0=lam, D=D, eta=0.3),
    )
    put(
        "weighted_aperture",
        u=u,
        v=v,
        wavelength=wl,
        weights=weights,
        aperture_diameter=D,
        obscuration_ratio=0.3,
        otf=out,
    )

    # Detector (3-36), with aggregation, CTE (3-39), diffusion (3-40).
    f = 4.0
    u, v = grid(1.5 * f / 8e-6)
    put(
        "detector",
        u=u,
        v=v,
        w_x=8e-6,
        w_y=6e-6,
        f=f,
        otf=otf.detector_OTF(u=u, v=v, w_x=8e-6, w_y=6e-6, f=f),
    )
    aggs = np.array([1, 2, 3])
    out = np.array(
        [
            otf.detector_OTF_with_aggregation(
                u=u, v=v, w_x=8e-6, w_y=6e-6, p_x=10e-6, p_y=9e-6, f=f, n=int(n)
            )
            for n in aggs
        ]
    )
    put("aggregation", u=u, v=v, w_x=8e-6, w_y=6e-6, p_x=10e-6, p_y=9e-6, f=f, n=aggs, otf=out)
    effs = np.array([0.9999, 0.999, 0.99])
    out = np.array(
        [
            otf.cte_OTF(
                u=u, v=v, p_x=8e-6, p_y=7e-6, cte_n_x=100, cte_n_y=50, phases_n=3, cte_eff=e, f=f
            )
            for e in effs
        ]
    )
    put(
        "cte",
        u=u,
        v=v,
        p_x=8e-6,
        p_y=7e-6,
        cte_n_x=100.0,
        cte_n_y=50.0,
        phases_n=3,
        cte_eff=effs,
        f=f,
        otf=out,
    )
    alphas = np.array([1e4, 1e5, 1e6])
    out = np.array([otf.diffusion_OTF(u=u, v=v, alpha=a, ald=5e-6, al0=1e-5, f=f) for a in alphas])
    put("diffusion", u=u, v=v, alpha=alphas, ald=5e-6, al0=1e-5, f=f, otf=out)

    # Motion: drift (3-29), jitter (3-28), TDI (3-38).
    u, v = grid(1.5e6)
    put("drift", u=u, v=v, a_x=2e-6, a_y=-3e-6, otf=otf.drift_OTF(u=u, v=v, a_x=2e-6, a_y=-3e-6))
    put(
        "jitter", u=u, v=v, s_x=1e-6, s_y=0.5e-6, otf=otf.jitter_OTF(u=u, v=v, s_x=1e-6, s_y=0.5e-6)
    )
    freq = np.linspace(-1.5 * f / 8e-6, 1.5 * f / 8e-6, 41)
    betas = np.array([0.9, 1.0, 1.05, 2.0])
    out = np.array(
        [otf.tdi_OTF(u_or_v=freq, w=8e-6, n_tdi=4, phases_n=2, beta=b, f=f) for b in betas]
    )
    put("tdi", frequency=freq, w=8e-6, n_tdi=4, phases_n=2, beta=betas, f=f, otf=out)

    # Turbulence (3-3), wind-blended (3-9).
    lams = np.array([0.5e-6, 1.0e-6, 4.0e-6])
    r0s = np.array([0.05, 0.2])
    u, v = grid(D / lams[0])
    out = np.array(
        [
            [
                [otf.turbulence_OTF(u=u, v=v, lambda0=lam, D=D, r0=r0, alpha=a) for a in (0.0, 0.5)]
                for r0 in r0s
            ]
            for lam in lams
        ]
    )
    put(
        "turbulence",
        u=u,
        v=v,
        wavelength=lams,
        aperture_diameter=D,
        r0=r0s,
        alpha=np.array([0.0, 0.5]),
        otf=out,
    )
    out = np.array(
        [
            [
                otf.wind_speed_turbulence_OTF(u=u, v=v, lambda0=lam, D=D, r0=r0, t_d=0.01, vel=5.0)
                for r0 in r0s
            ]
            for lam in lams
        ]
    )
    put(
        "wind_turbulence",
        u=u,
        v=v,
        wavelength=lams,
        aperture_diameter=D,
        r0=r0s,
        t_d=0.01,
        vel=5.0,
        otf=out,
    )

    # Hufnagel-Valley, coherence diameter on the curved slant path, polychromatic turbulence.
    h = np.linspace(0.0, 25000.0, 26)
    put(
        "hufnagel_valley",
        h=h,
        v=21.0,
        cn2_at_1m=1.7e-14,
        cn2=otf.hufnagel_valley_turbulence_profile(h=h, v=21.0, cn2_at_1m=1.7e-14),
    )
    scen = np.array(
        [[9000.0, 9000.0], [9000.0, 21944.568747898647], [1000.0, 30000.0], [15000.0, 100000.0]]
    )
    r0_1um = []
    for alt, rng in scen:
        z, hp = altitude_along_slant_path(h_target=0.0, h_sensor=alt, slant_range=rng)
        cn2 = otf.hufnagel_valley_turbulence_profile(h=hp, v=21.0, cn2_at_1m=1.7e-14)
        r0_1um.append(otf.coherence_diameter(lambda0=1e-6, z_path=z, cn2=cn2))
    put(
        "coherence_diameter",
        altitude=scen[:, 0],
        slant_range=scen[:, 1],
        v=21.0,
        cn2_at_1m=1.7e-14,
        r0=np.array(r0_1um),
    )
    u, v = grid(D / wl[0])
    outs, bands = [], []
    for alt, rng in scen:
        o, r = otf.polychromatic_turbulence_OTF(
            u=u,
            v=v,
            wavelengths=wl,
            weights=weights,
            altitude=alt,
            slant_range=rng,
            D=D,
            ha_wind_speed=21.0,
            cn2_at_1m=1.7e-14,
            int_time=0.03,
            aircraft_speed=100.0,
        )
        outs.append(o)
        bands.append(r)
    put(
        "polychromatic_turbulence",
        u=u,
        v=v,
        wavelength=wl,
        weights=weights,
        altitude=scen[:, 0],
        slant_range=scen[:, 1],
        aperture_diameter=D,
        ha_wind_speed=21.0,
        cn2_at_1m=1.7e-14,
        int_time=0.03,
        aircraft_speed=100.0,
        otf=np.array(outs),
        r0_band=np.array(bands),
    )

    # Wavefront (3-31) and Shannon's form.
    lams = np.array([0.5e-6, 1.0e-6, 4.0e-6])
    pv, pv_wl = (2 * np.pi * 0.05) ** 2, 0.633e-6
    u, v = grid(D / lams[0])
    out = np.array(
        [
            otf.wavefront_OTF(u=u, v=v, lambda0=lam, pv=pv * (pv_wl / lam) ** 2, L_x=D, L_y=0.5 * D)
            for lam in lams
        ]
    )
    put(
        "wavefront",
        u=u,
        v=v,
        wavelength=lams,
        pv=pv,
        pv_wavelength=pv_wl,
        L_x=D,
        L_y=0.5 * D,
        otf=out,
    )
    u, v = grid(1.3 * D / lams[0])
    out = np.array([otf.wavefront_OTF_2(u=u, v=v, cutoff=D / lam, w_rms=0.1) for lam in lams])
    put("wavefront_2", u=u, v=v, wavelength=lams, aperture_diameter=D, w_rms=0.1, otf=out)

    # Gaussian defocus (3-25), radii (3-26, 3-27), generic Gaussian.
    u, v = grid(1e6)
    put("defocus", u=u, v=v, w_x=1e-6, w_y=2e-6, otf=otf.defocus_OTF(u=u, v=v, w_x=1e-6, w_y=2e-6))
    put(
        "gaussian",
        u=u,
        v=v,
        blur_size_x=1e-6,
        blur_size_y=2e-6,
        otf=otf.gaussian_OTF(u=u, v=v, blur_size_x=1e-6, blur_size_y=2e-6),
    )
    rr = np.array([1000.0, 5000.0, 20000.0])
    put(
        "object_defocus",
        D=D,
        R=rr,
        R0=5000.0,
        w=np.array([otf.object_domain_defocus_radii(D=D, R=r, R0=5000.0) for r in rr]),
    )
    dz = np.array([1e-5, 1e-4, 1e-3])
    put(
        "image_defocus",
        D=D,
        dz=dz,
        f=f,
        w=np.array([otf.image_domain_defocus_radii(D=D, dz=d, f=f) for d in dz]),
    )

    # Sharpening-kernel filter: pyBSM's table lookup, quirks and all.
    ifov = 2e-6
    nyq = 0.5 / ifov
    u, v = grid(2.5 * nyq, 23)
    kernels = {
        "row3": np.array([[-0.25, 1.5, -0.25]]),
        "col3": np.array([[-0.25], [1.5], [-0.25]]),
        "pair": np.array([[0.5, 0.5]]),
        "sharpen3x3": np.array([[0.0, -0.1, -0.05], [-0.2, 1.6, -0.1], [0.0, -0.1, -0.05]]),
    }
    for name, k in kernels.items():
        put(
            f"filter_{name}",
            u=u,
            v=v,
            kernel=k,
            ifov=ifov,
            otf=otf.filter_OTF(u=u, v=v, kernel=k, ifov=ifov),
        )
    hu, hv = np.array([[0.5 / (2 * ifov), 0.0]]), np.array([[0.0, 0.5 / (2 * ifov)]])
    put(
        "filter_half_nyquist",
        u=hu,
        v=hv,
        kernel=kernels["row3"],
        ifov=ifov,
        otf=otf.filter_OTF(u=hu, v=hv, kernel=kernels["row3"], ifov=ifov),
    )

    # Defocused aperture as pyBSM 0.16.1 computes it (wrong: kept to document the size).
    lam, D1, f1 = 0.5e-6, 0.1, 1.0
    ratio = np.array([[0.1, 0.2, 0.3, 0.5, 0.7]])
    w20 = 0.25 * lam
    dz = w20 * 2.0 * (1.0 + 4.0 * (f1 / D1) ** 2)
    out = otf.circular_aperture_OTF_with_defocus(
        u=ratio * D1 / lam, v=0 * ratio, wavelength=lam, D=D1, f=f1, defocus=dz
    )
    put("defocus_aperture_pybsm", ratio=ratio, wavelength=lam, D=D1, f=f1, defocus=dz, otf=out)

    OUT.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(OUT, **data)
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes, {len(data)} arrays)", file=sys.stderr)


if __name__ == "__main__":
    main()
