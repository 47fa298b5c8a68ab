"""Image datasets in: an image folder, a COCO JSON file, or a list of arrays.

A dataset is a list of :class:`Item` (one image each: where its pixels come from,
its size and channels, its ground sample distance, its labels) and the COCO
categories. Everything that can be checked without decoding the pixels is
checked when the dataset is read: every file exists and has an image header,
every box and point lies inside its image, every annotation names a known
image, the GSDs are positive and in one unit. Each problem is a
:class:`DatasetError`, one line naming the file and the item. The pixels are
read only when an image is simulated (:meth:`Item.pixels`), so a dataset of
any length costs the memory of its labels.

Coordinates are continuous pixel coordinates, pixel ``i`` covering
``[i, i + 1)``: COCO's ``bbox`` ``[x, y, width, height]`` as it is, keypoints
``[x, y, v]`` as points (``v = 0``: not labelled).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["GSD_UNITS", "IMAGE_SUFFIXES", "DatasetError", "ImageDataset", "Item",
           "from_arrays", "from_coco", "from_folder", "read_pixels", "read_sidecar"]

#: Image files an image folder is read for (case-insensitive suffixes).
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")
#: Units a GSD may be given in, and their size in metres.
GSD_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}


class DatasetError(ValueError):
    """A dataset that cannot be simulated as given: one line naming the file and the item."""


@dataclass(frozen=True)
class Item:
    """One image of a dataset: its source, shape, GSD and labels.

    ``boxes`` are (n, 4) ``x_min, y_min, x_max, y_max`` [pixels] (COCO's
    ``[x, y, w, h]`` is ``x, y, x + w, y + h``); ``keypoints`` (n, k, 3) ``x, y, v``;
    ``annotations`` the source annotations (COCO dicts, carried with the moved
    geometry); ``segmentations`` polygons per annotation (lists of flat x, y lists).
    """

    id: int
    name: str  # file name relative to the dataset's image folder (or "image-<i>")
    height: int
    width: int
    channels: int  # 1 (grey) or 3 (colour; an alpha channel is dropped)
    gsd: float  # [m]
    path: Path | None = None
    array: np.ndarray | None = field(default=None, repr=False)
    boxes: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)), repr=False)
    keypoints: np.ndarray | None = field(default=None, repr=False)
    annotations: tuple = field(default=(), repr=False)

    def pixels(self) -> np.ndarray:
        """The image's pixel values, (rows, columns) or (rows, columns, 3)."""
        return read_pixels(self.path) if self.array is None else self.array


@dataclass(frozen=True)
class ImageDataset:
    """Images, their GSDs and labels, and the COCO categories (possibly empty)."""

    items: tuple
    categories: tuple = ()
    source: str = "arrays"
    keypoint_names: tuple = ()

    def __len__(self) -> int:
        return len(self.items)

    def __iter__(self):
        return iter(self.items)

    def __getitem__(self, index) -> Item:
        return self.items[index]


# --- pixels --------------------------------------------------------------------------


def _tiff(path: Path):
    try:
        import tifffile
    except ModuleNotFoundError:
        raise DatasetError(f"{path}: reading TIFF needs tifffile: pip install "
                           "'xbsm[datasets]'") from None
    return tifffile


def _pil(path: Path):
    try:
        from PIL import Image
    except ModuleNotFoundError:
        raise DatasetError(f"{path}: reading images needs Pillow: pip install "
                           "'xbsm[datasets]'") from None
    return Image


def _channels(array: np.ndarray, path) -> np.ndarray:
    """Grey (rows, columns) or colour (rows, columns, 3): alpha dropped, 1 channel squeezed."""
    if array.ndim == 3 and array.shape[-1] in (2, 4):  # grey + alpha, RGBA
        array = array[..., :-1]
    if array.ndim == 3 and array.shape[-1] == 1:
        array = array[..., 0]
    if array.ndim not in (2, 3) or (array.ndim == 3 and array.shape[-1] != 3):
        raise DatasetError(f"{path}: an image must be grey or RGB(A); got an array of shape "
                           f"{array.shape}")
    return array


