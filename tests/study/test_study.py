"""Studies: lazy build, safe resumable writing, range performance (xbsm.study)."""

import math
import subprocess
import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import dask
import numpy as np
import pytest
import xarray as xr
from dask.highlevelgraph import HighLevelGraph
from scipy.stats import norm

import xbsm
import xbsm.cli
from xbsm import interrupts, study
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.study import _parts, store
from xbsm.study.store import OutputLock

TINY = """
title = "tiny"
[sensor]
preset = "olson"
band = "nir"
[scenario]
altitude = 9000.0
platform_speed = 100.0
[sweep]
ground_range = [0.0, 20000.0, 60000.0]
visibility = [23.0, 5.0]
[run]
chunks = { ground_range = 1 }
"""

MILLION = """
[sensor]
preset = "olson"
[scenario]
platform_speed = 100.0
[sweep]
ground_range = { start = 0.0, stop = 100e3, num = 100 }
altitude = { start = 3000.0, stop = 15000.0, num = 10 }
focal_length = { start = 2.0, stop = 6.0, num = 10 }
visibility = [23.0, 5.0]
drift_rate_x = { start = 0.0, stop = 500e-6, num = 50 }
"""


def _raise_on_compute(*args, **kwargs):
    raise AssertionError("something was computed")


@pytest.fixture(scope="module")
def tiny():
    return study.parse(TINY, "tiny.toml")


def test_a_million_scenario_study_builds_without_computing():
    spec = study.parse(MILLION, "million.toml")
    assert spec.scenarios == 10**6
    with dask.config.set(scheduler=_raise_on_compute):
        result = study.run(spec)
    assert result.niirs.shape == (100, 10, 10, 2, 50, 3)
    assert result.niirs.data.npartitions > 1
    assert set(result.attrs) >= {"xbsm_study", "xbsm_method", "xbsm_knob_edge_rule"}


def test_study_equals_the_direct_model_call(tiny, tmp_path):
    # the same numbers from xbsm.niirs called directly on the same inputs
    direct = xbsm.niirs(olson_sensor("nir"), olson_scenario(
        ground_range=xr.DataArray([0.0, 20e3, 60e3], dims="ground_range"),
        visibility=xr.DataArray([23.0, 5.0], dims="visibility")))
    # (to rounding: a chunk of the study and the whole call may take other numpy paths; on
    # the newest versions they agree bit for bit, on the floors to about 1e-15)
    lazy = study.run(tiny)
    xr.testing.assert_allclose(lazy.niirs.compute().transpose(*direct.niirs.dims), direct.niirs,
                               rtol=1e-12, atol=0)
    path = study.write(lazy, tmp_path / "tiny.nc")
    with xr.open_dataset(path) as written:
        xr.testing.assert_allclose(written.niirs.transpose(*direct.niirs.dims), direct.niirs,
                                   rtol=1e-12, atol=0)
        assert written.attrs["xbsm_atmosphere_sha256"] == store.atmosphere_checksum()
        assert "numpy" in written.attrs["xbsm_dependencies"]
    assert not list(tmp_path.glob("*.parts")) and not list(tmp_path.glob("*.partial"))


_SAVE = _parts.save  # the real chunk saver, before any test replaces it


def _stop_after(count, saved):
    """A chunk saver that saves ``count`` chunks, then stops as if Ctrl-C arrived."""
    real = _SAVE

    def save(file, arrays, print_):
        if len(saved) == count:
            raise KeyboardInterrupt
        saved.append(file.name)
        real(file, arrays, print_)

    return save


def test_rerun_computes_only_the_missing_chunks(tiny, tmp_path, monkeypatch):
    result = study.run(tiny)
    path = tmp_path / "out.nc"
    saved = []
    monkeypatch.setattr(_parts, "save", _stop_after(2, saved))
    with pytest.raises(KeyboardInterrupt):
        study.write(result, path, scheduler="synchronous")
    assert not path.exists() and len(list((tmp_path / "out.nc.parts").glob("*.npz"))) == 2
    resumed = []
    monkeypatch.setattr(_parts, "save", _stop_after(99, resumed))
    study.write(study.run(tiny), path, scheduler="synchronous")
    assert len(resumed) == 1 and resumed[0] not in saved  # 3 chunks: only the third computed
    with xr.open_dataset(path) as written:
        xr.testing.assert_equal(written.niirs, result.niirs.compute())
    assert not (tmp_path / "out.nc.lock").exists()


