"""Study files: a TOML description of a parametric study, checked as a whole.

A study names a sensor, a scenario, the parameters it sweeps, the outputs it
wants, the numerical method and how to cut the work into chunks. :func:`load`
reads a file (``tomllib``: data only, nothing is evaluated) into a frozen
:class:`Study`; :func:`parse` does the same for text. Every problem is one
``StudyError`` that names the key, its line in the file and what is allowed.
The format is documented in ``docs/study.md``.

The work is shared, in data-flow order, by ``_source`` (the TOML text, the line
of every key, the error messages), ``_values`` (numbers, ranges, sweep values,
spectral curves, kernels), ``_sections`` ([sensor] and [bands], [method],
[outputs], [run]), this module ([sweep], :func:`parse`, :func:`load`) and
``_checks`` (the study as a whole).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np

from .. import params
from ._checks import (
    MAX_SCENARIOS,
    check_model_inputs,
    check_not_both,
    check_size,
    dimension_sizes,
)
from ._sections import (
    MTF_VARIABLES,
    NIIRS_VARIABLES,
    OUTPUT_GROUPS,
    SCHEDULERS,
    SENSOR_PRESETS,
    method_and_knobs,
    output_variables,
    outputs_and_frequency,
    run_options,
    sensor_and_bands,
)
from ._source import (
    Source,
    StudyError,
    read_toml,
    reject_unknown_keys,
    section,
    shown,
    suggestion,
)
from ._values import (
    BAND_PARAMETERS,
    MAX_SWEEP_VALUES,
    PARAMETERS,
    RANGE_KEYS,
    SCENARIO_PARAMETERS,
    SENSOR_PARAMETERS,
    fixed_parameters,
    sweep_values,
)
from .images import dataset_section

__all__ = ["BAND_PARAMETERS", "MAX_SCENARIOS", "MAX_STUDY_BYTES", "MAX_SWEEP_VALUES",
           "MTF_VARIABLES", "NIIRS_VARIABLES", "OUTPUT_GROUPS", "PARAMETERS", "RANGE_KEYS",
           "RESERVED_DIMS", "SCENARIO_PARAMETERS", "SCHEDULERS", "SENSOR_PARAMETERS",
           "SENSOR_PRESETS", "TOP_KEYS", "Study", "StudyError", "Sweep", "load", "parse"]

#: The largest study file read (a guard against passing a data file by mistake). [bytes]
MAX_STUDY_BYTES = 10 * 2**20
TOP_KEYS = ("title", "description", "sensor", "bands", "scenario", "sweep", "method",
            "outputs", "run", "dataset")
#: Names a paired sweep's dimension may not take: xbsm's own and the study's ``band``.
RESERVED_DIMS = (*params.RESERVED_DIMS, "band")


@dataclass(frozen=True)
class Sweep:
    """One swept dimension: its name and the parameter values along it."""

    dim: str
    values: MappingProxyType  # parameter name -> 1-D float array, all one length

    @property
    def size(self) -> int:
        """Number of values along the dimension."""
        return len(next(iter(self.values.values())))


@dataclass(frozen=True, repr=False)
class Study:
    """A parsed, checked study: everything :func:`xbsm.study.run` needs.

    ``print(study)`` (and its repr in a notebook) is a summary: the scenarios
    and their dimensions, the chunks, the sweeps, bands, method, outputs and
    run options; the parameters themselves are the attributes.
    """

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
    variables: tuple = ()  # the output variables kept ([outputs] variables); empty: all
    compress: int = 0  # zlib level of the data variables in the NetCDF file; 0: none
    dataset: object = None  # the [dataset] table (xbsm.study.images.DatasetSpec), or None

    @property
    def sizes(self) -> dict:
        """Length of every study dimension (``band`` first when there are bands)."""
        return dimension_sizes(self.bands, self.sweeps)

    @property
    def scenarios(self) -> int:
        """Number of scenarios: the product of every dimension's length."""
        return math.prod(self.sizes.values())

    def __repr__(self) -> str:
        return "\n".join(_summary(self))


def _values_text(name: str, values) -> str:
    """A swept parameter's values in a few words: a short list, or count and span."""
    spec = params.SENSOR_SPECS.get(name) or params.SCENARIO_SPECS.get(name) \
        or params.CONDITION_SPECS.get(name)
    units = f" {spec.units}" if spec is not None and spec.units not in ("", "1") else ""
    values = np.asarray(values, dtype=float)
    if len(values) <= 4:
        return f"{name} [{', '.join(f'{v:g}' for v in values)}]{units}"
    return f"{name} {len(values)} values {values.min():g} to {values.max():g}{units}"