def _png_header(path: Path):
    """(bit depth, colour type, interlace) of a PNG file, or None if it is not one."""
    with open(path, "rb") as handle:
        head = handle.read(29)
    if len(head) < 29 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    return head[24], head[25], head[28]


def _unfilter(lines: np.ndarray, bpp: int) -> np.ndarray:
    """PNG filters undone (ISO/IEC 15948 Sec. 9): rows of (1 filter byte + data)."""
    rows, width = lines.shape[0], lines.shape[1] - 1
    out = np.zeros((rows, width), np.uint8)
    previous = np.zeros(width, np.int64)
    for r in range(rows):
        kind, row = lines[r, 0], lines[r, 1:].astype(np.int64)
        if kind == 0:
            cur = row
        elif kind == 1:  # Sub: a running sum per byte of a pixel
            cur = np.cumsum(row.reshape(-1, bpp), axis=0).ravel() % 256
        elif kind == 2:  # Up
            cur = (row + previous) % 256
        elif kind in (3, 4):  # Average, Paeth: each pixel depends on the one left of it
            cur = row.copy()
            for i in range(0, width, bpp):
                a = cur[i - bpp:i] if i else np.zeros(bpp, np.int64)
                b = previous[i:i + bpp]
                if kind == 3:
                    cur[i:i + bpp] = (cur[i:i + bpp] + (a + b) // 2) % 256
                else:
                    c = previous[i - bpp:i] if i else np.zeros(bpp, np.int64)
                    p = a + b - c
                    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
                    pred = np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))
                    cur[i:i + bpp] = (cur[i:i + bpp] + pred) % 256
        else:
            raise ValueError(f"unknown PNG filter type {kind}")
        out[r] = cur
        previous = cur
    return out


def _read_png_rgb16(path: Path) -> np.ndarray:
    """A 16-bit RGB(A) PNG (Pillow reads it as 8 bits a channel): (rows, columns, 3|4) uint16."""
    import struct
    import zlib

    data = path.read_bytes()
    pos, idat, header = 8, [], None
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + length
    cols, rows, _, colour, _, _, interlace = header
    if interlace:
        raise ValueError("interlaced 16-bit RGB PNG (save it without interlacing or as TIFF)")
    channels = 3 if colour == 2 else 4
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), np.uint8)
    lines = raw.reshape(rows, 1 + cols * channels * 2)
    pixels = _unfilter(lines, channels * 2)
    return pixels.view(">u2").reshape(rows, cols, channels).astype(np.uint16)


