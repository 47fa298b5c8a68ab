"""The set-up tables of a study file: [sensor] and [bands], [method], [outputs], [run].

[scenario] holds plain parameters (``_values``); [sweep] is read in ``spec``.
"""

from __future__ import annotations

import dataclasses
from types import MappingProxyType

import numpy as np

from .. import examples, params
from ..methods import PRESETS
from ..methods import method as make_method
from ._source import Source, section, shown, suggestion, unknown_name
from ._values import BAND_PARAMETERS, SENSOR_PARAMETERS, fixed_parameters, sweep_values

__all__ = ["MTF_VARIABLES", "NIIRS_VARIABLES", "OUTPUT_GROUPS", "SCHEDULERS",
           "SENSOR_PRESETS", "method_and_knobs", "output_variables", "outputs_and_frequency",
           "run_options", "sensor_and_bands"]

#: Built-in sensors a study may start from (``[sensor] preset``), with their bands.
SENSOR_PRESETS = MappingProxyType({"olson": tuple(examples.OLSON_BANDS)})
OUTPUT_GROUPS = ("niirs", "mtf")
#: Variables of the ``niirs`` output group (what :func:`xbsm.niirs` returns), by name.
NIIRS_VARIABLES = (
    "niirs", "snr", "snr_frame", "effective_integration_time", "target_photoelectrons",
    "background_photoelectrons", "contrast_photoelectrons", "well_fill", "shot_noise",
    "scene_noise", "path_noise", "self_emission_noise", "dark_current_noise",
    "quantization_noise", "read_noise", "other_noise", "total_noise", "rer_x", "rer_y",
    "eho_x", "eho_y", "rer", "eho", "coherence_diameter", "cutoff_frequency", "rer_giqe5",
    "gsd", "gsd_gp", "gsd_w", "noise_gain", "slant_range", "elevation_angle", "flags")
#: Variables of the ``mtf`` output group (:func:`xbsm.system_otf`'s, prefixed ``mtf_``).
MTF_VARIABLES = tuple(f"mtf_{name}" for name in (
    "aperture", "turbulence", "detector", "jitter", "drift", "wavefront", "filter",
    "system_unfiltered", "system", "coherence_diameter", "flags"))
SCHEDULERS = ("threads", "synchronous", "local-cluster")


def _preset_bands(src: Source, preset: str, band) -> list:
    """The band names ``[sensor] band`` chooses from the preset sensor (default: nir)."""
    known = SENSOR_PRESETS[preset]
    names = [band] if isinstance(band, str) else ["nir"] if band is None else band
    if (not isinstance(names, list) or not names or len(set(map(str, names))) != len(names)
            or not all(isinstance(name, str) for name in names)):
        raise src.error("sensor", "band", "must be a band name or a list of different band "
                        f"names of the {preset} sensor ({', '.join(known)}); got {shown(band)}")
    for name in names:
        if name not in known:
            raise src.error("sensor", "band", f"unknown band {name!r} of the {preset} sensor; "
                            f"allowed: {', '.join(known)}")
    return names


def _preset(src: Source, table: dict) -> tuple[dict, dict]:
    """The preset sensor's parameters and, for a list of bands, each band's own ones."""
    preset, band = table.get("preset"), table.get("band")
    if preset is None:
        if band is not None:
            raise src.error("sensor", "band", 'a named band needs a sensor preset (preset = '
                            '"olson"); otherwise give the bands as [bands.NAME] tables')
        return {}, {}
    if not isinstance(preset, str) or preset not in SENSOR_PRESETS:
        raise src.error("sensor", "preset", unknown_name("sensor preset", preset, SENSOR_PRESETS))
    names = _preset_bands(src, preset, band)
    if not isinstance(band, list):
        return examples.olson_sensor_parameters(names[0]), {}
    for key in BAND_PARAMETERS:
        if key in table:
            raise src.error("sensor", key, f"is set per band by band = {shown(band)} (the "
                            f"{preset} preset); remove it, or give the bands as [bands.NAME] "
                            "tables")
    # the file's quantum_efficiency, if any, overrides each band's (as any preset value)
    per_band = [*BAND_PARAMETERS] + ([] if "quantum_efficiency" in table
                                     else ["quantum_efficiency"])
    bands = {name: {k: v for k, v in examples.olson_sensor_parameters(name).items()
                    if k in per_band} for name in names}
    return examples.olson_sensor_parameters(names[0]), bands


def sensor_and_bands(src: Source, doc: dict) -> tuple[dict, dict]:
    """Sensor parameters (preset first, then the file's) and the bands, if any."""
    table = section(src, doc, "sensor")
    base, bands = _preset(src, table)
    base.update(fixed_parameters(src, table, "sensor", SENSOR_PARAMETERS))
    custom = section(src, doc, "bands")
    if custom and bands:
        raise src.error("bands", None, "give bands either as [sensor] band = [...] or as "
                        "[bands.NAME] tables, not both")
    for name, values in custom.items():
        if not isinstance(values, dict):
            raise src.error("bands", name, "each band is a table [bands.NAME] of sensor "
                            f"parameters (wavelength_min, wavelength_max, ...); got "
                            f"{shown(values)}")
        bands[name] = fixed_parameters(src, values, f"bands.{name}", SENSOR_PARAMETERS)
    return base, bands


