"""Image-dataset studies through simulate_images (issue 26): a chunk's images of one shape
simulated together, tile_size passed on, one upsampled warning per run from the flags.

The reference of every comparison is ``xbsm.study.images.simulate_one``: the one
``xbsm.simulate_image`` call of that image alone with the output's recorded seed.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from image_datasets import STUDY

from xbsm import study
from xbsm.datasets import from_arrays, read_pixels
from xbsm.study import images

pytest.importorskip("PIL.Image")


def _arrays(n=5):
    """n grey 64 x 72 images (one batch per chunk) and an RGB one of another size."""
    rng = np.random.default_rng(3)
    grey = [np.clip(60 + 40 * rng.standard_normal((64, 72)), 0, 255).astype(np.uint8)
            for _ in range(n)]
    for k, img in enumerate(grey):
        img[10 + k: 30 + k, 20:50] = 230
    return [*grey, rng.integers(0, 256, (50, 40, 3)).astype(np.uint8)]


def _check_each_output_equals_its_image_alone(spec, out, dataset, tile_size=None):
    cells = images.output_cells(spec)
    checked = 0
    for cell in cells:
        coco = json.loads((out / cell.name / "annotations.json").read_text())
        for entry, (position, item) in zip(coco["images"], enumerate(dataset), strict=True):
            assert entry["xbsm"]["seed"] == str(images.output_seed(0, position, cell.index))
            alone, _ = images.simulate_one(item.pixels(), item.gsd, cell, spec.dataset,
                                           int(entry["xbsm"]["seed"]), spec.method)
            written = read_pixels(out / cell.name / entry["file_name"])
            np.testing.assert_array_equal(written, alone)
            checked += 1
    assert checked == len(dataset) * len(cells)


def test_a_chunk_is_simulated_in_batches_equal_to_each_image_alone(tmp_path, monkeypatch):
    spec = study.parse(STUDY.replace("chunk_images = 2", "chunk_images = 4"), "s.toml")
    dataset = from_arrays(_arrays(), gsd=0.004)
    batches = []
    real = images.simulate_batch
    monkeypatch.setattr(images, "simulate_batch",
                        lambda *a, **k: (batches.append(len(a[0])), real(*a, **k))[1])
    out = study.simulate(spec, tmp_path / "out", dataset=dataset, progress=False)
    # two chunks (4 and 2 images) at two ranges: one call per chunk and range (the
    # chunks run on threads, in either order)
    assert sorted(batches) == [2, 2, 4, 4]
    _check_each_output_equals_its_image_alone(spec, out, dataset)


def test_tile_size_is_passed_to_the_simulation(tmp_path, monkeypatch):
    from xbsm.simulate import image as image_module

    text = STUDY + "tile_size = 80\n"
    spec = study.parse(text, "s.toml")
    assert spec.dataset.tile_size == 80
    large = np.random.default_rng(1).integers(0, 256, (130, 100)).astype(np.uint8)
    dataset = from_arrays(_arrays(2)[:2] + [large], gsd=0.004)
    tiled = []
    real = image_module.tiled_blur_and_resample
    monkeypatch.setattr(image_module, "tiled_blur_and_resample",
                        lambda *a, **k: (tiled.append(a[0].shape), real(*a, **k))[1])
    out = study.simulate(spec, tmp_path / "out", dataset=dataset, progress=False)
    # the 130 x 100 image is larger than an 80-pixel tile: tiled, at each of the 2 ranges;
    # the 64 x 72 ones are not
    assert [shape[-2:] for shape in tiled] == [(130, 100)] * 2
    tiled.clear()
    _check_each_output_equals_its_image_alone(spec, out, dataset)  # simulate_one: tiled too
    assert len(tiled) == 2
    for bad in ("32", "64.0", "true"):
        with pytest.raises(study.StudyError, match="dataset.tile_size: must be a whole number "
                           ">= 64"):
            study.parse(STUDY + f"tile_size = {bad}\n", "s.toml")


def test_upsampled_outputs_are_one_warning_per_run_counted_from_the_flags(tmp_path):
    # 20 mm reference pixels are coarser than the camera's (5 mm at 2 km, 7 mm at 4 km,
    # 3 km altitude): every output is upsampled, in every chunk
    spec = study.parse(STUDY, "s.toml")
    dataset = from_arrays(_arrays(), gsd=0.02)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")  # a per-call warning would show up every time
        out = study.simulate(spec, tmp_path / "out", dataset=dataset, progress=False)
    upsampled = [w for w in record if "finely sampled" in str(w.message)]
    assert len(upsampled) == 1
    assert str(upsampled[0].message).startswith("12 of 12 simulated images")
    coco = json.loads((out / "ground_range=2000" / "annotations.json").read_text())
    assert all("upsampled" in entry["xbsm"]["flag_names"] for entry in coco["images"])
