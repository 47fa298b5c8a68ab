"""Study files: each kind of bad file gives one clear message; valid files parse as written.

One row per kind of mistake. A row gives the study text, a fragment naming the key at
fault, the line the key is on (counted by hand in the text of the row; None where the
key is not in the file) and a fragment of what is allowed. Every expected value below
comes from the study text itself, from a closed form (stated), from paper Table 2 or
Appendix A, or from the parameter ranges of ``xbsm.params``.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import cli, examples
from xbsm.study import Study, StudyError, load, parse

# A minimal valid study, 12 lines (the line numbers of the rows below count from it).
VALID = """title = "test study"

[sensor]
preset = "olson"
band = "red"

[scenario]
altitude = 9000.0
visibility = 23.0

[sweep]
ground_range = [1000.0, 2000.0]
"""

#: Fragments that would betray Python internals in a message meant for a user.
INTERNALS = ("Traceback", "KeyError", "TypeError", "AttributeError", "IndexError",
             "object has no attribute", "unhashable", "np.", "numpy", "xarray", "xr.",
             "DataArray", "ndarray", "Dataset", "float64", "dtype", "<class", "MappingProxy",
             "codec", "Errno", "',)", "\x00")


def replaced(old: str, new: str, text: str = VALID) -> str:
    """The valid study with one piece changed (the piece must be there)."""
    assert old in text
    return text.replace(old, new, 1)


def appended(extra: str) -> str:
    """The valid study with more lines after it: the first added line is line 13."""
    return VALID + extra


def method(body: str) -> str:
    """A [method] table after the valid study: its first key is on line 15."""
    return appended(f"\n[method]\n{body}\n")


def outputs(body: str) -> str:
    """An [outputs] table after the valid study: its first key is on line 15."""
    return appended(f"\n[outputs]\n{body}\n")


def run_table(body: str) -> str:
    """A [run] table after the valid study: its first key is on line 15."""
    return appended(f"\n[run]\n{body}\n")


def row(kind, text, key, line, allowed):
    return pytest.param(text, key, line, allowed, id=kind)


BAD = [
    # ---- TOML syntax: the line of the error and its text --------------------------------
    row("toml_unclosed_table_header", appended("[run\n"), "[run", 13, "TOML 1.0"),
    row("toml_missing_value", replaced("altitude = 9000.0", "altitude ="), "altitude", 8,
        "TOML 1.0"),
    row("toml_table_declared_twice", appended("\n[sensor]\n"), "[sensor]", 14, "TOML 1.0"),
    row("toml_control_character", appended("\x00\n"), "\\x00", 13, "TOML 1.0"),
    row("toml_duplicate_key", replaced("visibility = 23.0", "visibility = 23.0\naltitude = 1.0"),
        "altitude", 10, "TOML 1.0"),
    # ---- unknown keys, with the closest known name ---------------------------------------
    row("unknown_top_level_key", replaced('title = "test study"', 'titel = "test study"'),
        "titel", 1, "'title'"),
    row("unknown_sensor_key", replaced('band = "red"', 'band = "red"\nfocal_lenght = 4.0'),
        "sensor.focal_lenght", 6, "'focal_length'"),
    row("unknown_scenario_key",
        replaced("visibility = 23.0", "visibility = 23.0\nplatfrom_speed = 100.0"),
        "scenario.platfrom_speed", 10, "'platform_speed'"),
    row("unknown_sweep_key", appended("jiter_x = [0.0, 1e-6]\n"), "sweep.jiter_x", 13,
        "'jitter_x'"),
    row("unknown_method_key", method('edge_rul = "gauss_legendre"'), "method.edge_rul", 15,
        "'edge_rule'"),
    row("unknown_method_knob", method("quadrature = 1"), "method.quadrature", 15,
        "edge_rule"),
    row("unknown_outputs_key", outputs('includes = ["niirs"]'), "outputs.includes", 15,
        "'include'"),
    row("unknown_run_key", run_table("worker = 2"), "run.worker", 15, "'workers'"),
    row("unknown_key_of_a_range",
        replaced("[1000.0, 2000.0]", "{start = 0.0, stop = 1e4, nmu = 3}"),
        "sweep.ground_range.nmu", 12, "'num'"),
    row("unknown_parameter_in_paired_sweep",
        appended("\n[sweep.case]\nfocal_lenght = [3.0, 4.0]\n"), "sweep.case.focal_lenght", 15,
        "'focal_length'"),
    # ---- wrong types ---------------------------------------------------------------------
    row("text_for_a_number", replaced("altitude = 9000.0", 'altitude = "9 km"'),
        "scenario.altitude", 8, "number in SI units [m]"),
    row("boolean_for_a_number", replaced("visibility = 23.0", "visibility = true"),
        "scenario.visibility", 9, "number in SI units [km]"),
    row("date_for_a_number", replaced("altitude = 9000.0", "altitude = 1979-05-27"),
        "scenario.altitude", 8, "number in SI units [m]"),
    row("number_for_a_list", replaced("[1000.0, 2000.0]", "1000.0"), "sweep.ground_range", 12,
        "list of numbers"),
    row("list_in_a_fixed_table",
        replaced('band = "red"', 'band = "red"\nfocal_length = [3.0, 4.0]'),
        "sensor.focal_length", 6, "move it to [sweep]"),
    row("booleans_in_a_sweep", replaced("[1000.0, 2000.0]", "[true, false]"),
        "sweep.ground_range", 12, "list of numbers"),
    row("text_for_a_table", "method = \"pybsm\"\n" + VALID, "method", 1, "a table ([method])"),
    row("number_for_the_title", replaced('title = "test study"', "title = 3"), "title", 1,
        "text in quotes"),
    row("text_for_range_start",
        replaced("[1000.0, 2000.0]", '{start = "0", stop = 1e4, num = 3}'),
        "sweep.ground_range.start", 12, "finite number"),
    row("ragged_filter_kernel",
        replaced('band = "red"', 'band = "red"\nfilter_kernel = [[1.0], [0.0, 0.0]]'),
        "sensor.filter_kernel", 6, "rows of one length"),
    row("spectral_curve_with_wrong_keys",
        replaced('band = "red"', 'band = "red"\nquantum_efficiency = '
                 '{wavelength = [0.5e-6, 0.66e-6], value = [0.8, 0.8]}'),
        "sensor.quantum_efficiency", 6, "values = [...]"),
    row("knob_of_the_wrong_type", method('frequency_samples = "101"'),
        "method.frequency_samples", 15, "whole number in [3, 100001]"),
    row("outputs_not_a_list", outputs('include = "niirs"'), "outputs.include", 15,
        "non-empty list"),
    row("output_path_not_text", run_table("output = 3"), "run.output", 15, "file name"),
    # ---- values out of range (ranges from xbsm.params) -----------------------------------
    row("negative_focal_length", replaced('band = "red"', 'band = "red"\nfocal_length = -4.0'),
        "focal_length", 6, "(0, inf) m"),
    row("negative_ground_range_in_a_sweep", replaced("[1000.0, 2000.0]", "[-1000.0, 2000.0]"),
        "ground_range", 12, "[0, 300000] m"),
    row("ground_range_beyond_the_database", replaced("[1000.0, 2000.0]", "[1000.0, 350000.0]"),
        "ground_range", 12, "[0, 300000] m"),
    row("visibility_outside_the_database", replaced("visibility = 23.0", "visibility = 50.0"),
        "visibility", 9, "[5, 23] km: the atmosphere database holds 23, 5 km"),
    row("altitude_above_the_database", replaced("altitude = 9000.0", "altitude = 600000.0"),
        "altitude", 8, "[2, 550000] m"),
    row("negative_value_in_a_dotted_paired_sweep",
        appended("case.focal_length = [3.0, 4.0]\ncase.aperture_diameter = [-0.1, 0.2]\n"),
        "sweep.case.aperture_diameter", 14, "(0, inf) m"),
    row("negative_value_in_an_inline_paired_sweep",
        appended("case = {focal_length = [3.0, 4.0], aperture_diameter = [-0.1, 0.2]}\n"),
        "sweep.case.aperture_diameter", 13, "(0, inf) m"),
    row("negative_value_after_a_multiline_array",
        replaced("[1000.0, 2000.0]", "[\n    1000.0,  # a comment = 1\n    2000.0,\n]")
        + "jitter_x = [0.0, -1e-6]\n", "jitter_x", 16, "[0, inf) rad"),
    row("negative_value_after_a_multiline_string",
        'description = """\naltitude = 1\n[scenario]\n"""\n'
        + replaced("altitude = 9000.0", "altitude = -1.0"), "scenario.altitude", 12,
        "[2, 550000] m"),
    row("band_edges_reversed_in_a_quoted_band_table",
        appended('\n[bands."near infrared"]\nwavelength_min = 0.9e-6\nwavelength_max = 0.6e-6\n'),
        "wavelength_min", 15, "smaller than wavelength_max"),
    row("filter_kernel_not_summing_to_one",
        replaced('band = "red"', 'band = "red"\nfilter_kernel = [1.0, 2.0]'),
        "filter_kernel", 6, "sum to 1"),
    row("negative_mtf_frequency", outputs('include = ["mtf"]\nmtf_frequency = [-1.0, 1e5]'),
        "outputs.mtf_frequency", 16, ">= 0 cycles/rad"),
    # ---- sweeps ----------------------------------------------------------------------------
    row("empty_sweep", replaced("[1000.0, 2000.0]", "[]"), "sweep.ground_range", 12,
        "non-empty list"),
    row("range_with_num_zero", replaced("[1000.0, 2000.0]", "{start = 0.0, stop = 1e4, num = 0}"),
        "sweep.ground_range.num", 12, "whole number from 1"),
    row("range_too_long",
        replaced("[1000.0, 2000.0]", "{start = 0.0, stop = 1e4, num = 100000000}"),
        "sweep.ground_range.num", 12, "from 1 to 1e+07"),
    row("log_range_from_zero", replaced(
        "[1000.0, 2000.0]", '{start = 0.0, stop = 1e4, num = 3, spacing = "log"}'),
        "sweep.ground_range.start", 12, "start > 0"),
    row("range_without_stop", replaced("[1000.0, 2000.0]", "{start = 0.0, num = 3}"),
        "sweep.ground_range", 12, "needs start, stop and num"),
    row("range_with_unknown_spacing", replaced(
        "[1000.0, 2000.0]", '{start = 1.0, stop = 1e4, num = 3, spacing = "geometric"}'),
        "sweep.ground_range.spacing", 12, '"linear" or "log"'),
    row("repeated_values_in_a_sweep", replaced("[1000.0, 2000.0]", "[1000.0, 1000.0]"),
        "sweep.ground_range", 12, "must not repeat"),
    row("not_a_number_in_a_sweep", replaced("[1000.0, 2000.0]", "[nan, 1000.0]"),
        "sweep.ground_range", 12, "finite numbers"),
    row("unknown_word_for_a_sweep", replaced("[1000.0, 2000.0]", '"all"'),
        "sweep.ground_range", 12, '"database"'),
    row("paired_sweep_of_unequal_lengths",
        appended("\n[sweep.optics]\naperture_diameter = [0.2, 0.275]\nfocal_length = [3.0]\n"),
        "sweep.optics", 14, "one number of values"),
    row("parameter_swept_twice", appended("\n[sweep.case]\nground_range = [5000.0, 6000.0]\n"),
        "sweep.case.ground_range", 15, "sweep each parameter once"),
    row("parameter_fixed_and_swept",
        replaced("visibility = 23.0", "visibility = 23.0\nground_range = 5000.0"),
        "scenario.ground_range", 10, "keep one"),
    row("swept_band_edge", appended("wavelength_min = [0.5e-6, 0.6e-6]\n"),
        "sweep.wavelength_min", 13, "[bands.NAME]"),
    row("swept_spectral_curve", appended("quantum_efficiency = [0.5, 0.6]\n"),
        "sweep.quantum_efficiency", 13, "set it in [sensor]"),
    row("swept_filter_kernel", appended("filter_kernel = [1.0, 2.0]\n"),
        "sweep.filter_kernel", 13, "set it in [sensor]"),
    row("empty_paired_sweep", appended("\n[sweep.case]\n"), "sweep.case", 14,
        "at least one parameter"),
    row("paired_sweep_as_array_of_tables", appended("\n[[sweep.case]]\nfocal_length = [3.0]\n"),
        "sweep.case", 14, "one table [sweep.case]"),
    row("paired_sweep_named_like_a_parameter",
        appended("\n[sweep.focal_length]\naperture_diameter = [0.2, 0.275]\n"),
        "sweep.focal_length.aperture_diameter", 15, "e.g. [sweep.case]"),
    row("dimension_named_wavelength", appended("\n[sweep.wavelength]\nfocal_length = [3.0, 4.0]\n"),
        "sweep.wavelength", 14, "choose another name"),
    row("dimension_named_giqe", appended("\n[sweep.giqe]\nfocal_length = [3.0, 4.0]\n"),
        "sweep.giqe", 14, "choose another name"),
    row("dimension_named_band", appended("\n[sweep.band]\nfocal_length = [3.0, 4.0]\n"),
        "sweep.band", 14, "[bands.NAME]"),
    row("too_many_scenarios", appended(  # 2 x 1e5 x 1e5 = 2e10 scenarios
        "\n[sweep.a]\nfocal_length = {start = 1.0, stop = 2.0, num = 100000}\n"
        "[sweep.b]\naperture_diameter = {start = 0.1, stop = 0.2, num = 100000}\n"),
        "sweep", 11, "at most 1e+10"),
    # ---- sensor, preset and bands --------------------------------------------------------
    row("missing_sensor_field", replaced(
        'preset = "olson"\nband = "red"', "aperture_diameter = 0.275\npixel_pitch_x = 8e-6\n"
        "wavelength_min = 0.5e-6\nwavelength_max = 0.66e-6"),
        "focal_length", 3, "set it in [sensor] or sweep it"),
    row("no_sensor_table", replaced('[sensor]\npreset = "olson"\nband = "red"\n', ""),
        "aperture_diameter", None, "set it in [sensor] or sweep it"),
    row("missing_scenario_field", replaced("visibility = 23.0\n", ""), "visibility", 7,
        "set it in [scenario] or sweep it"),
    row("unknown_sensor_preset", replaced('preset = "olson"', 'preset = "olsen"'),
        "sensor.preset", 4, "'olson'"),
    row("sensor_preset_in_a_list", replaced('preset = "olson"', 'preset = ["olson"]'),
        "sensor.preset", 4, "olson"),
    row("unknown_band_of_the_preset", replaced('band = "red"', 'band = "blue"'),
        "sensor.band", 5, "red, nir"),
    row("band_given_as_a_number", replaced('band = "red"', "band = 3"), "sensor.band", 5,
        "red, nir"),
    row("band_listed_twice", replaced('band = "red"', 'band = ["red", "red"]'), "sensor.band", 5,
        "different band names"),
    row("band_without_a_preset", replaced('preset = "olson"\n', ""), "sensor.band", 4,
        'preset = "olson"'),
    row("band_edge_with_a_band_list",
        replaced('band = "red"', 'band = ["red", "nir"]\nwavelength_min = 0.5e-6'),
        "sensor.wavelength_min", 6, "[bands.NAME]"),
    row("band_list_and_band_tables", replaced('band = "red"', 'band = ["red", "nir"]')
        + "\n[bands.swir]\nwavelength_min = 1.0e-6\nwavelength_max = 1.7e-6\n",
        "bands", 14, "not both"),
    row("band_that_is_not_a_table", appended("\n[bands]\nred = 3\n"), "bands.red", 15,
        "a table [bands.NAME]"),
    # ---- method --------------------------------------------------------------------------
    row("unknown_method_preset", method('preset = "acurate"'), "method.preset", 15,
        "'accurate'"),
    row("method_preset_in_a_list", method('preset = ["pybsm"]'), "method.preset", 15,
        "accurate, fast, pybsm"),
    row("bad_knob_value", method('edge_rule = "gaus"'), "edge_rule", 15, "'gauss_legendre'"),
    # ---- outputs -------------------------------------------------------------------------
    row("unknown_output", outputs('include = ["niirs", "snr"]'), "outputs.include", 15,
        "mtf, niirs"),
    row("mtf_without_mtf_frequency", outputs('include = ["niirs", "mtf"]'), "outputs.include",
        15, "mtf_frequency"),
    row("mtf_frequency_without_mtf", outputs("mtf_frequency = [0.0, 1e5]"),
        "outputs.mtf_frequency", 15, 'add "mtf" to include'),
    row("too_many_mtf_frequencies",
        outputs('include = ["mtf"]\nmtf_frequency = {start = 0.0, stop = 1e5, num = 2000000}'),
        "outputs.mtf_frequency", 16, "at most 1000000"),
    # ---- run -----------------------------------------------------------------------------
    row("chunk_size_zero", run_table("chunk_scenarios = 0"), "run.chunk_scenarios", 15,
        "whole number >= 1"),
    row("chunks_for_an_unknown_dimension", run_table("chunks = {range = 10}"), "run.chunks", 15,
        "ground_range"),
    row("chunk_length_zero", run_table("chunks = {ground_range = 0}"), "run.chunks", 15,
        "whole number >= 1"),
    row("unknown_scheduler", run_table('scheduler = "thread"'), "run.scheduler", 15,
        "threads, synchronous, local-cluster"),
    row("zero_workers", run_table("workers = 0"), "run.workers", 15, "whole number >= 1"),
    row("empty_output_path", run_table('output = ""'), "run.output", 15, "file name"),
    row("compress_above_9", run_table("compress = 10"), "run.compress", 15, "0 (no compression)"),
    row("compress_as_text", run_table('compress = "zlib"'), "run.compress", 15, "to 9"),
    row("unknown_output_variable", outputs('variables = ["nirs"]'), "outputs.variables", 15,
        "did you mean 'niirs'"),
    row("output_variables_not_a_list", outputs('variables = "niirs"'), "outputs.variables", 15,
        "non-empty list"),
    row("mtf_variable_without_mtf", outputs('variables = ["mtf_system"]'), "outputs.variables",
        15, 'add "mtf" to include'),
]


def assert_clear(message: str, key: str, line: int | None, allowed: str) -> None:
    """One line that names the key (and its line), says what is allowed, hides internals."""
    assert "\n" not in message, message
    assert key in message, f"the key {key!r} is not named: {message}"
    if line is not None:
        assert f"line {line}:" in message or f"line {line}," in message, (
            f"line {line} expected: {message}")
    assert allowed in message, f"{allowed!r} (what is allowed) missing: {message}"
    leaked = [word for word in INTERNALS if word in message]
    assert not leaked, f"Python internals {leaked} in: {message}"


def test_the_table_has_a_row_for_more_than_25_kinds():
    assert len(BAD) >= 30  # the issue asks for 25+ kinds, the brief for at least 30 rows


def test_the_minimal_study_of_the_table_is_valid():
    assert isinstance(parse(VALID), Study)


@pytest.mark.parametrize("text, key, line, allowed", BAD)
def test_bad_study_text_raises_one_clear_study_error(text, key, line, allowed):
    with pytest.raises(StudyError) as err:
        parse(text, "study.toml")
    assert isinstance(err.value, ValueError)
    assert str(err.value).startswith("study.toml")
    assert_clear(str(err.value), key, line, allowed)


@pytest.mark.parametrize("text, key, line, allowed", BAD)
def test_bad_study_file_fails_the_command_with_one_line(text, key, line, allowed, tmp_path,
                                                          capsys):
    study = tmp_path / "study.toml"
    study.write_text(text, encoding="utf-8")
    with pytest.raises(SystemExit) as exit_:
        cli.main(["run", str(study), "-o", str(tmp_path / "o.nc"), "--no-figures"])
    assert exit_.value.code == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("xbsm run: "), lines
    assert_clear(lines[0], key, line, allowed)
    assert not (tmp_path / "o.nc").exists()


# ---- files that cannot be read ---------------------------------------------------------

def _not_utf8(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(VALID.replace('"test study"', '"caf\u00e9"').encode("latin-1"))
    return path


def _too_large(tmp_path):
    path = tmp_path / "data.toml"
    with open(path, "wb") as handle:  # sparse: nothing is written
        handle.truncate(xbsm.study.spec.MAX_STUDY_BYTES + 1)
    return path


FILES = [  # how to make the file, the fragment naming it, what is allowed or wrong
    pytest.param(_not_utf8, "line 1", "save the study file as UTF-8", id="non_utf8_file"),
    pytest.param(lambda tmp: tmp / "missing.toml", "missing.toml", "No such file",
                 id="missing_file"),
    pytest.param(lambda tmp: tmp, str(os.sep), "give a study file", id="directory"),
    pytest.param(_too_large, "data.toml", "a study file has at most", id="file_too_large"),
]


@pytest.mark.parametrize("make, name, allowed", FILES)
def test_unreadable_study_file_raises_one_clear_study_error(make, name, allowed, tmp_path):
    path = make(tmp_path)
    with pytest.raises(StudyError) as err:
        load(path)
    assert str(path) in str(err.value)
    assert_clear(str(err.value), name, None, allowed)


@pytest.mark.parametrize("make, name, allowed", FILES)
def test_unreadable_study_file_fails_the_command_with_one_line(make, name, allowed, tmp_path,
                                                               capsys):
    path = make(tmp_path)
    with pytest.raises(SystemExit) as exit_:
        cli.main(["run", str(path), "-o", str(tmp_path / "o.nc"), "--no-figures"])
    assert exit_.value.code == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("xbsm run: "), lines
    assert_clear(lines[0], name, None, allowed)


def test_study_text_that_is_not_a_str_raises_a_study_error():
    with pytest.raises(StudyError, match="str of TOML; got bytes"):
        parse(VALID.encode())


def test_a_utf8_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + VALID.encode())  # as Windows Notepad saves UTF-8
    assert load(path).title == "test study"


# ---- outputs that cannot be written (each runs the study's one-scenario template) ------

def test_output_in_a_missing_directory_fails_with_one_line(tmp_path, capsys):
    study = tmp_path / "study.toml"
    study.write_text(VALID)
    out = tmp_path / "missing-dir" / "x.nc"
    with pytest.raises(SystemExit) as exit_:
        cli.main(["run", str(study), "-o", str(out), "--no-figures"])
    assert exit_.value.code == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("xbsm run: "), lines
    assert_clear(lines[0], "missing-dir", None, "does not exist")


def test_existing_output_without_overwrite_fails_with_one_line_naming_the_flag(tmp_path,
                                                                              capsys):
    study = tmp_path / "study.toml"
    study.write_text(VALID)
    out = tmp_path / "x.nc"
    out.write_bytes(b"keep me")
    with pytest.raises(SystemExit) as exit_:
        cli.main(["run", str(study), "-o", str(out), "--no-figures"])
    assert exit_.value.code == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("xbsm run: "), lines
    assert_clear(lines[0], "x.nc", None, "--overwrite")
    assert out.read_bytes() == b"keep me"


# ---- valid files -------------------------------------------------------------------------

def test_minimal_study_holds_the_preset_and_the_file_values():
    study = parse(VALID)
    assert study.sizes == {"ground_range": 2}
    np.testing.assert_array_equal(study.sweeps[0].values["ground_range"], [1000.0, 2000.0])
    # the Olson red band of paper Table 2: 500-660 nm, f = 4 m, D = 0.275 m, p = 8 um
    assert (study.sensor["wavelength_min"], study.sensor["wavelength_max"]) == (0.50e-6, 0.66e-6)
    assert (study.sensor["focal_length"], study.sensor["aperture_diameter"]) == (4.0, 0.275)
    assert dict(study.scenario) == {"altitude": 9000.0, "visibility": 23.0}
    assert (study.method, dict(study.knobs), study.outputs) == ("accurate", {}, ("niirs",))
    assert study.bands == {} and study.text == VALID


def test_sweeps_keep_file_order_with_paired_log_and_database_sweeps():
    study = parse("""
