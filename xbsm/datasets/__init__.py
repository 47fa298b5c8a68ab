"""Image datasets in and out: image folders, COCO files and arrays; PNG, TIFF and COCO written.

:mod:`~xbsm.datasets.readers` reads a dataset (:func:`from_folder`,
:func:`from_coco`, :func:`from_arrays`) and checks it whole before any pixel
is simulated; :mod:`~xbsm.datasets.coco` moves its labels by a simulation's
pixel map; :mod:`~xbsm.datasets.writers` writes images and JSON files whole or
not at all. A study with a ``[dataset]`` table runs the sweep
(:func:`xbsm.study.simulate`, ``xbsm simulate``; ``docs/datasets.md``).
Reading and writing images needs the ``datasets`` extra (Pillow, tifffile).
"""

from .coco import PixelMap, move_annotations, moved_boxes
from .readers import (
    DatasetError,
    ImageDataset,
    Item,
    from_arrays,
    from_coco,
    from_folder,
    read_pixels,
    read_sidecar,
)
from .writers import encode_png, write_image, write_json

__all__ = ["DatasetError", "ImageDataset", "Item", "PixelMap", "encode_png", "from_arrays",
           "from_coco", "from_folder", "move_annotations", "moved_boxes", "read_pixels",
           "read_sidecar", "write_image", "write_json"]
