r"""The observer: the eye's contrast threshold, its optics and the visual channel.

Plain numpy functions (they also take DataArrays: pure elementwise arithmetic), one
quantity each, for the target-acquisition model of :mod:`xbsm.metrics.ttp`.

Two eye models, by name (:data:`EYE_MODELS`):

- ``"vollmerhausen"`` (default): the eye contrast threshold function (CTF) the US Army's
  target-acquisition models use for the observer (Vollmerhausen, "Representing the
  observer in electro-optical target acquisition models", Opt. Express 17(20), 17253,
  2009; the NVThermIP / NV-IPM observer): Barten's empirical closed-form CTF with its
  dependence on luminance and field size (:func:`ctf_vollmerhausen`), for ``eyes``
  eyes, and a noise term with calibration constant :data:`EYE_NOISE_CONSTANT` added by
  :mod:`xbsm.metrics.ttp`.
- ``"barten"``: Barten's physical contrast sensitivity model (:func:`csf_barten`):
  optical MTF of the eye, photon noise and neural noise, lateral inhibition, spatial
  and temporal integration (Barten, *Contrast Sensitivity of the Human Eye and its
  Effects on Image Quality*, SPIE Press, 1999, chapter 3; the same model as a
  formula in Barten, Proc. SPIE 5294, 2003).

The two are different models, not a model and its fit: at 1-16 cycles/deg, 10-1000
cd/m^2 and 2-40 deg the closed form's sensitivity is 0.55-1.05 times that of Barten's
own simplified formula of the physical model (Proc. SPIE 5294, 2003), which the
physical model here follows within 2 % at a 40 deg field (see below).

Sources and what was checked (``tests/metrics/test_published_values.py``; the table
in ``docs/target_acquisition.md``): the physical model's constants (k = 3, T = 0.1 s,
X_max = 12 deg, N_max = 15, eta = 0.03, p = 1.24e6, Phi0 = 3e-8 s deg^2, u0 = 7
cycles/deg, sigma0 = 0.5 arcmin, C_ab = 0.08 arcmin/mm, the log10 pupil formula) are
the ones of the open implementation of Barten's original model in castleCSF
(``gfxdisp/castleCSF``, ``matlab/CSF_Barten_Original.m``); the model reproduces the
unit-test values of ``colour.contrast.contrast_sensitivity_function_Barten1999``
(colour-science) to 1e-12 and Barten's 2003 simplified formula within 2 % at a 40 deg
field. The closed form's constants (540, 0.7, 12, 3, 0.3, 100, 0.15, 0.06) are those
of MITRE's open NV-IPM observer (``IRwhaleDetect.m``, Apache-2.0); the pages of the
2009 paper and of Barten's book with the equations could not be read with the
project's search tools.
"""

from __future__ import annotations

import math

import numpy as np

EYE_MODELS = ("vollmerhausen", "barten")
"""Names of the eye models: the closed-form CTF of the target-acquisition models, or
Barten's physical model."""

EYE_NOISE_CONSTANT = 169.6
"""Calibration constant alpha of the eye's noise term in the system CTF, [Hz^0.5]
(Vollmerhausen, Jacobs & Driggers, "New metric for predicting target acquisition
performance", Opt. Eng. 43(11), 2806, 2004; NVThermIP)."""

PHOTOPIC_LUMINANCE = (3.0, 1.0e4)
"""Luminances [cd/m^2] over which the eye models are stated: photopic vision (Barten
1999, ch. 3: "the application of the model is restricted to photopic vision"; cones
dominate above about 3 cd/m^2)."""

FOOTLAMBERT = 3.4262591
"""One foot-lambert in cd/m^2 (1 / pi cd/ft^2)."""

CHANNEL_WIDTH = 2.2
"""Width constant of the visual channel exp(-2.2 ln^2(f / f0)) (Vollmerhausen &
Jacobs, NVESD TR AMSEL-NV-TR-230, 2004)."""

# Barten 1999 ch. 3 / Barten 2003 constants of the physical model
_K = 3.0            # signal-to-noise ratio at threshold
_T = 0.1            # integration time of the eye [s]
_X_MAX = 12.0       # largest angular integration area [deg]
_N_MAX = 15.0       # largest number of cycles integrated [1]
_ETA = 0.03         # quantum efficiency of the eye [1]
_P = 1.24e6         # photon conversion factor [photons s-1 deg-2 Td-1]
_PHI0 = 3.0e-8      # spectral density of neural noise [s deg^2]
_U0 = 7.0           # spatial frequency above which lateral inhibition stops [cycles/deg]
_SIGMA0 = 0.5       # eye optics spread without pupil aberration [arcmin]
_C_AB = 0.08        # growth of the spread with the pupil diameter [arcmin/mm]


