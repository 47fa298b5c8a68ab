r"""Quadrature rules over spatial frequency for the edge response integral.

The edge response (IBSM Eq. 3-63) is a frequency integral of the system OTF,

.. math::

    ER(x) = \frac{1}{2} + \frac{1}{\pi}\int_0^{f_c}
            \frac{H(f)}{f}\,\sin(2\pi f\,\theta\,x)\,df,

with :math:`\theta` the detector IFOV [rad], :math:`x` the distance from the
edge [px] and :math:`f_c` the optics cutoff :math:`D/\lambda_{min}`
[cycles/rad]. A quadrature rule here is *data*: a pair of DataArrays on a
``frequency`` dimension,

- ``nodes``: the frequencies [cycles/rad] at which the caller samples the OTF;
- ``weights``: the quadrature weights [cycles/rad] on the same ``frequency``
  coordinate, with a non-dimension coordinate ``sine_frequency`` that holds
  the abscissa used in :math:`1/f` and :math:`\sin(2\pi f\theta x)`. It equals
  ``frequency`` for every rule except ``"pybsm"``, which offsets it by 1e-6.

:func:`xbsm.metrics.edge_response` consumes the pair. Three named presets
exist (:data:`PYBSM`, :data:`ACCURATE`, :data:`FAST`); each is a frozen
:class:`EdgeQuadrature` whose knobs can be overridden one at a time with
:func:`dataclasses.replace` or as keywords of :func:`edge_quadrature`.
Measured errors of each preset are in ``docs/metrics.md``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

__all__ = [
    "ACCURATE",
    "FAST",
    "PYBSM",
    "PRESETS",
    "EdgeQuadrature",
    "aperture_breakpoints",
    "detector_breakpoints",
    "edge_quadrature",
    "gauss_legendre_rule",
    "pybsm_slice_count",
    "uniform_trapezoid_rule",
]


@dataclass(frozen=True)
class EdgeQuadrature:
    r"""Knobs of a frequency quadrature rule for the edge response.

    Attributes
    ----------
    rule : str
        ``"uniform_trapezoid"`` (pyBSM's rule) or ``"gauss_legendre"``
        (composite Gauss-Legendre).
    name : str
        Preset name, recorded in the ``weights`` attrs.
    grid_size : int
        Uniform rule only: size N of the pyBSM 2-D grid ``linspace(-1, 1, N)``
        from which the 1-D slice is taken; the slice holds
        :func:`pybsm_slice_count` (N) samples.
    frequency_offset : float
        Uniform rule only: offset added to the abscissa in ``1/f`` and
        ``sin`` (pyBSM uses 1e-6). [cycles/rad]
    nodes_per_panel : int
        Gauss-Legendre only: nodes per panel.
    panels_per_oscillation : float
        Gauss-Legendre only: panels per period of
        :math:`\sin(2\pi f\theta x_{max})` over :math:`[0, f_c]`.
    min_panels : int
        Gauss-Legendre only: lower bound on the number of uniform panels.
    max_position : float
        Largest distance from the edge the rule must resolve (3 px covers the
        edge height overshoot). [px]
    """

    rule: str = "gauss_legendre"
    name: str = "custom"
    grid_size: int = 101
    frequency_offset: float = 1e-6
    nodes_per_panel: int = 8
    panels_per_oscillation: float = 1.0
    min_panels: int = 8
    max_position: float = 3.0

    def __post_init__(self):
        if self.rule not in ("uniform_trapezoid", "gauss_legendre"):
            raise ValueError(
                f"rule must be 'uniform_trapezoid' or 'gauss_legendre', got {self.rule!r}"
            )
        if self.grid_size < 3:
            raise ValueError(f"grid_size must be >= 3, got {self.grid_size}")
        if self.nodes_per_panel < 1:
            raise ValueError(f"nodes_per_panel must be >= 1, got {self.nodes_per_panel}")
        if not self.panels_per_oscillation > 0:
            raise ValueError(
                f"panels_per_oscillation must be > 0, got {self.panels_per_oscillation}"
            )
        if self.min_panels < 1:
            raise ValueError(f"min_panels must be >= 1, got {self.min_panels}")
        if not self.max_position > 0:
            raise ValueError(f"max_position must be > 0 [px], got {self.max_position}")


PYBSM = EdgeQuadrature(rule="uniform_trapezoid", name="pybsm")
"""pyBSM 0.16.1: trapezoid on the 50 slice samples of its 101-point grid."""

ACCURATE = EdgeQuadrature(
    rule="gauss_legendre",
    name="accurate",
    nodes_per_panel=10,
    panels_per_oscillation=1.0,
    min_panels=8,
)
"""Converged composite Gauss-Legendre (error < 1e-9 on smooth OTFs)."""

FAST = EdgeQuadrature(
    rule="gauss_legendre",
    name="fast",
    nodes_per_panel=6,
    panels_per_oscillation=1.0,
    min_panels=4,
)
"""Cheap composite Gauss-Legendre; measured error bound in docs/metrics.md."""

PRESETS = {"pybsm": PYBSM, "accurate": ACCURATE, "fast": FAST}


def pybsm_slice_count(grid_size: int) -> int:
    """Count the samples in pyBSM's 1-D OTF slice of an N-point grid.

    pyBSM takes the slice radius as ``arange(0, 1, step)`` with
    ``step = u[1] - u[0]`` on ``u = linspace(-1, 1, N)``. Floating-point
    rounding makes this N // 2 for most N (50 for N = 101) but N // 2 + 1 for
    some (801 for N = 1601, 751 for N = 1501).

    Parameters
    ----------
    grid_size : int
        Points N per axis of the square frequency grid. [1]

    Returns
    -------
    int
        Samples in the slice, including f = 0. [1]
    """
    u = np.linspace(-1.0, 1.0, grid_size)
    return int(np.arange(0.0, 1.0, u[1] - u[0]).size)


def _frequency_coord(values: np.ndarray) -> dict:
    return {
        "frequency": (
            "frequency",
            np.asarray(values, dtype=float),
            {"units": "cycles/rad", "long_name": "angular spatial frequency"},
        )
    }


def _pack(nodes: np.ndarray, weights: np.ndarray, sine_frequency: np.ndarray, attrs: dict):
    coords = _frequency_coord(nodes)
    node_da = xr.DataArray(
        np.asarray(nodes, dtype=float),
        dims="frequency",
        coords=coords,
        attrs={"units": "cycles/rad", "long_name": "quadrature frequency nodes", **attrs},
    )
    w_da = xr.DataArray(
        np.asarray(weights, dtype=float),
        dims="frequency",
        coords=coords,
        attrs={"units": "cycles/rad", "long_name": "quadrature weights", **attrs},
    )
    w_da = w_da.assign_coords(
        sine_frequency=(
            "frequency",
            np.asarray(sine_frequency, dtype=float),
            {
                "units": "cycles/rad",
                "long_name": "abscissa used in 1/f and sin(2 pi f ifov x)",
            },
        )
    )
    return node_da, w_da


def uniform_trapezoid_rule(count: int, step: float, offset: float = 1e-6):
    r"""Trapezoid rule on uniform samples, with pyBSM's shifted abscissa.

    The OTF is sampled at :math:`f_k = k\,\Delta f`, :math:`k = 0..n-1`; the
    integrand's :math:`1/f` and sine use :math:`w_k = f_k + \epsilon`, and the
    weights are trapezoid weights on :math:`w` (the semantics of
    ``numpy.trapezoid(y, w)``).

    Parameters
    ----------
    count : int
        Number of samples n. [1]
    step : float
        Sample spacing :math:`\Delta f`. [cycles/rad]
    offset : float, optional
        Abscissa offset :math:`\epsilon` (pyBSM: 1e-6). [cycles/rad]

    Returns
    -------
    nodes, weights : xr.DataArray
        Nodes [cycles/rad]; weights [cycles/rad] with coordinate
        ``sine_frequency`` = :math:`w_k`.

    Notes
    -----
    .. math::

        c_0 = \tfrac{1}{2}(w_1 - w_0),\quad
        c_k = \tfrac{1}{2}(w_{k+1} - w_{k-1}),\quad
        c_{n-1} = \tfrac{1}{2}(w_{n-1} - w_{n-2})
    """
    if count < 2:
        raise ValueError(f"count must be >= 2, got {count}")
    if not step > 0:
        raise ValueError(f"step must be > 0 [cycles/rad], got {step}")
    nodes = step * np.arange(1.0 * count)
    w = nodes + offset
    d = np.diff(w)
    weights = np.zeros(count)
    weights[:-1] += d / 2.0
    weights[1:] += d / 2.0
    return _pack(
        nodes,
        weights,
        w,
        {"quadrature_rule": "uniform_trapezoid", "frequency_offset": float(offset)},
    )


def gauss_legendre_rule(edges, nodes_per_panel: int):
    r"""Composite Gauss-Legendre rule on the panels between ``edges``.

    Parameters
    ----------
    edges : array_like
        Increasing panel edges, starting at 0. [cycles/rad]
    nodes_per_panel : int
        Gauss-Legendre nodes per panel. [1]

    Returns
    -------
    nodes, weights : xr.DataArray
        Nodes (none at a panel edge, so none at f = 0) [cycles/rad] and
        weights [cycles/rad].

    Notes
    -----
    On a panel :math:`[a, b]` with Legendre nodes :math:`t_i` and weights
    :math:`v_i` on :math:`[-1, 1]`:

    .. math:: f_i = \tfrac{a+b}{2} + \tfrac{b-a}{2}t_i,\qquad
              c_i = \tfrac{b-a}{2}v_i
    """
    edges = np.asarray(edges, dtype=float)
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0):
        raise ValueError("edges must be a 1-D strictly increasing array of >= 2 values")
    t, v = np.polynomial.legendre.leggauss(int(nodes_per_panel))
    a, b = edges[:-1, None], edges[1:, None]
    nodes = ((a + b) / 2 + (b - a) / 2 * t).ravel()
    weights = ((b - a) / 2 * v).ravel()
    return _pack(
        nodes,
        weights,
        nodes,
        {"quadrature_rule": "gauss_legendre", "nodes_per_panel": int(nodes_per_panel)},
    )


def detector_breakpoints(detector_ifov, cutoff):
    r"""Zeros of a rectangular detector's sinc OTF below the cutoff.

    Parameters
    ----------
    detector_ifov : float
        Detector width over focal length, :math:`w/f`. [rad]
    cutoff : float
        Upper integration limit. [cycles/rad]

    Returns
    -------
    numpy.ndarray
        :math:`k/\theta_{det}` for k = 1, 2, ... below ``cutoff``. [cycles/rad]
    """
    step = 1.0 / float(detector_ifov)
    return step * np.arange(1, int(np.floor(float(cutoff) / step)) + 1)


def aperture_breakpoints(aperture_diameter, wavelengths, obscuration_ratio=0.0):
    r"""Frequencies where a (possibly obscured) circular aperture OTF has a kink.

    Parameters
    ----------
    aperture_diameter : float
        Entrance pupil diameter D. [m]
    wavelengths : array_like
        Wavelengths of the polychromatic OTF. [m]
    obscuration_ratio : float, optional
        Linear obscuration ratio :math:`\epsilon`. [1]

    Returns
    -------
    numpy.ndarray
        :math:`(D/\lambda)\,\{1, \epsilon, (1-\epsilon)/2, (1+\epsilon)/2\}`
        for every wavelength (the pieces of the annular-pupil autocorrelation),
        sorted and unique. [cycles/rad]
    """
    eps = float(obscuration_ratio)
    rho = [1.0] if eps <= 0 else [1.0, eps, (1 - eps) / 2, (1 + eps) / 2]
    cut = float(aperture_diameter) / np.atleast_1d(np.asarray(wavelengths, dtype=float))
    return np.unique(np.outer(cut, rho).ravel())


def _panel_edges(cutoff, n_panels, breakpoints):
    edges = np.linspace(0.0, cutoff, n_panels + 1)
    if breakpoints is not None:
        bp = np.asarray(breakpoints, dtype=float).ravel()
        bp = bp[(bp > 0) & (bp < cutoff)]
        edges = np.unique(np.concatenate([edges, bp]))
        # merge edges closer than a rounding-level gap
        keep = np.concatenate([[True], np.diff(edges) > 1e-12 * cutoff])
        edges = edges[keep]
        edges[-1] = cutoff
    return edges


def edge_quadrature(method="accurate", *, cutoff, ifov, breakpoints=None, **knobs):
    r"""Frequency nodes and weights of a named edge-response quadrature rule.

    Parameters
    ----------
    method : {"accurate", "fast", "pybsm"} or EdgeQuadrature
        Preset name or a knob object.
    cutoff : float
        Upper integration limit, normally the optics cutoff
        :math:`D/\lambda_{min}`; the OTF must vanish beyond it. [cycles/rad]
    ifov : float or array_like or xr.DataArray
        Detector IFOV (pitch / focal length); the largest value sets the
        oscillation count. [rad]
    breakpoints : array_like, optional
        Frequencies where the OTF has a kink (Gauss-Legendre rules only),
        e.g. from :func:`aperture_breakpoints` and
        :func:`detector_breakpoints`. [cycles/rad]
    **knobs
        Overrides of :class:`EdgeQuadrature` fields.

    Returns
    -------
    nodes, weights : xr.DataArray
        On dimension ``frequency``. [cycles/rad]

    Notes
    -----
    The integrand :math:`H(f)\sin(2\pi f\theta x)/f` completes
    :math:`n_{osc} = f_c\,\theta\,x_{max}` periods over :math:`[0, f_c]`
    (about 60 for Q = 0.05 at :math:`x_{max}` = 3 px). The Gauss-Legendre
    rules use :math:`\max(n_{min}, \lceil p\,n_{osc}\rceil)` uniform panels,
    split further at the breakpoints. The pyBSM rule uses
    :math:`\Delta f = 2f_c/(N-1)` (computed as pyBSM does) and
    :func:`pybsm_slice_count` samples, whatever the oscillation count.
    """
    if isinstance(method, EdgeQuadrature):
        q = method
    elif method in PRESETS:
        q = PRESETS[method]
    else:
        raise ValueError(f"method must be one of {sorted(PRESETS)} or an EdgeQuadrature")
    if knobs:
        q = dataclasses.replace(q, **knobs)
    cutoff = float(cutoff)
    if not (np.isfinite(cutoff) and cutoff > 0):
        raise ValueError(f"cutoff must be finite and > 0 [cycles/rad], got {cutoff}")
    ifov_max = float(np.nanmax(np.asarray(ifov, dtype=float)))
    if not (np.isfinite(ifov_max) and ifov_max > 0):
        raise ValueError(f"ifov must be finite and > 0 [rad], got {ifov}")

    if q.rule == "uniform_trapezoid":
        grid = np.linspace(-1.0, 1.0, q.grid_size) * cutoff
        step = grid[1] - grid[0]
        nodes, weights = uniform_trapezoid_rule(
            pybsm_slice_count(q.grid_size), step, q.frequency_offset
        )
    else:
        n_osc = cutoff * ifov_max * q.max_position
        n_panels = max(q.min_panels, math.ceil(q.panels_per_oscillation * n_osc))
        nodes, weights = gauss_legendre_rule(
            _panel_edges(cutoff, n_panels, breakpoints), q.nodes_per_panel
        )
    meta = {"quadrature_preset": q.name, "cutoff_frequency": cutoff}
    nodes.attrs.update(meta)
    weights.attrs.update(meta)
    return nodes, weights
