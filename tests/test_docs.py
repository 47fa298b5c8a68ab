"""The documentation is checked against the code: examples run, tables are complete."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import runpy
from pathlib import Path

import pytest

import xbsm
from xbsm import flags, pybsm_compat
from xbsm.methods import Method

DOCS = Path(__file__).resolve().parent.parent / "docs"
PAGES = ("index", "guide", "migration", "quirks", "flags", "api", "validation", "study",
         "example1", "measure", "simulate")
# Pages of the documentation site (docs/conf.py) besides the ones above; Sphinx itself
# refuses (with -W) a page that no table of contents includes.
SITE_PAGES = ("quickstart", "concepts", "stages", "geometry", "radiometry", "noise", "niirs",
              "performance", "reference", "infrared", "target_acquisition")
GALLERY = sorted((DOCS / "gallery").glob("plot_*.py"))
ROOT = DOCS.parent

# Modules whose public functions docs/api.md must list, one by one.
API_MODULES = (
    "xbsm.params", "xbsm.pybsm_compat", "xbsm.methods", "xbsm.model", "xbsm.simulate",
    "xbsm.atmosphere", "xbsm.atmosphere.database", "xbsm.atmosphere.rules",
    "xbsm.atmosphere.lookup", "xbsm.atmosphere.tables", "xbsm.atmosphere.modtran",
    "xbsm.atmosphere.sixs",
    "xbsm.geometry", "xbsm.radiometry", "xbsm.noise", "xbsm.quadrature", "xbsm.metrics",
    "xbsm.metrics.edge", "xbsm.metrics.grd", "xbsm.metrics.giqe", "xbsm.metrics.pybsm_numerics",
    "xbsm.flags", "xbsm.examples", "xbsm.plot.axes", "xbsm.plot.figures", "xbsm.cli",
    "xbsm.otf.aperture", "xbsm.otf.defocus", "xbsm.otf.detector", "xbsm.otf.filters",
    "xbsm.otf.motion", "xbsm.otf.psf", "xbsm.otf.spectral", "xbsm.otf.system",
    "xbsm.otf.turbulence", "xbsm.otf.user", "xbsm.otf.wavefront",
    "xbsm.measure.slanted_edge", "xbsm.measure.flat_region",
    "xbsm.study.spec", "xbsm.study.build", "xbsm.study.store", "xbsm.study.goals",
    "xbsm.study.attributes", "xbsm.study.images",
    "xbsm.datasets.readers", "xbsm.datasets.writers", "xbsm.datasets.coco",
    "xbsm.interrupts",
    *(f"xbsm.simulate.{m}" for m in (
        "image", "options", "reflectance", "photoelectrons", "sampling", "psf", "pybsm_psf",
        "convolve", "resample", "camera", "inverse", "labels",
    )),
)


def read(page: str) -> str:
    return (DOCS / f"{page}.md").read_text()


def python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def resolve(dotted: str):
    """Import ``a.b.c`` as a module or as an attribute of the longest importable prefix."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for name in parts[i:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(dotted)


def public_functions(module_name: str) -> list[str]:
    module = importlib.import_module(module_name)
    return sorted(
        name for name, obj in vars(module).items()
        if not name.startswith("_") and inspect.isfunction(obj)
        and obj.__module__ == module_name
    )


def test_every_page_exists_and_index_links_to_each():
    index = read("index")
    for page in PAGES[1:] + ("atmosphere", "otf", "metrics"):
        assert (DOCS / f"{page}.md").exists(), page
        assert f"({page}.md)" in index, page


def test_index_links_show_page_titles_not_file_names():
    # the index's table of pages showed "guide.md", "study.md", ... (issue 21): each link
    # reads as the title (first heading) of the page it opens
    links = re.findall(r"^\| \[([^\]]+)\]\(([a-z0-9_]+)\.md\) \|", read("index"), flags=re.M)
    assert len(links) >= 15
    for text, page in links:
        heading = re.search(r"^# (.+)$", read(page), flags=re.M).group(1).strip()
        assert text == heading, (page, text)


def test_relative_links_between_pages_resolve():
    for page in PAGES + SITE_PAGES:
        for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", read(page)):
            assert (DOCS / target).exists(), (page, target)


