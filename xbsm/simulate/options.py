"""Numerical choices of an image simulation: small frozen presets of named knobs.

``xbsm.simulate_image(..., method="accurate")`` (the default) is converged and
shift-free; ``method="pybsm"`` reproduces pyBSM 0.16.1's noiseless image
simulation, quirks included (docs/quirks.md, "Image simulation"). The model
knobs (radiometry, OTFs) come from :func:`xbsm.method`; the image knobs here
sit next to them in an :class:`ImageMethod`::

    xbsm.simulate.image_method("pybsm", convolution="pad_fft", resampling="pil")
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import MappingProxyType

from ..methods import Method
from ..methods import method as model_method
from ..params import Choice, Instance, unknown_keyword

__all__ = ["ImageMethod", "image_method"]

#: Allowed values of every image knob.
IMAGE_KNOBS = MappingProxyType({
    "psf": ("exact", "pybsm"),
    "convolution": ("fft", "fft_zero", "pad_fft", "correlate"),
    "resampling": ("cubic", "area", "pil", "zoom", "none"),
    "basis": ("pixel-angle", "ground-angle"),
    "reflectance": ("percentile", "minmax", "identity"),
    "viewing": ("curved", "pybsm"),
    "filter_stage": ("digital", "optical"),
    "integration_time": ("effective", "maximum"),
    "quantization": ("round", "pybsm"),
})

#: The declared rule of every image knob but ``model`` (params words).
IMAGE_RULES = MappingProxyType({name: Choice(choices) for name, choices in IMAGE_KNOBS.items()})
_MODEL = Instance(Method, "a Method (xbsm.method(...))")

#: The OTF components ``components=`` may choose (``"defocus"`` needs ``defocus_radius``).
COMPONENTS = ("aperture", "turbulence", "detector", "jitter", "drift", "wavefront", "filter",
              "defocus")

#: pyBSM 0.16.1's ``ImageSimulator`` subclasses as ``simulate_image`` keywords (with
#: ``method="pybsm"`` and ``reflectance="minmax"``: their ``use_reflectance=True`` mode).
PYBSM_SIMULATORS = MappingProxyType({
    "SystemOTFSimulator": MappingProxyType(dict(
        components=None, convolution="pad_fft", resampling="pil", basis="pixel-angle")),
    "JitterSimulator": MappingProxyType(dict(
        components=("jitter",), convolution="correlate", resampling="pil",
        basis="pixel-angle")),
    "CircularApertureSimulator": MappingProxyType(dict(
        components=("aperture",), convolution="correlate", resampling="pil",
        basis="pixel-angle")),
    "DetectorSimulator": MappingProxyType(dict(
        components=("detector",), convolution="correlate", resampling="pil",
        basis="pixel-angle")),
    "DefocusSimulator": MappingProxyType(dict(
        components=("defocus",), convolution="fft_zero", resampling="pil",
        basis="pixel-angle")),
    "TurbulenceApertureSimulator": MappingProxyType(dict(
        components=("turbulence",), convolution="correlate", resampling="pil",
        basis="ground-angle")),
})


@dataclass(frozen=True)
class ImageMethod:
    """A complete set of numerical choices for one image simulation."""

    model: Method
    """Radiometry and OTF knobs (:func:`xbsm.method`)."""
    psf: str
    """Blur kernel at the reference image's sampling: "exact" (the OTF sampled on the
    image's own frequency grid, odd size, inverse FFT with ``ifftshift``: centred, sums
    to one, no crop) or "pybsm" (pyBSM's 1501 x 1501 grid to the optics cutoff,
    ``fftshift`` before the inverse FFT, linear ``zoom`` to the image sampling, crop to
    95 % of the energy: often an even size)."""
    convolution: str
    """"fft": FFT convolution of the reflect-padded image, the kernel centred by its
    coordinates; "fft_zero": zero padding (pyBSM ``fftconvolve``, dark borders);
    "pad_fft": pyBSM's ``pad_fftconvolve``; "correlate": ``scipy.ndimage.correlate`` in
    mirror mode (pyBSM's ``simulate_image`` and ``oaconvolve``)."""
    resampling: str
    """To the camera's pixels: "cubic" (Keys cubic interpolation at the output pixel
    centres, reflect at the borders: the detector footprint is already in the blur),
    "area" (mean over each output pixel's footprint), "pil" (Pillow's antialiased
    bilinear in float32, pyBSM's ``ImageSimulator``), "zoom" (pyBSM's ``resample_2D``:
    ``scipy.ndimage.zoom`` order 1, zero outside, zoom factors of x and y swapped) or
    "none" (the output keeps the reference sampling)."""
    basis: str
    """Output sample angle: "pixel-angle" (the pitch over the focal length) or
    "ground-angle" (the reference GSD over the altitude, pyBSM's turbulence simulator)."""
    reflectance: str
    """Pixel values to reflectance: "percentile" (pyBSM ``RefImage``: the 0.2 and 99.8
    percentiles to ``reflectance_range``), "minmax" (each image's min and max, pyBSM's
    ``use_reflectance``) or "identity" (the image is reflectance)."""
    viewing: str
    """"curved": the spherical-earth slant range of the NIIRS chain and each axis's own
    pitch; "pybsm": pyBSM's image-simulation geometry, the flat-earth
    ``sqrt(altitude^2 + ground_range^2)`` and the mean of the two pitches."""
    filter_stage: str
    """Post-processing kernel: "digital" (applied to the camera's sampled, noisy image)
    or "optical" (its OTF in the blur, before sampling and noise: pyBSM)."""
    integration_time: str
    """For drift and turbulence OTFs: "effective" (after the well-fill limit, as the
    photoelectrons) or "maximum" (the sensor's, as pyBSM's ``simulate_image``)."""
    quantization: str
    """"round": noise is shot + read + other, counts rounded by the ADC; "pybsm": the
    quantization noise is added as Gaussian noise too and counts are floored."""

    def __post_init__(self):
        _MODEL.check("image method knob model", self.model)
        for name, rule in IMAGE_RULES.items():
            rule.check(name, getattr(self, name))

    def replace(self, **knobs) -> ImageMethod:
        """A copy with some knobs changed (``None`` keeps a knob)."""
        known = [f.name for f in dataclasses.fields(self)]
        for name in knobs:
            if name not in known:
                raise unknown_keyword("image method knob", name, known)
        return dataclasses.replace(self, **{k: v for k, v in knobs.items() if v is not None})

    def describe(self) -> str:
        """The knobs as text for a result's attributes."""
        preset = image_presets().get(self.model.name)
        changed = [f"{f.name}={getattr(self, f.name)}" for f in dataclasses.fields(self)
                   if f.name != "model" and (preset is None or getattr(self, f.name)
                                             != getattr(preset, f.name))]
        model = self.model.describe()
        return f"{model}; image: {', '.join(changed)}" if changed else model


_ACCURATE = dict(psf="exact", convolution="fft", resampling="cubic", basis="pixel-angle",
                 reflectance="percentile", viewing="curved", filter_stage="digital",
                 integration_time="effective", quantization="round")
_PYBSM = dict(psf="pybsm", convolution="correlate", resampling="zoom", basis="pixel-angle",
              reflectance="percentile", viewing="pybsm", filter_stage="optical",
              integration_time="maximum", quantization="pybsm")


def image_presets() -> dict[str, ImageMethod]:
    """The image presets by model preset name: "accurate", "fast" and "pybsm"."""
    return {name: ImageMethod(model=model_method(name), **(_PYBSM if name == "pybsm"
                                                         else _ACCURATE))
            for name in ("accurate", "fast", "pybsm")}


def image_method(preset="accurate", /, **knobs) -> ImageMethod:
    """Return an image-simulation method: a preset with knobs overridden.

    Parameters
    ----------
    preset : str, Method or ImageMethod
        "accurate" (default), "fast" or "pybsm"; a :class:`xbsm.Method` (its image knobs
        are those of the preset of its name, else "accurate"'s); or an ImageMethod.
    **knobs
        Image knobs (:data:`IMAGE_KNOBS`) to override; ``None`` keeps the preset's.

    Returns
    -------
    ImageMethod
    """
    if isinstance(preset, ImageMethod):
        return preset.replace(**knobs)
    model = model_method(preset)
    base = _PYBSM if model.name == "pybsm" else _ACCURATE
    return ImageMethod(model=model, **base).replace(**knobs)
