"""Measurements on images: ISO 12233 slanted-edge MTF, RER and noise in flat regions.

Used to check simulated or real imagery against the model: measure the MTF on
a slanted edge and compare it with :func:`xbsm.system_otf`, the RER with the
NIIRS chain's, the noise of a flat region with :func:`xbsm.snr`'s.

- :mod:`xbsm.measure.slanted_edge`: :func:`slanted_edge_mtf` (ISO 12233:2017
  e-SFR) and :func:`edge_rer`.
- :mod:`xbsm.measure.flat_region`: :func:`flat_noise`.

Results carry ``flags`` (:data:`FLAGS`: ``edge_clipped``, ``region_not_flat``). Regions
are contiguous: a strided region is refused (a decimated image).

Images are numpy arrays or DataArrays over (``y``, ``x``) with any leading
dimensions (a stack), which every result keeps with their labels. The
arithmetic is numpy; dask-backed images are computed. Details, measured
accuracy and limits: ``docs/measure.md``.
"""

from ._image import FLAGS, flag
from .flat_region import flat_noise
from .slanted_edge import MAX_EDGE_ANGLE, MIN_EDGE_ANGLE, MIN_SIZE, edge_rer, slanted_edge_mtf

__all__ = [
    "FLAGS",
    "MAX_EDGE_ANGLE",
    "MIN_EDGE_ANGLE",
    "MIN_SIZE",
    "edge_rer",
    "flag",
    "flat_noise",
    "slanted_edge_mtf",
]
