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
  ``frequency`` for every rule except ``"pybsm"``, which offsets it by 1e-6. The
  Gauss-Kronrod rule adds ``error_weights`` (Kronrod minus embedded Gauss weights):
  the same OTF samples contracted with them give the rule's own error estimate.

The ``"accurate"`` and ``"fast"`` presets use the Gauss-Kronrod rule on panels that
follow the system OTF from sensor quantities alone (uniform panels for the sine's
oscillation, at least one per OTF lobe of a drift or a defocus, the first graded geometrically
toward f = 0 for any narrow blur; ``_kronrod_sensors``), so that every scenario of a
sweep shares one rule.

:func:`xbsm.metrics.edge_response` consumes the pair. The rules take plain
knobs; their values for the ``"pybsm"``, ``"accurate"`` and ``"fast"`` methods live
in one place, :data:`xbsm.methods.PRESETS`
(``xbsm.method(name).edge_quadrature_knobs()``). Measured errors of each preset
are in ``docs/metrics.md``.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import xarray as xr

from ._kernels import apply_kernel, apply_orchestrator
from ._metadata import Output, named, outputs

__all__ = [
    "EDGE_RULES",
    "UNRESOLVED_RER",
    "cutoff_wavelength",
    "optics_cutoff",
    "undersampled",
    "aperture_breakpoints",
    "detector_breakpoints",
    "edge_nodes",
    "edge_quadrature",
    "gauss_legendre_rule",
    "kronrod_nodes",
    "pybsm_slice_count",
    "samples_per_oscillation",
    "uniform_trapezoid_rule",
]

#: Edge-response quadrature rules: pyBSM's trapezoid on its grid slice, composite
#: Gauss-Legendre on uniform panels, or composite Gauss-Kronrod on panels that follow the
#: system OTF (graded toward f = 0, one per drift or defocus lobe) with its own error estimate.
EDGE_RULES = ("uniform_trapezoid", "gauss_legendre", "gauss_kronrod")
#: Largest distance from the edge the rules resolve: 3 px covers the edge height overshoot,
#: which looks at 1 to 3 px from the edge. [px]
MAX_POSITION = 3.0


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
    return _pack(
        *_uniform_trapezoid_kernel(count, step, offset),
        {"quadrature_rule": "uniform_trapezoid", "frequency_offset": float(offset)},
    )


def _uniform_trapezoid_kernel(count, step, offset):
    """Nodes, weights and sine abscissae of :func:`uniform_trapezoid_rule` (numpy)."""
    nodes = step * np.arange(1.0 * count)
    w = nodes + offset
    d = np.diff(w)
    weights = np.zeros(count)
    weights[:-1] += d / 2.0
    weights[1:] += d / 2.0
    return nodes, weights, w


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
    nodes, weights = _gauss_legendre_kernel(edges, nodes_per_panel)
    return _pack(
        nodes,
        weights,
        nodes,
        {"quadrature_rule": "gauss_legendre", "nodes_per_panel": int(nodes_per_panel)},
    )


@functools.lru_cache(maxsize=16)
def legendre_nodes(n):
    """Gauss-Legendre nodes and weights on [-1, 1] (read-only, cached: a few per process)."""
    t, v = np.polynomial.legendre.leggauss(n)
    for a in (t, v):
        a.flags.writeable = False
    return t, v


def _gauss_legendre_kernel(edges, nodes_per_panel):
    """Nodes and weights of :func:`gauss_legendre_rule` (numpy)."""
    t, v = legendre_nodes(int(nodes_per_panel))
    a, b = edges[:-1, None], edges[1:, None]
    return ((a + b) / 2 + (b - a) / 2 * t).ravel(), ((b - a) / 2 * v).ravel()


@functools.lru_cache(maxsize=16)
def kronrod_nodes(n):
    r"""Gauss-Kronrod rule on [-1, 1]: 2n+1 nodes, their weights, and the embedded Gauss weights.

    Parameters
    ----------
    n : int
        Gauss-Legendre nodes of the embedded rule (n = 7 gives the classical 7-15 pair). [1]

    Returns
    -------
    nodes, kronrod_weights, gauss_weights : numpy.ndarray
        Increasing nodes; the Kronrod weights (exact for polynomials of degree 3n + 1 for
        odd n, 3n + 2 for even n); the n-point Gauss-Legendre weights on the same nodes
        (zero at the n + 1 Kronrod-only nodes). Read-only.

    Notes
    -----
    The Kronrod-only nodes are the roots of the Stieltjes polynomial
    :math:`E_{n+1}`, orthogonal to :math:`P_n(x)\,x^k` for k = 0..n (Kronrod 1965);
    its coefficients in the Legendre basis solve that linear system (moments by a
    Gauss-Legendre rule exact to the degree involved), the weights solve the
    Legendre moment equations on all 2n + 1 nodes.
    """
    from numpy.polynomial import legendre as leg

    n = int(n)
    xq, wq = np.polynomial.legendre.leggauss(3 * n + 2)
    basis = np.array([leg.legval(xq, np.eye(n + 2)[j]) for j in range(n + 2)])
    moments = basis[n] * wq * basis[: n + 1]  # P_n P_k at the nodes, weighted
    a = moments @ basis[: n + 1].T
    b = -moments @ basis[n + 1]
    coef = np.concatenate([np.linalg.lstsq(a, b, rcond=None)[0], [1.0]])
    extra = np.sort(leg.legroots(coef).real)
    gx, gw = legendre_nodes(n)
    nodes = np.sort(np.concatenate([gx, extra]))
    vander = np.array([leg.legval(nodes, np.eye(2 * n + 1)[k]) for k in range(2 * n + 1)])
    rhs = np.zeros(2 * n + 1)
    rhs[0] = 2.0
    weights = np.linalg.solve(vander, rhs)
    gauss = np.zeros(2 * n + 1)
    gauss[1::2] = gw  # the Gauss nodes interleave with the Kronrod-only nodes
    for arr in (nodes, weights, gauss):
        arr.flags.writeable = False
    return nodes, weights, gauss


