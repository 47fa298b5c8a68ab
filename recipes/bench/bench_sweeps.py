"""Benchmark: what one scenario of an xbsm.niirs sweep costs, by swept parameter.

The Olson NIR camera (paper Table 2) at 9 km, 23 km visibility, 20.25 km ground
range, with one parameter swept at a time, each in two shapes:

- **alone**: the parameter on one dimension, every scenario its own value (10^5
  scenarios; 5x10^4 for the rows that change the atmosphere; 10^4 for the
  parameters that set the optics, which cost 10-100x more: at the issue's start a
  row takes 1-5 s a call);
- **crossed**: the parameter on its own dimension (1/100 of the scenarios) times
  100 ground ranges (0.25-99.25 km, 1 km apart), so what depends on the parameter
  alone can be shared across ranges.

The rows: ground range (alone only; its crossed shape is the next row),
altitude x ground range (alone: each scenario its own random altitude 3-15 km and
ground range 0-100 km on one dimension; crossed: altitudes x 100 ranges),
visibility (23 and 5 km alternating: the database has two, so "each scenario its
own" means each its own lookup, with half the values repeated), drift rate,
jitter, integration time, aperture diameter, focal length, pixel pitch and band
edges. Band edges cannot be a DataArray sweep of ``xbsm.sensor`` (each band sets
its own spectral grid), so they are swept the way the study layer sweeps bands
(``xbsm.study.build``: one model call per band, ``[bands.NAME]`` tables): a loop of
``xbsm.niirs`` calls, one per band, each with its own ``wavelength_min`` and
``wavelength_max`` (0.45-0.6 um to 0.6-0.9 um). Alone: 1,000 bands, 1,000 scalar
calls (one scenario a call, fewer than 10^4 because each is a whole call of
about 3 ms); crossed: 100 bands x 100 ground ranges (10^4 scenarios, 100 calls).
The ``xr.concat`` the study layer adds after the calls is not timed.

Each cell is one eager call (numpy-backed inputs, no dask) on prebuilt inputs,
after one warm-up call of the same inputs, with ``.niirs.values`` read; the
median of ``--repeats`` (3) calls, all of them kept in the JSON so that a cache
which makes repeats cheaper than the first call shows. Methods ``accurate`` and
``fast``.

**Side by side.** The timed part runs in child processes, one per checkout
(``--checkout PATH``, repeatable; default: this one), each started with
``PYTHONPATH=PATH`` in ``PATH`` (it prints and checks ``xbsm.__file__``) and kept
alive for the whole run. The parent sends each child the same cells in the same
order, one repeat at a time, the checkouts alternating (their order rotated
every repeat), so a load change on the shared machine falls on both. The load
average (``os.getloadavg``) is printed at the start, before every row and at the
end, and for every row the CPU time the rest of the machine used while it ran
(``/proc/stat`` busy time minus the children's own, in cores).

**Transcendental evaluations per scenario** (the ``count`` columns): after the
repeats, one more call of the same inputs runs instrumented, and its result must
equal the timed call's bit for bit (else the row says so). The method:

- every numpy ufunc among exp, exp2, expm1, log, log2, log10, log1p, power,
  float_power, sqrt, cbrt, sin, cos, tan, arcsin, arccos, arctan, arctan2, hypot,
  sinh, cosh, tanh, arcsinh, arccosh, arctanh, logaddexp, logaddexp2, every
  ufunc of ``scipy.special`` (Bessel, erf, erfcx, ndtr, ...), the same functions
  of ``math``, and ``operator.pow``, is replaced, for that call only, by a
  counting wrapper in every loaded module's namespace that holds it (so
  ``np.exp``, ``from scipy.special import jv`` and numpy's own ``sin`` inside
  ``np.sinc`` are all seen); the wrapper adds the number of elements of the
  output;
- ``a ** b`` in xbsm's own source (which no namespace holds) is counted by
  recompiling each loaded ``xbsm`` function with ``**`` turned into a counting
  call (``ast``), its code object swapped in for the call and swapped back after;
- only the outermost counted operation counts (``np.exp`` of a DataArray is
  one evaluation per element, not one for xarray's call and one for numpy's);
- powers with an integer-valued scalar exponent (``x**2``, ``x**3``) are
  multiplications, listed apart and not in the total;
- each count is also filed under the innermost ``xbsm`` module on the call stack
  (``counts_by_module`` in the JSON), which says which stage evaluates what.

Its blind spots: evaluations inside compiled code (a numba or C kernel, numpy's
own C functions such as FFT twiddles, ``np.interp``, ``np.linalg``, a ufunc's
``reduce`` / ``outer`` methods) are not seen, so on a branch with a compiled
kernel the count is a lower bound (the JSON records whether numba was loaded);
``**`` in other libraries' Python code (except xarray's, through
``operator.pow``) is not seen; a function held before the call in a default
argument, a closure or a container (``{"exp": np.exp}``) is not replaced; a
``where=`` mask counts every element of the output; a complex ``exp`` counts as
one; values cached by earlier calls (the warm-up) are not recounted, so the
count is the steady-state cost of one more call, which is what the time is too.

To put the count in time, each child measures at the end the nanoseconds per
element of every counted numpy / ``scipy.special`` function on 2^16 cache-resident
values (``unit_costs``; inputs in 0.01-100, so a sine of large arguments, with its
longer range reduction, costs more than this), and each cell gets the
microseconds its evaluations would take at those rates: the third number in the
summary's brackets, a floor for the evaluations as they are counted, not for the
model.

Run from the repository root with the project environment (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench/bench_sweeps.py [--repeats 3] [--checkout PATH ...]
        [--rows focal_length ...] [--methods accurate fast] [--scale 1.0]

``--scale 0.1`` shrinks every sweep tenfold for a quick look (do not commit its
numbers). Writes ``docs/benchmarks/bench_sweeps.json`` (or ``--out``): the
machine, each checkout's commit, the load, every repeat and every count.
"""

