"""MODTRAN's own files in and out: read tape7, ``.7sc`` and CSV outputs, write JSON inputs.

:func:`read_tape7` reads a MODTRAN text spectral output, the ``tape7`` (``.tp7``) or the
scanned (slit-convolved) ``.7sc``, one :class:`xarray.Dataset` per run on a ``wavelength``
dimension in metres, the database components under the database's names and in the
database file's units (:data:`~xbsm.atmosphere.tables.FILE_UNITS`), and the run's card echo
(model, aerosol, visibility, geometry, spectral settings) as ``modtran_*`` attributes.
:func:`read_modtran_csv` reads MODTRAN 6's CSV spectral output (``FILEOPTIONS.CSVPRNT``) into
runs of the same shape (a CSV has no card echo: the run's place is given by hand).
:func:`tables_from_runs` places runs on the (visibility, altitude, ground range) grid as the
DataArray :func:`~xbsm.atmosphere.tables.from_tables` takes.
:func:`modtran_inputs` writes the MODTRAN 6 JSON cases that would compute a cube on a grid,
with the settings of Appendix A of the pyBSM paper (the shipped database's) as defaults, on
the nanometre grid whose CSV output :func:`read_modtran_csv` reads back.

Where each format fact comes from (nothing here is guessed from the outputs alone):

- the tape7 column headers, their field widths and units: MODTRAN's own ``WTHEAD``,
  ``EWRITE`` and ``RWRITE`` subroutines (Fortran source found in a public repository with
  the code search tool): the tape7 spectral column is ``FREQ`` in cm-1 and the radiances are
  W sr-1 cm-2 / cm-1; the ``.7sc`` header is ``FREQ(CM-1)``, ``WAVLEN(MCRN)`` or
  ``WAVLEN(NM)`` by the unit flag, whose radiances are per cm-1, W sr-1 cm-2 / micron, or
  micro-W sr-1 cm-2 / nm (the ``XFLAG`` comment there); a DISORT run leaves a column blank;
- the ``.7sc`` as pyBSM's source, in W/(sr cm2 um) on a micrometre grid: Appendix A of
  LeMaster & Eismann (2017);
- the MODTRAN 6 names of two columns (``THRML_EM`` where MODTRAN 5 writes ``PTH_THRML``,
  ``MULT_SCAT`` where it writes ``SOL_SCAT``): the header of a MODTRAN 6 ``.tp7`` in the
  public repository jean-allen/modtran6-case-iteration (``blackbody_template_TPTEMP-300.tp7``,
  first commit), and the same 16 column names in the MODTRAN 6 reader of
  jesseturner/spectral_analysis (``MODTRAN_utils/modtran_utils.py``);
- the card echo at the top of each run (card 1: MODEL, ITYPE, IEMSCT, IMULT, M1-M6, MDEF,
  I_RD2C, NOPRNT, TPTEMP, SURREF; card 2: IHAZE, ISEASN, IVULCN, ICSTL, ICLD, IVSA, VIS, WSS,
  WHH, RAINRT, GNDALT; card 3: H1, H2, ANGLE, RANGE, BETA, RO, LENN, PHI; card 3A1: IPARM,
  IPH, IDAY, ISOURC; card 3A2: PARM1-4, TIME, PSIPO, ANGLEM, G; card 4: V1, V2, DV, FWHM):
  MODTRAN's card order, checked on the sample tape7 files of pyradi (NelisW/pyradi,
  ``pyradi/data/tape7-*``; e.g. the MODTRAN 6 echo of the JSON case above gives IHAZE 1,
  VIS 23, GNDALT 0.315, H1 21, IDAY 121 where its JSON says AER_RURAL, 23.0, 0.315, 21.0,
  121);
- the MODTRAN 6 CSV layout (``case index <N> = {``, ``los index``, ``num freq``, ``num
  column``, two header lines, the rows, ``}``), its column names and its units: public
  CSVPRNT files. Free-Space-QKD-Lab-HWU/Qrackling (MIT) holds transmittance runs
  (``Examples/Data/atmospheric transmittance/varying elevation MODTRAN data 2/*_scan.csv``;
  one is ``tests/data/modtran/Transm_100km_obs_zen_0deg_scan.csv``, unmodified); its fork
  brandon-reade/Qrackling holds radiance runs (``+modtran/Data/**/*_scan.csv``, with the
  JSON cases that made them: XFLAG N, so micro-W sr-1 cm-2 nm-1 as in a ``.7sc``). Their
  rows add up to ``total rad`` as path emission + path thermal scat + surface emission +
  path multiple scat + sing scat + grnd rflt (e.g. 0.129464 + 0.000674186 = 0.130138 at
  10000 nm by night; by day at 400 nm, path multiple scat 0 and sing scat 0.0601953 =
  total rad), so MODTRAN 6 prints the thermal scatter and the single scatter as terms of
  their own, where MODTRAN 5's PTH_THRML and SOL_SCAT hold them: the CSV reader sums them
  into PTH_THRML and SOL_SCAT. No radiance CSV with a licence that allows a copy was
  found: the radiance branch is tested on made-up rows under the public header. The same
  rule probably holds for a MODTRAN 6 ``.tp7`` (pymod6's tests find its binary tape7, SLI
  and JSON outputs equal column for column), where :func:`read_tape7` takes ``THRML_EM``
  and ``MULT_SCAT`` alone (read from a header without rows): open, see the docs.

MODTRAN 6's JSON spectral output (``JSONPRNT``) is not read: no public sample was found
(``docs/atmosphere.md``, "Bring your own MODTRAN tables").
"""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path

import numpy as np
import xarray as xr

from ..constants import EARTH_RADIUS
from .database import COMPONENTS
from .tables import DIMS, FILE_UNITS

__all__ = [
    "APPENDIX_A",
    "MODTRAN6_KEYS",
    "modtran_inputs",
    "read_modtran_csv",
    "read_tape7",
    "tables_from_runs",
]

#: Database component -> the column names that hold it, MODTRAN 5 tape7 first (WTHEAD), then
#: the ``.7sc`` name (``TRAN``), the transmittance-only tape7's ``COMBIN`` (IEMSCT 0) and the
#: MODTRAN 6 names (``THRML_EM``, ``MULT_SCAT``: jean-allen/modtran6-case-iteration's .tp7).
_COLUMNS = {
    "TRANS": ("TOT_TRANS", "TRAN", "COMBIN"),
    "PTH_THRML": ("PTH_THRML", "THRML_EM"),
    "SURF_EMIS": ("SURF_EMIS",),
    "SOL_SCAT": ("SOL_SCAT", "MULT_SCAT"),
    "GRND_RFLT": ("GRND_RFLT",),
}
#: Other radiance columns kept (for checks: TOTAL_RAD is the sum of the four database
#: radiances in a run without DISORT, RWRITE's SUMT).
_EXTRA_RADIANCES = ("TOTAL_RAD", "SING_SCAT", "DRCT_RFLT", "THRML_SCT")
#: First header name of the spectral column -> its unit (WTHEAD's tape7 and .7sc headers).
_SPECTRAL = {"FREQ": "cm-1", "FREQ(CM-1)": "cm-1", "FREQ (CM-1)": "cm-1",
             "WAVLEN(MCRN)": "um", "WAVLEN (UM)": "um", "WAVLEN(NM)": "nm", "WAVLEN (NM)": "nm"}
