"""The extinction profile of ``"extinction-profile"``, from the tables' nadir columns.

Numpy kernels. The profile is built once per :class:`~xbsm.atmosphere.database.Database`
(:func:`profile_of`, held as long as the database is) and scales the optical-depth
cubic's increment (:func:`profile_scale`). Names without an underscore are used by the
package's other modules.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np

from ..quadrature import legendre_nodes
from ._cubic import cubic_increment
from .database import ALTITUDE_GAP

#: Gauss-Legendre nodes of the extinction profile's integrals (its exponent is a quadratic
#: with coefficients below 10 on this database: 12 nodes solve for it, 8 integrate it, both
#: to double precision).
_PROFILE_FIT_NODES, _PROFILE_NODES = 12, 8


class ExtinctionProfile(NamedTuple):
    """Vertical extinction between the altitude tables, from their nadir columns.

    Interval ``i`` spans ``heights[i]`` to ``heights[i + 1]`` (the ground, then every
    table up to 24.5 km). Inside it the extinction is proportional to
    ``exp(slope * s + bulge * s * (1 - s))``, ``s`` the fraction of the interval's height,
    with ``mean`` that function's mean over the interval; ``exists`` where the profile
    could be built. Arrays (visibility, interval, wavelength); ``depth`` (visibility,
    height, wavelength) is the nadir optical depth at each height.
    """

    heights: np.ndarray
    depth: np.ndarray
    slope: np.ndarray
    bulge: np.ndarray
    mean: np.ndarray
    exists: np.ndarray

    def window(self, window) -> ExtinctionProfile:
        """The profile at the wavelengths ``window``."""
        return self._replace(**{f: getattr(self, f)[..., window] for f in self._fields[1:]})


#: Database -> its profile and the windows taken of it, for as long as the database lives
#: (a database is immutable).
_PROFILES = weakref.WeakKeyDictionary()


def profile_of(db, window=slice(None)) -> ExtinctionProfile:
    """The extinction profile of ``db`` at the wavelengths ``window`` (a slice).

    Computed once per database, each window once (a model call takes its band's).
    """
    held = _PROFILES.get(db)
    if held is None:
        held = _PROFILES.setdefault(db, {None: extinction_profile(db)})
    key = (window.start, window.stop, window.step)
    profile = held.get(key)
    if profile is None:
        profile = held.setdefault(key, held[None].window(window))
    return profile


def _interval_ends(mean):
    """Extinction at the bottom and top of each interval from the intervals' means.

    Akima's weights: at the node between intervals ``i - 1`` and ``i`` the value leans to
    the side whose means change less (``|k[i+1] - k[i]|`` weighs ``k[i-1]``,
    ``|k[i-1] - k[i-2]|`` weighs ``k[i]``), so a layer of uniform extinction keeps its
    value up to its edge; the plain average where both weights are 0. Beyond the first
    and last interval the end means are repeated. ``mean`` (visibility, interval,
    wavelength).
    """
    last = mean.shape[1] - 1
    i = np.arange(last + 1)

    def k(j):
        return mean[:, np.clip(j, 0, last)]

    def at_node(below2, below, above, above2):
        lean_below, lean_above = np.abs(above2 - above), np.abs(below - below2)
        total = lean_below + lean_above
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(total > 0.0, (lean_below * below + lean_above * above) / total,
                            0.5 * (below + above))

    return at_node(k(i - 2), k(i - 1), k(i), k(i + 1)), at_node(k(i - 1), k(i), k(i + 1),
                                                                   k(i + 2))


def extinction_profile(db) -> ExtinctionProfile:
    """The extinction profile of ``"extinction-profile"`` from ``db``'s nadir columns.

    The nadir entry of each table gives the vertical optical depth from the ground,
    -ln TRANS, so each interval's mean extinction is known; the extinction at its ends
    comes from :func:`_interval_ends`. Inside, ln(extinction) is the straight line between
    the ends plus ``bulge * s * (1 - s)``, with ``bulge`` solved (Newton) so the mean is
    the interval's: a boundary layer that stays uniform and then drops inside an interval
    gets a positive bulge. Where a mean or an end is not positive and finite (TRANS 0 at
    the database floor) or the solve does not converge, ``exists`` is False. Only the
    tables in ``db`` are used (the leave-one-out recipe removes some).
    """
    tables = db.altitude <= ALTITUDE_GAP[0]
    heights = np.concatenate(([0.0], db.altitude[tables]))
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = -np.log(db.cube[:, tables, 0, 0, :].astype(np.float64))
        depth = np.concatenate((np.zeros_like(depth[:, :1]), depth), axis=1)
        mean = np.diff(depth, axis=1) / np.diff(heights)[:, None]
        bottom, top = _interval_ends(mean)
        exists = np.isfinite(mean + bottom + top) & (mean > 0.0) & (bottom > 0.0) & (top > 0.0)
        slope = np.where(exists, np.log(top / bottom), 0.0)
        relative = np.where(exists, mean / bottom, 1.0)  # the mean of exp(slope s + bulge ...)
    nodes, weights = legendre_nodes(_PROFILE_FIT_NODES)
    s = 0.5 * (nodes + 1.0)
    s_bulge, weights = s * (1.0 - s), 0.5 * weights
    bulge = np.zeros_like(slope)
    for _ in range(40):  # convex and increasing in the bulge: Newton from 0 (about 6 steps)
        g = np.exp(slope[..., None] * s + bulge[..., None] * s_bulge)
        miss = g @ weights - relative
        converged = np.abs(miss) <= 1e-12 * relative
        if converged.all():
            break
        bulge = np.clip(bulge - miss / ((g * s_bulge) @ weights), -30.0, 30.0)
    exists &= converged
    return ExtinctionProfile(heights, depth, slope, np.where(exists, bulge, 0.0), relative,
                             exists)


def profile_scale(vis, a, nadir, profile):
    """``"extinction-profile"``'s factor on the cubic's increment (scenario, wavelength).

    Straight down, the extinction profile (:func:`extinction_profile`) gives the optical
    depth between the lower bracketing table and the scenario's altitude; the factor is
    that over the cubic's own value at nadir (the same four tables' nadir entries, the
    same coordinate at sin e = 1). 1 on a node and where the profile does not exist or
    the factor is not finite and positive. ``a`` (table, scenario) as in
    ``_sight.line_of_sight``; ``nadir`` a ``_sight.Nadir``; ``profile`` at the kernel's
    wavelengths. The factor depends on the visibility and the altitude only, so it is
    computed once for each distinct pair (a sweep over ground range shares it).
    """
    if vis.size < 2:
        return _nadir_factor(vis, a, nadir, profile)
    key = np.stack((vis, a[0], a[1], nadir.position))
    _, first, inverse = np.unique(key, axis=1, return_index=True, return_inverse=True)
    if first.size == vis.size:
        return _nadir_factor(vis, a, nadir, profile)
    factor = _nadir_factor(vis[first], a[:, first], nadir._make(f[first] for f in nadir),
                           profile)
    return factor[inverse.reshape(-1)]


@np.errstate(divide="ignore", invalid="ignore", over="ignore")
def _nadir_factor(vis, a, nadir, profile):
    """:func:`profile_scale` of each scenario given."""
    # ln of nadir TRANS (table, scenario, wavelength); a table above 24.5 km (only ever an
    # outer one, left out of the cubic) reads the last height's
    ln_t = -profile.depth[vis, np.minimum(a + 1, profile.heights.size - 1)]
    outer = nadir.outer
    ground = outer[:, 2, None]
    y0 = np.where(ground, 0.0, ln_t[2])
    step = cubic_increment((y0, ln_t[0], ln_t[1], ln_t[3]),
                           [nadir.x[:, k, None] for k in range(4)], nadir.weight[:, None],
                           (outer[:, 0, None] | ground) & np.isfinite(y0),
                           outer[:, 1, None] & np.isfinite(ln_t[3]))
    # the profile's intervals start at the ground; from 24.5 km up the scenario is on a
    # node or falls back, so any interval will do
    interval = np.minimum(a[0] + 1, profile.slope.shape[1] - 1)
    slope, bulge, mean, exists = (f[vis, interval] for f in (profile.slope, profile.bulge,
                                                             profile.mean, profile.exists))
    nodes, weights = legendre_nodes(_PROFILE_NODES)
    position = nadir.position[:, None]
    s = 0.5 * position[..., None] * (nodes + 1.0)  # Gauss-Legendre on [0, position]
    inside = np.exp(slope[..., None] * s + bulge[..., None] * (s * (1.0 - s))) @ weights
    fraction = 0.5 * position * inside / mean  # of the interval's nadir optical depth
    factor = fraction * (ln_t[1] - ln_t[0]) / step
    return np.where(exists & np.isfinite(factor) & (factor > 0.0), factor, 1.0)
