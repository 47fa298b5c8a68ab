"""The ``xbsm`` command: exit codes, one-line errors, signals, figures after a result."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from xbsm import cli, interrupts
from xbsm.atmosphere import database_path, load_database

# 40 altitudes: more panels than the standard figures lay out (issue 21, item 1)
FORTY_ALTITUDES = """
title = "forty altitudes"
[sensor]
preset = "olson"
band = "nir"
[scenario]
platform_speed = 100.0
[sweep]
ground_range = [0.0, 20000.0]
altitude = { start = 1000.0, stop = 20000.0, num = 40 }
visibility = [23.0, 5.0]
"""

# 48 chunks of a few scenarios: long enough to be signalled while computing
FORTY_EIGHT_CHUNKS = """
title = "forty-eight chunks"
[sensor]
preset = "olson"
band = "nir"
[scenario]
altitude = 9000.0
platform_speed = 100.0
[sweep]
ground_range = { start = 0.0, stop = 90e3, num = 48 }
visibility = [23.0, 5.0]
[run]
chunks = { ground_range = 1 }
"""


def _study(tmp_path, text, name="study.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_written_result_exits_0_even_when_its_figures_cannot_be_drawn(tmp_path, capsys):
    study = _study(tmp_path, FORTY_ALTITUDES)
    out = tmp_path / "out.nc"
    assert cli.main(["run", str(study), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    warning = [line for line in err.splitlines() if "warning" in line]
    assert len(warning) == 1 and "xbsm plot" in warning[0] and "--sel" in warning[0]
    with xr.open_dataset(out) as ds:
        assert ds.niirs.sizes["altitude"] == 40
    # the hint, followed: one altitude (nearest) draws the figures
    figures = tmp_path / "figures"
    assert cli.main(["plot", str(out), "--sel", "altitude=3000", "--out", str(figures)]) == 0
    assert sorted(p.name for p in figures.glob("*.png"))


def test_a_run_interrupted_while_drawing_its_figures_does_not_ask_to_resume(tmp_path, capsys,
                                                                            monkeypatch):
    # the result is complete when the figures are drawn: the same command would be refused
    # (the file exists), so the only advice is xbsm plot
    def interrupted(result_file, directory):
        raise interrupts.Interrupted()

    monkeypatch.setattr(cli, "draw", interrupted)
    study = _study(tmp_path, FORTY_ALTITUDES)
    out = tmp_path / "out.nc"
    with pytest.raises(SystemExit) as code:
        cli.main(["run", str(study), "-o", str(out)])
    assert code.value.code == 130
    err = capsys.readouterr().err
    assert "is complete; the figures were interrupted" in err and "xbsm plot" in err
    assert "resume" not in err
    with xr.open_dataset(out) as ds:
        assert ds.niirs.sizes["altitude"] == 40


def test_plot_sel_names_the_dimensions_on_a_wrong_one(tmp_path, capsys):
    study = _study(tmp_path, FORTY_ALTITUDES)
    out = tmp_path / "out.nc"
    cli.main(["run", str(study), "-o", str(out), "--no-figures"])
    capsys.readouterr()
    with pytest.raises(SystemExit) as code:
        cli.main(["plot", str(out), "--sel", "altitud=3000"])
    assert code.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "altitude" in err[0] and "DIM=VALUE" in err[0]


def test_the_study_file_is_never_the_output(tmp_path, capsys):
    study = _study(tmp_path, FORTY_ALTITUDES)
    with pytest.raises(SystemExit) as code:
        cli.main(["run", str(study), "-o", str(study), "--overwrite"])
    assert code.value.code == 2
    assert "study file itself" in capsys.readouterr().err
    assert study.read_text() == FORTY_ALTITUDES


@pytest.mark.parametrize("content", [b"", b"not a NetCDF file\n",
                                     b"\x89HDF\r\n\x1a\n" + b"\0" * 64])
def test_plot_of_a_file_that_is_not_a_result_is_one_line(tmp_path, capsys, content):
    path = tmp_path / "result.nc"
    path.write_bytes(content)
    with pytest.raises(SystemExit) as code:
        cli.main(["plot", str(path)])
    assert code.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a NetCDF result file" in err[0] and str(path) in err[0]


def test_a_damaged_database_is_named_in_one_clear_error(tmp_path):
    # zlib-compressed chunks (the shipped file's encoding): flipped bytes fail HDF5's inflate
    copy = tmp_path / "atmosphere.nc"
    shutil.copy(database_path(), copy)
    data = bytearray(copy.read_bytes())
    for offset in range(len(data) // 3, len(data) // 3 + 4096):
        data[offset] ^= 0xFF
    copy.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"atmosphere database .*atmosphere\.nc is damaged "
                                         r"\(NetCDF/HDF error"):
        load_database(copy)


def test_a_value_error_is_one_line_with_exit_2(tmp_path, capsys, monkeypatch):
    import xbsm.study

    def damaged(path):
        raise ValueError("atmosphere database X is damaged (NetCDF/HDF error): reinstall")

    monkeypatch.setattr(xbsm.study, "load", damaged)
    with pytest.raises(SystemExit) as code:
        cli.main(["run", str(tmp_path / "s.toml"), "-o", str(tmp_path / "o.nc")])
    assert code.value.code == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "xbsm run: atmosphere database X is damaged (NetCDF/HDF error): reinstall"]


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_inside_a_write_waits_for_the_end_of_it(signum, code):
    # the handler only records the signal inside a deferred section (no exception while a
    # library holds a lock); the section's end raises it, with the shell's exit code
    # (Python's own defaults first: a test run started in the background inherits SIGINT
    # ignored, and the handlers leave an ignored signal alone)
    default = signal.default_int_handler if signum == signal.SIGINT else signal.SIG_DFL
    before = signal.signal(signum, default)
    reached = []
    try:
        with interrupts.handling_signals():
            with pytest.raises(interrupts.Interrupted) as err:
                with interrupts.deferred():
                    os.kill(os.getpid(), signum)
                    reached.append("after the signal")
            assert reached == ["after the signal"] and err.value.exit_code == code
        assert signal.getsignal(signum) is default  # the handler is put back
    finally:
        signal.signal(signum, before)
        interrupts.INTERRUPTED.clear()


def test_a_signal_after_the_result_is_in_place_does_not_make_the_run_interrupted():
    # issue 26: a Ctrl-C that landed after a run's completion marker turned a complete run
    # into "interrupted; run the same command again to resume", and the resume was refused
    # as complete. After completing() the signal is recorded, raised only where a caller
    # checks (xbsm run's figures), and a new run starts with a clean slate
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    reached = []
    try:
        with interrupts.handling_signals():
            with interrupts.completing():
                os.kill(os.getpid(), signal.SIGINT)  # during the last rename: waits
                reached.append("the result in place")
            os.kill(os.getpid(), signal.SIGINT)  # after it: recorded, not raised
            reached.append("the lock released")
            with pytest.raises(interrupts.Interrupted):
                interrupts.stop_if_interrupted()  # an explicit check still stops
        assert reached == ["the result in place", "the lock released"]
        with interrupts.handling_signals():  # the next run: interruptible again
            with pytest.raises(interrupts.Interrupted):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1)  # the handler runs between bytecodes, before this ends
    finally:
        signal.signal(signal.SIGINT, before)
        interrupts.INTERRUPTED.clear()


def test_a_signal_inside_completing_that_fails_still_stops_the_run():
    # a failed final rename is no result: the run is not complete, the signal stops it
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with interrupts.handling_signals():
            with pytest.raises(OSError):
                with interrupts.completing():
                    os.kill(os.getpid(), signal.SIGINT)
                    raise OSError("rename refused")
            with pytest.raises(interrupts.Interrupted):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1)
    finally:
        signal.signal(signal.SIGINT, before)
        interrupts.INTERRUPTED.clear()


#: A run in a deferred section that gets SIGINT, and another SIGINT at every line its
#: handler runs (after a function's first line: a lock taken there is held), capped at 4.
_SIGNAL_DURING_THE_HANDLER = """
import os, signal, sys
from xbsm import interrupts