from __future__ import annotations

import argparse
import ast
import collections
import contextlib
import json
import math
import operator
import os
import statistics
import subprocess
import sys
import threading
import time
import types
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

ROOT = Path(__file__).resolve().parents[2]
BASE_SCENARIO = dict(altitude=9000.0, ground_range=20_250.0, visibility=23.0,
                     platform_speed=100.0)
CROSS_RANGES = [250.0 + 1000.0 * i for i in range(100)]  # 0.25-99.25 km, off most nodes

#: (row, what is swept, scenarios alone, scenarios crossed); None: no such shape.
ROWS = {
    "ground_range": ("ground range 0-100 km", 50_000, None),
    "altitude_ground_range": ("altitude 3-15 km x ground range", 50_000, 50_000),
    "visibility": ("visibility 23 / 5 km", 50_000, 50_000),
    "drift": ("drift rate x 0-500 urad/s", 100_000, 100_000),
    "jitter": ("jitter x 0.1-5 urad", 100_000, 100_000),
    "integration_time": ("integration time 1-30 ms", 100_000, 100_000),
    "aperture_diameter": ("aperture diameter 0.1-0.5 m", 10_000, 10_000),
    "focal_length": ("focal length 2-6 m", 10_000, 10_000),
    "pixel_pitch": ("pixel pitch 4-16 um", 10_000, 10_000),
    "band_edges": ("band edges (one call per band)", 1_000, 10_000),
}
#: sensor parameter and range of each one-parameter row
SENSOR_SWEEPS = {
    "drift": ("drift_rate_x", 0.0, 500e-6),
    "jitter": ("jitter_x", 0.1e-6, 5e-6),
    "integration_time": ("integration_time", 1e-3, 30e-3),
    "aperture_diameter": ("aperture_diameter", 0.1, 0.5),
    "focal_length": ("focal_length", 2.0, 6.0),
    "pixel_pitch": ("pixel_pitch_x", 4e-6, 16e-6),
}
METHODS = ("accurate", "fast")


# --------------------------------------------------------------------------- child side