def method_and_knobs(src: Source, doc: dict) -> tuple[str, dict]:
    """Method preset and knob overrides, each checked as :func:`xbsm.method` does."""
    knobs = dict(section(src, doc, "method"))
    preset = knobs.pop("preset", "accurate")
    if not isinstance(preset, str) or preset not in PRESETS:
        raise src.error("method", "preset", unknown_name("method preset", preset, PRESETS))
    known = {f.name for f in dataclasses.fields(PRESETS[preset])} - {"name", "constants"}
    for key, value in knobs.items():
        if key not in known:
            raise src.error("method", key, f"unknown method knob; {suggestion(key, known)}")
        try:
            make_method(preset, **{key: value})
        except (TypeError, ValueError) as err:
            raise src.error("method", key, str(err)) from None
    return preset, knobs


def output_variables(src: Source, doc: dict, groups: tuple) -> tuple:
    """The variables ``[outputs] variables`` keeps (empty: all), each checked by name.

    The flag variable that describes a kept variable (``flags``, or ``mtf_flags`` for
    an ``mtf_*`` one) is always kept with it.
    """
    table = section(src, doc, "outputs", ("include", "mtf_frequency", "variables"))
    if "variables" not in table:
        return ()
    names = table["variables"]
    if not isinstance(names, list) or not names or not all(isinstance(x, str) for x in names):
        raise src.error("outputs", "variables", "must be a non-empty list of output variable "
                        f"names, e.g. [\"niirs\", \"snr\"]; got {shown(names)}")
    for name in names:
        if name in MTF_VARIABLES and "mtf" not in groups:
            raise src.error("outputs", "variables", f"{name!r} is an mtf output; add \"mtf\" "
                            "to include (with mtf_frequency) or remove it")
        if name not in NIIRS_VARIABLES and name not in MTF_VARIABLES:
            raise src.error("outputs", "variables", f"unknown output variable {name!r}; "
                            f"{suggestion(name, NIIRS_VARIABLES + MTF_VARIABLES)}")
    flags = ["flags"] + (["mtf_flags"] if any(n in MTF_VARIABLES for n in names) else [])
    return tuple(dict.fromkeys([*names, *flags]))


def outputs_and_frequency(src: Source, doc: dict) -> tuple[tuple, np.ndarray | None]:
    """Output groups (``niirs`` always; ``mtf`` with its frequency grid)."""
    table = section(src, doc, "outputs", ("include", "mtf_frequency", "variables"))
    include = table.get("include", ["niirs"])
    if not isinstance(include, list) or not include or not all(
            isinstance(x, str) for x in include):
        raise src.error("outputs", "include", f"must be a non-empty list from "
                        f"{list(OUTPUT_GROUPS)}; got {shown(include)}")
    for name in include:
        if name not in OUTPUT_GROUPS:
            raise src.error("outputs", "include", f"unknown output {name!r}; "
                            f"{suggestion(name, OUTPUT_GROUPS)}")
    frequency = None
    if "mtf" in include:
        if "mtf_frequency" not in table:
            raise src.error("outputs", "include", "the mtf output needs mtf_frequency = "
                            "{start, stop, num} or a list (cycles/rad) in [outputs]")
        frequency = sweep_values(src, "outputs", "mtf_frequency", table["mtf_frequency"])
        if np.any(frequency < 0) or len(frequency) > params.MAX_FREQUENCIES:
            raise src.error("outputs", "mtf_frequency", "must hold at most "
                            f"{params.MAX_FREQUENCIES} frequencies, each >= 0 cycles/rad; got "
                            f"{len(frequency)} from {frequency.min():g}")
    elif "mtf_frequency" in table:
        raise src.error("outputs", "mtf_frequency", 'given without "mtf" in include; add '
                        '"mtf" to include or remove mtf_frequency')
    return tuple(dict.fromkeys(["niirs", *include])), frequency


def _whole(src: Source, key: str, value, name: str | None = None) -> None:
    """An error unless ``value`` is a whole number >= 1 (``name``: the chunked dimension)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise src.error("run", key, f"{name + ' ' if name else ''}must be a whole number >= 1;"
                        f" got {shown(value)}")


def run_options(src: Source, doc: dict, dims) -> dict:
    """Chunking, scheduler, workers, the default output path and the zlib level."""
    table = section(src, doc, "run", ("chunk_scenarios", "chunks", "scheduler", "workers",
                                      "output", "compress"))
    out = dict(chunk_scenarios=table.get("chunk_scenarios", 20_000),
               chunks=table.get("chunks", {}), scheduler=table.get("scheduler", "threads"),
               workers=table.get("workers", 2), output=table.get("output"),
               compress=table.get("compress", 0))
    compress = out["compress"]
    if isinstance(compress, bool) or not isinstance(compress, int) or not 0 <= compress <= 9:
        raise src.error("run", "compress", "must be a zlib level, a whole number from 0 (no "
                        f"compression) to 9 (smallest file); got {shown(compress)}")
    for key in ("chunk_scenarios", "workers"):
        _whole(src, key, out[key])
    if not isinstance(out["chunks"], dict):
        raise src.error("run", "chunks", "must be a table {dimension = chunk length}; got "
                        f"{shown(out['chunks'])}")
    for dim, size in out["chunks"].items():
        if dim not in dims:
            raise src.error("run", "chunks", f"unknown dimension {dim!r}; "
                            f"{suggestion(dim, dims) if dims else 'the study has no dimensions'}")
        _whole(src, "chunks", size, dim)
    scheduler = out["scheduler"]
    if not isinstance(scheduler, str) or not (scheduler in SCHEDULERS or "://" in scheduler):
        raise src.error("run", "scheduler", f"must be one of {', '.join(SCHEDULERS)} or a "
                        f"scheduler address such as tcp://host:8786; got {shown(scheduler)}")
    if out["output"] is not None and not (isinstance(out["output"], str) and out["output"]):
        raise src.error("run", "output", "must be a file name such as \"study.nc\"; got "
                        f"{shown(out['output'])}")
    return out
