"""pyproject.toml: metadata that installs without warnings."""

from __future__ import annotations

import re
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parent.parent


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_license_is_an_spdx_expression_with_its_files():
    # `project.license` as a TOML table made setuptools >= 77 warn three times per
    # `pip install .` (issue 21; measured with pip wheel -v: 3 SetuptoolsDeprecationWarning,
    # 0 after); PEP 639's form is an SPDX string plus license-files
    project = _pyproject()["project"]
    assert project["license"] == "Apache-2.0"
    assert project["license-files"] and all((ROOT / f).is_file()
                                            for f in project["license-files"])
    assert not any(c.startswith("License ::") for c in project.get("classifiers", []))


def test_build_requires_a_setuptools_that_reads_spdx_licenses():
    # setuptools 77.0 is the first to accept the SPDX string and license-files (its
    # changelog, PEP 639); measured with pip wheel: 77.0.3 builds the wheel with
    # License-Expression: Apache-2.0, 76.1.0 refuses the string ("configuration error:
    # `project.license` must be valid exactly by one definition")
    requires = _pyproject()["build-system"]["requires"]
    floor = [re.fullmatch(r"setuptools>=(\d+)(?:\.\d+)*", r) for r in requires]
    assert any(m and int(m.group(1)) >= 77 for m in floor), requires


def test_the_version_has_one_home():
    # issue 22: submodules read the version back from the lazy package root; it now lives
    # in xbsm/_version.py, which pyproject.toml, xbsm.__version__ and the submodules read
    import importlib.metadata

    import xbsm
    from xbsm import _version

    project = _pyproject()
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {
        "attr": "xbsm._version.__version__"}
    assert xbsm.__version__ == _version.__version__ == importlib.metadata.version("xbsm")