def build(row: str, shape: str, n: int):
    """The (sensor, scenario) pairs of one cell: one pair, or one per band."""
    import numpy as np
    import xarray as xr

    import xbsm
    from xbsm.examples import olson_sensor

    def scenario(**changes):
        return xbsm.scenario(**{**BASE_SCENARIO, **changes})

    crossed = shape == "crossed"
    m = n // 100 if crossed else n
    ranges = xr.DataArray(np.asarray(CROSS_RANGES), dims="ground_range")
    on_ranges = {"ground_range": ranges} if crossed else {}
    if row == "ground_range":
        return [(olson_sensor("nir"), scenario(
            ground_range=xr.DataArray(np.linspace(0.0, 100e3, m), dims="ground_range")))]
    if row == "altitude_ground_range":
        if crossed:
            alt = xr.DataArray(np.linspace(3000.0, 15_000.0, m), dims="altitude")
            return [(olson_sensor("nir"), scenario(altitude=alt, ground_range=ranges))]
        rng = np.random.default_rng(0)
        alt = xr.DataArray(rng.uniform(3000.0, 15_000.0, m), dims="case")
        gr = xr.DataArray(rng.uniform(0.0, 100e3, m), dims="case")
        return [(olson_sensor("nir"), scenario(altitude=alt, ground_range=gr))]
    if row == "visibility":
        vis = xr.DataArray(np.resize([23.0, 5.0], m), dims="visibility")
        return [(olson_sensor("nir"), scenario(visibility=vis, **on_ranges))]
    if row in SENSOR_SWEEPS:
        name, lo, hi = SENSOR_SWEEPS[row]
        values = xr.DataArray(np.linspace(lo, hi, m), dims=name)
        return [(olson_sensor("nir", **{name: values}), scenario(**on_ranges))]
    if row == "band_edges":
        lows = np.linspace(0.45e-6, 0.60e-6, m)
        widths = 0.15e-6 + 0.15e-6 * ((np.arange(m) * 0.618034) % 1.0)
        sc = scenario(**on_ranges)
        return [(olson_sensor("nir", wavelength_min=lo, wavelength_max=lo + w), sc)
                for lo, w in zip(lows, widths, strict=True)]
    raise ValueError(f"unknown row {row!r}")


def run_cell(pairs, method):
    """One timed unit: xbsm.niirs over every pair; the NIIRS values read."""
    import xbsm

    return [xbsm.niirs(s, sc, method=method)["niirs"].values for s, sc in pairs]


class Counter:
    """Transcendental evaluations by function, outermost call only (see the docstring)."""

    def __init__(self):
        self.counts = collections.Counter()
        self.by_module = collections.Counter()  # (innermost xbsm module on the stack, name)
        self.local = threading.local()
        self.lock = threading.Lock()

    @contextlib.contextmanager
    def outermost(self):
        depth = getattr(self.local, "depth", 0)
        self.local.depth = depth + 1
        try:
            yield depth == 0
        finally:
            self.local.depth = depth

    def add(self, name, out):
        import numpy as np

        first = out[0] if isinstance(out, tuple) else out
        frame, module = sys._getframe(1), "(outside xbsm)"
        while frame is not None:
            owner = frame.f_globals.get("__name__", "")
            if owner == "xbsm" or owner.startswith("xbsm."):
                module = owner
                break
            frame = frame.f_back
        size = int(np.size(first))
        with self.lock:
            self.counts[name] += size
            self.by_module[module, name] += size

    def power(self, base, exponent, out, name="power"):
        import numpy as np

        try:
            integral = np.ndim(exponent) == 0 and float(np.real(exponent)).is_integer()
        except (TypeError, ValueError):
            integral = False
        self.add(f"{name} (integer exponent)" if integral else name, out)


class CountedCall:
    """A ufunc or function that counts its output's elements, attributes passed through."""

    def __init__(self, func, name, counter):
        self._func, self._name, self._counter = func, name, counter

    def __call__(self, *args, **kwargs):
        with self._counter.outermost() as top:
            out = self._func(*args, **kwargs)
        if top:
            if self._name in ("power", "float_power", "math.pow") and len(args) >= 2:
                self._counter.power(args[0], args[1], out, self._name)
            else:
                self._counter.add(self._name, out)
        return out

    def __getattr__(self, attr):
        return getattr(self._func, attr)

    def __repr__(self):
        return f"<counted {self._func!r}>"


