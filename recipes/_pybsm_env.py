"""Where the recipes find pyBSM 0.16.1, and a clear exit when it is missing.

pyBSM is never a dependency of xbsm. The recipes that need it use an
environment of its own inside the repository, ``recipes/_cache/pybsm-venv``
(git-ignored), or the interpreter named by ``$PYBSM_PYTHON``. The commands
that make it are in ``recipes/README.md``; :data:`MAKE_VENV` is the same
command, printed when pyBSM cannot be imported.
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

VENV = Path(__file__).resolve().parent / "_cache" / "pybsm-venv"
MAKE_VENV = ("python3 -m venv recipes/_cache/pybsm-venv && "
             "recipes/_cache/pybsm-venv/bin/pip install pybsm==0.16.1")


def missing_pybsm_message(python: str, script: str | None = None) -> str:
    """What to do when ``python`` cannot import pyBSM (``script``: the recipe to rerun, its path
    from the repository root)."""
    lines = [f"pyBSM 0.16.1 is not installed for {python}.",
             "Make its environment once, from the repository root:",
             f"    {MAKE_VENV}"]
    if script:
        lines += ["then run this recipe with it:",
                  f"    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python {script}"]
    else:
        lines += ["or point $PYBSM_PYTHON at an interpreter that has pybsm==0.16.1."]
    lines += ["See recipes/README.md."]
    return "\n".join(lines)


@contextlib.contextmanager
def pybsm_required():
    """Wrap a recipe's ``import pybsm`` lines: a missing pyBSM exits with instructions."""
    try:
        yield
    except ModuleNotFoundError as exc:
        if exc.name != "pybsm" and not str(exc.name).startswith("pybsm."):
            raise
        script = Path(sys.argv[0]).resolve().relative_to(VENV.parents[2])  # recipes/<group>/...
        raise SystemExit(missing_pybsm_message(sys.executable, str(script))) from None