#: The end of a run's spectral block (MODTRAN writes " -9999." after the last row).
_END = "-9999."
_F5 = re.compile(r"[-+]?\d*\.\d{5}|[-+]?\d+")  # card 2, 3, 3A2 echo: F10.5 fields that may touch
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?")
_CARD1 = re.compile(r"^\s*((?:[-+]?\d+\s+){12})([-+]?\d*\.\d{3})(.*)$")
_CARD1_INTS = ("ITYPE", "IEMSCT", "IMULT", "M1", "M2", "M3", "M4", "M5", "M6", "MDEF",
               "I_RD2C", "NOPRNT")
_CARD2 = ("IHAZE", "ISEASN", "IVULCN", "ICSTL", "ICLD", "IVSA", "VIS", "WSS", "WHH", "RAINRT",
          "GNDALT")
_CARD3 = ("H1", "H2", "ANGLE", "RANGE", "BETA", "RO", "LENN", "PHI")
_CARD3A1 = ("IPARM", "IPH", "IDAY", "ISOURC")
_CARD3A2 = ("PARM1", "PARM2", "PARM3", "PARM4", "TIME", "PSIPO", "ANGLEM", "G")
#: Default visibility of MODTRAN's rural IHAZE codes when VIS is 0 (Appendix A: "1 - rural
#: extinction, 23 km visibility and 2 - rural extinction, 5 km visibility"). [km]
_IHAZE_VISIBILITY = {1: 23.0, 2: 5.0}


class _FileError(ValueError):
    """A malformed file: the message names the file and the line."""


def _fail(path, lineno, message):
    raise _FileError(f"{path}:{lineno}: {message}")


def _numbers(pattern, text, names, path, lineno, card):
    found = pattern.findall(text)
    if len(found) < len(names):
        _fail(path, lineno, f"{card} echo needs {len(names)} numbers ({', '.join(names)}); "
                            f"found {len(found)} in {text.strip()!r}")
    out = {}
    for name, token in zip(names, found, strict=False):
        value = float(token)
        out[name] = int(value) if re.fullmatch(r"[-+]?\d+", token) else value
    return out


def _card1(line, path, lineno):
    """The card 1 echo of a run.

    Flags (MODTRN, SPEED, BINARY, LYMOLC: columns 1-4), MODEL (column 5), then card 1's
    integers, TPTEMP (F8.3) and SURREF (the rest, a number or a BRDF/LAMBER word).
    """
    if len(line) < 6 or not line[4].isdigit():
        _fail(path, lineno, "expected the card 1 echo (flags in columns 1-4, MODEL in column "
                            f"5) at the start of a run; got {line.rstrip()!r}")
    match = _CARD1.match(line[6:])
    if match is None:
        _fail(path, lineno, "card 1 echo needs 12 integers (ITYPE ... NOPRNT), TPTEMP and "
                            f"SURREF after MODEL; got {line.rstrip()!r}")
    out = {"MODTRN_FLAGS": line[:4], "MODEL": int(line[4])}
    out.update(zip(_CARD1_INTS, (int(t) for t in match.group(1).split()), strict=True))
    out["TPTEMP"] = float(match.group(2))
    surref = match.group(3).strip()
    try:
        out["SURREF"] = float(surref)
    except ValueError:
        out["SURREF"] = surref
    return out


def _header_columns(line):
    """Column names of a spectral header and the end column of each field.

    Each name is right-aligned on its field (WTHEAD writes the header to the data's
    formats), so a field spans from the previous name's end to its own. A word in
    parentheses belongs to the name before it (``FREQ (CM-1)``, ``WAVLEN (NM)``).
    """
    names, ends = [], []
    for m in re.finditer(r"\S+", line):
        if m.group().startswith("(") and names:
            names[-1] = f"{names[-1]} {m.group()}"
            ends[-1] = m.end()
        else:
            names.append(m.group())
            ends.append(m.end())
    return names, ends


def _row(line, names, ends, path, lineno, *, first_columns_only=False):
    """The numbers of one spectral row; NaN for a blank field (a DISORT run's THRML_SCT).

    ``first_columns_only``: read only the fields of ``names`` (the row goes on).
    """
    if first_columns_only:
        line = line[:ends[-1]]
    tokens = line.split()
    if len(tokens) == len(names):
        try:
            return [float(t.replace("D", "E")) for t in tokens]
        except ValueError:
            pass  # fall through to the fixed fields, which name the bad one
    if len(line.rstrip()) > ends[-1]:
        _fail(path, lineno, f"row is longer than its header ({len(line.rstrip())} > {ends[-1]} "
                            f"columns) and does not split into the {len(names)} columns "
                            f"{', '.join(names)}")
    values, start = [], 0
    for name, end in zip(names, ends, strict=True):
        field = line[start:end].strip()
        start = end
        if not field:
            values.append(math.nan)
            continue
        try:
            values.append(float(field.replace("D", "E")))
        except ValueError:
            _fail(path, lineno, f"column {name} holds {field!r}, not a number")
    if math.isnan(values[0]):
        _fail(path, lineno, f"the spectral column {names[0]} is blank")
    return values


def _to_file_units(unit, grid, columns):
    """Wavelength [m] ascending, and the column arrays (radiances per um) in that order."""
    grid = np.asarray(grid, dtype=np.float64)
    if unit == "cm-1":
        wavelength = 1e-2 / grid
        per_um = grid**2 / 1e4  # |d nu / d lambda| with nu in cm-1 and lambda in um
    elif unit == "um":
        wavelength, per_um = grid * 1e-6, np.ones_like(grid)
    else:  # nm: micro-W sr-1 cm-2 / nm = 1e-6 W per 1e-3 um
        wavelength, per_um = grid * 1e-9, np.full_like(grid, 1e-3)
    order = np.argsort(wavelength, kind="stable")
    out = {}
    for name, (values, radiance) in columns.items():
        values = np.asarray(values, dtype=np.float64)
        out[name] = (values * per_um if radiance else values)[order]
    return wavelength[order], out