def test_an_interrupted_finish_leaves_no_output(tiny, tmp_path, monkeypatch):
    def interrupted(*args, **kwargs):  # once OUT.nc.partial exists
        assert (tmp_path / "out.nc.partial").exists()
        raise KeyboardInterrupt

    monkeypatch.setattr(store, "write_variables", interrupted)
    path = tmp_path / "out.nc"
    with pytest.raises(KeyboardInterrupt):
        study.write(study.run(tiny), path, scheduler="synchronous")
    assert not path.exists() and not (tmp_path / "out.nc.partial").exists()
    assert len(list((tmp_path / "out.nc.parts").glob("*.npz"))) == 3  # work kept


def test_parts_without_a_readable_fingerprint_are_set_aside(tiny, tmp_path, capsys):
    path = tmp_path / "out.nc"
    parts = tmp_path / "out.nc.parts"
    parts.mkdir()
    (parts / "study.json").write_text('{"fingerprint": "another study"}')
    (parts / "block-0-0.npz").write_bytes(b"stale")
    study.write(study.run(tiny), path, scheduler="synchronous")
    with xr.open_dataset(path) as written:
        assert np.isfinite(written.niirs).all()
    aside = list(tmp_path.glob("out.nc.parts.set-aside-*"))
    assert len(aside) == 1 and (aside[0] / "block-0-0.npz").read_bytes() == b"stale"
    assert "set aside" in capsys.readouterr().err


@pytest.mark.parametrize(("entry", "words"), [
    ("atmosphere", "atmosphere database"), ("code", "xbsm's code"), ("numpy", "numpy version"),
    ("xbsm", "xbsm version"), ("study", "study or its method")])
def test_parts_of_another_fingerprint_are_set_aside_never_mixed(tiny, tmp_path, monkeypatch,
                                                                capsys, entry, words):
    # a run interrupted after two chunks, resumed with one input of the numbers changed:
    # nothing of the first run may be reused, and one line says what differs
    path = tmp_path / "out.nc"
    first = []
    monkeypatch.setattr(_parts, "save", _stop_after(2, first))
    with pytest.raises(KeyboardInterrupt):
        study.write(study.run(tiny), path, scheduler="synchronous")
    real = _parts.fingerprint
    monkeypatch.setattr(_parts, "fingerprint", lambda r: {**real(r), entry: "changed"})
    second = []
    monkeypatch.setattr(_parts, "save", _stop_after(99, second))
    study.write(study.run(tiny), path, scheduler="synchronous")
    assert len(second) == 3  # every chunk computed again
    err = capsys.readouterr().err
    assert words in err and "set aside" in err and len(err.strip().splitlines()) == 1
    (aside,) = tmp_path.glob("out.nc.parts.set-aside-*")
    assert sorted(f.name for f in aside.glob("block-*.npz")) == sorted(first)


@pytest.mark.parametrize("damage", ["truncate", "flip", "swap"])
def test_a_damaged_chunk_file_is_computed_again(tiny, tmp_path, monkeypatch, capsys, damage):
    path = tmp_path / "out.nc"
    first = []
    monkeypatch.setattr(_parts, "save", _stop_after(2, first))
    with pytest.raises(KeyboardInterrupt):
        study.write(study.run(tiny), path, scheduler="synchronous")
    victim = tmp_path / "out.nc.parts" / first[0]
    data = bytearray(victim.read_bytes())
    if damage == "swap":  # the other chunk's whole file under this chunk's name
        data = bytearray((tmp_path / "out.nc.parts" / first[1]).read_bytes())
    elif damage == "truncate":
        data = data[: len(data) // 2]
    else:  # one bit of the stored SNR values (npz members are stored uncompressed)
        with np.load(victim) as saved:
            where = bytes(data).find(saved["snr"].tobytes())
        assert where > 0
        data[where + 3] ^= 0x10
    victim.write_bytes(bytes(data))
    second = []
    monkeypatch.setattr(_parts, "save", _stop_after(99, second))
    study.write(study.run(tiny), path, scheduler="synchronous")
    assert len(second) == 2 and first[0] in second  # the damaged one and the never-saved one
    assert "did not verify" in capsys.readouterr().err
    with xr.open_dataset(path) as written:
        xr.testing.assert_equal(written.niirs, study.run(tiny).niirs.compute())


def test_a_second_writer_of_one_output_is_refused(tiny, tmp_path):
    # another process holds the output's lock (the lock is re-entrant within a process)
    path = tmp_path / "out.nc"
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from pathlib import Path; "
         "from xbsm.study.store import OutputLock\n"
         "with OutputLock(Path(sys.argv[1]), 'study A'):\n"
         "    print('locked', flush=True); time.sleep(60)", str(path)],
        stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(study.StudyError) as err:
            study.write(study.run(tiny), path, scheduler="synchronous")
    finally:
        holder.kill()
        holder.communicate()
    message = str(err.value)
    assert f"process {holder.pid}" in message and "study A" in message
    assert "\n" not in message and not path.exists()


