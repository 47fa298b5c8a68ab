"""The layout as a test: the package's data-flow order as docs/stages.md draws it, and the
tests mirroring the package.

docs/stages.md ("The package, in data-flow order") lists the modules in the order a
model call runs them and says that each imports only from the lines above it, with five
named exceptions at the atmosphere package. The order is read from that page's picture
and every ``import`` of ``xbsm/`` is read with :mod:`ast` (nothing is imported), so the
picture cannot drift from the code.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "xbsm"
TESTS = ROOT / "tests"

#: Imports that run against the order of the picture, each named on the page with its
#: reason: (importing module, imported module).
AGAINST_THE_ORDER = {
    ("xbsm.params", "xbsm.atmosphere.database"): "the database's facts bound the inputs",
    ("xbsm.flags", "xbsm.atmosphere.database"): "the database's facts in the flag texts",
    ("xbsm.atmosphere._sight", "xbsm.geometry"): "the line of sight uses the geometry kernels",
    ("xbsm.atmosphere._profile", "xbsm.quadrature"): "Gauss-Legendre nodes of quadrature",
    ("xbsm.atmosphere.lookup", "xbsm.methods"): "the presets' rule is atmosphere_at's default",
}

#: Top-level test files about the whole package, not one module.
WHOLE_PACKAGE = {"test_architecture", "test_layout", "test_conventions", "test_docs",
                 "test_packaging", "test_bad_inputs", "test_speed_reference"}
#: Top-level test files named otherwise than their module: file stem -> module.
NAMED_OTHERWISE = {"test_model_snr": "model", "test_model_niirs": "model",
                   "test_model_netd": "model", "test_model_mrtd": "model",
                   "test_kernel_boundary": "_kernels", "test_chain": "_chain",
                   "test_trig": "_trig"}


def picture_order() -> list[str]:
    """The top-level names of ``xbsm`` in the order of docs/stages.md's picture: the first
    word of each line that does not start with a space."""
    page = (ROOT / "docs" / "stages.md").read_text()
    block = page.split("## The package, in data-flow order", 1)[1].split("```\n", 2)[1]
    return [line.split()[0].rstrip("/") for line in block.splitlines()
            if line and not line[0].isspace()]


def imports(path: Path) -> set[str]:
    """Every ``xbsm`` module the file imports (relative imports resolved)."""
    module = path.relative_to(ROOT).with_suffix("").parts
    package = list(module[:-1])
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            found |= ({f"{name}.{a.name}" for a in node.names} if node.module is None
                      else {name})
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
    return {name for name in found if name.startswith("xbsm.")}


def test_the_picture_lists_every_module_of_the_package_once():
    order = picture_order()
    assert len(order) == len(set(order)), order
    modules = {p.stem for p in PACKAGE.glob("*.py")} | {p.parent.name for p in
                                                       PACKAGE.glob("*/__init__.py")}
    assert set(order) == modules - {"__init__", "_version"}


def test_each_module_imports_only_from_the_lines_above_it_but_for_the_named_exceptions():
    rank = {name: i for i, name in enumerate(picture_order())}
    against = set()
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        top = module.split(".")[1]
        if top not in rank:  # the package root and its version
            continue
        for imported in imports(path):
            if rank.get(imported.split(".")[1], -1) > rank[top]:
                against.add((module.removesuffix(".__init__"), imported))
    assert against == set(AGAINST_THE_ORDER)


def test_tests_mirror_the_package():
    packages = {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    modules = {p.stem for p in PACKAGE.glob("*.py")}
    folders = {p.name for p in TESTS.iterdir() if p.is_dir() and any(p.glob("test_*.py"))}
    assert folders <= packages, folders - packages
    for path in TESTS.glob("test_*.py"):
        stem = path.stem
        if stem in WHOLE_PACKAGE:
            continue
        module = NAMED_OTHERWISE.get(stem, stem.removeprefix("test_"))
        assert module in modules, f"{path.name}: no module xbsm/{module}.py; a test of a " \
            "subpackage goes into its folder, a rule of the whole package into WHOLE_PACKAGE"