def _parse_run(lines, start, path):
    """One run from line index ``start``: (Dataset, index after its end line)."""
    conditions, header = _run_cards(lines, start, path)
    names, ends, transmittance_only = _run_columns(lines, start, header, conditions, path)
    table, i = _run_rows(lines, start, header, names, ends, transmittance_only, path)
    return _run_dataset(table, names, conditions, path, start, header), i


def _run_cards(lines, start, path):
    """The run's card echo as a dict of settings, and the index of its spectral header."""
    card1 = _card1(lines[start], path, start + 1)
    conditions = dict(card1)
    conditions.update(_numbers(_F5, lines[start + 1], _CARD2,
                               path, start + 2, "card 2"))
    header = None
    for i in range(start + 2, min(start + 40, len(lines))):
        first = lines[i].split()[:1]
        if first and (first[0].startswith("FREQ") or first[0].startswith("WAVLEN")):
            header = i
            break
    if header is None:
        _fail(path, start + 1, "no spectral header (a line starting FREQ or WAVLEN) within "
                               "40 lines of the run's card 1 echo")
    columns_line = next((i for i in range(start + 2, header) if "H2O & O3" in lines[i]), None)
    if columns_line is None or header - columns_line != 7:
        _fail(path, header + 1, "the card echo before the spectral header is not the expected "
                                "H2O & O3 columns, model name, card 3, 3A1, 3A2, 4 and 5 lines")
    conditions["MODEL_NAME"] = lines[columns_line + 1][5:].strip()  # after an I5 field
    for offset, names, pattern, card in ((2, _CARD3, _F5, "card 3"),
                                         (3, _CARD3A1, _F5, "card 3A1"),
                                         (4, _CARD3A2, _F5, "card 3A2"),
                                         (5, ("V1", "V2", "DV", "FWHM"), _NUMBER, "card 4")):
        i = columns_line + offset
        conditions.update(_numbers(pattern, lines[i], names, path, i + 1, card))
    return conditions, header


def _run_columns(lines, start, header, conditions, path):
    """The spectral header's column names and ends, and whether the run is IEMSCT 0."""
    names, ends = _header_columns(lines[header])
    spectral = names[0].upper()
    if spectral not in _SPECTRAL:
        _fail(path, header + 1, f"spectral column {names[0]!r} is none of {sorted(_SPECTRAL)}")
    if len(names) > 1 and names[1] == "LOS":
        _fail(path, header + 1, "a run with several lines of sight (a LOS column) is not "
                                "supported; write one line of sight per run")
    if conditions["IEMSCT"] == 3:
        _fail(path, start + 1, "IEMSCT 3 (transmitted solar irradiance) holds no path "
                               "radiances or path transmittance; run IEMSCT 2 (or 0)")
    transmittance_only = conditions["IEMSCT"] == 0
    if transmittance_only:
        # keep FREQ and COMBIN (the total); the species columns after them can run
        # together in the header (pyradi's tape7-01b: 'H2-CH4CH4-CH4')
        names, ends = names[:2], ends[:2]
    return names, ends, transmittance_only


def _run_rows(lines, start, header, names, ends, transmittance_only, path):
    """The spectral rows as a table (strictly monotone first column), and the next index."""
    rows, row_lines, i = [], [], header + 1
    while i < len(lines):
        text = lines[i]
        stripped = text.strip()
        if stripped.startswith(_END):
            i += 1
            break
        if not stripped:
            i += 1
            continue
        if i == header + 1 and stripped.startswith("CM-1"):  # IEMSCT 0's units line (WTHEAD)
            i += 1
            continue
        rows.append(_row(text, names, ends, path, i + 1,
                         first_columns_only=transmittance_only))
        row_lines.append(i + 1)
        i += 1
    else:
        _fail(path, len(lines), f"the run starting at line {start + 1} ends without its "
                                f"{_END!r} line (truncated file?)")
    if len(rows) < 2:
        _fail(path, header + 1, f"a run needs at least two spectral rows; found {len(rows)}")
    table = np.array(rows, dtype=np.float64)
    grid = table[:, 0]
    step = np.sign(np.diff(grid))
    if step[0] == 0 or np.any(step != step[0]):
        k = int(np.flatnonzero(step != step[0])[0]) + 1 if step[0] != 0 else 1
        _fail(path, row_lines[k], f"the spectral column {names[0]} is not strictly monotone "
                                  f"({float(grid[k - 1])!r} then {float(grid[k])!r})")
    return table, i


def _run_dataset(table, names, conditions, path, start, header):
    """The database components of one run's table, in the file's units, as a Dataset."""
    grid = table[:, 0]
    spectral = names[0].upper()
    picked, sources = {}, {}
    for component, candidates in _COLUMNS.items():
        for name in candidates:
            if name in names:
                picked[component] = (table[:, names.index(name)], component != "TRANS")
                sources[component] = name
                break
    for name in _EXTRA_RADIANCES:
        if name in names:
            picked[name] = (table[:, names.index(name)], True)
            sources[name] = name
    if "TRANS" not in picked:
        _fail(path, header + 1, f"no transmittance column (one of {_COLUMNS['TRANS']}) among "
                                f"{', '.join(names)}")
    unit = _SPECTRAL[spectral]
    wavelength, values = _to_file_units(unit, grid, picked)
    data_vars = _components(values, sources, unit, "MODTRAN column")
    attrs = {f"modtran_{k}": v for k, v in conditions.items()}
    attrs.update(modtran_file=str(path), modtran_first_line=start + 1,
                 modtran_spectral_column=names[0], modtran_spectral_unit=unit,
                 modtran_columns=" ".join(n.replace(" ", "_") for n in names))
    ds = xr.Dataset(data_vars, coords={"wavelength": ("wavelength", wavelength, {
        "units": "m", "long_name": "wavelength", "standard_name": "radiation_wavelength"})},
        attrs=attrs)
    return ds


def read_tape7(path) -> list[xr.Dataset]:
    """Every run of a MODTRAN tape7 (``.tp7``) or scanned ``.7sc`` text file.

    Parameters
    ----------
    path : str or os.PathLike
        A tape7 / ``.tp7`` (spectral column FREQ, cm-1) or ``.7sc`` (``FREQ(CM-1)``,
        ``WAVLEN(MCRN)`` or ``WAVLEN(NM)``) in the layout of MODTRAN 5 and 6, one or more
        runs.

    Returns
    -------
    list of xr.Dataset
        One per run, on ``wavelength`` [m] ascending: ``TRANS`` [1] and those of PTH_THRML,
        SURF_EMIS, SOL_SCAT, GRND_RFLT (and TOTAL_RAD, SING_SCAT, DRCT_RFLT, THRML_SCT) the
        file holds, radiances in W sr-1 cm-2 um-1 (the database file's units; per-cm-1
        values times nu^2 / 1e4); a blank field (a DISORT run's) is NaN. Attributes: the card
        echo as ``modtran_<NAME>`` (MODEL, IHAZE, VIS, GNDALT, H1, H2, ANGLE, RANGE, BETA,
        IDAY, PARM1, PARM2, V1, V2, DV, FWHM, ...), ``modtran_file`` and
        ``modtran_first_line``.

    Raises
    ------
    ValueError
        A malformed file, naming the file and the line (``path:line: what``).
    """
    return _read_runs(path, _parse_run, "no MODTRAN run in the file")


