"""Sphinx configuration of the xbsm documentation site.

Build (from the repository root, after ``pip install -e ".[docs]"``)::

    python -m sphinx -W --keep-going docs docs/_build/html

The Markdown pages are read by MyST, the API reference is generated from the
docstrings by autosummary and numpydoc, and the scripts in ``docs/gallery``
are executed by sphinx-gallery, which renders their figures.
"""

import os

import matplotlib

import xbsm

matplotlib.use("Agg")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

project = "xbsm"
author = "the xbsm authors"
copyright = "the xbsm authors; atmosphere data from pyBSM 0.16.1 (Apache-2.0)"
release = version = xbsm.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

root_doc = "index"
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
templates_path = ["_templates"]
exclude_patterns = ["_build", "benchmarks", "gallery/README.txt", "**.ipynb_checkpoints"]

# Docstrings write magnitudes as |OTF| and |FFT|, which reStructuredText would read
# as substitutions: define them as themselves.
rst_prolog = """
.. |OTF| replace:: \\|OTF\\|
.. |FFT| replace:: \\|FFT\\|
"""

# MyST: the existing pages link to each other's headings (guide.md#methods-and-knobs).
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 4

# API reference: one page per module and per function, generated from the docstrings.
autosummary_generate = True
autosummary_imported_members = False
autodoc_typehints = "none"          # numpydoc shows the documented types
autodoc_default_options = {"member-order": "bysource"}
autodoc_preserve_defaults = True    # signatures show GIQE5_CALIBRATION, not its long repr
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "abort_on_example_error": True,
    "show_memory": False,
}

html_theme = "pydata_sphinx_theme"
html_title = f"xbsm {version}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    # one function per generated API page: its table of contents would be one line,
    # so the column goes to the text and the equations instead
    "secondary_sidebar_items": {"*": ["page-toc"], "auto_examples/*": ["page-toc"],
                                "generated/*": []},
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_show_sourcelink = False
# pages without sub-pages have nothing for a section navigation to list
html_sidebars = {page: [] for page in (
    "quickstart", "concepts", "guide", "api", "flags", "migration", "quirks", "example1",
    "example2", "validation")}
