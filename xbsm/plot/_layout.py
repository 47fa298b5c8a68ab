"""A quantity against a swept dimension: faceting, one flagged line per value, legends.

:func:`layout_of` places every dimension of a variable (x axis, line colour,
panel column, panel row); :func:`_draw_series` draws one line with its
validity flags; :func:`plot_against` makes the whole faceted figure (Figures 2
and 3 of the paper).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ._style import COLORS, MAX_PANELS, axis_label, set_suptitle, units_of, value_label, words

# ---- faceting -------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Layout:
    """Which dimension goes where: x axis, line colour, panel column, panel row."""

    x: str
    hue: str | None
    col: str | None
    row: str | None


def layout_of(da: xr.DataArray) -> _Layout | None:
    """Place every dimension of ``da`` (size-1 ones aside); None if nothing varies.

    The x axis is ``ground_range`` (else the first dimension); the lines are
    ``visibility`` (else the longest other dimension but ``band``); the panel
    columns ``band`` (else the next); one more dimension makes panel rows.

    Raises
    ------
    ValueError
        If a dimension is left over, or a faceted one has more than :data:`MAX_PANELS` values.
    """
    dims = [dim for dim in da.dims if da.sizes[dim] > 1]
    if not dims:
        return None
    x = "ground_range" if "ground_range" in dims else dims[0]
    rest = [dim for dim in dims if dim != x]

    def take(preferred):
        dim = preferred if preferred in rest else (rest[0] if rest else None)
        if dim is not None:
            rest.remove(dim)
        return dim

    # lines: visibility, else the longest dimension other than band; panels: band first
    others = sorted((d for d in rest if d != "band"), key=lambda d: -da.sizes[d])
    hue = take("visibility" if "visibility" in rest else (others[0] if others else None))
    col, row = take("band"), take(None)
    if rest:
        raise ValueError(
            f"cannot draw {da.name}: dimension {rest[0]!r} is left over (x axis {x!r}, lines "
            f"{hue!r}, panel columns {col!r}, panel rows {row!r}); select one value first, "
            f"e.g. ds.isel({rest[0]}=0)")
    for dim in (col, row):
        if dim is not None and da.sizes[dim] > MAX_PANELS:
            raise ValueError(
                f"cannot draw {da.name}: dimension {dim!r} has {da.sizes[dim]} values, one "
                f"panel each; at most {MAX_PANELS} are allowed (select some first)")
    return _Layout(x, hue, col, row)


def _grid(layout: _Layout, sizes, height: float = 3.8):
    """A constrained-layout Figure and its (rows x columns) array of axes."""
    from matplotlib.figure import Figure

    ncols = sizes[layout.col] if layout.col else 1
    nrows = sizes[layout.row] if layout.row else 1
    fig = Figure(figsize=(1.0 + 4.6 * ncols, 1.6 + height * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True)
    return fig, axes


def _panels(layout: _Layout, sizes):
    """(row index, column index, isel selector) of every panel."""
    rows = range(sizes[layout.row]) if layout.row else [None]
    cols = range(sizes[layout.col]) if layout.col else [None]
    for i, r in enumerate(rows):
        for j, c in enumerate(cols):
            selector = {d: k for d, k in ((layout.row, r), (layout.col, c)) if d is not None}
            yield i, j, selector


# ---- one line with its flags ----------------------------------------------------------------

def run_starts(mask: np.ndarray) -> np.ndarray:
    """True at the first element of every run of True."""
    return mask & ~np.concatenate([[False], mask[:-1]])


def _draw_series(ax, x, y, invalid, outside, color, bounds) -> set:
    """One flagged curve: solid inside, dashed outside the calibration, markers where it leaves.

    Returns the set of styles used (``"inside"``, ``"outside"``, ``"below"``, ``"above"``,
    ``"invalid"``).
    """
    y = np.asarray(y, dtype=float)
    lo, hi = bounds
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(y) & ~invalid
        below, above = valid & (y < lo), valid & (y > hi)
    drawn = valid & ~below & ~above
    near = outside | np.concatenate([outside[1:], [False]]) | np.concatenate([[False],
                                                                                outside[:-1]])
    solid, dashed = drawn & ~outside, drawn & near
    ax.plot(x, np.where(solid, y, np.nan), "-", color=color, lw=1.6)
    ax.plot(x, np.where(dashed, y, np.nan), "--", color=color, lw=1.2)
    # a point with no drawn neighbour of its style makes no line segment: mark it (filled
    # inside the calibration, open outside it), else a two-point curve can draw nothing
    for style, face in ((solid, color), (dashed, "none")):
        lonely = style & ~np.concatenate([style[1:], [False]]) & ~np.concatenate(
            [[False], style[:-1]])
        ax.plot(x[lonely], y[lonely], "o", color=color, mfc=face, ms=4)
    used = {name for name, mask in (("inside", solid), ("outside", drawn & outside))
            if mask.any()}
    for name, mask, level, marker in (("below", below, lo, "v"), ("above", above, hi, "^"),
                                      ("invalid", ~valid, lo, "x")):
        starts = run_starts(mask)
        if starts.any():
            ax.plot(x[starts], np.full(starts.sum(), level), marker, color=color, ms=7,
                    clip_on=False, zorder=5)
            used.add(name)
    return used


def mark_handles(used: set, bounds, quantity: str, calibrated: bool) -> list:
    """Legend entries explaining the line styles and markers actually used."""
    from matplotlib.lines import Line2D

    texts = {
        "outside": ("--", None, "outside the GIQE calibration (extrapolated)"),
        "below": ("none", "v", f"{quantity} falls below {bounds[0]:g} from here (not drawn)"),
        "above": ("none", "^", f"{quantity} exceeds {bounds[1]:g} from here (not drawn)"),
        "invalid": ("none", "x", "no valid value from here (NaN or invalid flag; not drawn)"),
    }
    handles = [Line2D([], [], color="k", lw=1.6, label="inside the GIQE calibration")
               ] if calibrated and "inside" in used else []
    for name in ("outside", "below", "above", "invalid"):
        if name in used:
            style, marker, label = texts[name]
            handles.append(Line2D([], [], color="k", ls=style, marker=marker, lw=1.2,
                                  label=label))
    return handles


# ---- Figures 2 and 3: a quantity against range ----------------------------------------------

@dataclass(frozen=True)
class Curves:
    """A quantity to draw against its first dimension, with its flags and axis settings."""

    values: xr.DataArray
    invalid: xr.DataArray  # bool, like values
    outside: xr.DataArray  # bool, like values
    ylabel: str
    bounds: tuple
    log: bool
    calibrated: bool


def hue_colors(da: xr.DataArray, hue: str | None):
    """Line colours, and (values, label) for a colour bar when there are too many for a legend."""
    n = da.sizes[hue] if hue else 1
    if n <= len(COLORS):
        return COLORS[:n], None
    from matplotlib import colormaps

    values, label = x_values(da, hue)
    low, span = values.min(), np.ptp(values) or 1.0
    return [colormaps["viridis"]((v - low) / span) for v in values], (values, label)


def x_values(da: xr.DataArray, dim: str) -> tuple[np.ndarray, str]:
    """Values and axis label of the x dimension (a paired sweep by its first parameter)."""
    if dim not in da.coords or da[dim].dtype.kind not in "iuf":
        return np.arange(da.sizes[dim], dtype=float), words(dim)
    coord = da[dim]
    paired = [name for name in da.coords if name != dim and da[name].dims == (dim,)]
    if coord.attrs.get("long_name") == "case number" and paired:
        coord = da[paired[0]]
    factor, label = axis_label(str(coord.name), units_of(coord), coord.values)
    return np.asarray(coord.values, dtype=float) / factor, label


def plot_against(curves: Curves, layout: _Layout, title: str):
    """One figure: a panel per facet, a line per hue value, flags drawn."""
    da = curves.values
    fig, axes = _grid(layout, da.sizes)
    x, xlabel = x_values(da, layout.x)
    hues = list(range(da.sizes[layout.hue])) if layout.hue else [None]
    colors, bar = hue_colors(da, layout.hue)
    used = set()
    for i, j, selector in _panels(layout, da.sizes):
        ax = axes[i, j]
        for k, color in zip(hues, colors, strict=True):
            pick = {**selector, **({layout.hue: k} if k is not None else {})}
            used |= _draw_series(ax, x, da.isel(pick).values, curves.invalid.isel(pick).values,
                                 curves.outside.isel(pick).values, color, curves.bounds)
        ax.set_title("; ".join(value_label(da, d, k) for d, k in selector.items()),
                     fontsize="medium")
        ax.grid(True, alpha=0.3)
    _finish_axes(axes, curves, xlabel, x)
    marks = mark_handles(used, curves.bounds, curves.ylabel.split(" (")[0], curves.calibrated)
    _legend(fig, da, layout, *((hues, colors) if bar is None else ([], [])), marks)
    if bar is not None:
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        values, label = bar
        fig.colorbar(ScalarMappable(Normalize(values.min(), values.max()), "viridis"),
                     ax=axes, label=label)
    set_suptitle(fig, title)
    return fig


def _finish_axes(axes, curves: Curves, xlabel: str, x) -> None:
    """Axis labels, scales and limits shared by every panel."""
    ax = axes[0, 0]
    if curves.log:
        ax.set_yscale("log")
        with np.errstate(invalid="ignore"):
            shown = curves.values.where(~curves.invalid & (curves.values >= curves.bounds[0]))
        any_shown = bool(shown.notnull().any())
        low, top = (float(shown.min()), float(shown.max())) if any_shown else (1.0, 10.0)
        if bool(shown.isnull().any()):  # markers sit on the floor
            low = curves.bounds[0]
        ax.set_ylim(max(curves.bounds[0], 10 ** np.floor(np.log10(low))),
                    10 ** np.ceil(np.log10(max(top, 10 * curves.bounds[0]))))
    else:
        ax.set_ylim(*curves.bounds)
    if np.isfinite(x).any() and np.nanmax(x) > np.nanmin(x):
        ax.set_xlim(np.nanmin(x), np.nanmax(x))
    for row in axes:
        row[0].set_ylabel(curves.ylabel)
    for ax in axes[-1]:
        ax.set_xlabel(xlabel)


def _legend(fig, da, layout: _Layout, hues, colors, marks: list) -> None:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=c, lw=2, label=value_label(da, layout.hue, k))
               for k, c in zip(hues, colors, strict=True) if k is not None]
    handles += marks
    if handles:
        columns, width = legend_columns([h.get_label() for h in handles], fig.get_figwidth())
        for handle in handles:
            handle.set_label(textwrap.fill(handle.get_label(), width))
        fig.legend(handles=handles, loc="outside lower center", fontsize="small",
                   ncols=columns, frameon=False)


#: Characters of a "small" legend label per inch of figure width (about 8 pt type: a
#: 58-character label of the standard figures measures 3.1 in, 18.7 a inch; 16 leaves room).
_LEGEND_CHARS_PER_INCH = 16.0
#: Room a legend entry needs besides its text (the handle and the gap between columns).
_LEGEND_ENTRY_CHARS = 6


def legend_columns(labels: list, width: float) -> tuple[int, int]:
    """Legend columns (at most 3) and the characters a label may take per line in them.

    The most columns whose longest label fits ``width`` inches side by side unwrapped;
    one column, labels wrapped to the width, when even one does not fit.
    """
    line = int(width * _LEGEND_CHARS_PER_INCH)
    entry = max(len(label) for label in labels) + _LEGEND_ENTRY_CHARS
    columns = max(1, min(3, len(labels), line // entry))
    return columns, max(line // columns - _LEGEND_ENTRY_CHARS, 1)