# ---------------------------------------------------------------------------------------
# MODTRAN 6 CSV output (FILEOPTIONS.CSVPRNT)
# ---------------------------------------------------------------------------------------

_CSV_CASE = re.compile(r"^case index\s+(\d+)\s*=\s*\{$")
_CSV_COUNT = re.compile(r"^(los index|num freq|num column)\s*,\s*(\d+)$")
#: A CSV field MODTRAN prints for a NaN or an infinity: the C runtime's text, e.g. the
#: ``-nan(ind)`` of a Windows build (seen in public CSVPRNT files).
_CSV_NONFINITE = re.compile(r"^([-+]?)(nan|inf|infinity)(\(\w*\))?$", re.IGNORECASE)
#: Spectral column of a CSVPRNT block -> its unit. Only the scanned file's nanometre grid
#: (``<CSVPRNT>_scan.csv`` of a run with XFLAG N) has been seen in a public file; it is the
#: grid :data:`APPENDIX_A` (so :func:`modtran_inputs`) asks for.
_CSV_SPECTRAL = {"Waveln [nm]": "nm"}
#: Database component -> the CSV columns summed into it. Transmittance runs (IEMSCT 0):
#: ``combin trans``. Radiance runs: MODTRAN 6 prints the thermal scatter and the single
#: scatter as their own terms of ``total rad`` (total = path emission + path thermal scat +
#: surface emission + path multiple scat + sing scat + grnd rflt in the public rows), where
#: MODTRAN 5's PTH_THRML and SOL_SCAT already hold them.
_CSV_COLUMNS = {
    "TRANS": (("combin trans",), ("combin path trans",)),
    "PTH_THRML": (("path emission", "path thermal scat"),),
    "SURF_EMIS": (("surface emission",),),
    "SOL_SCAT": (("path multiple scat", "sing scat"),),
    "GRND_RFLT": (("grnd rflt",),),
}
#: Other radiance columns kept (for checks), under the tape7 names.
_CSV_EXTRA = {"TOTAL_RAD": "total rad", "SING_SCAT": "sing scat", "DRCT_RFLT": "drct rflt",
              "THRML_SCT": "path thermal scat"}


def _csv_number(token, name, path, lineno):
    text = token.strip()
    match = _CSV_NONFINITE.match(text)
    if match:
        value = math.inf if match.group(2).lower().startswith("inf") else math.nan
        return -value if match.group(1) == "-" else value
    try:
        return float(text)
    except ValueError:
        _fail(path, lineno, f"column {name} holds {text!r}, not a number")


def _csv_block(lines, start, path):
    """One ``case index N = {`` ... ``}`` block from line index ``start``: (Dataset, next)."""
    head, counts, names, header = _csv_header(lines, start, path)
    table, end = _csv_rows(lines, header + 2, counts["num freq"], names, start, path)
    return _csv_dataset(table, names, head, counts, path, start, header), end + 1


def _csv_header(lines, start, path):
    """A block's opening line, its counts and its column names; and the header's line index."""
    head = _CSV_CASE.match(lines[start].strip())
    if head is None:
        _fail(path, start + 1, "expected 'case index <N> = {' (the start of a CSVPRNT block); "
                               f"got {lines[start].strip()!r}")
    counts, i = {}, start + 1
    while i < len(lines) and (m := _CSV_COUNT.match(lines[i].strip())):
        counts[m.group(1)] = int(m.group(2))
        i += 1
    for key in ("num freq", "num column"):
        if key in counts:
            continue
        if i >= len(lines):
            _fail(path, len(lines), f"the block starting at line {start + 1} ends before its "
                                    f"'{key}, <N>' line (truncated file?)")
        _fail(path, i + 1, f"the block starting at line {start + 1} has no '{key}, <N>' line "
                           f"before its column header; got {lines[i].strip()[:60]!r}")
    ncol = counts["num column"] + 1  # the count leaves out the spectral column
    if i + 2 > len(lines):
        _fail(path, len(lines), f"the block starting at line {start + 1} ends before its "
                                "two column-header lines (truncated file?)")
    top, bottom = lines[i].split(","), lines[i + 1].split(",")
    if len(top) != ncol or len(bottom) != ncol:
        _fail(path, i + 1, f"'num column, {ncol - 1}' means {ncol} header fields (with the "
                           f"spectral column) on two lines; found {len(top)} and "
                           f"{len(bottom)}")
    names = [" ".join(f"{a} {b}".split()) for a, b in zip(top, bottom, strict=True)]
    if names[0] not in _CSV_SPECTRAL:
        _fail(path, i + 1, f"spectral column {names[0]!r} is not {sorted(_CSV_SPECTRAL)} (the "
                           "only one seen in a public CSVPRNT file: the _scan.csv of a run "
                           "with XFLAG N); read the run's .tp7 or .7sc instead")
    return head, counts, names, i


def _csv_rows(lines, first_row, nfreq, names, start, path):
    """A block's ``nfreq`` rows from line index ``first_row``: (table, index of its '}')."""
    ncol, rows = len(names), []
    for k in range(first_row, first_row + nfreq):
        if k >= len(lines) or lines[k].strip() == "}":
            _fail(path, min(k, len(lines) - 1) + 1,
                  f"'num freq, {nfreq}' but the block starting at line {start + 1} has "
                  f"{len(rows)} rows (truncated file?)")
        fields = lines[k].split(",")
        if len(fields) == ncol + 1 and not fields[-1].strip():
            fields = fields[:-1]  # a trailing comma
        if len(fields) != ncol:
            _fail(path, k + 1, f"row has {len(fields)} fields; the header has {ncol}")
        rows.append([_csv_number(t, n, path, k + 1) for t, n in zip(fields, names,
                                                                     strict=True)])
    end = first_row + nfreq
    if end >= len(lines) or lines[end].strip() != "}":
        got = repr(lines[end].strip()) if end < len(lines) else "the end of the file"
        _fail(path, min(end, len(lines) - 1) + 1,
              f"expected '}}' after the {nfreq} rows ('num freq') of the block starting at "
              f"line {start + 1}; got {got}")
    if nfreq < 2:
        _fail(path, first_row + 1, f"a run needs at least two spectral rows; found {nfreq}")
    table = np.array(rows, dtype=np.float64)
    grid = table[:, 0]
    if not np.isfinite(grid).all():
        k = int(np.flatnonzero(~np.isfinite(grid))[0])
        _fail(path, first_row + k + 1, f"the spectral column {names[0]} is not finite")
    step = np.sign(np.diff(grid))
    if step[0] == 0 or np.any(step != step[0]):
        k = int(np.flatnonzero(step != step[0])[0]) + 1 if step[0] != 0 else 1
        _fail(path, first_row + k + 1, f"the spectral column {names[0]} is not strictly "
                                       f"monotone ({float(grid[k - 1])!r} then "
                                       f"{float(grid[k])!r})")
    return table, end


