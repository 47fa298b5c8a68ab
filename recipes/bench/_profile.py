"""Where the time of an xbsm call goes: cProfile time grouped by xbsm module.

Shared by ``recipes/bench/bench_single.py`` (one scalar ``xbsm.niirs`` call) and
``recipes/bench/bench_niirs.py`` (the Olson sweep). The self time of every function is
attributed to the innermost xbsm module on the call stack (``atmosphere``,
``radiometry``, ``noise``, ``quadrature``, ``otf.*``, ``metrics.*``, ``model``,
``params``, ``geometry``, ``_kernels``, ``_metadata``, ``flags``, ...), split into
that module's own code with the numpy/scipy it calls directly, and "xarray
overhead": time spent in xarray (and whatever xarray calls) below that module and
above any xbsm kernel. cProfile records only caller-callee pairs, so time two or
more levels below an xbsm function is shared among callers in proportion to each
pair's cumulative time (gprof's rule); :func:`stack_shares` is an exact, slower
check (``sys.setprofile``, walking the stack at every event). Profilers slow the
call down; the shares, not the profiled times, are the result.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import sys
import time
import warnings
from collections import defaultdict
from pathlib import Path

import numpy as np
import xarray as xr

import xbsm

XBSM_DIR = Path(xbsm.__file__).resolve().parent
XARRAY_DIR = Path(xr.__file__).resolve().parent


def _under(filename, folder):
    try:
        Path(filename).resolve().relative_to(folder)
    except (ValueError, OSError):
        return False
    return True


def short_name(func):
    """'package/module.py:line(name)' without the machine's folders."""
    filename, line, name = func
    if filename.startswith(("~", "<")):
        return name
    path = Path(filename).resolve()
    for base in sorted({XBSM_DIR.parent, XARRAY_DIR.parent, *map(Path, sys.path)},
                       key=lambda p: len(str(p)), reverse=True):
        try:
            return f"{path.relative_to(Path(base).resolve())}:{line}({name})"
        except (ValueError, OSError):
            continue
    return f"{path.name}:{line}({name})"


def attribute(stats):
    """Self time of every function -> {(innermost xbsm module, through xarray?): seconds}.

    The time of a function outside xbsm climbs the caller graph until it reaches an xbsm
    function: at the first step in proportion to the self time recorded for each caller
    pair, above that in proportion to each pair's cumulative time (cProfile keeps no
    deeper stacks). "Through xarray" means an xarray function was passed on the way. The
    climb is an absorbing Markov chain (recursion makes cycles), solved exactly with one
    sparse linear solve.
    """
    from scipy.sparse import coo_matrix, identity
    from scipy.sparse.linalg import MatrixRankWarning, spsolve

    raw = stats.stats  # {func: (cc, nc, tt, ct, {caller: (nc, cc, tt, ct)})}
    kind = {}

    def classify(func):
        if func not in kind:
            filename = func[0]
            if _under(filename, XBSM_DIR):
                rel = Path(filename).resolve().relative_to(XBSM_DIR).with_suffix("")
                parts = [p for p in rel.parts if p != "__init__"] or ["__init__"]
                kind[func] = ("xbsm", ".".join(parts))
            elif _under(filename, XARRAY_DIR):
                kind[func] = ("xarray", None)
            else:
                kind[func] = ("other", None)
        return kind[func]

    states, buckets = {}, {}  # (func, through_xarray) -> row; bucket -> column
    p_rows, p_cols, p_vals, a_rows, a_cols, a_vals = [], [], [], [], [], []
    pending = []

    def state(func, through):
        key = (func, through)
        if key not in states:
            states[key] = len(states)
            pending.append(key)
        return states[key]

    def column(bucket):
        return buckets.setdefault(bucket, len(buckets))

    def split(func, through, weight):
        """(caller target, probability) pairs for time spent in ``func``."""
        through = through or classify(func)[0] == "xarray"
        callers = {c: e for c, e in raw[func][4].items() if c != func}
        if not callers:
            return [(("bucket", ("(outside xbsm)", through)), 1.0)]
        weights = {c: e[weight] for c, e in callers.items()}
        if sum(weights.values()) <= 0:
            weights = {c: e[0] for c, e in callers.items()}  # by number of calls
        total = sum(weights.values())
        out = []
        for caller, w in weights.items():
            c_kind, c_module = classify(caller)
            target = (("bucket", (c_module, through)) if c_kind == "xbsm"
                      else ("state", (caller, through)))
            out.append((target, w / total))
        return out

    source = defaultdict(float)  # state row -> seconds entering it
    direct = defaultdict(float)  # bucket -> seconds
    for func, (_cc, _nc, tt, _ct, _callers) in raw.items():
        if tt <= 0:
            continue
        f_kind, module = classify(func)
        if f_kind == "xbsm":
            direct[(module, False)] += tt
            continue
        for (what, key), prob in split(func, False, 2):
            if what == "bucket":
                direct[key] += tt * prob
            else:
                source[state(*key)] += tt * prob
    while pending:
        func, through = pending.pop()
        row = states[(func, through)]
        for (what, key), prob in split(func, through, 3):
            if what == "bucket":
                a_rows.append(row)
                a_cols.append(column(key))
                a_vals.append(prob)
            else:
                p_rows.append(row)
                p_cols.append(state(*key))
                p_vals.append(prob)
    out = defaultdict(float, direct)
    n = len(states)
    if n:
        transition = coo_matrix((p_vals, (p_rows, p_cols)), shape=(n, n)).tocsc()
        absorb = coo_matrix((a_vals, (a_rows, a_cols)), shape=(n, len(buckets))).tocsr()
        s = np.zeros(n)
        for row, seconds in source.items():
            s[row] = seconds
        # seconds passing through each state: (I - P)^T m = s
        system = (identity(n, format="csc") - transition).T.tocsc()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", MatrixRankWarning)
            mass = spsolve(system, s)
        if not np.all(np.isfinite(mass)):
            # a recursion seen in one call only (deepcopy's own cycle) leaves the chain
            # without an exit there: the least-squares solution of the same equations
            mass = np.linalg.lstsq(system.toarray(), s, rcond=None)[0]
        totals = absorb.T @ mass
        for bucket, col in buckets.items():
            out[bucket] += float(totals[col])
    return out