def test_guide_examples_run_in_order(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    blocks = python_blocks(read("guide"))
    assert len(blocks) >= 10
    namespace: dict = {"__name__": "guide"}
    for number, block in enumerate(blocks):
        exec(compile(block, f"docs/guide.md block {number}", "exec"), namespace)


@pytest.mark.parametrize("page", ["migration", "flags", "validation", "quickstart", "concepts",
                                  "geometry", "radiometry", "noise", "niirs", "infrared",
                                  "target_acquisition"])
def test_examples_of_other_pages_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": page}
    for number, block in enumerate(python_blocks(read(page))):
        exec(compile(block, f"docs/{page}.md block {number}", "exec"), namespace)


def test_readme_notebook_example_runs_and_holds_niirs_to_its_scale(tmp_path, monkeypatch):
    # the README's notebook snippet drew an axis down to -720 NIIRS (issue 21)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)
    plt.close("all")
    try:
        namespace: dict = {"__name__": "readme"}
        for number, block in enumerate(python_blocks((ROOT / "README.md").read_text())):
            exec(compile(block, f"README.md block {number}", "exec"), namespace)
        assert plt.gca().get_ylim() == xbsm.plot.NIIRS_SCALE
    finally:
        plt.close("all")


def test_simulate_page_says_plainly_what_to_pass_for_a_box_far_edge():
    # a reader passed inclusive indices to transform_boxes and every box came out one
    # pixel short (issue 21); the page gives the rule and a worked box
    page = " ".join(read("simulate").split())
    assert "pass `x_max = last column + 1` and `y_max = last row + 1`" in page
    assert "A box over columns 10 to 19 and rows 5 to 8 is `(10, 5, 20, 9)`" in page


def test_guide_lists_every_method_knob():
    guide = read("guide")
    for knob in Method.knobs():
        assert f"| `{knob}` |" in guide, knob


@pytest.mark.parametrize("table", [pybsm_compat.SENSOR_NAMES, pybsm_compat.SCENARIO_NAMES],
                         ids=["Sensor", "Scenario"])
def test_migration_table_has_every_pybsm_keyword(table):
    migration = read("migration")
    for pybsm_name, xbsm_name in table.items():
        row = re.search(rf"^\| `{re.escape(pybsm_name)}` \|(.*)$", migration, flags=re.M)
        assert row, pybsm_name
        # the xbsm parameter named first in the mapping appears in the same row
        first = re.match(r"[a-z_0-9]+", xbsm_name)
        if first:
            assert f"`{first.group(0)}" in row.group(1), (pybsm_name, xbsm_name)


def _function_rows(page: str):
    """(section, pyBSM cell, xbsm cell) of every table row from '## Functions' on."""
    text = read(page)
    section = ""
    for line in text[text.index("## Functions"):].splitlines():
        if line.startswith("#"):
            section = line
        elif line.startswith("|") and not set(line) <= set("|- "):
            cells = [cell.strip() for cell in line.strip().strip("|").split(" | ")]
            if cells[0] in ("pyBSM", "pyBSM 0.16.1"):
                continue
            yield section, cells[0], cells[1]


# variables of the results the "Result objects become datasets" table maps to
_RESULT_VARIABLES = None


def _result_variables() -> set:
    global _RESULT_VARIABLES
    if _RESULT_VARIABLES is None:
        sensor, scenario = xbsm.examples.olson_sensor(), xbsm.examples.olson_scenario()
        _RESULT_VARIABLES = {*xbsm.niirs(sensor, scenario).variables,
                             *xbsm.snr(sensor, scenario).variables}
    return _RESULT_VARIABLES


def test_migration_rows_name_a_counterpart_that_exists_or_say_why_there_is_none():
    # docs/migration.md from "## Functions" on: every row names an xbsm function (or
    # module, or result variable) that exists, or says "no counterpart: <reason>"; the
    # page said image simulation was "not in xbsm yet" long after it was (issue 21)
    import xbsm.examples  # noqa: F401

    page = read("migration")
    assert not re.search(r"not (in xbsm )?yet", page, flags=re.I)
    rows = list(_function_rows("migration"))
    assert len(rows) > 60
    names = re.compile(r"`(xbsm(?:\.[A-Za-z_][A-Za-z0-9_]*)+)")
    for section, pybsm, counterpart in rows:
        where = (section, pybsm)
        if counterpart.startswith("no counterpart"):
            reason = counterpart.removeprefix("no counterpart").lstrip(":").strip()
            assert counterpart.startswith("no counterpart: ") and len(reason.split()) >= 4, where
            continue
        found = [resolve(dotted) for dotted in names.findall(counterpart)]
        same = re.match(r"same names? in `(xbsm[a-z_.]*)`", counterpart)
        if same:  # the pyBSM names themselves, in that xbsm module
            module = importlib.import_module(same.group(1))
            found += [getattr(module, name) for name in re.findall(r"`([a-z_0-9]+)`", pybsm)]
        if not found:  # a result variable: the first word of each backticked name
            named = counterpart.split(" (")[0]  # what follows in parentheses is a note
            variables = [re.match(r"[A-Za-z_0-9]+", token).group(0)
                         for token in re.findall(r"`([^`]+)`", named)]
            assert variables and all(v in _result_variables() for v in variables), where
            found = variables
        assert found, where


def test_every_xbsm_name_in_backticks_exists():
    pattern = re.compile(r"`(xbsm(?:\.[A-Za-z_][A-Za-z0-9_]*)+)")
    for page in PAGES + SITE_PAGES:
        for dotted in set(pattern.findall(read(page))):
            resolve(dotted)


def test_api_reference_lists_every_public_function():
    api = read("api")
    for module_name in API_MODULES:
        assert f"`{module_name}`" in api, module_name
        for name in public_functions(module_name):
            assert f"`{name}(" in api, f"{module_name}.{name}"
    for name in xbsm.__all__:
        assert f"`xbsm.{name}" in api, name


def test_flags_page_documents_every_bit():
    page = read("flags")
    for name, (bit, _) in flags.FLAGS.items():
        assert re.search(rf"^\| {bit} \| `{name}` \|", page, flags=re.M), name


def test_validation_page_figure4_numbers_are_what_xbsm_gives():
    # docs/validation.md quotes 57,600 total and 658 / 1338 contrast photoelectrons
    import xbsm.examples

    sc = xbsm.scenario(altitude=9000, ground_range=20000, visibility=5, platform_speed=100)
    for band, contrast in (("red", 658), ("nir", 1338)):
        r = xbsm.snr(xbsm.examples.olson_sensor(band), sc)
        assert round(float(r.target_photoelectrons)) == 57600
        assert round(float(r.contrast_photoelectrons)) == contrast
    page = read("validation")
    assert "| 658 (-1.5 %) |" in page and "| 1338 (+4.3 %) |" in page


def test_flags_page_example_values_match_the_code():
    # docs/flags.md: the bits of 36 are gsd_out_of_range and well_fill_limited
    assert flags.flag("gsd_out_of_range") | flags.flag("well_fill_limited") == 36


def reference_modules() -> list[str]:
    """The modules docs/reference.md hands to autosummary (recursively, with submodules)."""
    listing = re.search(r":recursive:\n\n(.*?)^```", read("reference"), flags=re.S | re.M)
    return listing.group(1).split()


def test_generated_reference_covers_every_public_module():
    # The site's API pages are generated from the docstrings of the modules listed in
    # docs/reference.md and of their submodules: every public module must be reached,
    # and every module docs/api.md describes must be one of them.
    listed = reference_modules()
    public = [m.name for m in pkgutil.walk_packages(xbsm.__path__, "xbsm.")
              if not any(part.startswith("_") for part in m.name.split("."))]
    for name in public + list(API_MODULES):
        assert any(name == top or name.startswith(top + ".") for top in listed), name
    for top in listed:
        importlib.import_module(top)


def test_reference_entry_points_are_the_top_level_names():
    # docs/reference.md's entry-point table names where each top-level function lives
    entries = re.search(r"## Entry points.*?:nosignatures:\n\n(.*?)^```", read("reference"),
                        flags=re.S | re.M).group(1).split()
    objects = {id(resolve(name)) for name in entries}
    for name in ("sensor", "scenario", "snr", "niirs", "system_otf", "method", "Method",
                 "open_atmosphere", "atmosphere_at", "simulate_image"):
        assert id(getattr(xbsm, name)) in objects, name


def test_readme_and_ci_build_the_docs_with_one_command():
    # the README's build command is the one .ci/run executes, with warnings as errors
    command = ('pip install -e ".[docs]" && python -m sphinx -W --keep-going docs '
               "docs/_build/html")
    assert command in (ROOT / "README.md").read_text()
    assert f"    {command}\n" in (ROOT / ".ci" / "run").read_text()
    assert "docs_build\n" in (ROOT / ".ci" / "run").read_text()


def test_gallery_has_the_six_examples():
    # docs/gallery: range performance, focal-length trade, noise and MTF breakdowns,
    # a simulated image stack over range (issue 11), the infrared cameras' NETD, MRTD
    # and NIIRS (issue 25)
    assert [p.stem for p in GALLERY] == [
        "plot_focal_length_trade", "plot_image_stack", "plot_infrared_cameras",
        "plot_mtf_breakdown", "plot_noise_breakdown", "plot_range_performance"]


@pytest.mark.slow
@pytest.mark.parametrize("script", GALLERY, ids=[p.stem for p in GALLERY])
def test_gallery_script_runs_and_draws(script, tmp_path, monkeypatch):
    # each gallery script runs as sphinx-gallery runs it and leaves at least one figure
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)
    plt.close("all")
    try:
        runpy.run_path(str(script), run_name="__main__")
        assert plt.get_fignums(), script.name
    finally:
        plt.close("all")
