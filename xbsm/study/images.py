"""Image-dataset studies: every image of a dataset simulated at every scenario of a sweep.

A study file with a ``[dataset]`` table (``docs/datasets.md``) names an image
folder or a COCO file, what to write and how; ``xbsm simulate STUDY.toml`` and
:func:`simulate` run it. The images are cut into chunks of ``chunk_images``;
each chunk is one lazy dask task that reads its images, simulates each at
every scenario (:func:`simulate_batch`, one :func:`xbsm.simulate_images` call per
scenario for the chunk's images, each output with its own seed; images of one
shape share the radiometry and blur, and each output equals the
:func:`simulate_one` call of its image alone) and writes each output image as
soon as the scenario is done, so memory depends on the chunk, not the dataset. Each file
is written whole or not at all (:mod:`xbsm.datasets.writers`); a chunk's record
(its images' metadata and moved labels, with SHA-256 checksums of its files) is
written last, so a chunk with a record is finished. An interrupted run (Ctrl-C,
SIGTERM, a crash) is resumed by running it again: finished chunks are checked
and kept, the others computed again. The COCO files (one per scenario) and the
optional NetCDF table are assembled from the records at the end: a COCO file
that exists is complete.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import math
import os
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .. import flags as fl
from .. import params
from .._netcdf import netcdf_file, write_variables
from ..datasets import coco as coco_labels
from ..datasets import readers, writers
from ..interrupts import (
    INTERRUPTED,
    completing,
    deferred,
    handling_signals,
    stop_if_interrupted,
)
from ._lock import OutputLock
from ._parts import code_checksum
from ._progress import Progress
from ._source import Source, StudyError, section, shown, unknown_name
from ._values import SCENARIO_PARAMETERS, SENSOR_PARAMETERS

__all__ = ["DATASET_KEYS", "DTYPES", "LAYOUTS", "VALUES", "DatasetSpec", "dataset_section",
           "output_cells", "read_dataset", "simulate", "simulate_batch", "simulate_one"]

DATASET_KEYS = ("input", "images", "gsd", "recursive", "output", "layout", "format", "values",
                "dtype", "coco", "netcdf", "chunk_images", "seed", "noise", "tile_size")
#: "scenario-folders": one folder per scenario; "flat": one folder, the scenario in the name.
LAYOUTS = ("scenario-folders", "flat")
#: "counts": the camera's digital numbers; "radiometric": pyBSM's radiometric pixel mapping
#: (reflectance 0.05-0.95 to the dtype's full range, comparable across scenarios).
VALUES = ("counts", "radiometric")
DTYPES = ("uint8", "uint16")
#: The folder of a run's state (chunk records, the run's fingerprint, its lock).
STATE = ".xbsm-run"


@dataclass(frozen=True)
class DatasetSpec:
    """The ``[dataset]`` table of a study: the dataset in, what to write and how."""

    input: str | None = None
    images: str | None = None
    gsd: float | str | None = None
    recursive: bool = False
    output: str | None = None
    layout: str = "scenario-folders"
    format: str = "png"
    values: str = "counts"
    dtype: str | None = None  # default: uint16 for counts, uint8 for radiometric
    coco: bool = True
    netcdf: str | None = None
    chunk_images: int = 8
    seed: int = 0
    noise: bool = True
    tile_size: int | None = None  # reference pixels per tile side (simulate_image's default)
    base: str = "."  # the folder relative paths start from (the study file's)

    @property
    def out_dtype(self) -> str:
        """The dtype of the written images."""
        return self.dtype or ("uint16" if self.values == "counts" else "uint8")

    def path(self, value) -> Path | None:
        """A path of the table, relative to the study file's folder."""
        if value is None:
            return None
        path = Path(value)
        return path if path.is_absolute() else Path(self.base) / path


