"""Image-dataset studies: `xbsm simulate`, xbsm.study.simulate (issue 26)."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from image_datasets import BOX, STUDY, write_coco

import xbsm
from xbsm import study
from xbsm.datasets import DatasetError, from_arrays, read_pixels
from xbsm.simulate import transform_boxes
from xbsm.study import images

Image = pytest.importorskip("PIL.Image")
COCO = pytest.importorskip("pycocotools.coco").COCO


def _files(folder):
    """Every output file (not the run's state) and its SHA-256."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and images.STATE not in p.parts}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """The test dataset simulated once at two ranges (5 images of mixed sizes, grey and RGB)."""
    folder = tmp_path_factory.mktemp("coco")
    spec = study.load(write_coco(folder, STUDY.replace('chunk_images = 2',
                                                       'chunk_images = 2\nnetcdf = "sweep.nc"')))
    out = study.simulate(spec, progress=False)
    return spec, out


def test_every_image_at_every_range_with_a_coco_file_that_pycocotools_loads(finished):
    spec, out = finished
    for name in ("ground_range=2000", "ground_range=4000"):
        coco = COCO(str(out / name / "annotations.json"))
        assert sorted(coco.getImgIds()) == [10, 11, 12, 13, 14]
        assert len(coco.getAnnIds()) == 5 and coco.loadCats(1)[0]["name"] == "square"
        for entry in coco.loadImgs(coco.getImgIds()):
            pixels = read_pixels(out / name / entry["file_name"])
            assert pixels.shape[:2] == (entry["height"], entry["width"])
            assert pixels.dtype == np.uint16  # what was asked: 16-bit counts
            assert entry["xbsm"]["scenario"] == {"ground_range": float(name.split("=")[1])}
            assert {"seed", "gsd", "slant_range", "flags", "flag_names"} <= set(entry["xbsm"])
        rgb = coco.loadImgs(11)[0]
        assert read_pixels(out / name / rgb["file_name"]).shape[2] == 3


def test_boxes_are_moved_by_the_images_own_pixel_map_and_bound_the_blurred_square(finished):
    spec, out = finished
    coco = COCO(str(out / "ground_range=2000" / "annotations.json"))
    dataset = images.read_dataset(spec.dataset)
    cells = images.output_cells(spec)
    for position, item in enumerate(dataset):
        entry = coco.loadImgs(item.id)[0]
        # regenerate this one output alone from its recorded seed: the same pixels
        seed = int(entry["xbsm"]["seed"])
        assert seed == images.output_seed(0, position, 0)
        image, result = images.simulate_one(item.pixels(), item.gsd, cells[0], spec.dataset,
                                            seed, spec.method)
        np.testing.assert_array_equal(image, read_pixels(out / "ground_range=2000" /
                                                         entry["file_name"]))
        (ann,) = coco.loadAnns(coco.getAnnIds(imgIds=item.id))
        x, y, w, h = ann["bbox"]
        expected = transform_boxes([BOX], result, clip=True).values[0]
        np.testing.assert_allclose([x, y, x + w, y + h], expected, atol=1e-4)
        # the square's edges in the noiseless blurred image: half-way between its levels
        blurred = xbsm.simulate_image(item.pixels(), cells[0].sensor, cells[0].scenario,
                                      gsd=item.gsd, noise=False, outputs=("blurred",))
        row = blurred.blurred.transpose("y", "x", ...).values[int(y + h / 2)]
        row = row.mean(axis=-1) if row.ndim == 2 else row
        half = 0.5 * (row.min() + row.max())
        inside = np.flatnonzero(row > half)
        # the crossings of the half level bound the moved box to a pixel
        assert abs(inside[0] - x) < 1.0 and abs(inside[-1] + 1 - (x + w)) < 1.0


def test_the_netcdf_table_holds_every_outputs_metadata(finished):
    import xarray as xr

    spec, out = finished
    with xr.open_dataset(out / "sweep.nc") as table:
        assert dict(table.sizes) == {"image": 5, "scenario": 2}
        assert table.seed.dtype == np.uint64 and (table.gsd > 0.004).all()
        # written with netCDF4 under xbsm's lock (xbsm._netcdf.write_variables), read as
        # xarray's own writer would have it: coordinates, units and the flags' meanings
        assert {"source_file", "reference_gsd"} <= set(table.coords)
        assert table.gsd.attrs["units"] == "m" and "flag_meanings" in table.flags.attrs
        assert table.file_name.dtype.kind in "OU"
        coco = COCO(str(out / "ground_range=4000" / "annotations.json"))
        assert str(int(table.seed.sel(image=12, scenario="ground_range=4000"))) == \
            coco.loadImgs(12)[0]["xbsm"]["seed"]


def test_a_finished_run_is_not_replaced_without_overwrite(finished):
    spec, out = finished
    before = _files(out)
    with pytest.raises(study.StudyError, match="is complete"):
        study.simulate(spec, progress=False)
    assert _files(out) == before


def test_a_resumed_run_recomputes_only_the_unfinished_chunks(tmp_path, finished, capsys,
                                                             monkeypatch):
    spec, reference = finished
    folder = tmp_path / "again"
    path = write_coco(folder)
    spec2 = study.load(path)
    out = study.simulate(spec2, progress=False)
    # as after an interrupt: chunk 1 unrecorded with a missing image, chunk 2 unrecorded
    (out / images.STATE / "complete.json").unlink()
    (out / images.STATE / "chunks" / "chunk-000001.json").unlink()
    (out / images.STATE / "chunks" / "chunk-000002.json").unlink()
    (out / "ground_range=4000" / "img3.png").unlink()
    (out / "ground_range=4000" / "annotations.json").unlink()
    calls = []
    real = images.simulate_batch
    monkeypatch.setattr(images, "simulate_batch",
                        lambda *a, **k: (calls.extend(a[0]), real(*a, **k))[1])
    study.simulate(spec2, progress=False)
    assert len(calls) == 3 * 2  # images 2, 3 and 4 at two ranges; 0 and 1 were kept
    assert "1 of 3 chunks are finished and kept" in capsys.readouterr().out
    files = _files(out)
    assert files == {k: v for k, v in _files(reference).items() if k != "sweep.nc"}


def test_another_runs_outputs_are_refused_then_replaced_with_overwrite(tmp_path):
    path = write_coco(tmp_path)
    out = study.simulate(study.load(path), progress=False)
    other = study.parse(path.read_text().replace("chunk_images = 2",
                                                 "chunk_images = 2\nseed = 5"), str(path))
    with pytest.raises(study.StudyError, match="another run .*differs in .*spec"):
        study.simulate(other, progress=False)
    study.simulate(other, overwrite=True, progress=False)
    coco = json.loads((out / "ground_range=2000" / "annotations.json").read_text())
    assert coco["images"][0]["xbsm"]["seed"] == str(images.output_seed(5, 0, 0))


def test_flat_layout_tiff_radiometric_8_bit(tmp_path):
    tifffile = pytest.importorskip("tifffile")
    path = write_coco(tmp_path, STUDY.replace(
        'output = "out"', 'output = "flat"\nlayout = "flat"\nformat = "tiff"\n'
        'values = "radiometric"\ndtype = "uint8"\ncoco = false'))
    out = study.simulate(study.load(path), progress=False)
    names = sorted(p.name for p in out.iterdir() if p.is_file())
    assert names == sorted(f"img{i}__ground_range={r}.tif" for i in range(5)
                           for r in (2000, 4000))
    img = tifffile.imread(out / "img1__ground_range=2000.tif")
    assert img.dtype == np.uint8 and img.ndim == 3
    # the radiometric mapping: the bright square (input 220) stays bright, the dark field dark
    assert img.max() > 180 and np.median(img) < 80


def test_an_arrays_dataset_from_python(tmp_path):
    spec = study.parse(STUDY.split("[dataset]")[0], "arrays.toml")
    arrays = [np.full((40, 50), 30.0), np.full((30, 30, 3), 90.0)]
    arrays[0][10:20, 10:30] = 200.0
    out = study.simulate(spec, tmp_path / "out", dataset=from_arrays(
        arrays, gsd=0.004, boxes=[[[10, 10, 30, 20]], []]), progress=False)
    coco = COCO(str(out / "ground_range=2000" / "annotations.json"))
    assert coco.loadCats(1)[0]["name"] == "object" and len(coco.getAnnIds()) == 1


def test_a_dataset_table_with_an_unknown_key_is_one_line_with_its_line(tmp_path):
    with pytest.raises(study.StudyError) as err:
        study.parse(STUDY.replace('output = "out"', 'ouptut = "out"'), "s.toml")
    assert str(err.value) == ("s.toml, line 20: dataset.ouptut: unknown key; did you mean "
                              "'output'?")
    with pytest.raises(study.StudyError, match='line 22: dataset.layout: unknown layout "tree"'):
        study.parse(STUDY + 'layout = "tree"\n', "s.toml")


def test_counts_wider_than_the_dtype_are_refused_before_any_work(tmp_path):
    path = write_coco(tmp_path, STUDY + 'dtype = "uint8"\n')
    with pytest.raises(study.StudyError, match="bit_depth 12"):
        study.simulate(study.load(path), progress=False)
    assert not (tmp_path / "out").exists()


def test_a_bad_dataset_is_one_line_and_writes_nothing(tmp_path):
    path = write_coco(tmp_path)
    doc = json.loads((tmp_path / "coco.json").read_text())
    doc["annotations"][0]["image_id"] = 77
    (tmp_path / "coco.json").write_text(json.dumps(doc))
    done = subprocess.run([sys.executable, "-m", "xbsm.cli", "simulate", str(path)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.splitlines() == [
        f"xbsm simulate: {tmp_path / 'coco.json'}, annotation id 100: image_id 77 is not in "
        "'images'"]
    assert not (tmp_path / "out").exists()


def test_an_image_damaged_during_a_run_stops_it_and_keeps_the_finished_chunks(tmp_path):
    # the header reads (the dataset loads), the pixels do not; with one worker the chunks
    # run two at a time, so chunks 0 and 1 are finished before chunk 2 (img4) fails
    path = write_coco(tmp_path)
    data = (tmp_path / "img4.png").read_bytes()
    (tmp_path / "img4.png").write_bytes(data[:len(data) // 2])
    with pytest.raises(DatasetError, match="img4.png: cannot decode") as err:
        study.simulate(study.load(path), workers=1, progress=False)
    assert "\n" not in str(err.value)
    out = tmp_path / "out"
    assert sorted(p.name for p in (out / images.STATE / "chunks").iterdir()) == [
        "chunk-000000.json", "chunk-000001.json"]
    assert not list(out.rglob("annotations.json"))


def test_a_ctrl_c_after_the_completion_marker_leaves_a_finished_run(tmp_path, finished,
                                                                   monkeypatch):
    # issue 26 (reproduced by signalling as soon as complete.json appeared: 3 of 4 runs
    # said "interrupted; run the same command again to resume", and that was refused as
    # complete): once the marker is written the run has succeeded
    _, reference = finished
    path = write_coco(tmp_path, STUDY.replace('chunk_images = 2',
                                              'chunk_images = 2\nnetcdf = "sweep.nc"'))
    real = images.writers.write_json

    def write_then_signal(file, doc):
        written = real(file, doc)
        if file.name == "complete.json":
            os.kill(os.getpid(), signal.SIGINT)
        return written

    monkeypatch.setattr(images.writers, "write_json", write_then_signal)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        out = study.simulate(study.load(path), progress=False)
    except KeyboardInterrupt:  # (uncaught, it would stop the whole test run)
        pytest.fail("a run with its completion marker written was reported interrupted")
    finally:
        signal.signal(signal.SIGINT, before)
        images.INTERRUPTED.clear()
    assert (out / images.STATE / "complete.json").is_file()
    assert _files(out) == _files(reference)


def _as_in_a_terminal():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("moment", ["first output", "half"])
def test_sigint_stops_the_command_and_the_resumed_outputs_equal_a_whole_run(
        tmp_path, finished, moment):
    _, reference = finished
    path = write_coco(tmp_path, STUDY.replace("chunk_images = 2", "chunk_images = 1"))
    command = [sys.executable, "-m", "xbsm.cli", "simulate", str(path), "--workers", "1"]
    proc = subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                            text=True, preexec_fn=_as_in_a_terminal)
    out = tmp_path / "out"
    if moment == "first output":
        deadline = time.monotonic() + 120
        while not list(out.rglob("img*.png")) and time.monotonic() < deadline:
            time.sleep(0.01)
    else:
        for line in proc.stderr:
            if "simulating images: 4 of 10" in line:
                break
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    # (a worker thread may still finish the output it was making after that line.) The
    # exit code tells the truth: 130 and an unfinished run that resumes, or, if the run
    # completed before the signal landed (seen under load 7), 0 and a finished run
    complete = (out / images.STATE / "complete.json").is_file()
    if proc.returncode == 0:
        assert complete
    else:
        assert proc.returncode == 130 and "xbsm simulate: interrupted" in err
        assert not complete and not list(out.rglob("annotations.json"))  # nothing complete
        subprocess.run(command, capture_output=True, text=True, timeout=300, check=True)
    assert not list(out.rglob(".xbsm-partial-*"))
    expected = {k: v for k, v in _files(reference).items() if k != "sweep.nc"}
    assert _files(out) == expected