def ctf_vollmerhausen(frequency, luminance, field_size, eyes=2):
    r"""Contrast threshold of the eye, closed form, against frequency at the eye.

    Parameters
    ----------
    frequency : array_like
        Spatial frequency at the eye, in (0, inf). [cycles/deg]
    luminance : array_like
        Mean luminance of the display, in (0, inf). [cd/m^2]
    field_size : array_like
        Angular size of the field (square root of its angular area), in (0, inf). [deg]
    eyes : {1, 2}
        Eyes viewing (2: binocular, for which the fit was made). [1]

    Returns
    -------
    array_like
        Threshold modulation; inf at frequency 0. [1]

    Notes
    -----
    .. math::

        \mathrm{CTF}(f) = \frac{\sqrt{2 / n_e}}
        {a\,f\,e^{-b f}\sqrt{1 + 0.06\,e^{b f}}},\quad
        a = \frac{540\,(1 + 0.7/L)^{-0.2}}{1 + 12 / \left(w (1 + f/3)^2\right)},\quad
        b = 0.3\,(1 + 100/L)^{0.15}

    Barten's empirical closed form (Barten 1999, Eq. 3.26), as the NVESD observer uses
    it (Vollmerhausen 2009; constants as in MITRE's ``IRwhaleDetect.m``).
    """
    a = 540.0 * (1.0 + 0.7 / luminance) ** -0.2 / (
        1.0 + 12.0 / (field_size * (1.0 + frequency / 3.0) ** 2))
    b = 0.3 * (1.0 + 100.0 / luminance) ** 0.15
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        sensitivity = a * frequency * np.exp(-b * frequency) * np.sqrt(
            1.0 + 0.06 * np.exp(b * frequency))
        return np.sqrt(2.0 / eyes) / sensitivity


def pupil_diameter(luminance, field_size):
    r"""Diameter of the eye's pupil (Barten's formula) [mm].

    .. math:: d = 5 - 3 \tanh\left(0.4 \log_{10}\frac{L\,X_0^2}{40^2}\right)

    with L [cd/m^2] and the field size X0 [deg] (Barten 1999 ch. 3; Barten 2003).
    """
    return 5.0 - 3.0 * np.tanh(0.4 * np.log10(luminance * field_size ** 2 / 40.0 ** 2))


def eye_mtf(frequency, luminance, field_size=10.0):
    r"""Optical MTF of the eye against frequency at the eye (Barten) [1].

    .. math:: M_{opt}(f) = e^{-2\pi^2\sigma^2 f^2},\quad
        \sigma = \sqrt{\sigma_0^2 + (C_{ab}\,d)^2}

    sigma0 = 0.5 arcmin, C_ab = 0.08 arcmin/mm, d from :func:`pupil_diameter`;
    ``frequency`` in cycles/deg, ``luminance`` in cd/m^2, ``field_size`` in deg.
    """
    sigma = np.sqrt(_SIGMA0 ** 2 + (_C_AB * pupil_diameter(luminance, field_size)) ** 2) / 60.0
    return np.exp(-2.0 * math.pi ** 2 * sigma ** 2 * frequency ** 2)


def retinal_illuminance(luminance, pupil):
    r"""Retinal illuminance with the Stiles-Crawford correction (Barten) [Td].

    .. math:: E = \frac{\pi d^2}{4} L \left(1 - (d/9.7)^2 + (d/12.4)^4\right)

    ``luminance`` L [cd/m^2], ``pupil`` diameter d [mm] (:func:`pupil_diameter`).
    """
    return math.pi * pupil ** 2 / 4.0 * luminance * (1.0 - (pupil / 9.7) ** 2
                                                       + (pupil / 12.4) ** 4)


