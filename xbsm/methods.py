"""Numerical method presets: small frozen objects of named knobs.

``method="pybsm"`` reproduces pyBSM 0.16.1's numerics (quirks included) so
that results compare number for number; ``"accurate"`` (the default) is
converged; ``"fast"`` trades a documented error for speed. Every knob can be
overridden one by one::

    xbsm.niirs(s, sc, method=xbsm.method("pybsm", frequency_samples=1601))
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import MappingProxyType

from .atmosphere.rules import INTERPOLATIONS
from .constants import CODATA, PYBSM_CODATA_2014, Constants
from .geometry import ELEVATIONS, FORMS
from .params import Choice, Instance, Spec, unknown_keyword

#: Allowed values of every text knob.
KNOB_CHOICES = MappingProxyType({
    "atmosphere_interpolation": INTERPOLATIONS,
    "band_edges": ("exact", "interpolated"),
    "edge_rule": ("uniform_trapezoid", "gauss_legendre", "gauss_kronrod"),
    "edge_otf": ("abs", "real"),
    "filter_otf": ("pybsm", "dtft"),
    "turbulence_path_rule": ("trapezoid", "gauss-legendre"),
    "elevation": ELEVATIONS,
    "geometry": FORMS,
    "defocus_otf": ("hopkins", "geometric", "gaussian", None),
})
#: Allowed range [low, high] of every whole-number knob. The upper limits guard memory:
#: each bounds an array the knob sizes (frequency nodes, path samples, wavelengths) well
#: above any converged setting (docs/speed_accuracy.md uses at most 16x "accurate").
KNOB_INTEGERS = MappingProxyType({
    "frequency_samples": (3, 100_001),
    "nodes_per_panel": (1, 200),
    "min_panels": (1, 10_000),
    "otf_wavelengths": (0, 10_000),
    "turbulence_path_samples": (2, 1_000_000),
    "max_frequency_nodes": (10, 100_000_000),
})
#: Allowed range of every real-valued knob: (low, high, low is inclusive).
KNOB_REALS = MappingProxyType({
    "panels_per_oscillation": (0.0, 64.0, False),
    "giqe4_noise_coefficient": (0.0, 1.0, True),
    "undersampling_threshold": (0.0, 100.0, True),
    "grading_ratio": (1.0, 64.0, False),
    "graded_frequency": (0.0, 1.0, False),
    "edge_error_tolerance": (0.0, 10.0, False),
})


#: The declared rule of every knob but ``name`` (a non-empty string), from the tables above.
KNOB_RULES = MappingProxyType({
    "constants": Instance(Constants, "a Constants object (xbsm.constants)"),
    **{name: Choice(choices) for name, choices in KNOB_CHOICES.items()},
    **{name: Spec("1", name, low, high, whole=True)
       for name, (low, high) in KNOB_INTEGERS.items()},
    **{name: Spec("1", name, low, high, low_open=not closed)
       for name, (low, high, closed) in KNOB_REALS.items()},
})


@dataclass(frozen=True)
class Method:
    """A complete set of numerical choices for one model run."""

    name: str
    constants: Constants
    """Physical constants (pyBSM hard-codes CODATA 2014)."""
    atmosphere_interpolation: str
    """Between database nodes: "linear" (pyBSM), "log-linear" (exponential fall-off, at
    fixed ground range), "same-elevation" (the attenuated components along lines of sight
    of the same elevation angle, between the two bracketing tables) or
    "optical-depth-cubic" (as "same-elevation", by a monotone cubic of the optical depth
    through one more table on each side) or "extinction-profile" (that cubic, its step
    matched straight down to the vertical extinction profile of the tables' nadir
    columns; docs/atmosphere.md)."""
    band_edges: str
    """Band edges on the 10 nm database grid: "exact" float comparison (pyBSM: a 2.91 um
    edge is dropped because 1e-6 * 2.91 > 2.91e-6 in floating point, and 0.503 um snaps
    to 0.51 um) or "interpolated" (the band is exactly [min, max]: the atmosphere is
    interpolated linearly in wavelength at edges that fall between database samples)."""
    edge_rule: str
    """Edge-response quadrature over frequency: "uniform_trapezoid" (pyBSM: trapezoid on
    the slice of its square grid, with a 1e-6 cycles/rad offset in 1/f and the sine) or
    "gauss_legendre" (composite Gauss-Legendre on uniform panels resolving every oscillation
    of the integrand) or "gauss_kronrod" (composite Gauss-Kronrod on those panels, graded
    toward f = 0 and one per lobe of the sensor's drift sinc, with the Kronrod - Gauss
    difference as its error estimate; see xbsm.quadrature)."""
    frequency_samples: int
    """uniform_trapezoid: points N of pyBSM's grid linspace(-1, 1, N) * D / lambda_min
    (pyBSM: 101, which leaves 50 samples from 0 to the cutoff)."""
    nodes_per_panel: int
    """gauss_legendre: nodes per panel; gauss_kronrod: nodes n of the embedded Gauss rule
    (the Kronrod rule has 2n + 1)."""
    panels_per_oscillation: float
    """gauss_legendre: panels per period of sin(2 pi f ifov x) at x = 3 px."""
    min_panels: int
    """gauss_legendre, gauss_kronrod: fewest uniform panels over [0, D / lambda_min]."""
    grading_ratio: float
    """gauss_kronrod: ratio of successive panels graded geometrically toward f = 0 from the
    first uniform panel."""
    graded_frequency: float
    """gauss_kronrod: where the grading stops, in cycles per pixel (4e-3: the last panel,
    [0, 4e-3], spans under four 1/e widths of the OTF of a Gaussian blur of RER 0.002)."""
    edge_error_tolerance: float
    """gauss_kronrod: flag ``blur_unresolved`` where the rule's own error estimate
    (the Kronrod - Gauss difference of each slice's RER and edge response, through the GIQE's
    sensitivity) exceeds this many NIIRS."""
    max_frequency_nodes: int
    """gauss_legendre: most nodes a sensor's edge-response rule may need before the call is
    refused (a pitch of 1 m instead of 1 um asks for millions and gigabytes); 200,000 is
    Q = lambda F / p down to about 1.5e-4 with the accurate knobs."""
    otf_wavelengths: int
    """Most wavelengths used for the polychromatic OTFs (aperture, turbulence, wavefront);
    0 = every database wavelength of the band. Fewer bins the spectral weights."""
    edge_otf: str
    """OTF part used for edge response: "abs" (pyBSM's |OTF|) or "real"."""
    giqe4_noise_coefficient: float
    """0.344 in Leachtenauer et al. 1997; pyBSM 0.16.1 uses 0.334."""
    filter_otf: str
    """Sharpening-kernel OTF: "pybsm" (|FFT| on 100^2, axes swapped, 100/99 stretch)
    or "dtft" (the exact discrete-space Fourier transform)."""
    turbulence_path_samples: int
    """Samples along the slant path for the r0 integral."""
    turbulence_path_rule: str
    """Path quadrature for r0: "trapezoid" (pyBSM) or "gauss-legendre"."""
    elevation: str
    """GIQE elevation angle: "look-down" (pyBSM: pi/2 minus the nadir angle at the sensor)
    or "target" (elevation of the sensor above the target's horizon, which is what
    projects the GSD onto the ground; smaller by the central angle)."""
    geometry: str
    """Curved-earth triangle: "law-of-cosines" (pyBSM: sqrt(a^2 + c^2 - 2ac cos) and arccos,
    which lose up to half their digits near nadir and on short paths) or "stable"
    (half-angle and atan2 forms, exact to rounding)."""
    undersampling_threshold: float
    """Flag ``undersampled_grid`` when a uniform edge rule has fewer samples than this per
    period of sin(2 pi f ifov x) at x = 3 px. 2.0 flags wherever the NIIRS error of the
    uniform rule may exceed 0.01 (at 2 samples or more the worst measured error over
    Q = 0.02-2 and N = 101-1601 is 0.006; docs/speed_accuracy.md); at N = 101 that is
    Q = lambda F# / p < 0.12."""
    defocus_otf: str | None
    """How the sensor's ``defocus_opd`` (W020) enters the aperture OTF
    (:func:`xbsm.otf.defocus.defocused_aperture_otf`): "hopkins" (Hopkins 1955, the exact
    defocused clear-pupil OTF), "geometric" (the blur disk 2 J1(pi d f) / (pi d f)) or
    "gaussian" (IBSM's approximation, w = 0.62 d); or None (pyBSM: its chain has no
    defocus term, so a non-zero ``defocus_opd`` is refused rather than ignored)."""

    def __post_init__(self):
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"method knob name must be a non-empty string; got {self.name!r}")
        for name, rule in KNOB_RULES.items():
            rule.check(f"method knob {name}", getattr(self, name))

    def overrides(self) -> dict:
        """Knobs that differ from the preset of the same name (every knob if none has it)."""
        base = PRESETS.get(self.name)
        if base is self:  # a preset itself (every model call's default): nothing to compare
            return {}
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name != "name" and (base is None or getattr(self, f.name) != getattr(
                    base, f.name))}

    def describe(self) -> str:
        """The method as text for a result's attributes, e.g. ``pybsm (frequency_samples=201)``."""
        changed = ", ".join(f"{k}={getattr(v, 'name', v)!s}" for k, v in self.overrides().items())
        return f"{self.name} ({changed})" if changed else self.name

    def edge_quadrature_knobs(self) -> dict:
        """The knobs of :func:`xbsm.quadrature.edge_quadrature`, as plain values."""
        return dict(rule=self.edge_rule, grid_size=self.frequency_samples,
                    nodes_per_panel=self.nodes_per_panel,
                    panels_per_oscillation=self.panels_per_oscillation,
                    min_panels=self.min_panels, name=self.name,
                    max_nodes=self.max_frequency_nodes, grading_ratio=self.grading_ratio,
                    graded_frequency=self.graded_frequency)

    def replace(self, **knobs) -> Method:
        """A copy with some knobs changed."""
        known = self.knobs()
        for name in knobs:
            if name not in known:
                raise unknown_keyword("method knob", name, known)
        return dataclasses.replace(self, **knobs)

    @classmethod
    def knobs(cls) -> list[str]:
        """Names of every knob."""
        return [f.name for f in dataclasses.fields(cls)]


