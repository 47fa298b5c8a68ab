"""xbsm.target_acquisition: P(task) against range, properties, flags, bad input, sweeps,
and the inverse questions through xbsm.study."""

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

import xbsm
from xbsm import flags as fl

CAMERA = {"focal_length": 0.2, "pixel_pitch_x": 15e-6, "wavelength_min": 3e-6,
          "wavelength_max": 5e-6, "quantum_efficiency": 0.8, "optics_transmission": 0.8,
          "integration_time": 2e-3, "read_noise": 100.0, "max_well": 1.1e7,
          "bit_depth": 14.0, "dark_current": 1e4, "cold_shield_temperature": 77.0,
          "cold_filter_temperature": 77.0}
"""The MWIR camera of docs/infrared.md (f/4, 15 um, 3-5 um)."""


def mwir(aperture_diameter=0.05, **changes):
    return xbsm.sensor(aperture_diameter=aperture_diameter, **{**CAMERA, **changes})


def path(ground_range, **changes):
    return xbsm.scenario(altitude=10.0, ground_range=ground_range, visibility=23.0,
                         background_temperature=290.0, **changes)


def vehicle(contrast=2.0):
    return xbsm.radiometry.target_set(2.5, thermal_contrast=contrast, names=["vehicle"])


RANGES = xr.DataArray(np.linspace(500.0, 5000.0, 10), dims="ground_range")  # in the database


@pytest.fixture(scope="module")
def sweep():
    return xbsm.target_acquisition(mwir(), path(RANGES), vehicle())


def test_probability_falls_with_range_and_with_the_task_difficulty(sweep):
    p = sweep.probability.sel(target="vehicle")
    assert list(p.task.values) == ["detect", "recognize", "identify"]
    assert bool((p.diff("ground_range") <= 0).all())
    assert bool((p.sel(task="detect") >= p.sel(task="recognize")).all())
    assert bool((p.sel(task="recognize") >= p.sel(task="identify")).all())
    assert bool(((p >= 0) & (p <= 1)).all())
    assert p.attrs["units"] == "1" and sweep.ttp.attrs["units"] == "cycles/rad"
    assert sweep.ctf_system.dims[-2:] == ("orientation", "frequency")


def test_cycles_on_target_is_ttp_times_size_over_range(sweep):
    v = sweep.ttp * 2.5 / sweep.slant_range
    xr.testing.assert_allclose(sweep.cycles_on_target, v.transpose(*sweep.cycles_on_target.dims))
    expected = xbsm.metrics.ttp.task_probability(sweep.cycles_on_target, 13.0)
    np.testing.assert_allclose(sweep.probability.sel(task="identify"), expected, rtol=1e-12)


@settings(max_examples=6, deadline=None)
@given(aperture=st.floats(0.02, 0.09), factor=st.floats(1.2, 2.0),
       ground_range=st.floats(800.0, 5000.0))
def test_identification_rises_with_aperture(aperture, factor, ground_range):
    sizes = xr.DataArray([aperture, aperture * factor], dims="aperture_diameter")
    p = xbsm.target_acquisition(mwir(sizes), path(ground_range), vehicle()).probability
    p = p.sel(task="identify").squeeze()
    assert float(p[1]) >= float(p[0])


@settings(max_examples=6, deadline=None)
@given(contrast=st.floats(0.2, 3.0), factor=st.floats(1.3, 3.0),
       ground_range=st.floats(800.0, 5000.0))
def test_identification_rises_with_snr(contrast, factor, ground_range):
    targets = xbsm.radiometry.target_set(2.5, thermal_contrast=[contrast, contrast * factor])
    r = xbsm.target_acquisition(mwir(), path(ground_range), targets)
    snr = r.snr_frame.squeeze()
    p = r.probability.sel(task="identify").squeeze()
    assert float(snr[1]) > float(snr[0])
    assert float(p[1]) >= float(p[0])
    assert bool(((r.probability >= 0) & (r.probability <= 1)).all())


def test_an_undersampled_camera_is_worse_with_aliasing_as_noise():
    # f/1.3 optics behind 15 um pixels: strong spurious response
    sensor = mwir(0.15)
    on = xbsm.target_acquisition(sensor, path(3000.0), vehicle())
    off = xbsm.target_acquisition(sensor, path(3000.0), vehicle(), aliasing=False)
    assert float(on.ttp.squeeze()) < float(off.ttp.squeeze())


def test_outside_the_photopic_range_is_flagged_and_inside_is_not(sweep):
    assert not bool(fl.has_flag(sweep.flags, "outside_acquisition_model").any())
    dim = xbsm.target_acquisition(mwir(), path(2000.0), vehicle(), display_luminance=1.0)
    assert bool(fl.has_flag(dim.flags, "outside_acquisition_model").all())
    assert bool(fl.is_outside_calibration(dim.flags).all())
    assert fl.flag("outside_acquisition_model") == 2 ** 28
    p = dim.probability
    assert bool(((p >= 0) & (p <= 1)).all())


def test_beyond_the_database_is_nan_and_flagged_invalid():
    r = xbsm.target_acquisition(mwir(), path(20000.0), vehicle())
    assert bool(r.probability.isnull().all())
    assert bool(fl.is_invalid(r.flags).all())