[sensor]
preset = "olson"
[scenario]
visibility = 5.0
[sweep]
optics = {aperture_diameter = [0.2, 0.275], focal_length = [3.0, 4.0]}
altitude = {start = 1000.0, stop = 10000.0, num = 3, spacing = "log"}
ground_range = "database"
""")
    assert [sweep.dim for sweep in study.sweeps] == ["optics", "altitude", "ground_range"]
    assert study.sizes == {"optics": 2, "altitude": 3, "ground_range": 97}
    assert study.scenarios == 2 * 3 * 97
    optics, altitude, ground_range = study.sweeps
    assert list(optics.values) == ["aperture_diameter", "focal_length"]  # file order
    np.testing.assert_array_equal(optics.values["focal_length"], [3.0, 4.0])
    # closed form: 1000 * 10**(k / 2) for k = 0, 1, 2
    np.testing.assert_allclose(altitude.values["altitude"], [1e3, 1e3 * 10**0.5, 1e4],
                               rtol=1e-15)
    # paper Appendix A: 97 database ground ranges from 0 to 300 km
    values = ground_range.values["ground_range"]
    assert (len(values), values[0], values[-1]) == (97, 0.0, 300e3)
    np.testing.assert_array_equal(values, examples.DATABASE_GROUND_RANGES)


def test_linear_range_gives_evenly_spaced_values():
    study = parse(replaced("[1000.0, 2000.0]", "{start = 0.0, stop = 10000.0, num = 5}"))
    # closed form: 0, 2500, ..., 10000
    np.testing.assert_array_equal(study.sweeps[0].values["ground_range"],
                                  [0.0, 2500.0, 5000.0, 7500.0, 10000.0])


def test_bands_come_from_the_preset_list():
    study = parse(replaced('band = "red"', 'band = ["red", "nir"]'))
    assert study.sizes == {"band": 2, "ground_range": 2}
    # paper Table 2: red 500-660 nm QE 0.80, NIR 550-850 nm QE 0.71
    assert dict(study.bands["red"]) == {"wavelength_min": 0.50e-6, "wavelength_max": 0.66e-6,
                                        "quantum_efficiency": 0.80}
    assert dict(study.bands["nir"]) == {"wavelength_min": 0.55e-6, "wavelength_max": 0.85e-6,
                                        "quantum_efficiency": 0.71}


def test_the_file_quantum_efficiency_overrides_that_of_each_preset_band():
    study = parse(replaced('band = "red"', 'band = ["red", "nir"]\nquantum_efficiency = 0.5'))
    assert study.sensor["quantum_efficiency"] == 0.5  # the file's value
    # paper Table 2 band edges stay per band; their QE (0.80, 0.71) gives way to the file's
    assert dict(study.bands["nir"]) == {"wavelength_min": 0.55e-6, "wavelength_max": 0.85e-6}


def test_bands_come_from_band_tables_in_file_order():
    study = parse(appended("""
