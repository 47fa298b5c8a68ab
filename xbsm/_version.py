"""The package version, in one place (private).

``pyproject.toml`` reads it (``[tool.setuptools.dynamic]``), ``xbsm.__version__`` re-exports
it, and submodules import it from here rather than from the package root, whose names are
loaded lazily (PEP 562).
"""

__version__ = "0.1.0"