def dataset_section(src: Source, doc: dict) -> DatasetSpec | None:
    """The ``[dataset]`` table checked, or None without one."""
    if "dataset" not in doc:
        return None
    table = section(src, doc, "dataset", DATASET_KEYS)
    name = Path(src.name)
    base = str(name.parent) if name.is_file() else "."
    texts = {"input": True, "images": False, "output": False, "netcdf": False}
    for key, required in texts.items():
        if required and key not in table:
            raise src.error("dataset", None, "needs input = an image folder or a COCO JSON file")
        if key in table and not (isinstance(table[key], str) and table[key]):
            raise src.error("dataset", key, f"must be a path in quotes; got {shown(table[key])}")
    for key, allowed in (("layout", LAYOUTS), ("format", tuple(writers.FORMATS)),
                         ("values", VALUES), ("dtype", DTYPES)):
        if key in table and table[key] not in allowed:
            raise src.error("dataset", key, unknown_name(key, table[key], allowed))
    for key in ("recursive", "coco", "noise"):
        if key in table and not isinstance(table[key], bool):
            raise src.error("dataset", key, f"must be true or false; got {shown(table[key])}")
    for key, low in (("chunk_images", 1), ("seed", 0), ("tile_size", 64)):
        value = table.get(key, low)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise src.error("dataset", key, f"must be a whole number >= {low}; got "
                            f"{shown(value)}")
    gsd = table.get("gsd")
    if gsd is not None and (isinstance(gsd, bool) or not isinstance(gsd, int | float | str)
                            or (not isinstance(gsd, str) and not (math.isfinite(gsd)
                                                                  and gsd > 0))):
        raise src.error("dataset", "gsd", "must be a ground sample distance in (0, inf) m or a "
                        f"sidecar file (CSV or JSON) in quotes; got {shown(gsd)}")
    return DatasetSpec(**{k: v for k, v in table.items()}, base=base)


def read_dataset(spec: DatasetSpec) -> readers.ImageDataset:
    """The dataset a ``[dataset]`` table names (a COCO file if ``input`` ends in .json)."""
    source = spec.path(spec.input)
    gsd = spec.gsd
    if isinstance(gsd, str):
        gsd = spec.path(gsd)
    if source.suffix.lower() == ".json":
        return readers.from_coco(source, spec.path(spec.images), gsd)
    return readers.from_folder(source, gsd, recursive=spec.recursive)


# --- the scenario cells --------------------------------------------------------------


@dataclass(frozen=True)
class Cell:
    """One scenario of the sweep: its position, its labels, its parameters, its name."""

    index: int
    position: tuple
    labels: dict
    sensor: object
    scenario: object
    name: str


def _label_text(value) -> str:
    return f"{value:g}" if isinstance(value, float | np.floating) else str(value)


def output_cells(study) -> list[Cell]:
    """Every scenario of the study's sweep (bands first, then the sweeps in file order)."""
    axes = []
    if study.bands:
        axes.append(("band", [(name, {"band": name}, dict(values))
                              for name, values in study.bands.items()]))
    for sweep in study.sweeps:
        paired = list(sweep.values) != [sweep.dim]
        steps = []
        for k in range(sweep.size):
            values = {name: float(v[k]) for name, v in sweep.values.items()}
            steps.append((k if paired else values[sweep.dim],
                          {sweep.dim: k, **values} if paired else values, values))
        axes.append((sweep.dim, steps))
    cells = []
    ranges = [range(len(steps)) for _, steps in axes]
    for index, position in enumerate(itertools.product(*ranges)):
        combo = [steps[k] for (_, steps), k in zip(axes, position, strict=True)]
        kwargs = {**study.sensor, **study.scenario}
        labels = {}
        for _label, shown_values, values in combo:
            kwargs.update(values)
            labels.update(shown_values)
        name = "__".join(f"{dim}={_label_text(label)}"
                         for (dim, _), (label, _, _) in zip(axes, combo, strict=True))
        sensor = params.sensor(**{k: v for k, v in kwargs.items() if k in SENSOR_PARAMETERS})
        scenario = params.scenario(**{k: v for k, v in kwargs.items()
                                      if k in SCENARIO_PARAMETERS})
        cells.append(Cell(index, position, labels, sensor, scenario, name or "scenario"))
    return cells


