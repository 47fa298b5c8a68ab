"""COCO labels carried into a simulated image by the pixel map of its resampling.

The map is the simulation's own, ``u_out = scale * u_in + offset`` per axis
(``scale_x``, ``offset_x``, ``scale_y``, ``offset_y`` of
:func:`xbsm.simulate_image`; :func:`xbsm.simulate.transform_boxes` applies the
same one), so a moved box bounds the same blurred object. Boxes are clipped to
the simulated image (the map sends the reference image's edges to within a
fraction of a pixel of the simulated image's); areas scale by
``scale_x * scale_y``; keypoints move with their visibility kept (``v = 0``,
unlabelled, stays ``0, 0, 0``); polygon segmentations move point by point. A
run-length (RLE) mask is on the reference grid and cannot be moved exactly: it
is left out (the annotation keeps its moved box), and the run says so once.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PixelMap", "move_annotations", "moved_boxes"]


class PixelMap:
    """The affine map of one simulated image: scale and offset per axis, and its size."""

    def __init__(self, scale_x, offset_x, scale_y, offset_y, size_x, size_y):
        self.scale_x, self.offset_x = float(scale_x), float(offset_x)
        self.scale_y, self.offset_y = float(scale_y), float(offset_y)
        self.size_x, self.size_y = int(size_x), int(size_y)

    @classmethod
    def of(cls, simulation) -> PixelMap:
        """The map of a one-image, one-scenario :func:`xbsm.simulate_image` result."""
        return cls(*(float(simulation[name]) for name in (
            "scale_x", "offset_x", "scale_y", "offset_y", "size_x", "size_y")))

    def points(self, xy: np.ndarray) -> np.ndarray:
        """(..., 2) x, y in reference pixels to simulated-image pixels."""
        xy = np.asarray(xy, dtype=float)
        return np.stack([xy[..., 0] * self.scale_x + self.offset_x,
                         xy[..., 1] * self.scale_y + self.offset_y], axis=-1)


def moved_boxes(boxes: np.ndarray, pixel_map: PixelMap) -> np.ndarray:
    """(n, 4) x_min, y_min, x_max, y_max moved and clipped to the simulated image."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    low = pixel_map.points(boxes[:, :2])
    high = pixel_map.points(boxes[:, 2:])
    out = np.concatenate([low, high], axis=1)
    size = np.array([pixel_map.size_x, pixel_map.size_y] * 2, dtype=float)
    return np.clip(out, 0.0, size)


def _moved_keypoints(values, pixel_map: PixelMap) -> list:
    points = np.asarray(values, dtype=float).reshape(-1, 3).copy()
    shown = points[:, 2] > 0
    points[shown, :2] = pixel_map.points(points[shown, :2])
    points[~shown] = 0.0
    return [_number(v) for v in points.ravel()]


def _number(value: float):
    """A JSON number: whole values as int (visibility flags, zeros), others rounded to 1e-4."""
    value = float(value)
    return int(value) if value.is_integer() else round(value, 4)


def move_annotations(item, pixel_map: PixelMap, first_id: int, image_id: int) -> tuple:
    """An item's annotations as COCO dicts in the simulated image, and whether an RLE was left out.

    Annotation ids are ``first_id, first_id + 1, ...``; every other key of the source
    annotation (``category_id``, ``iscrowd``, user keys) is kept, and the source id
    is kept as ``source_id``.
    """
    boxes = moved_boxes(item.boxes, pixel_map)
    sources = item.annotations or tuple({"category_id": 1} for _ in range(len(boxes)))
    out, dropped_rle = [], False
    area_scale = pixel_map.scale_x * pixel_map.scale_y
    for k, (source, box) in enumerate(zip(sources, boxes, strict=True)):
        ann = {key: value for key, value in source.items()
               if key not in ("id", "image_id", "bbox", "area", "keypoints", "segmentation")}
        if "id" in source:
            ann["source_id"] = source["id"]
        ann.update(id=first_id + k, image_id=image_id,
                   bbox=[_number(box[0]), _number(box[1]), _number(box[2] - box[0]),
                         _number(box[3] - box[1])])
        reference_box = item.boxes[k]
        area = source.get("area", (reference_box[2] - reference_box[0])
                          * (reference_box[3] - reference_box[1]))
        ann["area"] = _number(float(area) * area_scale)
        ann.setdefault("iscrowd", 0)
        if "keypoints" in source:
            ann["keypoints"] = _moved_keypoints(source["keypoints"], pixel_map)
        segmentation = source.get("segmentation")
        if isinstance(segmentation, list) and segmentation:
            ann["segmentation"] = [
                [_number(v) for v in pixel_map.points(np.reshape(poly, (-1, 2))).ravel()]
                for poly in segmentation]
        elif segmentation:
            dropped_rle = True
        out.append(ann)
    return out, dropped_rle
