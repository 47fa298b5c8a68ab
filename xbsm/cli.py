"""The ``xbsm`` command: ``run``, ``plot``, ``info`` (and ``olson``, an alias of ``run``).

``xbsm run [STUDY.toml] [-o OUT.nc]`` runs a study file (by default the
paper's first worked example, shipped with the package) lazily in chunks,
writes the NetCDF safely (an interrupted run resumes; the output appears only
when complete) and draws the standard figures. ``xbsm plot OUT.nc`` draws the
figures of any result file; ``xbsm info`` prints the atmosphere database's
coverage, the method presets and the versions.
"""

from __future__ import annotations

import argparse
import signal
import sys
from importlib import resources
from pathlib import Path

import xarray as xr

from . import __version__, plot, study
from .methods import PRESETS
from .study.store import INTERRUPTED, check_output, dependency_versions, stop_if_interrupted

#: The study ``xbsm run`` runs without a study file: the paper's Example 1 (Sec. 3).
DEFAULT_STUDY = "example1.toml"


def default_study_path() -> Path:
    """Path of the study file shipped with the package (paper Example 1)."""
    return Path(str(resources.files("xbsm") / "data" / DEFAULT_STUDY))


def _figure_dir(out: Path) -> Path:
    return out.with_name(out.stem + "_figures")


def run(study_file: Path | None, out: Path | None, *, overwrite=False, scheduler=None,
        workers=None, figures=True, progress=True) -> Path:
    """Load, compute, write and draw one study; return the NetCDF path."""
    spec = study.load(study_file or default_study_path())
    out = out or Path(spec.output or (Path(study_file or DEFAULT_STUDY).stem + ".nc"))
    check_output(out, overwrite)  # before any work
    result = study.run(spec)
    stop_if_interrupted()
    study.write(result, out, overwrite=overwrite, scheduler=scheduler or spec.scheduler,
                workers=workers or spec.workers, progress=progress)
    print(f"wrote {out}")
    if figures:
        draw(out, _figure_dir(out))
    return out


def draw(result_file: Path, directory: Path) -> list[Path]:
    """The standard figures of a result file, written into ``directory``."""
    with xr.open_dataset(result_file) as ds:
        try:
            paths = plot.standard_figures(ds.load(), directory)
        except ValueError as err:  # a result these figures cannot lay out
            raise study.StudyError(f"no standard figures for {result_file}: {err}") from None
    for path in paths:
        print(f"wrote {path}")
    return paths


def info() -> None:
    """Print the atmosphere coverage, the method presets and the versions."""
    from .atmosphere import database_path, open_atmosphere
    atm = open_atmosphere()
    print(f"xbsm {__version__} ({dependency_versions()})")
    print(f"atmosphere database: {database_path()}")
    for dim, units, scale in (("altitude", "km", 1e-3), ("ground_range", "km", 1e-3),
                              ("visibility", "km", 1.0), ("wavelength", "um", 1e6)):
        values = atm[dim].values * scale
        print(f"  {dim}: {len(values)} values from {values.min():g} to {values.max():g} {units}")
    print("method presets: " + ", ".join(sorted(PRESETS)) + " (default accurate)")
    print(f"default study (xbsm run): {default_study_path()}")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="xbsm", description="xbsm imaging-system model")
    sub = parser.add_subparsers(dest="command", required=True)
    run_ = sub.add_parser("run", help="run a study file (default: the paper's Example 1)")
    run_.add_argument("study", nargs="?", type=Path, help="study file (TOML); see docs/study.md")
    run_.add_argument("-o", "--out", type=Path, help="output NetCDF file")
    run_.add_argument("--overwrite", action="store_true", help="replace an existing output")
    run_.add_argument("--scheduler", help="threads, synchronous, local-cluster or an address "
                      "such as tcp://host:8786 (default: the study's, else threads)")
    run_.add_argument("--workers", type=int, help="threads or cluster workers")
    run_.add_argument("--no-figures", action="store_true", help="write only the NetCDF file")
    plot_ = sub.add_parser("plot", help="the standard figures of a result file")
    plot_.add_argument("result", type=Path, help="a NetCDF file written by xbsm run")
    plot_.add_argument("--out", type=Path, help="directory (default: next to the file)")
    sub.add_parser("info", help="atmosphere coverage, method presets, versions")
    olson = sub.add_parser("olson", help="alias of `xbsm run` into a directory")
    olson.add_argument("--out", type=Path, default=Path("olson"), help="output directory")
    return parser


def _on_ctrl_c(signum, frame):
    """Ctrl-C: remember it (for the checks between stages) and raise KeyboardInterrupt."""
    INTERRUPTED.set()
    raise KeyboardInterrupt


def main(argv=None) -> int:
    """Entry point of the ``xbsm`` command."""
    parser = _parser()
    args = parser.parse_args(argv)
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not if ignored
        signal.signal(signal.SIGINT, _on_ctrl_c)
    try:
        if args.command == "run":
            if args.workers is not None and args.workers < 1:
                parser.error(f"--workers must be >= 1; got {args.workers}")
            run(args.study, args.out, overwrite=args.overwrite, scheduler=args.scheduler,
                workers=args.workers, figures=not args.no_figures)
        elif args.command == "olson":
            if args.out.exists() and not args.out.is_dir():
                parser.error(f"--out {args.out} exists and is not a directory")
            args.out.mkdir(parents=True, exist_ok=True)
            run(None, args.out / "example1.nc", overwrite=True)
        elif args.command == "plot":
            if not args.result.is_file():
                parser.error(f"no result file {args.result}")
            draw(args.result, args.out or _figure_dir(args.result))
        else:
            info()
    except study.StudyError as err:
        parser.exit(2, f"xbsm {args.command}: {err}\n")
    except OSError as err:
        parser.exit(2, f"xbsm {args.command}: {err.strerror or err}: {err.filename or ''}\n")
    except KeyboardInterrupt:
        parser.exit(130, f"xbsm {args.command}: interrupted; finished chunks are kept, run the "
                    "same command again to resume (no output file was written)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
