"""partisim.dask.run_population_dask with checkpoints: Centaurs through their encounters,
killed after a checkpoint and resumed, end bit for bit as one uninterrupted process."""

import csv

import numpy as np
import pytest

import partisim
from conftest import REPO
from partisim import PopulationSpec

INITIAL = REPO / "reference-data" / "centaur-population" / "initial_1000.csv"
YEARS = 3000.0
EVERY = 1000.0


# Comets of the experiment's initial states: the first eight that MERCURIUS ended within
# 1.1 kyr (`mercurius_ends_1000.csv`; so some end here too) and four others, in identifier
# order (the order the merged shards come back in).
IDS = sorted([961, 924, 614, 664, 419, 475, 139, 880, 0, 1, 2, 3])


def centaurs(n=len(IDS)):
    """``n`` comets of ``IDS`` with the settings of ``populations/centaurs.toml``
    (encounters integrated, its end rules)."""
    with open(INITIAL) as f:
        rows = {int(r["id"]): r for r in csv.DictReader(f) if r["kind"] == "particle"}
    ids = IDS[:n]
    states = np.array([[float(rows[i][c]) for c in ("x", "y", "z", "vx", "vy", "vz")]
                       for i in ids])
    return PopulationSpec(
        particles=states, ids=np.array(ids, dtype=np.uint64), kind="barycentric_state",
        planet_step_days=91.3125, b1=4e-6,
        initial_step_days=20.0,
        removal={"min_perihelion": 2.5, "ejection_distance": 100.0},
        encounters={"hill_factor": 3.0, "hand_back_hill_factor": 3.5, "tolerance": 1e-12},
    )


def same(a: partisim.Population, b: partisim.Population):
    assert np.array_equal(a.ids, b.ids)
    assert a.states.tobytes() == b.states.tobytes()  # bit for bit
    assert a.status == b.status
    assert a.particle_steps == b.particle_steps
    ta, tb = a.table(), b.table()
    assert ta["time_days"].tobytes() == tb["time_days"].tobytes()  # each comet's end time


class Killed(BaseException):
    """The process running the call dies (not an error a task would report)."""


class InlineClient:
    """Runs each task in this process when gathered, as a worker would."""

    def submit(self, fn, *args, key=None, retries=0, pure=False):
        return (fn, args)

    def gather(self, futures):
        return [fn(*args) for fn, args in futures]


def test_a_killed_run_resumes_bit_for_bit(tmp_path, monkeypatch):
    whole = centaurs().build().advance(YEARS, progress=False)
    from partisim.dask import run_population_dask

    saves = []
    real_save = partisim.Population.save

    def save_then_die(self, path):
        real_save(self, path)
        saves.append(path)
        if len(saves) == 2:  # shard 0's first checkpoint, then shard 0's second: killed
            raise Killed()

    monkeypatch.setattr(partisim.Population, "save", save_then_die)
    with pytest.raises(Killed):
        run_population_dask(InlineClient(), centaurs(), YEARS, shards=2,
                            checkpoint_dir=tmp_path, checkpoint_every_years=EVERY)
    monkeypatch.setattr(partisim.Population, "save", real_save)
    files = sorted(tmp_path.glob("shard*.population"))
    assert [f.name[:9] for f in files] == ["shard0000"]
    assert partisim.Population.load(files[0]).time_years == pytest.approx(2 * EVERY)
    # Started again: shard 0 goes on from 2 kyr, shard 1 from the epoch.
    advanced_from = []
    real_advance = partisim.Population.advance

    def watch(self, to_years, **kw):
        advanced_from.append(round(self.time_years))
        return real_advance(self, to_years, **kw)

    monkeypatch.setattr(partisim.Population, "advance", watch)
    resumed = run_population_dask(InlineClient(), centaurs(), YEARS, shards=2,
                                  checkpoint_dir=tmp_path, checkpoint_every_years=EVERY)
    assert advanced_from == [2000, 0, 1000, 2000]
    same(resumed, whole)
    assert not all(s == "active" for s in whole.status), "no comet ended: the test sees no end"
    # Once more: both shards finished, loaded without a step.
    advanced_from.clear()
    again = run_population_dask(InlineClient(), centaurs(), YEARS, shards=2,
                                checkpoint_dir=tmp_path, checkpoint_every_years=EVERY)
    assert advanced_from == []
    same(again, whole)
    # Another end time is another run: its checkpoints are not these.
    assert len(list(tmp_path.glob("shard*.population"))) == 2


def test_checkpointed_local_cluster_equals_one_process(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    from partisim.dask import run_population_dask

    whole = centaurs().build().advance(YEARS, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        merged = run_population_dask(client, centaurs(), YEARS, shards=3,
                                     checkpoint_dir=tmp_path, checkpoint_every_years=EVERY)
    same(merged, whole)
    assert len(list(tmp_path.glob("shard*.population"))) == 3


@pytest.mark.parametrize("every", [0.0, -1.0, float("nan"), True, "10"])
def test_bad_checkpoint_cadence_is_named(every):
    from partisim.dask import run_population_dask

    with pytest.raises(ValueError, match="checkpoint_every_years"):
        run_population_dask(InlineClient(), centaurs(2), 10.0, checkpoint_every_years=every)
