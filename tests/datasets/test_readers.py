"""xbsm.datasets.readers: folders, COCO files and arrays in; bad datasets one line each."""

from __future__ import annotations

import json

import numpy as np
import pytest
from image_datasets import SHAPES, scene, write_coco

from xbsm.datasets import DatasetError, from_arrays, from_coco, from_folder, read_pixels

Image = pytest.importorskip("PIL.Image")  # the datasets extra, which the test extra pulls in
tifffile = pytest.importorskip("tifffile")


def test_a_folder_of_mixed_sizes_grey_rgb_16_bit_and_tiff(tmp_path):
    grey16 = (np.arange(40 * 30).reshape(40, 30) * 50).astype(np.uint16)
    rgba = np.zeros((20, 25, 4), np.uint8)
    rgba[..., 0], rgba[..., 3] = 200, 128
    Image.fromarray(scene(30, 50, 1)).save(tmp_path / "a.png")
    Image.fromarray(scene(60, 40, 3)).save(tmp_path / "b.png")
    Image.fromarray(grey16).save(tmp_path / "c.png")  # Pillow writes mode I;16
    Image.fromarray(rgba).save(tmp_path / "d.png")
    tifffile.imwrite(tmp_path / "e.tif", grey16)
    (tmp_path / "notes.txt").write_text("not an image")
    ds = from_folder(tmp_path, gsd=0.05)
    assert [i.name for i in ds] == ["a.png", "b.png", "c.png", "d.png", "e.tif"]
    assert [(i.height, i.width, i.channels) for i in ds] == [
        (30, 50, 1), (60, 40, 3), (40, 30, 1), (20, 25, 3), (40, 30, 1)]
    np.testing.assert_array_equal(ds[0].pixels(), scene(30, 50, 1))
    np.testing.assert_array_equal(ds[2].pixels(), grey16)
    np.testing.assert_array_equal(ds[4].pixels(), grey16)
    assert ds[3].pixels().shape == (20, 25, 3)  # the alpha channel is dropped
    assert all(i.gsd == 0.05 for i in ds)


def test_coco_boxes_keypoints_and_gsd_units(tmp_path):
    write_coco(tmp_path)
    doc = json.loads((tmp_path / "coco.json").read_text())
    for entry in doc["images"]:
        entry["gsd"], entry["gsd_units"] = 0.4, "cm"
    (tmp_path / "coco.json").write_text(json.dumps(doc))
    ds = from_coco(tmp_path / "coco.json")
    assert len(ds) == len(SHAPES) and ds.keypoint_names == ("centre", "unseen")
    assert ds[0].gsd == pytest.approx(0.004)  # 0.4 cm
    np.testing.assert_array_equal(ds[1].boxes, [[30, 20, 60, 50]])  # [x, y, w, h] -> corners
    np.testing.assert_array_equal(ds[1].keypoints[0], [[45, 35, 2], [0, 0, 0]])
    assert ds[2].channels == 3 and ds[0].channels == 1


def test_gsd_sidecars_csv_and_json_and_a_constant(tmp_path):
    for k in range(2):
        Image.fromarray(scene(20, 20, 1)).save(tmp_path / f"{k}.png")
    (tmp_path / "gsd.csv").write_text("file_name,gsd,units\n0.png,5,cm\n1.png,7,cm\n")
    assert [i.gsd for i in from_folder(tmp_path, tmp_path / "gsd.csv")] == pytest.approx(
        [0.05, 0.07])
    (tmp_path / "gsd.json").write_text(json.dumps({"0.png": "2 mm", "1.png": {"gsd": 3,
                                                                            "units": "mm"}}))
    assert [i.gsd for i in from_folder(tmp_path, str(tmp_path / "gsd.json"))] == pytest.approx(
        [0.002, 0.003])
    with pytest.raises(DatasetError, match="no ground sample distance"):
        from_folder(tmp_path)


def test_arrays_of_mixed_sizes_and_channels():
    ds = from_arrays([np.zeros((10, 12)), np.ones((7, 9, 3)), np.ones((5, 5, 4))], gsd=[1, 2, 3],
                     boxes=[[[1, 1, 5, 5]], [], []])
    assert [(i.height, i.width, i.channels, i.gsd) for i in ds] == [
        (10, 12, 1, 1.0), (7, 9, 3, 2.0), (5, 5, 3, 3.0)]
    assert ds[0].boxes.shape == (1, 4) and ds[1].boxes.shape == (0, 4)


# --- bad datasets: one line naming the file and the item (issue 26) ----------------------


