"""xbsm.plot: the standard figures' files and what they show, and the range-performance axes."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import xbsm.study as st
from xbsm import flags, plot
from xbsm.plot import figures as plot_figures

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
    original = plot_figures._png
    with pytest.MonkeyPatch.context() as mp:
        def keep(fig):
            figures[len(figures)] = fig
            return original(fig) if render else b"not rendered"

        mp.setattr(plot_figures, "_png", keep)
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


def test_a_point_with_no_drawn_neighbour_is_marked_whatever_its_style(result, tmp_path):
    # one visibility, two ground ranges: the 20 km point is on the scale but outside the
    # GIQE 3 calibration (dashed style) and the 200 km point falls off the scale, so no
    # segment joins it to anything; it must still be drawn (an open marker), not vanish
    ds = result[["niirs", "flags"]].sel(giqe=[3], band=["red"], visibility=[5.0],
                                        ground_range=[20000.0, 200000.0])
    value = float(ds.niirs.sel(ground_range=20000.0).squeeze())
    assert 0.0 < value < 10.0 and float(ds.niirs.sel(ground_range=200000.0).squeeze()) < 0
    assert bool(flags.is_outside_calibration(ds.flags.sel(ground_range=20000.0)).all())
    _, figures = _draw(ds, tmp_path)
    fig = figures["figure2_niirs_giqe3.png"]
    marked = [line for line in fig.axes[0].get_lines() if line.get_marker() == "o"
              and np.isclose(np.asarray(line.get_ydata(), float), value).any()]
    assert marked and marked[0].get_markerfacecolor() == "none"
    # the legend's long labels are wrapped to fit the figure's width side by side
    (legend,) = fig.legends
    chars = max(len(line) for text in legend.get_texts() for line in text.get_text().split("\n"))
    assert chars * legend._ncols <= fig.get_figwidth() * 16


def test_legend_columns_fit_the_figure_width():
    from xbsm.plot._layout import legend_columns

    assert legend_columns(["a", "b", "c", "d"], 6.0) == (3, 26)  # 96 chars a line, 3 columns
    # 43-character labels (+6 for the handle): two abreast in 144 characters, not three
    assert legend_columns(["x" * 43, "y" * 43, "z" * 43], 9.0) == (2, 66)
    assert legend_columns(["x" * 60], 2.0) == (1, 26)  # one column, wrapped, however narrow


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
    monkeypatch.setattr(plot_figures, "_png", lambda fig: b"not rendered")
    old = tmp_path / "figure2_niirs_giqe4.png"
    old.write_bytes(b"previous figure")
    calls = []

    def interrupt_second(path, mode):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(path, mode)

    original = plot_figures.os.chmod
    monkeypatch.setattr(plot_figures.os, "chmod", interrupt_second)
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


# ---- range_performance ---------------------------------------------------------------------

# Olson camera (nir), 6 ground ranges x 3 focal lengths x 2 visibilities. GIQE 5 NIIRS of this
# study (xbsm.niirs, 'accurate'): at 23 km visibility it falls from 6.1-6.9 at 40 km to
# 4.38 / 4.90 / 4.25 at 80 km for f = 2 / 4 / 8 m; at 5 km visibility it is at most 3.2 from
# 40 km on. A requirement of NIIRS >= 4.5 thus has an exact crossing (f = 2 m), one still met
# at the grid's last range (f = 4 m) and a visibility that never meets it.
RANGE_STUDY = """
[sensor]
preset = "olson"
band = "nir"
[scenario]
altitude = 9000.0
platform_speed = 100.0
[sweep]
ground_range = [40000.0, 45000.0, 50000.0, 60000.0, 70000.0, 80000.0]
focal_length = [2.0, 4.0, 8.0]
visibility = [23.0, 5.0]
"""


@pytest.fixture(scope="module")
def range_niirs():
    ds = st.run(st.parse(RANGE_STUDY)).compute()
    return ds.niirs.sel(giqe=5), ds.flags.sel(giqe=5)


@pytest.fixture(scope="module")
def goal(range_niirs):
    niirs, bits = range_niirs
    bits = bits.copy()
    cell = {"focal_length": 2, "visibility": 0, "ground_range": 4}  # f = 8 m, 23 km, 70 km
    bits[cell] = bits[cell] | flags.flag("snr_nonpositive")  # an invalid cell ends the search
    out = st.max_range(niirs, 4.5, flags=bits)
    # precondition (from the NIIRS values above): exact, grid edge, invalid cell; never meets;
    # every answer at 23 km lands 40-80 km from a 9 km altitude, below the GIQE 5 elevation
    # calibration (xbsm.metrics.GIQE_CALIBRATIONS; decode(out.flags) shows
    # elevation_out_of_range on all three): outside_calibration (8) on each
    outside = st.goals.GOAL_FLAGS["outside_calibration"]
    assert (out.goal_flags.sel(visibility=23.0) & ~outside).values.tolist() == [0, 2, 4]
    assert ((out.goal_flags.sel(visibility=23.0) & outside) != 0).all()
    assert out.goal_flags.sel(visibility=5.0).values.tolist() == [1, 1, 1]
    return out


def _new_axes():
    from matplotlib.figure import Figure

    return Figure(layout="constrained").subplots()


def _open_markers(ax) -> dict:
    """{marker: (x, y)} of the lines drawn with white-filled markers (the bounds)."""
    from matplotlib.colors import to_rgba

    return {line.get_marker(): (list(line.get_xdata()), list(line.get_ydata()))
            for line in ax.get_lines() if line.get_linestyle() == "None"
            and to_rgba(line.get_markerfacecolor()) == (1.0, 1.0, 1.0, 1.0)
            and len(line.get_xdata())}


def _arrows(ax) -> list:
    from matplotlib.text import Annotation

    return [a for a in ax.texts if isinstance(a, Annotation) and a.arrow_patch is not None]


def test_range_performance_labels_axes_with_units_and_the_threshold(goal):
    import io

    ax = plot.range_performance(goal, ax=_new_axes())
    assert ax.get_xlabel() == "focal length [m]"  # x: the first dimension of max_range
    assert ax.get_ylabel() == "longest ground range [km]"
    assert ax.get_title() == "Longest ground range with NIIRS (GIQE 5) \u2265 4.5"
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend[:2] == ["visibility = 23\u00a0km", "visibility = 5\u00a0km"]  # hue: the other
    ax.figure.savefig(io.BytesIO(), format="png")  # renders, no warning (the glyphs exist)


def test_range_performance_draws_exact_answers_in_km_one_line_per_hue(goal):
    ax = plot.range_performance(goal, ax=_new_axes())
    solid = [line for line in ax.get_lines() if line.get_linestyle() == "-"]
    assert len(solid) == 2  # one per visibility
    x, y = np.asarray(solid[0].get_xdata(), float), np.asarray(solid[0].get_ydata(), float)
    assert x.tolist() == [2.0, 4.0, 8.0]  # the focal lengths swept [m]
    # the exact crossing is max_range's own answer in km; NIIRS passes 4.5 between 70 and 80 km
    exact = float(goal.max_range.sel(focal_length=2.0, visibility=23.0)) / 1e3
    assert y[0] == pytest.approx(exact, rel=1e-12) and 70.0 < y[0] < 80.0
    assert np.isnan(y[1:]).all()  # the two bounds are not on the solid line


def test_range_performance_draws_bounds_open_with_an_arrow_up(goal):
    ax = plot.range_performance(goal, ax=_new_axes())
    markers = _open_markers(ax)
    # bound_at_grid_edge: f = 4 m still meets NIIRS 4.5 at the last range swept, 80 km
    assert markers["o"] == ([4.0], [80.0])
    # invalid_cell: f = 8 m is known good only up to 60 km, the range before the invalid cell
    assert markers["s"] == ([8.0], [60.0])
    arrows = _arrows(ax)
    assert sorted(a.xy for a in arrows) == [(4.0, 80.0), (8.0, 60.0)]
    assert all(a.xyann[1] > 0 for a in arrows)  # up: the true range is at least this
    top = ax.get_ylim()[1]
    assert top > 80.0  # room for the arrow above the highest bound
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "lower bound \u2191: still met at the longest range swept" in legend
    assert "lower bound \u2191: an invalid model cell ended the search" in legend


def test_range_performance_leaves_out_cells_that_never_meet_and_names_them(goal):
    ax = plot.range_performance(goal, ax=_new_axes())
    orange = [line for line in ax.get_lines() if line.get_color() == "tab:orange"]
    assert orange and all(np.isnan(np.asarray(line.get_ydata(), float)).all()
                          for line in orange)  # 5 km visibility: nothing drawn
    note = [t.get_text() for t in ax.get_legend().get_texts()][-1].replace("\n", " ")
    assert note == ("never meets the requirement (not drawn): visibility = 5\u00a0km at "
                    "2\u00a0m, 4\u00a0m, 8\u00a0m")


def test_range_performance_of_min_parameter_points_bounds_down(range_niirs):
    niirs, bits = range_niirs
    smallest = st.min_parameter(niirs, 4.5, "focal_length", flags=bits)
    # precondition: f = 2 m (the first swept) already meets 4.5 at 23 km out to 70 km
    # (each also outside_calibration, 8: elevations below GIQE 5's at 40-80 km, as above)
    outside = st.goals.GOAL_FLAGS["outside_calibration"]
    assert (smallest.goal_flags.sel(visibility=23.0) & ~outside).values.tolist()[:5] == [2] * 5
    ax = plot.range_performance(smallest, x="ground_range", ax=_new_axes())
    assert ax.get_xlabel() == "ground range [km]"
    assert ax.get_ylabel() == "smallest focal length [m]"
    arrows = _arrows(ax)
    assert len(arrows) == 5 and all(a.xyann[1] < 0 for a in arrows)  # the answer is at most


def test_range_performance_refuses_what_it_cannot_draw(goal, range_niirs):
    with pytest.raises(ValueError, match="goal must be the Dataset"):
        plot.range_performance(range_niirs[0].to_dataset(), ax=_new_axes())
    with pytest.raises(ValueError, match="x must be one of"):
        plot.range_performance(goal, x="ground_range", ax=_new_axes())
    extra = xr.concat([goal] * 2, dim=xr.DataArray([1.0, 2.0], dims="altitude"))
    with pytest.raises(ValueError, match="dimension 'altitude' besides"):
        plot.range_performance(extra, x="focal_length", hue="visibility", ax=_new_axes())


# --- the notebook helpers on pyplot (issue 21 item 4) ----------------------------------------


@pytest.fixture()
def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.close("all")
    yield plt
    plt.close("all")


@pytest.fixture(scope="module")
def olson_to_100km():
    # the README's notebook example: the Olson camera (xbsm.examples) to 100 km; at 5 km
    # visibility GIQE 5 NIIRS falls far below the 0-10 scale (-726 at 100 km, computed here)
    import xbsm
    from xbsm.examples import olson_scenario, olson_sensor

    ranges = xr.DataArray(np.linspace(0.0, 100e3, 21), dims="ground_range")
    return xbsm.niirs(olson_sensor(), olson_scenario(ground_range=ranges))


def test_against_range_holds_niirs_to_its_scale_and_marks_where_it_leaves(pyplot,
                                                                          olson_to_100km):
    n = olson_to_100km.niirs.sel(giqe=5)
    assert float(n.min()) < -100  # precondition: far off the scale
    ax = plot.against_range(n, hue="visibility")
    assert ax.get_ylim() == plot.NIIRS_SCALE
    drawn = np.concatenate([np.asarray(line.get_ydata(), float) for line in ax.get_lines()])
    assert np.nanmin(drawn) >= 0.0  # nothing below the scale is drawn (markers sit on 0)
    below = [line for line in ax.get_lines() if line.get_marker() == "v"]
    assert below and all(np.all(np.asarray(line.get_ydata()) == 0.0) for line in below)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "NIIRS falls below 0 from here (not drawn)" in texts
    assert "visibility = 5\u00a0km" in texts


def test_against_range_with_flags_dashes_values_outside_the_calibration(pyplot,
                                                                        olson_to_100km):
    n = olson_to_100km.sel(giqe=5, visibility=23.0)
    assert bool(flags.is_outside_calibration(n.flags).any())  # precondition
    ax = plot.against_range(n.niirs, flags=n.flags)
    assert any(line.get_linestyle() == "--" for line in ax.get_lines())
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "outside the GIQE calibration (extrapolated)" in texts


def test_against_range_leaves_other_quantities_unbounded(pyplot, olson_to_100km):
    gsd = olson_to_100km.gsd
    ax = plot.against_range(gsd)
    assert ax.get_ylim()[1] >= float(gsd.max())


def test_noise_breakdown_on_a_new_figure_keeps_its_tick_labels_inside(pyplot):
    import xbsm
    from xbsm.examples import olson_scenario, olson_sensor

    r = xbsm.snr(olson_sensor(), olson_scenario(ground_range=20e3, visibility=5.0))
    ax = plot.noise_breakdown(r)
    fig = ax.figure
    assert fig.get_layout_engine() is not None
    fig.canvas.draw()
    drawn = ax.get_tightbbox(fig.canvas.get_renderer())  # the axes with its tick labels
    box = fig.bbox
    assert (drawn.x0 >= box.x0 - 0.5 and drawn.y0 >= box.y0 - 0.5
            and drawn.x1 <= box.x1 + 0.5 and drawn.y1 <= box.y1 + 0.5), (drawn, box)


def _tick_texts(ax) -> list:
    return [t.get_text() for t in ax.get_xticklabels()]


def test_noise_breakdown_splits_self_emission_by_source_when_set(pyplot):
    # an MWIR camera with cold shield, optics, cold filter and stray light all set
    # (tests/test_noise.py MWIR): one bar per source instead of "emission / stray"
    from test_noise import MWIR

    import xbsm

    sensor = xbsm.sensor(**MWIR)
    r = xbsm.snr(sensor, xbsm.scenario(altitude=3000.0, ground_range=5000.0, visibility=23.0))
    labels = _tick_texts(plot.noise_breakdown(r, sensor=sensor))
    assert {"cold shield", "optics emission", "cold filter emission", "stray light"} <= set(
        labels)
    assert "emission / stray" not in labels
    # a source that is off gets no bar
    off = xbsm.sensor(**{**MWIR, "stray_irradiance": 0.0})
    r_off = xbsm.snr(off, xbsm.scenario(altitude=3000.0, ground_range=5000.0, visibility=23.0))
    assert "stray light" not in _tick_texts(plot.noise_breakdown(r_off, sensor=off))


def test_noise_breakdown_draws_only_the_sources_that_contribute(pyplot):
    # the Olson camera (visible/NIR): only its 70 K cold shield gives any photoelectrons
    # (1e-46 electrons, computed with xbsm.noise.self_emission_noise_terms); its one
    # emission bar is named for it, the sources that are off get none
    import xbsm
    from xbsm.examples import olson_scenario, olson_sensor

    sensor = olson_sensor()
    r = xbsm.snr(sensor, olson_scenario(ground_range=20e3, visibility=5.0))
    plain = _tick_texts(plot.noise_breakdown(r))
    labels = _tick_texts(plot.noise_breakdown(r, sensor=sensor))
    assert "emission / stray" in plain and "cold shield" not in plain
    assert labels == [("cold shield" if t == "emission / stray" else t) for t in plain]


def test_noise_figure_of_a_study_splits_self_emission_by_source():
    # the standard Figure 4 rebuilds the sensor from the result's study file
    from test_noise import MWIR

    sensor = "\n".join(f"{k} = {v!r}" for k, v in MWIR.items())
    text = (f"[sensor]\n{sensor}\n[scenario]\naltitude = 3000.0\nvisibility = 23.0\n"
            "[sweep]\nground_range = [5000.0, 20000.0]\n")
    result = st.run(st.parse(text)).compute()
    figures = dict(plot_figures._noise_figure(result, plot_figures.context_of(result)))
    labels = _tick_texts(figures["figure4_noise.png"].axes[0])
    assert {"cold shield", "optics emission", "cold filter emission", "stray light"} <= set(
        labels)


def test_noise_figure_of_an_older_result_keeps_one_self_emission_bar():
    # a result written before xbsm.study.attributes (its study text only): the figure
    # does not parse the study file, so self-emission stays one bar
    from test_noise import MWIR

    sensor = "\n".join(f"{k} = {v!r}" for k, v in MWIR.items())
    text = (f"[sensor]\n{sensor}\n[scenario]\naltitude = 3000.0\nvisibility = 23.0\n"
            "[sweep]\nground_range = [5000.0, 20000.0]\n")
    result = st.run(st.parse(text)).compute()
    result.attrs = {k: v for k, v in result.attrs.items()
                    if not k.startswith(("xbsm_sensor_", "xbsm_scenario_", "xbsm_band"))}
    figures = dict(plot_figures._noise_figure(result, plot_figures.context_of(result)))
    labels = _tick_texts(figures["figure4_noise.png"].axes[0])
    assert "emission / stray" in labels and "cold shield" not in labels
