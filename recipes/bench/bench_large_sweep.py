"""Benchmark: one lazy xbsm.niirs sweep over many random scenarios, chunked with dask.

Random altitudes (3-15 km) and ground ranges (0-100 km) off the database nodes
(so the atmosphere is interpolated), the Olson NIR camera, 23 km visibility,
chunks of 20,000 scenarios. Prints the time to build the graph, the time to
compute NIIRS (GIQE 3, 4, 5), the time per scenario and the peak resident
memory of the process; ``docs/benchmarks.md`` quotes one run.

Run from the repository root with the project environment (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench/bench_large_sweep.py [--scenarios 200000] [--chunk 20000]
"""

from __future__ import annotations

import argparse
import resource
import time

import dask.array as da
import numpy as np
import xarray as xr

import xbsm
from xbsm.examples import olson_sensor


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", type=int, default=200_000)
    parser.add_argument("--chunk", type=int, default=20_000)
    args = parser.parse_args()
    rng = np.random.default_rng(0)

    def sweep(low, high):
        values = rng.uniform(low, high, args.scenarios)
        return xr.DataArray(da.from_array(values, chunks=args.chunk), dims="case")

    scenario = xbsm.scenario(altitude=sweep(3000.0, 15000.0), ground_range=sweep(0.0, 100e3),
                             visibility=23.0, platform_speed=100.0)
    t0 = time.perf_counter()
    result = xbsm.niirs(olson_sensor("nir"), scenario)
    graph = time.perf_counter() - t0
    t0 = time.perf_counter()
    niirs = result.niirs.compute()
    total = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
    print(f"{args.scenarios} scenarios in chunks of {args.chunk}: graph {graph:.2f} s, "
          f"compute {total:.2f} s = {1e6 * total / args.scenarios:.1f} us/scenario, "
          f"peak RSS {peak:.0f} MB; mean GIQE 3/4/5 "
          + " / ".join(f"{v:.3f}" for v in niirs.mean("case").values))


if __name__ == "__main__":
    main()