def _csv_dataset(table, names, head, counts, path, start, header):
    """The database components of one CSVPRNT block, in the file's units, as a Dataset."""
    picked, sources = {}, {}
    for component, alternatives in _CSV_COLUMNS.items():
        for columns in alternatives:
            if all(c in names for c in columns):
                values = sum(table[:, names.index(c)] for c in columns)
                picked[component] = (values, component != "TRANS")
                sources[component] = " + ".join(columns)
                break
    if "TRANS" not in picked:
        _fail(path, header + 1, "no total transmittance column ('combin trans' or 'combin "
                                f"path trans') among {', '.join(names)}")
    for name, column in _CSV_EXTRA.items():
        if column in names:
            picked[name] = (table[:, names.index(column)], True)
            sources[name] = column
    unit = _CSV_SPECTRAL[names[0]]
    wavelength, values = _to_file_units(unit, table[:, 0], picked)
    data_vars = _components(values, sources, unit, "MODTRAN CSV column")
    attrs = {"modtran_format": "CSVPRNT", "modtran_case_index": int(head.group(1))}
    if "los index" in counts:
        attrs["modtran_los_index"] = counts["los index"]
    attrs.update(modtran_file=str(path), modtran_first_line=start + 1,
                 modtran_spectral_column=names[0], modtran_spectral_unit=unit,
                 modtran_columns=" ".join(n.replace(" ", "_") for n in names))
    return xr.Dataset(data_vars, coords={"wavelength": ("wavelength", wavelength, {
        "units": "m", "long_name": "wavelength", "standard_name": "radiation_wavelength"})},
        attrs=attrs)


def read_modtran_csv(path) -> list[xr.Dataset]:
    """Every block of a MODTRAN 6 CSV spectral output (``FILEOPTIONS.CSVPRNT``).

    The layout, as public CSVPRNT files show it: per case (and line of sight) a block
    ``case index <N> = {``, optionally ``los index, <K>``, ``num freq, <rows>``,
    ``num column, <columns after the spectral one>``, two header lines whose fields join
    into the column names (``Waveln`` over ``[nm]``, ``combin`` over ``trans``), the rows,
    and ``}``. A NaN printed by the C runtime (``-nan(ind)``) reads as NaN.

    Parameters
    ----------
    path : str or os.PathLike
        A ``<CSVPRNT>_scan.csv`` on a nanometre grid (XFLAG N): the only spectral column
        seen in a public file, ``Waveln [nm]``, and the one the cases of
        :func:`modtran_inputs` ask for. Another spectral column is refused.

    Returns
    -------
    list of xr.Dataset
        One per block, on ``wavelength`` [m] ascending, in the shape :func:`read_tape7`
        returns: ``TRANS`` [1] (``combin trans`` of a transmittance run, ``combin path
        trans`` of a radiance run); for a radiance run also, where the block holds their
        columns, PTH_THRML (``path emission`` + ``path thermal scat``), SURF_EMIS
        (``surface emission``), SOL_SCAT (``path multiple scat`` + ``sing scat``),
        GRND_RFLT (``grnd rflt``) and TOTAL_RAD, SING_SCAT, DRCT_RFLT, THRML_SCT, radiances
        in W sr-1 cm-2 um-1 (the file's micro-W sr-1 cm-2 nm-1 times 1e-3). Attributes:
        ``modtran_format`` (``"CSVPRNT"``), ``modtran_case_index``, ``modtran_los_index``
        (when printed), ``modtran_file``, ``modtran_first_line``. A CSV holds no card
        echo: :func:`tables_from_runs` needs ``visibility=``, ``altitude=`` and
        ``ground_range=`` for these runs.

    Raises
    ------
    ValueError
        A malformed file, naming the file and the line (``path:line: what``).
    """
    return _read_runs(path, _csv_block, "no 'case index <N> = {' block in the file")


def _components(values, sources, unit, label):
    """The runs' data variables: each component on ``wavelength`` with its units and column."""
    out = {}
    for name, array in values.items():
        units = "1" if name == "TRANS" else FILE_UNITS[1]
        out[name] = ("wavelength", array, {
            "units": units, "modtran_column": sources[name],
            "long_name": f"{label} {sources[name]}" + (
                "" if units == "1" else f", converted from the file's {unit} grid")})
    return out


def _read_runs(path, parse, empty):
    """Every run of a text file, read by ``parse(lines, i, path)`` -> (run, next line).

    Blank lines between runs are skipped; ``empty`` is the error when there is no run.
    """
    path = Path(path)
    lines = path.read_text(errors="replace").splitlines()
    runs, i = [], 0
    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        run, i = parse(lines, i, path)
        runs.append(run)
    if not runs:
        raise _FileError(f"{path}:1: {empty}")
    return runs


def _where(run):
    return f"{run.attrs['modtran_file']}:{run.attrs['modtran_first_line']}"


def _run_visibility(run):
    """Visibility of a run [km]: VIS, or IHAZE's default when VIS is 0."""
    if "modtran_VIS" not in run.attrs:
        raise ValueError(f"{_where(run)}: the run has no card echo (a MODTRAN CSV output "
                         "holds none); pass visibility=, altitude= and ground_range=")
    vis = float(run.attrs["modtran_VIS"])
    if vis <= 0:
        ihaze = int(run.attrs["modtran_IHAZE"])
        if ihaze not in _IHAZE_VISIBILITY:
            raise ValueError(f"{_where(run)}: VIS is 0 and IHAZE {ihaze} has no default "
                             "visibility here (1: 23 km, 2: 5 km); pass visibility=")
        vis = _IHAZE_VISIBILITY[ihaze]
    return vis


def _run_geometry(run):
    """(altitude [m], ground range [m]) of a run: a sensor at H1 above a target on the ground."""
    a = run.attrs
    if "modtran_H1" not in a:
        raise ValueError(f"{_where(run)}: the run has no card echo (a MODTRAN CSV output "
                         "holds none); pass altitude= and ground_range=")
    ground, h1, h2 = float(a["modtran_GNDALT"]), float(a["modtran_H1"]), float(a["modtran_H2"])
    if not (math.isclose(h2, ground, abs_tol=1e-5) and h1 > h2):
        raise ValueError(
            f"{_where(run)}: the run's path is H1 = {h1:g} km to H2 = {h2:g} km with the ground "
            f"at {ground:g} km; a database table is a sensor above a target on the ground "
            "(H2 = GNDALT < H1): pass altitude= and ground_range= to place it anyway")
    return (h1 - ground) * 1e3, math.radians(float(a["modtran_BETA"])) * EARTH_RADIUS