NUMPY_TRANSCENDENTAL = (
    "exp", "exp2", "expm1", "log", "log2", "log10", "log1p", "power", "float_power",
    "sqrt", "cbrt", "sin", "cos", "tan", "arcsin", "arccos", "arctan", "arctan2", "hypot",
    "sinh", "cosh", "tanh", "arcsinh", "arccosh", "arctanh", "logaddexp", "logaddexp2",
)
MATH_TRANSCENDENTAL = (
    "exp", "expm1", "log", "log2", "log10", "log1p", "pow", "sqrt", "cbrt", "sin", "cos",
    "tan", "asin", "acos", "atan", "atan2", "hypot", "sinh", "cosh", "tanh", "erf", "erfc",
    "gamma", "lgamma",
)


class _PowToCall(ast.NodeTransformer):
    """``a ** b`` -> ``__bench_pow__(a, b)``; ``x **= b`` -> ``x = __bench_pow__(x, b)``."""

    def visit_BinOp(self, node):
        self.generic_visit(node)
        if isinstance(node.op, ast.Pow):
            return ast.copy_location(ast.Call(
                func=ast.Name("__bench_pow__", ast.Load()), args=[node.left, node.right],
                keywords=[]), node)
        return node

    def visit_AugAssign(self, node):
        self.generic_visit(node)
        if isinstance(node.op, ast.Pow) and isinstance(node.target, ast.Name):
            value = ast.Call(func=ast.Name("__bench_pow__", ast.Load()),
                             args=[ast.Name(node.target.id, ast.Load()), node.value], keywords=[])
            return ast.copy_location(ast.Assign(targets=[node.target], value=value), node)
        return node


def _code_objects(code):
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _code_objects(const)


def _functions_of(module):
    """Every function object reachable from a module's namespace and its classes."""
    seen, stack, found = set(), list(vars(module).values()), []
    while stack:
        obj = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, (staticmethod, classmethod)):
            stack.append(obj.__func__)
        elif isinstance(obj, property):
            stack.extend(f for f in (obj.fget, obj.fset, obj.fdel) if f is not None)
        elif isinstance(obj, types.FunctionType):
            if obj.__module__ == module.__name__:
                found.append(obj)
            if hasattr(obj, "__wrapped__"):
                stack.append(obj.__wrapped__)
        elif isinstance(obj, type) and obj.__module__ == module.__name__:
            stack.extend(vars(obj).values())
        elif hasattr(obj, "__wrapped__") and callable(obj):  # functools.lru_cache, ...
            stack.append(obj.__wrapped__)
    return found


@contextlib.contextmanager
def counting(counter: Counter):
    """Install the counters of the docstring for the duration of the block."""
    import numpy as np
    import scipy.special

    targets = {}
    for name in NUMPY_TRANSCENDENTAL:
        targets[id(getattr(np, name))] = (getattr(np, name), name)
    for name in dir(scipy.special):
        obj = getattr(scipy.special, name)
        if isinstance(obj, np.ufunc) and id(obj) not in targets:
            targets[id(obj)] = (obj, f"scipy.special.{obj.__name__}")
    for name in MATH_TRANSCENDENTAL:
        if hasattr(math, name):
            targets[id(getattr(math, name))] = (getattr(math, name), f"math.{name}")
    targets[id(operator.pow)] = (operator.pow, "power")
    wrappers = {key: CountedCall(func, name, counter) for key, (func, name) in targets.items()}
    replaced = []
    for module in list(sys.modules.values()):
        namespace = getattr(module, "__dict__", None)
        if not isinstance(namespace, dict):
            continue
        for key, value in list(namespace.items()):
            if id(value) in wrappers and not isinstance(value, CountedCall):
                replaced.append((namespace, key, value))
                namespace[key] = wrappers[id(value)]

    def bench_pow(base, exponent):
        with counter.outermost() as top:
            out = base ** exponent
        if top:
            counter.power(base, exponent, out)
        return out

    swapped, globals_set = [], []
    for name, module in list(sys.modules.items()):
        if not (name == "xbsm" or name.startswith("xbsm.")) or not getattr(
                module, "__file__", None):
            continue
        try:
            source = Path(module.__file__).read_text()
            tree = _PowToCall().visit(ast.parse(source))
            code = compile(ast.fix_missing_locations(tree), module.__file__, "exec")
        except (OSError, SyntaxError, UnicodeDecodeError):
            continue
        new = {(c.co_qualname, c.co_firstlineno): c for c in _code_objects(code)}
        for func in _functions_of(module):
            old = func.__code__
            replacement = new.get((old.co_qualname, old.co_firstlineno))
            if replacement is not None and replacement.co_freevars == old.co_freevars:
                swapped.append((func, old))
                func.__code__ = replacement
        globals_set.append(module.__dict__)
        module.__dict__["__bench_pow__"] = bench_pow
    try:
        yield counter
    finally:
        for func, old in swapped:
            func.__code__ = old
        for namespace in globals_set:
            namespace.pop("__bench_pow__", None)
        for namespace, key, value in replaced:
            namespace[key] = value


