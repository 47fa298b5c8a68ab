"""Parametric studies: study files (TOML) -> lazy sweeps -> NetCDF.

``xbsm.study.load(path)`` reads and checks a study file, ``xbsm.study.run(study)``
returns its result as a lazy Dataset and ``xbsm.study.write(result, path)``
computes it chunk by chunk into a NetCDF file, resuming an interrupted run.
The ``xbsm run`` command is these three calls. The file format is in
``docs/study.md``. A study with a ``[dataset]`` table simulates an image dataset
over its sweep: ``xbsm.study.simulate(study)``, the ``xbsm simulate`` command
(``docs/datasets.md``).
"""

from .build import chunk_sizes, run
from .goals import GIQE5_STANDARD_ERROR, max_range, min_parameter, probability_meets
from .images import simulate
from .spec import Study, StudyError, Sweep, load, parse
from .store import write

__all__ = ["GIQE5_STANDARD_ERROR", "Study", "StudyError", "Sweep", "chunk_sizes", "load",
           "max_range", "min_parameter", "parse", "probability_meets", "run", "simulate", "write"]