def _method(study):
    from ..methods import method

    return method(study.method, **study.knobs) if study.knobs else study.method


def output_seed(seed: int, image_position: int, cell_index: int) -> int:
    """The noise seed of one output: 64 bits spawned from the study's seed, image and scenario."""
    state = np.random.SeedSequence(seed, spawn_key=(image_position, cell_index)).generate_state(
        2, np.uint32)
    return (int(state[0]) << 32) | int(state[1])


def simulate_batch(images, gsds, cell: Cell, spec: DatasetSpec, seeds, method) -> list:
    """Images at one scenario, each with its own seed: (written array, Dataset) per image.

    One :func:`xbsm.simulate_images` call: images of one shape and GSD are simulated
    as a stack (one radiometry and blur for all), large ones in tiles of
    ``spec.tile_size``; every output equals its image's :func:`simulate_one`. The
    ``upsampled`` flag is left to the caller, who warns once per run.
    """
    from ..simulate import image as sim

    counts = spec.values == "counts"
    dtype = np.dtype(spec.out_dtype)
    results = sim.simulate_images(images, cell.sensor, cell.scenario, gsd=list(gsds),
                                  seeds=list(seeds), noise=spec.noise, method=method,
                                  outputs=("counts",) if counts else ("noisy",),
                                  counts_dtype=dtype if counts else None,
                                  tile_size=spec.tile_size, warn_upsampled=False)
    return [(_written(result, spec), result) for result in results]


def _written(result, spec: DatasetSpec) -> np.ndarray:
    """The array written for one output: the counts, or the radiometric pixel mapping."""
    from ..simulate import inverse

    dtype = np.dtype(spec.out_dtype)
    if spec.values == "counts":
        image = result["counts"]
    else:
        top = float(np.iinfo(dtype).max)
        image = inverse.photoelectrons_to_pixels(result["noisy"], result,
                                                 pixel_range=(0.0, top))
    image = image.transpose("y", "x", ...).values
    if spec.values != "counts":
        image = np.rint(np.nan_to_num(image, nan=0.0)).astype(dtype)
    return image


def simulate_one(pixels, gsd: float, cell: Cell, spec: DatasetSpec, seed: int, method):
    """One image at one scenario: the written image's array and the simulation Dataset.

    The same call regenerates any output alone: the image, its GSD, the scenario and
    the output's seed (all recorded in the COCO file) give the same pixels.
    """
    from ..simulate import image as sim

    counts = spec.values == "counts"
    dtype = np.dtype(spec.out_dtype)
    result = sim.simulate_image(pixels, cell.sensor, cell.scenario, gsd=gsd, seed=seed,
                                noise=spec.noise, method=method,
                                outputs=("counts",) if counts else ("noisy",),
                                counts_dtype=dtype if counts else None,
                                tile_size=spec.tile_size,
                                warn_upsampled=False)  # once per run, from the flags
    return _written(result, spec), result


# --- the run's files -----------------------------------------------------------------


def _stem(name: str) -> str:
    path = Path(name)
    return path.with_suffix("").as_posix()


def _image_name(spec: DatasetSpec, item, cell: Cell) -> str:
    """An output image's path relative to the output folder."""
    suffix = writers.FORMATS[spec.format]
    if spec.layout == "flat":
        return f"{_stem(item.name)}__{cell.name}{suffix}"
    return f"{cell.name}/{_stem(item.name)}{suffix}"


def _coco_name(spec: DatasetSpec, cell: Cell) -> str:
    return (f"annotations__{cell.name}.json" if spec.layout == "flat"
            else f"{cell.name}/annotations.json")


