"""partisim.dask.run_scene_sweep: a table of scene variants over a Dask LocalCluster, equal
to the same runs on one machine, and resumed from its checkpoint when a worker dies."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import partisim
from conftest import PBF, REPO, WEDGE, WEDGE_OBJ

SCENE = REPO / "scenes" / "dam_break.toml"
# Two variants of the quick dam break (12,288 particles, about 0.2 s a frame on one core):
# Jacobi iterations per substep, a setting that changes every frame's positions.
ROWS = [{"solver.solver_iterations": 2}, {"solver.solver_iterations": 3}]
FRAMES = 12
EVERY = 2

# The sweep is written on the scene API (overrides, save, load): skipped until it is there.
_sig = getattr(partisim.Simulation.from_scene, "__text_signature__", "") or ""
needs_scene_api = pytest.mark.skipif(
    not (hasattr(partisim.Simulation, "save") and hasattr(partisim.Simulation, "load")
         and "overrides" in _sig),
    reason="Simulation.from_scene(overrides=...), save and load are not in this build",
)

# Columns that depend on the wall clock or on where the run went, not on the physics.
NOT_PHYSICS = {"wall_s", "resumed_from_frame", "checkpoint"}
# The frame record's wall-clock fields, left out of the table.
WALL_CLOCK = {"phases_s", "total_s"}


def test_override_tables_as_lists_and_dataframes():
    from partisim.dask import _override_rows

    rows = [{"solver.friction_angle_deg": 30.0, "solver.substeps": 6},
            {"solver.friction_angle_deg": 40.0, "solver.substeps": 8}]
    assert _override_rows(rows) == rows
    pd = pytest.importorskip("pandas")
    from_frame = _override_rows(pd.DataFrame(rows))
    assert from_frame == rows
    # numpy scalars from the DataFrame become the plain values a TOML file would hold.
    assert [type(v) for v in from_frame[0].values()] == [float, int]
    with pytest.raises(TypeError, match="a list of dicts or a pandas DataFrame"):
        _override_rows({"solver.substeps": 6})
    with pytest.raises(TypeError, match="overrides row 1"):
        _override_rows([{}, 3])


def test_bad_sweep_arguments_are_named(tmp_path):
    from partisim.dask import run_scene_sweep

    with pytest.raises(FileNotFoundError, match="no_such.toml"):
        run_scene_sweep(None, tmp_path / "no_such.toml", [{}])
    with pytest.raises(ValueError, match="frames = -1"):
        run_scene_sweep(None, SCENE, [{}], frames=-1)
    with pytest.raises(ValueError, match="checkpoint_every = 0"):
        run_scene_sweep(None, SCENE, [{}], checkpoint_every=0)


def one_machine(row: dict):
    sim = partisim.Simulation.from_scene(SCENE, quick=True, overrides=row)
    outcome = sim.run(FRAMES, progress=False)
    return sim, outcome


def test_sweep_of_the_scene_as_written_equals_one_machine():
    """Rows without overrides and no checkpoints: the Dask path alone."""
    distributed = pytest.importorskip("dask.distributed")
    from partisim.dask import run_scene_sweep

    frames = 3
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None,
                                  env={"RAYON_NUM_THREADS": "1"}) as cluster, \
            distributed.Client(cluster) as client:
        table = run_scene_sweep(client, SCENE, [{}, {}], frames=frames, quick=True)
    sim = partisim.Simulation.from_scene(SCENE, quick=True)
    outcome = sim.run(frames, progress=False)
    assert len(table) == 2
    for i in range(2):
        got = table.loc[i]
        assert got["ending"] == outcome["ending"] == "completed" and got["frame"] == frames
        assert got["resumed_from_frame"] == 0 and got["checkpoint"] is None
        for key, value in sim.stats.items():
            if key not in WALL_CLOCK:
                assert got[key] == value, (i, key)
        assert not WALL_CLOCK & set(table.columns)


@needs_scene_api
def test_sweep_survives_a_killed_worker_and_equals_one_machine(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    from partisim.dask import run_scene_sweep

    ckpt_dir = tmp_path / "checkpoints"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None,
                                  env={"RAYON_NUM_THREADS": "1"}) as cluster, \
            distributed.Client(cluster) as client:
        out = {}

        def sweep():
            try:
                out["table"] = run_scene_sweep(client, SCENE, ROWS, frames=FRAMES, quick=True,
                                               checkpoint_dir=ckpt_dir, checkpoint_every=EVERY)
            except BaseException as e:  # surfaced by the assertion below
                out["error"] = e

        thread = threading.Thread(target=sweep)
        thread.start()
        # Wait for run 0's first checkpoint, then kill the worker process running it.
        killed = None
        deadline = time.monotonic() + 120
        while killed is None and time.monotonic() < deadline and thread.is_alive():
            if list(ckpt_dir.glob("run0000-*.partisim")):
                for addr, keys in client.processing().items():
                    if any("scene-run-0000" in str(k) for k in keys):
                        pid = client.run(os.getpid, workers=[addr])[addr]
                        os.kill(pid, signal.SIGKILL)
                        killed = addr
            time.sleep(0.02)
        thread.join(timeout=300)
        assert not thread.is_alive(), "the sweep did not finish"
        assert "error" not in out, out.get("error")
        # The same sweep again: every run is finished, so its row comes from its checkpoint.
        again = run_scene_sweep(client, SCENE, ROWS, frames=FRAMES, quick=True,
                                checkpoint_dir=ckpt_dir, checkpoint_every=EVERY)
    assert killed is not None, "run 0 was never seen running after its first checkpoint"
    table = out["table"]
    assert list(table["solver.solver_iterations"]) == [2, 3]
    # The killed run started again from a checkpoint, not from frame 0.
    assert table.loc[0, "resumed_from_frame"] >= EVERY
    assert table.loc[0, "resumed_from_frame"] % EVERY == 0
    for i, row in enumerate(ROWS):
        sim, outcome = one_machine(row)
        got = table.loc[i]
        assert got["ending"] == outcome["ending"] == "completed"
        assert got["frame"] == FRAMES == sim.frame
        # Every statistic of the final frame record, bit for bit (floats compared exactly).
        for key, value in sim.stats.items():
            if key not in WALL_CLOCK:
                assert got[key] == value, (i, key)
        # The final state kept in the run's checkpoint equals the one-machine run's.
        final = partisim.Simulation.load(got["checkpoint"])
        assert final.frame == FRAMES
        for name in ("positions", "velocities", "densities"):
            assert np.array_equal(getattr(final, name), getattr(sim, name)), (i, name)
    assert list(again["resumed_from_frame"]) == [FRAMES, FRAMES]
    physics = [c for c in table.columns if c not in NOT_PHYSICS]
    assert again[physics].equals(table[physics])
    assert set(table.columns) >= {"ending", "reason", "time_s", "max_density_ratio",
                                  "kinetic_energy_j"} | NOT_PHYSICS


# ---- the at-rest verdict and the repose angle in the sweep's table ----

# The PBF column of 96 particles and 5 frames of 0.02 s, its walls as a collision boundary.
TINY = PBF.replace('"volume-map"', '"collision"')


class WorkerDied(Exception):
    """A worker's death, as the inline client below sees it."""


