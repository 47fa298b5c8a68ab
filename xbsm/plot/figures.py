"""The standard figures of a study result (the paper's Figures 2-5), written as PNG files.

:func:`standard_figures` is what ``xbsm plot`` and ``xbsm run`` call. It uses
matplotlib's Agg renderer on figures of its own and never touches pyplot or
the global backend. Each file is written under a temporary name and renamed
into place when complete.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from .. import flags
from .._version import __version__
from ..interrupts import stop_if_interrupted
from ._layout import Curves, layout_of, plot_against
from ._panels import (
    frequency_axis,
    mtf_handles,
    mtf_panel,
    nearest_point,
    noise_panel,
    orientation_rows,
    select_at,
)
from ._style import (
    DPI,
    MTF_POINT,
    MTF_RANGES,
    NIIRS_SCALE,
    NOISE_POINT,
    SNR_FLOOR,
    Context,
    context_of,
    set_suptitle,
    value_label,
    with_unit,
    words,
)
from .axes import with_self_emission_split


def _bits(ds: xr.Dataset, like: xr.DataArray, names=None, group=None) -> xr.DataArray:
    """Where ``ds.flags`` has any of the bits ``names`` (or the group test), like ``like``."""
    if "flags" not in ds:
        return xr.zeros_like(like, dtype=bool)
    bits = ds["flags"]
    if "giqe" in bits.dims and "giqe" not in like.dims:
        bits = bits.reduce(np.bitwise_or.reduce, dim="giqe")
    if group is not None:
        out = group(bits)
    else:
        out = xr.zeros_like(bits, dtype=bool)
        for name in names:
            out = out | flags.has_flag(bits, name)
    single = [d for d in out.dims if d not in like.dims and out.sizes[d] == 1]
    return out.squeeze(single).broadcast_like(like).transpose(*like.dims)


def _squeeze(ds: xr.Dataset, da: xr.DataArray) -> tuple[xr.DataArray, str]:
    """``da`` without its length-1 dimensions, and their values for the title."""
    single = [d for d in da.dims if da.sizes[d] == 1]
    labels = ", ".join(value_label(ds, d, 0) for d in single)
    return da.squeeze(single), f": {labels}" if labels else ""


def _niirs_figures(ds: xr.Dataset, ctx: Context):
    """Figure 2: NIIRS against range, one figure per GIQE version."""
    if "niirs" not in ds:
        return
    versions = list(ds["giqe"].values) if "giqe" in ds["niirs"].dims else [None]
    for version in versions:
        da = ds["niirs"].sel(giqe=version) if version is not None else ds["niirs"]
        da, single = _squeeze(ds, da)
        layout = layout_of(da)
        if layout is None:
            return
        flagged = ds if version is None or "flags" not in ds else ds.sel(giqe=version)
        label = f"NIIRS (GIQE {int(version)})" if version is not None else "NIIRS"
        curves = Curves(da, _bits(flagged, da, group=flags.is_invalid),
                         _bits(flagged, da, group=flags.is_outside_calibration), label,
                         NIIRS_SCALE, log=False, calibrated=True)
        name = f"figure2_niirs_giqe{int(version)}.png" if version is not None else (
            "figure2_niirs.png")
        yield name, plot_against(curves, layout, f"{label} against {words(layout.x)}{single}\n"
                             f"{ctx.title}")


def _snr_figure(ds: xr.Dataset, ctx: Context):
    """Figure 3: contrast SNR against range (log axis)."""
    if "snr" not in ds:
        return
    da, single = _squeeze(ds, ds["snr"])
    layout = layout_of(da)
    if layout is None:
        return
    invalid = _bits(ds, da, names=("beyond_database", "snr_nonpositive"))
    curves = Curves(da, invalid, xr.zeros_like(da, dtype=bool), "contrast SNR",
                     (SNR_FLOOR, np.inf), log=True, calibrated=False)
    yield "figure3_snr.png", plot_against(curves, layout, f"contrast SNR against "
                                      f"{words(layout.x)}{single}\n{ctx.title}")



def _noise_figure(ds: xr.Dataset, ctx: Context):
    """Figure 4: the noise breakdown at 20 km ground range, 5 km visibility (or nearest)."""
    if "total_noise" not in ds:
        return
    from matplotlib.figure import Figure

    selector, described = nearest_point(ds, NOISE_POINT, keep=("band",))
    bands = list(range(ds.sizes["band"])) if "band" in ds.dims else [None]
    fig = Figure(figsize=(1.0 + 4.6 * len(bands), 5.2), layout="constrained")
    axes = fig.subplots(1, len(bands), squeeze=False, sharey=True)[0]
    for ax, band in zip(axes, bands, strict=True):
        pick = {**selector, **({"band": band} if band is not None else {})}
        point = _split_self_emission(ds.isel({d: i for d, i in pick.items() if d in ds.dims}),
                                     band)
        noise_panel(ax, point, {})
        if band is not None:
            ax.set_title(value_label(ds, "band", band), fontsize="medium")
        if ax is not axes[0]:
            ax.set_ylabel("")
    where = " at " + ", ".join(described) if described else ""
    set_suptitle(fig, f"Noise breakdown{where} (total: root sum square of the terms)\n"
                   f"{ctx.title}")
    yield "figure4_noise.png", fig



def _split_self_emission(point: xr.Dataset, band: int | None) -> xr.Dataset:
    """One scenario of a study result with its self-emission noise split by source.

    The sensor is rebuilt from the parameters the result records in its attributes
    (:mod:`xbsm.study.attributes`, those of the band at position ``band``) and the
    swept values at this scenario; without them (a result written before they
    existed) or if they no longer make a sensor, ``point`` as is.
    """
    from .. import params
    from ..study.attributes import parameters_of
    from ..study.spec import SENSOR_PARAMETERS

    values, _ = parameters_of(point, band)
    if not values or "self_emission_noise" not in point:
        return point
    values.update({name: float(point[name]) for name in SENSOR_PARAMETERS
                   if name in point.coords and point[name].ndim == 0})
    try:
        sensor = params.sensor(**values)
    except ValueError:
        return point
    return with_self_emission_split(point, sensor)


def _mtf_figure(ds: xr.Dataset, ctx: Context):
    """Figure 5: the MTF breakdown at 0 and 100 km ground range, red band, 23 km visibility."""
    if "mtf_system" not in ds:
        return
    if ctx.frequency is None or len(ctx.frequency) != ds.sizes["frequency"]:
        raise ValueError("the mtf_* variables need a frequency coordinate [cycles/rad] "
                         "(xbsm.study results carry one)")
    from matplotlib.figure import Figure

    selector, described = nearest_point(ds, {"band": "red", **MTF_POINT}, keep=("ground_range",))
    ranges = sorted({int(np.abs(ds["ground_range"].values - r).argmin()) for r in
                     MTF_RANGES}) if "ground_range" in ds.dims else [None]
    rows, ones = orientation_rows(ds), []
    fig = Figure(figsize=(1.0 + 4.8 * len(ranges), 2.0 + 3.8 * len(rows)), layout="constrained")
    axes = fig.subplots(len(rows), len(ranges), squeeze=False, sharey=True)
    for i, row in enumerate(rows):
        for j, gr in enumerate(ranges):
            pick = {**selector, **({"ground_range": gr} if gr is not None else {}),
                    **({"orientation": row} if row is not None else {})}
            axis = frequency_axis(ds, pick, np.asarray(ctx.frequency, dtype=float))
            ones += mtf_panel(axes[i, j], ds, pick, axis)
            axes[i, j].set_title(_mtf_title(ds, pick, row), fontsize="medium")
        axes[i, 0].set_ylabel("MTF")
    fig.legend(handles=mtf_handles(axes, ones), loc="outside lower center", fontsize="small",
               ncols=4, frameon=False)
    if rows == [0]:
        described.append(f"{ds['orientation'].values[0]} orientation (x and y identical)")
    set_suptitle(fig, f"MTF breakdown: {', '.join(described)}\n{ctx.title}")
    yield "figure5_mtf.png", fig


def _mtf_title(ds: xr.Dataset, pick: dict, row) -> str:
    parts = []
    if "ground_range" in pick:
        values = ds["ground_range"].values
        parts.append(with_unit(values[pick["ground_range"]], "m", values) + " ground range")
    if "effective_integration_time" in ds:
        seconds = float(select_at(ds, "effective_integration_time", pick))
        parts.append(f"integration time {with_unit(seconds, 's')}")
    if row is not None and len(orientation_rows(ds)) > 1:
        orientation = ds["orientation"].values[row] if "orientation" in ds.coords else row
        parts.append(f"{orientation} orientation")
    return ", ".join(parts)



# ---- writing ----------------------------------------------------------------------------------

def _png(fig) -> bytes:
    """``fig`` as a 256-colour PNG (a third of the RGBA size; line art looks the same)."""
    from PIL import Image, PngImagePlugin

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI)
    buffer.seek(0)
    image = Image.open(buffer).convert("RGB").quantize(256, dither=0)  # 0: no dithering
    info = PngImagePlugin.PngInfo()
    info.add_text("Software", f"xbsm {__version__}")
    out = io.BytesIO()
    image.save(out, format="png", optimize=True, pnginfo=info)
    return out.getvalue()


def _save(fig, path: Path) -> Path:
    """Write ``fig`` as PNG under a temporary name in the same directory, then rename it."""
    data = _png(fig)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    stop_if_interrupted()  # a signal deferred while matplotlib drew stops the run here
    return path


def standard_figures(ds: xr.Dataset, directory) -> list[Path]:
    """The equivalents of the paper's Figures 2-5 of a study result, as PNG files.

    Parameters
    ----------
    ds : xr.Dataset
        A loaded result of :func:`xbsm.study.run` (or the NetCDF file it wrote), of any study.
    directory : str or Path
        Where the files go; created if missing.

    Returns
    -------
    list of Path
        The files written, in this order and only where the variables exist:
        ``figure2_niirs_giqe<N>.png`` (NIIRS against ground range, or against the
        first swept dimension, one file per GIQE version), ``figure3_snr.png``,
        ``figure4_noise.png`` (at 20 km ground range and 5 km visibility, or the
        nearest) and ``figure5_mtf.png`` (at 0 and 100 km, red band, 23 km
        visibility, or the nearest; only with ``mtf_*`` variables).

    Raises
    ------
    ValueError
        If ``ds`` has none of the variables drawn, or a dimension that can be neither
        drawn nor faceted (lines per ``visibility``, panel columns per ``band``, one more
        dimension as panel rows, at most :data:`MAX_PANELS` panels per row or column).

    Notes
    -----
    Each file is written under a temporary name in ``directory`` and renamed into
    place when complete, so an interrupted call never leaves a truncated PNG; a
    signal recorded while a figure was drawn (:mod:`xbsm.interrupts`) stops the
    call after that figure.
    """
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"ds must be an xarray Dataset (a study result); got {type(ds).__name__}")
    if not any(name in ds for name in ("niirs", "snr", "total_noise", "mtf_system")):
        raise ValueError("ds has none of the variables of the standard figures (niirs, snr, "
                         "total_noise, mtf_system)")
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    ctx = context_of(ds)
    written = []
    for figures in (_niirs_figures, _snr_figure, _noise_figure, _mtf_figure):
        for name, fig in figures(ds, ctx):
            written.append(_save(fig, directory / name))
    return written