def _fingerprint(study, spec: DatasetSpec, dataset, method) -> dict:
    """Everything that determines the outputs' bytes, as text."""
    from .._version import __version__

    listing = []
    for item in dataset:
        entry = [item.id, item.name, item.height, item.width, item.channels, item.gsd]
        if item.path is not None:
            stat = item.path.stat()
            entry += [stat.st_size, stat.st_mtime_ns]
        else:
            entry.append(hashlib.sha256(np.ascontiguousarray(item.array)).hexdigest())
        entry.append(hashlib.sha256(json.dumps([item.boxes.tolist(), list(item.annotations)],
                                               sort_keys=True, default=str).encode())
                     .hexdigest())
        listing.append(entry)
    spec_fields = {k: v for k, v in asdict(spec).items() if k not in ("output", "base")}
    return {"study": study.text, "method": repr(method), "dataset": hashlib.sha256(
        json.dumps(listing, default=str).encode()).hexdigest(), "spec": json.dumps(
        spec_fields, sort_keys=True, default=str), "xbsm": __version__, "code": code_checksum(),
        "numpy": np.__version__}


def _digest(print_: dict) -> str:
    return hashlib.sha256(json.dumps(print_, sort_keys=True).encode()).hexdigest()


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _record_file(state: Path, chunk: int) -> Path:
    return state / "chunks" / f"chunk-{chunk:06d}.json"


def _verified(out: Path, file: Path, digest: str) -> dict | None:
    """A chunk's record if it is this run's and every file it lists is intact, else None."""
    try:
        record = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("fingerprint") != digest:
        return None
    for entry in record.get("outputs", []):
        path = out / entry["file_name"]
        if not path.is_file() or path.stat().st_size != entry["bytes"] \
                or _sha256(path) != entry["sha256"]:
            return None
    return record


def _flag_names(code: int) -> list[str]:
    return [name for name, spec in fl.FLAGS.items() if code & spec[0]]


def _run_chunk(chunk: int, positions, dataset, cells, spec, method, out: Path, state: Path,
               digest: str, progress) -> int:
    """Simulate and write one chunk of images at every scenario; its record last."""
    outputs = []
    items = [dataset[position] for position in positions]
    pixels = [item.pixels() for item in items]
    for cell in cells:
        if INTERRUPTED.is_set():  # a signal: stop between two scenarios
            return chunk
        seeds = [output_seed(spec.seed, position, cell.index) for position in positions]
        made = simulate_batch(pixels, [item.gsd for item in items], cell, spec, seeds, method)
        for position, item, seed, (image, result) in zip(positions, items, seeds, made,
                                                         strict=True):
            outputs.append(_write_output(out, spec, position, item, cell, seed, image, result))
        progress.add(len(positions))
    if INTERRUPTED.is_set():
        return chunk
    outputs.sort(key=lambda entry: (entry["position"], entry["cell"]))
    writers.write_json(_record_file(state, chunk), {"fingerprint": digest, "chunk": chunk,
                                                     "outputs": outputs})
    return chunk


def _write_output(out: Path, spec, position: int, item, cell: Cell, seed: int, image,
                  result) -> dict:
    """One output image written; its record (metadata, moved labels, checksum)."""
    name = _image_name(spec, item, cell)
    path = out / name
    path.parent.mkdir(parents=True, exist_ok=True)
    writers.write_image(path, image, spec.format)
    pixel_map = coco_labels.PixelMap.of(result)
    code = int(result["flags"].values.max())
    annotations, dropped = coco_labels.move_annotations(item, pixel_map, 0, 0)
    return {
        "position": position, "cell": cell.index, "file_name": name,
        "bytes": path.stat().st_size, "sha256": _sha256(path),
        "width": pixel_map.size_x, "height": pixel_map.size_y,
        "annotations": annotations, "rle_dropped": dropped,
        "xbsm": {
            "source_file": item.name, "source_id": item.id, "scenario": cell.labels,
            "seed": str(seed), "noise": spec.noise, "values": spec.values,
            "dtype": spec.out_dtype, "reference_gsd": item.gsd,
            **{k: float(result[k]) for k in ("gsd", "gsd_x", "gsd_y", "slant_range",
                                             "scale_x", "offset_x", "scale_y", "offset_y")},
            "flags": code, "flag_names": _flag_names(code)}}