def test_the_lock_is_reentrant_within_a_process(tiny, tmp_path):
    # the command holds it from before the study is built, and write() takes it again
    path = tmp_path / "out.nc"
    with OutputLock(path, "study A"):
        study.write(study.run(tiny), path, scheduler="synchronous")
        assert (tmp_path / "out.nc.lock").exists()
    assert path.exists() and not (tmp_path / "out.nc.lock").exists()


def test_a_second_thread_writing_one_output_is_refused(tiny, tmp_path):
    # the lock was re-entrant across threads: two threads writing one output both ran,
    # and one failed on the other's chunk files (FileNotFoundError, 1 of 3 races)
    path = tmp_path / "out.nc"
    with OutputLock(path, "study A"), ThreadPoolExecutor(1) as pool:
        other = pool.submit(study.write, study.run(tiny), path, scheduler="synchronous")
        with pytest.raises(study.StudyError, match="being written by"):
            other.result()
    assert not path.exists()


def test_two_threads_taking_one_lock_at_once_are_told_apart(tmp_path):
    # both threads found the output not held, and the one the kernel refused was told
    # "another process" (130 of 300 such races before the lock table had a lock)
    for i in range(50):
        path = tmp_path / f"out{i}.nc"
        start, done, refusals = threading.Barrier(2), threading.Barrier(2), []

        def take(path, start, done, refusals):
            start.wait()
            try:
                with OutputLock(path, "study A"):
                    done.wait()
            except study.StudyError as err:
                refusals.append(str(err))
                done.wait()

        threads = [threading.Thread(target=take, args=(path, start, done, refusals))
                   for _ in range(2)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        assert len(refusals) == 1 and "another thread of this process" in refusals[0]
        assert not (tmp_path / f"out{i}.nc.lock").exists()


def test_the_lock_of_a_dead_process_is_taken_over(tiny, tmp_path):
    # a lock file left by a killed run: the kernel's lock died with its process
    path = tmp_path / "out.nc"
    (tmp_path / "out.nc.lock").write_text('{"pid": 999999999, "host": "h", "study": "s", '
                                          '"started": "t"}')
    study.write(study.run(tiny), path, scheduler="synchronous")
    assert path.exists() and not (tmp_path / "out.nc.lock").exists()


def test_setup_culls_the_graph_once_per_batch_not_per_chunk(tmp_path, monkeypatch):
    # the review measured one cull per chunk (quadratic set-up); 40 chunks are one batch
    spec = study.parse(TINY.replace("[0.0, 20000.0, 60000.0]",
                                    "{ start = 0.0, stop = 60e3, num = 40 }"), "forty.toml")
    calls = []
    real = HighLevelGraph.cull
    monkeypatch.setattr(HighLevelGraph, "cull", lambda self, keys: (calls.append(len(keys)),
                                                                    real(self, keys))[1])
    study.write(study.run(spec), tmp_path / "out.nc", scheduler="synchronous", workers=1)
    assert len(calls) == math.ceil(40 / store._BATCH_PER_WORKER)


def test_existing_output_needs_overwrite(tiny, tmp_path):
    path = tmp_path / "out.nc"
    path.write_text("precious")
    with pytest.raises(study.StudyError, match="--overwrite"):
        study.write(study.run(tiny), path)
    assert path.read_text() == "precious"


def test_chunks_follow_the_study(tiny):
    assert study.chunk_sizes(tiny) == {"ground_range": 1, "visibility": 2}
    spec = study.parse(MILLION.replace("[sweep]", "[run]\nchunk_scenarios = 1000\n[sweep]"))
    chunks = study.chunk_sizes(spec)
    assert np.prod(list(chunks.values())) <= 1000
    assert study.run(spec).niirs.chunks[:5] == tuple(
        tuple(min(c, n - i) for i in range(0, n, c))
        for c, n in zip(chunks.values(), spec.sizes.values(), strict=True))


def test_chunks_cut_first_the_dims_every_output_varies_along():
    # every output of MILLION varies along ground_range and altitude, the SNR terms not
    # along drift_rate_x: ground_range (the longest) is cut just enough, 50,000 / (10 x 10
    # x 2 x 50) = 5 long, and drift_rate_x stays whole, so no chunk repeats the SNR chain
    spec = study.parse(MILLION.replace("[sweep]", "[run]\nchunk_scenarios = 50000\n[sweep]"))
    assert study.chunk_sizes(spec) == {"ground_range": 5, "altitude": 10, "focal_length": 10,
                                       "visibility": 2, "drift_rate_x": 50}
    # 30 cuts every other dim to 1 (visibility last of them: only gsd, slant range and
    # elevation do not vary along it), then the drift rate into blocks of equal length:
    # 50 in 2 blocks of 25, not 30 + 20
    spec = study.parse(MILLION.replace("[sweep]", "[run]\nchunk_scenarios = 30\n[sweep]"))
    assert study.chunk_sizes(spec) == {"ground_range": 1, "altitude": 1, "focal_length": 1,
                                       "visibility": 1, "drift_rate_x": 25}


def test_local_cluster_workers_keep_glibc_heap_trimming(monkeypatch):
    # distributed sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which turns off
    # glibc's adaptive mmap threshold: every large temporary was mmapped and faulted
    # in again (a chunk of recipes/studies/million.toml 0.64 s instead of 0.36 s)
    pytest.importorskip("distributed")
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    with store._distributed_client("local-cluster", 1) as client:
        seen = client.run(lambda: __import__("os").environ.get("MALLOC_TRIM_THRESHOLD_"))
        assert list(seen.values()) == [None]
        threads = client.run(lambda: __import__("os").environ.get("OMP_NUM_THREADS"))
        assert list(threads.values()) == ["1"]  # distributed's other settings stay


def test_local_cluster_workers_run_without_the_profiler():
    # distributed's profiler thread cost a worker 13 % of its CPU (19 % more than the
    # computing thread used, 6 % without)
    pytest.importorskip("distributed")
    with store._distributed_client("local-cluster", 1) as client:
        seen = client.run(lambda: dask.config.get("distributed.worker.profile.enabled"))
        assert list(seen.values()) == [False]


@pytest.mark.skipif(not store._FORK, reason="workers are forked on Linux only")
def test_local_cluster_workers_start_with_xbsm_imported():
    # forked from this process (imported, database read): spawned workers imported xbsm
    # and made a slow first model call before their first chunk, 2.7-2.9 s on 2 cores
    pytest.importorskip("distributed")
    with store._distributed_client("local-cluster", 1) as client:
        seen = client.run(lambda: "xbsm.study.build" in __import__("sys").modules)
        assert list(seen.values()) == [True]


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="no fork")
@pytest.mark.filterwarnings("ignore:This process:DeprecationWarning")  # fork with threads
def test_a_forked_child_does_not_keep_the_output_lock(tmp_path):
    # flock belongs to the open file a fork shares: a worker outliving a killed run
    # would keep its output locked
    import os

    with OutputLock(tmp_path / "out.nc", "s") as lock:
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: is the lock's file descriptor still open here?
            try:
                os.fstat(lock.fd)
                os.write(write, b"open")
            except OSError:
                os.write(write, b"shut")
            os._exit(0)
        os.close(write)
        assert os.read(read, 4) == b"shut"
        os.waitpid(pid, 0)
        os.close(read)