def unit_costs(names) -> dict:
    """Nanoseconds per element of each counted numpy / scipy.special function.

    Each on 2^16 values (cache-resident), uniform in 0.01-100 (0.01-0.99 for
    arcsin, arccos, arctanh; power with exponent 5/3; Bessel-like functions of two
    arguments as f(1, x)), fastest of 9 runs. ``math`` functions (scalars) and
    integer-exponent powers are left out, as they are from the count's total.
    """
    import numpy as np
    import scipy.special

    rng = np.random.default_rng(0)
    x = rng.uniform(0.01, 100.0, 2**16)
    unit = rng.uniform(0.01, 0.99, 2**16)
    out = {}
    for name in names:
        if "integer exponent" in name or name.startswith("math."):
            continue
        if name.startswith("scipy.special."):
            func = getattr(scipy.special, name.split(".", 2)[2], None)
        else:
            func = getattr(np, name, None)
        nin = getattr(func, "nin", None)
        if name in ("arcsin", "arccos", "arctanh"):
            args = (unit,)
        elif name == "arccosh":
            args = (x + 1.0,)
        elif name in ("power", "float_power"):
            args = (x, 5.0 / 3.0)
        elif nin == 1:
            args = (x,)
        elif nin == 2:
            args = (1.0, x) if name.startswith("scipy.") else (x, x)
        else:
            continue
        times = []
        with np.errstate(all="ignore"):
            func(*args)
            for _ in range(9):
                t0 = time.perf_counter()
                func(*args)
                times.append(time.perf_counter() - t0)
        out[name] = 1e9 * min(times) / x.size
    return out


def evaluation_estimate_us(counts: dict, n: int, costs: dict) -> float:
    """Microseconds per scenario the counted evaluations take at the measured unit costs."""
    return sum(v * costs[k] for k, v in counts.items() if k in costs) / n / 1e3


def child():
    """Serve the parent's commands on stdin, one JSON line each, until EOF."""
    import numpy as np

    import xbsm

    state = {}
    print(json.dumps({"xbsm_file": xbsm.__file__, "pid": os.getpid()}), flush=True)
    for line in sys.stdin:
        cmd = json.loads(line)
        op = cmd["op"]
        if op == "prepare":
            state.clear()
            t0 = time.perf_counter()
            pairs = build(cmd["row"], cmd["shape"], cmd["n"])
            t1 = time.perf_counter()
            run_cell(pairs[:2] if cmd["row"] == "band_edges" else pairs, cmd["method"])
            t2 = time.perf_counter()
            state.update(pairs=pairs, method=cmd["method"])
            reply = {"build_s": t1 - t0, "warmup_s": t2 - t1, "calls": len(pairs)}
        elif op == "time":
            t0 = time.perf_counter()
            state["last"] = run_cell(state["pairs"], state["method"])
            reply = {"seconds": time.perf_counter() - t0}
        elif op == "count":
            counter = Counter()
            with counting(counter):
                counted = run_cell(state["pairs"], state["method"])
            same = all(np.array_equal(a, b, equal_nan=True)
                       for a, b in zip(counted, state["last"], strict=True))
            by_module = collections.defaultdict(dict)
            for (module, name), value in counter.by_module.items():
                by_module[module][name] = value
            reply = {"counts": dict(counter.counts), "counts_by_module": by_module,
                     "result_unchanged": bool(same),
                     "numba_loaded": "numba" in sys.modules}
        elif op == "unit_costs":
            reply = {"ns_per_element": unit_costs(cmd["names"])}
        else:
            reply = {"error": f"unknown op {op!r}"}
        print(json.dumps(reply), flush=True)


# --------------------------------------------------------------------------- parent side


