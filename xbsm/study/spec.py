"""Study files: a TOML description of a parametric study, checked as a whole.

A study names a sensor, a scenario, the parameters it sweeps, the outputs it
wants, the numerical method and how to cut the work into chunks. :func:`load`
reads a file (``tomllib``: data only, nothing is evaluated) into a frozen
:class:`Study`; :func:`parse` does the same for text. Every problem is one
``StudyError`` that names the key, its line in the file and what is allowed.
The format is documented in ``docs/study.md``.
"""

from __future__ import annotations

import dataclasses
import datetime
import difflib
import inspect
import math
import re
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np

from .. import examples, params
from ..methods import PRESETS

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

SENSOR_PARAMETERS = tuple(inspect.signature(params.sensor).parameters)
SCENARIO_PARAMETERS = tuple(inspect.signature(params.scenario).parameters)
#: Parameters that set the spectral grid: a band is a dimension of its own ([bands]).
BAND_PARAMETERS = ("wavelength_min", "wavelength_max")
#: Built-in sensors a study may start from (``[sensor] preset``), with their bands.
SENSOR_PRESETS = MappingProxyType({"olson": tuple(examples.OLSON_BANDS)})
OUTPUT_GROUPS = ("niirs", "mtf")
SCHEDULERS = ("threads", "synchronous", "local-cluster")
#: The most scenarios one study may hold (a guard against a typo of 10 zeros).
MAX_SCENARIOS = 10**10
#: The most values one range may produce (its coordinate is held in memory).
MAX_SWEEP_VALUES = 10**7
#: The largest study file read (a guard against passing a data file by mistake). [bytes]
MAX_STUDY_BYTES = 10 * 2**20
TOP_KEYS = ("title", "description", "sensor", "bands", "scenario", "sweep", "method",
            "outputs", "run")
#: Names a paired sweep's dimension may not take: xbsm's own and the study's ``band``.
RESERVED_DIMS = (*params.RESERVED_DIMS, "band")
RANGE_KEYS = ("start", "stop", "num", "spacing")
#: Every parameter a study may set or sweep.
PARAMETERS = frozenset(SENSOR_PARAMETERS) | frozenset(SCENARIO_PARAMETERS)


class StudyError(ValueError):
    """A study file or study table that cannot be run, with the key and line at fault."""


@dataclass(frozen=True)
class Sweep:
    """One swept dimension: its name and the parameter values along it."""

    dim: str
    values: MappingProxyType  # parameter name -> 1-D float array, all one length

    @property
    def size(self) -> int:
        """Number of values along the dimension."""
        return len(next(iter(self.values.values())))


@dataclass(frozen=True)
class Study:
    """A parsed, checked study: everything :func:`xbsm.study.run` needs."""

    sensor: MappingProxyType
    bands: MappingProxyType  # band name -> sensor parameters of that band (may be empty)
    scenario: MappingProxyType
    sweeps: tuple  # of Sweep, in file order
    method: str
    knobs: MappingProxyType
    outputs: tuple
    mtf_frequency: np.ndarray | None
    chunk_scenarios: int
    chunks: MappingProxyType
    scheduler: str
    workers: int
    output: str | None
    title: str
    text: str = dataclasses.field(repr=False, default="")

    @property
    def sizes(self) -> dict:
        """Length of every study dimension (``band`` first when there are bands)."""
        sizes = {"band": len(self.bands)} if self.bands else {}
        sizes.update({sweep.dim: sweep.size for sweep in self.sweeps})
        return sizes

    @property
    def scenarios(self) -> int:
        """Number of scenarios: the product of every dimension's length."""
        return math.prod(self.sizes.values())


_TOKENS = re.compile(r'''
    (?P<mstring>"""(?:\\.|[^\\])*?"""|'{3}.*?'{3})
  | (?P<string>"(?:\\.|[^"\\\n])*"|'[^'\n]*')
  | (?P<skip>\#[^\n]*|[ \t\r]+)
  | (?P<newline>\n)
  | (?P<punct>\[\[|\]\]|[\[\]{}=,.])
  | (?P<word>[^\s\[\]{}=,.\#"']+)
''', re.S | re.X)