def test_distributed_local_cluster(tiny, tmp_path):
    pytest.importorskip("distributed")
    path = study.write(study.run(tiny), tmp_path / "out.nc", scheduler="local-cluster",
                       workers=1)
    with xr.open_dataset(path) as written:
        assert written.niirs.shape == (3, 2, 3)


# --- CF details, output variables and compression (issue 21 item 7) ----------------------

CF_STUDY = """
title = "cf"
[sensor]
preset = "olson"
band = ["red", "nir"]
[scenario]
altitude = 9000.0
platform_speed = 100.0
[sweep]
ground_range = [0.0, 20000.0, 60000.0]
visibility = [23.0, 5.0]
[outputs]
include = ["niirs", "mtf"]
mtf_frequency = { start = 0.0, stop = 5e5, num = 5 }
"""


@pytest.fixture(scope="module")
def cf_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cf") / "cf.nc"
    study.write(study.run(study.parse(CF_STUDY)), path, scheduler="synchronous")
    return path


def test_written_study_names_its_flags_and_explains_them(cf_file):
    import netCDF4

    with netCDF4.Dataset(cf_file) as nc:  # what ncdump -h shows
        names = set(nc.variables)
        for name, var in nc.variables.items():
            if name in nc.dimensions:  # coordinate variables: no fill value (CF 2.5.1)
                assert "_FillValue" not in var.ncattrs(), name
            elif name not in ("flags", "mtf_flags") and name not in ("wavelength_min",
                                                                     "wavelength_max"):
                flag = "mtf_flags" if name.startswith("mtf_") else "flags"
                assert var.getncattr("ancillary_variables") == flag, name
                assert flag in names
        assert nc.variables["giqe"].getncattr("units") == "1"
        assert nc.variables["giqe"].dtype == np.int32  # CF 1.8 has no 64-bit integers
        comment = nc.variables["flags"].getncattr("comment")
        assert "band, ground_range, visibility, giqe" in comment
        assert "apply to niirs only, per GIQE version" in comment
        assert "gsd" in comment and "snr" in comment  # the variables it describes
        assert "mtf_system" in nc.variables["mtf_flags"].getncattr("comment")
        assert "history" in nc.ncattrs()