[bands.green]
wavelength_min = 0.50e-6
wavelength_max = 0.58e-6
[bands."near infrared"]
wavelength_min = 0.70e-6
wavelength_max = 0.90e-6
quantum_efficiency = {wavelength = [0.70e-6, 0.90e-6], values = [0.6, 0.3]}
"""))
    assert list(study.bands) == ["green", "near infrared"]
    assert dict(study.bands["green"]) == {"wavelength_min": 0.50e-6, "wavelength_max": 0.58e-6}
    curve = study.bands["near infrared"]["quantum_efficiency"]
    np.testing.assert_array_equal(curve.values, [0.6, 0.3])
    np.testing.assert_array_equal(curve["wavelength"].values, [0.70e-6, 0.90e-6])


def test_method_knobs_outputs_and_run_options_are_kept():
    study = parse(appended("""
[method]
preset = "pybsm"
frequency_samples = 201
edge_rule = "gauss_legendre"

[outputs]
include = ["mtf"]
mtf_frequency = {start = 0.0, stop = 1e5, num = 11}

[run]
chunk_scenarios = 1
chunks = {ground_range = 1}
scheduler = "synchronous"
workers = 1
output = "out.nc"
"""))
    assert study.method == "pybsm"
    assert dict(study.knobs) == {"frequency_samples": 201, "edge_rule": "gauss_legendre"}
    assert study.outputs == ("niirs", "mtf")
    # closed form: 0, 1e4, ..., 1e5 cycles/rad
    np.testing.assert_array_equal(study.mtf_frequency, np.arange(11) * 1e4)
    assert (study.chunk_scenarios, dict(study.chunks), study.scheduler, study.workers,
            study.output) == (1, {"ground_range": 1}, "synchronous", 1, "out.nc")


def test_printing_a_study_gives_a_summary_not_every_array():
    # print(study) printed every parameter and array, 3343 characters for Example 1
    # (issue 21); the summary's numbers come from the shipped study file (97 database
    # ranges x 2 visibilities x 2 bands, one band per chunk) and chunk_sizes
    study = load(cli.default_study_path())
    text = str(study)
    assert text == repr(study)
    assert text.splitlines() == [
        "<xbsm Study 'Paper Example 1: the Olson camera at 9 km'>",
        "  scenarios: 388 (band 2 x ground_range 97 x visibility 2)",
        "  chunks:    2 of at most 194 scenarios (band 1, ground_range 97, visibility 2)",
        "  sweeps:    ground_range 97 values 0 to 300000 m; visibility [23, 5] km",
        "  bands:     red, nir",
        "  method:    accurate",
        "  outputs:   niirs, mtf (111 MTF frequencies); variables: all",
        "  run:       threads, 2 worker(s), output example1.nc",
    ]
    assert "array(" not in text and "mappingproxy" not in text


def test_printing_a_study_names_paired_sweeps_knobs_and_run_options():
    text = str(parse(appended(
        "\n[sweep.target]\ntarget_reflectance = [0.1, 0.2]\n"
        "background_reflectance = [0.05, 0.1]\n[method]\notf_wavelengths = 24\n"
        '[outputs]\nvariables = ["niirs"]\n[run]\ncompress = 3\n')))
    assert "scenarios: 4 (ground_range 2 x target 2)" in text
    assert "target: target_reflectance [0.1, 0.2]; background_reflectance [0.05, 0.1]" in text
    assert "method:    accurate (otf_wavelengths=24)" in text
    assert "variables: niirs, flags" in text and "zlib level 3" in text


def test_the_shipped_example1_study_parses():
    study = load(cli.default_study_path())
    # paper Sec. 3: red and NIR bands, 97 database ground ranges, 23 and 5 km visibility
    assert study.sizes == {"band": 2, "ground_range": 97, "visibility": 2}
    assert study.outputs == ("niirs", "mtf")


def test_study_run_equals_the_model_called_directly_exactly():
    # the Python face (parse + run) of `xbsm run` against a notebook's direct call
    study = parse(VALID)
    result = xbsm.study.run(study).compute(scheduler="synchronous")
    sensor = xbsm.sensor(**examples.olson_sensor_parameters("red"))
    scenario = xbsm.scenario(altitude=9000.0, visibility=23.0, ground_range=xr.DataArray(
        [1000.0, 2000.0], dims="ground_range"))
    direct = xbsm.niirs(sensor, scenario, "accurate")
    assert set(result.data_vars) == set(direct.data_vars)
    for name, expected in direct.data_vars.items():
        got = result[name].transpose(*expected.dims)
        np.testing.assert_array_equal(got.values, expected.values, err_msg=name)
        assert got.attrs["units"] == expected.attrs["units"]
    np.testing.assert_array_equal(result["ground_range"].values, [1000.0, 2000.0])
