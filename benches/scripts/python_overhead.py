"""What the Python package adds to the Rust it binds (docs/performance.md).

1. `partisim.neighbour_lists` on 10^6 particles (conversion in and out included) against
   the same Rust call (`benches/examples/neighbour_lists_file.rs`) on the same positions,
   REPEATS alternating runs each, on RAYON_NUM_THREADS threads.
2. `--dask`: a 10^5-comet population advanced YEARS on a 2-worker Dask LocalCluster
   (1 thread per worker) against one process on 2 threads.

Run from the repository root in a virtual environment with `pip install "./python[dask]"`:

    flock /work/bench.lock env RAYON_NUM_THREADS=2 python benches/scripts/python_overhead.py [--dask]
"""

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import partisim

REPEATS = 5
N = 1_000_000
RADIUS = 0.02  # about 33 neighbours per particle in the unit cube


def neighbour_lists():
    rng = np.random.default_rng(2026)
    p = rng.random((N, 3))
    rust, py = [], []
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "positions.bin"
        p.astype("<f8").tofile(f)
        # Rust and Python alternate, so that a change of load on a shared machine hits both;
        # each round is the median of 3 calls in one warm process on each side (the first
        # call of a process pays the page faults of its fresh allocations).
        for _ in range(REPEATS):
            out = subprocess.run(
                ["cargo", "run", "--release", "--quiet", "-p", "benches", "--example",
                 "neighbour_lists_file", "--", str(f), str(RADIUS), "cell-start-grid", "3"],
                check=True, capture_output=True, text=True).stdout
            rust.append(float(out.split("median")[1].split()[0]))
            calls = []
            for _ in range(3):
                t = time.perf_counter()
                offsets, indices = partisim.neighbour_lists(p, RADIUS)
                calls.append(time.perf_counter() - t)
                del offsets, indices
            py.append(statistics.median(calls))
    print(f"neighbour_lists, {N} particles, radius {RADIUS}, "
          f"{os.environ.get('RAYON_NUM_THREADS')} threads, {REPEATS} alternating rounds of 3 calls each:")
    print(f"  Rust   {out.split(',')[1].strip()}, min {min(rust):.6f} s, median {statistics.median(rust):.6f} s")
    print(f"  Python min {min(py):.6f} s, median {statistics.median(py):.6f} s")
    print(f"  ratio of minima {min(py) / min(rust):.3f}, of medians "
          f"{statistics.median(py) / statistics.median(rust):.3f}")


def dask_population(n=100_000, years=500.0):
    from dask.distributed import Client, LocalCluster
    from partisim.dask import run_population_dask

    rng = np.random.default_rng(5)
    q = rng.uniform(32.0, 40.0, n)
    a = rng.uniform(40.0, 100.0, n)
    el = np.column_stack([a, 1 - q / a, rng.uniform(0, 20, n), rng.uniform(0, 360, (n, 3))])
    spec = partisim.PopulationSpec(particles=el, removal={"hill_factor": 1.0, "min_perihelion": 26.0})
    t = time.perf_counter()
    whole = spec.build().advance(years)
    single = time.perf_counter() - t
    env = {"RAYON_NUM_THREADS": "1"}
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      env=env) as cluster, Client(cluster) as client:
        client.submit(lambda: 0).result()  # workers up before the clock starts
        t = time.perf_counter()
        merged = run_population_dask(client, spec, years, shards=2)
        distributed = time.perf_counter() - t
    same = merged.states.tobytes() == whole.states.tobytes()
    print(f"population, {n} comets, {years} years: one process on "
          f"{os.environ.get('RAYON_NUM_THREADS')} threads {single:.3f} s, 2-worker LocalCluster "
          f"{distributed:.3f} s, ratio {distributed / single:.3f}, bit-identical {same}")


if __name__ == "__main__":
    neighbour_lists()
    if "--dask" in sys.argv:
        dask_population()