def test_written_study_passes_the_cf_checker(cf_file):
    # compliance-checker (IOOS, the package index's CF 1.8 checker; it carries its own
    # standard-name table, so it runs offline): no error and no warning. Before issue 21
    # it found 4 errors (int64 giqe, _FillValue on 3 coordinates) and 1 warning (history)
    # on example1.nc.
    pytest.importorskip("compliance_checker")
    import json
    import warnings

    from compliance_checker.runner import CheckSuite, ComplianceChecker

    report = cf_file.with_suffix(".json")
    with warnings.catch_warnings():  # its own deprecation of its IOOS SOS suites
        warnings.simplefilter("ignore")
        CheckSuite().load_all_available_checkers()
        ComplianceChecker.run_checker(str(cf_file), ["cf:1.8"], 0, "normal",
                                      output_filename=str(report), output_format="json")
    results = json.loads(report.read_text())["cf:1.8"]
    messages = {group: [m for r in results[group] for m in r["msgs"]]
                for group in ("high_priorities", "medium_priorities")}
    assert messages == {"high_priorities": [], "medium_priorities": []}


def test_every_output_variable_name_is_known_to_the_study_file():
    # [outputs] variables is checked when the file is read against these lists; they are
    # exactly what the model writes (a study with both output groups and no selection)
    from xbsm.study.spec import MTF_VARIABLES, NIIRS_VARIABLES

    result = study.run(study.parse(CF_STUDY))
    assert set(result.data_vars) == set(NIIRS_VARIABLES) | set(MTF_VARIABLES)


def test_output_variables_keep_only_those_and_their_flags():
    text = CF_STUDY.replace('mtf_frequency', 'variables = ["niirs", "mtf_system"]\nmtf_frequency')
    result = study.run(study.parse(text))
    assert set(result.data_vars) == {"niirs", "mtf_system", "flags", "mtf_flags"}
    assert "frequency" in result.coords and "orientation" in result.coords
    niirs_only = study.run(study.parse(TINY.replace("[run]", '[outputs]\nvariables = ["niirs"]'
                                                               "\n[run]")))
    assert set(niirs_only.data_vars) == {"niirs", "flags"}
    xr.testing.assert_equal(niirs_only.niirs.compute(), study.run(tiny_spec()).niirs.compute())


def tiny_spec():
    return study.parse(TINY, "tiny.toml")


def test_compress_writes_every_data_variable_with_zlib_at_that_level(tmp_path):
    import netCDF4

    plain = study.run(tiny_spec())
    packed = study.run(study.parse(TINY.replace("[run]", "[run]\ncompress = 4")))
    arrays = [name for name, var in packed.data_vars.items() if var.ndim]  # scalars: whole
    assert len(arrays) > 20
    assert all(packed[name].encoding == {"zlib": True, "complevel": 4, "shuffle": True}
               for name in arrays)
    assert not any(var.encoding.get("zlib") for var in plain.data_vars.values())
    for name, result in (("plain", plain), ("packed", packed)):
        path = study.write(result, tmp_path / f"{name}.nc", scheduler="synchronous")
        with netCDF4.Dataset(path) as nc:
            for var_name in arrays:
                filters = nc.variables[var_name].filters()
                assert bool(filters["zlib"]) == (name == "packed"), var_name
                assert filters["complevel"] == (4 if name == "packed" else 0), var_name
        with xr.open_dataset(path) as back:  # lossless
            xr.testing.assert_equal(back.niirs, plain.niirs.compute())


def test_cf_encoding_is_what_a_writer_passes_to_to_netcdf(tmp_path):
    from xbsm.study._cf import cf_encoding

    result = study.run(study.parse(TINY.replace("[run]", "[run]\ncompress = 2"))).compute()
    encoding = cf_encoding(result)
    assert encoding["ground_range"] == {"_FillValue": None}
    assert encoding["niirs"] == {"zlib": True, "complevel": 2, "shuffle": True}
    bare = result.copy()
    for var in bare.variables.values():
        var.encoding = {}  # a writer that rebuilt the variables and lost their encoding
    bare.to_netcdf(tmp_path / "out.nc", encoding=encoding)
    with xr.open_dataset(tmp_path / "out.nc") as back:
        assert back.niirs.encoding["complevel"] == 2
        assert "_FillValue" not in back.ground_range.encoding


# --- range performance ------------------------------------------------------------------