def stack_shares(fn):
    """The same grouping, exact: walk the Python stack at every profiler event.

    A check on :func:`attribute`'s proportional rule (``sys.setprofile``; the time
    between two events goes to the innermost xbsm frame then on the stack, as xarray
    overhead if an xarray frame lies above it). Slower than cProfile; shares only.
    """
    xb, xa = str(XBSM_DIR), str(XARRAY_DIR)
    cache = {}

    def owner(frame):
        through = False
        while frame is not None:
            filename = frame.f_code.co_filename
            k = cache.get(filename)
            if k is None:
                path = str(Path(filename).resolve()) if not filename.startswith("<") else ""
                if path.startswith(xb + os.sep):
                    rel = Path(path).relative_to(xb).with_suffix("")
                    k = ("xbsm", ".".join(p for p in rel.parts if p != "__init__") or "__init__")
                else:
                    k = ("xarray" if path.startswith(xa + os.sep) else "other", None)
                cache[filename] = k
            if k[0] == "xbsm":
                return (k[1], through)
            through = through or k[0] == "xarray"
            frame = frame.f_back
        return ("(outside xbsm)", through)

    acc = defaultdict(float)
    current = [None, 0.0]

    def hook(frame, event, arg):
        t = time.perf_counter()
        if current[0] is not None:
            acc[current[0]] += t - current[1]
        current[0] = owner(frame.f_back if event == "return" else frame)
        current[1] = time.perf_counter()

    sys.setprofile(hook)
    try:
        fn()
    finally:
        sys.setprofile(None)
    total = sum(acc.values())
    modules = defaultdict(float)
    for (module, _), seconds in acc.items():
        modules[module] += seconds / total
    xarray = sum(v for (_, through), v in acc.items() if through) / total
    return {"by_module_share": dict(sorted(modules.items(), key=lambda kv: -kv[1])),
            "xarray_overhead_share": xarray}


def profile_call(fn, top_n=25):
    """Run ``fn()`` once under cProfile; its time grouped by xbsm module.

    Returns the profiled total, the number of Python function calls, the xarray
    overhead (ms and share), ``by_module`` ({module: own_ms, xarray_ms, total_ms,
    share}, largest first) and the top functions by cumulative and by self time.
    """
    profiler = cProfile.Profile()
    profiler.enable()
    fn()
    profiler.disable()
    stats = pstats.Stats(profiler)
    total = stats.total_tt
    buckets = attribute(stats)
    modules = defaultdict(lambda: {"own_ms": 0.0, "xarray_ms": 0.0})
    for (module, via_xarray), seconds in buckets.items():
        modules[module]["xarray_ms" if via_xarray else "own_ms"] += 1e3 * seconds
    for row in modules.values():
        row["total_ms"] = row["own_ms"] + row["xarray_ms"]
        row["share"] = row["total_ms"] / (1e3 * total)
    xarray_ms = sum(r["xarray_ms"] for r in modules.values())

    def top(key):
        rows = sorted(stats.stats.items(), key=lambda kv: kv[1][key], reverse=True)[:top_n]
        return [{"function": short_name(f), "ncalls": v[1], "tottime_ms": 1e3 * v[2],
                 "cumtime_ms": 1e3 * v[3]} for f, v in rows]

    return {
        "profiled_total_ms": 1e3 * total,
        "function_calls": sum(v[1] for v in stats.stats.values()),
        "xarray_overhead_ms": xarray_ms, "xarray_overhead_share": xarray_ms / (1e3 * total),
        "by_module": dict(sorted(modules.items(), key=lambda kv: -kv[1]["total_ms"])),
        "top_cumulative": top(3), "top_self": top(2),
    }


def print_by_module(profiles, title, cell, width=24, label="module"):
    """Print one row per xbsm module and one column per method; return (methods, modules).

    ``profiles`` maps a method name to a profile with a ``by_module`` table;
    ``cell(profile, row)`` formats one module's row of one method.
    """
    methods = list(profiles)
    print(title)
    print(f"{label:22s}" + "".join(f"{m:>{width}s}" for m in methods))
    modules = []
    for profile in profiles.values():
        modules += [m for m in profile["by_module"] if m not in modules]
    for module in modules:
        cells = [cell(profiles[m], profiles[m]["by_module"][module])
                 if module in profiles[m]["by_module"] else "" for m in methods]
        print(f"{module:22s}" + "".join(f"{c:>{width}s}" for c in cells))
    return methods, modules
