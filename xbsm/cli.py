"""The ``xbsm`` command.

``xbsm olson --out DIR`` runs the paper's first worked example (Sec. 3) on
the built-in atmosphere: the Olson camera (Table 2) at 9 km over every
database ground range, both visibilities, red and near-infrared bands. It
writes one NetCDF file per band as soon as that band is done (a long run
never loses finished work) and the paper's Figures 2-5.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import xarray as xr

from . import examples, model, plot
from .flags import flag
from .methods import PRESETS

WELL_FILL = flag("well_fill_limited")  # informational, not a validity problem


def _encode_for_netcdf(ds: xr.Dataset) -> xr.Dataset:
    """Make attrs NetCDF-safe (no None, bools as ints)."""
    ds = ds.copy()
    for var in list(ds.variables.values()) + [ds]:
        for key, value in list(var.attrs.items()):
            if value is None:
                del var.attrs[key]
            elif isinstance(value, bool):
                var.attrs[key] = int(value)
    return ds


def compute_olson(method: str = "accurate") -> dict[str, xr.Dataset]:
    """NIIRS, SNR and their breakdowns of the Olson camera, by band (paper Sec. 3)."""
    results = {}
    for band in examples.OLSON_BANDS:
        ds = model.niirs(examples.olson_sensor(band), examples.olson_scenario(), method)
        ds.attrs.update(
            title=f"xbsm: NIIRS and SNR of the Olson camera, {band} band",
            source="xbsm olson (LeMaster & Eismann 2017, Sec. 3)", method=method,
            Conventions="CF-1.8",
        )
        results[band] = ds
    return results


def write_olson(results: dict[str, xr.Dataset], out: Path) -> None:
    """One NetCDF file per band in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    for band, ds in results.items():
        path = out / f"olson_{band}.nc"
        _encode_for_netcdf(ds).to_netcdf(path)
        print(f"wrote {path}")


def draw_olson(results: dict[str, xr.Dataset], out: Path, method: str = "accurate") -> None:
    """The paper's Figures 2-5 as PNG files in ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def panels(name, draw, height=4.0):
        fig, axes = plt.subplots(1, 2, figsize=(11, height), sharey=True)
        for ax, key in zip(axes, results, strict=False):
            draw(ax, key)
        fig.tight_layout()
        fig.savefig(out / name, dpi=110)

    def niirs_panel(ax, band):
        plot.against_range(results[band].niirs.sel(giqe=3), ax=ax, hue="visibility")
        ax.set_ylim(0, 10)  # the rating scale; flagged values far below it are off the chart
        ax.set_title(f"{band} band: NIIRS (GIQE 3, paper Eq. 4)")

    def snr_panel(ax, band):
        plot.against_range(results[band].snr, ax=ax, hue="visibility")
        ax.set_yscale("log")
        ax.set_ylim(1e-2, None)
        ax.set_title(f"{band} band: contrast SNR")

    def noise_panel(ax, band):
        plot.noise_breakdown(results[band].sel(ground_range=20000.0, visibility=5.0), ax=ax)
        ax.set_xlabel(f"{band} band, 20 km ground range, 5 km visibility")

    panels("figure2_niirs.png", niirs_panel)
    panels("figure3_snr.png", snr_panel)
    panels("figure4_noise.png", noise_panel, height=4.5)

    sensor = examples.olson_sensor("red")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, ground_range in zip(axes, (0.0, 100e3), strict=False):
        scenario = examples.olson_scenario(ground_range=ground_range, visibility=23.0)
        otf = model.system_otf(sensor, scenario, method=method)
        nyquist = 0.5 / float(sensor.pixel_pitch_x / sensor.focal_length)
        plot.mtf_breakdown(otf, float(sensor.focal_length), nyquist=nyquist, ax=ax)
        ax.set_title(f"red band, {ground_range / 1e3:g} km ground range, 23 km visibility")
    fig.tight_layout()
    fig.savefig(out / "figure5_mtf.png", dpi=110)
    plt.close("all")


def summarize_olson(results: dict[str, xr.Dataset]) -> None:
    """Print NIIRS and SNR at three ranges, marking values outside the GIQE calibration."""
    print("NIIRS (GIQE 3 / 4 / 5) at 9 km altitude (* outside the GIQE calibration ranges):")
    for band, ds in results.items():
        for vis in (23.0, 5.0):
            for gr in (0.0, 20e3, 100e3):
                point = ds.sel(visibility=vis, ground_range=gr)
                marks = ["*" if int(f) & ~WELL_FILL else " " for f in point.flags.values]
                print(f"  {band:3s} vis {vis:4.0f} km  range {gr / 1e3:5.0f} km: "
                      + " / ".join(f"{x:9.2f}{m}" for x, m in zip(point.niirs.values, marks,
                                                                   strict=True))
                      + f"   SNR {float(point.snr):8.2f}")


def run_olson(out: Path, method: str = "accurate") -> dict[str, xr.Dataset]:
    """Compute, write and draw the Olson example; return the per-band datasets."""
    results = compute_olson(method)
    write_olson(results, out)
    draw_olson(results, out, method)
    summarize_olson(results)
    print(f"figures in {out}")
    return results


def main(argv=None) -> int:
    """Entry point of the ``xbsm`` command."""
    parser = argparse.ArgumentParser(prog="xbsm", description="xbsm imaging-system model")
    sub = parser.add_subparsers(dest="command", required=True)
    olson = sub.add_parser("olson", help="the paper's worked example (Olson camera, Sec. 3)")
    olson.add_argument("--out", type=Path, default=Path("olson"), help="output directory")
    olson.add_argument("--method", choices=sorted(PRESETS), default="accurate")
    args = parser.parse_args(argv)
    if args.command == "olson":
        if args.out.exists() and not args.out.is_dir():
            parser.error(f"--out {args.out} exists and is not a directory")
        try:
            run_olson(args.out, args.method)
        except OSError as err:
            parser.error(f"cannot write to --out {args.out}: {err.strerror or err}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