class Checkout:
    """One long-lived child process timing one checkout's xbsm."""

    def __init__(self, path: Path):
        from _provenance import commit

        self.path = path.resolve()
        self.provenance = commit(self.path)
        self.label = self.provenance["commit"] or str(self.path)
        env = {**os.environ, "PYTHONPATH": str(self.path)}
        self.proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--child"],
                                     cwd=self.path, env=env, stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, bufsize=1)
        hello = self._read()
        self.xbsm_file = hello["xbsm_file"]
        if not Path(self.xbsm_file).resolve().is_relative_to(self.path):
            raise SystemExit(f"{self.path}: the child imported {self.xbsm_file}, not this "
                             "checkout's xbsm")
        print(f"checkout {self.label} ({self.path}): xbsm from {self.xbsm_file}", flush=True)

    def _read(self):
        line = self.proc.stdout.readline()
        if not line:
            raise SystemExit(f"the child for {self.path} stopped (see its stderr above)")
        return json.loads(line)

    def ask(self, **cmd):
        self.proc.stdin.write(json.dumps(cmd) + "\n")
        return self._read()

    def cpu_seconds(self):
        import psutil

        try:
            t = psutil.Process(self.proc.pid).cpu_times()
        except psutil.Error:
            return 0.0
        return t.user + t.system

    def close(self):
        self.proc.stdin.close()
        self.proc.wait(timeout=60)


