"""Range performance: the answer of a crossing question, its bounds and its gaps, drawn.

:func:`xbsm.study.max_range` and :func:`xbsm.study.min_parameter` answer with
one value per swept cell and ``goal_flags`` saying which values are only
bounds (the requirement is still met at the grid's edge, or an invalid model
cell ended the search) and which cells never meet it. Exact answers are drawn
as filled points on solid lines, bounds as open markers with an arrow towards
the true answer, and cells that never meet the requirement are left out and
named in the legend.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from ._layout import hue_colors
from ._style import axis_label, units_of, value_label, with_unit, words

NOTE_WIDTH = 60
"""Characters per line of the legend's note on cells that never meet the requirement."""


@dataclass(frozen=True)
class _Answer:
    """A crossing answer ready to draw: values in display units, flags, axes and texts."""

    da: xr.DataArray  # the answer over (x[, hue]), in display units
    bits: xr.DataArray  # goal_flags, like values
    x: str
    hue: str | None
    title: str
    ylabel: str
    arrow: int  # +1: the true answer lies above a bound (max_range), -1: below (min_<dim>)


@dataclass
class _Seen:
    """Which kinds of point were drawn, and where the requirement is never met."""

    exact: bool = False
    bound: bool = False
    invalid: bool = False
    never: list = field(default_factory=list)


def goal_answer(goal, x, hue) -> _Answer:
    """The answer of ``goal`` without its length-1 dimensions, checked and labelled."""
    if not isinstance(goal, xr.Dataset) or "goal_flags" not in goal:
        raise ValueError("goal must be the Dataset of xbsm.study.max_range or min_parameter "
                         f"(an answer variable and goal_flags); got {type(goal).__name__}")
    names = [name for name in goal.data_vars if name not in ("goal_flags", "flags")]
    if len(names) != 1 or not (names[0] == "max_range" or names[0].startswith("min_")):
        raise ValueError("goal must hold one answer variable, max_range or min_<dim>, besides "
                         f"goal_flags; got {names}")
    answer = goal[names[0]]
    answer = answer.squeeze([d for d in answer.dims if answer.sizes[d] == 1 and d != x])
    x, hue = _x_and_hue(list(answer.dims), x, hue)
    bits = goal["goal_flags"]
    bits = bits.squeeze([d for d in bits.dims if d not in answer.dims])
    bits = bits.broadcast_like(answer).transpose(*answer.dims)
    title, asked = _requirement(goal, answer)
    units = units_of(answer)
    if answer.name == "max_range" and units == "m":
        factor, ylabel = 1e3, f"{asked} [km]"  # ranges in km, whatever their size
    else:
        factor, ylabel = axis_label(asked, units, answer.values)
    arrow = 1 if answer.name == "max_range" else -1
    return _Answer(answer / factor, bits, x, hue, title, ylabel, arrow)


def _x_and_hue(dims: list, x, hue) -> tuple[str, str | None]:
    """The x dimension (default the first) and the hue one (default the one left, if one)."""
    x = dims[0] if x is None and dims else x
    if x not in dims:
        raise ValueError(f"x must be one of the dimensions of goal {tuple(dims)}; got {x!r}")
    rest = [d for d in dims if d != x]
    hue = rest[0] if hue is None and len(rest) == 1 else hue
    if hue is not None and hue not in rest:
        raise ValueError(f"hue must be one of the dimensions {tuple(rest)}; got {hue!r}")
    extra = [d for d in rest if d != hue]
    if extra:
        raise ValueError(f"goal has dimension {extra[0]!r} besides x={x!r} and hue={hue!r}; "
                         f"select one value first, e.g. goal.isel({extra[0]}=0)")
    return x, hue


def _requirement(goal: xr.Dataset, answer: xr.DataArray) -> tuple[str, str]:
    """Title (the question with its threshold) and y axis name of a range-performance plot."""
    name = words(str(answer.attrs.get("long_name", answer.name)))
    asked = name.replace(" meeting the requirement", "")
    giqe = goal.coords.get("giqe")
    quantity = f"NIIRS (GIQE {int(giqe)})" if giqe is not None and giqe.size == 1 else (
        "the quantity")
    threshold = str(goal.attrs.get("threshold", ""))
    try:
        title = f"{asked} with {quantity} \u2265 {float(threshold):g}"
    except ValueError:
        title = f"{asked} for each requirement" if threshold == "array" else name
    fixed = [value_label(goal, d, 0) for d in goal.dims if goal.sizes[d] == 1]
    return title[:1].upper() + title[1:] + "".join(f", {f}" for f in fixed), asked