def _kronrod_panels(edges, n):
    """Nodes, Kronrod weights and (Kronrod - Gauss) weights on the panels between ``edges``.

    ``edges`` is (panel edge, sensor...) or 1-D; results are (node, sensor...).
    """
    t, vk, vg = kronrod_nodes(int(n))
    a, b = edges[:-1, None], edges[1:, None]
    extra = (1,) * (edges.ndim - 1)
    t, vk, vg = (v.reshape(v.shape + extra) for v in (t, vk, vg))
    half = (b - a) / 2
    shape = ((edges.shape[0] - 1) * t.shape[0],) + edges.shape[1:]
    return (((a + b) / 2 + half * t).reshape(shape), (half * vk).reshape(shape),
            (half * (vk - vg)).reshape(shape))


def _kronrod_counts(c, ifov, lobe_width, *, nodes_per_panel, panels_per_oscillation, min_panels,
                    grading_ratio, graded_frequency, max_nodes):
    """Uniform panels and graded panels of every sensor (integer arrays, ``_kronrod_sensors``)."""
    per_panel = 2 * int(nodes_per_panel) + 1
    n_osc = c * ifov * MAX_POSITION
    base = np.maximum(min_panels, np.ceil(panels_per_oscillation * n_osc)).astype(np.int64)
    # an OTF with lobes 1/a apart (a drift's sinc(a f), a defocus blur disk of diameter a)
    # has about c a of them below the cutoff: one panel per lobe at least
    lobes = np.ceil(c * np.where(np.isfinite(lobe_width), lobe_width, 0.0)).astype(np.int64)
    uniform = np.maximum(base, lobes)
    width = c * ifov / uniform  # first uniform panel [cycles/px]
    with np.errstate(divide="ignore"):
        graded = np.ceil(np.log(width / graded_frequency) / np.log(grading_ratio))
    graded = np.maximum(graded, 0).astype(np.int64)
    if max_nodes is not None:
        # the lobe panels give way to the node limit (the error estimate then flags the
        # unresolved sinc); the optics' own panels do not (the error below names the cause)
        room = np.maximum(max_nodes // per_panel - graded, base)
        uniform = np.minimum(uniform, room)
    return base, uniform, graded, per_panel


def aperture_kink_fractions(obscuration_ratio, wavelength_ratio):
    r"""Where a polychromatic circular-aperture OTF has kinks, as fractions of its cutoff.

    The OTF of a pupil of diameter D with a central obscuration :math:`\epsilon` is a
    piecewise function of :math:`\rho = f\lambda/D` with pieces meeting at
    :math:`\rho \in \{\epsilon, (1-\epsilon)/2, (1+\epsilon)/2, 1\}` (a clear pupil: 1
    alone). Summed over a band, the kinks of the wavelengths inside smooth out, and those
    of the band's two ends stay: at :math:`\rho D/\lambda_{min}` (the cutoff
    :math:`f_c` times :math:`\rho`) and :math:`\rho D/\lambda_{max}` (:math:`f_c` times
    :math:`\rho\,\lambda_{min}/\lambda_{max}`). A quadrature panel that straddles one
    converges only algebraically; these are its edges.

    Parameters
    ----------
    obscuration_ratio : numpy.ndarray
        Linear obscuration ratio :math:`\epsilon` of every sensor. [1]
    wavelength_ratio : numpy.ndarray
        :math:`\lambda_{min}/\lambda_{max}` of the wavelengths with signal. [1]

    Returns
    -------
    numpy.ndarray
        On (kink, the inputs' broadcast shape...), seven rows, ascending in each column,
        NaN where there is no kink (a clear pupil, a single wavelength) or where it repeats
        another or the cutoff itself (to 1e-9). [1]
    """
    eps, ratio = np.broadcast_arrays(np.asarray(obscuration_ratio, dtype=float),
                                     np.asarray(wavelength_ratio, dtype=float))
    obscured = eps > 0
    annular = [np.where(obscured, rho, np.nan) for rho in (eps, (1 - eps) / 2, (1 + eps) / 2)]
    # rows of one shape: np.array, without np.stack's checks (6 us on one sensor)
    kinks = np.array(annular + [ratio] + [ratio * rho for rho in annular])
    kinks = np.sort(np.where((kinks > 0) & (kinks < 1 - 1e-9), kinks, np.nan), axis=0)
    repeated = np.zeros(kinks.shape, dtype=bool)
    repeated[1:] = np.diff(kinks, axis=0) <= 1e-9
    return np.sort(np.where(repeated, np.nan, kinks), axis=0)


def _with_kinks(edges, cutoffs, count, steps, kinks):
    """``edges`` (:func:`_graded_edges`) of some sensors with their aperture kinks as edges.

    Each kink takes the place of the nearest interior uniform edge (moving it by at most
    half a panel, so the panel count stays); a kink whose nearest edge is taken, or that
    lies in the first panel, becomes an edge of its own. Returns the sorted edges and the
    number of added ones, one column per sensor; the caller groups sensors by that number.
    """
    edges = edges.copy()
    # NaN (no kink) as 0, which moves nothing; np.where, not nan_to_num (15 us a call)
    near = np.rint(np.where(np.isnan(kinks), 0.0, kinks) * count).astype(np.int64)
    candidate = np.isfinite(kinks) & (near >= 1) & (near <= count - 1)
    # the first kink (in row order) nearest an interior edge moves it; the others near
    # that edge are added (every row at once: a row at a time cost 7 x 10 small calls)
    rows = np.arange(kinks.shape[0])
    before = (rows[None, :] < rows[:, None])[..., None]  # (row, earlier row, 1)
    taken = (before & candidate[None, :] & (near[None, :] == near[:, None])).any(axis=1)
    movable = candidate & ~taken
    row, column = np.nonzero(movable)
    edges[steps + near[row, column], column] = kinks[row, column] * cutoffs[column]
    added = np.where(np.isfinite(kinks) & ~movable, kinks * cutoffs, np.nan)
    return edges, np.sort(added, axis=0), np.isfinite(added).sum(axis=0)


def _kronrod_sensors(c, ifov, lobe_width, kinks=None, *, nodes_per_panel, panels_per_oscillation,
                     min_panels, grading_ratio, graded_frequency, max_nodes=None, **_):
    r"""Gauss-Kronrod edge rule of every sensor, all at once (numpy).

    Parameters
    ----------
    c, ifov, lobe_width : numpy.ndarray
        One shape: optics cutoff [cycles/rad], the larger IFOV [rad] and the lobe width
        (:func:`edge_nodes`) [rad] of every sensor.
    kinks : numpy.ndarray, optional
        On (kink, that shape...): fractions of the cutoff where the OTF has kinks
        (:func:`aperture_kink_fractions`), NaN where none. Each becomes a panel edge.

    Returns
    -------
    nodes, weights, error_weights : numpy.ndarray
        On (node, that shape...). Sensors with fewer nodes are padded with their cutoff and
        zero weights. ``error_weights`` are Kronrod minus embedded Gauss weights.

    Notes
    -----
    Panels over :math:`[0, f_c]`: :math:`m = \max(m_{min}, \lceil p\,n_{osc}\rceil,
    \lceil f_c a\rceil)` uniform ones (the last term: one per lobe of an OTF whose lobes
    are 1/a apart), the first of them split geometrically (ratio ``grading_ratio``) down to
    ``graded_frequency`` cycles per pixel, so that an OTF living in a small part of the
    passband (jitter, turbulence, defocus: any smooth blur) meets panels of its own scale.
    Each of the aperture OTF's ``kinks`` moves the nearest interior uniform edge onto
    itself, or adds an edge where that one is taken (:func:`_with_kinks`): Gauss rules
    converge only algebraically on a panel that straddles a kink (measured: an annular
    MWIR system at Q 73, four panels, 4.5e-5 relative in RER without the kink edges,
    1.3e-7 with them). The sensors with the same panel counts share one node formula.
    """
    flat_c, flat_ifov = c.ravel(), ifov.ravel()
    flat_lobe = np.broadcast_to(lobe_width, c.shape).ravel()
    good = np.isfinite(flat_c) & (flat_c > 0) & np.isfinite(flat_ifov) & (flat_ifov > 0)
    if not good.all():
        bad = int(np.argmin(good))
        _checked("gauss_kronrod", flat_c[bad], flat_ifov[bad])  # raises its error
    base, uniform, graded, per_panel = _kronrod_counts(
        flat_c, flat_ifov, flat_lobe, nodes_per_panel=nodes_per_panel,
        panels_per_oscillation=panels_per_oscillation, min_panels=min_panels,
        grading_ratio=grading_ratio, graded_frequency=graded_frequency, max_nodes=max_nodes)
    if max_nodes is not None and (base.max() + graded.max()) * per_panel > max_nodes:
        worst = int(np.argmax((base + graded) * per_panel > max_nodes))
        _too_many(int((base[worst] + graded[worst]) * per_panel), max_nodes,
                  flat_c[worst], flat_ifov[worst])
    panel_sets = []  # (sensors, edges) with one panel count
    flat_kinks = None if kinks is None else np.broadcast_to(
        kinks, kinks.shape[:1] + c.shape).reshape(kinks.shape[0], -1)
    for count, steps in set(zip(uniform.tolist(), graded.tolist(), strict=True)):
        which = np.flatnonzero((uniform == count) & (graded == steps))
        edges = _graded_edges(flat_c[which], count, steps, grading_ratio)
        if flat_kinks is None:
            panel_sets.append((which, edges))
            continue
        edges, added, n_added = _with_kinks(edges, flat_c[which], count, steps,
                                            flat_kinks[:, which])
        for n in np.unique(n_added).tolist():
            mine = np.flatnonzero(n_added == n)
            panel_sets.append((which[mine], np.sort(np.concatenate(
                [edges[:, mine], added[:n, mine]]), axis=0)))
    size = max(edges.shape[0] - 1 for _, edges in panel_sets) * per_panel
    nodes = np.empty((size, flat_c.size))
    weights, error = np.zeros((size, flat_c.size)), np.zeros((size, flat_c.size))
    nodes[...] = flat_c  # padding
    for which, edges in panel_sets:
        head = (edges.shape[0] - 1) * per_panel
        nodes[:head, which], weights[:head, which], error[:head, which] = _kronrod_panels(
            edges, nodes_per_panel)
    shape = (size,) + c.shape
    return nodes.reshape(shape), weights.reshape(shape), error.reshape(shape)


def _graded_edges(cutoffs, count, steps, ratio):
    """Panel edges (edge, sensor): ``count`` uniform panels to each cutoff.

    The first is split geometrically into ``steps`` + 1 panels of ratio ``ratio`` toward 0.
    """
    h = cutoffs / count
    geometric = h * float(ratio) ** -np.arange(steps, 0, -1.0)[:, None]
    edges = np.concatenate([np.zeros((1, cutoffs.size)), geometric,
                            h * np.arange(1.0, count + 1)[:, None]])
    edges[-1] = cutoffs
    return edges


def _panel_edges_with(edges, breakpoints, cutoff):
    """``edges`` with the ``breakpoints`` inside (0, cutoff) added (merged at rounding level)."""
    bp = np.asarray(breakpoints, dtype=float).ravel()
    bp = bp[(bp > 0) & (bp < cutoff)]
    edges = np.unique(np.concatenate([edges, bp]))
    keep = np.concatenate([[True], np.diff(edges) > 1e-12 * cutoff])
    return edges[keep]


def _too_many(count, max_nodes, cutoff, ifov_max):
    q = 1.0 / (cutoff * ifov_max)
    raise ValueError(
        f"the edge-response quadrature would need {count} "
        f"frequency nodes (limit max_frequency_nodes={max_nodes}): the detector samples "
        f"the optics far too coarsely (Q = lambda_min F / p = {q:.3g}); check "
        "pixel_pitch_x, pixel_pitch_y, focal_length and aperture_diameter, or raise the "
        "limit with xbsm.method(..., max_frequency_nodes=...)")


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


def edge_quadrature(*, cutoff, ifov, rule, grid_size, nodes_per_panel, panels_per_oscillation,
                    min_panels, breakpoints=None, frequency_offset=1e-6, name="custom",
                    max_nodes=None, grading_ratio=4.0, graded_frequency=4e-3, lobe_width=0.0):
    r"""Frequency nodes and weights of an edge-response quadrature rule.

    Parameters
    ----------
    cutoff : float
        Upper integration limit, normally the optics cutoff
        :math:`D/\lambda_{min}`; the OTF must vanish beyond it. [cycles/rad]
    ifov : float or array_like or xr.DataArray
        Detector IFOV (pitch / focal length); the largest value sets the
        oscillation count. [rad]
    rule : {"uniform_trapezoid", "gauss_legendre"}
        pyBSM's trapezoid on its grid slice, or composite Gauss-Legendre.
    grid_size : int
        Uniform rule: size N of pyBSM's grid ``linspace(-1, 1, N)`` whose
        slice holds :func:`pybsm_slice_count` (N) samples. [1]
    nodes_per_panel : int
        Gauss-Legendre: nodes per panel. [1]
    panels_per_oscillation : float
        Gauss-Legendre: panels per period of :math:`\sin(2\pi f\theta x_{max})`. [1]
    min_panels : int
        Gauss-Legendre: fewest uniform panels over :math:`[0, f_c]`. [1]
    breakpoints : array_like, optional
        Frequencies where the OTF has a kink (Gauss-Legendre only), e.g. from
        :func:`aperture_breakpoints` and :func:`detector_breakpoints`. [cycles/rad]
    frequency_offset : float, optional
        Uniform rule: offset added to the abscissa in ``1/f`` and ``sin``
        (pyBSM uses 1e-6). [cycles/rad]
    name : str, optional
        Method name recorded in the attrs.
    max_nodes : int, optional
        Refuse (``ValueError``) a Gauss-Legendre rule that would need more nodes: a
        detector that samples the optics absurdly coarsely asks for millions.
    grading_ratio : float, optional
        Gauss-Kronrod: ratio of successive panels graded toward f = 0. [1]
    graded_frequency : float, optional
        Gauss-Kronrod: lowest graded panel edge. [cycles/px]
    lobe_width : float, optional
        Gauss-Kronrod: the widest blur whose OTF has lobes 1/lobe_width apart (one panel
        per lobe), as for :func:`edge_nodes`. [rad]

    Returns
    -------
    nodes, weights : xr.DataArray
        On dimension ``frequency``. [cycles/rad]

    Notes
    -----
    The integrand :math:`H(f)\sin(2\pi f\theta x)/f` completes
    :math:`n_{osc} = f_c\,\theta\,x_{max}` periods over :math:`[0, f_c]`
    (about 60 for Q = 0.05 at :math:`x_{max}` = 3 px). The Gauss-Legendre
    rule uses :math:`\max(n_{min}, \lceil p\,n_{osc}\rceil)` uniform panels,
    split further at the breakpoints. The pyBSM rule uses
    :math:`\Delta f = 2f_c/(N-1)` (computed as pyBSM does) and
    :func:`pybsm_slice_count` samples, whatever the oscillation count.

    Examples
    --------
    The knobs of a method preset: ``edge_quadrature(cutoff=..., ifov=...,
    **xbsm.method("accurate").edge_quadrature_knobs())``.
    """
    cutoff, ifov_max = _checked(rule, cutoff, np.nanmax(np.asarray(ifov, dtype=float)))
    if rule == "gauss_kronrod":
        nodes, weights, error = _kronrod_sensors(
            np.asarray(cutoff), np.asarray(ifov_max), np.asarray(float(lobe_width)),
            nodes_per_panel=nodes_per_panel, panels_per_oscillation=panels_per_oscillation,
            min_panels=min_panels, grading_ratio=grading_ratio,
            graded_frequency=graded_frequency, max_nodes=max_nodes)
        if breakpoints is not None:  # the same panels, split at the kinks
            _, uniform, graded, _ = _kronrod_counts(
                np.asarray(cutoff), np.asarray(ifov_max), np.asarray(float(lobe_width)),
                nodes_per_panel=nodes_per_panel, panels_per_oscillation=panels_per_oscillation,
                min_panels=min_panels, grading_ratio=grading_ratio,
                graded_frequency=graded_frequency, max_nodes=max_nodes)
            edges = _graded_edges(np.array([cutoff]), int(uniform), int(graded),
                                  grading_ratio)[:, 0]
            nodes, weights, error = _kronrod_panels(
                _panel_edges_with(edges, breakpoints, cutoff), nodes_per_panel)
        node_da, w_da = _pack(nodes, weights, nodes, {
            "quadrature_rule": rule, "nodes_per_panel": int(nodes_per_panel),
            "quadrature_preset": name, "cutoff_frequency": cutoff})
        return node_da, w_da.assign_coords(error_weights=(
            "frequency", error, {"units": "cycles/rad",
                                 "long_name": "Kronrod minus embedded Gauss weights"}))
    nodes, weights, sine = _edge_rule(
        cutoff, ifov_max, rule, grid_size=grid_size, nodes_per_panel=nodes_per_panel,
        panels_per_oscillation=panels_per_oscillation, min_panels=min_panels,
        breakpoints=breakpoints, frequency_offset=frequency_offset, max_nodes=max_nodes)
    if rule == "uniform_trapezoid":
        rule_attrs = {"quadrature_rule": rule, "frequency_offset": float(frequency_offset)}
    else:
        rule_attrs = {"quadrature_rule": rule, "nodes_per_panel": int(nodes_per_panel)}
    meta = {"quadrature_preset": name, "cutoff_frequency": cutoff}
    return _pack(nodes, weights, sine, {**rule_attrs, **meta})


def _checked(rule, cutoff, ifov_max):
    """The rule's name, cutoff and largest IFOV checked; the last two as floats."""
    if rule not in EDGE_RULES:
        raise ValueError(f"rule must be one of {', '.join(map(repr, EDGE_RULES))}; got {rule!r}")
    cutoff, ifov_max = float(cutoff), float(ifov_max)
    if not (np.isfinite(cutoff) and cutoff > 0):
        raise ValueError(f"cutoff must be finite and > 0 [cycles/rad], got {cutoff}")
    if not (np.isfinite(ifov_max) and ifov_max > 0):
        raise ValueError(f"ifov must be finite and > 0 [rad], got {ifov_max}")
    return cutoff, ifov_max


def _edge_rule(cutoff, ifov_max, rule, *, grid_size, nodes_per_panel, panels_per_oscillation,
               min_panels, breakpoints=None, frequency_offset=1e-6, max_nodes=None):
    """Nodes, weights and sine abscissae of :func:`edge_quadrature` (numpy, plain floats).

    Raises the ``max_nodes`` error, which depends on the sensor (not a programming error).
    """
    if rule == "uniform_trapezoid":
        grid = np.linspace(-1.0, 1.0, grid_size) * cutoff
        return _uniform_trapezoid_kernel(pybsm_slice_count(grid_size), grid[1] - grid[0],
                                         frequency_offset)
    n_osc = cutoff * ifov_max * MAX_POSITION
    n_panels = max(min_panels, math.ceil(panels_per_oscillation * n_osc))
    if max_nodes is not None and n_panels * nodes_per_panel > max_nodes:
        q = 1.0 / (cutoff * ifov_max)
        raise ValueError(
            f"the edge-response quadrature would need {n_panels * nodes_per_panel} "
            f"frequency nodes (limit max_frequency_nodes={max_nodes}): the detector samples "
            f"the optics far too coarsely (Q = lambda_min F / p = {q:.3g}); check "
            "pixel_pitch_x, pixel_pitch_y, focal_length and aperture_diameter, or raise the "
            "limit with xbsm.method(..., max_frequency_nodes=...)")
    nodes, weights = _gauss_legendre_kernel(
        _panel_edges(cutoff, n_panels, breakpoints), nodes_per_panel)
    return nodes, weights, nodes


def _sensor_grid(*arrays):
    """Sensor quantities as numpy arrays on their joint dims, with those dims' coordinates."""
    arrays = [a if isinstance(a, xr.DataArray) else xr.DataArray(a) for a in arrays]
    sizes = {}
    for a in arrays:
        sizes.update(a.sizes)
    dims = tuple(sizes)
    values = [a.variable.set_dims(sizes).transpose(*dims).values for a in arrays]
    coords = {}
    for a in arrays:
        coords.update({d: a.coords[d] for d in a.dims if d in a.coords and d not in coords})
    return values, dims, coords


def edge_nodes(cutoff, ifov_x, ifov_y, lobe_width=0.0, obscuration_ratio=0.0,
               wavelength_ratio=1.0, **knobs):
    """Frequency nodes and quadrature weights for the edge response of every sensor.

    Parameters
    ----------
    cutoff : float or xr.DataArray
        Optics cutoff D / lambda_min, possibly over sensor dims. [cycles/rad]
    ifov_x, ifov_y : float or xr.DataArray
        Detector pitch over focal length. [rad]
    lobe_width : float or xr.DataArray, optional
        The widest blur whose OTF has lobes 1/lobe_width apart: the larger of the drift
        angle over the nominal exposure (drift rate x integration time x TDI stages; its
        sinc) and the defocus blur circle's diameter 8 W020 / D (its disk). Gauss-Kronrod:
        one panel per lobe. [rad]
    obscuration_ratio, wavelength_ratio : float or xr.DataArray, optional
        The pupil's linear obscuration and the band's shortest over longest wavelength
        with signal: Gauss-Kronrod puts panel edges at the aperture OTF's kinks
        (:func:`aperture_kink_fractions`). The defaults (a clear pupil, one wavelength)
        add none. [1]
    **knobs
        The rule's knobs, as for :func:`edge_quadrature`
        (``Method.edge_quadrature_knobs()``).

    Returns
    -------
    nodes, weights : xr.DataArray
        On dims (``frequency``, sensor dims...); ``weights`` carries the
        ``sine_frequency`` coordinate of :mod:`xbsm.quadrature` (and, for the
        Gauss-Kronrod rule, ``error_weights``: Kronrod minus embedded Gauss weights).
        Sensors that need fewer nodes than the largest are padded with zero weights.
        [cycles/rad]
    """
    (c, ix, iy, d, eps, ratio), dims, coords = _sensor_grid(
        cutoff, ifov_x, ifov_y, lobe_width, obscuration_ratio, wavelength_ratio)
    nodes, weights, sine, error = edge_rule_arrays(c, ix, iy, d, eps, ratio, **knobs)
    all_dims = ("frequency",) + tuple(dims)
    attrs = {"units": "cycles/rad"}
    nodes_da = xr.DataArray(nodes, dims=all_dims, coords=coords,
                            attrs={**attrs, "long_name": "edge-response frequency nodes"})
    weights_da = xr.DataArray(weights, dims=all_dims, coords=coords,
                              attrs={**attrs, "long_name": "edge-response quadrature weights"})
    weights_da = weights_da.assign_coords(
        sine_frequency=(all_dims, sine, {**attrs, "long_name": "abscissa of 1/f and the sine"})
    )
    if error is not None:
        weights_da = weights_da.assign_coords(error_weights=(all_dims, error, {
            **attrs, "long_name": "Kronrod minus embedded Gauss weights"}))
    return nodes_da, weights_da


def _rule_per_sensor(c, ifov, rule, knobs):
    """Nodes, weights and sine abscissae of :func:`_edge_rule` for every sensor, one at a time.

    On (frequency, sensor dims...); sensors with fewer nodes are padded with their cutoff
    (nodes, abscissae) and zero weights.
    """
    per_sensor = {}
    for index in np.ndindex(c.shape):
        key = (float(c[index]), float(ifov[index]))
        if key not in per_sensor:
            per_sensor[key] = _edge_rule(*_checked(rule, *key), rule, **knobs)
    size = max(v[0].size for v in per_sensor.values())
    nodes, weights, sine = (np.empty((size,) + c.shape), np.zeros((size,) + c.shape),
                            np.empty((size,) + c.shape))
    for index in np.ndindex(c.shape):
        key = (float(c[index]), float(ifov[index]))
        n, w, s = per_sensor[key]
        nodes[(slice(None),) + index] = sine[(slice(None),) + index] = key[0]  # padding
        head = (slice(0, n.size),) + index
        nodes[head], weights[head], sine[head] = n, w, s
    return nodes, weights, sine


def _gauss_legendre_sensors(c, ifov, *, nodes_per_panel, panels_per_oscillation, min_panels,
                            max_nodes=None, **_):
    """:func:`_rule_per_sensor` for the Gauss-Legendre rule without breakpoints, all at once.

    The sensors that need the same number of panels share one ``linspace`` and one node
    formula over their cutoffs (the same arithmetic as :func:`_edge_rule`, value for
    value), so a sweep of 10^4 optical states costs a few array operations, not 10^4
    Python rules.
    """
    flat_c, flat_ifov = c.ravel(), ifov.ravel()
    good = np.isfinite(flat_c) & (flat_c > 0) & np.isfinite(flat_ifov) & (flat_ifov > 0)
    if not good.all():
        bad = int(np.argmin(good))
        _checked("gauss_legendre", flat_c[bad], flat_ifov[bad])  # raises its error
    n_osc = flat_c * flat_ifov * MAX_POSITION
    panels = np.maximum(min_panels, np.ceil(panels_per_oscillation * n_osc)).astype(np.int64)
    if max_nodes is not None and panels.max() * nodes_per_panel > max_nodes:
        worst = int(np.argmax(panels * nodes_per_panel > max_nodes))  # the first, as one by one
        _edge_rule(flat_c[worst], flat_ifov[worst], "gauss_legendre",
                   nodes_per_panel=nodes_per_panel, panels_per_oscillation=panels_per_oscillation,
                   min_panels=min_panels, max_nodes=max_nodes, grid_size=0)  # raises its error
    t, v = legendre_nodes(int(nodes_per_panel))
    size = int(panels.max()) * t.size
    nodes, weights = np.empty((size, flat_c.size)), np.zeros((size, flat_c.size))
    nodes[...] = flat_c  # padding
    for count in np.unique(panels):
        which = np.flatnonzero(panels == count)
        edges = np.linspace(0.0, flat_c[which], int(count) + 1)  # (panel edge, sensor)
        a, b = edges[:-1, None, :], edges[1:, None, :]
        head = int(count) * t.size
        nodes[:head, which] = ((a + b) / 2 + (b - a) / 2 * t[:, None]).reshape(head, -1)
        weights[:head, which] = ((b - a) / 2 * v[:, None]).reshape(head, -1)
    shape = (size,) + c.shape
    return nodes.reshape(shape), weights.reshape(shape)


_KRONROD_KNOBS = ("grading_ratio", "graded_frequency")


def edge_rule_arrays(cutoff, ifov_x, ifov_y, lobe_width=0.0, obscuration_ratio=0.0,
                     wavelength_ratio=1.0, **knobs):
    """:func:`edge_nodes` on plain arrays: nodes, weights, sine abscissae, error weights.

    The sensor quantities share one shape (0-d for one sensor); the result's arrays are on
    (node, that shape...). The error weights (Kronrod minus embedded Gauss) are None for
    the other rules.
    """
    knobs = {k: v for k, v in knobs.items() if k != "name"}
    rule = knobs.pop("rule")
    c, ifov = np.asarray(cutoff), np.maximum(ifov_x, ifov_y)
    if rule == "gauss_kronrod":
        kinks = aperture_kink_fractions(obscuration_ratio, wavelength_ratio)
        nodes, weights, error = _kronrod_sensors(c, ifov, np.asarray(lobe_width, dtype=float),
                                                 kinks, **knobs)
        return nodes, weights, nodes.copy(), error
    knobs = {k: v for k, v in knobs.items() if k not in _KRONROD_KNOBS}
    if rule == "gauss_legendre" and knobs.get("breakpoints") is None:
        nodes, weights = _gauss_legendre_sensors(c, ifov, **knobs)
        return nodes, weights, nodes.copy(), None
    return (*_rule_per_sensor(c, ifov, rule, knobs), None)


def _samples_per_oscillation_kernel(count, cutoff, ifov_max):
    """Nodes per period of the edge-response integrand at the farthest position (numpy)."""
    return count / (cutoff * ifov_max * MAX_POSITION)


def undersampled_arrays(count, cutoff, ifov_x, ifov_y, threshold):
    """:func:`undersampled` with ``count`` nodes on plain arrays."""
    samples = _samples_per_oscillation_kernel(count, cutoff, np.maximum(ifov_x, ifov_y))
    return samples < threshold


def samples_per_oscillation(nodes, cutoff, ifov_x, ifov_y):
    """Frequency samples per period of the edge-response integrand at 3 px.

    Parameters
    ----------
    nodes : xr.DataArray
        Frequency nodes on ``frequency``. [cycles/rad]
    cutoff : float or xr.DataArray
        [cycles/rad]
    ifov_x, ifov_y : float or xr.DataArray
        [rad]

    Returns
    -------
    xr.DataArray
        [1]
    """
    samples = _samples_per_oscillation_kernel(nodes.sizes["frequency"], cutoff,
                                              np.maximum(ifov_x, ifov_y))
    return named(samples, "1",
                 "frequency samples per period of the edge-response integrand at 3 px")


def cutoff_wavelength(wavelength: xr.DataArray, qe, transmission):
    """Shortest band wavelength that contributes signal (where QE x transmission > 0).

    Parameters
    ----------
    wavelength : xr.DataArray
        Band wavelengths. [m]
    qe, transmission : xr.DataArray or float
        Quantum efficiency and optics transmission on ``wavelength``. [1]

    Returns
    -------
    xr.DataArray
        The wavelength setting the optics cutoff D / lambda. [m]
    """
    out = _over_band(_shortest_contributing_kernel, wavelength, qe, transmission)
    return named(out, "m", "shortest contributing wavelength",
                 standard_name="radiation_wavelength")


def _shortest_contributing_kernel(wavelength, qe, transmission):
    """Smallest ``wavelength`` (last axis) where ``qe * transmission > 0``; NaN if none."""
    contributes = np.broadcast_to(qe * transmission > 0,
                                  np.broadcast_shapes(np.shape(qe * transmission),
                                                      np.shape(wavelength)))
    return np.fmin.reduce(np.where(contributes, wavelength, np.nan), axis=-1)


def _cutoff_kernel(aperture_diameter, wavelength, qe, transmission):
    return aperture_diameter / _shortest_contributing_kernel(wavelength, qe, transmission)


def _over_band(kernel, wavelength, *args, leading=()):
    """``kernel(*leading, wavelength, *args)`` with ``wavelength`` as the arguments' last axis.

    Arguments without a ``wavelength`` dimension reach the kernel with a length-1 last
    axis; dims keep the order of arithmetic on the arguments in that order.
    """
    cores = [isinstance(a, xr.DataArray) and "wavelength" in a.dims for a in args]
    n = len(leading)

    def on_band(*arrays):
        front, band, rest = arrays[:n], arrays[n], arrays[n + 1:]
        return kernel(*front, band, *(a if core else np.asarray(a)[..., np.newaxis]
                                      for a, core in zip(rest, cores, strict=True)))

    return apply_kernel(on_band, *leading, wavelength, *args,
                        core=[[]] * len(leading) + [["wavelength"]]
                        + [["wavelength"] if core else [] for core in cores])


def optics_cutoff(aperture_diameter, wavelength: xr.DataArray, qe, transmission):
    """Diffraction cutoff of the optics over the band, D / lambda_min, where the band has signal.

    Parameters
    ----------
    aperture_diameter : float or xr.DataArray
        [m]
    wavelength : xr.DataArray
        Band wavelengths. [m]
    qe, transmission : xr.DataArray or float
        Quantum efficiency and optics transmission on ``wavelength``. [1]

    Returns
    -------
    xr.DataArray
        Upper limit of every frequency integral: the system OTF vanishes beyond it.
        [cycles/rad]
    """
    out = _over_band(_cutoff_kernel, wavelength, qe, transmission,
                     leading=(aperture_diameter,))
    return named(out, "cycles/rad", "optics cutoff frequency D/lambda_min")


def band_cutoff(aperture_diameter, wavelength: xr.DataArray, qe, transmission,
                wavelength_min):
    """:func:`optics_cutoff`, or the band's own D / lambda_min where no wavelength has signal.

    A band without signal (cold_filter_transmission = 0) still gets a finite cutoff, so
    that the edge response can be computed; its SNR is 0, flagged ``snr_nonpositive``.

    Parameters
    ----------
    aperture_diameter : float or xr.DataArray
        [m]
    wavelength : xr.DataArray
        Band wavelengths. [m]
    qe, transmission : xr.DataArray or float
        Quantum efficiency and optics transmission on ``wavelength``. [1]
    wavelength_min : float or xr.DataArray
        The band's first wavelength. [m]

    Returns
    -------
    xr.DataArray
        [cycles/rad]
    """
    return band_optics_limits(aperture_diameter, wavelength, qe, transmission,
                              wavelength_min)["cutoff_frequency"]


def band_optics_limits(aperture_diameter, wavelength: xr.DataArray, qe, transmission,
                       wavelength_min) -> dict:
    """:func:`band_cutoff` and the band's wavelength ratio (:data:`CUTOFF_OUTPUTS`).

    Parameters are those of :func:`band_cutoff`. Returns a dict of DataArrays: the cutoff
    and the ratio of the shortest to the longest wavelength with signal (1 where none
    has), which places the aperture OTF's kinks (:func:`aperture_kink_fractions`).
    """
    spectral = [(a if "wavelength" in a.dims else a.broadcast_like(wavelength))
                if isinstance(a, xr.DataArray) else xr.full_like(wavelength, a)
                for a in (qe, transmission)]
    band = ["wavelength"]
    return apply_orchestrator(band_cutoff_arrays, CUTOFF_OUTPUTS, aperture_diameter,
                              wavelength, *spectral, wavelength_min,
                              core=[[], band, band, band, []])


CUTOFF_OUTPUTS = outputs(
    Output("cutoff_frequency", "cycles/rad", "optics cutoff frequency D/lambda_min",
           carries=("sensor",)),
    Output("band_wavelength_ratio", "1",
           "shortest over longest wavelength with signal (the aperture OTF's kinks)",
           carries=("sensor",)))
"""What :func:`band_cutoff_arrays` returns."""


def band_cutoff_arrays(aperture_diameter, wavelength, qe, transmission, wavelength_min):
    """:func:`band_cutoff` on plain arrays (:data:`CUTOFF_OUTPUTS`).

    ``qe`` and ``transmission`` are on the band's wavelengths (last axis) or 0-d. The
    wavelength ratio places the polychromatic aperture OTF's kinks (:func:`edge_nodes`);
    it is 1 (no kinks but the cutoff's own) where no wavelength has signal.
    """
    spectral = [np.asarray(a) for a in (qe, transmission)]
    spectral = [a if a.ndim else a[..., np.newaxis] for a in spectral]
    shortest = _shortest_contributing_kernel(wavelength, *spectral)
    cutoff = aperture_diameter / shortest
    fallback = aperture_diameter / wavelength_min
    ratio = shortest / _longest_contributing_kernel(wavelength, *spectral)
    return {"cutoff_frequency": np.where(np.isnan(cutoff), fallback, cutoff),
            "band_wavelength_ratio": np.where(np.isnan(ratio), 1.0, ratio)}


def _longest_contributing_kernel(wavelength, qe, transmission):
    """Largest ``wavelength`` (last axis) where ``qe * transmission > 0``; NaN if none."""
    contributes = np.broadcast_to(qe * transmission > 0,
                                  np.broadcast_shapes(np.shape(qe * transmission),
                                                      np.shape(wavelength)))
    return np.fmax.reduce(np.where(contributes, wavelength, np.nan), axis=-1)


#: For rules without an error estimate (pybsm's trapezoid, edge_rule="gauss_legendre"):
#: below this RER the edge-response quadrature is not converged (tested on the worse of
#: the x and y slices, where a one-axis smear shows first): against the independent
#: reference on 434 systems (recipes/evidence/preset_error.py at 3b99eb9,
#: docs/benchmarks/preset_error_before_issue23.json) the uniform-panel Gauss-Legendre rule
#: was within 2.3e-4 NIIRS where RER >= 0.05 and off by up to 28 below (flag
#: ``blur_unresolved``). The Gauss-Kronrod rule flags by its own estimate instead.
UNRESOLVED_RER = 0.05


def undersampled(nodes, cutoff, ifov_x, ifov_y, threshold):
    """Where a uniform frequency grid has too few samples per oscillation of the edge integrand.

    Parameters
    ----------
    nodes : xr.DataArray
        Frequency nodes on ``frequency``. [cycles/rad]
    cutoff : float or xr.DataArray
        [cycles/rad]
    ifov_x, ifov_y : float or xr.DataArray
        [rad]
    threshold : float
        Fewest samples per period of the integrand at 3 px that the rule resolves. [1]

    Returns
    -------
    xr.DataArray
        Boolean, True where the edge response of a uniform rule may be inaccurate.
    """
    return apply_kernel(undersampled_arrays, nodes.sizes["frequency"], cutoff, ifov_x, ifov_y,
                        threshold, dtype=bool)