def _line(values, coords, dim="ground_range"):
    return xr.DataArray(np.asarray(values, dtype=float), dims=dim,
                        coords={dim: (dim, coords, {"units": "m"})})


def test_max_range_interpolates_the_crossing():
    # NIIRS 8, 7, 5, 3 at 0, 10, 20, 30 km: 6 is crossed halfway from 10 to 20 km (linear)
    niirs = _line([8, 7, 5, 3], [0.0, 10e3, 20e3, 30e3])
    out = study.max_range(niirs, 6.0)
    assert float(out.max_range) == pytest.approx(15e3, rel=1e-12)
    assert int(out.goal_flags) == 0
    assert out.max_range.attrs["units"] == "m"


def test_max_range_bounds_and_misses_are_flagged():
    niirs = _line([8, 7, 5, 3], [0.0, 10e3, 20e3, 30e3])
    never = study.max_range(niirs, 9.0)
    assert np.isnan(float(never.max_range))
    assert int(never.goal_flags) == study.goals.GOAL_FLAGS["never_meets"]
    always = study.max_range(niirs, 1.0)
    assert float(always.max_range) == 30e3
    assert int(always.goal_flags) == study.goals.GOAL_FLAGS["bound_at_grid_edge"]


def test_max_range_stops_at_an_invalid_cell():
    # the third cell is beyond the database: the search ends at 10 km, flagged
    niirs = _line([8, 7, 7, 6.5], [0.0, 10e3, 20e3, 30e3])
    flags = xr.zeros_like(niirs, dtype=np.int32)
    flags[2] = xbsm.flags.flag("beyond_database")
    out = study.max_range(niirs, 6.0, flags=flags)
    assert float(out.max_range) == 10e3
    assert int(out.goal_flags) == study.goals.GOAL_FLAGS["invalid_cell"]


def test_min_parameter_over_other_dimensions_at_once():
    # NIIRS rising with aperture; two visibilities with different crossings
    d = np.array([0.1, 0.2, 0.3, 0.4])
    niirs = xr.DataArray([[4.0, 5.0, 6.0, 7.0], [3.0, 4.0, 4.5, 5.5]],
                         dims=("visibility", "aperture_diameter"),
                         coords={"aperture_diameter": d, "visibility": [23.0, 5.0]})
    out = study.min_parameter(niirs, 5.0, "aperture_diameter")
    # 5.0 is met first at 0.2 (vis 23: exactly) and between 0.3 (4.5) and 0.4 (5.5) for vis 5
    np.testing.assert_allclose(out.min_aperture_diameter.values, [0.2, 0.35], rtol=1e-12)


def test_max_range_says_when_it_lands_outside_the_calibration():
    # NIIRS 8, 7, 5, 3 at 0-30 km: 6 is crossed between 10 and 20 km; the 20 km cell has
    # elevation_out_of_range (a calibration bit, xbsm.flags.CALIBRATION), so the answer is
    # interpolated from an extrapolated cell and says so, with the cells' own flags
    niirs = _line([8, 7, 5, 3], [0.0, 10e3, 20e3, 30e3])
    flags = xr.zeros_like(niirs, dtype=np.int32).assign_attrs(xbsm.flags.flag_attrs())
    flags[2:] = xbsm.flags.flag("elevation_out_of_range")
    out = study.max_range(niirs, 6.0, flags=flags)
    assert float(out.max_range) == pytest.approx(15e3, rel=1e-12)
    assert int(out.goal_flags) == study.goals.GOAL_FLAGS["outside_calibration"]
    assert bool(xbsm.flags.decode(out.goal_flags).outside_calibration)
    assert bool(xbsm.flags.decode(out.flags).elevation_out_of_range)
    assert bool(xbsm.flags.is_outside_calibration(out.flags))
    # a requirement met exactly on the calibrated 10 km cell (7) uses that cell only
    exact = study.max_range(niirs, 7.0, flags=flags)
    assert float(exact.max_range) == 10e3 and int(exact.goal_flags) == 0
    assert int(exact.flags) == 0


def test_min_parameter_says_when_it_lands_outside_the_calibration():
    # NIIRS 4, 6, 8 over apertures 0.1, 0.2, 0.3 m: 5 is met between 0.1 and 0.2 m; the
    # 0.1 m cell has rer_out_of_range and q_out_of_range (xbsm.flags.CALIBRATION)
    d = np.array([0.1, 0.2, 0.3])
    niirs = _line([4.0, 6.0, 8.0], d, dim="aperture_diameter")
    flags = xr.zeros_like(niirs, dtype=np.int32).assign_attrs(xbsm.flags.flag_attrs())
    flags[0] = xbsm.flags.flag("rer_out_of_range") | xbsm.flags.flag("q_out_of_range")
    out = study.min_parameter(niirs, 5.0, "aperture_diameter", flags=flags)
    assert float(out.min_aperture_diameter) == pytest.approx(0.15, rel=1e-12)
    assert int(out.goal_flags) == study.goals.GOAL_FLAGS["outside_calibration"]
    bits = xbsm.flags.decode(out.flags)
    assert bool(bits.rer_out_of_range) and bool(bits.q_out_of_range)
    # 6 is met first, exactly, at 0.2 m (calibrated): nothing to say
    assert int(study.min_parameter(niirs, 6.0, "aperture_diameter", flags=flags).goal_flags) == 0