def barten_sensitivity(frequency, sigma, retinal, field_size, photon_conversion=_P):
    r"""Barten's physical contrast sensitivity from its physical inputs [1].

    Parameters
    ----------
    frequency : array_like
        Spatial frequency at the eye, in (0, inf). [cycles/deg]
    sigma : array_like
        Standard deviation of the eye's line-spread function, in [0, inf). [deg]
    retinal : array_like
        Retinal illuminance E, in (0, inf). [Td]
    field_size : array_like
        Angular size X0 of the (square) field, in (0, inf). [deg]
    photon_conversion : float
        Photon conversion factor p, in (0, inf); 1.24e6 for Barten's standard light.
        [photons s-1 deg-2 Td-1]

    Returns
    -------
    array_like
        Sensitivity, one over the threshold modulation (binocular). [1]

    Notes
    -----
    .. math::

        S(f) = \frac{e^{-2\pi^2\sigma^2 f^2} / k}{\sqrt{\frac{2}{T}
        \left(\frac{1}{X_0^2} + \frac{1}{X_{max}^2} + \frac{f^2}{N_{max}^2}\right)
        \left(\frac{1}{\eta\,p\,E} + \frac{\Phi_0}{1 - e^{-(f/u_0)^2}}\right)}}

    k = 3, T = 0.1 s, X_max = 12 deg, N_max = 15, eta = 0.03, Phi0 = 3e-8 s deg^2,
    u0 = 7 cycles/deg (Barten 1999, ch. 3; Barten 2003). :func:`csf_barten` gives
    sigma and E from the luminance and the field.
    """
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        integration = (2.0 / _T) * (1.0 / field_size ** 2 + 1.0 / _X_MAX ** 2
                                    + frequency ** 2 / _N_MAX ** 2)
        noise = (1.0 / (_ETA * photon_conversion * retinal)
                 + _PHI0 / (1.0 - np.exp(-(frequency / _U0) ** 2)))
        optics = np.exp(-2.0 * math.pi ** 2 * sigma ** 2 * frequency ** 2)
        return optics / _K / np.sqrt(integration * noise)


def csf_barten(frequency, luminance, field_size):
    r"""Contrast sensitivity of the eye, Barten's physical model, against frequency [1].

    Parameters
    ----------
    frequency : array_like
        Spatial frequency at the eye, in (0, inf). [cycles/deg]
    luminance : array_like
        Mean luminance, in (0, inf). [cd/m^2]
    field_size : array_like
        Angular size X0 of the (square) field, in (0, inf). [deg]

    Returns
    -------
    array_like
        Sensitivity, one over the threshold modulation (binocular). [1]

    Notes
    -----
    :func:`barten_sensitivity` with the pupil d of :func:`pupil_diameter`, the
    line-spread sigma = sqrt(sigma0^2 + (C_ab d)^2) of :func:`eye_mtf` (sigma0 = 0.5
    arcmin, C_ab = 0.08 arcmin/mm), the retinal illuminance of
    :func:`retinal_illuminance` and p = 1.24e6 photons/(s deg^2 Td) (Barten 1999,
    ch. 3; Barten 2003).
    """
    d = pupil_diameter(luminance, field_size)
    sigma = np.sqrt(_SIGMA0 ** 2 + (_C_AB * d) ** 2) / 60.0
    return barten_sensitivity(frequency, sigma, retinal_illuminance(luminance, d), field_size)


def eye_ctf(frequency, luminance, field_size, eye="vollmerhausen", eyes=2):
    """Contrast threshold of the eye by model name (:data:`EYE_MODELS`) [1].

    ``frequency`` at the eye [cycles/deg], ``luminance`` [cd/m^2], ``field_size`` [deg];
    ``eyes`` scales the binocular threshold by sqrt(2 / eyes) for either model.
    """
    if eye == "vollmerhausen":
        return ctf_vollmerhausen(frequency, luminance, field_size, eyes)
    if eye == "barten":
        with np.errstate(divide="ignore"):
            return np.sqrt(2.0 / eyes) / csf_barten(frequency, luminance, field_size)
    raise ValueError(f"eye must be one of {', '.join(map(repr, EYE_MODELS))}; got {eye!r}")


def visual_channel(frequency, centre):
    r"""Gain of the visual channel centred on ``centre`` at ``frequency`` [1].

    .. math:: B(f) = \exp\left(-2.2\,\ln^2\frac{f}{f_0}\right)

    The bandpass through which the eye sees noise when it looks for a sine wave of
    frequency f0 (Vollmerhausen & Jacobs 2004); 0 at f = 0.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.log(frequency / centre)
        return np.where(frequency > 0.0, np.exp(-CHANNEL_WIDTH * ratio * ratio), 0.0)