_PRESETS: dict[str, Method] = {
    "pybsm": Method(
        name="pybsm",
        constants=PYBSM_CODATA_2014,
        atmosphere_interpolation="linear",
        band_edges="exact",
        edge_rule="uniform_trapezoid",
        frequency_samples=101,
        nodes_per_panel=10,
        panels_per_oscillation=1.0,
        min_panels=8,
        grading_ratio=4.0,
        graded_frequency=4e-3,
        edge_error_tolerance=1e-3,
        max_frequency_nodes=200_000,
        otf_wavelengths=0,
        edge_otf="abs",
        giqe4_noise_coefficient=0.334,
        filter_otf="pybsm",
        turbulence_path_samples=10000,
        turbulence_path_rule="trapezoid",
        elevation="look-down",
        geometry="law-of-cosines",
        undersampling_threshold=2.0,
        defocus_otf=None,
    ),
    "accurate": Method(
        name="accurate",
        constants=CODATA,
        # "extinction-profile": altitude leave-one-out (double spacing) median error of
        # the transmission 0.06 % against 0.08 % for "optical-depth-cubic", 0.36 % for
        # "same-elevation" and 0.9 % for "log-linear", 95th percentile 1.9 % against 2.8 %,
        # 6.6 % and 13 %; the only rule with all three attenuated components at most 3 %
        # (recipes/evidence/atmosphere_leave_one_out.py)
        atmosphere_interpolation="extinction-profile",
        band_edges="interpolated",
        edge_rule="gauss_kronrod",
        frequency_samples=101,
        # Gauss 7 / Kronrod 15 (QUADPACK's qk15), not 5 / 11: on 400 random systems against
        # an independent dense-trapezoid reference (recipes/evidence/preset_error.py) 5 / 11
        # left unflagged errors to 3.7e-4 NIIRS (GIQE 5) on diffraction-limited systems
        # (Q 2.6-68, obscured, the polychromatic aperture's kinks inside 4 panels); 7 / 15
        # brings the eight worst to 4.7e-5 for 1.11x the Olson sweep's time
        nodes_per_panel=7,
        panels_per_oscillation=1.0,
        min_panels=4,
        grading_ratio=4.0,
        graded_frequency=4e-3,
        edge_error_tolerance=1e-3,
        max_frequency_nodes=200_000,
        otf_wavelengths=0,
        edge_otf="real",
        giqe4_noise_coefficient=0.344,
        filter_otf="dtft",
        turbulence_path_samples=64,
        turbulence_path_rule="gauss-legendre",
        elevation="target",
        geometry="stable",
        undersampling_threshold=2.0,
        defocus_otf="hopkins",
    ),
}
_PRESETS["fast"] = _PRESETS["accurate"].replace(
    # otf_wavelengths 24, not 8: on 240 random systems (recipes/evidence/archive/preset_tuning.py)
    # 8 bins cost up to 7.3e-3 NIIRS where RER >= 0.2 and 24 bins 7.1e-4, at 1.34x the
    # speed of accurate
    name="fast", nodes_per_panel=4, otf_wavelengths=24, turbulence_path_samples=16,
    edge_error_tolerance=1e-2
)
#: The presets by name: the one table of method numbers (read-only).
PRESETS = MappingProxyType(_PRESETS)


def method(preset: str | Method = "accurate", /, **knobs) -> Method:
    """Return a method preset by name, with any knobs overridden.

    Parameters
    ----------
    preset : str or Method
        "accurate" (default), "fast" or "pybsm", or a Method to modify.
    **knobs
        Knob overrides, e.g. ``frequency_samples=1601``.

    Returns
    -------
    Method
    """
    if isinstance(preset, Method):
        base = preset
    elif isinstance(preset, str) and preset in PRESETS:
        base = PRESETS[preset]
    else:
        raise ValueError(f"method must be one of {sorted(PRESETS)} or a Method; got {preset!r}")
    return base.replace(**knobs) if knobs else base