def _check_outputs(spec: DatasetSpec, dataset, cells, out: Path) -> None:
    """Refuse what cannot be written before any work: dtype too narrow, names that collide."""
    if spec.values == "counts":
        bits = 8 * np.dtype(spec.out_dtype).itemsize
        for cell in cells:
            depth = float(cell.sensor["bit_depth"].max())
            if depth > bits:
                raise StudyError(f"dataset.dtype {spec.out_dtype!r} holds {bits}-bit counts but "
                                 f"the camera ({cell.name}) has bit_depth {depth:g}; give dtype "
                                 "= \"uint16\" or values = \"radiometric\"")
    seen = {}
    for item in dataset:
        name = _image_name(spec, item, cells[0])
        if name in seen:
            raise StudyError(f"{dataset.source}: images {seen[name]!r} and {item.name!r} would "
                             f"both be written as {name!r}; rename one")
        seen[name] = item.name
    source = Path(dataset.source)
    if source.is_dir() and out.resolve() == source.resolve():
        raise StudyError(f"the output folder {out} is the input folder; give another with -o")


def _prepare(out: Path, state: Path, print_: dict, overwrite: bool) -> None:
    """The state folder for this run: kept if it is this run's, refused or cleared if not."""
    run_file = state / "run.json"
    complete = state / "complete.json"
    if run_file.is_file():
        try:
            previous = json.loads(run_file.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            previous = {}
        same = previous == print_
        if not overwrite and not same:
            differs = sorted(k for k in print_ if previous.get(k) != print_[k])
            raise StudyError(f"{out} holds the outputs of another run (it differs in "
                             f"{', '.join(differs) or 'everything'}); give --overwrite "
                             "(overwrite=True) to replace them, or another output with -o")
        if not overwrite and complete.is_file():
            raise StudyError(f"{out} is complete (a finished run); give --overwrite "
                             "(overwrite=True) to compute it again, or another output with -o")
        if overwrite:
            for file in sorted((state / "chunks").glob("chunk-*.json")):
                file.unlink()
            complete.unlink(missing_ok=True)
    (state / "chunks").mkdir(parents=True, exist_ok=True)
    writers.write_json(run_file, print_)
    for temp in out.rglob(f"{writers.TEMP_PREFIX}*"):  # left by an interrupted run
        temp.unlink(missing_ok=True)


def _categories(dataset) -> list:
    if dataset.categories:
        return list(dataset.categories)
    if any(len(item.boxes) for item in dataset):
        return [{"id": 1, "name": "object", "supercategory": "object"}]
    return []


def _records(state: Path, chunks: int):
    """Every output's record, chunk by chunk (one chunk's records in memory at a time)."""
    for chunk in range(chunks):
        yield from json.loads(_record_file(state, chunk).read_text(encoding="utf-8"))["outputs"]


def _coco_items(state, chunks, spec, dataset, cell, what: str):
    """The COCO ``images`` or ``annotations`` of one scenario, one JSON text at a time."""
    next_id = 1
    for entry in _records(state, chunks):
        if entry["cell"] != cell.index:
            continue
        image_id = dataset[entry["position"]].id
        if what == "images":
            # relative to the COCO file's folder (the scenario's folder, or the output's)
            name = entry["file_name"]
            if spec.layout != "flat":
                name = name.split("/", 1)[1]
            yield _json({"id": image_id, "file_name": name, "width": entry["width"],
                         "height": entry["height"], "xbsm": entry["xbsm"]})
            continue
        for ann in entry["annotations"]:
            yield _json({**ann, "id": next_id, "image_id": image_id})
            next_id += 1


def _json(doc) -> str:
    return json.dumps(doc, allow_nan=False, separators=(",", ":"))


def _write_coco(path: Path, head: dict, parts) -> None:
    """A COCO file written as it is read from the records, whole or not at all."""
    with writers.atomic_file(path) as handle:
        handle.write(_json(head)[:-1])
        for key, texts in parts:
            handle.write(f',"{key}":[')
            for k, text in enumerate(texts):
                handle.write(("," if k else "") + text)
            handle.write("]")
        handle.write("}")


def _assemble(out, state, spec, dataset, cells, chunks, study, say) -> None:
    """The COCO file of every scenario (and the NetCDF table) from the chunk records.

    The records are read from disk again for each file, so memory holds one chunk's
    records, not the dataset's.
    """
    upsampled = dropped = total = 0
    for entry in _records(state, chunks):
        total += 1
        upsampled += "upsampled" in entry["xbsm"]["flag_names"]
        dropped += entry["rle_dropped"]
    if upsampled:
        warnings.warn(f"{upsampled} of {total} simulated images are more finely sampled "
                      "than their reference image (flag 'upsampled' in their metadata): the "
                      "camera is better than the reference, so they lack detail it would "
                      "record", UserWarning, stacklevel=3)
    if dropped:
        say("xbsm simulate: run-length (RLE) masks cannot be moved to the simulated images; "
            "their annotations keep their moved boxes without a segmentation")
    categories = _json(_categories(dataset))
    with deferred():  # a signal waits for the file being written, then stops the run
        if spec.coco:
            for cell in cells:
                stop_if_interrupted()
                head = {"info": {"description": f"{study.title or 'xbsm'}: {cell.name}",
                                 "source": Path(dataset.source).name,
                                 "xbsm_scenario": cell.labels}}
                path = out / _coco_name(spec, cell)
                path.parent.mkdir(parents=True, exist_ok=True)
                _write_coco(path, head, [
                    ("images", _coco_items(state, chunks, spec, dataset, cell, "images")),
                    ("annotations", _coco_items(state, chunks, spec, dataset, cell,
                                                "annotations")),
                    ("categories", iter([categories[1:-1]] if categories != "[]" else []))])
        if spec.netcdf:
            stop_if_interrupted()
            _write_table(out / spec.netcdf, _records(state, chunks), dataset, cells, study)


def _write_table(path: Path, rows, dataset, cells, study) -> None:
    """One NetCDF file of the sweep: every output's metadata over (image, scenario)."""
    import xarray as xr

    n, m = len(dataset), len(cells)
    names = ("gsd", "gsd_x", "gsd_y", "slant_range", "scale_x", "offset_x", "scale_y",
             "offset_y")
    table = {k: np.full((n, m), np.nan) for k in names}
    seeds = np.zeros((n, m), np.uint64)
    codes = np.zeros((n, m), np.int32)
    files = np.full((n, m), "", dtype=object)
    sizes = {k: np.zeros((n, m), np.int32) for k in ("width", "height")}
    for row in rows:
        i, j = row["position"], row["cell"]
        for k in names:
            table[k][i, j] = row["xbsm"][k]
        seeds[i, j] = int(row["xbsm"]["seed"])
        codes[i, j] = row["xbsm"]["flags"]
        files[i, j] = row["file_name"]
        for k in sizes:
            sizes[k][i, j] = row[k]
    units = {"gsd": "m", "gsd_x": "m", "gsd_y": "m", "slant_range": "m"}
    ds = xr.Dataset(
        {**{k: (("image", "scenario"), v, {"units": units.get(k, "1")})
            for k, v in table.items()},
         "seed": (("image", "scenario"), seeds, {"long_name": "noise seed of the output"}),
         "flags": (("image", "scenario"), codes, fl.flag_attrs("image simulation validity "
                                                               "flags")),
         "file_name": (("image", "scenario"), files.astype(str)),
         "size_x": (("image", "scenario"), sizes["width"], {"units": "1"}),
         "size_y": (("image", "scenario"), sizes["height"], {"units": "1"})},
        coords={"image": ("image", [item.id for item in dataset]),
                "source_file": ("image", [item.name for item in dataset]),
                "reference_gsd": ("image", [item.gsd for item in dataset], {"units": "m"}),
                "scenario": ("scenario", [cell.name for cell in cells])},
        attrs={"title": study.title or "xbsm image dataset study", "Conventions": "CF-1.8",
               "xbsm_study": study.text})
    temp = writers.temp_path(path)
    try:
        with netcdf_file(temp, "w") as nc:  # all of it under xbsm's NetCDF lock
            write_variables(nc, ds)
        os.replace(temp, path)
    finally:
        temp.unlink(missing_ok=True)


def simulate(study, out=None, *, dataset=None, overwrite=False, workers=None, progress=True,
             say=print) -> Path:
    """Simulate every image of a dataset at every scenario of a study; write the outputs.

    Parameters
    ----------
    study : xbsm.study.Study
        A study with a ``[dataset]`` table (or any study, with ``dataset=``).
    out : str or Path, optional
        The output folder; default the table's ``output``.
    dataset : xbsm.datasets.ImageDataset, optional
        The images (e.g. :func:`xbsm.datasets.from_arrays`); default the table's ``input``.
    overwrite : bool
        Replace a finished run's outputs (or another run's) in ``out``.
    workers : int, optional
        Threads computing chunks; default the study's ``[run] workers``.
    progress : bool
        A progress bar (a line per 10 % in a log) on standard error.
    say : callable
        Where the one-line notices go.

    Returns
    -------
    Path
        The output folder. Images, one COCO file per scenario (``coco = true``) and
        the NetCDF table (``netcdf = "..."``) are in it, each complete.
    """
    spec = getattr(study, "dataset", None)
    if spec is None:
        if dataset is None:
            raise StudyError("the study has no [dataset] table; add one (docs/datasets.md) "
                             "or pass dataset=")
        spec = DatasetSpec()
    out = Path(out) if out is not None else spec.path(spec.output)
    if out is None:
        raise StudyError("no output folder: give output = \"...\" in [dataset] or -o FOLDER")
    if out.exists() and not out.is_dir():
        raise StudyError(f"the output {out} is a file; give a folder")
    dataset = dataset if dataset is not None else read_dataset(spec)
    cells = output_cells(study)
    method = _method(study)
    _check_outputs(spec, dataset, cells, out)
    out.mkdir(parents=True, exist_ok=True)
    state = out / STATE
    state.mkdir(exist_ok=True)
    with handling_signals(), OutputLock(state / "run", study.title or "image dataset"):
        print_ = _fingerprint(study, spec, dataset, method)
        _prepare(out, state, print_, overwrite)
        digest = _digest(print_)
        size = spec.chunk_images
        chunks = [list(range(k, min(k + size, len(dataset))))
                  for k in range(0, len(dataset), size)]
        missing = [k for k in range(len(chunks))
                   if _verified(out, _record_file(state, k), digest) is None]
        if len(missing) < len(chunks):
            say(f"xbsm simulate: resuming: {len(chunks) - len(missing)} of {len(chunks)} "
                "chunks are finished and kept")
        _compute(missing, chunks, dataset, cells, spec, method, out, state, digest,
                 workers or study.workers, progress)
        stop_if_interrupted()
        _assemble(out, state, spec, dataset, cells, len(chunks), study, say)
        with completing():  # from here a signal no longer makes the run "interrupted"
            writers.write_json(state / "complete.json", {"fingerprint": digest})
    return out


def _compute(missing, chunks, dataset, cells, spec, method, out, state, digest, workers,
             progress) -> None:
    """The missing chunks as lazy dask tasks, computed a few at a time on threads."""
    import dask

    from ..atmosphere import database_visibilities, load_database

    # read the database once here: netCDF4 (HDF5) must not open a file on two threads at once
    load_database()
    database_visibilities()
    bar = Progress("simulating images", sum(len(chunks[k]) for k in missing) * len(cells),
                   enabled=progress)
    batch = max(1, 2 * workers)
    # the heavy arguments in a partial: dask neither traverses nor hashes them
    run = functools.partial(_run_chunk, dataset=dataset, cells=cells, spec=spec, method=method,
                            out=out, state=state, digest=digest, progress=bar)
    for start in range(0, len(missing), batch):
        stop_if_interrupted()
        tasks = [dask.delayed(run, pure=False)(k, chunks[k])
                 for k in missing[start:start + batch]]
        dask.compute(*tasks, scheduler="threads", num_workers=workers)
        stop_if_interrupted()