class InlineClient:
    """Runs each task when submitted, in this process, and runs a task again when its
    worker "died" (as Dask reschedules a dead worker's task): the sweep's checkpoint logic
    without a cluster."""

    def __init__(self):
        self.attempts = 0

    def submit(self, fn, *args, key=None, retries=0, pure=False):
        while True:
            self.attempts += 1
            try:
                return fn(*args)
            except WorkerDied:
                continue

    def gather(self, futures):
        return list(futures)


def test_the_at_rest_verdict_survives_checkpoints_and_a_death(tmp_path, monkeypatch):
    """Every speed is below the bound (1e4 sqrt(g s), 7 km/s; the speeds only): the whole
    run is at rest from t = 0 after 0.06 s (frame 3). With a checkpoint after every frame,
    and the worker dying while writing the third, the verdict is still frame 3 from t = 0:
    the criterion's samples are carried beside each checkpoint."""
    import partisim.dask as pd_mod

    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY)
    rest = {"speed_scale": 1e4, "speed_hold_s": 0.06, "angle_drift_deg": None}
    whole = partisim.Simulation.from_scene(scene, volume_map_cache=None)
    w = whole.run(progress=False, until_rest=rest)
    assert w["at_rest"] is True and w["frame"] == 3 and w["rest_from_s"] == 0.0

    writes = []
    real_write = pd_mod._write_json_atomic

    def dying_write(path, data):
        writes.append(data["frame"])
        if len(writes) == 3:  # the third checkpoint: the worker dies before writing it
            raise WorkerDied()
        real_write(path, data)

    monkeypatch.setattr(pd_mod, "_write_json_atomic", dying_write)
    client = InlineClient()
    table = pd_mod.run_scene_sweep(client, scene, [{}], checkpoint_dir=tmp_path / "ckpt",
                                   checkpoint_every=1, until_rest=rest)
    assert client.attempts == 2 and writes == [1, 2, 3, 3]
    got = table.loc[0]
    assert got["resumed_from_frame"] == 2
    assert got["at_rest"] and got["rest_from_s"] == 0.0 and got["frame"] == 3
    assert got["rest_summary"] == w["rest_summary"]
    assert got["rest_percentile_speed_misses_by"] == 0.0 and got["rest_deep_speed_misses_by"] == 0.0
    assert got["rest_percentile_speed"] == w["rest_margins"]["percentile_speed"]["value"]
    assert got["ending"] == "stopped" and got["reason"] == w["reason"]
    assert np.array_equal(partisim.Simulation.load(got["checkpoint"]).positions,
                          whole.positions)
    # No repose columns: the scene is not granular.
    assert not any(c.startswith("repose_") for c in table.columns)
    # The finished run again: its row from the side file, the verdict with it.
    again = pd_mod.run_scene_sweep(client, scene, [{}], checkpoint_dir=tmp_path / "ckpt",
                                   checkpoint_every=1, until_rest=rest)
    assert again.loc[0, "resumed_from_frame"] == 3 and bool(again.loc[0, "at_rest"])
    assert again.loc[0, "rest_from_s"] == 0.0


