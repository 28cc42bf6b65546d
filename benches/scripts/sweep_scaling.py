"""A scene sweep on one Dask worker against two (docs/performance.md).

`partisim.dask.run_scene_sweep` runs RUNS quick dam breaks (12,288 particles, FRAMES frames
each, the Jacobi iterations per substep varied over the rows) on a LocalCluster of one
worker and on one of two workers, one thread each (RAYON_NUM_THREADS=1 in the workers), the
workers started before the clock; REPEATS rounds alternate the two so that a change of load
on a shared machine hits both. Checkpoints every EVERY frames into a fresh directory, as a
sweep on a cluster would write them. Prints each round's wall times and the speed-up.

Run from the repository root in a virtual environment with the wheel and its dask extra:

    flock /tmp/build.lock python benches/scripts/sweep_scaling.py [--plain]

`--plain`: RUNS copies of the scene as written, without checkpoints (what a build without
scene overrides and `Simulation.save` can run).
"""

import statistics
import sys
import tempfile
import time
from pathlib import Path

from dask.distributed import Client, LocalCluster

from partisim.dask import run_scene_sweep

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "dam_break.toml"
RUNS = 8
FRAMES = 15
EVERY = 5
REPEATS = 3
ROWS = [{"solver.solver_iterations": 2 + i % 4, "solver.vorticity_epsilon": 0.0001 * (i // 4)}
        for i in range(RUNS)]


def _import_partisim() -> None:
    import partisim  # noqa: F401


PLAIN = "--plain" in sys.argv[1:]


def sweep(client: Client) -> float:
    with tempfile.TemporaryDirectory() as d:
        start = time.perf_counter()
        if PLAIN:
            table = run_scene_sweep(client, SCENE, [{}] * RUNS, frames=FRAMES, quick=True)
        else:
            table = run_scene_sweep(client, SCENE, ROWS, frames=FRAMES, quick=True,
                                    checkpoint_dir=d, checkpoint_every=EVERY)
        wall = time.perf_counter() - start
    assert (table["ending"] == "completed").all() and (table["frame"] == FRAMES).all()
    return wall


def main() -> None:
    clusters = {
        n: LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                        dashboard_address=None, env={"RAYON_NUM_THREADS": "1"})
        for n in (1, 2)
    }
    clients = {n: Client(c) for n, c in clusters.items()}
    try:
        for client in clients.values():  # workers import partisim before the clock
            client.wait_for_workers(len(client.scheduler_info()["workers"]))
            client.run(_import_partisim)
        times = {1: [], 2: []}
        for r in range(REPEATS):
            for n in ((1, 2) if r % 2 == 0 else (2, 1)):
                times[n].append(sweep(clients[n]))
            print(f"round {r + 1}: 1 worker {times[1][-1]:.2f} s, 2 workers {times[2][-1]:.2f} s,"
                  f" speed-up {times[1][-1] / times[2][-1]:.2f}", flush=True)
        m1, m2 = statistics.median(times[1]), statistics.median(times[2])
        print(f"{RUNS} runs x {FRAMES} frames: median 1 worker {m1:.2f} s, 2 workers {m2:.2f} s,"
              f" speed-up {m1 / m2:.2f} (target >= 1.7)")
    finally:
        for client in clients.values():
            client.close()
        for cluster in clusters.values():
            cluster.close()


if __name__ == "__main__":
    main()