def _summary(study: Study) -> list:
    """The lines of ``print(study)``."""
    from .build import chunk_sizes  # build imports this module

    sizes, chunks = study.sizes, chunk_sizes(study)
    dims = " x ".join(f"{dim} {size}" for dim, size in sizes.items()) or "one scenario"
    per_chunk = math.prod(chunks.values())
    count = math.prod(math.ceil(sizes[d] / chunks[d]) for d in sizes)
    lines = [f"<xbsm Study {study.title!r}>" if study.title else "<xbsm Study>",
             f"  scenarios: {study.scenarios:,} ({dims})",
             f"  chunks:    {count:,} of at most {per_chunk:,} scenarios"
             + (" (" + ", ".join(f"{dim} {n}" for dim, n in chunks.items()) + ")"
                if chunks else "")]
    sweeps = []
    for sweep in study.sweeps:
        texts = [_values_text(name, values) for name, values in sweep.values.items()]
        sweeps.append(texts[0] if list(sweep.values) == [sweep.dim]
                      else f"{sweep.dim}: " + "; ".join(texts))
    lines.append("  sweeps:    " + ("; ".join(sweeps) if sweeps else "none"))
    if study.bands:
        lines.append(f"  bands:     {', '.join(study.bands)}")
    knobs = ", ".join(f"{k}={v!r}" for k, v in study.knobs.items())
    lines.append(f"  method:    {study.method}" + (f" ({knobs})" if knobs else ""))
    outputs = ", ".join(study.outputs)
    if study.mtf_frequency is not None:
        outputs += f" ({len(study.mtf_frequency)} MTF frequencies)"
    lines.append(f"  outputs:   {outputs}; variables: "
                 + (", ".join(study.variables) if study.variables else "all"))
    lines.append(f"  run:       {study.scheduler}, {study.workers} worker(s)"
                 + (f", output {study.output}" if study.output else "")
                 + (f", zlib level {study.compress}" if study.compress else ""))
    if study.dataset is not None:
        spec = study.dataset
        lines.append(f"  dataset:   {spec.input} -> {spec.output or '(-o FOLDER)'} "
                     f"({spec.format}, {spec.values}, {spec.out_dtype}, {spec.layout}, "
                     f"{spec.chunk_images} images per chunk)")
    return lines


def _sweeps(src: Source, doc: dict) -> tuple:
    """Every [sweep] entry in file order: a parameter on its own dimension, or a paired table."""
    sweeps = []
    for key, value in section(src, doc, "sweep").items():
        if key in PARAMETERS:
            values = sweep_values(src, "sweep", key, value)
            sweeps.append(Sweep(key, MappingProxyType({key: values})))
        else:
            sweeps.append(_paired(src, key, value))
    _check_swept_once(src, sweeps)
    return tuple(sweeps)


def _paired(src: Source, dim: str, table) -> Sweep:
    """A [sweep.DIM] table: parameters of one length along the new dimension ``dim``."""
    if dim == "band":
        raise src.error("sweep", dim, "bands are chosen in [sensor] (band = [...] with a preset) "
                        "or as [bands.NAME] tables; they are not swept")
    if isinstance(table, list) and table and all(isinstance(item, dict) for item in table):
        raise src.error("sweep", dim, f"write a paired sweep as one table [sweep.{dim}], not "
                        f"as an array of tables [[sweep.{dim}]]")
    if not isinstance(table, dict) or (table and set(table) <= set(RANGE_KEYS)):
        hint = suggestion(dim, PARAMETERS)
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
                            f"{suggestion(name, PARAMETERS)}")
        values[name] = sweep_values(src, f"sweep.{dim}", name, given)
    lengths = {name: len(v) for name, v in values.items()}
    if len(set(lengths.values())) != 1:
        counts = ", ".join(f"{name} has {n}" for name, n in lengths.items())
        raise src.error("sweep", dim, f"paired parameters share the dimension {dim!r} and must "
                        f"have one number of values; {counts}")
    return Sweep(dim, MappingProxyType(values))


def _check_swept_once(src: Source, sweeps) -> None:
    """Each parameter is swept on one dimension only."""
    seen = {}
    for sweep in sweeps:
        for name in sweep.values:
            if name in seen:
                table = "sweep" if sweep.dim == name else f"sweep.{sweep.dim}"
                raise src.error(table, name, f"is swept twice (on dimensions {seen[name]!r} and "
                                f"{sweep.dim!r}); sweep each parameter once")
            seen[name] = sweep.dim


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
    src = Source(text, name)
    doc = read_toml(text, name)
    reject_unknown_keys(src, "", doc, TOP_KEYS)
    for key in ("title", "description"):
        if not isinstance(doc.get(key, ""), str):
            raise src.error("", key, f"must be text in quotes; got {shown(doc[key])}")
    sensor, bands = sensor_and_bands(src, doc)
    scenario = fixed_parameters(src, section(src, doc, "scenario"), "scenario",
                                SCENARIO_PARAMETERS)
    sweeps = _sweeps(src, doc)
    check_not_both(src, sweeps, {"sensor": section(src, doc, "sensor"),
                                 "scenario": scenario,
                                 **{f"bands.{band}": v for band, v in bands.items()}})
    check_size(src, bands, sweeps)
    method, knobs = method_and_knobs(src, doc)
    outputs, frequency = outputs_and_frequency(src, doc)
    variables = output_variables(src, doc, outputs)
    dims = list(dimension_sizes(bands, sweeps))
    study = Study(sensor=MappingProxyType(sensor), bands=MappingProxyType(bands),
                  scenario=MappingProxyType(scenario), sweeps=sweeps, method=method,
                  knobs=MappingProxyType(knobs), outputs=outputs, mtf_frequency=frequency,
                  title=doc.get("title", ""), text=text, variables=variables,
                  dataset=dataset_section(src, doc), **run_options(src, doc, dims))
    check_model_inputs(src, study)
    return study


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