def draw_goal_lines(ax, answer: _Answer, xs: np.ndarray, flag_bits) -> _Seen:
    """One line per hue value; returns what was drawn and where the requirement is never met."""
    seen = _Seen()
    hue = answer.hue
    hues = range(answer.da.sizes[hue]) if hue is not None else [None]
    for k, color in zip(hues, hue_colors(answer.da, hue)[0], strict=True):
        pick = {hue: k} if k is not None else {}
        y, bits = answer.da.isel(pick).values, answer.bits.isel(pick).values
        finite = np.isfinite(y)
        bound = finite & ((bits & flag_bits["bound_at_grid_edge"]) != 0)
        invalid = finite & ((bits & flag_bits["invalid_cell"]) != 0) & ~bound
        _draw_goal_line(ax, xs, y, bound, invalid, color, answer.arrow)
        seen.exact |= bool((finite & ~bound & ~invalid).any())
        seen.bound |= bool(bound.any())
        seen.invalid |= bool(invalid.any())
        missing = ((bits & flag_bits["never_meets"]) != 0) | ~finite
        if missing.any():
            where = ", ".join(_x_text(answer.da, answer.x, i)
                              for i in np.flatnonzero(missing))
            seen.never.append(f"{value_label(answer.da, hue, k)} at {where}"
                              if k is not None else where)
    return seen


def _draw_goal_line(ax, x, y, bound, invalid, color, arrow: int) -> None:
    """Exact answers solid, bounds open (circle: grid edge, square: invalid cell) with arrows."""
    loose = bound | invalid
    exact = np.isfinite(y) & ~loose
    near = loose | np.concatenate([loose[1:], [False]]) | np.concatenate([[False], loose[:-1]])
    ax.plot(x, np.where(exact, y, np.nan), "-o", color=color, lw=1.6, ms=4)
    ax.plot(x, np.where(np.isfinite(y) & near, y, np.nan), "--", color=color, lw=1.2)
    for marker, mask in (("o", bound), ("s", invalid)):
        ax.plot(x[mask], y[mask], marker, mfc="white", mec=color, mew=1.5, ms=7, zorder=5)
    for xi, yi in zip(x[loose], y[loose], strict=True):
        ax.annotate("", xy=(xi, yi), xytext=(0, 20 * arrow), textcoords="offset points",
                    arrowprops={"arrowstyle": "<|-", "color": color, "lw": 1.2,
                                "shrinkA": 0, "shrinkB": 4})


def _x_text(da: xr.DataArray, dim: str, index: int) -> str:
    """One value of the x dimension with its unit."""
    if dim not in da.coords:
        return f"#{index}"
    coord = da[dim]
    if coord.dtype.kind in "iuf":
        return with_unit(coord.values[index], units_of(coord), coord.values)
    return str(coord.values[index])


def goal_legend(ax, answer: _Answer, seen: _Seen) -> None:
    """Legend: a line per hue value, the kinds of point drawn, the cells that never meet."""
    from matplotlib.lines import Line2D

    handles = []
    if answer.hue is not None:
        colors = hue_colors(answer.da, answer.hue)[0]
        handles += [Line2D([], [], color=c, lw=2, label=value_label(answer.da,
                                                                     answer.hue, k))
                    for k, c in enumerate(colors)]
    edge = ("lower bound \u2191: still met at the longest range swept" if answer.arrow > 0
            else "upper bound \u2193: already met at the smallest value swept")
    side = "lower bound \u2191" if answer.arrow > 0 else "upper bound \u2193"
    for used, marker, face, ls, text in (
            (seen.exact, "o", None, "-", "crossing, interpolated between grid values"),
            (seen.bound, "o", "white", "none", edge),
            (seen.invalid, "s", "white", "none", f"{side}: an invalid model cell ended the "
                                                  "search")):
        if used:
            handles.append(Line2D([], [], color="k", ls=ls, marker=marker, mfc=face, mec="k",
                                  ms=6, label=text))
    if seen.never:
        note = "never meets the requirement (not drawn): " + "; ".join(seen.never)
        handles.append(Line2D([], [], ls="none", label=textwrap.fill(note, NOTE_WIDTH)))
    ax.legend(handles=handles, fontsize="small")


def finish_goal_axes(ax, answer: _Answer, xs: np.ndarray, xlabel: str) -> None:
    """Labels, title, the whole swept x range, a y axis from zero with room for the arrows."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(answer.ylabel)
    ax.set_title(answer.title, fontsize="medium")
    ys = answer.da.values
    top = np.nanmax(ys) if np.isfinite(ys).any() else 0.0
    ax.set_ylim(0.0, 1.2 * top if top > 0 else 1.0)
    pad = 0.05 * (np.ptp(xs) or 1.0)
    ax.set_xlim(xs.min() - pad, xs.max() + pad)
    coord = answer.da.coords.get(answer.x)
    if coord is None or coord.dtype.kind not in "iuf":
        ax.set_xticks(xs, [_x_text(answer.da, answer.x, i) for i in range(len(xs))])
    ax.grid(True, alpha=0.3)
