"""Archived: the candidate altitude rules of the atmosphere study (issue 12) that lost.

Each candidate interpolates across altitude through more than the two bracketing tables;
the first, "cubic, optical path H=2 km", is the prototype of the package's
"optical-depth-cubic" (the package reads only the four tables of its stencil), the others
never entered the package. The table this prints, next to the package's
"same-elevation", "optical-depth-cubic" and "extinction-profile" on the same altitude and
ground-range leave-one-out, is where the candidate numbers in docs/atmosphere.md
(sections "optical-depth-cubic" and "extinction-profile") come from. Not maintained with
the package's rules: it is kept so those numbers can be reproduced; the maintained
leave-one-out is ``recipes/evidence/atmosphere_leave_one_out.py``, whose scoring it reuses.

Run from the repository root with the project environment (about 20 s)::

    .venv/bin/python recipes/evidence/archive/atmosphere_candidate_rules.py
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import numpy as np
from scipy.special import erfcx

from xbsm.atmosphere import (
    ALTITUDE_GAP,
    COMPONENTS,
    SCALE_HEIGHT,
    interpolate_database,
    load_database,
)
from xbsm.atmosphere.rules import bracket, interpolate
from xbsm.constants import EARTH_RADIUS
from xbsm.geometry import ground_range_at_elevation_kernel, slant_range, target_elevation_angle

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/evidence/
from atmosphere_leave_one_out import WAVELENGTHS_UM, cell, kernel_errors  # noqa: E402

# --- Candidate altitude rules from more than two tables (issue 12) -------------------------
# The first is the package's "optical-depth-cubic" (its prototype: the package reads only
# the four tables of the stencil and, in the lowest interval, also uses the table above
# for the slopes of SURF_EMIS and GRND_RFLT); the others are not in the package
# (docs/atmosphere.md, "optical-depth-cubic").
# Each reads every altitude table up to 24.5 km along the scenario's line of
# sight, as "same-elevation" reads its two brackets, and interpolates across altitude
# through the brackets and the tables beyond them (and the ground, where the optical
# depth is 0), vectorised over scenarios and wavelengths.

_ALONG = (0, 2, 4)  # TRANS, SURF_EMIS, GRND_RFLT: the components attenuated along the path


def _same_elevation_logs(db, altitude, ground_range, visibility):
    """ln of TRANS, SURF_EMIS, GRND_RFLT in every table up to 24.5 km at the scenario's
    target elevation angle (log-linear in ground range), and where each table covers it."""
    v = np.searchsorted(-db.visibility, -visibility)
    elevation = target_elevation_angle(slant_range(ground_range, altitude), altitude)
    sin_e, cos_e = np.sin(elevation), np.cos(elevation)
    nodes = db.altitude[db.altitude <= ALTITUDE_GAP[0]]
    last = db.ground_range[-1]
    logs = np.empty((altitude.size, nodes.size, len(_ALONG), db.cube.shape[-1]))
    covered = np.empty((altitude.size, nodes.size), dtype=bool)
    for j, node in enumerate(nodes):  # a loop over the 22 tables, not over scenarios
        same = (node == altitude) | (ground_range == 0.0)
        g = np.where(same, ground_range, ground_range_at_elevation_kernel(sin_e, cos_e, node))
        g0, g1, wg = bracket(np.minimum(g, last), db.ground_range)
        covered[:, j] = (elevation > 0.0) & (g <= last) & db.present[v, j, g0] & \
            db.present[v, j, g1]
        low = db.cube[v, j, g0][:, _ALONG].astype(np.float64)
        high = db.cube[v, j, g1][:, _ALONG].astype(np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            logs[:, j] = np.log(interpolate(low, high, wg, "log"))
    return nodes, logs, covered, sin_e


def _path_coordinate(kind, altitude, sin_e, scale_height):
    """The altitude coordinate of the interpolation along a line of sight of elevation e.

    "altitude"; "sqrt-altitude"; "slant" (path length from the target up to the
    altitude, spherical Earth); "optical-path" (the optical depth of that path in an
    exponential atmosphere of the given scale height, thin-shell path element: the
    coordinate in which "same-elevation" is linear).
    """
    if kind == "altitude":
        return altitude
    if kind == "sqrt-altitude":
        return np.sqrt(altitude)
    if kind == "slant":
        above = altitude * (2.0 * EARTH_RADIUS + altitude)
        rise = EARTH_RADIUS * sin_e
        return above / (np.sqrt(rise * rise + above) + rise)
    k = EARTH_RADIUS / (2.0 * scale_height)

    def above_(h):
        return erfcx(np.sqrt(k * (sin_e * sin_e + 2.0 * h / EARTH_RADIUS))) * np.exp(
            -h / scale_height)

    return scale_height * (above_(0.0 * altitude) - above_(altitude))


def _interior_slope(h_left, h_right, s_left, s_right, slopes):
    """Derivative at a node between two intervals: PCHIP (Fritsch-Butland weighted
    harmonic mean, scipy's) or Steffen's; 0 at a local extremum."""
    with np.errstate(divide="ignore", invalid="ignore"):
        if slopes == "steffen":
            p = (s_left * h_right + s_right * h_left) / (h_left + h_right)
            d = (np.sign(s_left) + np.sign(s_right)) * np.minimum(
                np.minimum(np.abs(s_left), np.abs(s_right)), 0.5 * np.abs(p))
            return np.where(np.isfinite(d), d, 0.0)
        w1, w2 = 2.0 * h_right + h_left, h_right + 2.0 * h_left
        d = (w1 + w2) / (w1 / s_left + w2 / s_right)
    monotone = (np.sign(s_left) == np.sign(s_right)) & (s_left != 0.0) & (s_right != 0.0)
    return np.where(monotone, d, 0.0)


def _end_slope(h_near, h_far, s_near, s_far):
    """scipy's PCHIP derivative at the end node of two intervals (shape-preserving)."""
    d = ((2.0 * h_near + h_far) * s_near - h_near * s_far) / (h_near + h_far)
    d = np.where(np.sign(d) != np.sign(s_near), 0.0, d)
    overshoot = (np.sign(s_near) != np.sign(s_far)) & (np.abs(d) > 3.0 * np.abs(s_near))
    return np.where(overshoot, 3.0 * s_near, d)


def _monotone_cubic(x, y, outer, target, slopes):
    """Monotone cubic Hermite value in [x1, x2] of the stencil (x0, x1, x2, x3).

    ``x`` (n, 4) or, a coordinate per wavelength, (n, 4, wavelength) with ``target``
    (n, wavelength); ``y`` (n, 4, wavelength); ``outer`` (n, 2): whether x0 and x3 exist
    (a missing or infinite outer value gives the one-sided end derivative, or the
    secant without either).
    """
    per_wavelength = x.ndim == 3  # a coordinate per wavelength: x (n, 4, wavelength)
    X = [x[:, k] if per_wavelength else x[:, k, None] for k in range(4)]
    Y = [y[:, k] for k in range(4)]
    h0, h1, h2 = X[1] - X[0], X[2] - X[1], X[3] - X[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        s0, s1, s2 = (Y[1] - Y[0]) / h0, (Y[2] - Y[1]) / h1, (Y[3] - Y[2]) / h2
    t = ((target if per_wavelength else target[:, None]) - X[1]) / h1
    left = outer[:, 0, None] & np.isfinite(Y[0])
    right = outer[:, 1, None] & np.isfinite(Y[3])
    d1 = np.where(left, _interior_slope(h0, h1, s0, s1, slopes),
                  np.where(right, _end_slope(h1, h2, s1, s2), s1))
    d2 = np.where(right, _interior_slope(h1, h2, s1, s2, slopes),
                  np.where(left, _end_slope(h1, h0, s1, s0), s1))
    t2, t3 = t * t, t * t * t
    return ((t3 - 2.0 * t2 + t) * h1 * d1 + (-2.0 * t3 + 3.0 * t2) * (Y[2] - Y[1])
            + (t3 - t2) * h1 * d2)  # the increment over y1


@np.errstate(divide="ignore", invalid="ignore")
def multi_node(db, altitude, ground_range, visibility, *, coordinate="optical-path",
               scale_height=SCALE_HEIGHT, slopes="pchip", others="own"):
    """Candidate rule: TRANS, SURF_EMIS, GRND_RFLT by a monotone cubic through the tables.

    The optical depth -ln TRANS of the line of sight is 0 at the ground and grows
    monotonically with altitude at a fixed elevation angle (a lower path is a prefix
    of a higher one), so it is interpolated through the ground and the bracketing
    tables and one table beyond each (PCHIP's or Steffen's slopes, four-point
    stencil: the same value as a monotone cubic through all the nodes) in
    ``coordinate`` (see :func:`_path_coordinate`). ``scale_height`` may be a callable
    ``(db, altitude, visibility) -> (scenario, wavelength)`` scale heights taken from the
    database's own nadir columns (:func:`global_scale_heights`,
    :func:`local_scale_heights`): the coordinate is then one per wavelength.
    ``coordinate="nadir-column"`` uses the vertical optical depth of the nadir columns
    itself (exact in the plane-parallel limit), at the scenario's altitude the package
    cubic's at ground range 0; the package rule where the columns do not increase
    through the stencil. ``slopes="exp-fit"`` instead fits
    the optical depth of the extinction ``a exp(-z / H) + b`` to the two brackets and
    the ground (linear in ``coordinate`` where a or b comes out negative).

    SURF_EMIS and GRND_RFLT (``others``): "own", ln of the value by the same cubic
    through the tables only (no ground node); "ratio", ln(C / TRANS) linear in the
    coordinate between the brackets, times the interpolated TRANS.

    The path radiances, and every scenario where a bracket is not covered or a value
    is not positive, are ``"same-elevation"``'s. Returns (scenario, component, wavelength).
    """
    base = interpolate_database(db, altitude, ground_range, visibility, "same-elevation",
                                 slice(None))
    nodes, logs, covered, sin_e = _same_elevation_logs(db, altitude, ground_range, visibility)
    n = altitude.size
    # the ground is node 0: altitude 0, optical depth 0
    heights = np.concatenate([[0.0], nodes])
    if coordinate == "nadir-column":  # the vertical optical depth of the nadir columns
        v = np.searchsorted(-db.visibility, -visibility)
        with np.errstate(divide="ignore"):
            column = -np.log(db.cube[:, :nodes.size, 0, 0, :].astype(np.float64))
        x_nodes = np.concatenate([np.zeros((n, 1, column.shape[-1])), column[v]], axis=1)
        nadir = interpolate_database(db, altitude, 0.0 * altitude, visibility,
                                      "optical-depth-cubic", slice(None))
        nadir_target = -np.log(nadir[:, 0])  # the package's cubic at ground range 0
    elif callable(scale_height):  # a scale height per (visibility, wavelength) of the database
        if slopes == "exp-fit":
            raise ValueError("exp-fit takes one scale height")
        scale_height = scale_height(db, altitude, visibility)[:, None, :]  # (scenario, 1, wl)
        x_nodes = _path_coordinate(coordinate, heights[None, :, None], sin_e[:, None, None],
                                   scale_height)  # (scenario, node, wavelength)
    else:
        x_nodes = np.broadcast_to(
            _path_coordinate(coordinate, heights[None, :], sin_e[:, None], scale_height),
            (n, heights.size))
    tau = np.concatenate([np.zeros((n, 1, logs.shape[-1])), -logs[:, :, 0]], axis=1)
    lnc = np.concatenate([np.full((n, 1, 2, logs.shape[-1]), np.nan), logs[:, :, 1:]], axis=1)
    covered = np.concatenate([np.ones((n, 1), dtype=bool), covered], axis=1)
    a0, a1, _ = bracket(altitude, nodes)
    on_node = a0 == a1
    i1 = a0 + 1
    i2 = np.minimum(np.where(on_node, a0 + 2, a1 + 1), nodes.size)
    i3 = np.minimum(i2 + 1, nodes.size)
    stencil = np.stack([i1 - 1, i1, i2, i3], axis=1)
    rows = np.arange(n)[:, None]
    x, ok = x_nodes[rows, stencil], covered[rows, stencil]
    ok[:, 3] &= i3 > i2
    if coordinate == "nadir-column":
        target = nadir_target
        t = (target - x[:, 1]) / (x[:, 2] - x[:, 1])
    elif x.ndim == 3:
        target = _path_coordinate(coordinate, altitude[:, None], sin_e[:, None],
                                  scale_height[:, 0])  # (scenario, wavelength)
        t = (target - x[:, 1]) / (x[:, 2] - x[:, 1])
    else:
        target = _path_coordinate(coordinate, altitude, sin_e, scale_height)
        t = ((target - x[:, 1]) / (x[:, 2] - x[:, 1]))[:, None]
    y = tau[rows, stencil]
    if slopes == "exp-fit":
        # tau(h) = a X(h) + b s(h) through tau(h0), tau(h1) (tau(0) = 0); Cramer's rule
        s = _path_coordinate("slant", heights[stencil[:, 1:3]], sin_e[:, None], 0.0)
        s_t = _path_coordinate("slant", altitude, sin_e, 0.0)
        det = (x[:, 1] * s[:, 1] - s[:, 0] * x[:, 2])[:, None]
        a = (y[:, 1] * s[:, 1, None] - s[:, 0, None] * y[:, 2]) / det
        b = (x[:, 1, None] * y[:, 2] - y[:, 1] * x[:, 2, None]) / det
        fitted = a * target[:, None] + b * s_t[:, None] - y[:, 1]
        step = np.where((a >= 0.0) & (b >= 0.0), fitted, t * (y[:, 2] - y[:, 1]))
    else:
        step = _monotone_cubic(x, y, ok[:, [0, 3]], target, slopes)
    step = np.where(on_node[:, None], 0.0, step)
    out = base.copy()
    out[:, 0] = np.exp(-(y[:, 1] + step))
    for k, component in ((1, 2), (2, 4)):
        c = lnc[rows, stencil, k - 1]
        if others == "ratio":
            ratio = c + y  # ln(C / TRANS)
            weight = np.where(on_node[:, None], 0.0, t)
            ln_ratio = ratio[:, 1] + weight * (ratio[:, 2] - ratio[:, 1])
            out[:, component] = np.exp(ln_ratio + np.log(out[:, 0]))
        else:
            c_step = _monotone_cubic(x, c, ok[:, [0, 3]] & (stencil[:, [0]] > 0), target, slopes
                                     if slopes != "exp-fit" else "pchip")
            out[:, component] = np.exp(c[:, 1] + np.where(on_node[:, None], 0.0, c_step))
    top = db.altitude[np.minimum(a1, db.altitude.size - 1)]
    usable = ok[:, 1] & ok[:, 2] & (top <= ALTITUDE_GAP[0])
    along = out[:, _ALONG]
    bad = ~usable[:, None, None] | ~np.isfinite(along) | (along <= 0.0)
    out[:, _ALONG] = np.where(bad, base[:, _ALONG], along)
    if coordinate == "nadir-column":  # the package's rule where the columns are no coordinate
        increasing = (np.diff(x, axis=1) > 0.0).all(axis=1) & np.isfinite(x).all(axis=1)
        cubic = interpolate_database(db, altitude, ground_range, visibility,
                                      "optical-depth-cubic", slice(None))
        out[:, _ALONG] = np.where(increasing[:, None], out[:, _ALONG], cubic[:, _ALONG])
    return out


def fitted_scale_heights(db, top=20000.0, floor=1e-3, fallback=SCALE_HEIGHT,
                         bounds=(100.0, 50000.0)):
    """Scale height H of each (visibility, wavelength) fitted to the database's nadir columns.

    The nadir entry (ground range 0) of each altitude table up to ``top`` gives the
    vertical optical depth from the ground, tau(h) = -ln TRANS(h, nadir); the fit is
    tau(h) = tau_inf (1 - exp(-h / H)), least squares in the residual relative to
    tau + ``floor`` (relative where tau is large, absolute where it is small), H on a
    log grid within ``bounds`` (tau_inf in closed form for each). Only the tables in
    ``db`` are used (the leave-one-out's thinned database). ``fallback`` where the fit
    is ill-posed: fewer than 3 usable nodes (TRANS 0, i.e. below the database floor,
    or missing), a column that does not grow, or a best H at an end of the grid.
    Returns (visibility, wavelength) [m].
    """
    keep = (db.altitude <= top) & db.present[:, :, 0].all(axis=0)
    h = db.altitude[keep]
    with np.errstate(divide="ignore"):
        tau = -np.log(db.cube[:, keep, 0, 0, :].astype(np.float64))  # (vis, node, wl)
    usable = np.isfinite(tau) & (tau > 0.0)
    weight = np.where(usable, 1.0 / (np.where(usable, tau, 0.0) + floor) ** 2, 0.0)
    tau = np.where(usable, tau, 0.0)
    grid = np.geomspace(*bounds, 241)
    basis = -np.expm1(-h[None, :] / grid[:, None])  # (H, node)
    # weighted least squares of tau_inf for each H: sum w f tau / sum w f^2
    wf_tau = np.einsum("gn,vnw->gvw", basis, weight * tau)
    wf2 = np.einsum("gn,vnw->gvw", basis ** 2, weight)
    wt2 = np.einsum("vnw->vw", weight * tau ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        residual = wt2[None] - wf_tau ** 2 / wf2  # (H, vis, wl)
    residual = np.where(np.isfinite(residual), residual, np.inf)
    best = np.argmin(residual, axis=0)
    grows = np.take_along_axis(tau, np.argmax(usable * h[None, :, None], axis=1)[:, None],
                               axis=1)[:, 0] > np.where(usable, tau, np.inf).min(axis=1)
    posed = ((usable.sum(axis=1) >= 3) & grows & (best > 0) & (best < grid.size - 1)
             & np.isfinite(residual.min(axis=0)))
    return np.where(posed, grid[best], fallback)


def global_scale_heights(db, altitude, visibility, **fit):
    """(scenario, wavelength) scale heights of :func:`fitted_scale_heights`."""
    return fitted_scale_heights(db, **fit)[np.searchsorted(-db.visibility, -visibility)]


def local_scale_heights(db, altitude, visibility, fallback=SCALE_HEIGHT,
                        bounds=(100.0, 50000.0), intervals=2):
    """(scenario, wavelength) scale heights from the nadir columns around each scenario.

    The mean vertical extinction of the interval below the bracketing tables (from the
    table below the lower bracket, or the ground) and of the interval above them (to the
    table above the upper bracket) give H = (distance of the intervals' midpoints) /
    ln(ratio of the extinctions); ``fallback`` where either is missing, not positive or
    not finite, or H is outside ``bounds``. ``intervals=3`` also uses the interval
    between the brackets: H from the least-squares slope of ln(extinction) against the
    three midpoints. Only the tables in ``db`` are used.
    """
    v = np.searchsorted(-db.visibility, -visibility)
    nodes = db.altitude[db.altitude <= ALTITUDE_GAP[0]]
    heights = np.concatenate([[0.0], nodes])
    with np.errstate(divide="ignore"):
        tau = -np.log(db.cube[:, :nodes.size, 0, 0, :].astype(np.float64))
    tau = np.concatenate([np.zeros_like(tau[:, :1]), tau], axis=1)  # the ground: 0
    a0, a1, _ = bracket(altitude, nodes)
    lo = a0 + 1  # the lower bracket among heights (the ground is 0)
    hi = np.minimum(np.maximum(a1, a0 + 1) + 1, heights.size - 1)  # above 24.5 km: no table
    below, above = lo - 1, np.minimum(hi + 1, heights.size - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        k_below = (tau[v, lo] - tau[v, below]) / (heights[lo] - heights[below])[:, None]
        k_above = (tau[v, above] - tau[v, hi]) / (heights[above] - heights[hi])[:, None]
        span = (0.5 * (heights[above] + heights[hi] - heights[lo] - heights[below]))[:, None]
        h = span / np.log(k_below / k_above)
        if intervals == 3:
            k_mid = (tau[v, hi] - tau[v, lo]) / (heights[hi] - heights[lo])[:, None]
            m = np.stack([0.5 * (heights[lo] + heights[below]), 0.5 * (heights[lo] + heights[hi]),
                          0.5 * (heights[above] + heights[hi])], axis=1)[:, :, None]
            ln_k = np.log(np.stack([k_below, k_mid, k_above], axis=1))
            dm = m - m.mean(axis=1, keepdims=True)
            slope = (dm * (ln_k - ln_k.mean(axis=1, keepdims=True))).sum(axis=1) / (
                dm * dm).sum(axis=1)
            h = -1.0 / slope
    good = (np.isfinite(h) & (h >= bounds[0]) & (h <= bounds[1]) & (above > hi)[:, None])
    return np.where(good, h, fallback)


#: Candidate rules of the study: label -> rule(db, altitude, ground_range, visibility).
CANDIDATES = {
    "cubic, optical path H=2 km": functools.partial(multi_node),
    "cubic, optical path H=2 km, C/T ratio": functools.partial(multi_node, others="ratio"),
    "cubic, optical path H=1.5 km": functools.partial(multi_node, scale_height=1500.0),
    "cubic, optical path H=2.5 km": functools.partial(multi_node, scale_height=2500.0),
    "Steffen, optical path H=2.5 km": functools.partial(multi_node, scale_height=2500.0,
                                                        slopes="steffen"),
    "cubic, optical path H fitted (nadir columns)": functools.partial(
        multi_node, scale_height=global_scale_heights),
    "cubic, optical path H local (nadir columns)": functools.partial(
        multi_node, scale_height=local_scale_heights),
    "cubic, nadir optical depth": functools.partial(multi_node, coordinate="nadir-column"),
    "cubic, altitude": functools.partial(multi_node, coordinate="altitude"),
    "cubic, sqrt altitude": functools.partial(multi_node, coordinate="sqrt-altitude"),
    "cubic, slant length": functools.partial(multi_node, coordinate="slant"),
    "exp + constant fit, H=2 km": functools.partial(multi_node, slopes="exp-fit",
                                                    others="ratio"),
}


def print_candidate_tables(db, wl, axes=("altitude", "ground_range")):
    """``"same-elevation"`` and every candidate, 2x, TRANS, SURF_EMIS, GRND_RFLT."""
    rules = {"same-elevation": "same-elevation", "optical-depth-cubic": "optical-depth-cubic",
             "extinction-profile": "extinction-profile", **CANDIDATES}
    print("| axis | visibility | component | " + " | ".join(rules) + " |")
    print("|---" * (3 + len(rules)) + "|")
    for axis in axes:
        for vis in (None, 23.0, 5.0):
            results = [kernel_errors(db, axis, rule, wl, 2, vis) for rule in rules.values()]
            label = "both" if vis is None else f"{vis:g} km"
            for c in _ALONG:
                name = COMPONENTS[c]
                print(f"| {axis} | {label} | {name} | "
                      + " | ".join(cell(r[name]) for r in results) + " |", flush=True)


def main() -> int:
    db = load_database()
    wl = np.array([int(np.argmin(np.abs(db.wavelength - w * 1e-6))) for w in WAVELENGTHS_UM])
    print("Candidate altitude rules from more than two tables (the first is the package's "
          "optical-depth-cubic), 2x: "
          "median / 95th percentile / max of |relative error|")
    print_candidate_tables(db, wl)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