def _unquote(token: str) -> str:
    return token[1:-1] if token[:1] in "\"'" else token


class _KeyLines:
    """Line of the first mention of every key path in valid TOML text.

    A small scanner over tokens: table headers (``[a.b]``, ``[[a.b]]``), dotted
    keys and the keys of inline tables (nested too) are recorded; strings,
    comments and values are skipped. ``lines`` maps a key path (a tuple) to its line.
    """

    def __init__(self, text: str):
        self.lines = {}
        self.table = ()  # the current [table]
        self.stack = []  # "[" for each open array, the key path of each open inline table
        self.keys = []  # the (dotted) key being read
        self.key_line = self.line = 1
        self.value_path = ()  # the key whose value is being read
        self.header = None  # the parts of a [table] header being read
        self.expect_key = True
        for match in _TOKENS.finditer(text):
            self._token(match.lastgroup, match.group())

    def _token(self, kind: str, token: str) -> None:
        if kind in ("newline", "mstring"):
            self.line += token.count("\n")
            if kind == "newline" and not self.stack:
                self.expect_key, self.keys = True, []
        elif kind == "skip":
            return
        elif self.header is not None:
            self._header(token)
        elif self.expect_key:
            self._key(token)
        else:
            self._value(token)

    def _header(self, token: str) -> None:
        if token in ("]", "]]"):
            self.table, self.header = tuple(self.header), None
            for i in range(1, len(self.table) + 1):
                self.lines.setdefault(self.table[:i], self.line)
        elif token != ".":
            self.header.append(_unquote(token))

    def _key(self, token: str) -> None:
        if token in ("[", "[[") and not self.stack and not self.keys:
            self.header = []
        elif token == "=":
            base = self.stack[-1] if self.stack else self.table
            for i in range(1, len(self.keys) + 1):
                self.lines.setdefault((*base, *self.keys[:i]), self.key_line)
            self.value_path, self.keys, self.expect_key = (*base, *self.keys), [], False
        elif token == "}" and self.stack:  # an empty inline table
            self.stack.pop()
            self.expect_key = False
        elif token != ".":
            if not self.keys:
                self.key_line = self.line
            self.keys.append(_unquote(token))

    def _value(self, token: str) -> None:
        if token == "{":
            self.stack.append(self.value_path)
            self.expect_key = True
        elif token in ("[", "[["):
            self.stack.extend("[" * len(token))
        elif token in ("]", "]]"):
            del self.stack[-len(token):]
        elif token == "}":
            self.stack.pop()
        elif token == "," and self.stack and self.stack[-1] != "[":
            self.expect_key = True


class _Source:
    """The study text, to say on which line a key was written."""

    def __init__(self, text: str, name: str):
        self.text = text
        self.name = name
        self._lines = None

    def line(self, table: str, key: str | None = None) -> int | None:
        """1-based line of ``table.key`` (or of the nearest enclosing key or table)."""
        if self._lines is None:
            self._lines = _KeyLines(self.text).lines
        path = tuple(part for part in table.split(".") if part) + ((key,) if key else ())
        while path:
            if path in self._lines:
                return self._lines[path]
            path = path[:-1]
        return None

    def error(self, table: str, key: str | None, message: str) -> StudyError:
        """A StudyError naming the file, line and key, on one line."""
        line = self.line(table, key)
        where = ".".join(part for part in (table, key) if part)
        at = f"{self.name}" + (f", line {line}" if line else "")
        return StudyError(_one_line(f"{at}: {where or 'study'}: {message}"))


def _one_line(message: str) -> str:
    """A message on one line, numbers printed as numbers (never ``np.float64(...)``)."""
    message = re.sub(r"np\.(?:float|int|uint|bool_?)\d*\(([^()]*)\)", r"\1", message)
    return " ".join(message.split())


def _closest(given: str, known) -> str:
    close = difflib.get_close_matches(given, list(known), n=3)
    return (f"did you mean {' or '.join(map(repr, close))}?" if close
            else f"allowed: {', '.join(sorted(known))}")