def tables_from_runs(runs, *, visibility=None, altitude=None, ground_range=None,
                     wavelength=None, blank_as_zero=False, attrs=None) -> xr.DataArray:
    """Runs of the MODTRAN readers as the DataArray :func:`~xbsm.atmosphere.from_tables` takes.

    Each run is one table: its (visibility, altitude, ground range) cell is read from its
    card echo (VIS, or IHAZE's default when VIS is 0; altitude H1 - GNDALT for a target on
    the ground, H2 = GNDALT; ground range BETA x :data:`xbsm.constants.EARTH_RADIUS`) or
    given (a CSV run has no card echo: give all three). The grid is every distinct
    coordinate; cells without a run are NaN.

    Parameters
    ----------
    runs : sequence of xr.Dataset
        From :func:`read_tape7` or :func:`read_modtran_csv` (of one or several files).
    visibility, altitude, ground_range : sequence of float, optional
        The coordinate of each run, overriding the card echo. [km], [m], [m]
    wavelength : sequence of float, optional
        A common grid [m]; each run is linearly interpolated onto it (not a slit
        convolution). Default: the runs' own grid, which must then be the same for all.
    blank_as_zero : bool
        Take a component the runs do not hold (or hold blank) as zero, e.g. SOL_SCAT and
        GRND_RFLT of a thermal-only (IEMSCT 1) run; otherwise that is an error.
    attrs : dict, optional
        Global attributes added to those built here (title, source, the conditions every
        run shares as ``modtran_*``, and ``surface_reflectance_of_database`` when the runs
        share a SURREF in (0, 1]).

    Returns
    -------
    xr.DataArray
        On :data:`~xbsm.atmosphere.tables.DIMS`, in the file's units, with coordinates and
        attributes.

    Raises
    ------
    ValueError
        A run that lacks a component, two runs on one cell, different grids without
        ``wavelength``, a geometry that is not a sensor above the ground (naming the file
        and line of the run).
    """
    runs = list(runs)
    if not runs:
        raise ValueError("tables_from_runs needs at least one run")
    given = {"visibility": visibility, "altitude": altitude, "ground_range": ground_range}
    for name, values in given.items():
        if values is not None and len(values) != len(runs):
            raise ValueError(f"{name} must give one value per run ({len(runs)}); got "
                             f"{len(values)}")
    cells = []
    for k, run in enumerate(runs):
        vis = float(visibility[k]) if visibility is not None else _run_visibility(run)
        if altitude is None or ground_range is None:
            echo = _run_geometry(run)
        alt = float(altitude[k]) if altitude is not None else echo[0]
        gr = float(ground_range[k]) if ground_range is not None else echo[1]
        cells.append((vis, alt, gr))
    if wavelength is None:
        grid = runs[0]["wavelength"].values
        for run in runs[1:]:
            if not np.array_equal(run["wavelength"].values, grid):
                raise ValueError(f"runs {runs[0].attrs['modtran_file']} and "
                                 f"{run.attrs['modtran_file']} have different spectral grids; "
                                 "pass wavelength= (a common grid in metres)")
    else:
        grid = np.asarray(wavelength, dtype=np.float64)
    vis = sorted({c[0] for c in cells}, reverse=True)
    alt = sorted({c[1] for c in cells})
    gr = sorted({c[2] for c in cells})
    values = np.full((len(vis), len(alt), len(gr), len(COMPONENTS), grid.size), np.nan)
    owner = {}
    for run, cell in zip(runs, cells, strict=True):
        where = _where(run)
        if cell in owner:
            raise ValueError(f"runs {owner[cell]} and {where} are both the table at "
                             f"visibility={cell[0]!r} km, altitude={cell[1]!r} m, "
                             f"ground_range={cell[2]!r} m")
        owner[cell] = where
        index = (vis.index(cell[0]), alt.index(cell[1]), gr.index(cell[2]))
        for c, component in enumerate(COMPONENTS):
            if component in run and not np.isnan(run[component].values).any():
                spectrum = run[component].values
                if wavelength is not None:
                    own = run["wavelength"].values
                    if grid[0] < own[0] or grid[-1] > own[-1]:
                        raise ValueError(f"{where}: wavelength= [{grid[0]:.6g}, {grid[-1]:.6g}]"
                                         f" m reaches beyond the run's [{own[0]:.6g}, "
                                         f"{own[-1]:.6g}] m")
                    spectrum = np.interp(grid, own, spectrum)
            elif blank_as_zero:
                spectrum = np.zeros(grid.size)
            else:
                state = "is blank in" if component in run else "is not a column of"
                raise ValueError(f"{where}: component {component} {state} the run "
                                 f"(columns: {run.attrs['modtran_columns']}); run MODTRAN with "
                                 "IEMSCT 2, or pass blank_as_zero=True if it is zero")
            values[index][c] = spectrum
    shared = {k: v for k, v in runs[0].attrs.items()
              if k.startswith("modtran_") and k not in ("modtran_file", "modtran_first_line")
              and all(r.attrs.get(k) == v for r in runs)}
    files = sorted({str(r.attrs["modtran_file"]) for r in runs})
    readers = sorted({"read_modtran_csv" if r.attrs.get("modtran_format") == "CSVPRNT"
                      else "read_tape7" for r in runs}, reverse=True)  # read_tape7 first
    out_attrs = {"title": f"MODTRAN tables from {len(runs)} run(s)",
                 "source": "MODTRAN text outputs read by "
                           + ", ".join(f"xbsm.atmosphere.{f}" for f in readers) + ": "
                           + ", ".join(Path(f).name for f in files)}
    surref = {r.attrs.get("modtran_SURREF") for r in runs}
    if len(surref) == 1:
        (s,) = surref
        if isinstance(s, float) and 0.0 < s <= 1.0:
            out_attrs["surface_reflectance_of_database"] = s
    out_attrs.update(shared)
    out_attrs.update(attrs or {})
    return xr.DataArray(values, dims=DIMS, coords={
        "visibility": vis, "altitude": alt, "ground_range": gr, "wavelength": grid},
        attrs=out_attrs)


# ---------------------------------------------------------------------------------------
# MODTRAN 6 JSON input
# ---------------------------------------------------------------------------------------

