"""Image datasets out: PNG and TIFF images and JSON files, each written whole or not at all.

Every file is written under a temporary name in its own folder (a hidden name
that no reader takes for an image or a COCO file), flushed to disk and renamed
onto its final name with :func:`os.replace`, which is atomic on POSIX and
Windows: a file with its final name is complete, whatever interrupts the
writer. PNG is encoded here (numpy and :mod:`zlib`: 8- and 16-bit grey and RGB,
which Pillow cannot write at 16 bits per colour channel); TIFF through tifffile.
"""

from __future__ import annotations

import contextlib
import json
import os
import struct
import threading
import zlib
from pathlib import Path

import numpy as np

__all__ = ["FORMATS", "TEMP_PREFIX", "atomic_file", "atomic_write", "encode_png", "temp_path",
           "write_image", "write_json"]

#: Image formats and their file suffixes.
FORMATS = {"png": ".png", "tiff": ".tif"}
#: Temporary files start with this (a crash leaves them; a resumed run removes them).
TEMP_PREFIX = ".xbsm-partial-"


def temp_path(path: Path) -> Path:
    """The temporary file of ``path`` for this process and thread (:data:`TEMP_PREFIX`)."""
    return path.with_name(f"{TEMP_PREFIX}{os.getpid()}-{threading.get_ident()}-{path.name}")


@contextlib.contextmanager
def atomic_file(path, mode: str = "w"):
    """A file opened under a temporary name, renamed onto ``path`` only when the block ends.

    Text (UTF-8) with ``mode="w"``, bytes with ``"wb"``. The data is flushed and synced
    before :func:`os.replace`; an exception (a signal) removes the temporary file and
    leaves ``path`` as it was. The temporary name is the process's and the thread's own
    (:func:`temp_path`), so threads writing one ``path`` at once each rename a whole file.
    """
    path = Path(path)
    temp = temp_path(path)
    try:
        with open(temp, mode, **({} if "b" in mode else {"encoding": "utf-8"})) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temp, path)
    except BaseException:
        temp.unlink(missing_ok=True)
        raise


def atomic_write(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` whole or not at all (temporary file, fsync, os.replace)."""
    with atomic_file(path, "wb") as handle:
        handle.write(data)
    return Path(path)


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(
        ">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def encode_png(image: np.ndarray, level: int = 6) -> bytes:
    """PNG bytes of a uint8 or uint16 image, (rows, columns) grey or (rows, columns, 3) RGB.

    The PNG specification (ISO/IEC 15948): IHDR, one zlib IDAT of filter-0 rows in
    network byte order, IEND.
    """
    image = np.asarray(image)
    if image.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"a PNG holds uint8 or uint16 pixels; got {image.dtype}")
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise ValueError(f"a PNG image is (rows, columns) or (rows, columns, 3); got "
                         f"{image.shape}")
    rows, cols = image.shape[:2]
    colour = 2 if image.ndim == 3 else 0
    depth = 8 * image.dtype.itemsize
    raw = image.astype(image.dtype.newbyteorder(">"), copy=False).reshape(rows, -1)
    raw = raw.view(np.uint8).reshape(rows, -1)
    lines = np.concatenate([np.zeros((rows, 1), np.uint8), raw], axis=1)
    header = struct.pack(">IIBBBBB", cols, rows, depth, colour, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header)
            + _chunk(b"IDAT", zlib.compress(lines.tobytes(), level)) + _chunk(b"IEND", b""))


def _encode_tiff(image: np.ndarray) -> bytes:
    try:
        import tifffile
    except ModuleNotFoundError:
        raise ModuleNotFoundError("writing TIFF needs tifffile: pip install "
                                  "'xbsm[datasets]'") from None
    import io

    buffer = io.BytesIO()
    tifffile.imwrite(buffer, image, photometric="rgb" if image.ndim == 3 else "minisblack",
                     compression="zlib")
    return buffer.getvalue()


def write_image(path, image: np.ndarray, format: str = "png") -> Path:  # noqa: A002
    """Write an image atomically as PNG or TIFF (:data:`FORMATS`)."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {sorted(FORMATS)}; got {format!r}")
    data = encode_png(image) if format == "png" else _encode_tiff(np.asarray(image))
    return atomic_write(path, data)


def write_json(path, doc) -> Path:
    """Write a JSON document atomically (UTF-8, no NaN: a NaN is an error)."""
    return atomic_write(path, json.dumps(doc, allow_nan=False, separators=(",", ":"))
                        .encode("utf-8"))
