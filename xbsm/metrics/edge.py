r"""Edge response, relative edge response (RER) and edge height overshoot (EHO).

Inputs are OTF slices: DataArrays with a ``frequency`` dimension whose
coordinate is angular spatial frequency in object space [cycles/rad]. Every
other dimension (orientation, scenario sweeps) broadcasts and is never
reduced. The frequency integrals use a quadrature rule from
:mod:`xbsm.quadrature`; sample the OTF at its nodes and pass its weights.

Which part of the OTF to use
----------------------------
:func:`edge_response` integrates the complex OTF exactly (real part against
the sine, imaginary part against the cosine). For a symmetric PSF the OTF is
real and may be negative (sinc lobes, defocus, drift); pass it as is. pyBSM
0.16.1 passes :math:`|OTF|`, which folds the negative lobes up and biases RER
high or low; ``docs/metrics.md`` quantifies this (a rect detector alone gives
RER = 1 exactly with the OTF, 0.867 with its modulus). To reproduce pyBSM, pass
``abs(otf)``.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._kernels import apply_kernel, apply_orchestrator, dataset
from .._metadata import Output, named, outputs
from .._trig import sine as trig_sine
from .._trig import sine_cosine

__all__ = [
    "EHO_POSITIONS",
    "RER_POSITIONS",
    "edge_height_overshoot",
    "edge_response",
    "edge_terms",
    "relative_edge_response",
]

EHO_POSITIONS = np.arange(1.0, 3.25, 0.25)
"""Distances from the edge at which EHO is evaluated: 1 to 3 px by 0.25. [px]"""

RER_POSITIONS = np.array([-0.5, 0.5])
"""Distances from the edge whose difference is the RER: -0.5 and +0.5 px. [px]"""
EHO_POSITIONS.flags.writeable = RER_POSITIONS.flags.writeable = False  # read-only tables


def _as_position(position):
    if isinstance(position, xr.DataArray):
        return position
    arr = np.asarray(position, dtype=float)
    if arr.ndim == 0:
        return xr.DataArray(float(arr))
    if arr.ndim != 1:
        raise ValueError("position must be a scalar, a 1-D array or a DataArray [px]")
    return xr.DataArray(arr, dims="position", coords={"position": arr})


def check_slice(otf_slice, weights):
    """Raise ValueError unless ``otf_slice`` (and ``weights``) can feed an edge response."""
    if not isinstance(otf_slice, xr.DataArray) or "frequency" not in otf_slice.dims:
        raise ValueError("otf_slice must be an xr.DataArray with a 'frequency' dimension")
    if weights is None:
        if "frequency" not in otf_slice.coords:
            raise ValueError("otf_slice needs a 'frequency' coordinate [cycles/rad]")
        return
    if otf_slice.sizes["frequency"] != weights.sizes["frequency"]:
        raise ValueError("otf_slice and weights must have the same number of frequency samples")
    if "frequency" in otf_slice.coords and "frequency" in weights.coords:
        a = np.asarray(otf_slice["frequency"].values)
        b = np.asarray(weights["frequency"].values)
        if not np.array_equal(a, b):
            raise ValueError(
                "otf_slice must be sampled at the quadrature nodes: its 'frequency' "
                "coordinate differs from that of weights"
            )


def _edge_response_kernel(otf, weights, abscissa, ifov, position):
    """Edge response at ``position`` [px] (NumPy; the quadrature along the last axis).

    ``otf``, ``weights`` and ``abscissa`` carry the frequency samples on their last axis;
    ``ifov`` and ``position`` broadcast against the other axes. The sine (and cosine) table
    has the shape of the broadcast of weights, abscissa, ifov and position only: computed
    once, then contracted with the OTF, whatever the OTF's other axes.
    """
    with np.errstate(all="ignore"):  # IEEE results without warnings, as xarray's arithmetic
        phase = (2.0 * np.pi * abscissa * np.asarray(ifov)[..., None]
                 * np.asarray(position)[..., None])
        if np.iscomplexobj(otf):
            sin_phase, cos_phase = sine_cosine(phase)
            sine = weights * sin_phase / abscissa
            cosine = weights * cos_phase / abscissa
            integral = _sum_of_products(otf.real, sine) + _sum_of_products(otf.imag, cosine)
        else:
            integral = _sum_of_products(otf, weights * trig_sine(phase) / abscissa)
        return 0.5 + integral / np.pi


def _sum_of_products(a, b):
    return np.einsum("...k,...k->...", a, b)


def _eho_kernel(er):
    """EHO from the edge response at :data:`EHO_POSITIONS` along the last axis."""
    rising = (np.diff(er, axis=-1) > 0).all(axis=-1)
    return np.where(rising, er[..., 1], er.max(axis=-1))  # er[..., 1]: 1.25 px


def _edge_terms_kernel(otf, weights, abscissa, ifov, rer=True, eho=True):
    """RER and/or EHO (in that order) from one edge response at the positions they need."""
    positions = np.concatenate([RER_POSITIONS] * rer + [EHO_POSITIONS] * eho)
    er = _edge_response_kernel(otf[..., None, :], weights[..., None, :],
                               abscissa[..., None, :], np.asarray(ifov)[..., None], positions)
    out = ([er[..., 1] - er[..., 0]] if rer else []) + (
        [_eho_kernel(er[..., -EHO_POSITIONS.size:])] if eho else [])
    return tuple(out) if len(out) > 1 else out[0]


def _edge_terms_error_kernel(otf, weights, error_weights, abscissa, ifov, tables=None):
    """RER, EHO and their error estimates from a rule with embedded error weights (numpy).

    One sine (and cosine) table at the RER and EHO positions, contracted with the OTF
    times the weights and times the error weights (Kronrod minus embedded Gauss): the
    second contraction is the difference of the two rules' edge responses. Returns
    RER, EHO, the absolute RER difference and the largest absolute edge-response difference
    over the EHO positions. ``tables``: :func:`_edge_tables` of the same abscissa and
    ifov, when the caller has them (the filtered and unfiltered OTFs share one).
    """
    if tables is None:
        tables = _edge_tables(abscissa, ifov, cosine=np.iscomplexobj(otf))
    sine, cosine = tables
    with np.errstate(all="ignore"):  # IEEE results without warnings, as xarray's arithmetic
        # both rules' weights in one table (positions: the rule's, then the error's), so
        # the OTF, the largest array, is read once, by a matrix product
        def weighted(table):
            return np.concatenate([weights[..., None, :] * table,
                                   error_weights[..., None, :] * table], axis=-2)

        both = _contract(otf.real, weighted(sine))
        if np.iscomplexobj(otf):
            both = both + _contract(otf.imag, weighted(cosine))
        both = both / np.pi
        p = sine.shape[-2]
        er, d = 0.5 + both[..., :p], both[..., p:]
        n = RER_POSITIONS.size
        return (er[..., 1] - er[..., 0], _eho_kernel(er[..., n:]), np.abs(d[..., 1] - d[..., 0]),
                np.abs(d[..., n:]).max(axis=-1))


#: Bytes of the values regrouped at a time, so that the regrouping copy stays in cache.
CONTRACT_BLOCK_BYTES = 1 << 22
#: Scenarios sharing a table below which the values are contracted where they lie.
CONTRACT_MIN_ROWS = 64


def _contract(values, table):
    """``sum_k values[..., k] table[..., p, k]`` as a matrix product per distinct table.

    ``table``'s leading axes broadcast against ``values``'; where it varies (an optical
    state's nodes, the orientation) the values are grouped by table, and each group is one
    (scenarios x k) by (k x p) product: the values are read once (einsum of the broadcast
    operands took 0.7 of a 1.8 s study chunk). Large values go in blocks along their
    outermost axis in memory, so that grouping them copies from cache. Where few scenarios
    share a table, einsum contracts them where they lie.
    """
    lead = np.broadcast_shapes(values.shape[:-1], table.shape[:-2])
    table = table.reshape((1,) * (len(lead) + 2 - table.ndim) + table.shape)
    shared = [axis for axis in range(len(lead)) if table.shape[axis] == 1 and lead[axis] > 1]
    if math.prod(lead[axis] for axis in shared) < CONTRACT_MIN_ROWS:
        # one scenario, or a table per scenario (an optics sweep): nothing to group
        return np.einsum("...k,...pk->...p", values, table)
    values = np.broadcast_to(values, (*lead, values.shape[-1]))
    if values.nbytes <= CONTRACT_BLOCK_BYTES:
        return _contract_grouped(values, table)
    outer = max(shared, key=lambda axis: abs(values.strides[axis]))
    step = max(1, lead[outer] * CONTRACT_BLOCK_BYTES // values.nbytes)
    out = np.empty((*lead, table.shape[-2]))
    for start in range(0, lead[outer], step):
        block = (slice(None),) * outer + (slice(start, start + step),)
        out[block] = _contract_grouped(values[block], table)
    return out


def _contract_grouped(values, table):
    """:func:`_contract` of values on the table's axes (plus size-1 axes), in one go."""
    lead, k, p = values.shape[:-1], table.shape[-1], table.shape[-2]
    varies = [axis for axis in range(len(lead)) if table.shape[axis] > 1]
    # the other axes in the values' memory order: grouping an array so laid out is free
    rest = sorted((axis for axis in range(len(lead)) if table.shape[axis] == 1),
                  key=lambda axis: -abs(values.strides[axis]))
    order = varies + rest
    groups = math.prod(lead[a] for a in varies)
    rows = np.reshape(values.transpose(*order, len(lead)), (groups, -1, k))
    tables = np.reshape(table.transpose(*order, len(lead), len(lead) + 1)[
        (slice(None),) * len(varies) + (0,) * len(rest)], (groups, p, k))
    out = _matmul_in_stacks(rows, np.swapaxes(tables, -1, -2))  # (groups, rows, p)
    out = out.reshape(*(lead[a] for a in order), p)
    return np.moveaxis(out, range(len(lead)), order)


#: Rows per matrix product: small enough that OpenBLAS runs each on the calling thread.
#: One large product runs on its thread pool, which serialises the calls of two threads
#: (a 2-thread study ran at 0.55 of two single-threaded ones); non-BLAS einsum was 6x
#: slower on one thread.
STACK_ROWS = 32


def _matmul_in_stacks(a, b):
    """``a @ b`` for (groups, rows, k) by (groups, k, p), as products of STACK_ROWS rows."""
    groups, rows, k = a.shape
    whole = rows - rows % STACK_ROWS
    out = np.empty((groups, rows, b.shape[-1]))
    if whole:
        stacked = np.reshape(a[:, :whole], (groups, whole // STACK_ROWS, STACK_ROWS, k))
        out[:, :whole] = np.reshape(np.matmul(stacked, b[:, None]), (groups, whole, -1))
    if whole < rows:  # the last rows padded to a whole stack: every row, one BLAS kernel
        last = np.zeros((groups, STACK_ROWS, k))
        last[:, :rows - whole] = a[:, whole:]
        out[:, whole:] = np.matmul(last, b)[:, :rows - whole]
    return out


def _edge_tables(abscissa, ifov, cosine: bool):
    """sin(2 pi f ifov x) / f (and cos(...) / f, or None) at the RER and EHO positions x."""
    positions = np.concatenate([RER_POSITIONS, EHO_POSITIONS])
    with np.errstate(all="ignore"):
        phase = (2.0 * np.pi * abscissa[..., None, :] * np.asarray(ifov)[..., None, None]
                 * positions[:, None])
        inverse = 1.0 / abscissa[..., None, :]
        if not cosine:
            return trig_sine(phase) * inverse, None
        sin_phase, cos_phase = sine_cosine(phase)
        return sin_phase * inverse, cos_phase * inverse


def _apply_edge(kernel, otf_slice, weights, *args, n_out=1, **knobs):
    """``kernel`` over (OTF, weights, abscissa, *args) with ``frequency`` as the core dimension.

    The abscissa is the ``sine_frequency`` coordinate of ``weights`` (else its ``frequency``
    coordinate); it may carry sensor dimensions besides ``frequency`` when every sensor of a
    sweep has nodes of its own. Auxiliary coordinates of the OTF and the weights are dropped.
    """
    check_slice(otf_slice, weights)
    abscissa = weights.coords["sine_frequency"] if "sine_frequency" in weights.coords else (
        weights["frequency"])
    dtype = np.result_type(np.finfo(otf_slice.dtype).dtype, weights.dtype,
                           *(np.asarray(a).dtype for a in args))
    return apply_kernel(
        kernel, otf_slice.reset_coords(drop=True), weights.reset_coords(drop=True),
        abscissa.variable, *args, core=[["frequency"]] * 3 + [[]] * len(args),
        outputs=[()] * n_out, dtype=dtype, **knobs)


def edge_response(otf_slice, ifov, position, weights):
    r"""Normalised response to an ideal edge, at a distance from the edge.

    Parameters
    ----------
    otf_slice : xr.DataArray
        OTF (real or complex) sampled at the quadrature nodes along
        ``frequency``; other dimensions broadcast. [1]
    ifov : float or xr.DataArray
        Detector instantaneous field of view (pitch / focal length). [rad]
    position : float, array_like or xr.DataArray
        Distance from the edge; a 1-D array becomes dimension ``position``. [px]
    weights : xr.DataArray
        Quadrature weights from :func:`xbsm.quadrature.edge_quadrature` (or
        one of its building blocks) on the same ``frequency`` coordinate.
        [cycles/rad]

    Returns
    -------
    xr.DataArray
        Edge response, 0 far on the dark side and 1 far on the bright side,
        broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-63, written for a complex OTF :math:`H` so that asymmetric
    PSFs are handled too:

    .. math::

        ER(x) = \frac{1}{2} + \frac{1}{\pi}\sum_k c_k\,
                \frac{\operatorname{Re}H(f_k)\sin(2\pi w_k\theta x)
                      + \operatorname{Im}H(f_k)\cos(2\pi w_k\theta x)}{w_k}

    with weights :math:`c_k` and abscissae :math:`w_k` (the ``sine_frequency``
    coordinate of ``weights``; :math:`w_k = f_k` except in the pyBSM rule).
    The sine and cosine tables depend only on (frequency, position, ifov)
    and are computed once, then contracted with the OTF by a dot product.
    """
    out = _apply_edge(_edge_response_kernel, otf_slice, weights, ifov, _as_position(position))
    return named(out, "1", "edge response", references="IBSM Eq. 3-63")


def relative_edge_response(otf_slice, ifov, weights):
    r"""Relative edge response: the rise of the edge response across one pixel.

    Parameters
    ----------
    otf_slice : xr.DataArray
        OTF sampled at the quadrature nodes along ``frequency``. [1]
    ifov : float or xr.DataArray
        Detector IFOV. [rad]
    weights : xr.DataArray
        Quadrature weights on the same ``frequency`` coordinate. [cycles/rad]

    Returns
    -------
    xr.DataArray
        RER. [1]

    Notes
    -----
    IBSM Eq. 3-61:

    .. math:: RER = ER(+\tfrac{1}{2}) - ER(-\tfrac{1}{2})
    """
    rer = _apply_edge(_edge_terms_kernel, otf_slice, weights, ifov, eho=False)
    return named(rer, "1", "relative edge response", references="IBSM Eq. 3-61")


def edge_height_overshoot(otf_slice, ifov, weights):
    r"""Edge height overshoot: peak of the edge response 1 to 3 px from the edge.

    Parameters
    ----------
    otf_slice : xr.DataArray
        OTF sampled at the quadrature nodes along ``frequency``. [1]
    ifov : float or xr.DataArray
        Detector IFOV. [rad]
    weights : xr.DataArray
        Quadrature weights on the same ``frequency`` coordinate. [cycles/rad]

    Returns
    -------
    xr.DataArray
        EHO. [1]

    Notes
    -----
    IBSM Eq. 3-60 as corrected by Leachtenauer et al. (1997): with
    :math:`x_j = 1, 1.25, \dots, 3` px,

    .. math::

        EHO = \begin{cases}
              ER(1.25) & \text{if } ER(x_{j+1}) > ER(x_j)\ \forall j \\
              \max_j ER(x_j) & \text{otherwise}
              \end{cases}

    This is pyBSM 0.16.1's rule (strict increase; a NaN anywhere gives NaN).
    """
    eho = _apply_edge(_edge_terms_kernel, otf_slice, weights, ifov, rer=False)
    return named(eho, "1", "edge height overshoot", references="IBSM Eq. 3-60")


def edge_terms(otf_slice, ifov, weights):
    """RER and EHO from one evaluation of the edge response.

    Parameters
    ----------
    otf_slice : xr.DataArray
        OTF sampled at the quadrature nodes along ``frequency``. [1]
    ifov : float or xr.DataArray
        Detector IFOV. [rad]
    weights : xr.DataArray
        Quadrature weights on the same ``frequency`` coordinate. [cycles/rad]

    Returns
    -------
    xr.Dataset
        ``rer`` (IBSM Eq. 3-61) and ``eho`` (IBSM Eq. 3-60). [1]
    """
    rer, eho = _apply_edge(_edge_terms_kernel, otf_slice, weights, ifov, n_out=2)
    return dataset({
        "rer": named(rer, "1", "relative edge response", references="IBSM Eq. 3-61"),
        "eho": named(eho, "1", "edge height overshoot", references="IBSM Eq. 3-60"),
    })


SLICE_OUTPUTS = outputs(
    *(Output(f"{name}_{o}", "1", f"{long} along {o}", references=reference)
      for name, long, reference in (("rer", "relative edge response", "IBSM Eq. 3-61"),
                                    ("eho", "edge height overshoot", "IBSM Eq. 3-60"))
      for o in ("x", "y")),
    Output("rer", "1", "relative edge response (geometric mean)", references="IBSM Eq. 3-61"),
    Output("eho", "1", "edge height overshoot (geometric mean)", references="IBSM Eq. 3-60"),
)
"""What :func:`slice_terms` and :func:`slice_terms_arrays` return (besides the RER of the
unfiltered system along x and y, ``rer_unfiltered_x`` and ``rer_unfiltered_y``)."""


def _rer_mean_kernel(rer_x, rer_y):
    """Geometric mean of the two slices' RER; NaN unless both are positive.

    The product of two negative slices would otherwise pass for a resolved edge.
    """
    with np.errstate(invalid="ignore"):
        return np.where((rer_x > 0) & (rer_y > 0), np.sqrt(rer_x * rer_y), np.nan)


def _eho_mean_kernel(eho_x, eho_y):
    """Geometric mean of the two slices' EHO (NaN, without a warning, where it has none)."""
    with np.errstate(invalid="ignore"):
        return np.sqrt(eho_x * eho_y)


def slice_terms(filtered, unfiltered, ifov, weights, edge_otf: str) -> xr.Dataset:
    """RER and EHO of the x and y slices of a system OTF, and their geometric means.

    Parameters
    ----------
    filtered : xr.DataArray
        System OTF on ``frequency`` and ``orientation`` (x, y). [1]
    unfiltered : xr.DataArray or None
        The same without the post-processing filter (None: there is none). [1]
    ifov : xr.DataArray
        IFOV over ``orientation``. [rad]
    weights : xr.DataArray
        Quadrature weights on ``frequency`` (from :func:`xbsm.quadrature.edge_nodes`).
    edge_otf : {"real", "abs"}
        The OTF or its modulus.

    Returns
    -------
    xr.Dataset
        :data:`SLICE_OUTPUTS` and ``rer_unfiltered_x``, ``rer_unfiltered_y``; with
        ``error_weights`` on ``weights`` (the Gauss-Kronrod rule), also ``edge_error``
        (:func:`slice_terms_arrays`).
    """
    abscissa = weights.coords["sine_frequency"] if "sine_frequency" in weights.coords else (
        weights["frequency"])
    error = weights.coords.get("error_weights")
    otfs = [None if otf is None else otf.reset_coords(drop=True)
            for otf in (filtered, unfiltered)]
    slice_, orientation = ["frequency", "orientation"], ["orientation"]
    if error is None:
        out = apply_orchestrator(
            slice_terms_arrays, _ALL_SLICE_OUTPUTS, *otfs, weights.reset_coords(drop=True),
            abscissa.reset_coords(drop=True), ifov,
            core=[slice_, slice_, ["frequency"], ["frequency"], orientation],
            edge_otf=edge_otf)
        return dataset(out)
    out = apply_orchestrator(
        _slice_terms_estimated, _ESTIMATED_SLICE_OUTPUTS, *otfs,
        weights.reset_coords(drop=True), abscissa.reset_coords(drop=True),
        error.reset_coords(drop=True), ifov,
        core=[slice_, slice_, ["frequency"], ["frequency"], ["frequency"], orientation],
        edge_otf=edge_otf)
    return dataset(out)


def _slice_terms_estimated(filtered, unfiltered, weights, abscissa, error_weights, ifov,
                           edge_otf):
    return slice_terms_arrays(filtered, unfiltered, weights, abscissa, ifov, edge_otf,
                              error_weights=error_weights)


_ALL_SLICE_OUTPUTS = outputs(
    *SLICE_OUTPUTS.values(),
    *(Output(f"rer_unfiltered_{o}", "1", f"relative edge response along {o} without the "
             "post-processing filter", references="IBSM Eq. 3-61") for o in ("x", "y")),
)
_ESTIMATED_SLICE_OUTPUTS = outputs(
    *_ALL_SLICE_OUTPUTS.values(),
    Output("edge_error", "1", "NIIRS error the edge-response quadrature's own estimate allows"),
)


def slice_terms_arrays(filtered, unfiltered, weights, abscissa, ifov, edge_otf: str,
                       error_weights=None) -> dict:
    """:func:`slice_terms` on plain arrays (:data:`SLICE_OUTPUTS` and the unfiltered RERs).

    OTFs on (..., frequency, orientation), weights and abscissae on (..., frequency), ifov
    on (..., orientation); orientations x, y in that order. With ``error_weights`` (on
    the weights' axes: a rule's embedded error estimate), also ``edge_error``: the NIIRS
    error that estimate allows in any GIQE (``_niirs_error_bound``).
    """
    tables = None
    if error_weights is not None:  # one sine (and cosine) table for both OTFs
        # square pixels where every optical state has nodes of its own (an optics sweep,
        # whose largest array is this table): one orientation's table, broadcast against
        # both in the contraction, is the same table at half the cost (focal-length sweep:
        # 415 -> 247 us a scenario). With shared nodes the table is small and einsum
        # contracts a broadcast one more slowly (a jitter sweep: 13 -> 28 us), so both
        # orientations are kept there.
        ifov = np.asarray(ifov)
        square = (math.prod(np.shape(abscissa)[:-1]) > 1 and ifov.ndim > 0
                  and ifov.shape[-1] == 2 and filtered.shape[-1] == 2
                  and (unfiltered is None or unfiltered.shape[-1] == 2)
                  and bool((ifov[..., 0] == ifov[..., 1]).all()))
        tables = _edge_tables(abscissa[..., None, :], ifov[..., :1] if square else ifov,
                              cosine=edge_otf != "abs" and (
                                  np.iscomplexobj(filtered) or np.iscomplexobj(unfiltered)))

    def edge(system):
        system = np.abs(system) if edge_otf == "abs" else system
        if error_weights is None:
            return _edge_terms_kernel(np.swapaxes(system, -1, -2), weights[..., None, :],
                                      abscissa[..., None, :], ifov)
        return _edge_terms_error_kernel(np.swapaxes(system, -1, -2), weights[..., None, :],
                                        error_weights[..., None, :], abscissa[..., None, :],
                                        ifov, tables)

    rer, eho, *errors = edge(filtered)
    rer_x, rer_y, eho_x, eho_y = rer[..., 0], rer[..., 1], eho[..., 0], eho[..., 1]
    unfiltered, *unfiltered_errors = (rer, *errors[:1]) if unfiltered is None else (
        edge(unfiltered)[::2])
    unfiltered_x, unfiltered_y = unfiltered[..., 0], unfiltered[..., 1]
    out = {"rer_x": rer_x, "rer_y": rer_y, "eho_x": eho_x, "eho_y": eho_y,
           "rer": _rer_mean_kernel(rer_x, rer_y), "eho": _eho_mean_kernel(eho_x, eho_y),
           "rer_unfiltered_x": unfiltered_x, "rer_unfiltered_y": unfiltered_y}
    if error_weights is not None:
        d_rer, d_eho = errors
        out["edge_error"] = _niirs_error_bound(rer, eho, d_rer, d_eho, unfiltered,
                                                     unfiltered_errors[0])
    return out


_LN10 = np.log(10.0)


def _quadpack(relative):
    """QUADPACK's error of the Kronrod result from the relative Kronrod - Gauss difference.

    ``e min(1, (200 e)^1.5)`` (Piessens et al. 1983, QUADPACK ``qk15``): the difference
    measures the embedded Gauss rule's error, far larger than the Kronrod rule's once
    both converge; the 1.5 power is the rates' ratio the package's authors measured.
    """
    with np.errstate(all="ignore"):
        return relative * np.minimum(1.0, (200.0 * relative) ** 1.5)


def binning_niirs_error(rer_unfiltered_x, rer_unfiltered_y, relative):
    r"""Largest NIIRS change (GIQE 3, 4, 5) a relative error common to both slices' RER allows.

    The OTF's wavelength binning (:func:`xbsm.otf.system.binning_error_kernel`) moves the
    RER of both slices by about the same relative amount :math:`\epsilon`: GIQE 3 and 4
    change by at most :math:`3.32\,\epsilon/\ln 10`, GIQE 5 by
    :math:`(3.32 + 8|\log_{10}RER_5|^3)\,\epsilon/\ln 10`, with the sensitivities of
    ``_niirs_error_bound``. Plain numpy (or DataArray) arithmetic. [NIIRS]
    """
    lo = np.minimum(np.abs(rer_unfiltered_x), np.abs(rer_unfiltered_y))
    hi = np.maximum(np.abs(rer_unfiltered_x), np.abs(rer_unfiltered_y))
    with np.errstate(all="ignore"):
        log5 = np.abs(np.log10(np.cbrt(hi * lo * lo)))
    return (3.32 + 8.0 * log5**3) / _LN10 * relative


def _niirs_error_bound(rer, eho, d_rer, d_eho, rer_unfiltered, d_rer_unfiltered):
    r"""Largest NIIRS change (GIQE 3, 4, 5) that edge-term errors of the x and y slices allow.

    Parameters
    ----------
    rer, eho : numpy.ndarray
        RER and EHO of the two slices (last axis: x, y). [1]
    d_rer, d_eho : numpy.ndarray
        Their error estimates (EHO: the largest edge-response error at 1-3 px). [1]
    rer_unfiltered, d_rer_unfiltered : numpy.ndarray
        RER of the slices without the post-processing filter (GIQE 5) and its error. [1]

    Returns
    -------
    numpy.ndarray
        [NIIRS]; infinite where a slice's RER or EHO is zero and its estimate is not.

    Notes
    -----
    First order in the relative errors :math:`\epsilon_s = \delta RER_s / RER_s` (each
    through QUADPACK's :math:`\epsilon\min(1, (200\epsilon)^{1.5})`). GIQE 3
    and 4 use the geometric means (:math:`\delta\ln RER = \tfrac12\sum_s \epsilon_s`) with
    :math:`|\partial N/\partial\log_{10}RER| \le 3.32` and :math:`|\partial N/\partial
    H| \le 1.48` (GIQE 3's coefficients, the larger of GIQE 3 and 4); GIQE 5 uses
    :math:`(RER_{hi} RER_{lo}^2)^{1/3}` (weights 1/3, 2/3, bounded by 2/3 each) and
    :math:`|\partial N/\partial\log_{10}RER| \le 3.32 + 8|\log_{10}RER|^3` (the
    :math:`-2\log_{10}^4` term, at the SNR that maximises the other).
    """
    with np.errstate(all="ignore"):
        rel = _quadpack(np.where(d_rer > 0, d_rer / np.abs(rer), 0.0))
        rel_eho = _quadpack(np.where(d_eho > 0, d_eho / np.abs(eho), 0.0))
        mean_eho = np.sqrt(np.abs(eho[..., 0] * eho[..., 1]))
        giqe34 = (3.32 / _LN10 * 0.5 * rel.sum(axis=-1)
                  + 1.48 * 0.5 * mean_eho * rel_eho.sum(axis=-1))
        rel5 = _quadpack(np.where(d_rer_unfiltered > 0,
                                  d_rer_unfiltered / np.abs(rer_unfiltered), 0.0))
        lo = np.min(np.abs(rer_unfiltered), axis=-1)
        hi = np.max(np.abs(rer_unfiltered), axis=-1)
        log5 = np.abs(np.log10(np.cbrt(hi * lo * lo)))
        giqe5 = (3.32 + 8.0 * log5**3) / _LN10 * (2.0 / 3.0) * rel5.sum(axis=-1)
        return np.maximum(giqe34, giqe5)