def _one_line(err, *words):
    message = str(err.value)
    assert "\n" not in message, message
    for word in words:
        assert word in message, (word, message)


def test_a_missing_image_names_the_file(tmp_path):
    write_coco(tmp_path)
    (tmp_path / "img3.png").unlink()
    with pytest.raises(DatasetError) as err:
        from_coco(tmp_path / "coco.json")
    _one_line(err, "img3.png", "no such image file")


def test_a_corrupt_image_names_the_file(tmp_path):
    write_coco(tmp_path)
    (tmp_path / "img2.png").write_bytes(b"this is not a PNG file at all")
    with pytest.raises(DatasetError) as err:
        from_coco(tmp_path / "coco.json")
    _one_line(err, "img2.png", "not a readable image")


def test_a_truncated_image_names_the_file_when_its_pixels_are_read(tmp_path):
    # the header is intact (the dataset reads), the pixel data is cut short
    write_coco(tmp_path)
    data = (tmp_path / "img1.png").read_bytes()
    (tmp_path / "img1.png").write_bytes(data[:len(data) // 2])
    ds = from_coco(tmp_path / "coco.json")
    with pytest.raises(DatasetError) as err:
        ds[1].pixels()
    _one_line(err, "img1.png", "cannot decode")


def test_a_box_outside_the_image_names_the_annotation(tmp_path):
    write_coco(tmp_path)
    doc = json.loads((tmp_path / "coco.json").read_text())
    doc["annotations"][3]["bbox"] = [50, 10, 30, 20]  # img3 is 64 wide: x_max 80
    (tmp_path / "coco.json").write_text(json.dumps(doc))
    with pytest.raises(DatasetError) as err:
        from_coco(tmp_path / "coco.json")
    _one_line(err, "coco.json", "annotation id 103", "img3.png", "not inside the 64 x 64 image")


def test_a_keypoint_outside_the_image_names_the_annotation(tmp_path):
    write_coco(tmp_path)
    doc = json.loads((tmp_path / "coco.json").read_text())
    doc["annotations"][0]["keypoints"] = [45, 35, 2, 500, 3, 1]
    (tmp_path / "coco.json").write_text(json.dumps(doc))
    with pytest.raises(DatasetError) as err:
        from_coco(tmp_path / "coco.json")
    _one_line(err, "annotation id 100", "keypoint 1")


def test_an_unknown_image_id_names_the_annotation(tmp_path):
    write_coco(tmp_path)
    doc = json.loads((tmp_path / "coco.json").read_text())
    doc["annotations"][2]["image_id"] = 999
    (tmp_path / "coco.json").write_text(json.dumps(doc))
    with pytest.raises(DatasetError) as err:
        from_coco(tmp_path / "coco.json")
    _one_line(err, "coco.json", "annotation id 102", "image_id 999 is not in 'images'")


def test_mixed_gsd_units_name_the_images(tmp_path):
    write_coco(tmp_path)
    doc = json.loads((tmp_path / "coco.json").read_text())
    doc["images"][0]["gsd_units"] = "m"
    doc["images"][4]["gsd"], doc["images"][4]["gsd_units"] = 0.4, "cm"
    (tmp_path / "coco.json").write_text(json.dumps(doc))
    with pytest.raises(DatasetError) as err:
        from_coco(tmp_path / "coco.json")
    _one_line(err, "coco.json", "mixed GSD units", "img4.png", "img0.png")


def test_mixed_units_in_a_sidecar_name_the_line(tmp_path):
    for k in range(2):
        Image.fromarray(scene(20, 20, 1)).save(tmp_path / f"{k}.png")
    (tmp_path / "gsd.csv").write_text("file_name,gsd,units\n0.png,5,cm\n1.png,0.07,m\n")
    with pytest.raises(DatasetError) as err:
        from_folder(tmp_path, tmp_path / "gsd.csv")
    _one_line(err, "gsd.csv", "mixed GSD units", "1.png")


def test_an_image_size_that_disagrees_with_the_coco_entry(tmp_path):
    write_coco(tmp_path)
    doc = json.loads((tmp_path / "coco.json").read_text())
    doc["images"][1]["width"] = 81
    (tmp_path / "coco.json").write_text(json.dumps(doc))
    with pytest.raises(DatasetError) as err:
        from_coco(tmp_path / "coco.json")
    _one_line(err, "image id 11", "img1.png", "width 81 but the file has 80")


def test_read_pixels_of_a_missing_file(tmp_path):
    with pytest.raises(DatasetError, match="no such image file"):
        read_pixels(tmp_path / "nothing.png")
