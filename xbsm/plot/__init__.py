"""The standard figures: NIIRS and SNR against range, the noise and MTF breakdowns.

:func:`standard_figures` (:mod:`xbsm.plot.figures`) draws the equivalents of
the paper's Figures 2-5 (LeMaster & Eismann 2017, Sec. 3) from any study
result and writes them as PNG files; it is what ``xbsm plot`` and ``xbsm run``
call.

:func:`against_range`, :func:`noise_breakdown`, :func:`mtf_breakdown` and
:func:`range_performance` (:mod:`xbsm.plot.axes`) draw one panel on a
matplotlib Axes (a new pyplot one if none is given) for use in a notebook;
:func:`probability_against_range` (:mod:`xbsm.plot.acquisition`) the probability of
detection, recognition and identification against range of
:func:`xbsm.target_acquisition`.

Validity flags are drawn, never hidden: a value outside the GIQE calibration
(:func:`xbsm.flags.is_outside_calibration`) is drawn dashed, a value that is
invalid (:func:`xbsm.flags.is_invalid`) or off the plotted scale (NIIRS
outside 0-10, SNR below 0.01) is not drawn, and a marker on the axis edge
shows where a curve leaves the scale or stops having valid values.

The modules, in data-flow order: ``_style`` (constants, units, labels,
titles), ``_layout`` (faceting and flagged lines), ``_panels`` (one scenario:
noise bars, MTF curves), ``_goal`` (range-performance answers and their
bounds), ``axes`` (the single-Axes functions) and ``figures`` (the standard
figures and their files).
"""

from ._style import (
    DPI,
    MAX_PANELS,
    MTF_COMPONENTS,
    MTF_POINT,
    MTF_RANGES,
    NIIRS_SCALE,
    NOISE_POINT,
    NOISE_TERMS,
    SNR_FLOOR,
)
from .acquisition import probability_against_range
from .axes import against_range, mtf_breakdown, noise_breakdown, range_performance
from .figures import standard_figures

__all__ = ["DPI", "MAX_PANELS", "MTF_COMPONENTS", "MTF_POINT", "MTF_RANGES", "NIIRS_SCALE",
           "NOISE_POINT", "NOISE_TERMS", "SNR_FLOOR", "against_range", "mtf_breakdown",
           "noise_breakdown", "probability_against_range", "range_performance",
           "standard_figures"]