def read_pixels(path) -> np.ndarray:
    """An image file's pixel values: (rows, columns) grey or (rows, columns, 3) colour.

    PNG, JPEG and BMP through Pillow (8- and 16-bit grey, 8-bit RGB and RGBA; a palette
    image as RGB), 16-bit RGB(A) PNG here (Pillow reads it as 8 bits a channel), TIFF
    through tifffile (any integer or float dtype). An alpha channel is
    dropped.

    Raises
    ------
    DatasetError
        A missing, unreadable or damaged file, naming it.
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: no such image file")
    try:
        if path.suffix.lower() in (".tif", ".tiff"):
            array = _tiff(path).imread(path)
        elif (_png_header(path) or (0, 0, 0))[:2] in ((16, 2), (16, 6)):
            array = _read_png_rgb16(path)
        else:
            with _pil(path).open(path) as img:
                if img.mode in ("P", "PA", "1", "CMYK", "YCbCr", "LAB", "HSV"):
                    img = img.convert("RGBA" if "transparency" in img.info else "RGB")
                img.load()
                array = np.asarray(img)
    except DatasetError:
        raise
    except Exception as err:  # noqa: BLE001 - any decoder failure is a damaged file
        raise DatasetError(f"{path}: cannot decode the image ({type(err).__name__}: "
                           f"{str(err).splitlines()[0] if str(err) else 'damaged file'})"
                           ) from None
    return _channels(np.asarray(array), path)


def _header(path: Path) -> tuple[int, int, int]:
    """(rows, columns, channels) from the file's header, without decoding the pixels."""
    if not path.is_file():
        raise DatasetError(f"{path}: no such image file")
    try:
        if path.suffix.lower() in (".tif", ".tiff"):
            with _tiff(path).TiffFile(path) as tif:
                shape = tif.pages[0].shape
            rows, cols = shape[0], shape[1]
            bands = shape[2] if len(shape) == 3 else 1
        else:
            with _pil(path).open(path) as img:
                cols, rows = img.size
                bands = len(img.getbands())
                if img.mode in ("P", "PA", "1"):
                    bands = 3 if img.mode != "1" else 1
    except DatasetError:
        raise
    except Exception as err:  # noqa: BLE001 - any header failure is a damaged file
        raise DatasetError(f"{path}: not a readable image ({type(err).__name__}: "
                           f"{str(err).splitlines()[0] if str(err) else 'damaged file'})"
                           ) from None
    channels = {1: 1, 2: 1, 3: 3, 4: 3}.get(bands)
    if channels is None or rows < 1 or cols < 1:
        raise DatasetError(f"{path}: an image must be grey or RGB(A) with at least one pixel; "
                           f"got {rows} x {cols} with {bands} channels")
    return rows, cols, channels


# --- ground sample distances ---------------------------------------------------------


