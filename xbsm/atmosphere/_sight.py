"""The line-of-sight machinery of ``"same-elevation"`` and the cubic rules.

Numpy kernels: which altitude tables each scenario reads, and where, so that every table
is read along a line of sight that leaves the target at the scenario's elevation angle
(:func:`along_sight`); the optical-path coordinate between them; and the values of the
components attenuated along the path (:func:`line_of_sight`). The curved-earth geometry is
``xbsm.geometry``'s kernels. Names without an underscore are used by the package's other
modules.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.special import erfcx

from ..constants import EARTH_RADIUS
from ..geometry import ground_range_at_elevation_kernel, slant_and_elevation_kernel
from ._cubic import optical_depth_cubic
from ._profile import profile_scale
from .database import ALTITUDE_GAP
from .rules import SCALE_HEIGHT, bracket, gather, interpolate, ln_interpolate

#: Components that the line-of-sight rules interpolate along it (indices of
#: TRANS, SURF_EMIS, GRND_RFLT: attenuated along the path; the path radiances are not).
ALONG_PATH = (0, 2, 4)
#: PTH_THRML, SOL_SCAT: path radiances, at fixed ground range.
ACROSS_PATH = (1, 3)


def optical_path_above(altitude, sin_elevation):
    """Optical path above ``altitude`` of a line of sight from the ground (numpy kernel).

    For extinction ``exp(-z / H)`` and the thin-shell path element
    ``dz / sqrt(sin^2 e + 2 z / R)``, the optical depth between two heights is
    proportional to the difference of this function (``H`` = ``rules.SCALE_HEIGHT``):
    ``erfcx(sqrt(k (sin^2 e + 2 h / R))) exp(-h / H)`` with ``k = R / (2 H)``.
    """
    k = EARTH_RADIUS / (2.0 * SCALE_HEIGHT)
    inside = k * (sin_elevation * sin_elevation + 2.0 * altitude / EARTH_RADIUS)
    return erfcx(np.sqrt(inside)) * np.exp(-altitude / SCALE_HEIGHT)


class Nadir(NamedTuple):
    """The cubic's four tables seen from straight above (``"extinction-profile"``).

    ``x`` (scenario, 4) the nodes' optical-path coordinate at nadir, ``weight`` the
    scenario's weight in it, ``outer`` (scenario, 3) as :class:`Sight`'s, ``position``
    the scenario's fraction of the height between the bracketing tables.
    """

    x: np.ndarray
    weight: np.ndarray
    outer: np.ndarray
    position: np.ndarray


class Sight(NamedTuple):
    """The line-of-sight rules' tables of each scenario (numpy arrays).

    ``tables`` holds the altitude index and the ground-range bracket ``(a, g0, g1, wg)``,
    each (scenario, table), of the tables read at the scenario's target elevation angle:
    the lower and upper brackets, then for the cubic rules the table below and
    the table above them. ``weight`` is the scenario's altitude weight in the
    optical-path coordinate, ``usable`` where both brackets can be read along the line of
    sight. For the cubic, ``outer`` (scenario, 3) says whether each outer table is usable
    and whether the lower outer node is the ground, and ``x`` (scenario, 4) is the
    optical-path coordinate of the four nodes; both None for ``"same-elevation"``.
    ``nadir`` is the same stencil at nadir for ``"extinction-profile"``, else None.
    """

    tables: tuple
    weight: np.ndarray
    usable: np.ndarray
    outer: np.ndarray | None
    x: np.ndarray | None
    nadir: Nadir | None

    def block(self, s: slice) -> Sight:
        """The scenarios ``s`` of every field."""
        nadir = None if self.nadir is None else self.nadir._make(f[s] for f in self.nadir)
        return Sight(tuple(t[s] for t in self.tables), self.weight[s], self.usable[s],
                     *(None if f is None else f[s] for f in (self.outer, self.x)), nadir)


def along_sight(altitude, ground_range, vis, alt, db, rule):
    """Tables, weight and usability of the line-of-sight rules (numpy kernel).

    Each table is read where a sensor at its altitude sees the target at the scenario's
    elevation angle (on an altitude node and at nadir, at the scenario's own ground
    range). A bracketing table without such a point (beyond the horizon or the
    coverage, no entry) makes the scenario fall back to the fixed-range rule; an outer
    table without one, or missing (below the lowest table, above 24.5 km), is left
    out of the cubic (a one-sided slope). ``rule`` is a :class:`~xbsm.atmosphere.Rule`.
    """
    a0, a1, _ = alt
    cubic = rule.cubic
    top = db.altitude.size - 1
    _, elevation = slant_and_elevation_kernel(altitude, ground_range, "stable", "target")
    sin_e, cos_e = np.sin(elevation)[:, None], np.cos(elevation)[:, None]
    # (scenario, table) arrays built as (table, scenario) and transposed: np.stack costs a
    # single scenario 6-7 us a call, np.array 2
    index = np.array((a0, a1, a0 - 1, a1 + 1) if cubic else (a0, a1)).T.copy()
    a = np.minimum(np.maximum(index, 0), top)
    node = db.altitude[a]
    same = (node == altitude[:, None]) | (ground_range == 0.0)[:, None]
    g = np.where(same, ground_range[:, None],
                 ground_range_at_elevation_kernel(sin_e, cos_e, node))
    last = db.ground_range[-1]
    g0, g1, wg = bracket(np.minimum(g, last), db.ground_range)
    covered = ((g <= last) & db.present[vis[:, None], a, g0] & db.present[vis[:, None], a, g1]
               & (elevation > 0.0)[:, None])
    usable = covered[:, 0] & covered[:, 1] & (db.altitude[a1] <= ALTITUDE_GAP[0])
    # optical path above each node: lower bracket, the scenario, upper bracket (, below,
    # above; the ground is the lower outer node below the lowest table)
    heights = [node[:, 0], altitude, node[:, 1]]
    ground = a0 == 0
    if cubic:
        heights += [np.where(ground, 0.0, node[:, 2]), node[:, 3]]
    heights = np.array(heights).T.copy()
    # along the line of sight and, for the extinction profile, straight up (one call)
    sines = np.array((sin_e, np.ones_like(sin_e))) if rule.profile else sin_e[None]
    x, weight = _optical_path_nodes(heights, sines, a0 == a1)
    if not cubic:
        return Sight((a, g0, g1, wg), weight[0], usable, None, None, None)
    exists = (~ground, (index[:, 3] <= top) & (node[:, 3] <= ALTITUDE_GAP[0]))
    outer = np.array((exists[0] & covered[:, 2], exists[1] & covered[:, 3], ground)).T.copy()
    nadir = None
    if rule.profile:
        x_up, weight_up = x[1], weight[1]
        with np.errstate(divide="ignore", invalid="ignore"):  # 0 / 0 on a node
            position = np.where(a0 == a1, 0.0,
                                (altitude - node[:, 0]) / (node[:, 1] - node[:, 0]))
        nadir = Nadir(x_up, weight_up, np.array((*exists, ground)).T.copy(), position)
    return Sight((a, g0, g1, wg), weight[0], usable, outer, x[0], nadir)


def _optical_path_nodes(heights, sines, on_node):
    """Optical-path coordinate of the cubic's nodes and the scenario's weight in it.

    ``heights`` (scenario, 3 or 5): lower bracket, the scenario, upper bracket (, the
    node below, the node above); ``sines`` (..., scenario, 1) the sines of the elevation
    angles to take them at. Returns the coordinate (..., scenario, 4) of below, lower,
    upper, above (None with three heights) and the weight (..., scenario) (0 on a node).
    """
    path = optical_path_above(heights, sines)
    with np.errstate(divide="ignore", invalid="ignore"):
        weight = np.where(on_node, 0.0,
                          (path[..., 0] - path[..., 1]) / (path[..., 0] - path[..., 2]))
    x = -path[..., [3, 0, 2, 4]] if heights.shape[1] == 5 else None
    return x, weight


def line_of_sight(cube, vis, sight, fixed_range, profile=None):
    """TRANS, SURF_EMIS, GRND_RFLT of the line-of-sight rules (numpy kernel).

    Ground range log-linear inside each table, then altitude along the line of sight:
    log-linear in the optical-path coordinate (``"same-elevation"``) or the cubic
    (``"optical-depth-cubic"``, ``_cubic.optical_depth_cubic``; ``"extinction-profile"``
    scales its increment by ``_profile.profile_scale`` of ``profile``, given for that
    rule only). ``fixed_range(components, where)`` gives the fixed-range rule's values,
    taken where the line of sight leaves a table.
    """
    a, g0, g1, wg = (t.T for t in sight.tables)  # (table, scenario)
    # every table at both ground ranges in one gather each: the brackets, then the outer
    near, far = (gather(cube, vis, a, g, ALONG_PATH) for g in (g0, g1))
    brackets = slice(0, 2)
    low, high = interpolate(near[brackets], far[brackets], wg[brackets], "log")
    out = interpolate(low, high, sight.weight, "log")
    if sight.x is not None:
        outer = slice(2, 4)
        beyond = ln_interpolate(near[outer], far[outer], wg[outer])
        scale = None if sight.nadir is None else profile_scale(vis, a, sight.nadir, profile)
        out = optical_depth_cubic(out, low, high, beyond, sight, a[0] == a[1], scale)
    fallback = ~sight.usable
    if fallback.any():  # the fixed-range rule where the line of sight leaves a table
        out[fallback] = fixed_range(ALONG_PATH, fallback)
    return out
