"""The ``xbsm`` command: ``run``, ``simulate``, ``plot``, ``info`` (``olson``: ``run``'s alias).

``xbsm run [STUDY.toml] [-o OUT.nc]`` runs a study file (by default the
paper's first worked example, shipped with the package) lazily in chunks,
writes the NetCDF safely (one run per output; an interrupted run resumes; the
output appears only when complete) and draws the standard figures. ``xbsm
simulate STUDY.toml [-o FOLDER]`` simulates the image dataset of a study's
``[dataset]`` table at every scenario of its sweep (resumable the same way). ``xbsm
plot OUT.nc`` draws the figures of any result file; ``xbsm info`` prints the
atmosphere database's coverage, the method presets and the versions.

Every foreseeable failure is one line on standard error and exit code 2; a
signal is exit code 130 (SIGINT, Ctrl-C) or 143 (SIGTERM) with finished work
kept. The heavy imports happen after the signal handlers are in place, so even
a Ctrl-C while Python imports numpy is one line.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from pathlib import Path

from .interrupts import Interrupted, deferred, handling_signals, stop_if_interrupted

#: The study ``xbsm run`` runs without a study file: the paper's Example 1 (Sec. 3).
DEFAULT_STUDY = "example1.toml"


def default_study_path() -> Path:
    """Path of the study file shipped with the package (paper Example 1)."""
    from importlib import resources

    return Path(str(resources.files("xbsm") / "data" / DEFAULT_STUDY))


def _figure_dir(out: Path) -> Path:
    return out.with_name(out.stem + "_figures")


def run(study_file: Path | None, out: Path | None, *, overwrite=False, scheduler=None,
        workers=None, figures=True, progress=True, atmosphere: Path | None = None) -> Path:
    """Load, compute, write and draw one study; return the NetCDF path.

    A result that is written is a success: figures that cannot be drawn are a
    warning line saying how to draw them (:func:`_draw_or_warn`). ``atmosphere``: a
    database file used for the whole study (:func:`xbsm.atmosphere.use_database`).
    """
    from contextlib import nullcontext

    from . import study
    from .atmosphere import check_supported, use_database
    from .study.store import OutputLock, check_output

    if atmosphere is not None:
        try:
            check_supported(atmosphere)
        except ValueError as err:
            raise study.StudyError(f"--atmosphere {atmosphere}: {err}") from None
    with nullcontext() if atmosphere is None else use_database(atmosphere):
        spec = study.load(study_file or default_study_path())
        out = out or Path(spec.output or (Path(study_file or DEFAULT_STUDY).stem + ".nc"))
        check_output(out, overwrite, study_file)  # before any work
        with OutputLock(out, spec.title):  # a second run on this output is refused at once
            result = study.run(spec)
            stop_if_interrupted()
            study.write(result, out, overwrite=overwrite,
                        scheduler=scheduler or spec.scheduler,
                        workers=workers or spec.workers, progress=progress)
    print(f"wrote {out}")
    if figures:
        _draw_or_warn(out, _figure_dir(out))
    return out


def simulate(study_file: Path, out: Path | None, *, overwrite=False, workers=None,
             progress=True) -> Path:
    """Load a study with a ``[dataset]`` table and simulate its dataset; return the folder."""
    from . import study

    spec = study.load(study_file)
    if spec.dataset is None:
        raise study.StudyError(f"{study_file} has no [dataset] table; `xbsm simulate` needs one "
                               "(docs/datasets.md); `xbsm run` runs other studies")
    folder = study.simulate(spec, out, overwrite=overwrite, workers=workers, progress=progress)
    print(f"wrote {folder}")
    return folder


def _open_result(result_file: Path):
    """The result file, loaded; a StudyError if it is not a NetCDF file xbsm can read."""
    import xarray as xr

    from .study import StudyError

    try:
        with xr.open_dataset(result_file) as ds:
            return ds.load()
    except (OSError, ValueError, RuntimeError) as err:
        raise StudyError(f"{result_file} is not a NetCDF result file that xbsm can read "
                         f"({type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''})"
                         ) from None


def _select(ds, selections: list[str]):
    """``ds`` at ``DIM=VALUE`` selections: nearest for numbers, exact for names."""
    from .study import StudyError

    for text in selections or []:
        dim, sep, value = text.partition("=")
        if not sep or dim not in ds.dims:
            raise StudyError(f"--sel {text!r}: give DIM=VALUE with DIM one of "
                             f"{', '.join(map(str, ds.dims))}")
        try:
            number = float(value)
        except ValueError:
            if value not in ds[dim].values.astype(str):
                raise StudyError(f"--sel {text!r}: {dim} has no value {value!r}; it has "
                                 f"{', '.join(ds[dim].values.astype(str)[:10])}") from None
            ds = ds.sel({dim: value})
        else:
            ds = ds.sel({dim: number}, method="nearest")
    return ds


def draw(result_file: Path, directory: Path, selections=None) -> list[Path]:
    """The standard figures of a result file (at ``DIM=VALUE`` selections) in ``directory``."""
    from . import plot
    from .study import StudyError

    ds = _select(_open_result(result_file), selections)
    try:
        paths = plot.standard_figures(ds, directory)
    except ValueError as err:  # a result these figures cannot lay out
        raise StudyError(f"no standard figures for {result_file}: {err}") from None
    for path in paths:
        print(f"wrote {path}")
    return paths


def _draw_or_warn(result_file: Path, directory: Path) -> list[Path]:
    """:func:`draw`, but a figure that cannot be drawn is a warning line, not a failure."""
    from .study import StudyError

    try:
        with deferred():  # a signal waits for the figure being drawn (never inside matplotlib)
            return draw(result_file, directory)
    except Interrupted as err:
        print(f"xbsm run: {result_file} is complete; the figures were interrupted: draw them "
              f"with `xbsm plot {result_file}`", file=sys.stderr)
        err.result_complete = True  # main then says nothing of resuming: a rerun is refused
        raise
    except (StudyError, OSError, ValueError, RuntimeError) as err:
        print(f"xbsm run: warning: {result_file} is complete, but its standard figures were "
              f"not drawn ({err}); draw them with `xbsm plot {result_file} --sel DIM=VALUE`",
              file=sys.stderr)
        return []


def info(atmosphere=None) -> None:
    """Print the atmosphere coverage, the method presets and the versions.

    ``atmosphere``: another database file (validated as ``xbsm run --atmosphere`` does);
    its conditions besides visibility (aerosol model, model atmosphere, sun, ...) are
    listed with the values it holds.
    """
    from ._version import __version__
    from .atmosphere import (
        database_conditions,
        database_path,
        listed,
        open_atmosphere,
        use_database,
    )
    from .methods import PRESETS
    from .study.store import dependency_versions

    with use_database(atmosphere) if atmosphere is not None else contextlib.nullcontext():
        atm = open_atmosphere()
        print(f"xbsm {__version__} ({dependency_versions()})")
        print(f"atmosphere database: {database_path()}")
        for dim, units, scale in (("altitude", "km", 1e-3), ("ground_range", "km", 1e-3),
                                  ("visibility", "km", 1.0), ("wavelength", "um", 1e6)):
            values = atm[dim].values * scale
            print(f"  {dim}: {len(values)} values from {values.min():g} to {values.max():g} "
                  f"{units}")
        for name, values in database_conditions().items():
            if name != "visibility":
                print(f"  {name}: {listed(name, values)}")
    print("method presets: " + ", ".join(sorted(PRESETS)) + " (default accurate)")
    print(f"default study (xbsm run): {default_study_path()}")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="xbsm", description="xbsm imaging-system model")
    sub = parser.add_subparsers(dest="command", required=True)
    run_ = sub.add_parser("run", help="run a study file (default: the paper's Example 1)")
    run_.add_argument("study", nargs="?", type=Path, help="study file (TOML); see docs/study.md")
    run_.add_argument("-o", "--out", type=Path, help="output NetCDF file")
    run_.add_argument("--overwrite", action="store_true",
                      help="compute again and replace an existing output")
    run_.add_argument("--scheduler", help="threads, synchronous, local-cluster or an address "
                      "such as tcp://host:8786 (default: the study's, else threads)")
    run_.add_argument("--workers", type=int, help="threads or cluster workers")
    run_.add_argument("--no-figures", action="store_true", help="write only the NetCDF file")
    run_.add_argument("--atmosphere", type=Path, metavar="FILE",
                      help="atmosphere database file for the whole study (default: the "
                           "shipped one); see docs/atmosphere.md")
    sim = sub.add_parser("simulate", help="simulate a study's image dataset ([dataset] table) "
                         "at every scenario of its sweep")
    sim.add_argument("study", type=Path, help="study file (TOML) with a [dataset] table; see "
                     "docs/datasets.md")
    sim.add_argument("-o", "--out", type=Path, help="output folder (default: the table's output)")
    sim.add_argument("--overwrite", action="store_true",
                     help="compute again and replace a finished run's outputs")
    sim.add_argument("--workers", type=int, help="threads (default: the study's)")
    plot_ = sub.add_parser("plot", help="the standard figures of a result file")
    plot_.add_argument("result", type=Path, help="a NetCDF file written by xbsm run")
    plot_.add_argument("--out", type=Path, help="directory (default: next to the file)")
    plot_.add_argument("--sel", action="append", metavar="DIM=VALUE",
                       help="draw at one value of a dimension (nearest for numbers); repeatable, "
                            "e.g. --sel altitude=3000 --sel visibility=23")
    info_ = sub.add_parser("info", help="atmosphere coverage, method presets, versions")
    info_.add_argument("--atmosphere", type=Path, metavar="FILE",
                       help="another atmosphere database file: its coverage and conditions")
    olson = sub.add_parser("olson", help="alias of `xbsm run` into a directory")
    olson.add_argument("--out", type=Path, default=Path("olson"), help="output directory")
    return parser


def _command(parser, args) -> None:
    if args.command == "run":
        if args.workers is not None and args.workers < 1:
            parser.error(f"--workers must be >= 1; got {args.workers}")
        run(args.study, args.out, overwrite=args.overwrite, scheduler=args.scheduler,
            workers=args.workers, figures=not args.no_figures, atmosphere=args.atmosphere)
    elif args.command == "simulate":
        if args.workers is not None and args.workers < 1:
            parser.error(f"--workers must be >= 1; got {args.workers}")
        simulate(args.study, args.out, overwrite=args.overwrite, workers=args.workers)
    elif args.command == "olson":
        if args.out.exists() and not args.out.is_dir():
            parser.error(f"--out {args.out} exists and is not a directory")
        args.out.mkdir(parents=True, exist_ok=True)
        run(None, args.out / "example1.nc", overwrite=True)
    elif args.command == "plot":
        if not args.result.is_file():
            parser.error(f"no result file {args.result}")
        draw(args.result, args.out or _figure_dir(args.result), args.sel)
    else:
        info(args.atmosphere)


def _exit_past_hdf5(code: int) -> None:
    """End the process without the interpreter's shutdown, where HDF5 may crash.

    A HDF5 library that has refused a write may crash at exit (see
    :class:`xbsm.study.store.WriteFailed`); every file of ours is already closed, removed
    or kept as intended, and the output lock released.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def main(argv=None) -> int:
    """Entry point of the ``xbsm`` command."""
    parser = _parser()
    args = parser.parse_args(argv)
    # the command itself ignores signals once its outcome is decided (a Ctrl-C while the
    # interpreter shuts down is no traceback); a caller's main([...]) gets its own back
    with handling_signals(until_exit=argv is None):
        try:
            from .study import StudyError  # the heavy imports, under the handlers
            from .study.store import WriteFailed

            try:
                _command(parser, args)
            except WriteFailed as err:
                print(f"xbsm {args.command}: {err}", file=sys.stderr)
                if argv is None:  # the command itself, not a caller's main([...])
                    _exit_past_hdf5(2)
                return 2
            except StudyError as err:
                parser.exit(2, f"xbsm {args.command}: {err}\n")
            except OSError as err:
                parser.exit(2, f"xbsm {args.command}: {err.strerror or err}: "
                            f"{err.filename or ''}\n")
            except ValueError as err:  # a damaged or foreign database, an impossible value
                parser.exit(2, f"xbsm {args.command}: {err}\n")
        except KeyboardInterrupt as err:
            code = getattr(err, "exit_code", 130)
            if getattr(err, "result_complete", False):  # only the figures were cut short
                parser.exit(code)
            parser.exit(code, f"xbsm {args.command}: interrupted; finished chunks are kept, run "
                        "the same command again to resume\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