def _unknown(what: str, given, known) -> str:
    """The message for a name that is not one of ``known`` (or not a name at all)."""
    if not isinstance(given, str):
        names = ", ".join(sorted(known))
        return f"must be the name of a {what} in quotes, one of {names}; got {_shown(given)}"
    return f"unknown {what} {_shown(given)}; {_closest(given, known)}"


def _table(src: _Source, doc: dict, name: str, allowed=None) -> dict:
    """``doc[name]`` as a dict (empty if absent); unknown keys are errors."""
    value = doc.get(name, {})
    if not isinstance(value, dict):
        raise src.error("", name, f"must be a table ([{name}]); got {_shown(value)}")
    if allowed is not None:
        for key in value:
            if key not in allowed:
                raise src.error(name, key, f"unknown key; {_closest(key, allowed)}")
    return value


def _is_number(value) -> bool:
    """A TOML integer or float (never a boolean) that a float can hold."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        float(value)
    except OverflowError:
        return False
    return True


def _shown(value) -> str:
    """A value spelled roughly as TOML writes it, at most 60 characters."""
    if isinstance(value, bool):
        text = str(value).lower()
    elif isinstance(value, str):
        text = '"' + value.replace('"', '\\"') + '"'
    elif isinstance(value, (datetime.date, datetime.time)):
        text = f"{value.isoformat()} (a date or time)"
    elif isinstance(value, list):
        text = "[" + ", ".join(_shown(item) for item in value[:20]) + "]"
    elif isinstance(value, dict):
        text = "{" + ", ".join(f"{k} = {_shown(v)}" for k, v in list(value.items())[:20]) + "}"
    else:
        text = repr(value)
    return text if len(text) <= 60 else text[:56] + " ..."


def _number_list(src: _Source, table: str, key: str, value) -> np.ndarray:
    """A non-empty list of finite numbers as a float array."""
    if not isinstance(value, list) or not value or not all(_is_number(v) for v in value):
        word = ' or "database"' if key == "ground_range" else ""
        raise src.error(table, key, "must be a non-empty list of numbers, a range "
                        f"{{start, stop, num[, spacing]}}{word}; got {_shown(value)}")
    array = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(array)):
        raise src.error(table, key, f"values must be finite numbers; got {_shown(value)}")
    return array


def _range(src: _Source, table: str, key: str, spec: dict) -> np.ndarray:
    """``{start, stop, num, spacing}`` as linearly or logarithmically spaced values."""
    where = f"{table}.{key}"
    for name in spec:
        if name not in RANGE_KEYS:
            hint = (" (a table under a parameter's name is a range; a paired sweep needs a "
                    "dimension name that is not a parameter, e.g. [sweep.case])"
                    if name in PARAMETERS else "")
            raise src.error(where, name, f"unknown key of a range; "
                            f"{_closest(name, RANGE_KEYS)}{hint}")
    for name in ("start", "stop", "num"):
        if name not in spec:
            raise src.error(table, key, f"a range needs start, stop and num; {name} is missing")
    start, stop, num = spec["start"], spec["stop"], spec["num"]
    for name, value in (("start", start), ("stop", stop)):
        if not _is_number(value) or not math.isfinite(value):
            raise src.error(where, name, f"must be a finite number; got {_shown(value)}")
    if isinstance(num, bool) or not isinstance(num, int) or not 1 <= num <= MAX_SWEEP_VALUES:
        raise src.error(where, "num", f"must be a whole number from 1 to {MAX_SWEEP_VALUES:.0e};"
                        f" got {_shown(num)}")
    spacing = spec.get("spacing", "linear")
    if spacing not in ("linear", "log"):
        raise src.error(where, "spacing", f'must be "linear" or "log"; got {_shown(spacing)}')
    if spacing == "log" and (start <= 0 or stop <= 0):
        raise src.error(where, "start" if start <= 0 else "stop", "a log range needs start > 0 "
                        f"and stop > 0; got start = {start!r}, stop = {stop!r}")
    return np.geomspace(start, stop, num) if spacing == "log" else np.linspace(start, stop, num)


def _sweep_values(src: _Source, table: str, key: str, value) -> np.ndarray:
    """The values of one swept parameter (or the MTF frequencies), written any of three ways."""
    if key in BAND_PARAMETERS:
        raise src.error(table, key, "a band edge cannot be swept (it sets the spectral grid); "
                        "give each band as a [bands.NAME] table instead")
    if key in params.SPECTRAL or key == "filter_kernel":
        raise src.error(table, key, f"{key} cannot be swept in a study; set it in [sensor] or "
                        "per band in [bands.NAME]")
    if isinstance(value, str):
        if key == "ground_range" and value == "database":
            return np.array(examples.DATABASE_GROUND_RANGES)
        allowed = ('the only word allowed is "database" (the 97 ground ranges of the '
                   'atmosphere database)' if key == "ground_range" else
                   "must be a list of numbers or a range {start, stop, num[, spacing]}")
        raise src.error(table, key, f"{allowed}; got {_shown(value)}")
    values = (_range(src, table, key, value) if isinstance(value, dict)
              else _number_list(src, table, key, value))
    repeated = len(values) - len(np.unique(values))
    if repeated and table in ("sweep", "outputs"):
        raise src.error(table, key, f"values must not repeat (they label the dimension); "
                        f"{repeated} value(s) repeated")
    return values


def _sweeps(src: _Source, doc: dict) -> tuple:
    """Every [sweep] entry in file order: a parameter on its own dimension, or a paired table."""
    sweeps = []
    for key, value in _table(src, doc, "sweep").items():
        if key in PARAMETERS:
            values = _sweep_values(src, "sweep", key, value)
            sweeps.append(Sweep(key, MappingProxyType({key: values})))
        else:
            sweeps.append(_paired(src, key, value))
    _check_swept_once(src, sweeps)
    return tuple(sweeps)


def _paired(src: _Source, dim: str, table) -> Sweep:
    """A [sweep.DIM] table: parameters of one length along the new dimension ``dim``."""
    if dim == "band":
        raise src.error("sweep", dim, "bands are chosen in [sensor] (band = [...] with a preset) "
                        "or as [bands.NAME] tables; they are not swept")
    if isinstance(table, list) and table and all(isinstance(item, dict) for item in table):
        raise src.error("sweep", dim, f"write a paired sweep as one table [sweep.{dim}], not "
                        f"as an array of tables [[sweep.{dim}]]")
    if not isinstance(table, dict) or (table and set(table) <= set(RANGE_KEYS)):
        hint = _closest(dim, PARAMETERS)
        raise src.error("sweep", dim, f"unknown parameter; {hint}" + (
            "" if hint.startswith("did you") else " (or a paired sweep: a table [sweep.NAME] "
            "of parameters along one new dimension NAME)"))
    if dim in RESERVED_DIMS:
        raise src.error("sweep", dim, f"{dim!r} is a dimension name xbsm uses itself; choose "
                        f"another name (reserved: {', '.join(RESERVED_DIMS)})")
    if not table:
        raise src.error("sweep", dim, "a paired sweep needs at least one parameter, e.g. "
                        "focal_length = [3.0, 4.0]")
    values = {}
    for name, given in table.items():
        if name not in PARAMETERS:
            raise src.error(f"sweep.{dim}", name, f"unknown parameter; "
                            f"{_closest(name, PARAMETERS)}")
        values[name] = _sweep_values(src, f"sweep.{dim}", name, given)
    lengths = {name: len(v) for name, v in values.items()}
    if len(set(lengths.values())) != 1:
        shown = ", ".join(f"{name} has {n}" for name, n in lengths.items())
        raise src.error("sweep", dim, f"paired parameters share the dimension {dim!r} and must "
                        f"have one number of values; {shown}")
    return Sweep(dim, MappingProxyType(values))


def _check_swept_once(src: _Source, sweeps) -> None:
    seen = {}
    for sweep in sweeps:
        for name in sweep.values:
            if name in seen:
                table = "sweep" if sweep.dim == name else f"sweep.{sweep.dim}"
                raise src.error(table, name, f"is swept twice (on dimensions {seen[name]!r} and "
                                f"{sweep.dim!r}); sweep each parameter once")
            seen[name] = sweep.dim


def _parameter(src: _Source, table: str, key: str, value):
    """One fixed parameter value: a number, a spectral curve table or a filter kernel."""
    if _is_number(value):
        return float(value)
    if key == "filter_kernel":
        return _kernel(src, table, key, value)
    if key in params.SPECTRAL and isinstance(value, dict):
        return _curve(src, table, key, value)
    units = (params.SENSOR_SPECS.get(key) or params.SCENARIO_SPECS[key]).units
    curve = (" or a curve {wavelength = [...], values = [...]}" if key in params.SPECTRAL
             else "")
    hint = ("; to sweep it, move it to [sweep]" if isinstance(value, (list, dict))
            and key not in params.SPECTRAL else "")
    raise src.error(table, key, f"must be a number in SI units [{units}]{curve}; "
                    f"got {_shown(value)}{hint}")


def _kernel(src: _Source, table: str, key: str, value) -> np.ndarray:
    """A filter kernel: a list of numbers (one row) or a list of rows of one length."""
    rows = (value if isinstance(value, list) and value
            and all(isinstance(row, list) for row in value) else [value])
    if (not all(isinstance(row, list) and row and all(_is_number(v) for v in row)
                for row in rows) or len({len(row) for row in rows}) != 1):
        raise src.error(table, key, "must be a list of numbers (one row) or a list of rows of "
                        f"one length, e.g. [[-0.25, 1.5, -0.25]]; got {_shown(value)}")
    return np.asarray(rows, dtype=float)


def _curve(src: _Source, table: str, key: str, value: dict):
    """A spectral curve ``{wavelength = [...], values = [...]}`` as a DataArray."""
    import xarray as xr

    if set(value) != {"wavelength", "values"}:
        raise src.error(table, key, "a spectral curve is a table {wavelength = [...] (m), "
                        f"values = [...]}}; got keys {', '.join(value) or 'none'}")
    wavelength = _number_list(src, f"{table}.{key}", "wavelength", value["wavelength"])
    curve = _number_list(src, f"{table}.{key}", "values", value["values"])
    if len(wavelength) != len(curve):
        raise src.error(table, key, f"wavelength and values differ in length "
                        f"({len(wavelength)} and {len(curve)})")
    return xr.DataArray(curve, dims="wavelength", coords={"wavelength": wavelength})


def _fixed(src: _Source, values: dict, table: str, known) -> dict:
    """The fixed parameters of a table ([sensor] ``preset`` and ``band`` aside)."""
    out = {}
    for key, value in values.items():
        if key in ("preset", "band") and table == "sensor":
            continue
        if key not in known:
            raise src.error(table, key, f"unknown parameter; {_closest(key, known)}")
        out[key] = _parameter(src, table, key, value)
    return out


def _preset(src: _Source, table: dict) -> tuple[dict, dict]:
    """The preset sensor's parameters and, for a list of bands, each band's own ones."""
    preset, band = table.get("preset"), table.get("band")
    if preset is None:
        if band is not None:
            raise src.error("sensor", "band", 'a named band needs a sensor preset (preset = '
                            '"olson"); otherwise give the bands as [bands.NAME] tables')
        return {}, {}
    if not isinstance(preset, str) or preset not in SENSOR_PRESETS:
        raise src.error("sensor", "preset", _unknown("sensor preset", preset, SENSOR_PRESETS))
    known = SENSOR_PRESETS[preset]
    names = [band] if isinstance(band, str) else ["nir"] if band is None else band
    if (not isinstance(names, list) or not names or len(set(map(str, names))) != len(names)
            or not all(isinstance(name, str) for name in names)):
        raise src.error("sensor", "band", "must be a band name or a list of different band "
                        f"names of the {preset} sensor ({', '.join(known)}); got {_shown(band)}")
    for name in names:
        if name not in known:
            raise src.error("sensor", "band", f"unknown band {name!r} of the {preset} sensor; "
                            f"allowed: {', '.join(known)}")
    if not isinstance(band, list):
        return examples.olson_sensor_parameters(names[0]), {}
    for key in BAND_PARAMETERS:
        if key in table:
            raise src.error("sensor", key, f"is set per band by band = {_shown(band)} (the "
                            f"{preset} preset); remove it, or give the bands as [bands.NAME] "
                            "tables")
    # the file's quantum_efficiency, if any, overrides each band's (as any preset value)
    per_band = [*BAND_PARAMETERS] + ([] if "quantum_efficiency" in table
                                     else ["quantum_efficiency"])
    bands = {name: {k: v for k, v in examples.olson_sensor_parameters(name).items()
                    if k in per_band} for name in names}
    return examples.olson_sensor_parameters(names[0]), bands


def _sensor_and_bands(src: _Source, doc: dict) -> tuple[dict, dict]:
    """Sensor parameters (preset first, then the file's) and the bands, if any."""
    table = _table(src, doc, "sensor")
    base, bands = _preset(src, table)
    base.update(_fixed(src, table, "sensor", SENSOR_PARAMETERS))
    custom = _table(src, doc, "bands")
    if custom and bands:
        raise src.error("bands", None, "give bands either as [sensor] band = [...] or as "
                        "[bands.NAME] tables, not both")
    for name, values in custom.items():
        if not isinstance(values, dict):
            raise src.error("bands", name, "each band is a table [bands.NAME] of sensor "
                            f"parameters (wavelength_min, wavelength_max, ...); got "
                            f"{_shown(values)}")
        bands[name] = _fixed(src, values, f"bands.{name}", SENSOR_PARAMETERS)
    return base, bands


def _method(src: _Source, doc: dict) -> tuple[str, dict]:
    """Method preset and knob overrides, each checked as :func:`xbsm.method` does."""
    from ..methods import method as make_method

    knobs = dict(_table(src, doc, "method"))
    preset = knobs.pop("preset", "accurate")
    if not isinstance(preset, str) or preset not in PRESETS:
        raise src.error("method", "preset", _unknown("method preset", preset, PRESETS))
    known = {f.name for f in dataclasses.fields(PRESETS[preset])} - {"name", "constants"}
    for key, value in knobs.items():
        if key not in known:
            raise src.error("method", key, f"unknown method knob; {_closest(key, known)}")
        try:
            make_method(preset, **{key: value})
        except (TypeError, ValueError) as err:
            raise src.error("method", key, str(err)) from None
    return preset, knobs


def _outputs(src: _Source, doc: dict) -> tuple[tuple, np.ndarray | None]:
    """Output groups (``niirs`` always; ``mtf`` with its frequency grid)."""
    table = _table(src, doc, "outputs", ("include", "mtf_frequency"))
    include = table.get("include", ["niirs"])
    if not isinstance(include, list) or not include or not all(
            isinstance(x, str) for x in include):
        raise src.error("outputs", "include", f"must be a non-empty list from "
                        f"{list(OUTPUT_GROUPS)}; got {_shown(include)}")
    for name in include:
        if name not in OUTPUT_GROUPS:
            raise src.error("outputs", "include", f"unknown output {name!r}; "
                            f"{_closest(name, OUTPUT_GROUPS)}")
    frequency = None
    if "mtf" in include:
        if "mtf_frequency" not in table:
            raise src.error("outputs", "include", "the mtf output needs mtf_frequency = "
                            "{start, stop, num} or a list (cycles/rad) in [outputs]")
        frequency = _sweep_values(src, "outputs", "mtf_frequency", table["mtf_frequency"])
        if np.any(frequency < 0) or len(frequency) > params.MAX_FREQUENCIES:
            raise src.error("outputs", "mtf_frequency", "must hold at most "
                            f"{params.MAX_FREQUENCIES} frequencies, each >= 0 cycles/rad; got "
                            f"{len(frequency)} from {frequency.min():g}")
    elif "mtf_frequency" in table:
        raise src.error("outputs", "mtf_frequency", 'given without "mtf" in include; add '
                        '"mtf" to include or remove mtf_frequency')
    return tuple(dict.fromkeys(["niirs", *include])), frequency


def _whole(src: _Source, key: str, value, name: str | None = None) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise src.error("run", key, f"{name + ' ' if name else ''}must be a whole number >= 1;"
                        f" got {_shown(value)}")


def _run_options(src: _Source, doc: dict, dims) -> dict:
    """Chunking, scheduler, workers and the default output path."""
    table = _table(src, doc, "run", ("chunk_scenarios", "chunks", "scheduler", "workers",
                                     "output"))
    out = dict(chunk_scenarios=table.get("chunk_scenarios", 20_000),
               chunks=table.get("chunks", {}), scheduler=table.get("scheduler", "threads"),
               workers=table.get("workers", 2), output=table.get("output"))
    for key in ("chunk_scenarios", "workers"):
        _whole(src, key, out[key])
    if not isinstance(out["chunks"], dict):
        raise src.error("run", "chunks", "must be a table {dimension = chunk length}; got "
                        f"{_shown(out['chunks'])}")
    for dim, size in out["chunks"].items():
        if dim not in dims:
            raise src.error("run", "chunks", f"unknown dimension {dim!r}; "
                            f"{_closest(dim, dims) if dims else 'the study has no dimensions'}")
        _whole(src, "chunks", size, dim)
    scheduler = out["scheduler"]
    if not isinstance(scheduler, str) or not (scheduler in SCHEDULERS or "://" in scheduler):
        raise src.error("run", "scheduler", f"must be one of {', '.join(SCHEDULERS)} or a "
                        f"scheduler address such as tcp://host:8786; got {_shown(scheduler)}")
    if out["output"] is not None and not (isinstance(out["output"], str) and out["output"]):
        raise src.error("run", "output", "must be a file name such as \"study.nc\"; got "
                        f"{_shown(out['output'])}")
    return out


def _check_model_inputs(src: _Source, study: Study) -> None:
    """Build the sensor and scenario of every band with the full sweeps: xbsm's own checks."""
    import xarray as xr

    swept = {name: (sweep.dim, values) for sweep in study.sweeps
             for name, values in sweep.values.items()}
    origin = {name: f"sweep.{dim}" if dim != name else "sweep" for name, (dim, _) in
              swept.items()}
    for band, band_params in (study.bands or {None: {}}).items():
        for name in band_params:
            origin.setdefault(name, f"bands.{band}")
        kwargs = {**study.sensor, **band_params, **study.scenario}
        kwargs.update({name: xr.DataArray(values, dims=dim)
                       for name, (dim, values) in swept.items()})
        sensor = {k: v for k, v in kwargs.items() if k in SENSOR_PARAMETERS}
        scenario = {k: v for k, v in kwargs.items() if k in SCENARIO_PARAMETERS}
        for kind, call, given in (("sensor", params.sensor, sensor),
                                  ("scenario", params.scenario, scenario)):
            missing = [p for p, v in inspect.signature(call).parameters.items()
                       if v.default is inspect.Parameter.empty and p not in given]
            if missing:
                raise src.error(kind, None, f"missing {kind} parameter {missing[0]!r} "
                                f"(set it in [{kind}] or sweep it in [sweep])")
            try:
                call(**given)
            except ValueError as err:
                name = _first_named(str(err), given)
                raise src.error(origin.get(name, kind), name, str(err)) from None


def _first_named(message: str, names) -> str | None:
    """The parameter a model error message names first."""
    found = [(message.find(name), name) for name in names if re.search(
        rf"\b{re.escape(name)}\b", message)]
    return min(found)[1] if found else None


def _toml(text: str, name: str) -> dict:
    """The TOML document; a syntax error names the line, the column and the line's text."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        message = str(err)
    found = re.search(r"\s*\(at (?:line (\d+), column (\d+)|end of document)\)$", message)
    reason = re.sub(r"\(((?:'[^']*',?\s*)+)\)",  # tomllib's ('a', 'b') is the table [a.b]
                    lambda m: "[" + ".".join(re.findall(r"'([^']*)'", m.group(1))) + "]",
                    message[:found.start()] if found else message)
    lines = text.splitlines()
    line = int(found.group(1)) if found and found.group(1) else len(lines)
    column = f", column {found.group(2)}" if found and found.group(2) else ""
    shown = re.sub(r"[\x00-\x08\x0b-\x1f\x7f]", lambda m: f"\\x{ord(m.group()):02x}",
                   lines[line - 1].strip() if 0 < line <= len(lines) else "")
    raise StudyError(_one_line(
        f"{name}, line {line}{column}: not valid TOML ({reason}) in: {shown[:80]} "
        "(the syntax is TOML 1.0, https://toml.io; see docs/study.md)"))


def parse(text: str, name: str = "<study>") -> Study:
    """A :class:`Study` from TOML text; ``name`` is used in error messages.

    Raises
    ------
    StudyError
        Naming the file, the line, the key and what is allowed.
    """
    if not isinstance(text, str):
        raise StudyError(f"study text must be a str of TOML; got {type(text).__name__} "
                         "(xbsm.study.load reads a file)")
    src = _Source(text, name)
    doc = _toml(text, name)
    for key in doc:
        if key not in TOP_KEYS:
            raise src.error("", key, f"unknown key; {_closest(key, TOP_KEYS)}")
    for key in ("title", "description"):
        if not isinstance(doc.get(key, ""), str):
            raise src.error("", key, f"must be text in quotes; got {_shown(doc[key])}")
    sensor, bands = _sensor_and_bands(src, doc)
    scenario = _fixed(src, _table(src, doc, "scenario"), "scenario", SCENARIO_PARAMETERS)
    sweeps = _sweeps(src, doc)
    _check_not_both(src, sweeps, {"sensor": _table(src, doc, "sensor"),
                                  "scenario": scenario,
                                  **{f"bands.{band}": v for band, v in bands.items()}})
    _check_size(src, bands, sweeps)
    method, knobs = _method(src, doc)
    outputs, frequency = _outputs(src, doc)
    dims = (["band"] if bands else []) + [sweep.dim for sweep in sweeps]
    study = Study(sensor=MappingProxyType(sensor), bands=MappingProxyType(bands),
                  scenario=MappingProxyType(scenario), sweeps=sweeps, method=method,
                  knobs=MappingProxyType(knobs), outputs=outputs, mtf_frequency=frequency,
                  title=doc.get("title", ""), text=text, **_run_options(src, doc, dims))
    _check_model_inputs(src, study)
    return study


def _check_not_both(src: _Source, sweeps, tables: dict) -> None:
    """A parameter is fixed ([sensor], [scenario], a band) or swept, never both."""
    for sweep in sweeps:
        for name in sweep.values:
            for table, given in tables.items():
                if name in given:
                    raise src.error(table, name, "is set here and swept in [sweep]; keep one")


def _check_size(src: _Source, bands: dict, sweeps) -> None:
    """At most :data:`MAX_SCENARIOS` scenarios."""
    sizes = {"band": len(bands)} if bands else {}
    sizes.update({sweep.dim: sweep.size for sweep in sweeps})
    total = math.prod(sizes.values())
    if total > MAX_SCENARIOS:
        shown = " x ".join(f"{dim} {size}" for dim, size in sizes.items())
        raise src.error("sweep", None, f"{total:.3g} scenarios ({shown}); at most "
                        f"{MAX_SCENARIOS:.0e} per study: sweep fewer values")


def load(path) -> Study:
    """Read and check a study file (TOML; see ``docs/study.md``).

    Parameters
    ----------
    path : str or Path
        A UTF-8 text file of at most :data:`MAX_STUDY_BYTES`.

    Returns
    -------
    Study

    Raises
    ------
    StudyError
        A file that cannot be read, or any problem in it, in one message.
    """
    path = Path(path)
    try:
        if path.is_dir():
            raise StudyError(f"{path} is a directory; give a study file (TOML)")
        if path.exists() and path.stat().st_size > MAX_STUDY_BYTES:
            raise StudyError(f"{path} has {path.stat().st_size} bytes; a study file has at "
                             f"most {MAX_STUDY_BYTES} (is it a study file?)")
        data = path.read_bytes()
    except OSError as err:
        raise StudyError(f"cannot read study file {path}: {err.strerror or err}") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = data[:err.start].count(b"\n") + 1
        raise StudyError(f"{path}, line {line}: not UTF-8 text (byte 0x{data[err.start]:02x}); "
                         "save the study file as UTF-8") from None
    return parse(text, str(path))