signal.signal(signal.SIGINT, signal.default_int_handler)
handler, sent, seen = interrupts._on_signal.__code__, [], set()

def called_by_handler(frame):
    while frame is not None:
        if frame.f_code is handler:
            return True
        frame = frame.f_back
    return False

def another_signal(frame, event, arg):
    if (event == "return" or (event == "line" and id(frame) in seen)) and len(sent) < 4:
        sent.append(frame.f_code.co_name)
        os.kill(os.getpid(), signal.SIGINT)
    seen.add(id(frame))
    return another_signal

def tracer(frame, event, arg):
    return another_signal if called_by_handler(frame.f_back) else None

with interrupts.handling_signals():
    try:
        with interrupts.deferred():
            sys.settrace(tracer)
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):
                pass
            sys.settrace(None)
    except interrupts.Interrupted:
        sys.settrace(None)
        print("stopped after", len(sent), "more signals")
"""


def test_a_signal_while_the_handler_runs_does_not_hang_the_run():
    # a second Ctrl-C landing while the handler set threading.Event INTERRUPTED (which holds
    # the Event's lock) ran the handler again in the same thread, which waited for that
    # lock for ever; SIGTERM could not end it either (its handler waited too)
    try:
        done = subprocess.run([sys.executable, "-c", _SIGNAL_DURING_THE_HANDLER],
                              capture_output=True, text=True, timeout=30)
    except subprocess.TimeoutExpired:  # (killed by subprocess.run)
        pytest.fail("a signal during the signal handler hung the process")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("stopped after") and "0 more" not in done.stdout


def _as_in_a_terminal():
    # a background child of a non-interactive shell inherits SIGINT ignored (POSIX)
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signalled_run_exits_with_its_code_and_resumes(tmp_path, signum, code):
    study = _study(tmp_path, FORTY_EIGHT_CHUNKS)
    out = tmp_path / "out.nc"
    command = [sys.executable, "-m", "xbsm.cli", "run", str(study), "-o", str(out),
               "--no-figures", "--workers", "1"]
    proc = subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                            text=True, preexec_fn=_as_in_a_terminal)
    for line in proc.stderr:  # off a terminal, progress is a line per 10 %
        if "chunks computed" in line:
            break
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code and "interrupted" in err.strip().splitlines()[-1]
    assert not out.exists() and not (tmp_path / "out.nc.lock").exists()
    saved = len(list((tmp_path / "out.nc.parts").glob("block-*.npz")))
    assert saved >= 1
    resumed = subprocess.run(command, capture_output=True, text=True, timeout=300, check=True)
    assert f"{saved} of 48 chunks already done" in resumed.stderr
    reference = tmp_path / "reference.nc"
    subprocess.run([*command[:5], "-o", str(reference), "--no-figures"], check=True,
                   capture_output=True, timeout=300)
    with xr.open_dataset(out) as a, xr.open_dataset(reference) as b:
        for name in b.data_vars:
            np.testing.assert_array_equal(a[name].values, b[name].values)


def test_progress_off_a_terminal_is_a_line_per_ten_percent(tmp_path):
    # issue 21: a run whose standard error was a file wrote 94 KB of carriage-return updates
    study = _study(tmp_path, FORTY_EIGHT_CHUNKS)
    done = subprocess.run([sys.executable, "-m", "xbsm.cli", "run", str(study), "-o",
                           str(tmp_path / "out.nc"), "--no-figures"], capture_output=True,
                          text=True, timeout=300, check=True)
    lines = done.stderr.splitlines()
    assert "\r" not in done.stderr
    # one line of what is done, then at most 10 per phase (computing, writing the file)
    assert len(lines) <= 21 and sum("chunks computed" in line for line in lines) <= 10
    assert lines[-1].endswith(")") and "100 %" in lines[-1]


def test_a_write_that_fails_is_one_line_naming_the_file_and_keeps_the_chunks(tmp_path):
    # a real failed write (the kernel refuses to grow the file past RLIMIT_FSIZE, as a
    # full disk refuses it): one line with the file and the free space, exit 2, no
    # output, no .partial, every chunk kept for the next run
    import resource

    def limit_file_size():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # EFBIG instead of death
        resource.setrlimit(resource.RLIMIT_FSIZE, (60_000, 60_000))

    study = _study(tmp_path, FORTY_EIGHT_CHUNKS)
    out = tmp_path / "out.nc"
    done = subprocess.run([sys.executable, "-m", "xbsm.cli", "run", str(study), "-o", str(out),
                           "--no-figures"], capture_output=True, text=True, timeout=300,
                          preexec_fn=limit_file_size)
    assert done.returncode == 2
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith(f"xbsm run: cannot write {out}.partial: ") and "MB free" in last
    assert not out.exists() and not (tmp_path / "out.nc.partial").exists()
    assert len(list((tmp_path / "out.nc.parts").glob("block-*.npz"))) == 48


def test_a_failed_write_called_from_python_returns_2_without_ending_the_caller(
        tmp_path, capsys, monkeypatch):
    # `xbsm run` ends its own process at once after a refused write (an old HDF5 crashes at
    # interpreter exit, see xbsm.study.store.WriteFailed), but cli.main([...]) called from
    # Python returns 2 with the same one line and leaves the caller running
    from xbsm.study import store

    def refused(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(store, "_stream", refused)
    out = tmp_path / "out.nc"
    code = cli.main(["run", str(_study(tmp_path, FORTY_EIGHT_CHUNKS)), "-o", str(out),
                     "--no-figures"])
    assert code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith(
        f"xbsm run: cannot write {out}.partial: No space left on device")
    assert not out.exists()