def test_max_range_on_a_model_result_flags_a_low_elevation_answer():
    # the Olson camera at 1 km altitude (xbsm.examples): far ground ranges look at a few
    # degrees of elevation, outside every GIQE's calibration (xbsm.metrics.GIQE_CALIBRATIONS)
    ranges = xr.DataArray(np.linspace(0.0, 30e3, 16), dims="ground_range")
    n = xbsm.niirs(olson_sensor(), olson_scenario(ground_range=ranges, altitude=1000.0,
                                                  visibility=23.0))
    niirs5, flags5 = n.niirs.sel(giqe=5), n.flags.sel(giqe=5)
    assert niirs5.dims == ("ground_range",)
    low = float(niirs5.min()) + 0.01
    out = study.max_range(niirs5, low, flags=flags5)
    assert bool(xbsm.flags.decode(out.flags).elevation_out_of_range)
    assert int(out.goal_flags) & study.goals.GOAL_FLAGS["outside_calibration"]


def test_probability_meets_is_named_for_what_it_is():
    p = study.probability_meets(xr.DataArray([5.0], name="niirs"), 5.0)
    assert p.name == "probability_meets"


def test_goals_on_a_study_result_stay_lazy(tiny):
    result = study.run(tiny)
    with dask.config.set(scheduler=_raise_on_compute):
        out = study.max_range(result.niirs, 7.0, flags=result.flags)
    assert out.max_range.chunks is not None
    eager = study.max_range(result.niirs.compute(), 7.0, flags=result.flags.compute())
    xr.testing.assert_equal(out.compute(), eager)


def test_probability_meets_is_the_normal_cdf():
    # P(N >= T) for N ~ Normal(prediction, 0.35): scipy.stats.norm as the reference
    niirs = xr.DataArray([5.0, 5.35, 4.3])
    p = study.probability_meets(niirs, 5.0)
    np.testing.assert_allclose(p.values, norm.cdf((niirs.values - 5.0) / 0.35), rtol=1e-14)
    assert float(p[0]) == 0.5
    with pytest.raises(ValueError, match="standard_error"):
        study.probability_meets(niirs, 5.0, standard_error=0.0)


def test_default_study_layout_with_pybsm_numerics_reproduces_pybsm():
    # Example 1's study (both bands, both visibilities) with method "pybsm" at two points
    # of pybsm_test_cases.md computed with pyBSM 0.16.1: A5 (NIR, 23 km visibility = ihaze 1,
    # 20 km ground range) and A6 (red, 5 km visibility = ihaze 2, nadir)
    text = xbsm.cli.default_study_path().read_text()
    text = text.replace('ground_range = "database"', "ground_range = [0.0, 20000.0]")
    text = text.replace('preset = "accurate"', 'preset = "pybsm"')
    text = text.replace('include = ["niirs", "mtf"]', 'include = ["niirs"]').replace(
        "mtf_frequency", "# mtf_frequency")
    result = study.run(study.parse(text)).compute()
    a5 = result.niirs.sel(band="nir", visibility=23.0, ground_range=20e3)
    a6 = result.niirs.sel(band="red", visibility=5.0, ground_range=0.0)
    for point, expected in ((a5, (8.180362337723714, 6.990223083421799, 8.252057802116985)),
                            (a6, (9.522427179922438, 8.895972852352036, 9.802914580025174))):
        np.testing.assert_allclose(point.values, expected, rtol=0, atol=1e-8)


def test_a_swallowed_ctrl_c_still_stops_the_run(tiny, tmp_path, monkeypatch):
    # the Ctrl-C handler records the signal besides raising; a library that swallows the
    # KeyboardInterrupt cannot keep the run going: it stops after the chunk being saved
    real = _SAVE

    def save_then_signal(file, arrays, print_):
        real(file, arrays, print_)
        interrupts.INTERRUPTED.set()  # as the handler does, its exception lost

    monkeypatch.setattr(_parts, "save", save_then_signal)
    with pytest.raises(KeyboardInterrupt):
        study.write(study.run(tiny), tmp_path / "out.nc", scheduler="synchronous")
    interrupts.INTERRUPTED.clear()
    assert not (tmp_path / "out.nc").exists()
    assert len(list((tmp_path / "out.nc.parts").glob("*.npz"))) == 1  # its work kept


