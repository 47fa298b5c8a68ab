"""Where the edge is: ISO 12233's windowed centroids of the row derivative and a line fit.

Plain numpy on one 2-D image whose edge is near vertical (x across the edge).
"""

from __future__ import annotations

import numpy as np

MIN_EDGE_ANGLE = 1.0
"""Smallest angle between the edge and its nearer pixel axis. [degree]"""

MAX_EDGE_ANGLE = 40.0
"""Largest angle between the edge and its nearer pixel axis (45 is degenerate). [degree]"""


def hamming(length, centre):
    """Hamming windows peaked at ``centre`` reaching the far end of ``length`` (ISO)."""
    centre = np.asarray(centre, dtype=float)[..., None]
    half = np.maximum(np.maximum(centre, length - 1 - centre), 1.0)
    return 0.54 + 0.46 * np.cos(np.pi * (np.arange(length) - centre) / half)


def orient(img):
    """The image with its edge near vertical, and whether it was already."""
    across_x = np.square(np.diff(img, axis=1)).sum()
    across_y = np.square(np.diff(img, axis=0)).sum()
    vertical = bool(across_x >= across_y)
    return (img if vertical else img.T), vertical


def polarity(img):
    """+1 for a dark-to-bright edge along x, -1 for bright-to-dark; error if none."""
    k = max(2, img.shape[1] // 8)
    step = img[:, -k:].mean() - img[:, :k].mean()
    diffs = np.diff(img, axis=1)
    noise = 1.4826 * np.median(np.abs(diffs - np.median(diffs))) / np.sqrt(2.0)
    if not abs(step) > 2.0 * noise:
        raise ValueError(f"no edge found: the step between the two sides ({step:.3g}) is not "
                         f"larger than twice the pixel noise ({noise:.3g}); the region must "
                         "hold one straight edge between two flat areas")
    return np.sign(step)


def row_centroids(deriv, centre):
    """Windowed centroid of each row's derivative, in pixel coordinates, and its validity."""
    weighted = deriv * hamming(deriv.shape[1], centre)
    total = weighted.sum(axis=1)
    valid = total > 0
    moment = weighted @ (np.arange(deriv.shape[1]) + 0.5)  # differences sit between pixels
    return np.where(valid, moment / np.where(valid, total, 1.0), np.nan), valid


def fit_edge_line(img, sign):
    """Edge position per row, ``x = intercept + slope * y``: ISO's two passes."""
    deriv = sign * np.diff(img, axis=1)
    rows = np.arange(img.shape[0])
    centre = np.full(img.shape[0], (deriv.shape[1] - 1) / 2.0)
    for _ in range(2):
        location, valid = row_centroids(deriv, centre)
        if valid.sum() < max(3, img.shape[0] // 2):
            raise ValueError("no edge found: fewer than half of the rows have a derivative "
                             "of the edge's sign; the region must hold one straight edge")
        slope, intercept = np.polyfit(rows[valid], location[valid], 1)
        centre = intercept + slope * rows - 0.5
    return intercept, slope


def check_geometry(img, intercept, slope):
    """Raise unless the angle is in range, the rows span a phase cycle, the edge is inside."""
    angle = np.degrees(np.arctan(slope))
    if not MIN_EDGE_ANGLE <= abs(angle) <= MAX_EDGE_ANGLE:
        raise ValueError(f"edge angle {angle:.3f} degrees is outside the allowed range: "
                         f"{MIN_EDGE_ANGLE:g} to {MAX_EDGE_ANGLE:g} degrees off the nearer "
                         "pixel axis (2 to 10 degrees is best)")
    rows, cols = img.shape
    if rows * abs(slope) < 1.0:
        raise ValueError(f"the region has {rows} rows along an edge at {angle:.2f} degrees: "
                         f"too few to cover one sub-pixel phase cycle; at least "
                         f"{int(np.ceil(1.0 / abs(slope)))} are needed")
    ends = intercept + slope * np.array([0.0, rows - 1.0])
    if ends.min() < 2.0 or ends.max() > cols - 3.0:
        raise ValueError("the fitted edge leaves the region: it must stay at least 2 pixels "
                         f"inside it on every row; it runs from x = {ends[0]:.1f} to "
                         f"{ends[1]:.1f} in a region {cols} pixels wide")
    return angle


def phase_rows(rows, slope):
    """The central rows holding a whole number of edge phase cycles (ISO 12233)."""
    used = min(rows, int(round(np.floor(rows * abs(slope)) / abs(slope))))
    start = (rows - used) // 2
    return slice(start, start + used)

