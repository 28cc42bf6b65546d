"""The 1,000 Centaurs of `centaur-population --full` on Dask workers, resumable: the initial
states of reference-data/centaur-population/initial_1000.csv with the settings of
populations/centaurs.toml, split into chunks of comets (one Dask task each), every chunk
checkpointed atomically at a cadence of simulated time into CHECKPOINT_DIR. Killed and
started again with the same arguments, it goes on from the checkpoints, bit for bit.

Needs partisim with its Dask extra in a virtual environment (`pip install "./python[dask]"`).
Run from the workspace root:
    python benches/scripts/centaurs_dask.py CHECKPOINT_DIR ENDS_CSV [YEARS] [WORKERS] [CHUNKS] [EVERY_YEARS] [COMPARE_CSV]

YEARS = 1e6, WORKERS = 2 (one thread each), CHUNKS = 8, EVERY_YEARS = 1e5 by default.
ENDS_CSV gets `id,end,end_time_years` (the columns of the experiment's ours_ends.csv; `inf`
for active); COMPARE_CSV (such an ours_ends.csv) is compared with it row by row, exactly.
"""
import csv
import math
import sys
import time
from pathlib import Path

import numpy as np
from dask.distributed import Client, LocalCluster

import partisim
from partisim import PopulationSpec
from partisim.dask import run_population_dask

ROOT = Path(__file__).resolve().parents[2]
INITIAL = ROOT / "reference-data" / "centaur-population" / "initial_1000.csv"
YEAR_DAYS = 365.25


def spec() -> PopulationSpec:
    """populations/centaurs.toml's settings, with the comets of INITIAL."""
    with open(INITIAL) as f:
        rows = [r for r in csv.DictReader(f) if r["kind"] == "particle"]
    states = np.array([[float(r[c]) for c in ("x", "y", "z", "vx", "vy", "vz")] for r in rows])
    ids = np.array([int(r["id"]) for r in rows], dtype=np.uint64)
    return PopulationSpec(
        particles=states, ids=ids, kind="barycentric_state",
        planet_scheme="s6", planet_step_days=91.3125, variant="barycentric", scheme="s2",
        b0=0.0, b1=4e-6, initial_step_days=20.0,
        removal={"min_perihelion": 2.5, "ejection_distance": 100.0},
        encounters={"hill_factor": 3.0, "hand_back_hill_factor": 3.5, "tolerance": 1e-12},
    )


def ends(population: partisim.Population, years: float):
    """(id, end label, end time in years or inf) per comet, as the experiment writes them."""
    table = population.table()
    out = []
    for i, status, t in zip(table["id"], table["status"], table["removal_time_days"]):
        t_years = float(t) / YEAR_DAYS
        if status == "active" or t_years > years:
            out.append((int(i), "active", math.inf))
        else:
            out.append((int(i), status, t_years))
    return out


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    ckpt, out = Path(args[0]), Path(args[1])
    years = float(args[2]) if len(args) > 2 else 1e6
    workers = int(args[3]) if len(args) > 3 else 2
    chunks = int(args[4]) if len(args) > 4 else 8
    every = float(args[5]) if len(args) > 5 else 1e5
    start = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None, env={"RAYON_NUM_THREADS": "1"}) as cluster, \
            Client(cluster) as client:
        population = run_population_dask(client, spec(), years, shards=chunks,
                                         checkpoint_dir=ckpt, checkpoint_every_years=every)
    wall = time.perf_counter() - start
    rows = ends(population, years)
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["id", "end", "end_time_years"])
        for i, label, t in rows:
            w.writerow([i, label, "inf" if math.isinf(t) else repr(t)])
    counts = {}
    for _, label, _ in rows:
        counts[label] = counts.get(label, 0) + 1
    print(f"comets={len(rows)} years={years:g} workers={workers} chunks={chunks} "
          f"wall_s={wall:.1f} " + " ".join(f"{k}={v}" for k, v in sorted(counts.items())))
    if len(args) > 6:
        with open(args[6]) as f:
            theirs = [(int(r["id"]), r["end"], float(r["end_time_years"])) for r in csv.DictReader(f)]
        differ = [(a, b) for a, b in zip(rows, theirs) if a != b]
        print(f"compared with {args[6]}: {len(theirs)} rows, {len(differ)} differ"
              + (f"; first: {differ[0]}" if differ else ""))


if __name__ == "__main__":
    main()