@pytest.mark.parametrize("window", ["during the rename", "after it"])
def test_a_ctrl_c_once_the_file_is_in_place_leaves_a_finished_run(tiny, tmp_path, monkeypatch,
                                                                  window):
    # issue 26: a signal that landed after OUT.nc had its name made the run "interrupted"
    # (resume, which then refused: "exists"). Once the file is in place the run has
    # succeeded: write returns the path, the lock and the parts are gone
    import os
    import signal

    real_replace, real_rmtree = os.replace, store.shutil.rmtree

    def replace_then_signal(src, dst):  # (os.replace: the chunk files' too)
        real_replace(src, dst)
        if str(dst).endswith("out.nc"):
            os.kill(os.getpid(), signal.SIGINT)

    def signal_then_rmtree(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        real_rmtree(*args, **kwargs)

    if window == "during the rename":
        monkeypatch.setattr(store.os, "replace", replace_then_signal)
    else:
        monkeypatch.setattr(store.shutil, "rmtree", signal_then_rmtree)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        out = study.write(study.run(tiny), tmp_path / "out.nc", scheduler="synchronous")
    except interrupts.Interrupted:  # (a KeyboardInterrupt would stop the whole test run)
        pytest.fail("a run whose file was in place was reported interrupted")
    finally:
        signal.signal(signal.SIGINT, before)
        interrupts.INTERRUPTED.clear()
    assert out.exists() and not (tmp_path / "out.nc.parts").exists()
    assert not (tmp_path / "out.nc.lock").exists()
    with xr.open_dataset(out) as ds:
        assert ds.niirs.notnull().all()


def test_written_result_records_its_fixed_parameters_for_the_figures(tmp_path):
    # xbsm.study.attributes: the parameters of the study file below, read back from the
    # NetCDF file without parsing the study text (a curve, a kernel and two bands)
    from xbsm.study.attributes import parameters_of

    text = """
[sensor]
aperture_diameter = 0.2
focal_length = 3.0
pixel_pitch_x = 10e-6
quantum_efficiency = { wavelength = [0.5e-6, 0.7e-6, 0.9e-6], values = [0.4, 0.6, 0.3] }
filter_kernel = [[0.0, -0.25, 0.0], [-0.25, 2.0, -0.25], [0.0, -0.25, 0.0]]
[bands.green]
wavelength_min = 0.5e-6
wavelength_max = 0.6e-6
[bands.red]
wavelength_min = 0.6e-6
wavelength_max = 0.7e-6
[scenario]
altitude = 3000.0
visibility = 23.0
[sweep]
ground_range = [5000.0, 20000.0]
[outputs]
variables = ["snr"]
"""
    path = tmp_path / "out.nc"
    study.write(study.run(study.parse(text)), path)
    with xr.open_dataset(path) as ds:
        sensor, scenario = parameters_of(ds, band=1)
    assert scenario == {"altitude": 3000.0, "visibility": 23.0}
    assert sensor["focal_length"] == 3.0 and sensor["wavelength_min"] == 0.6e-6
    assert list(sensor["quantum_efficiency"].values) == [0.4, 0.6, 0.3]
    assert list(sensor["quantum_efficiency"]["wavelength"].values) == [0.5e-6, 0.7e-6, 0.9e-6]
    assert sensor["filter_kernel"].shape == (3, 3) and sensor["filter_kernel"][1, 1] == 2.0
    xbsm.sensor(**sensor)  # a sensor again


def test_a_result_without_the_attributes_records_no_parameters():
    # a result written before xbsm.study.attributes existed carries only xbsm_study
    from xbsm.study.attributes import parameters_of

    assert parameters_of(xr.Dataset(attrs={"xbsm_study": "[sensor]\n"}), band=0) == ({}, {})


def test_each_variable_is_stored_in_chunks_of_the_study_blocks(tiny, tmp_path):
    # a block cut along an inner dim is one contiguous HDF5 chunk write, not many
    # strided pieces (recipes/studies/optics_million.toml: assembly 2.7 s for 50 chunks)
    import netCDF4

    path = study.write(study.run(tiny), tmp_path / "out.nc", scheduler="synchronous")
    with netCDF4.Dataset(path) as nc:
        # tiny: ground_range chunks of 1 ([run] chunks), visibility 2 whole, giqe 3
        assert nc["niirs"].chunking() == [1, 2, 3]
        assert nc["gsd"].chunking() == [1]
        assert nc["noise_gain"].chunking() == "contiguous"