def test_granular_runs_get_their_repose_angle(tmp_path):
    import partisim.dask as pd_mod

    (tmp_path / "wedge.obj").write_text(WEDGE_OBJ)
    scene = tmp_path / "wedge.toml"
    scene.write_text(WEDGE)
    rows = [{}, {"solver.friction_angle_deg": 40.0}]
    table = pd_mod.run_scene_sweep(InlineClient(), scene, rows, checkpoint_dir=tmp_path / "c",
                                   checkpoint_every=1)
    for i, row in enumerate(rows):
        sim = partisim.Simulation.from_scene(scene, overrides=row or None,
                                             volume_map_cache=None)
        sim.run(progress=False)
        m = sim.repose()
        got = table.loc[i]
        assert got["repose_error"] is None
        assert got["repose_angle_deg"] == m["angle_deg"]
        assert got["repose_resolution_deg"] == m["resolution_deg"]
        assert got["repose_pile_height_m"] == m["pile_height_m"]
        # The heap measured is the wedge's: 30° within the sampling's resolution.
        assert abs(got["repose_angle_deg"] - 30.0) <= got["repose_resolution_deg"]
    # repose=False: no measurement; options: passed to Simulation.repose.
    off = pd_mod.run_scene_sweep(InlineClient(), scene, [{}], repose=False)
    assert not any(c.startswith("repose_") for c in off.columns)
    flat = pd_mod.run_scene_sweep(InlineClient(), scene, [{}], repose={"min_fit_points": 10**6})
    assert np.isnan(flat.loc[0, "repose_angle_deg"]) and flat.loc[0, "repose_error"]
    with pytest.raises(TypeError, match="repose"):
        pd_mod.run_scene_sweep(InlineClient(), scene, [{}], repose="yes")