def busy_seconds():
    """CPU time the whole machine has spent busy (all cores), from /proc/stat."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    idle = fields[3] + fields[4]  # idle + iowait
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def load():
    return [round(x, 2) for x in os.getloadavg()]


def per_scenario_total(counts: dict, n: int) -> float:
    return sum(v for k, v in counts.items() if "integer exponent" not in k) / n


def run(args) -> dict:
    from _provenance import machine

    checkouts = [Checkout(Path(p)) for p in (args.checkout or [ROOT])]
    labels = [c.label for c in checkouts]
    for c in checkouts:  # two checkouts at one commit: tell them apart by folder
        if labels.count(c.label) > 1:
            c.label = f"{c.label}@{c.path.name}"
    results = {"machine": machine(), "repeats": args.repeats, "scale": args.scale,
               "checkouts": [{"path": str(c.path), "label": c.label, "xbsm_file": c.xbsm_file,
                              **c.provenance} for c in checkouts],
               "load_start": load(), "rows": []}
    print(f"load average (1, 5, 15 min) at start: {results['load_start']}; "
          f"{os.cpu_count()} cores", flush=True)
    try:
        for row in args.rows:
            what, n_alone, n_crossed = ROWS[row]
            for shape, n in (("alone", n_alone), ("crossed", n_crossed)):
                if n is None:
                    continue
                n = max(100, int(round(n * args.scale / 100)) * 100)
                record = {"row": row, "what": what, "shape": shape, "scenarios": n,
                          "load_before": load(), "cells": {}}
                busy0, own0, t0 = busy_seconds(), sum(c.cpu_seconds() for c in checkouts), \
                    time.perf_counter()
                for method in args.methods:
                    prepared = {c.label: c.ask(op="prepare", row=row, shape=shape, n=n,
                                               method=method) for c in checkouts}
                    times = {c.label: [] for c in checkouts}
                    for r in range(args.repeats):
                        order = checkouts[r % len(checkouts):] + checkouts[:r % len(checkouts)]
                        for c in order:
                            times[c.label].append(c.ask(op="time")["seconds"])
                    for c in checkouts:
                        count = c.ask(op="count")
                        median = statistics.median(times[c.label])
                        record["cells"][f"{c.label}/{method}"] = {
                            "checkout": c.label, "method": method, "seconds": times[c.label],
                            "median_s": median, "us_per_scenario": 1e6 * median / n,
                            "min_us": 1e6 * min(times[c.label]) / n,
                            "max_us": 1e6 * max(times[c.label]) / n,
                            "transcendental_per_scenario": per_scenario_total(count["counts"], n),
                            **count, **prepared[c.label]}
                wall = time.perf_counter() - t0
                own = sum(c.cpu_seconds() for c in checkouts) - own0
                record["other_cpu_cores"] = max(0.0, (busy_seconds() - busy0 - own) / wall)
                record["load_after"] = load()
                results["rows"].append(record)
                print_row(record, checkouts, args.methods)
        names = sorted({name for r in results["rows"] for cell in r["cells"].values()
                        for name in cell["counts"]})
        results["unit_costs_ns"] = {c.label: c.ask(op="unit_costs", names=names)[
            "ns_per_element"] for c in checkouts}
        for r in results["rows"]:
            for cell in r["cells"].values():
                cell["evaluation_estimate_us"] = evaluation_estimate_us(
                    cell["counts"], r["scenarios"], results["unit_costs_ns"][cell["checkout"]])
    finally:
        for c in checkouts:
            c.close()
    for label, costs in results["unit_costs_ns"].items():
        print(f"ns per element, {label}: " + ", ".join(
            f"{k} {v:.2g}" for k, v in sorted(costs.items(), key=lambda kv: -kv[1])))
    results["load_end"] = load()
    print(f"load average at end: {results['load_end']}", flush=True)
    return results


def print_row(record, checkouts, methods):
    cells = []
    for c in checkouts:
        for method in methods:
            cell = record["cells"][f"{c.label}/{method}"]
            flag = "" if cell["result_unchanged"] else " (COUNTED RESULT DIFFERS)"
            flag += " (numba loaded: count is a lower bound)" if cell["numba_loaded"] else ""
            cells.append(f"{c.label} {method}: {cell['us_per_scenario']:7.1f} us "
                         f"({cell['min_us']:.1f}-{cell['max_us']:.1f}), "
                         f"{cell['transcendental_per_scenario']:8.0f} transc.{flag}")
    print(f"{record['row']:22s} {record['shape']:7s} n={record['scenarios']:6d} load "
          f"{record['load_before'][0]:.2f}->{record['load_after'][0]:.2f}, other CPU "
          f"{record['other_cpu_cores']:.2f} cores | " + " | ".join(cells), flush=True)


def _us(value: float) -> str:
    return f"{value:,.0f}" if value >= 100 else f"{value:.1f}"


def print_summary(results):
    """Markdown: us per scenario (transcendental evaluations per scenario), every checkout."""
    labels = [c["label"] for c in results["checkouts"]]
    by_row = collections.defaultdict(dict)
    for r in results["rows"]:
        by_row[r["row"]][r["shape"]] = r
    methods = [m for m in METHODS if any(cell["method"] == m for r in results["rows"]
                                         for cell in r["cells"].values())]
    print(f"\nus per scenario (transcendental evaluations per scenario; the us they take at "
          f"the measured ns per element), checkouts "
          f"{' / '.join(labels)}; other CPU: cores the rest of the machine used, alone / crossed\n")
    print("| swept | scenarios alone / crossed | " + " | ".join(
        f"`{m}` {shape}" for m in methods for shape in ("alone", "crossed"))
        + " | other CPU |")
    print("|---|---|" + "---|" * (2 * len(methods)) + "---|")
    for row, shapes in by_row.items():
        out = [ROWS[row][0], " / ".join(f"{shapes[s]['scenarios']:,}" if s in shapes else "-"
                                        for s in ("alone", "crossed"))]
        for method in methods:
            for shape in ("alone", "crossed"):
                if shape not in shapes:
                    out.append("-")
                    continue
                cells = [shapes[shape]["cells"][f"{lab}/{method}"] for lab in labels]
                out.append(" / ".join(
                    f"{_us(c['us_per_scenario'])} ({c['transcendental_per_scenario']:,.0f}; "
                    f"{_us(c.get('evaluation_estimate_us', float('nan')))})" for c in cells))
        out.append(" / ".join(f"{shapes[s]['other_cpu_cores']:.1f}" for s in ("alone", "crossed")
                              if s in shapes))
        print("| " + " | ".join(out) + " |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--checkout", action="append", type=Path,
                        help="a checkout to time (repeatable; default: this one)")
    parser.add_argument("--rows", nargs="+", default=list(ROWS), choices=list(ROWS))
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scale", type=float, default=1.0,
                        help="multiply every sweep's size (0.1 for a quick look)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/benchmarks/bench_sweeps.json")
    args = parser.parse_args()
    if args.child:
        child()
        return
    results = run(args)
    print_summary(results)
    args.out.write_text(json.dumps(results, indent=1))
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
