"""xbsm.datasets.writers and coco: images and JSON whole or absent; labels moved by the map."""

from __future__ import annotations

import json
import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import xbsm
from xbsm.datasets import PixelMap, from_arrays, move_annotations, write_image, write_json, writers
from xbsm.simulate import transform_boxes, transform_points

Image = pytest.importorskip("PIL.Image")
tifffile = pytest.importorskip("tifffile")


@pytest.mark.parametrize("shape", [(17, 23), (17, 23, 3)])
def test_png_decodes_in_pillow(tmp_path, shape):
    # an independent decoder (Pillow's libpng-compatible reader) reads our PNG bytes back
    rng = np.random.default_rng(1)
    img8 = rng.integers(0, 256, shape, dtype=np.uint8)
    write_image(tmp_path / "a.png", img8)
    with Image.open(tmp_path / "a.png") as back:
        np.testing.assert_array_equal(np.asarray(back), img8)
    img16 = rng.integers(0, 65536, shape, dtype=np.uint16)
    write_image(tmp_path / "b.png", img16)
    with Image.open(tmp_path / "b.png") as back:
        if len(shape) == 2:  # Pillow's I;16 keeps all 16 bits of grey
            np.testing.assert_array_equal(np.asarray(back), img16)
        else:  # Pillow reads 48-bit RGB as 8 bits a channel: the high byte
            np.testing.assert_array_equal(np.asarray(back), (img16 >> 8).astype(np.uint8))


def test_tiff_round_trip_16_bit_rgb(tmp_path):
    img = np.random.default_rng(2).integers(0, 65536, (9, 11, 3), dtype=np.uint16)
    write_image(tmp_path / "a.tif", img, "tiff")
    np.testing.assert_array_equal(tifffile.imread(tmp_path / "a.tif"), img)


def test_a_write_that_fails_leaves_no_file_that_looks_complete(tmp_path, monkeypatch):
    # a failure (a signal, a full disk) between writing and renaming: neither the final
    # name nor the temporary file remains
    def fail(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(KeyboardInterrupt):
        write_json(tmp_path / "annotations.json", {"images": []})
    assert list(tmp_path.iterdir()) == []


def test_png_refuses_float_pixels(tmp_path):
    with pytest.raises(ValueError, match="uint8 or uint16"):
        writers.encode_png(np.zeros((3, 3)))


def test_moved_labels_equal_transform_boxes_and_points():
    sensor = xbsm.sensor(aperture_diameter=0.2, focal_length=4.0, pixel_pitch_x=10e-6,
                         wavelength_min=0.45e-6, wavelength_max=0.7e-6,
                         integration_time=0.004, read_noise=20.0, max_well=60000.0,
                         bit_depth=12.0)
    scenario = xbsm.scenario(altitude=3000.0, ground_range=3000.0, visibility=23.0)
    image = np.full((90, 120), 40.0)
    result = xbsm.simulate_image(image, sensor, scenario, gsd=0.004, seed=0,
                                 outputs=("counts",))
    boxes = [[30, 20, 60, 50], [0, 0, 120, 90]]
    ds = from_arrays([image], gsd=0.004, boxes=[boxes])
    source = ({"id": 7, "category_id": 3, "keypoints": [45, 35, 2, 0, 0, 0]},
              {"id": 8, "category_id": 3, "segmentation": [[30, 20, 60, 20, 60, 50]]})
    item = ds[0].__class__(**{**ds[0].__dict__, "annotations": source})
    moved, dropped = move_annotations(item, PixelMap.of(result), 1, 5)
    expected = transform_boxes(boxes, result, clip=True).values
    for ann, box in zip(moved, expected, strict=True):
        x, y, w, h = ann["bbox"]
        np.testing.assert_allclose([x, y, x + w, y + h], box, atol=1e-4)
    point = transform_points([[45, 35]], result).values[0]
    np.testing.assert_allclose(moved[0]["keypoints"][:2], point, atol=1e-4)
    assert moved[0]["keypoints"][2:] == [2, 0, 0, 0]  # visibility kept, unlabelled stays 0
    corner = transform_points([[60, 20]], result).values[0]
    np.testing.assert_allclose(moved[1]["segmentation"][0][2:4], corner, atol=1e-4)
    assert [a["id"] for a in moved] == [1, 2] and {a["image_id"] for a in moved} == {5}
    assert [a["source_id"] for a in moved] == [7, 8] and not dropped
    scale = float(result.scale_x * result.scale_y)
    assert moved[0]["area"] == pytest.approx(900 * scale, abs=1e-3)


def test_16_bit_rgb_png_from_another_encoder_reads_back_whole(tmp_path):
    # OpenCV, if present, writes 16-bit RGB PNG with libpng's adaptive filters (Sub, Up,
    # Average, Paeth); our reader must undo each. Without OpenCV, our own file (filter 0).
    from xbsm.datasets import read_pixels

    y, x = np.mgrid[0:37, 0:41]
    img = np.stack([x * 1500, y * 1700, (x * y * 37) % 65536], axis=-1).astype(np.uint16)
    img[5:9, 5:30] = np.random.default_rng(3).integers(0, 65536, (4, 25, 3))
    try:
        import cv2
    except ModuleNotFoundError:
        write_image(tmp_path / "a.png", img)
    else:
        cv2.imwrite(str(tmp_path / "a.png"), img[..., ::-1])  # OpenCV's order is BGR
    np.testing.assert_array_equal(read_pixels(tmp_path / "a.png"), img)


def test_writes_of_one_file_from_four_threads_at_once_each_succeed_whole(tmp_path):
    # the temporary name was per process: the threads wrote into one temporary file, and
    # all but the first to rename it raised FileNotFoundError (3 of 4 in every round)
    path, threads = tmp_path / "a.json", 4
    docs = [{"thread": k, "pad": "x" * (1 << 20)} for k in range(threads)]
    barrier = threading.Barrier(threads)

    def write(doc):
        barrier.wait()
        return write_json(path, doc)

    for _ in range(5):
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(write, docs))
        assert json.loads(path.read_text()) in docs
    assert os.listdir(tmp_path) == ["a.json"]