#: Every key :func:`modtran_inputs` may write, by section, each seen in a public MODTRAN 6
#: JSON case (no MODTRAN 6 schema file is public). Sources:
#: [wagl] GeoscienceAustralia/wagl, ``wagl/modtran_profile_json.py`` (the full echo of a case,
#: every key of every section); [isofit] isofit/isofit, ``isofit/utils/template_construction.py``;
#: [ja] jean-allen/modtran6-case-iteration, ``template.json`` / ``multi_template.json``.
MODTRAN6_KEYS = {
    "MODTRANINPUT": ("NAME", "DESCRIPTION", "CASE", "RTOPTIONS", "ATMOSPHERE", "AEROSOLS",
                     "GEOMETRY", "SURFACE", "SPECTRAL", "FILEOPTIONS"),  # [isofit], [ja]
    "RTOPTIONS": ("MODTRN", "LYMOLC", "T_BEST", "IEMSCT", "IMULT", "DISALB", "NSTR",
                  "SOLCON"),  # [wagl], [isofit], [ja]
    "ATMOSPHERE": ("MODEL", "M1", "M2", "M3", "M4", "M5", "M6", "MDEF", "CO2MX", "H2OSTR",
                   "H2OUNIT", "O3STR", "O3UNIT", "C_PROF", "AERRH"),  # [wagl]
    "AEROSOLS": ("IHAZE", "CNOVAM", "ISEASN", "IVULCN", "ICSTL", "ICLD", "IVSA", "VIS", "WSS",
                 "WHH", "RAINRT"),  # [wagl]; IHAZE and VIS also [ja]
    "GEOMETRY": ("ITYPE", "IPARM", "IDAY", "PARM1", "PARM2", "PARM3", "PARM4", "GMTIME",
                 "TRUEAZ", "ANGLEM", "H1ALT", "H2ALT", "OBSZEN", "HRANGE", "BETA", "RAD_E",
                 "LENN", "BCKZEN", "CKRANG"),  # [wagl]; IPARM, IDAY, PARM2 also [ja]
    "SURFACE": ("SURFTYPE", "TPTEMP", "SURREF", "GNDALT", "NSURF", "SALBFL"),  # [wagl], [ja]
    "SPECTRAL": ("V1", "V2", "DV", "FWHM", "YFLAG", "XFLAG", "DLIMIT", "FLAGS", "MLFLX",
                 "VRFRAC", "SFWHM", "LSUNFL", "LBMNAM", "FILTNM", "BMNAME"),  # [wagl], [ja]
    "FILEOPTIONS": ("BINARY", "CKPRNT", "NOPRNT", "SLIPRNT", "CSVPRNT", "JSONPRNT",
                    "FLROOT"),  # BINARY, CKPRNT, NOPRNT [wagl]; SLIPRNT, CSVPRNT [ja]
}

#: Appendix A of LeMaster & Eismann (2017), the shipped database's MODTRAN settings, as
#: MODTRAN 6 JSON values (section -> key -> value), with what each stands for.
APPENDIX_A = {
    "RTOPTIONS": {
        # IEMSCT 2 = thermal emission plus solar scatter (WTHEAD's comment): the five
        # database columns; the JSON word is [wagl]'s, [isofit]'s and [ja]'s.
        "IEMSCT": "RT_SOLAR_AND_THERMAL",
        # IMULT 1 (Appendix A: multiple scattering on; WTHEAD: 1 = at the sensor). [ja]'s
        # RT_DISORT_AT_OBS echoes IMULT 1 in its .tp7 card 1. Appendix A does not say
        # whether DISORT or Isaacs two-stream was used: DISORT is an assumption.
        "IMULT": "RT_DISORT_AT_OBS",
    },
    "ATMOSPHERE": {"MODEL": "ATM_MIDLAT_SUMMER"},  # MODEL 2; word from [wagl], [isofit], [ja]
    "AEROSOLS": {
        # IHAZE 1 (23 km) and 2 (5 km) are both rural extinction; with VIS given, the rural
        # model at that visibility (AER_RURAL: [wagl], [isofit], [ja]; VIS: [wagl], [ja]).
        "IHAZE": "AER_RURAL",
        "ICLD": "CLOUD_NONE",  # ICLD 0, no clouds ([wagl]'s word)
        "RAINRT": 0.0,  # no rain
    },
    "GEOMETRY": {
        "ITYPE": 2,  # slant path between two altitudes ([wagl])
        "IPARM": 2,  # PARM1 = relative azimuth, PARM2 = solar zenith ([ja]: IPARM 2, PARM2);
                     # Appendix A does not name IPARM
        "PARM1": 90.0,  # azimuth between the line of sight and the sun [deg]
        "PARM2": 50.0,  # solar zenith angle [deg]
        "IDAY": 236,  # day of year (23 August)
        "H2ALT": 0.0,  # target altitude, km MSL (H2 = 0)
    },
    "SURFACE": {
        "SURFTYPE": "REFL_CONSTANT",  # [wagl], [ja]
        "SURREF": 0.15,  # target reflectance, constant 15 %
        "TPTEMP": 299.0,  # target temperature [K]
        "GNDALT": 0.0,  # ground altitude, km MSL
    },
    "SPECTRAL": {
        # 0.3-14 um by 0.01 um with a 0.02 um slit, written in nanometres (300-14000 nm by
        # 10 nm, FWHM 20 nm): FLAGS(1) = 'N', XFLAG 'N' (micro-W sr-1 cm-2 / nm: WTHEAD's
        # XFLAG comment). The only CSVPRNT spectral column seen in a public file is
        # 'Waveln [nm]', from cases with FLAGS 'N' and XFLAG 'N' (brandon-reade/Qrackling,
        # Python/example.json), so the CSV these cases ask for is one read_modtran_csv
        # reads; their .7sc is then WAVLEN(NM), which read_tape7 reads. YFLAG 'R' radiance.
        "V1": 300.0, "V2": 14000.0, "DV": 10.0, "FWHM": 20.0,
        "YFLAG": "R", "XFLAG": "N", "FLAGS": "NT A   ",
    },
}
#: Settings of Appendix A that MODTRAN 6's JSON cannot take as written there: the background
#: (AATEMP 297 K, SURREFb 'Mixed Forest') was MODTRAN 5's two-surface option; it is recorded
#: in the case's DESCRIPTION, not as keys.
_BACKGROUND = "background AATEMP 297 K, SURREFb 'Mixed Forest' (Appendix A; not written)"


