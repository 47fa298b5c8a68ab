"""Interrupt and resume an image-dataset study (`xbsm simulate`) at 6 moments.

A labelled synthetic dataset (24 images of mixed sizes, grey and RGB, a box and two
keypoints each, a COCO file) over 3 ranges (72 outputs, 16-bit PNG, a COCO file per
range and the NetCDF table) is run once without interruption (the reference), then
again from scratch for each moment, with SIGINT sent:

1. ``startup``: 0.3 s after launch (Python importing numpy, the study loading);
2. ``first image``: as soon as the first output image has its final name;
3. ``half``: when the progress line says half the outputs are done;
4. ``assembly``: as soon as every chunk's record is written (the COCO files and the
   NetCDF table being assembled);
5. ``late``: 1.5 s after the ``half`` moment of the reference run's timing;
6. ``completion``: as soon as the run's completion marker appears (the run releasing
   its lock and returning: a signal here once made a complete run "interrupted", and
   the resume was then refused as complete).

For each: the exit code (130, or 0 exactly when the run is complete: it finished
before the signal, or the signal landed after its completion marker), the seconds from
the signal to the exit (no hang: at most 60), then every file that has its final name is
checked (each image decodes whole; a COCO file, which is written only after every
chunk, so that the run may stop between two scenarios' files, must list every image of
its scenario, each written), and the run is resumed by running the same command again
(refused as complete after an exit 0, which is no problem; any other failure is). The resumed
outputs (every image, every COCO file; the NetCDF table's values) must equal the
reference byte for byte. Results to ``docs/benchmarks/interrupt_dataset.json``;
``docs/datasets.md`` quotes them. Run from the repository root (the ``datasets``
extra installed)::

    python recipes/bench/interrupt_dataset.py
"""

from __future__ import annotations

import hashlib
import json
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

from _provenance import commit, machine

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "benchmarks" / "interrupt_dataset.json"
MOMENTS = ("startup", "first image", "half", "assembly", "late", "completion")
IMAGES = 24

STUDY = '''
title = "interrupt test"
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
ground_range = [2000.0, 4000.0, 6000.0]
[dataset]
input = "coco.json"
output = "out"
chunk_images = 2
netcdf = "sweep.nc"
'''


def dataset(folder: Path) -> None:
    """Images of mixed sizes (grey and RGB), a bright square each, a COCO file, the study."""
    from PIL import Image

    rng = np.random.default_rng(0)
    images, annotations = [], []
    for i in range(IMAGES):
        rows, cols = (int(v) for v in rng.integers(60, 160, 2))
        img = rng.integers(20, 60, (rows, cols)).astype(np.uint8)
        img[20:50, 25:55] = 220
        if i % 3 == 0:
            img = np.repeat(img[..., None], 3, axis=2)
        Image.fromarray(img).save(folder / f"img{i:02d}.png")
        images.append({"id": i + 1, "file_name": f"img{i:02d}.png", "width": cols,
                       "height": rows, "gsd": 0.004})
        annotations.append({"id": i + 1, "image_id": i + 1, "category_id": 1,
                            "bbox": [25, 20, 30, 30], "area": 900, "iscrowd": 0,
                            "keypoints": [40, 35, 2, 0, 0, 0]})
    (folder / "coco.json").write_text(json.dumps({
        "images": images, "annotations": annotations,
        "categories": [{"id": 1, "name": "square", "keypoints": ["centre", "none"]}]}))
    (folder / "study.toml").write_text(STUDY)


def outputs(out: Path) -> dict:
    """Every output file but the NetCDF table and the run's state: path -> SHA-256."""
    return {p.relative_to(out).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(out.rglob("*")) if p.is_file() and ".xbsm-run" not in p.parts
            and p.suffix != ".nc"}


def table(out: Path) -> dict:
    import xarray as xr

    with xr.open_dataset(out / "sweep.nc") as ds:
        return {name: ds[name].values.tolist() for name in ds.data_vars}


def nothing_partial(out: Path) -> list[str]:
    """Problems: a file with its final name that is not whole, a COCO file not complete."""
    from xbsm.datasets import read_pixels

    problems = []
    for path in out.rglob("*.png"):
        try:
            read_pixels(path)
        except ValueError as err:
            problems.append(f"{path}: {err}")
    for path in out.rglob("annotations.json"):
        # a COCO file is written only after every chunk: whichever exist when the run stops
        # (it may stop between two scenarios' files) must list all of their scenario's images
        doc = json.loads(path.read_text())
        if len(doc["images"]) != IMAGES:
            problems.append(f"{path} lists {len(doc['images'])} of {IMAGES} images")
        for entry in doc["images"]:
            if not (path.parent / entry["file_name"]).is_file():
                problems.append(f"{path} lists {entry['file_name']}, which is not written")
    return problems


