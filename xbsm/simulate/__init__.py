"""Image simulation (paper Sec. 4, Eq. 5-6): a reference image seen by a modelled camera.

Modules in data-flow order: :mod:`~xbsm.simulate.reflectance` (pixel values to
reflectance), :mod:`~xbsm.simulate.photoelectrons` (the radiometry),
:mod:`~xbsm.simulate.sampling` (sample angles and the pixel map),
:mod:`~xbsm.simulate.psf` / :mod:`~xbsm.simulate.pybsm_psf` (the blur kernel),
:mod:`~xbsm.simulate.convolve`, :mod:`~xbsm.simulate.resample`,
:mod:`~xbsm.simulate.camera` (noise, digital filter, ADC),
:mod:`~xbsm.simulate.inverse` (back to reflectance and pixels, Wiener filter,
8-bit stretch), :mod:`~xbsm.simulate.labels` (points and boxes into the output);
:func:`simulate_image` runs them all.
"""

from .camera import add_noise, digital_filter, digitize
from .convolve import blur
from .image import simulate_image, simulate_images
from .inverse import (
    photoelectrons_to_pixels,
    photoelectrons_to_reflectance,
    stretch_contrast_8bit,
    wiener_filter,
)
from .labels import transform_boxes, transform_points
from .options import COMPONENTS, PYBSM_SIMULATORS, ImageMethod, image_method
from .photoelectrons import reflectance_to_photoelectrons
from .reflectance import image_to_reflectance
from .resample import resample, resampling_taps

__all__ = [
    "COMPONENTS",
    "PYBSM_SIMULATORS",
    "ImageMethod",
    "add_noise",
    "blur",
    "digital_filter",
    "digitize",
    "image_method",
    "image_to_reflectance",
    "photoelectrons_to_pixels",
    "photoelectrons_to_reflectance",
    "reflectance_to_photoelectrons",
    "resample",
    "resampling_taps",
    "simulate_image",
    "simulate_images",
    "stretch_contrast_8bit",
    "transform_boxes",
    "transform_points",
    "wiener_filter",
]
