"""Array helpers shared by the image-simulation kernels (private)."""

from __future__ import annotations

import numpy as np


def align_leading(*arrays_and_cores):
    """Give arrays the same number of leading (loop) axes, for numpy broadcasting.

    ``xr.apply_ufunc`` hands a kernel arrays whose missing leading loop dims are left
    out; kernels that index along an axis (``take_along_axis``) need equal ``ndim``.
    Arguments alternate: array, number of its core (trailing) axes.
    """
    pairs = list(zip(arrays_and_cores[::2], arrays_and_cores[1::2], strict=True))
    lead = max(np.ndim(a) - core for a, core in pairs)
    return [np.reshape(a, (1,) * (lead - (np.ndim(a) - core)) + np.shape(a))
            for a, core in pairs]