def command(folder: Path) -> list:
    return [sys.executable, "-m", "xbsm.cli", "simulate", str(folder / "study.toml"),
            "--workers", "2"]


def _as_in_a_terminal():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def interrupted_run(folder: Path, moment: str, late_after: float) -> dict:
    out = folder / "out"
    started = time.monotonic()
    proc = subprocess.Popen(command(folder), stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                            text=True, preexec_fn=_as_in_a_terminal)
    total = IMAGES * 3

    def wait_for(condition, limit=300.0):
        while not condition() and proc.poll() is None and time.monotonic() - started < limit:
            time.sleep(0.005)

    if moment == "startup":
        time.sleep(0.3)
    elif moment == "first image":
        wait_for(lambda: any(out.rglob("img*.png")) if out.exists() else False)
    elif moment == "half":
        for line in proc.stderr:
            if f"simulating images: {total // 2} of" in line or "100 %" in line:
                break
    elif moment == "assembly":
        chunks = out / ".xbsm-run" / "chunks"
        wait_for(lambda: chunks.is_dir() and len(list(chunks.glob("chunk-*.json")))
                 >= IMAGES // 2)
    elif moment == "late":
        time.sleep(late_after + 1.5)
    else:
        marker = out / ".xbsm-run" / "complete.json"
        wait_for(marker.is_file, limit=900.0)
    signalled = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=60)
        hung = False
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        hung = True
    exit_s = time.monotonic() - signalled
    problems = nothing_partial(out) if out.exists() else []
    images_before = len(list(out.rglob("img*.png"))) if out.exists() else 0
    complete = (out / ".xbsm-run" / "complete.json").is_file()
    # the exit code tells the truth: 0 exactly when the run is complete (then the same
    # command again is refused as complete), 130 when it is not (then it resumes)
    if complete != (proc.returncode == 0):
        problems.append(f"exit code {proc.returncode} with the run "
                        f"{'complete' if complete else 'unfinished'}")
    resumed = subprocess.run(command(folder), capture_output=True, text=True, timeout=900)
    if resumed.returncode and not (complete and "is complete" in resumed.stderr):
        problems.append(f"the same command again exited {resumed.returncode}")
    return {"moment": moment, "signal_after_s": signalled - started,
            "exit_code": proc.returncode, "exit_after_signal_s": exit_s, "hung": hung,
            "last_line": err.strip().splitlines()[-1] if err.strip() else "",
            "images_on_disk_at_exit": images_before, "complete_at_exit": complete,
            "problems": problems,
            "resume_exit_code": resumed.returncode,
            "resume_error": (resumed.stderr.strip().splitlines()[-1]
                             if resumed.returncode and resumed.stderr.strip() else ""),
            "resume_notice": [line for line in resumed.stdout.splitlines()
                              if "resuming" in line or "complete" in line]}


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        reference = Path(tmp) / "reference"
        reference.mkdir()
        dataset(reference)
        started = time.monotonic()
        subprocess.run(command(reference), check=True, capture_output=True, timeout=900)
        reference_s = time.monotonic() - started
        expected, expected_table = outputs(reference / "out"), table(reference / "out")
        print(f"reference: {len(expected)} files in {reference_s:.1f} s", flush=True)
        runs = []
        for moment in MOMENTS:
            folder = Path(tmp) / moment.replace(" ", "_")
            folder.mkdir()
            dataset(folder)
            run = interrupted_run(folder, moment, reference_s / 2)
            run["equal_to_reference"] = (outputs(folder / "out") == expected
                                         and table(folder / "out") == expected_table)
            runs.append(run)
            print(f"{moment}: signal at {run['signal_after_s']:.2f} s, exit "
                  f"{run['exit_code']} after {run['exit_after_signal_s']:.2f} s, "
                  f"{run['images_on_disk_at_exit']} images on disk, problems "
                  f"{run['problems'] or 'none'}, resumed equal: {run['equal_to_reference']}",
                  flush=True)
    ok = all(r["equal_to_reference"] and not r["problems"] and not r["hung"] for r in runs)
    OUT.write_text(json.dumps({"machine": machine(), **commit(), "reference_s": reference_s,
                               "files": len(expected), "runs": runs, "all_ok": ok},
                              indent=1) + "\n")
    print(f"all moments ok: {ok}; wrote {OUT}")
    if not ok:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
