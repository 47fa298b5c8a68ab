"""The named interpolation rules between database nodes, and the fixed-range steps.

:data:`RULES` is the one dispatch table: each name of ``interpolation=`` maps to a
:class:`Rule` whose fields say what the rule does (its value rule between the
bracketing tables, its altitude coordinate, whether it follows the line of sight, the
cubic, the extinction profile); the machinery reads those fields, never the name.

The fixed-range rules (``"exact"``, ``"linear"`` = pyBSM 0.16.1's
``load_database_atmosphere``, ``"log-linear"``) interpolate in altitude at the two
bracketing ground ranges, then in ground range (pyBSM's order), with :func:`bracket` and
:func:`interpolate`; the line-of-sight rules use them for the path radiances and where
they fall back. These are numpy kernels: plain arrays in and out, no checks.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

__all__ = [
    "INTERPOLATIONS",
    "RULES",
    "SCALE_HEIGHT",
    "Rule",
    "bracket",
    "fixed_range",
    "gather",
    "interpolate",
    "ln_interpolate",
]


@dataclass(frozen=True)
class Rule:
    """What one named interpolation rule does (a row of :data:`RULES`)."""

    #: The name of ``interpolation=``.
    name: str
    #: Value rule between two bracketing tables, in altitude and in ground range:
    #: ``"linear"`` or ``"log"`` (:func:`interpolate`).
    value: str
    #: The altitude weight is linear in log(altitude) (else in altitude).
    log_altitude: bool
    #: Only database nodes are accepted (any other altitude or ground range raises).
    nodes_only: bool = False
    #: TRANS, SURF_EMIS, GRND_RFLT follow the line of sight between altitude tables.
    line_of_sight: bool = False
    #: ... through a monotone cubic in the optical-path coordinate over four tables.
    cubic: bool = False
    #: ... with the cubic's increment scaled to the nadir extinction profile.
    profile: bool = False


#: ``interpolation`` -> :class:`Rule`, in the order the docs present them.
RULES = MappingProxyType({rule.name: rule for rule in (
    Rule("exact", "linear", log_altitude=False, nodes_only=True),
    Rule("linear", "linear", log_altitude=False),
    Rule("log-linear", "log", log_altitude=True),
    # the line-of-sight rules: "log-linear" for the path radiances and where they fall back
    Rule("same-elevation", "log", log_altitude=True, line_of_sight=True),
    Rule("optical-depth-cubic", "log", log_altitude=True, line_of_sight=True, cubic=True),
    Rule("extinction-profile", "log", log_altitude=True, line_of_sight=True, cubic=True,
         profile=True),
)})
#: Accepted values of ``interpolation``.
INTERPOLATIONS = tuple(RULES)
#: Scale height of the extinction profile behind the line-of-sight rules' altitude coordinate:
#: 2 km is the best of 0.5-3 km in the altitude leave-one-out (docs/atmosphere.md). [m]
SCALE_HEIGHT = 2000.0


def bracket(values, nodes, log=False):
    """Lower/upper node index and weight of the upper node (0 exactly on a node).

    Parameters
    ----------
    values : numpy.ndarray
        Points inside ``[nodes[0], nodes[-1]]``.
    nodes : numpy.ndarray
        Increasing database nodes.
    log : bool
        Weight linear in the logarithm of the value (else in the value).

    Returns
    -------
    tuple of numpy.ndarray
        ``(lower, upper, weight)``; the weight is ``(x - x0) / (x1 - x0)``, pyBSM's
        expression, with ``x`` the value itself or, if ``log``, its logarithm.
    """
    lower = np.maximum(nodes.searchsorted(values, side="right") - 1, 0)  # <= size - 1
    x, x0 = values, nodes[lower]
    on_node = x0 == values
    upper = np.where(on_node, lower, np.minimum(lower + 1, nodes.size - 1))
    x1 = nodes[upper]
    if log:
        x, x0, x1 = np.log(x), np.log(x0), np.log(x1)
    span = np.where(on_node, 1.0, x1 - x0)
    weight = np.where(on_node, 0.0, (x - x0) / span)
    return lower, upper, weight


def interpolate(low, high, weight, rule):
    """One interpolation step between two gathered spectra (weight of ``high``).

    Parameters
    ----------
    low, high : numpy.ndarray
        Spectra (..., component, wavelength) of the two bracketing tables.
    weight : numpy.ndarray
        Weight of ``high`` (...), from :func:`bracket`.
    rule : {"linear", "log"}
        :attr:`Rule.value`.

    Returns
    -------
    numpy.ndarray
        Linear: ``(1 - w) * low + w * high``, pyBSM's expression and operation order.
        Log: ``low * exp(w * (log(high) - log(low)))`` where both are positive, which
        returns ``low`` exactly when ``w == 0`` or ``high is low``; linear elsewhere.
    """
    w = weight[..., None, None]
    if rule == "linear":
        return (1.0 - w) * low + w * high
    positive = (low > 0.0) & (high > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_step = np.log(high) - np.log(low)
        logged = low * np.exp(w * log_step)
    if positive.all():
        return logged
    return np.where(positive, logged, (1.0 - w) * low + w * high)


def ln_interpolate(low, high, weight):
    """Natural logarithm of ``interpolate(low, high, weight, "log")``, without its exp.

    Parameters
    ----------
    low, high, weight : numpy.ndarray
        As for :func:`interpolate`.

    Returns
    -------
    numpy.ndarray
        The logarithm of the log-rule step (-inf where it is 0).
    """
    w = weight[..., None, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        ln_low, ln_high = np.log(low), np.log(high)
        out = ln_low + w * (ln_high - ln_low)
        linear = ~((low > 0.0) & (high > 0.0))
        if linear.any():
            np.log((1.0 - w) * low + w * high, out=out, where=linear)
    return out


def gather(cube, vis, a, g, components):
    """Spectra of the tables ``(vis, a, g)`` of ``cube`` as float64.

    Parameters
    ----------
    cube : numpy.ndarray
        (visibility, altitude, ground_range, component, wavelength).
    vis, a, g : numpy.ndarray of int
        Table indices; ``a`` and ``g`` may carry a leading axis of tables before the
        scenario axis.
    components : sequence of int or None
        Component indices to keep (None: all).

    Returns
    -------
    numpy.ndarray
        (..., component, wavelength).
    """
    spectra = cube[vis, a, g]  # whole (component, wavelength) blocks: the fastest gather
    if components is not None:
        spectra = spectra[..., components, :]
    return spectra.astype(np.float64)


def fixed_range(cube, vis, alt, gr, rule, components=None):
    """A fixed-range rule: altitude at both bracketing ground ranges, then ground range.

    Parameters
    ----------
    cube : numpy.ndarray
        As for :func:`gather`.
    vis : numpy.ndarray of int
        Visibility index of each scenario.
    alt, gr : tuple of numpy.ndarray
        :func:`bracket` of each scenario's altitude and ground range.
    rule : {"linear", "log"}
        :attr:`Rule.value`.
    components : sequence of int, optional
        As for :func:`gather`.

    Returns
    -------
    numpy.ndarray
        (scenario, component, wavelength), in pyBSM's order of the two steps.
    """
    (a0, a1, wa), (g0, g1, wg) = alt, gr
    ranges = np.array((g0, g1))  # np.stack's checks cost a single scenario 3 us a call
    by_range = interpolate(gather(cube, vis, a0, ranges, components),
                           gather(cube, vis, a1, ranges, components), np.array((wa, wa)), rule)
    return interpolate(by_range[0], by_range[1], wg, rule)
