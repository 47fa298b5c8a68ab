"""Tests of xbsm.atmosphere.modtran: MODTRAN tape7 and CSV files read into database tables,
and the MODTRAN 6 JSON cases of a grid.

The tape7 files under tests/data/modtran/ are MODTRAN runs from pyradi's repository
(NelisW/pyradi, pyradi/data/, MIT licence; see NOTICE), unmodified; the CSV file there is a
MODTRAN 6 run from Free-Space-QKD-Lab-HWU/Qrackling (MIT licence; see NOTICE), unmodified.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import trapezoid  # numpy.trapezoid needs numpy 2 (floor 1.24)

import xbsm
from xbsm import atmosphere as atm
from xbsm.atmosphere.modtran import APPENDIX_A, MODTRAN6_KEYS
from xbsm.constants import EARTH_RADIUS
from xbsm.examples import olson_scenario, olson_sensor

DATA = Path(__file__).resolve().parents[1] / "data" / "modtran"


def _columns(path, first_row, ncol):
    """The numbers of a tape7's spectral block, split on whitespace (independent of the reader;
    valid only for files without blank fields)."""
    lines = path.read_text().splitlines()
    rows = []
    for line in lines[first_row - 1:]:
        if line.strip().startswith("-9999."):
            break
        rows.append([float(t) for t in line.split()[:ncol]])
    return np.array(rows)


def test_read_tape7_gives_the_cards_of_pyradis_tape7_03b():
    # the card echo of pyradi's tape7-03b as printed in its first 10 lines: US standard
    # (MODEL 6), slant path (ITYPE 2), thermal + solar (IEMSCT 2), TPTEMP 300 K, rural
    # IHAZE 1 at VIS 23 km, H1 2 km, H2 10 km, zenith 30 deg, range 9.2359 km, BETA 0.04147,
    # IPARM 0 IPH 0 IDAY 1, PARM1 25, PARM3 23, PARM4 45, 2050-2100 cm-1 by 1 cm-1
    (run,) = atm.read_tape7(DATA / "tape7-03b")
    a = run.attrs
    expected = {"MODEL": 6, "ITYPE": 2, "IEMSCT": 2, "IMULT": 1, "TPTEMP": 300.0, "SURREF": 0.0,
                "IHAZE": 1, "VIS": 23.0, "GNDALT": 0.0, "H1": 2.0, "H2": 10.0, "ANGLE": 30.0,
                "RANGE": 9.2359, "BETA": 0.04147, "IPARM": 0, "IDAY": 1, "PARM1": 25.0,
                "PARM3": 23.0, "PARM4": 45.0, "V1": 2050.0, "V2": 2100.0, "DV": 1.0,
                "FWHM": 1.0, "MODEL_NAME": "1976 U S STANDARD"}
    for key, value in expected.items():
        assert a[f"modtran_{key}"] == value, key
    assert list(run.data_vars) == ["TRANS", "PTH_THRML", "SURF_EMIS", "SOL_SCAT", "GRND_RFLT",
                                   "TOTAL_RAD", "SING_SCAT", "DRCT_RFLT", "THRML_SCT"]
    assert run.sizes["wavelength"] == 51


def test_read_tape7_converts_wavenumber_radiances_to_the_files_per_micrometre_units():
    # independent: the text's columns split on whitespace; lambda = 1e4 / nu um, and
    # L_lambda = L_nu * nu^2 / 1e4 (d nu / d lambda); the file's rows run up in nu, so down
    # in wavelength
    path = DATA / "tape7-05b"
    (run,) = atm.read_tape7(path)
    raw = _columns(path, 12, 10)  # FREQ TOT_TRANS PTH_THRML THRML_SCT SURF_EMIS SOL_SCAT ...
    nu = raw[::-1, 0]
    np.testing.assert_allclose(run["wavelength"].values, 1e-2 / nu, rtol=1e-15)
    np.testing.assert_array_equal(run["TRANS"].values, raw[::-1, 1])
    np.testing.assert_allclose(run["PTH_THRML"].values, raw[::-1, 2] * nu**2 / 1e4, rtol=1e-15)
    np.testing.assert_allclose(run["SOL_SCAT"].values, raw[::-1, 5] * nu**2 / 1e4, rtol=1e-15)
    assert run["PTH_THRML"].attrs["units"] == "W sr-1 cm-2 um-1"


def test_tape7_radiances_add_up_to_modtrans_total_and_keep_the_band_integral():
    # MODTRAN's RWRITE: TOTAL_RAD = PTH_THRML + SURF_EMIS + SOL_SCAT + GRND_RFLT (no DISORT),
    # printed to 5 digits: the sum agrees to the print's rounding (5e-5 of each term)
    for name in ("tape7-03b", "tape7-05b"):
        (run,) = atm.read_tape7(DATA / name)
        total = run.PTH_THRML + run.SURF_EMIS + run.SOL_SCAT + run.GRND_RFLT
        np.testing.assert_allclose(total.values, run.TOTAL_RAD.values, rtol=1e-4)
    # the band radiance is the same in either spectral variable: the trapezoid over nu of the
    # per-cm-1 column against the trapezoid over lambda of the per-um column (1 cm-1 steps:
    # the two quadratures differ by O(step^2), 1e-5 here)
    path = DATA / "tape7-03b"
    (run,) = atm.read_tape7(path)
    raw = _columns(path, 12, 10)
    per_nu = trapezoid(raw[:, 2], raw[:, 0])
    per_um = trapezoid(run.PTH_THRML.values, run.wavelength.values * 1e6)
    assert per_um == pytest.approx(per_nu, rel=1e-4)


def test_read_tape7_takes_blank_disort_columns_and_transmittance_only_runs():
    # tape7-02 (thermal only, DISORT): SOL_SCAT, SING_SCAT, DRCT_RFLT are blank fields
    (run,) = atm.read_tape7(DATA / "tape7-02")
    assert np.isnan(run.SOL_SCAT.values).all()
    assert np.isfinite(run.PTH_THRML.values).all()
    assert run.PTH_THRML.values[-1] == pytest.approx(2.0416e-08 * 2050.0**2 / 1e4)
    # tape7-01 / -01b: IEMSCT 0, TRANS is COMBIN (the header of -01b runs two species
    # names together: 'H2-CH4CH4-CH4'); first rows 0.9100 at 2050 cm-1 and 0.0000 at 655 cm-1
    (t1,) = atm.read_tape7(DATA / "tape7-01")
    assert list(t1.data_vars) == ["TRANS"] and t1.TRANS.values[-1] == 0.9100
    (t1b,) = atm.read_tape7(DATA / "tape7-01b")
    assert t1b.TRANS.attrs["modtran_column"] == "COMBIN" and t1b.TRANS.values[-1] == 0.0
    # tape7-02c: 0.5 km visibility, IHAZE 2, the run's 13 rows from 655 cm-1
    (t2c,) = atm.read_tape7(DATA / "tape7-02c")
    assert (t2c.attrs["modtran_IHAZE"], t2c.attrs["modtran_VIS"]) == (2, 0.5)
    assert t2c.sizes["wavelength"] == 13


@pytest.mark.parametrize(("edit", "message"), [
    (lambda lines: lines[:20], r"tape7-03b:20: the run starting at line 1 ends without"),
    (lambda lines: lines[:14] + [lines[14][:20] + "x.xx" + lines[14][24:]] + lines[15:],
     r"tape7-03b:15: column \w+ holds '"),
    (lambda lines: ["garbage"] + lines, r"tape7-03b:1: expected the card 1 echo"),
    (lambda lines: lines[:5] + lines[6:], r"tape7-03b:10: the card echo before the spectral"),
])
def test_read_tape7_names_the_file_and_line_of_a_malformed_file(edit, message, tmp_path):
    lines = (DATA / "tape7-03b").read_text().splitlines()
    bad = tmp_path / "tape7-03b"
    bad.write_text("\n".join(edit(lines)) + "\n")
    with pytest.raises(ValueError, match=message):
        atm.read_tape7(bad)


def test_read_tape7_refuses_an_irradiance_run():
    with pytest.raises(ValueError, match=r"tape7-04:1: IEMSCT 3"):
        atm.read_tape7(DATA / "tape7-04")


def test_tables_from_runs_places_a_run_by_its_geometry_or_as_told(tmp_path):
    (run,) = atm.read_tape7(DATA / "tape7-05b")  # H1 0, H2 100 km: looking up, not a table
    with pytest.raises(ValueError, match=r"tape7-05b:1: the run's path is H1 = 0 km to H2 = "
                                         r"100 km"):
        atm.tables_from_runs([run])
    (thermal,) = atm.read_tape7(DATA / "tape7-02")
    with pytest.raises(ValueError, match=r"tape7-02:1: component SOL_SCAT is blank"):
        atm.tables_from_runs([thermal], altitude=[8000.0], ground_range=[0.0])
    night = atm.tables_from_runs([thermal], altitude=[8000.0], ground_range=[0.0],
                                 blank_as_zero=True)
    assert float(night[..., 3, :].max()) == 0.0  # SOL_SCAT
    assert np.isfinite(night[..., 1, :].values).all()  # PTH_THRML
    # a sensor above the ground: the geometry of the echo, edited to H1 8 km, H2 0, BETA 0.1
    lines = (DATA / "tape7-03b").read_text().splitlines()
    lines[5] = "   8.00000   0.00000 150.00000   9.23590   0.10000   0.00000    0        0.00000"
    edited = tmp_path / "down.tp7"
    edited.write_text("\n".join(lines) + "\n")
    (down,) = atm.read_tape7(edited)
    table = atm.tables_from_runs([down])
    assert table.altitude.values.tolist() == [8000.0]
    assert table.ground_range.item() == pytest.approx(math.radians(0.1) * EARTH_RADIUS)
    assert table.visibility.values.tolist() == [23.0]


def _tape7_cube(**attrs):
    (run,) = atm.read_tape7(DATA / "tape7-03b")
    ground_range = math.radians(run.attrs["modtran_BETA"]) * EARTH_RADIUS
    table = atm.tables_from_runs([run], altitude=[8000.0], ground_range=[ground_range],
                                 attrs={"surface_reflectance_of_database": 0.15, **attrs})
    return run, atm.from_tables(table), ground_range


def test_a_public_tape7_becomes_a_database_and_atmosphere_at_returns_its_values(tmp_path):
    run, cube, ground_range = _tape7_cube()
    path = atm.write_database(cube, tmp_path / "tape7.nc")
    with atm.use_database(path):
        out = atm.atmosphere_at(8000.0, ground_range, 23.0, interpolation="exact")
    # the reader's file units -> SI exactly as the database reader does: float32 / 1e-10
    np.testing.assert_array_equal(out.transmission.values,
                                  run.TRANS.values.astype(np.float32))
    si = run.PTH_THRML.values.astype(np.float32) / np.float32(1e-10)
    np.testing.assert_array_equal(out.path_thermal.values, si)
    assert int(out.flags) == 0


def test_a_public_tape7_used_in_snr(tmp_path):
    # docs/atmosphere.md, "Bring your own MODTRAN tables": pyradi's tape7-03b (US standard,
    # 23 km rural, a 9.24 km path between 2 and 10 km, 4.76-4.88 um) as the one table at
    # altitude 8 km, ground range 4.616 km; the Olson camera with a 4.77-4.87 um band.
    # SNR 3.571 is this pipeline's number (a record, quoted in the docs); the check that the
    # chain reads the tape7's values is the halving below: every component halved halves the
    # contrast photoelectron rate exactly (the aperture radiance is linear in them).
    sensor = olson_sensor("nir", wavelength_min=4.77e-6, wavelength_max=4.87e-6)
    _, cube, ground_range = _tape7_cube()
    scenario = olson_scenario(ground_range=ground_range, visibility=23.0, altitude=8000.0)
    full = atm.write_database(cube, tmp_path / "full.nc")
    half = cube.copy(deep=True)
    half["atmosphere"] = half["atmosphere"] * np.float32(0.5)
    half = atm.write_database(half, tmp_path / "half.nc")
    results = []
    for path in (full, half):
        with atm.use_database(path):
            results.append(xbsm.snr(sensor, scenario))
    r, h = results
    assert float(r.snr) == pytest.approx(3.571, abs=5e-4)
    assert int(r.flags) == 0
    rate = [float(x.contrast_photoelectrons / x.effective_integration_time) for x in (r, h)]
    assert rate[1] == pytest.approx(0.5 * rate[0], rel=1e-12)


# ---- MODTRAN 6 JSON input -------------------------------------------------------------

GRID = {"altitude": [2.0, 9000.0], "ground_range": [0.0, 5000.0, 20000.0],
        "visibility": [23.0, 5.0]}


def test_modtran_inputs_writes_appendix_a_for_each_point_inside_the_horizon():
    doc = atm.modtran_inputs(GRID)
    cases = [c["MODTRANINPUT"] for c in doc["MODTRAN"]]
    # 2 m sees 5.05 km (horizon): ground ranges 0 and 5 km there, all three at 9 km
    assert len(cases) == 2 * (2 + 3)
    assert [c["CASE"] for c in cases] == list(range(10))
    c = cases[3]  # 23 km, 9000 m, 5000 m
    # Appendix A of LeMaster & Eismann (2017): MODEL 2, rural, IMULT 1, IDAY 236, PARM1 90,
    # PARM2 50, GNDALT 0, H2 0, TPTEMP 299, 15 % target, 0.3-14 um by 0.01, FWHM 0.02, ICLD 0
    # (the spectral grid in nm, the unit of the CSV read_modtran_csv reads)
    assert c["ATMOSPHERE"]["MODEL"] == "ATM_MIDLAT_SUMMER"
    assert c["AEROSOLS"] == {"IHAZE": "AER_RURAL", "ICLD": "CLOUD_NONE", "RAINRT": 0.0,
                             "VIS": 23.0}
    assert c["RTOPTIONS"] == {"IEMSCT": "RT_SOLAR_AND_THERMAL", "IMULT": "RT_DISORT_AT_OBS"}
    g = c["GEOMETRY"]
    assert (g["ITYPE"], g["IDAY"], g["PARM1"], g["PARM2"], g["H2ALT"]) == (2, 236, 90.0, 50.0,
                                                                          0.0)
    assert g["H1ALT"] == 9.0
    # BETA on xbsm's sphere: BETA * RAD_E = the ground range
    assert math.radians(g["BETA"]) * g["RAD_E"] * 1e3 == pytest.approx(5000.0, rel=1e-14)
    assert c["SURFACE"] == {"SURFTYPE": "REFL_CONSTANT", "SURREF": 0.15, "TPTEMP": 299.0,
                            "GNDALT": 0.0}
    s = c["SPECTRAL"]
    assert (s["V1"], s["V2"], s["DV"], s["FWHM"]) == (300.0, 14000.0, 10.0, 20.0)
    assert s["FLAGS"][0] == "N" and s["XFLAG"] == "N"
    nadir = cases[2]
    assert nadir["GEOMETRY"]["OBSZEN"] == 180.0 and "BETA" not in nadir["GEOMETRY"]
    assert cases[5]["AEROSOLS"]["VIS"] == 5.0


def test_modtran_inputs_keys_are_those_of_the_public_modtran6_cases():
    doc = atm.modtran_inputs(GRID, {"ATMOSPHERE": {"MODEL": "ATM_TROPICAL"}})
    for entry in doc["MODTRAN"]:
        case = entry["MODTRANINPUT"]
        assert set(case) <= set(MODTRAN6_KEYS["MODTRANINPUT"])
        for section, values in case.items():
            if isinstance(values, dict):
                assert set(values) <= set(MODTRAN6_KEYS[section]), section
        assert case["ATMOSPHERE"]["MODEL"] == "ATM_TROPICAL"
    assert APPENDIX_A["ATMOSPHERE"]["MODEL"] == "ATM_MIDLAT_SUMMER"  # not changed in place
    with pytest.raises(ValueError, match=r"GEOMETRY key\(s\) \['SUNZEN'\] are not in"):
        atm.modtran_inputs(GRID, {"GEOMETRY": {"SUNZEN": 40.0}})
    with pytest.raises(ValueError, match=r"section 'CLOUDS' is not a MODTRAN 6 input"):
        atm.modtran_inputs(GRID, {"CLOUDS": {"X": 1}})
    with pytest.raises(ValueError, match=r"grid altitude must be finite and > 0; got -1.0"):
        atm.modtran_inputs({"altitude": -1.0, "ground_range": 0.0})


def test_modtran_inputs_round_trips_through_json_files(tmp_path):
    doc = atm.modtran_inputs(GRID, directory=tmp_path / "multi")
    assert json.loads((tmp_path / "multi" / "xbsm_cases.json").read_text()) == doc
    atm.modtran_inputs(GRID, directory=tmp_path / "single", multi_case=False)
    files = sorted((tmp_path / "single").glob("*.json"))
    assert len(files) == len(doc["MODTRAN"])
    by_name = {c["MODTRANINPUT"]["NAME"]: c for c in doc["MODTRAN"]}
    for f in files:
        (case,) = json.loads(f.read_text())["MODTRAN"]
        assert f.stem == case["MODTRANINPUT"]["NAME"]
        assert case == by_name[f.stem]


@pytest.mark.parametrize(("header", "scale", "factor"), [
    ("WAVLEN(MCRN)", 1e4, 1.0),   # um grid, W sr-1 cm-2 / um: no conversion
    ("  WAVLEN(NM)", 1e7, 1e-3),  # nm grid, micro-W sr-1 cm-2 / nm = 1e-3 W sr-1 cm-2 / um
])
def test_read_tape7_reads_a_7sc_header_on_a_wavelength_grid(header, scale, factor, tmp_path):
    # No public .7sc with data was found: this file is pyradi's tape7-05b with its spectral
    # block rewritten under the .7sc header MODTRAN's WTHEAD writes for CHUNIT 'M' / 'N'
    # (the wavenumber column as 1e4 / nu um or 1e7 / nu nm, the other numbers as printed)
    lines = (DATA / "tape7-05b").read_text().splitlines()
    names = ("      TRAN  PTH_THRML  THRML_SCT  SURF_EMIS   SOL_SCAT  SING_SCAT  GRND_RFLT  "
             "DRCT_RFLT  TOTAL_RAD")
    rows = []
    for line in lines[11:-1]:
        tokens = line.split()
        rows.append(f"{scale / float(tokens[0]):12.6f} " + " ".join(tokens[1:10]))
    path = tmp_path / "case.7sc"
    path.write_text("\n".join(lines[:10] + [header + names] + rows + [" -9999."]) + "\n")
    (run,) = atm.read_tape7(path)
    raw = _columns(DATA / "tape7-05b", 12, 10)
    grid = np.array([float(r.split()[0]) for r in rows])[::-1]  # the rows descend in lambda
    np.testing.assert_allclose(run.wavelength.values, grid * (1e-6 if factor == 1.0 else 1e-9),
                               rtol=1e-15)
    np.testing.assert_array_equal(run.TRANS.values, raw[::-1, 1])
    np.testing.assert_allclose(run.PTH_THRML.values, raw[::-1, 2] * factor, rtol=1e-15)


def test_modtran_inputs_sweeps_condition_points_and_keeps_the_target_on_the_ground():
    points = [{}, {"ATMOSPHERE": {"MODEL": "ATM_TROPICAL"}},
              {"SURFACE": {"GNDALT": 1.5}, "GEOMETRY": {"PARM2": 30.0}}]
    grid = {"altitude": 9000.0, "ground_range": [0.0, 5000.0], "visibility": 10.0}
    cases = [c["MODTRANINPUT"] for c in atm.modtran_inputs(grid, points)["MODTRAN"]]
    assert [c["NAME"][:7] for c in cases] == ["xbsm_c0"] * 2 + ["xbsm_c1"] * 2 + ["xbsm_c2"] * 2
    assert [c["ATMOSPHERE"]["MODEL"] for c in cases[::2]] == [
        "ATM_MIDLAT_SUMMER", "ATM_TROPICAL", "ATM_MIDLAT_SUMMER"]
    high = cases[4]["GEOMETRY"]
    # ground 1.5 km MSL: the sensor 9 km above it, the target on it; the sun moved
    assert (high["H1ALT"], high["H2ALT"], high["PARM2"]) == (10.5, 1.5, 30.0)
    assert cases[0]["GEOMETRY"]["H2ALT"] == 0.0 and cases[0]["GEOMETRY"]["PARM2"] == 50.0
    assert len({c["NAME"] for c in cases}) == 6
    with pytest.raises(ValueError, match=r"section 'AEROSOLS' must map keys to values"):
        atm.modtran_inputs(grid, {"AEROSOLS": "AER_DESERT"})


def test_read_tape7_reads_every_run_of_a_file_and_tables_from_runs_grids_them(tmp_path):
    # two runs in one file (MODTRAN appends runs, each closed by ' -9999.'): pyradi's
    # tape7-03b with its card 3 edited to a sensor at 8 km above a ground target, nadir
    # (BETA 0) and BETA 0.1 deg
    lines = (DATA / "tape7-03b").read_text().splitlines()
    runs_text = []
    for beta in ("0.00000", "0.10000"):
        edited = list(lines)
        edited[5] = (f"   8.00000   0.00000 150.00000   9.23590   {beta}   0.00000    0"
                     "        0.00000")
        runs_text += edited
    path = tmp_path / "two.tp7"
    path.write_text("\n".join(runs_text) + "\n")
    runs = atm.read_tape7(path)
    assert [r.attrs["modtran_first_line"] for r in runs] == [1, len(lines) + 1]
    table = atm.tables_from_runs(runs)
    assert table.ground_range.values.tolist() == [0.0, math.radians(0.1) * EARTH_RADIUS]
    with pytest.raises(ValueError, match=r"lacks the global attribute\(s\) surface_reflectance"):
        atm.from_tables(table)  # SURREF 0 in the file: the reflectance must be given
    table.attrs["surface_reflectance_of_database"] = 0.15
    cube = atm.from_tables(table)  # a valid database: both tables present, within the horizon
    np.testing.assert_array_equal(cube.atmosphere.values[0, 0, 1, 0],
                                  runs[1].TRANS.values.astype(np.float32))
    with pytest.raises(ValueError, match=r"two.tp7:1 and .*two.tp7:\d+ are both the table"):
        atm.tables_from_runs(runs, ground_range=[0.0, 0.0])
    with pytest.raises(ValueError, match=r"altitude must give one value per run \(2\)"):
        atm.tables_from_runs(runs, altitude=[1.0])


def test_the_docs_tape7_snr_example_runs_and_gives_the_number_it_quotes(tmp_path, monkeypatch):
    # docs/atmosphere.md, "A public tape7 in xbsm.snr": the block runs as written and its
    # quoted SNR (3.571) and contrast (270 photoelectrons) are what it computes
    import re

    page = (Path(__file__).resolve().parents[2] / "docs" / "atmosphere.md").read_text()
    section = page[page.index("### A public tape7 in `xbsm.snr`"):]
    block = re.findall(r"```python\n(.*?)```", section, flags=re.S)[0]
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(block, "docs/atmosphere.md tape7 block", "exec"), namespace)
    r = namespace["r"]
    assert "float(r.snr)   # 3.571" in block and "SNR **3.571**" in section
    assert round(float(r.snr), 3) == 3.571
    assert round(float(r.contrast_photoelectrons)) == 270 and "contrast 270" in section


def test_read_tape7_names_the_row_where_the_spectral_column_turns_back(tmp_path):
    lines = (DATA / "tape7-03b").read_text().splitlines()
    lines[20] = lines[20].replace(lines[20][:8], " 2000.00", 1)  # line 21: 2000 after 2058
    bad = tmp_path / "turn.tp7"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"turn.tp7:21: the spectral column FREQ is not strictly "
                                         r"monotone \(2058.0 then 2000.0\)"):
        atm.read_tape7(bad)


# ---- MODTRAN 6 CSV output (CSVPRNT) ---------------------------------------------------
# tests/data/modtran/Transm_100km_obs_zen_0deg_scan.csv: a MODTRAN 6 CSVPRNT scanned output
# (a transmittance run, 300-2000 nm by 1 nm, 38 columns after the wavelength) from
# Free-Space-QKD-Lab-HWU/Qrackling (MIT licence; see NOTICE), unmodified.

CSV = DATA / "Transm_100km_obs_zen_0deg_scan.csv"
#: The two header lines of a radiance-run CSVPRNT block as a public file prints them
#: (brandon-reade/Qrackling, +modtran/Data/Goldstone/.../000013__Rad_..._scan.csv, commit
#: eef4dc3): the column names only; the rows of the fixture below are made up.
RADIANCE_HEADER = (
    "Waveln,  combin,  path,  path thermal,  surface,  path multiple,  sing,  grnd,  drct,  "
    "total,  irrad,  irrad,  - nat log,  direct,  ToA,  bbody\n"
    "  [nm],  path trans,  emission,   scat,   emission,   scat,  scat,  rflt,  rflt,   rad,"
    "   ref,  @obs,  path trans,  emiss,  irrad,  temp[K]\n")


def _radiance_csv(path, rows, los="los index, 0\n"):
    """A radiance block under the public header: rows of (nm, trans, emission, thermal scat,
    surface emission, multiple scat, single scat, grnd rflt, drct rflt); total rad is their
    sum (the rule the public rows follow), the other seven columns are filler."""
    text = f"case index 0 = {{\n{los}num freq, {len(rows)}\nnum column, 15\n" + RADIANCE_HEADER
    for nm, trans, em, tsc, surf, mult, sing, grnd, drct in rows:
        terms = (em, tsc, surf, mult, sing, grnd)
        total = "-nan(ind)" if "-nan(ind)" in terms else sum(terms)  # as MODTRAN prints it
        text += (f"{nm}, {trans}, {em}, {tsc}, {surf}, {mult}, {sing}, {grnd}, {drct}, "
                 f"{total}, 0, 0, 0.5, 0.97, 1e-08, 210.0\n")
    path.write_text(text + "}\n")
    return path


def test_read_modtran_csv_reproduces_the_public_files_numbers():
    # independent of the reader: the file split on commas; rows 6-1706 are 1701 rows of
    # 39 numbers (wavelength in nm, then 'combin trans' and 37 more transmittances)
    lines = CSV.read_text().splitlines()
    assert lines[:3] == ["case index 1 = {", "num freq, 1701", "num column, 38"]
    assert lines[-1] == "}"
    table = np.array([[float(t) for t in line.split(",")] for line in lines[5:-1]])
    assert table.shape == (1701, 39)
    (run,) = atm.read_modtran_csv(CSV)
    assert list(run.data_vars) == ["TRANS"]  # a transmittance run: no radiance columns
    np.testing.assert_array_equal(run.TRANS.values, table[:, 1])
    np.testing.assert_array_equal(run.wavelength.values, table[:, 0] * 1e-9)
    assert (run.TRANS.values[0], run.TRANS.values[-1]) == (0.0129122, 0.326133)
    assert run.TRANS.attrs["modtran_column"] == "combin trans"
    assert run.TRANS.attrs["units"] == "1" and run.wavelength.attrs["units"] == "m"
    a = run.attrs
    assert (a["modtran_format"], a["modtran_case_index"], a["modtran_first_line"]) == (
        "CSVPRNT", 1, 1)
    assert "modtran_los_index" not in a  # this MODTRAN 6 build prints no 'los index' line
    assert a["modtran_spectral_column"] == "Waveln [nm]"
    assert a["modtran_columns"].split()[:3] == ["Waveln_[nm]", "combin_trans", "H2O_trans"]


def test_read_modtran_csv_reads_every_block_of_a_file(tmp_path):
    # a CSVPRNT file shared by several cases holds one block per case: the public block
    # twice, the second renumbered
    lines = CSV.read_text().splitlines()
    path = tmp_path / "two.csv"
    path.write_text("\n".join(lines + ["case index 2 = {"] + lines[1:]) + "\n")
    runs = atm.read_modtran_csv(path)
    assert [r.attrs["modtran_case_index"] for r in runs] == [1, 2]
    assert [r.attrs["modtran_first_line"] for r in runs] == [1, len(lines) + 1]
    np.testing.assert_array_equal(runs[0].TRANS.values, runs[1].TRANS.values)


def test_read_modtran_csv_radiance_block_sums_modtran6_terms_into_the_database_components(
        tmp_path):
    rows = [(400, 0.5, 1e-6, 2e-7, 3e-6, 0.04, 0.06, 0.02, 0.015),
            (401, 0.6, 2e-6, 3e-7, 4e-6, "-nan(ind)", 0.07, 0.03, 0.02),
            (402, 0.7, 3e-6, 4e-7, 5e-6, 0.05, 0.08, 0.04, 0.03)]
    (run,) = atm.read_modtran_csv(_radiance_csv(tmp_path / "rad_scan.csv", rows))
    assert list(run.data_vars) == ["TRANS", "PTH_THRML", "SURF_EMIS", "SOL_SCAT", "GRND_RFLT",
                                   "TOTAL_RAD", "SING_SCAT", "DRCT_RFLT", "THRML_SCT"]
    assert run.attrs["modtran_los_index"] == 0
    np.testing.assert_array_equal(run.TRANS.values, [0.5, 0.6, 0.7])
    # micro-W sr-1 cm-2 nm-1 -> W sr-1 cm-2 um-1: times 1e-3, as read_tape7 does a .7sc's
    assert run.PTH_THRML.values[0] == pytest.approx((1e-6 + 2e-7) * 1e-3, rel=1e-15)
    assert run.SOL_SCAT.values[0] == pytest.approx((0.04 + 0.06) * 1e-3, rel=1e-15)
    assert run.GRND_RFLT.values[2] == pytest.approx(0.04e-3, rel=1e-15)
    assert run.PTH_THRML.attrs["modtran_column"] == "path emission + path thermal scat"
    assert run.SOL_SCAT.attrs["modtran_column"] == "path multiple scat + sing scat"
    # the file's total is the sum of the four database radiances (NaN where a term is NaN)
    parts = run.PTH_THRML + run.SURF_EMIS + run.SOL_SCAT + run.GRND_RFLT
    np.testing.assert_allclose(parts.values[[0, 2]], run.TOTAL_RAD.values[[0, 2]], rtol=1e-12)
    assert np.isnan(run.SOL_SCAT.values[1]) and np.isnan(run.TOTAL_RAD.values[1])
    assert run.SING_SCAT.values[1] == pytest.approx(0.07e-3, rel=1e-15)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda lines: lines[:100], r"scan.csv:100: 'num freq, 1701' but the block starting at "
                                r"line 1 has 95 rows \(truncated file\?\)"),
    (lambda lines: lines[:-1], r"scan.csv:1706: expected '}' after the 1701 rows"),
    (lambda lines: lines[:9] + [lines[9].replace("0.0506637", "x.xx", 1)] + lines[10:],
     r"scan.csv:10: column combin trans holds 'x.xx', not a number"),
    (lambda lines: lines[:9] + [lines[9] + ", 1"] + lines[10:],
     r"scan.csv:10: row has 40 fields; the header has 39"),
    (lambda lines: lines[:2] + ["num column, 37"] + lines[3:],
     r"scan.csv:4: 'num column, 37' means 38 header fields"),
    (lambda lines: [lines[0], lines[2]] + lines[3:],
     r"scan.csv:3: the block starting at line 1 has no 'num freq, <N>' line before its "
     r"column header; got 'Waveln,  combin"),
    (lambda lines: ["case index 1 ="] + lines[1:], r"scan.csv:1: expected 'case index <N> = {'"),
    (lambda lines: lines[:3] + [lines[3].replace("Waveln", "Freq", 1),
                                lines[4].replace("[nm]", "[cm-1]", 1)] + lines[5:],
     r"scan.csv:4: spectral column 'Freq \[cm-1\]' is not \['Waveln \[nm\]'\]"),
    (lambda lines: lines[:20] + [lines[20].replace("315, ", "300, ", 1)] + lines[21:],
     r"scan.csv:21: the spectral column Waveln \[nm\] is not strictly monotone "
     r"\(314.0 then 300.0\)"),
    (lambda lines: [], r"scan.csv:1: no 'case index <N> = {' block in the file"),
])
def test_read_modtran_csv_names_the_file_and_line_of_a_malformed_file(edit, message, tmp_path):
    lines = CSV.read_text().splitlines()
    bad = tmp_path / "scan.csv"
    bad.write_text("\n".join(edit(lines)) + "\n")
    with pytest.raises(ValueError, match=message) as info:
        atm.read_modtran_csv(bad)
    assert "\n" not in str(info.value)  # one line


def test_tables_from_runs_takes_csv_runs_placed_by_hand(tmp_path):
    (run,) = atm.read_modtran_csv(CSV)
    with pytest.raises(ValueError, match=r"scan.csv:1: the run has no card echo \(a MODTRAN "
                                         r"CSV output holds none\); pass visibility="):
        atm.tables_from_runs([run])
    with pytest.raises(ValueError, match=r"scan.csv:1: component PTH_THRML is not a column"):
        atm.tables_from_runs([run], visibility=[23.0], altitude=[1000.0], ground_range=[0.0])
    # the transmittance run with zero radiances, one table; then written and read back
    table = atm.tables_from_runs([run], visibility=[23.0], altitude=[1000.0],
                                 ground_range=[0.0], blank_as_zero=True,
                                 attrs={"surface_reflectance_of_database": 0.15})
    assert "xbsm.atmosphere.read_modtran_csv: Transm_100km" in table.attrs["source"]
    path = atm.write_database(atm.from_tables(table), tmp_path / "csv.nc")
    with atm.use_database(path):
        out = atm.atmosphere_at(1000.0, 0.0, 23.0, interpolation="exact")
    np.testing.assert_array_equal(out.transmission.values, run.TRANS.values.astype(np.float32))
    # a radiance block: every component from the file, in the file's units
    rows = [(400 + k, 0.5, 1e-6, 2e-7, 3e-6, 0.04, 0.06, 0.02, 0.015) for k in range(3)]
    (rad,) = atm.read_modtran_csv(_radiance_csv(tmp_path / "rad_scan.csv", rows, los=""))
    cube = atm.tables_from_runs([rad], visibility=[23.0], altitude=[1000.0], ground_range=[0.0])
    assert "modtran_los_index" not in rad.attrs
    np.testing.assert_array_equal(cube.values[0, 0, 0, 3], rad.SOL_SCAT.values)


def test_read_modtran_csv_reads_back_the_csv_modtran_inputs_asks_for(tmp_path):
    # A case of modtran_inputs asks for a CSVPRNT file; the file MODTRAN 6 writes for it must
    # be one read_modtran_csv reads. The only CSVPRNT spectral column seen in a public file is
    # 'Waveln' over '[nm]', written for cases with SPECTRAL.FLAGS[0] 'N' and XFLAG 'N'
    # (brandon-reade/Qrackling, Python/example.json: FLAGS 'NGAA  F', XFLAG 'N'), whose
    # radiances are micro-W sr-1 cm-2 nm-1 (a nanometre .7sc's, WTHEAD's XFLAG comment).
    grid = {"altitude": 9000.0, "ground_range": 0.0, "visibility": 23.0}
    (entry,) = atm.modtran_inputs(grid)["MODTRAN"]
    s = entry["MODTRANINPUT"]["SPECTRAL"]
    assert (s["FLAGS"][0], s["XFLAG"]) == ("N", "N"), (
        f"modtran_inputs asks for a CSV in FLAGS {s['FLAGS'][0]!r} / XFLAG {s['XFLAG']!r} units; "
        "read_modtran_csv reads only the 'Waveln [nm]' column of FLAGS 'N' / XFLAG 'N' cases")
    # the rows MODTRAN would print on the case's grid, V1 to V2 by DV in nm (made-up values:
    # radiance terms rising with the row number, as micro-W sr-1 cm-2 nm-1)
    nm = s["V1"] + s["DV"] * np.arange(round((s["V2"] - s["V1"]) / s["DV"]) + 1)
    k = np.arange(nm.size)
    rows = [(f"{x:g}", 0.5, 1e-6 * (i + 1), 2e-7, 3e-6, 0.04, 0.06, 0.02, 0.015)
            for i, x in zip(k, nm, strict=True)]
    (run,) = atm.read_modtran_csv(_radiance_csv(tmp_path / "xbsm_scan.csv", rows))
    # Appendix A's grid, 0.3-14 um by 0.01 um, in metres and ascending
    assert run.sizes["wavelength"] == 1371
    np.testing.assert_allclose(run.wavelength.values, np.linspace(0.3e-6, 14e-6, 1371),
                               rtol=1e-12)
    assert np.all(np.diff(run.wavelength.values) > 0)
    # micro-W sr-1 cm-2 nm-1 -> the database's W sr-1 cm-2 um-1: times 1e-3
    np.testing.assert_allclose(run.PTH_THRML.values, (1e-6 * (k + 1) + 2e-7) * 1e-3,
                               rtol=1e-12)
    assert run.PTH_THRML.attrs["units"] == "W sr-1 cm-2 um-1"
    assert run.attrs["modtran_spectral_column"] == "Waveln [nm]"