def test_johnson_criterion_counts_cycles_at_the_limiting_frequency():
    r = xbsm.target_acquisition(mwir(), path(2000.0), vehicle(), criterion="johnson")
    n = r.limiting_frequency * 2.5 / r.slant_range
    np.testing.assert_allclose(r.cycles_on_target, n.transpose(*r.cycles_on_target.dims))
    np.testing.assert_allclose(r.probability.sel(task="identify"),
                               xbsm.metrics.ttp.johnson_probability(r.cycles_on_target, 6.4))


def test_barten_eye_and_own_v50():
    r = xbsm.target_acquisition(mwir(), path(2000.0), vehicle(), eye="barten",
                                v50={"identify": 20.0})
    assert list(r.task.values) == ["identify"]
    assert 0.0 < float(r.probability.squeeze()) < 1.0


def test_dask_stays_lazy_and_equals_eager(sweep, no_compute):
    lazy = xbsm.target_acquisition(mwir(xr.DataArray([0.05], dims="a").chunk()),
                                   path(RANGES), vehicle())
    assert lazy.probability.chunks is not None


def test_dask_result_equals_eager(sweep):
    lazy = xbsm.target_acquisition(mwir(), path(RANGES.chunk({"ground_range": 4})), vehicle())
    xr.testing.assert_allclose(lazy.probability.compute(), sweep.probability)


@pytest.mark.parametrize(("changes", "message"), [
    ({"display_luminance": -1.0}, r"display_luminance must be a real number in \(0, inf\)"),
    ({"displayed_contrast": 1.5}, r"displayed_contrast must be a real number in \(0, 1\]"),
    ({"v50": {"identify": 0.0}}, r"v50\['identify'\] must be a real number in \(0, inf\)"),
    ({"v50": {"spot": 3.0}}, "v50 tasks must be among"),
    ({"v50": "nato"}, "v50 must name one of"),
    ({"eye": "nvtherm"}, "eye must be one of"),
    ({"criterion": "acquire"}, "criterion must be one of"),
    ({"frequencies": 4}, r"frequencies must be a whole number in \[16, inf\)"),
    ({"eyes": 3}, r"eyes must be a whole number in \[1, 2\]"),
    ({"viewing_distance": 0.0}, r"viewing_distance must be a real number in \(0, inf\)"),
])
def test_bad_input_names_the_parameter_and_its_range(changes, message):
    with pytest.raises(ValueError, match=message):
        xbsm.target_acquisition(mwir(), path(2000.0), vehicle(), **changes)


def test_targets_must_be_a_target_set():
    with pytest.raises(ValueError, match="targets must be one of"):
        xbsm.target_acquisition(mwir(), path(2000.0), "giqe")


def test_range_at_p_one_half_through_study_max_range_matches_a_root_find(sweep):
    # the inverse question on the labelled chain (xbsm.study.max_range: linear in P
    # between grid ranges) against an independent root-find of the door itself
    fine = xr.DataArray(np.linspace(1000.0, 5000.0, 41), dims="ground_range")
    r = xbsm.target_acquisition(mwir(), path(fine), vehicle())
    p = r.probability.sel(task="identify", target="vehicle")
    answer = xbsm.study.max_range(p, 0.5, "ground_range", flags=r.flags.sel(target="vehicle"))

    def excess(ground_range):
        one = xbsm.target_acquisition(mwir(), path(ground_range), vehicle())
        return float(one.probability.sel(task="identify").squeeze()) - 0.5

    root = brentq(excess, 1000.0, 5000.0, xtol=1e-3)
    assert float(answer.max_range) == pytest.approx(root, rel=2e-3)


def test_smallest_aperture_reaching_p_0_6_through_study_min_parameter():
    # at 2.5 km P(identify) grows from 0.31 (2 cm) and levels off at 0.68 (10 cm), where the
    # 15 um pixels, not the optics, limit it
    sizes = xr.DataArray(np.linspace(0.02, 0.1, 17), dims="aperture_diameter")
    r = xbsm.target_acquisition(mwir(sizes), path(2500.0), vehicle())
    p = r.probability.sel(task="identify").squeeze()
    answer = xbsm.study.min_parameter(p, 0.6, "aperture_diameter", flags=r.flags.squeeze())
    smallest = float(answer.min_aperture_diameter)
    assert 0.02 < smallest < 0.1
    lower = xbsm.target_acquisition(mwir(smallest * 0.97), path(2500.0), vehicle())
    upper = xbsm.target_acquisition(mwir(smallest * 1.03), path(2500.0), vehicle())
    assert float(lower.probability.sel(task="identify").squeeze()) < 0.6
    assert float(upper.probability.sel(task="identify").squeeze()) > 0.6


def test_standard_figure_draws_one_line_per_task(sweep):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ax = xbsm.plot.probability_against_range(sweep)
    labels = [line.get_label() for line in ax.get_lines()]
    assert [label for label in labels if not label.startswith("_")][:3] == [
        "task = detect", "task = recognize", "task = identify"]
    assert ax.get_ylim() == (0.0, 1.0)
    plt.close(ax.figure)