def _case(index, point, visibility, altitude, ground_range, conditions):
    """One MODTRANINPUT for a grid point, Appendix A updated by ``conditions``."""
    case = copy.deepcopy(APPENDIX_A)
    for section, values in conditions.items():
        if not isinstance(values, dict):
            raise ValueError(f"conditions: section {section!r} must map keys to values; got "
                             f"{values!r}")
        case.setdefault(section, {}).update(copy.deepcopy(values))
    geometry = case["GEOMETRY"]
    ground_km = float(case["SURFACE"]["GNDALT"])
    geometry["H1ALT"] = ground_km + altitude / 1e3  # km MSL: the sensor above the ground
    if "H2ALT" not in conditions.get("GEOMETRY", {}):
        geometry["H2ALT"] = ground_km  # the target on the ground (Appendix A: H2 = GNDALT = 0)
    if ground_range == 0.0:
        geometry["OBSZEN"] = 180.0  # straight down: H1ALT, H2ALT and OBSZEN ([wagl], case 2A)
    else:
        # H1ALT, H2ALT and BETA, the Earth-centre angle [deg], on a sphere of xbsm's radius
        # (RAD_E, km): the ground range is then exactly the database's great-circle distance.
        geometry["BETA"] = math.degrees(ground_range / EARTH_RADIUS)
        geometry["RAD_E"] = EARTH_RADIUS / 1e3
    case["AEROSOLS"]["VIS"] = float(visibility)
    name = f"xbsm_v{visibility:g}_a{altitude:g}_g{ground_range:g}".replace(".", "p")
    if point is not None:
        name = f"xbsm_c{point}" + name[4:]
    case["FILEOPTIONS"] = {"NOPRNT": 2, "CSVPRNT": f"{name}.csv", "JSONPRNT": f"{name}.json",
                           **case.get("FILEOPTIONS", {})}
    where = "" if point is None else f"condition point {point}, "
    head = {"NAME": name, "DESCRIPTION": (
        f"xbsm atmosphere table: {where}visibility {visibility:g} km, sensor altitude "
        f"{altitude:g} m above ground, ground range {ground_range:g} m; {_BACKGROUND}"),
        "CASE": index}
    return {"MODTRANINPUT": {**head, **case}}


def _check_keys(document):
    for entry in document["MODTRAN"]:
        top = entry["MODTRANINPUT"]
        for key, value in top.items():
            if key not in MODTRAN6_KEYS["MODTRANINPUT"]:
                raise ValueError(f"conditions: section {key!r} is not a MODTRAN 6 input "
                                 f"section ({', '.join(MODTRAN6_KEYS['MODTRANINPUT'])})")
            if isinstance(value, dict):
                bad = [k for k in value if k not in MODTRAN6_KEYS[key]]
                if bad:
                    raise ValueError(f"conditions: {key} key(s) {bad} are not in "
                                     f"MODTRAN6_KEYS[{key!r}] ({', '.join(MODTRAN6_KEYS[key])})")


def modtran_inputs(grid, conditions=None, *, directory=None, multi_case=True) -> dict:
    """The MODTRAN 6 JSON cases that would compute an atmosphere cube on ``grid``.

    One case per (visibility, altitude, ground range) point inside the horizon, with the
    settings of Appendix A of LeMaster & Eismann (2017) (:data:`APPENDIX_A`: mid-latitude
    summer, rural aerosol, sun 50 deg from zenith and 90 deg in azimuth from the line of
    sight, day 236, target at 299 K with 15 % reflectance on the ground at sea level,
    0.3-14 um by 0.01 um, slit 0.02 um, written as 300-14000 nm by 10 nm, FWHM 20 nm)
    unless ``conditions`` says otherwise. Each case asks for a CSV and a JSON spectral
    output (``FILEOPTIONS``); the CSV, on the nanometre grid, is what
    :func:`read_modtran_csv` reads back; the legacy tape7 and ``.7sc`` files, which
    :func:`read_tape7` reads back, are MODTRAN's to write unless ``FILEOPTIONS`` turns
    them off.

    Parameters
    ----------
    grid : dict or xr.Dataset
        ``altitude`` [m] (sensor above ground), ``ground_range`` [m] and ``visibility``
        [km] (default 23 and 5), each a scalar or a sequence.
    conditions : dict or sequence of dict, optional
        Section -> {key: value} updating :data:`APPENDIX_A`, e.g.
        ``{"ATMOSPHERE": {"MODEL": "ATM_TROPICAL"}, "GEOMETRY": {"PARM2": 30.0}}``; every key
        must be in :data:`MODTRAN6_KEYS`. A sequence of such dicts is a list of condition
        points: the cases are then every condition point x visibility x altitude x ground
        range, named ``xbsm_c<point>_...``.
    directory : str or os.PathLike, optional
        Write the cases there: one ``xbsm_cases.json`` holding them all (``multi_case``,
        MODTRAN 6's ``{"MODTRAN": [case, ...]}``), or one file per case named by its NAME.
    multi_case : bool
        One file for all cases (default) or one per case.

    Returns
    -------
    dict
        ``{"MODTRAN": [{"MODTRANINPUT": {...}}, ...]}``, the cases in (condition point,
        visibility, altitude, ground range) order, ``CASE`` numbering them from 0.

    Raises
    ------
    ValueError
        A coordinate outside its range, or a key of ``conditions`` not in
        :data:`MODTRAN6_KEYS`.
    """
    from .tables import horizon

    def values(name, default=None):
        raw = grid[name] if name in grid else default
        if raw is None:
            raise ValueError(f"grid needs {name!r}")
        return [float(v) for v in np.atleast_1d(np.asarray(raw, dtype=np.float64))]

    altitudes, ranges = values("altitude"), values("ground_range")
    visibilities = values("visibility", [23.0, 5.0])
    for name, vals, closed in (("altitude", altitudes, False), ("ground_range", ranges, True),
                               ("visibility", visibilities, False)):
        bad = [v for v in vals if not (math.isfinite(v) and (v >= 0.0 if closed else v > 0.0))]
        if bad:
            raise ValueError(f"grid {name} must be finite and {'>=' if closed else '>'} 0; "
                             f"got {bad[0]!r}")
    if conditions is None or isinstance(conditions, dict):
        points = [(None, dict(conditions or {}))]
    else:
        points = list(enumerate(dict(c) for c in conditions))
        if not points:
            raise ValueError("conditions must be a dict or a non-empty sequence of dicts")
    cases = []
    for point, condition in points:
        for vis in visibilities:
            for alt in altitudes:
                reach = float(horizon(alt))
                for gr in ranges:
                    if gr > reach:
                        continue
                    cases.append(_case(len(cases), point, vis, alt, gr, condition))
    document = {"MODTRAN": cases}
    _check_keys(document)
    if directory is not None:
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        if multi_case:
            (directory / "xbsm_cases.json").write_text(json.dumps(document, indent=2))
        else:
            for case in cases:
                name = case["MODTRANINPUT"]["NAME"]
                (directory / f"{name}.json").write_text(
                    json.dumps({"MODTRAN": [case]}, indent=2))
    return document
