"""Image-quality metrics: edge response, RER, EHO, GRD, the GIQE versions and the MRTD.

The stages follow the data flow, each in its own module:

- :mod:`xbsm.metrics.edge`: edge response, relative edge response (RER) and
  edge height overshoot (EHO) from an OTF slice and quadrature weights.
- :mod:`xbsm.metrics.grd`: ground resolved distance from an MTF slice and the
  contrast SNR.
- :mod:`xbsm.metrics.giqe`: NIIRS from GIQE 3, 4 and 5, each version's
  calibration ranges, the validity flags and the sampling ratio Q.
- :mod:`xbsm.metrics.acquisition`: the four-bar minimum resolvable temperature
  difference from a NETD and an MTF (target-acquisition figures of merit).
- :mod:`xbsm.metrics.eye` and :mod:`xbsm.metrics.ttp`: the observer (eye contrast
  threshold, display, noise) and the Targeting Task Performance metric with P(task),
  behind :func:`xbsm.target_acquisition`.
- :mod:`xbsm.metrics.pybsm_numerics`: NumPy's interpolation search, copied so
  that ``method="pybsm"`` reproduces pyBSM 0.16.1 bit for bit.

Every public name of the first three and of ``acquisition`` is available here, e.g.
``xbsm.metrics.giqe5``.
"""

from .acquisition import bar_constant, minimum_resolvable
from .edge import (
    EHO_POSITIONS,
    RER_POSITIONS,
    edge_height_overshoot,
    edge_response,
    edge_terms,
    relative_edge_response,
)
from .giqe import (
    GIQE3_CALIBRATION,
    GIQE4_CALIBRATION,
    GIQE5_CALIBRATION,
    GIQE_CALIBRATIONS,
    GIQE_REFERENCES,
    GIQE_VERSIONS,
    INCH,
    GiqeCalibration,
    giqe3,
    giqe4,
    giqe5,
    giqe5_rer,
    giqe_by_version,
    giqe_calibrations,
    giqe_flags,
    sampling_q,
)
from .grd import ground_resolved_distance

__all__ = [
    "EHO_POSITIONS",
    "GIQE3_CALIBRATION",
    "GIQE4_CALIBRATION",
    "GIQE5_CALIBRATION",
    "GIQE_CALIBRATIONS",
    "GIQE_REFERENCES",
    "GIQE_VERSIONS",
    "INCH",
    "RER_POSITIONS",
    "GiqeCalibration",
    "bar_constant",
    "edge_height_overshoot",
    "edge_response",
    "edge_terms",
    "giqe3",
    "giqe4",
    "giqe5",
    "giqe5_rer",
    "giqe_by_version",
    "giqe_calibrations",
    "giqe_flags",
    "ground_resolved_distance",
    "minimum_resolvable",
    "relative_edge_response",
    "sampling_q",
]
