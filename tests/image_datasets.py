"""Small labelled image datasets on disk for the dataset tests (tests/datasets, tests/study)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

# The visible camera of recipes/fixtures/pybsm_reference_simulate.py (docs/simulate.md's
# example), at 3 km altitude; reference images at 4 mm GSD.
STUDY = '''
title = "dataset test"
[sensor]
aperture_diameter = 0.2
focal_length = 4.0
pixel_pitch_x = 10e-6
wavelength_min = 0.45e-6
wavelength_max = 0.7e-6
integration_time = 0.004
read_noise = 20.0
max_well = 60000.0
bit_depth = 12.0
[scenario]
altitude = 3000.0
visibility = 23.0
[sweep]
ground_range = [2000.0, 4000.0]
[dataset]
input = "coco.json"
output = "out"
chunk_images = 2
'''

# (rows, columns, channels) of the images: mixed sizes, grey and RGB
SHAPES = [(96, 120, 1), (80, 80, 3), (100, 90, 3), (64, 64, 1), (70, 110, 1)]
BOX = (30, 20, 60, 50)  # x_min, y_min, x_max, y_max of the bright square, every image


def scene(rows, cols, channels, k=0):
    """A dark image with a bright square at BOX and a little texture."""
    y, x = np.mgrid[0:rows, 0:cols]
    img = 40.0 + 10.0 * ((x // 8 + y // 8 + k) % 2)
    img[BOX[1]:BOX[3], BOX[0]:BOX[2]] = 220.0
    img = img.astype(np.uint8)
    return np.repeat(img[..., None], 3, axis=2) if channels == 3 else img


def write_coco(folder: Path, study: str = STUDY, gsd_entries=True) -> Path:
    """Images, a COCO file with a box and two keypoints per image, and the study file."""
    from PIL import Image

    folder.mkdir(parents=True, exist_ok=True)
    images, annotations = [], []
    for i, (rows, cols, channels) in enumerate(SHAPES):
        Image.fromarray(scene(rows, cols, channels, i)).save(folder / f"img{i}.png")
        entry = {"id": 10 + i, "file_name": f"img{i}.png", "width": cols, "height": rows}
        if gsd_entries:
            entry["gsd"] = 0.004
        images.append(entry)
        x0, y0, x1, y1 = BOX
        annotations.append({"id": 100 + i, "image_id": 10 + i, "category_id": 1,
                            "bbox": [x0, y0, x1 - x0, y1 - y0], "area": 900.0, "iscrowd": 0,
                            "keypoints": [45.0, 35.0, 2, 0, 0, 0]})
    doc = {"images": images, "annotations": annotations,
           "categories": [{"id": 1, "name": "square", "keypoints": ["centre", "unseen"]}]}
    (folder / "coco.json").write_text(json.dumps(doc))
    path = folder / "study.toml"
    path.write_text(study)
    return path
