"""Leave-one-out accuracy of the atmosphere interpolation rules.

Each interior database table is rebuilt from its two neighbours along one axis
(ground range at a fixed altitude, or altitude) and compared with the real table.
The neighbours are twice as far apart as the real node spacing ("double spacing");
with ``spacing=4`` three tables are removed and the neighbours are four times the
real spacing apart. The real spacing itself has no truth between nodes; the ratio
of the two gives the order of convergence to extrapolate to it.

The ``xbsm`` rules ("linear", "log-linear", "same-elevation", "optical-depth-cubic",
"extinction-profile", the presets' rule) run through the package's own kernel on a
copy of the database with the tables removed, so the numbers are those of
``atmosphere_at`` on such a database.

Run from the repository root with the project environment (numbers go to
docs/atmosphere.md; see ``recipes/README.md``)::

    .venv/bin/python recipes/evidence/atmosphere_leave_one_out.py

The candidate altitude rules that lost to the package's "optical-depth-cubic" and
"extinction-profile" (issue 12) are scored by
``recipes/evidence/archive/atmosphere_candidate_rules.py``, which reuses
:func:`kernel_errors` and :func:`cell` from here.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from xbsm.atmosphere import (
    COMPONENTS,
    interpolate_database,
    load_database,
)
from xbsm.atmosphere.rules import interpolate

WAVELENGTHS_UM = (0.45, 0.6, 1.0, 2.2, 4.0, 10.0)
#: a value counts when it is at least this fraction of its spectrum's maximum
#: (relative errors of values near zero are meaningless)
SIGNIFICANT = 1e-3


def rebuild(db, axis: str, rule: str, v: int, a: int, g: int,
            log_coordinate: bool = False) -> np.ndarray | None:
    """Table (v, a, g) rebuilt from its neighbours along ``axis`` (None if impossible).

    ``rule`` is "linear" or "log" (in the value); ``log_coordinate`` puts the weight
    linear in the logarithm of the coordinate (altitude only).
    """
    cube, present = db.cube, db.present
    nodes = db.ground_range if axis == "ground_range" else db.altitude
    i = g if axis == "ground_range" else a
    if i == 0 or i == nodes.size - 1:
        return None
    lo, hi = ((v, a, g - 1), (v, a, g + 1)) if axis == "ground_range" else \
        ((v, a - 1, g), (v, a + 1, g))
    if not (present[lo] and present[hi] and present[v, a, g]):
        return None
    if axis == "altitude" and db.altitude[i + 1] > 20000.0:
        return None  # skip the 24.5 km / 550 km tables: not a regular grid
    x = np.log(nodes[i - 1: i + 2]) if log_coordinate else nodes[i - 1: i + 2]
    w = np.array([(x[1] - x[0]) / (x[2] - x[0])])
    low = cube[lo].astype(np.float64)[None]
    high = cube[hi].astype(np.float64)[None]
    return interpolate(low, high, w, rule)[0]


def relative_errors(db, axis: str, rule: str, wavelength_index, visibility=None,
                    log_coordinate=False):
    """|rebuilt / true - 1| per component over every interior table."""
    errors = {c: [] for c in COMPONENTS}
    for v in range(db.visibility.size):
        if visibility is not None and db.visibility[v] != visibility:
            continue
        for a in range(db.altitude.size):
            for g in range(db.ground_range.size):
                est = rebuild(db, axis, rule, v, a, g, log_coordinate)
                if est is None:
                    continue
                true = db.cube[v, a, g].astype(np.float64)
                for c, name in enumerate(COMPONENTS):
                    t = true[c, wavelength_index]
                    e = est[c, wavelength_index]
                    keep = t >= SIGNIFICANT * true[c].max()
                    if keep.any():
                        errors[name].append(np.abs(e[keep] / t[keep] - 1.0))
    return {name: np.concatenate(e) if e else np.array([]) for name, e in errors.items()}


def single_case(db, axis, rule, visibility, altitude, ground_range, component, wavelength_um,
                log_coordinate=False):
    """Signed relative error of one rebuilt value."""
    v = int(np.flatnonzero(db.visibility == visibility)[0])
    a = int(np.flatnonzero(db.altitude == altitude)[0])
    g = int(np.flatnonzero(db.ground_range == ground_range)[0])
    c = COMPONENTS.index(component)
    w = int(np.argmin(np.abs(db.wavelength - wavelength_um * 1e-6)))
    est = rebuild(db, axis, rule, v, a, g, log_coordinate)
    return est[c, w] / db.cube[v, a, g, c, w] - 1.0


CASES = [
    # (axis, visibility [km], altitude [m], ground range [m], component, wavelength [um])
    ("ground_range", 5.0, 1000.0, 11000.0, "TRANS", 0.45),
    ("ground_range", 5.0, 1000.0, 11000.0, "TRANS", 0.6),
    ("ground_range", 5.0, 1000.0, 11000.0, "GRND_RFLT", 0.6),
    ("ground_range", 23.0, 5000.0, 90000.0, "TRANS", 0.6),
    ("ground_range", 23.0, 1000.0, 90000.0, "TRANS", 0.6),  # near the 1 km horizon
    ("altitude", 5.0, 2000.0, 20000.0, "TRANS", 0.6),
    ("altitude", 23.0, 5000.0, 60000.0, "TRANS", 0.6),
    ("altitude", 5.0, 500.0, 10000.0, "TRANS", 0.6),
]


#: (label, value rule, weight linear in log(altitude))
METHODS = (
    ("linear (pyBSM)", "linear", False),
    ("log value, linear altitude", "log", False),
    ("log value, log altitude (xbsm log-linear)", "log", True),
)


def _without(db, axis: str, removed, wavelength_index):
    """Copy of ``db`` on a few wavelengths with the tables ``removed`` along ``axis``."""
    dim = 1 if axis == "altitude" else 2
    cube = np.delete(db.cube[..., wavelength_index], removed, axis=dim)
    present = np.delete(db.present, removed, axis=dim)
    coordinate = np.delete(getattr(db, axis), removed)
    return dataclasses.replace(db, cube=cube, present=present, wavelength=db.wavelength[
        wavelength_index], **{axis: coordinate})


def kernel_errors(db, axis: str, rule, wavelength_index, spacing=2, visibility=None):
    """|rebuilt / true - 1| per component, every interior table, by xbsm's own kernel.

    ``rule`` names an ``interpolation`` of the package, or is a candidate rule (a
    callable of :data:`CANDIDATES`) called as ``rule(db, altitude, ground_range, visibility)``.

    Scored tables: those whose two neighbours ``spacing / 2`` nodes away exist at the
    same (altitude, ground range), as in :func:`relative_errors`, below 20 km in altitude.
    """
    half = spacing // 2
    nodes = db.altitude if axis == "altitude" else db.ground_range
    errors = {c: [] for c in COMPONENTS}
    for i in range(half, nodes.size - half):
        if axis == "altitude" and db.altitude[i + half] > 20000.0:
            continue
        thin = _without(db, axis, list(range(i - half + 1, i + half)), wavelength_index)
        lo, hi = i - half, i + half
        v, other = np.nonzero(db.present[:, i] if axis == "altitude" else db.present[:, :, i])
        if axis == "altitude":
            keep = db.present[v, lo, other] & db.present[v, hi, other]
            alt, gr, true = nodes[i], db.ground_range[other], db.cube[v, i, other]
        else:
            keep = db.present[v, other, lo] & db.present[v, other, hi]
            alt, gr, true = db.altitude[other], nodes[i], db.cube[v, other, i]
        if visibility is not None:
            keep &= db.visibility[v] == visibility
        if not keep.any():
            continue
        alt = np.broadcast_to(alt, other.shape)[keep]
        gr = np.broadcast_to(gr, other.shape)[keep]
        vis = db.visibility[v[keep]]
        est = (rule(thin, alt, gr, vis) if callable(rule)
               else interpolate_database(thin, alt, gr, vis, rule, slice(None)))
        true = true[keep].astype(np.float64)
        for c, name in enumerate(COMPONENTS):
            t, e = true[:, c, wavelength_index], est[:, c]
            scored = t >= SIGNIFICANT * true[:, c].max(axis=1, keepdims=True)
            errors[name].append(np.abs(e[scored] / t[scored] - 1.0))
    return {name: np.concatenate(e) for name, e in errors.items()}


KERNEL_RULES = ("linear", "log-linear", "same-elevation", "optical-depth-cubic",
                "extinction-profile")


def cell(err):
    """Median / 95th percentile / max of relative errors, as a table cell."""
    return f"{np.median(err):.2%} / {np.percentile(err, 95):.1%} / {err.max():.0%}"


def print_rule_tables(db, wl):
    """Every rule, both axes, every component, each visibility and both, spacing 2 and 4."""
    print("| axis | spacing | visibility | component | n | " + " | ".join(KERNEL_RULES) + " |")
    print("|---" * (5 + len(KERNEL_RULES)) + "|")
    for axis in ("ground_range", "altitude"):
        for spacing in (2, 4):
            for vis in (None, 23.0, 5.0):
                results = [kernel_errors(db, axis, rule, wl, spacing, vis)
                           for rule in KERNEL_RULES]
                label = "both" if vis is None else f"{vis:g} km"
                for name in COMPONENTS:
                    print(f"| {axis} | {spacing}x | {label} | {name} | {results[0][name].size} | "
                          + " | ".join(cell(r[name]) for r in results) + " |")


def main() -> int:
    db = load_database()
    wl = np.array([int(np.argmin(np.abs(db.wavelength - w * 1e-6))) for w in WAVELENGTHS_UM])
    print("Single cases: signed relative error of the rebuilt value")
    print("| axis | visibility | altitude | ground range | component | wavelength | "
          + " | ".join(m[0] for m in METHODS) + " |")
    print("|---" * (6 + len(METHODS)) + "|")
    for case in CASES:
        axis, vis, alt, gr, comp, um = case
        errs = [single_case(db, axis, rule, *case[1:], log_coordinate=logc and axis == "altitude")
                for _, rule, logc in METHODS]
        print(f"| {axis} | {vis:g} km | {alt:g} m | {gr / 1000:g} km | {comp} | {um} um | "
              + " | ".join(f"{e:+.2%}" for e in errs) + " |")
    print()
    print(f"All interior tables, wavelengths {WAVELENGTHS_UM} um, both visibilities: "
          "median / 95th percentile / max of |relative error|")
    print("| axis | component | n | " + " | ".join(m[0] for m in METHODS) + " |")
    print("|---" * (3 + len(METHODS)) + "|")
    for axis in ("ground_range", "altitude"):
        methods = METHODS[::2] if axis == "ground_range" else METHODS
        results = [relative_errors(db, axis, rule, wl, log_coordinate=logc and axis == "altitude")
                   for _, rule, logc in methods]
        for name in COMPONENTS:
            cells = [f"{np.median(r[name]):.2%} / {np.percentile(r[name], 95):.1%} / "
                     f"{r[name].max():.0%}" for r in results]
            if axis == "ground_range":
                cells.insert(1, "(same as log-linear)")
            print(f"| {axis} | {name} | {results[0][name].size} | " + " | ".join(cells) + " |")
    print()
    print("xbsm's kernel on the database without the left-out tables: median / 95th "
          "percentile / max of |relative error|")
    print_rule_tables(db, wl)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
