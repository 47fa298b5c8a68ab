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

import numpy as np
import xarray as xr

from .._kernels import apply_kernel, apply_orchestrator, dataset
from .._metadata import Output, named, outputs

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
        sine = weights * np.sin(phase) / abscissa
        if np.iscomplexobj(otf):
            cosine = weights * np.cos(phase) / abscissa
            integral = _sum_of_products(otf.real, sine) + _sum_of_products(otf.imag, cosine)
        else:
            integral = _sum_of_products(otf, sine)
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
        :data:`SLICE_OUTPUTS` and ``rer_unfiltered_x``, ``rer_unfiltered_y``.
    """
    abscissa = weights.coords["sine_frequency"] if "sine_frequency" in weights.coords else (
        weights["frequency"])
    otfs = [None if otf is None else otf.reset_coords(drop=True)
            for otf in (filtered, unfiltered)]
    slice_, orientation = ["frequency", "orientation"], ["orientation"]
    out = apply_orchestrator(
        slice_terms_arrays, _ALL_SLICE_OUTPUTS, *otfs, weights.reset_coords(drop=True),
        abscissa.reset_coords(drop=True), ifov,
        core=[slice_, slice_, ["frequency"], ["frequency"], orientation], edge_otf=edge_otf)
    return dataset(out)


_ALL_SLICE_OUTPUTS = outputs(
    *SLICE_OUTPUTS.values(),
    *(Output(f"rer_unfiltered_{o}", "1", f"relative edge response along {o} without the "
             "post-processing filter", references="IBSM Eq. 3-61") for o in ("x", "y")),
)


def slice_terms_arrays(filtered, unfiltered, weights, abscissa, ifov, edge_otf: str) -> dict:
    """:func:`slice_terms` on plain arrays (:data:`SLICE_OUTPUTS` and the unfiltered RERs).

    OTFs on (..., frequency, orientation), weights and abscissae on (..., frequency), ifov
    on (..., orientation); orientations x, y in that order.
    """
    def edge(system):
        system = np.abs(system) if edge_otf == "abs" else system
        return _edge_terms_kernel(np.swapaxes(system, -1, -2), weights[..., None, :],
                                  abscissa[..., None, :], ifov)

    rer, eho = edge(filtered)
    rer_x, rer_y, eho_x, eho_y = rer[..., 0], rer[..., 1], eho[..., 0], eho[..., 1]
    unfiltered = rer if unfiltered is None else edge(unfiltered)[0]
    unfiltered_x, unfiltered_y = unfiltered[..., 0], unfiltered[..., 1]
    return {"rer_x": rer_x, "rer_y": rer_y, "eho_x": eho_x, "eho_y": eho_y,
            "rer": _rer_mean_kernel(rer_x, rer_y), "eho": _eho_mean_kernel(eho_x, eho_y),
            "rer_unfiltered_x": unfiltered_x, "rer_unfiltered_y": unfiltered_y}