def _gsd_value(value, unit, where: str) -> tuple[float, str]:
    """A GSD in metres from a number (or "number unit" text) and a unit."""
    if isinstance(value, str):
        text = value.strip().split()
        if len(text) == 2:
            value, unit = text
        elif len(text) == 1:
            value = text[0]
    if unit is None:
        unit = "m"
    if unit not in GSD_UNITS:
        raise DatasetError(f"{where}: GSD unit {unit!r} is not one of {', '.join(GSD_UNITS)}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise DatasetError(f"{where}: GSD {value!r} is not a number") from None
    if not (math.isfinite(number) and number > 0):
        raise DatasetError(f"{where}: GSD must be in (0, inf); got {number!r}")
    return number * GSD_UNITS[unit], unit


def _one_unit(units: dict, where: str) -> None:
    """All GSDs of a dataset in one unit: a mix is refused, naming the first that differs."""
    first = next(iter(units.items()), None)
    for name, unit in units.items():
        if unit != first[1]:
            raise DatasetError(f"{where}: mixed GSD units: {name!r} is in {unit!r} but "
                               f"{first[0]!r} is in {first[1]!r}; give every GSD in one "
                               f"unit ({', '.join(GSD_UNITS)})")


def read_sidecar(path) -> dict[str, float]:
    """Per-image GSDs [m] from a sidecar file: file name -> GSD.

    A CSV file with a header ``file_name,gsd`` and optionally ``units`` (m, cm, mm;
    default m), or a JSON object ``{"file_name": gsd}`` whose values may also be
    ``{"gsd": value, "units": "cm"}`` or text such as ``"5 cm"``. Every GSD must be
    in one unit.
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: no such GSD sidecar file")
    out, units = {}, {}
    try:
        if path.suffix.lower() == ".csv":
            with path.open(newline="", encoding="utf-8") as handle:
                rows = list(csv.DictReader(handle))
            if rows and not {"file_name", "gsd"} <= set(rows[0]):
                raise DatasetError(f"{path}: a GSD sidecar CSV needs the columns file_name and "
                                   f"gsd (and optionally units); got {sorted(rows[0])}")
            entries = [(r["file_name"], r["gsd"], r.get("units") or None, f"line {i + 2}")
                       for i, r in enumerate(rows)]
        else:
            doc = json.loads(path.read_text(encoding="utf-8"))
            if not isinstance(doc, dict):
                raise DatasetError(f"{path}: a GSD sidecar JSON is an object "
                                   "{\"file_name\": gsd, ...}")
            entries = []
            for name, value in doc.items():
                unit = None
                if isinstance(value, dict):
                    value, unit = value.get("gsd"), value.get("units")
                entries.append((name, value, unit, repr(name)))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, csv.Error) as err:
        raise DatasetError(f"{path}: cannot read the GSD sidecar ({err})") from None
    for name, value, unit, where in entries:
        out[name], units[name] = _gsd_value(value, unit, f"{path}, {where}")
    _one_unit(units, str(path))
    return out


def _gsds(names: Sequence[str], gsd, where: str, given: dict | None = None) -> list[float]:
    """Each image's GSD [m]: a constant, a sidecar file, or the dataset's own values."""
    given = dict(given or {})
    if gsd is None and not given:
        raise DatasetError(f"{where}: no ground sample distance: give gsd= a number [m] or a "
                           "sidecar file (CSV file_name,gsd[,units] or JSON)")
    if isinstance(gsd, str | Path) and not _is_number_text(gsd):
        given.update(read_sidecar(gsd))
        gsd = None
    if gsd is not None:
        value = _gsd_value(gsd, None, f"{where}, gsd")[0]
        return [given.get(name, value) for name in names]
    missing = [name for name in names if name not in given]
    if missing:
        raise DatasetError(f"{where}: no GSD for image {missing[0]!r} ({len(missing)} of "
                           f"{len(names)} images have none); give it in the sidecar or a "
                           "constant gsd=")
    return [given[name] for name in names]


def _is_number_text(value) -> bool:
    try:
        _gsd_value(value, None, "")
    except DatasetError:
        return False
    return isinstance(value, str)


# --- the three readers ---------------------------------------------------------------


def from_folder(folder, gsd=None, *, recursive: bool = False) -> ImageDataset:
    """Every image file of a folder (:data:`IMAGE_SUFFIXES`), in sorted order.

    Parameters
    ----------
    folder : str or Path
        The image folder.
    gsd : float, str or Path
        One GSD for every image [m], or a sidecar file of per-image GSDs
        (:func:`read_sidecar`; its file names relative to ``folder``).
    recursive : bool
        Include the images of subfolders (file names keep their subfolder).

    Returns
    -------
    ImageDataset
        No labels.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DatasetError(f"{folder}: no such image folder")
    pattern = "**/*" if recursive else "*"
    paths = sorted(p for p in folder.glob(pattern)
                   if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
    if not paths:
        raise DatasetError(f"{folder}: no image files ({', '.join(IMAGE_SUFFIXES)})")
    names = [p.relative_to(folder).as_posix() for p in paths]
    gsds = _gsds(names, gsd, str(folder))
    items = []
    for i, (path, name, value) in enumerate(zip(paths, names, gsds, strict=True)):
        rows, cols, channels = _header(path)
        items.append(Item(id=i + 1, name=name, height=rows, width=cols, channels=channels,
                          gsd=value, path=path))
    return ImageDataset(tuple(items), source=str(folder))


def _check_box(box, rows, cols, where: str) -> np.ndarray:
    """A COCO ``[x, y, w, h]`` as x_min, y_min, x_max, y_max, inside the image."""
    try:
        x, y, w, h = (float(v) for v in box)
    except (TypeError, ValueError):
        raise DatasetError(f"{where}: bbox must be [x, y, width, height]; got {box!r}") from None
    # half a pixel of tolerance: labelling tools round edges to the nearest half pixel
    if not (w > 0 and h > 0 and x >= -0.5 and y >= -0.5 and x + w <= cols + 0.5
            and y + h <= rows + 0.5):
        raise DatasetError(f"{where}: bbox [{x:g}, {y:g}, {w:g}, {h:g}] is not inside the "
                           f"{cols} x {rows} image (x in [0, {cols}], y in [0, {rows}], "
                           "width and height > 0)")
    return np.array([x, y, x + w, y + h])


def _check_points(values, rows, cols, where: str) -> np.ndarray:
    """COCO keypoints ``[x1, y1, v1, ...]`` as (k, 3), the labelled ones inside the image."""
    points = np.asarray(values, dtype=float)
    if points.ndim != 1 or points.size % 3:
        raise DatasetError(f"{where}: keypoints must be a flat list x1, y1, v1, ...; got "
                           f"{len(values)} numbers")
    points = points.reshape(-1, 3)
    shown = points[:, 2] > 0
    outside = shown & ((points[:, 0] < 0) | (points[:, 0] > cols) | (points[:, 1] < 0)
                       | (points[:, 1] > rows))
    if outside.any():
        k = int(np.argmax(outside))
        raise DatasetError(f"{where}: keypoint {k} ({points[k, 0]:g}, {points[k, 1]:g}) is "
                           f"outside the {cols} x {rows} image")
    return points


def from_coco(annotation_file, images=None, gsd=None) -> ImageDataset:
    """A COCO detection or keypoint dataset: images, boxes, keypoints, categories.

    Parameters
    ----------
    annotation_file : str or Path
        The COCO JSON file (``images``, ``annotations``, ``categories``).
    images : str or Path, optional
        The folder of the images' ``file_name``; default the JSON file's folder.
    gsd : float, str or Path, optional
        One GSD for every image [m], or a sidecar file (:func:`read_sidecar`); default
        each image entry's own ``gsd`` (with an optional ``gsd_units``: m, cm, mm; one
        unit for the whole file). A sidecar or the entries' values win over a constant.

    Returns
    -------
    ImageDataset
    """
    path = Path(annotation_file)
    folder = Path(images) if images is not None else path.parent
    if not path.is_file():
        raise DatasetError(f"{path}: no such COCO file")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise DatasetError(f"{path}: not a COCO JSON file ({err})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("images"), list):
        raise DatasetError(f"{path}: a COCO file is an object with a list 'images'")
    entries, own, units = [], {}, {}
    for k, entry in enumerate(doc["images"]):
        if not isinstance(entry, dict) or "id" not in entry or "file_name" not in entry:
            raise DatasetError(f"{path}: images[{k}] needs 'id' and 'file_name'")
        entries.append(entry)
        if "gsd" in entry:
            where = f"{path}, image id {entry['id']} ({entry['file_name']})"
            own[entry["file_name"]], units[entry["file_name"]] = _gsd_value(
                entry["gsd"], entry.get("gsd_units"), where)
    _one_unit(units, str(path))
    ids = [e["id"] for e in entries]
    if len(set(ids)) != len(ids):
        dup = next(i for i in ids if ids.count(i) > 1)
        raise DatasetError(f"{path}: image id {dup} appears twice in 'images'")
    names = [e["file_name"] for e in entries]
    gsds = _gsds(names, gsd, str(path), own)
    shapes = {}
    for entry in entries:
        image_path = folder / entry["file_name"]
        rows, cols, channels = _header(image_path)
        for key, value in (("width", cols), ("height", rows)):
            if key in entry and int(entry[key]) != value:
                raise DatasetError(f"{path}, image id {entry['id']} ({entry['file_name']}): "
                                   f"{key} {entry[key]} but the file has {value}")
        shapes[entry["id"]] = (rows, cols, channels, image_path)
    boxes = {i: [] for i in ids}
    points = {i: [] for i in ids}
    kept = {i: [] for i in ids}
    for k, ann in enumerate(doc.get("annotations", [])):
        if not isinstance(ann, dict) or "image_id" not in ann:
            raise DatasetError(f"{path}: annotations[{k}] needs an 'image_id'")
        where = f"{path}, annotation id {ann.get('id', k)}"
        if ann["image_id"] not in shapes:
            raise DatasetError(f"{where}: image_id {ann['image_id']!r} is not in 'images'")
        rows, cols, _, image_path = shapes[ann["image_id"]]
        where += f" (image {image_path.name})"
        if "bbox" not in ann:
            raise DatasetError(f"{where}: no bbox")
        boxes[ann["image_id"]].append(_check_box(ann["bbox"], rows, cols, where))
        if "keypoints" in ann:
            points[ann["image_id"]].append(_check_points(ann["keypoints"], rows, cols, where))
        kept[ann["image_id"]].append(ann)
    items = []
    for entry, value in zip(entries, gsds, strict=True):
        i = entry["id"]
        rows, cols, channels, image_path = shapes[i]
        kp = points[i]
        if kp and len(kp) != len(boxes[i]):
            raise DatasetError(f"{path}, image id {i}: some annotations have keypoints and "
                               "some not; give keypoints to all of an image's annotations "
                               "or none")
        items.append(Item(id=i, name=entry["file_name"], height=rows, width=cols,
                          channels=channels, gsd=value, path=image_path,
                          boxes=np.array(boxes[i]).reshape(-1, 4),
                          keypoints=np.stack(kp) if kp else None,
                          annotations=tuple(kept[i])))
    names_kp = ()
    for cat in doc.get("categories", []):
        if isinstance(cat, dict) and cat.get("keypoints"):
            names_kp = tuple(cat["keypoints"])
    return ImageDataset(tuple(items), categories=tuple(doc.get("categories", [])),
                        source=str(path), keypoint_names=names_kp)


def from_arrays(arrays, gsd, *, boxes=None, names=None) -> ImageDataset:
    """A dataset of in-memory images: a list of (rows, columns) or (rows, columns, 3|4) arrays.

    Parameters
    ----------
    arrays : sequence of array_like
        The images (sizes and channel counts may differ).
    gsd : float or sequence of float
        One GSD for all [m], or one per image.
    boxes : sequence of array_like (n, 4), optional
        Per image, boxes ``x_min, y_min, x_max, y_max`` [pixels].
    names : sequence of str, optional
        Output file names (default ``image-00000``, ...).

    Returns
    -------
    ImageDataset
    """
    arrays = list(arrays)
    if not arrays:
        raise DatasetError("arrays: an empty list; give at least one image")
    names = list(names) if names is not None else [f"image-{i:05d}" for i in range(len(arrays))]
    if len(names) != len(arrays):
        raise DatasetError(f"names: {len(names)} names for {len(arrays)} images")
    values = np.broadcast_to(np.asarray(gsd, dtype=float), (len(arrays),)) \
        if np.ndim(gsd) == 0 else np.asarray(gsd, dtype=float)
    if values.shape != (len(arrays),):
        raise DatasetError(f"gsd: {values.size} values for {len(arrays)} images")
    items = []
    for i, (array, name, value) in enumerate(zip(arrays, names, values, strict=True)):
        where = f"arrays[{i}] ({name})"
        array = _channels(np.asarray(array), where)
        if array.shape[0] < 1 or array.shape[1] < 1:
            raise DatasetError(f"{where}: an image needs at least one pixel each way")
        rows, cols = array.shape[:2]
        value = _gsd_value(value, "m", f"{where}, gsd")[0]
        b = np.zeros((0, 4)) if boxes is None else np.asarray(boxes[i], dtype=float)
        b = b.reshape(-1, 4)
        for k, box in enumerate(b):
            _check_box([box[0], box[1], box[2] - box[0], box[3] - box[1]], rows, cols,
                       f"{where}, box {k}")
        items.append(Item(id=i + 1, name=name, height=rows, width=cols,
                          channels=1 if array.ndim == 2 else 3, gsd=value, array=array,
                          boxes=b))
    return ImageDataset(tuple(items))
