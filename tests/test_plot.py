"""xbsm.plot.standard_figures: the files it writes and what the figures show."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import xbsm.study as st
from xbsm import flags, plot

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"  # PNG specification (ISO/IEC 15948), Sec. 5.2

# The paper's Example 1 cut down: Olson camera, 2 bands, 2 visibilities, 5 ground ranges
# (200 km drives the red 5 km NIIRS far below 0), 21 MTF frequencies up to 5.5e5 cycles/rad.
SMALL_STUDY = """
title = "small Example 1"
[sensor]
preset = "olson"
band = ["red", "nir"]
[scenario]
altitude = 9000.0
platform_speed = 100.0
[sweep]
ground_range = [0.0, 20000.0, 60000.0, 100000.0, 200000.0]
visibility = [23.0, 5.0]
[outputs]
include = ["niirs", "mtf"]
mtf_frequency = { start = 0.0, stop = 5.5e5, num = 21 }
"""

EXPECTED_FILES = ["figure2_niirs_giqe3.png", "figure2_niirs_giqe4.png",
                  "figure2_niirs_giqe5.png", "figure3_snr.png", "figure4_noise.png",
                  "figure5_mtf.png"]


@pytest.fixture(scope="module")
def result():
    return st.run(st.parse(SMALL_STUDY)).compute()


def _draw(ds, directory, render=False):
    """standard_figures, keeping each matplotlib Figure it saves (by file name).

    Without ``render`` the files hold a stand-in instead of the PNG (the figures are
    inspected, not their pixels; rendering is what takes the time).
    """
    figures = {}
    original = plot._png
    with pytest.MonkeyPatch.context() as mp:
        def keep(fig):
            figures[len(figures)] = fig
            return original(fig) if render else b"not rendered"

        mp.setattr(plot, "_png", keep)
        paths = plot.standard_figures(ds, directory)
    return paths, {path.name: figures[i] for i, path in enumerate(paths)}


@pytest.fixture(scope="module")
def drawn(result, tmp_path_factory):
    import matplotlib.pyplot as plt

    directory = tmp_path_factory.mktemp("figures") / "made" / "here"
    before = plt.get_fignums()
    paths, figures = _draw(result, directory, render=True)
    return directory, paths, figures, plt.get_fignums() == before


def test_writes_every_standard_figure_as_a_complete_png(drawn):
    directory, paths = drawn[:2]
    assert [p.name for p in paths] == EXPECTED_FILES
    assert all(p.parent == directory for p in paths)
    for path in paths:
        data = path.read_bytes()
        assert data.startswith(PNG_SIGNATURE), path.name
        assert data.endswith(b"IEND\xaeB`\x82"), path.name  # the PNG end chunk: not truncated
        assert 10_000 < len(data) < 150_000, (path.name, len(data))  # drawn, and docs-sized


def test_leaves_no_temporary_file(drawn):
    directory = drawn[0]
    assert sorted(p.name for p in directory.iterdir()) == sorted(EXPECTED_FILES)


def test_creates_no_pyplot_figure(drawn):
    assert drawn[3]  # pyplot's list of open figures is the same before and after


def test_niirs_figure_names_the_giqe_version_and_facets_band(drawn):
    figures = drawn[2]
    for version in (3, 4, 5):
        axes = figures[f"figure2_niirs_giqe{version}.png"].axes
        assert len(axes) == 2  # one panel per band
        assert axes[0].get_ylabel() == f"NIIRS (GIQE {version})"
        assert axes[0].get_title().startswith("red band")
        assert axes[1].get_title().startswith("nir band")


def test_legend_gives_units(drawn):
    legend = drawn[2]["figure2_niirs_giqe3.png"].legends[0]
    texts = [t.get_text() for t in legend.get_texts()]
    assert "visibility = 23\u00a0km" in texts and "visibility = 5\u00a0km" in texts


def _plotted_y(ax):
    ys = [np.asarray(line.get_ydata(), dtype=float) for line in ax.get_lines()]
    return np.concatenate([y[np.isfinite(y)] for y in ys])


def test_values_off_the_niirs_scale_are_not_drawn_but_marked(result, drawn):
    # precondition: red band, 5 km visibility, 200 km: GIQE 3 far below 0 (flagged
    # niirs_out_of_scale, a calibration bit), so a plunge would go below the axis
    assert float(result.niirs.sel(band="red", visibility=5.0, ground_range=200e3, giqe=3)) < -10
    ax = drawn[2]["figure2_niirs_giqe3.png"].axes[0]
    assert ax.get_ylim() == plot.NIIRS_SCALE
    y = _plotted_y(ax)
    assert y.min() >= 0.0 and y.max() <= 10.0
    markers = [line for line in ax.get_lines() if line.get_marker() == "v"]
    assert markers and all(np.all(line.get_ydata() == 0.0) for line in markers)


def test_outside_calibration_is_drawn_dashed(result, drawn):
    # precondition: the Olson camera at 9 km is outside the GIQE 3 calibration at nadir
    assert bool(flags.is_outside_calibration(result.flags.sel(giqe=3, ground_range=0.0)).all())
    ax = drawn[2]["figure2_niirs_giqe3.png"].axes[0]
    dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
    assert any(np.isfinite(np.asarray(line.get_ydata(), dtype=float)).any() for line in dashed)


def test_invalid_cells_are_not_drawn(result, tmp_path):
    ds = result[["niirs", "flags"]].sel(giqe=[3]).copy(deep=True)
    cell = {"band": 0, "ground_range": 1, "visibility": 0}
    ds["niirs"][cell] = 7.0  # a plausible-looking number that must not appear
    ds["flags"][cell] = ds["flags"][cell] | flags.flag("snr_nonpositive")
    _, figures = _draw(ds, tmp_path)
    ax = figures["figure2_niirs_giqe3.png"].axes[0]
    x_km = 20.0  # ground range of the cell
    for line in ax.get_lines():
        x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
        at = (x == x_km) & np.isfinite(y)
        assert line.get_marker() == "x" or not np.any(y[at] == 7.0)
    crosses = [line for line in ax.get_lines() if line.get_marker() == "x"]
    assert any(x_km in np.asarray(line.get_xdata(), float) for line in crosses)


def test_snr_figure_is_logarithmic_with_nothing_below_its_floor(drawn):
    ax = drawn[2]["figure3_snr.png"].axes[0]
    assert ax.get_yscale() == "log"
    assert _plotted_y(ax).min() >= plot.SNR_FLOOR


def test_noise_figure_is_at_20_km_and_5_km_visibility(result, drawn):
    ax = drawn[2]["figure4_noise.png"].axes[1]  # nir band
    point = result.sel(band="nir", ground_range=20e3, visibility=5.0)
    heights = [bar.get_height() for bar in ax.patches]
    # the bars are the result's own noise terms (total first), xbsm.snr at that scenario
    assert heights[0] == pytest.approx(float(point.total_noise), rel=1e-12)
    assert heights[2] == pytest.approx(float(point.path_noise), rel=1e-12)
    titles = " ".join(t.get_text() for t in drawn[2]["figure4_noise.png"].texts)
    assert "20\u00a0km ground range, 5\u00a0km visibility" in titles.replace("\n", " ")


def test_mtf_figure_marks_nyquist_in_cycles_per_pixel(drawn):
    fig = drawn[2]["figure5_mtf.png"]
    ax = fig.axes[0]
    nyquist = [a for a in ax.texts if a.get_text() == "Nyquist"]
    assert len(nyquist) == 1 and nyquist[0].xy[0] == 0.5  # Nyquist = 1/(2 pixels)
    # last frequency 5.5e5 cycles/rad times the pixel angle 8 um / 4 m = 1.1 cycles/pixel
    system = [line for line in ax.get_lines() if line.get_label() == "system"][0]
    assert np.nanmax(system.get_xdata()) == pytest.approx(1.1, rel=1e-12)


def test_mtf_figure_leaves_out_components_identically_one(drawn):
    fig = drawn[2]["figure5_mtf.png"]
    labels = {line.get_label() for ax in fig.axes for line in ax.get_lines()}
    # the Olson camera has no wavefront error and no filter (paper Table 2)
    assert "wavefront" not in labels and "filter" not in labels
    assert {"aperture", "turbulence", "detector", "jitter", "drift", "system"} <= labels
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "identically 1, not drawn: wavefront, filter" in legend


def test_figures_of_absent_variables_are_skipped(result, tmp_path):
    paths, _ = _draw(result[["snr", "flags"]], tmp_path)
    names = [p.name for p in paths]
    assert names == ["figure3_snr.png"]  # no niirs, no noise terms, no mtf_* variables


def test_extra_dimension_becomes_panel_rows(result, tmp_path):
    focal = xr.DataArray([3.0, 4.0], dims="focal_length", attrs={"units": "m"})
    ds = xr.concat([result[["snr", "flags"]]] * 2, dim=focal)
    _, figures = _draw(ds, tmp_path)
    fig = figures["figure3_snr.png"]
    assert len(fig.axes) == 4  # rows: focal length, columns: band
    assert fig.axes[2].get_title() == "focal length = 4\u00a0m; red band (500-660\u00a0nm)"


def test_dimension_of_length_one_goes_into_the_title(result, tmp_path):
    _, figures = _draw(result[["snr", "flags"]].isel(visibility=[1]), tmp_path)
    fig = figures["figure3_snr.png"]
    assert len(fig.axes) == 1  # the bands become the lines, as visibility would have
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend[:2] == ["red band (500-660\u00a0nm)", "nir band (550-850\u00a0nm)"]
    title = " ".join(t.get_text() for t in fig.texts).replace("\n", " ")
    assert "visibility = 5\u00a0km" in title


def test_dimension_left_over_is_refused_by_name(result, tmp_path):
    ds = result[["snr", "flags"]]
    for dim in ("focal_length", "altitude"):
        ds = xr.concat([ds] * 2, dim=xr.DataArray([1.0, 2.0], dims=dim))
    with pytest.raises(ValueError, match="dimension '(focal_length|altitude)' is left over"):
        plot.standard_figures(ds, tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_interrupted_write_keeps_the_previous_file_and_no_temporary(result, tmp_path,
                                                                    monkeypatch):
    monkeypatch.setattr(plot, "_png", lambda fig: b"not rendered")
    old = tmp_path / "figure2_niirs_giqe4.png"
    old.write_bytes(b"previous figure")
    calls = []

    def interrupt_second(path, mode):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(path, mode)

    original = plot.os.chmod
    monkeypatch.setattr(plot.os, "chmod", interrupt_second)
    with pytest.raises(KeyboardInterrupt):
        plot.standard_figures(result[["niirs", "flags"]], tmp_path)
    monkeypatch.undo()
    assert old.read_bytes() == b"previous figure"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figure2_niirs_giqe3.png",
                                                          "figure2_niirs_giqe4.png"]


def test_rejects_what_it_cannot_draw(result, tmp_path):
    with pytest.raises(ValueError, match="xarray Dataset"):
        plot.standard_figures(result.niirs, tmp_path)
    with pytest.raises(ValueError, match="none of the variables"):
        plot.standard_figures(result[["gsd"]], tmp_path)
    mtf = result[["mtf_system"]].drop_vars("frequency", errors="ignore")
    mtf.attrs = {}
    with pytest.raises(ValueError, match="frequency coordinate"):
        plot.standard_figures(mtf, tmp_path)
