"""Work spread over a Dask cluster (optional: ``pip install "partisim[dask]"``).

- :func:`run_population_dask`: one comet population split into shards. Each task receives
  the :class:`~partisim.PopulationSpec` settings and its shard's particles only, builds the
  planets itself from the same initial state, advances and returns its shard; the shards are
  merged in identifier order. A particle's trajectory depends only on its own initial state
  and the planet grid, so the result is bit-identical to one process. With a checkpoint
  directory each shard is saved at a cadence of simulated time, and a shard whose worker
  died, or a whole run killed and started again, goes on from its checkpoint, bit for bit.
- :func:`run_scene_sweep`: a study of scene variants (a base scene file and a table of
  overrides: a friction-angle sweep, a resolution study, a parameter scan), one task per
  run, each run checkpointed into a shared directory and resumed from its latest
  checkpoint when its worker dies; the results come back as one table.

On one machine::

    from dask.distributed import Client, LocalCluster
    client = Client(LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None))

On a cluster, point the same call at a real scheduler, e.g. Slurm with ``dask-jobqueue``::

    from dask_jobqueue import SLURMCluster     # or PBSCluster, SGECluster, ...
    cluster = SLURMCluster(cores=32, memory="64GB", walltime="12:00:00")
    cluster.scale(jobs=8)                       # 8 batch jobs of 32 cores
    client = Client(cluster)                    # or Client("tcp://scheduler:8786")

Every worker needs ``partisim`` installed (the same version). Each task uses all the
threads of its worker process (rayon): give a worker process several cores, or set
``RAYON_NUM_THREADS`` in the worker's environment. ``python/README.md`` has a complete
Slurm and PBS recipe for scene sweeps.
"""

from __future__ import annotations

import hashlib
import json
import operator
import os
import time
import uuid
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from .comets import Population, PopulationSpec


def _shard_key(spec: PopulationSpec, to_years: float, every_years: Optional[float]) -> str:
    """A digest of everything that defines a shard's run (its settings, particles,
    identifiers, end time and checkpoint cadence), naming its checkpoint: a checkpoint of
    another run is never resumed."""
    h = hashlib.sha256()
    h.update(spec.settings_json().encode())
    h.update(spec.kind.encode())
    h.update(np.ascontiguousarray(spec.particles).tobytes())
    if spec.ids is not None:
        h.update(np.ascontiguousarray(spec.ids).tobytes())
    h.update(json.dumps([float(to_years), every_years]).encode())
    return h.hexdigest()[:16]


def _next_stop(time_years: float, every_years: Optional[float], to_years: float) -> float:
    """The next checkpoint time after ``time_years``: the next multiple of ``every_years``
    from the epoch (so that a resumed shard stops where the uninterrupted one did), or
    ``to_years``."""
    if every_years is None:
        return to_years
    # A stop lands on its multiple exactly; the margin keeps it from being taken again.
    k = int(np.floor(time_years / every_years + 1e-9)) + 1
    return min(k * every_years, to_years)


def _run_shard(
    spec: PopulationSpec,
    to_years: float,
    checkpoint: Optional[str] = None,
    every_years: Optional[float] = None,
) -> Population:
    """One shard (the Dask task): from its checkpoint if there is one, else from its
    specification; with ``checkpoint``, the shard is saved there (atomically, by
    :meth:`Population.save`) at every multiple of ``every_years`` and at the end."""
    ckpt = Path(checkpoint) if checkpoint is not None else None
    if ckpt is not None and ckpt.exists():
        population = Population.load(str(ckpt))
    else:
        population = spec.build()
    while population.time_years < to_years:
        population.advance(_next_stop(population.time_years, every_years, to_years),
                           progress=False)
        if ckpt is not None:
            population.save(str(ckpt))
    return population


def run_population_dask(
    client: Any,
    population_spec: PopulationSpec,
    to_years: float,
    shards: int = 2,
    checkpoint_dir: Optional[Union[str, os.PathLike]] = None,
    checkpoint_every_years: Optional[float] = None,
    retries: int = 0,
) -> Population:
    """Advances a population to ``to_years`` (years after the planets' epoch) as
    ``shards`` Dask tasks on ``client`` and merges them; resumable with ``checkpoint_dir``.

    Parameters
    ----------
    client : dask.distributed.Client
        Any client: a ``LocalCluster``, a ``dask-jobqueue`` cluster, a remote scheduler.
    population_spec : PopulationSpec
        The population at its epoch.
    to_years : float
        End time (years after the planets' epoch).
    shards : int
        Number of tasks (>= 1); the particles are split into contiguous blocks of nearly
        equal size. More shards than workers balance the load (a shard of comets that end
        early finishes early) and checkpoint the population by chunks of comets.
    checkpoint_dir : path, optional
        A directory shared by the workers (created if missing). Each shard saves its
        population there (``shardNNNN-<digest>.population``, written atomically: a temporary
        file renamed over the last) at every multiple of ``checkpoint_every_years`` and at
        its end; a shard started again (its worker died, or the whole call was killed and
        made again with the same arguments) goes on from its checkpoint, and a finished one
        is loaded without running. The digest names the shard's settings, particles,
        identifiers, ``to_years`` and cadence, so a checkpoint of another run is never
        resumed. The files are kept after the call (remove the directory to start afresh).
        ``None``: no checkpoints; a shard whose worker dies starts again from the epoch.
    checkpoint_every_years : float, optional
        Years between a shard's checkpoints (> 0); ``None``: only at its end.
    retries : int
        Dask retries of a task that raised (a worker's death is rescheduled by Dask in any
        case, up to its ``distributed.scheduler.allowed-failures``).

    Returns
    -------
    Population
        The merged population, equal bit for bit to ``population_spec.build().advance(to_years)``,
        interrupted and resumed or not (a particle's trajectory depends only on its own
        initial state and the planets' grid, and a stop changes no step).
    """
    n = len(population_spec.particles)
    # Any integer as numpy has them (np.int64, ...), not a float or a bool.
    try:
        count = None if isinstance(shards, (bool, np.bool_)) else operator.index(shards)
    except TypeError:
        count = None
    if count is None or count < 1:
        raise ValueError(f"shards = {shards!r}: must be an integer >= 1")
    if checkpoint_every_years is not None:
        every = checkpoint_every_years
        if isinstance(every, (bool, np.bool_)) or not isinstance(every, (int, float, np.number)) \
                or not np.isfinite(every) or every <= 0:
            raise ValueError(
                f"checkpoint_every_years = {every!r}: must be None or a finite number > 0"
            )
        checkpoint_every_years = float(every)
    if isinstance(retries, (bool, np.bool_)) or not isinstance(retries, (int, np.integer)) or retries < 0:
        raise ValueError(f"retries = {retries!r}: must be an integer >= 0")
    to_years = float(to_years)
    if not np.isfinite(to_years):
        raise ValueError(f"to_years = {to_years}: must be finite")
    ckpt_dir = None
    if checkpoint_dir is not None:
        ckpt_dir = Path(checkpoint_dir).resolve()
        ckpt_dir.mkdir(parents=True, exist_ok=True)
    shards = min(count, max(n, 1))
    ids = population_spec.ids
    if ids is None:
        ids = np.arange(n, dtype=np.uint64)
    bounds = np.linspace(0, n, shards + 1).round().astype(int)
    # A token per call in each task's key, so that a second call over the same checkpoints
    # reads them again instead of getting results Dask still holds.
    call = uuid.uuid4().hex[:8]
    futures: List[Any] = []
    for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
        part = PopulationSpec(
            **{
                **population_spec.__dict__,
                "particles": np.ascontiguousarray(population_spec.particles[a:b]),
                "ids": np.ascontiguousarray(ids[a:b]),
            }
        )
        digest = _shard_key(part, to_years, checkpoint_every_years)
        ckpt = None if ckpt_dir is None else str(ckpt_dir / f"shard{i:04d}-{digest}.population")
        futures.append(
            client.submit(
                _run_shard,
                part,
                to_years,
                ckpt,
                checkpoint_every_years,
                key=f"partisim-population-shard-{i:04d}-{digest}-{call}",
                retries=int(retries),
                pure=False,
            )
        )
    return Population.merge(client.gather(futures))


# The reason a sweep task gives when it stops a run to write a checkpoint (the frame loop's
# "stopped" outcome carries it back); any other stop or ending is the run's own.
_CHECKPOINT_STOP = "partisim.dask: checkpoint"


def _plain(value: Any) -> Any:
    """A table cell as a plain Python value (numpy scalars from a DataFrame become int,
    float, bool or str; lists stay lists), so that the override is the TOML value it reads as."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def _override_rows(overrides: Any) -> List[Dict[str, Any]]:
    """The table of overrides as a list of dicts (dotted key path -> value)."""
    if hasattr(overrides, "to_dict") and hasattr(overrides, "columns"):
        rows = overrides.to_dict("records")  # a pandas DataFrame
    elif isinstance(overrides, Mapping):
        raise TypeError(
            "overrides: a table of runs is expected (a list of dicts or a pandas DataFrame), "
            "not one dict; wrap one run's overrides in a list"
        )
    else:
        rows = list(overrides)
    out = []
    for i, row in enumerate(rows):
        if not isinstance(row, Mapping):
            raise TypeError(
                f"overrides row {i}: a dict from dotted scene key to value is expected, "
                f"not {type(row).__name__}"
            )
        for key in row:
            if not isinstance(key, str):
                raise TypeError(f"overrides row {i}: key {key!r} is not a string")
        out.append({key: _plain(value) for key, value in row.items()})
    return out


def _run_key(
    scene: Path,
    row: Dict[str, Any],
    quick: bool,
    frames: Optional[int],
    until_rest: Optional[Dict[str, Any]] = None,
    repose: Any = None,
) -> str:
    """A digest of everything that defines a run (the scene file's bytes, its overrides,
    quick, frames, the rest criterion, the repose options), naming its checkpoint: a
    checkpoint of another run is never resumed."""
    h = hashlib.sha256()
    h.update(scene.read_bytes())
    defining = [str(scene), row, quick, frames]
    if until_rest is not None or repose is not None:  # digests of earlier sweeps unchanged
        defining += [until_rest, repose]
    h.update(json.dumps(defining, sort_keys=True, default=repr).encode())
    return h.hexdigest()[:16]


def _write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data))
    os.replace(tmp, path)


# The frame record's wall-clock fields: they depend on the machine, not on the run (the
# table's ``wall_s`` is the run's).
_WALL_CLOCK = ("phases_s", "total_s")


def _stats_columns(record: Optional[Dict[str, Any]]) -> Dict[str, Any]:
    """The final frame record's statistics, without its wall-clock times."""
    if record is None:
        return {}
    return {k: v for k, v in record.items() if k not in _WALL_CLOCK}


def _result(
    outcome: Dict[str, Any],
    record: Optional[Dict[str, Any]],
    measured: Optional[Dict[str, Any]] = None,
) -> Dict[str, Any]:
    """A run's row: its outcome (with the at-rest verdict when watched), the repose
    columns when measured, then the final frame record's statistics."""
    result: Dict[str, Any] = {
        "ending": outcome["ending"],
        "reason": outcome["reason"],
        "frame": outcome["frame"],
        "time_s": outcome["time_s"],
    }
    if "at_rest" in outcome:
        result["at_rest"] = outcome["at_rest"]
        result["rest_from_s"] = outcome["rest_from_s"]
        result["rest_summary"] = outcome.get("rest_summary")
        # Each quantity of the verdict with by how much it misses its bound (0 when within).
        for name, margin in (outcome.get("rest_margins") or {}).items():
            result[f"rest_{name}"] = margin["value"]
            result[f"rest_{name}_misses_by"] = margin["misses_by"]
    result.update(measured or {})
    for key, value in _stats_columns(record).items():
        result.setdefault(key, value)
    return result


# The repose measurement's scalar results, as the table's columns.
_REPOSE_COLUMNS = {
    "angle_deg": "repose_angle_deg",
    "resolution_deg": "repose_resolution_deg",
    "steepest_deg": "repose_steepest_deg",
    "pile_height_m": "repose_pile_height_m",
}


def _measure_repose(sim: Any, repose: Any) -> Dict[str, Any]:
    """The repose columns of a finished run: ``sim.repose(**options)`` when ``repose`` is a
    dict, or with the defaults when it is None and the scene is granular; none when
    ``repose`` is False or the scene is not granular. A heap that cannot be measured (a
    flat layer, too few surface points) gives NaN angles and its message in
    ``repose_error``, not a failed sweep."""
    from . import PartisimError

    if repose is False or (repose is None and getattr(sim, "solver", None) != "granular"):
        return {}
    options = dict(repose) if isinstance(repose, Mapping) else {}
    try:
        m = sim.repose(**options)
    except PartisimError as e:
        out: Dict[str, Any] = {column: float("nan") for column in _REPOSE_COLUMNS.values()}
        out["repose_error"] = str(e)
        return out
    out = {column: m[key] for key, column in _REPOSE_COLUMNS.items()}
    out["repose_error"] = None
    return out


def _run_scene(
    scene: str,
    row: Dict[str, Any],
    quick: bool,
    frames: Optional[int],
    checkpoint: Optional[str],
    checkpoint_every: int,
    until_rest: Optional[Dict[str, Any]] = None,
    repose: Any = None,
) -> Dict[str, Any]:
    """One run of a sweep (the Dask task): from its latest checkpoint if there is one, else
    from the scene; a checkpoint every ``checkpoint_every`` frames; the result as a row.

    Beside each checkpoint ``NAME`` a small ``NAME.json`` keeps the frame it was taken at,
    that frame's record, the rest criterion's samples carried at each checkpoint frame
    (``holds``: frame -> the outcome's ``rest_state``) and, once the run has ended, its outcome and
    repose columns. It is written before the checkpoint, so it never lags behind it: a
    task that loads a checkpoint of the same frame takes the record (and a finished run's
    row) from it, one that loads an older checkpoint (killed between the two writes) runs
    those frames again, and either continues from the samples of its checkpoint's frame, so that
    the at-rest verdict is the uninterrupted run's."""
    from . import Simulation  # the worker imports the extension here, not at unpickling

    start = time.perf_counter()
    ckpt = Path(checkpoint) if checkpoint is not None else None
    side = ckpt.with_name(ckpt.name + ".json") if ckpt is not None else None
    record = None
    holds: Dict[str, Any] = {}
    if ckpt is not None and ckpt.exists():
        sim = Simulation.load(ckpt)
        saved = json.loads(side.read_text()) if side.exists() else {}
        holds = dict(saved.get("holds") or {})
        if saved.get("frame") == sim.frame:
            record = saved["record"]
            if saved.get("outcome") is not None:  # finished: its row, without running
                return {
                    **_result(saved["outcome"], record, saved.get("measured")),
                    "resumed_from_frame": sim.frame,
                    "checkpoint": checkpoint,
                    "wall_s": time.perf_counter() - start,
                }
    else:
        # An empty row is the scene as written (no overrides argument at all).
        extra = {"overrides": row} if row else {}
        sim = Simulation.from_scene(scene, quick=quick, **extra)
    resumed_from = sim.frame
    # The rest criterion's samples at the frame the run goes on from (none at frame 0).
    carried = holds.get(str(sim.frame))
    # The run's last frame (frames asked for, never past the scene's end): no checkpoint stop
    # there, so that the last call of `run` ends the run with its own outcome.
    final = frames
    scene_end = getattr(sim, "scene_frames", None)
    if scene_end is not None:
        final = scene_end if final is None else min(final, scene_end)

    def every(rec: Dict[str, Any]) -> Any:
        frame = rec["frame"]
        if frame % checkpoint_every == 0 and (final is None or frame < final):
            return _CHECKPOINT_STOP
        return None

    while True:
        todo = None if frames is None else frames - sim.frame
        if todo is not None and todo < 1:
            raise RuntimeError(
                f"{checkpoint}: resumed at frame {sim.frame}, not before the {frames} frames "
                "asked for (a checkpoint of a finished run without its record)"
            )
        watch = None if until_rest is None else {**until_rest, "resume": carried}
        outcome = sim.run(todo, progress=False, callback=every if ckpt is not None else None,
                          until_rest=watch)
        if sim.stats is not None:
            record = sim.stats
        carried = outcome.get("rest_state")
        pause = outcome["ending"] == "stopped" and outcome["reason"] == _CHECKPOINT_STOP
        measured = None if pause else _measure_repose(sim, repose)
        if ckpt is None:
            break
        if until_rest is not None:
            holds[str(sim.frame)] = carried
        _write_json_atomic(
            side,
            {
                "frame": sim.frame,
                "record": record,
                "holds": holds,
                "outcome": None if pause else outcome,
                "measured": measured,
            },
        )
        sim.save(ckpt)
        if not pause:
            break
    return {
        **_result(outcome, record, measured),
        "resumed_from_frame": resumed_from,
        "checkpoint": checkpoint,
        "wall_s": time.perf_counter() - start,
    }


def run_scene_sweep(
    client: Any,
    scene: Union[str, os.PathLike],
    overrides: Any,
    frames: Optional[int] = None,
    quick: bool = False,
    checkpoint_dir: Optional[Union[str, os.PathLike]] = None,
    checkpoint_every: int = 50,
    retries: int = 0,
    until_rest: Optional[Mapping[str, Any]] = None,
    repose: Union[None, bool, Mapping[str, Any]] = None,
) -> Any:
    """Runs one scene file under each row of a table of overrides, one Dask task per run,
    and gathers the results into one table.

    Each task builds ``Simulation.from_scene(scene, quick=quick, overrides=row)`` and runs
    it to ``frames`` (or to the scene's end, as the command line counts it). With
    ``checkpoint_dir`` it stops every ``checkpoint_every`` frames to ``sim.save`` its
    checkpoint there (an atomic write), and a task that starts again because its worker
    died resumes with ``Simulation.load`` from the latest one. A loaded run continues bit
    for bit, so every row is identical to the same run on one machine, interrupted or not.

    Parameters
    ----------
    client : dask.distributed.Client
        Any client: a ``LocalCluster``, a ``dask-jobqueue`` cluster, a remote scheduler.
        The workers read ``scene`` (and the meshes it names) and ``checkpoint_dir`` at the
        same paths as the caller: on a cluster, a shared file system.
    scene : path
        The base scene file (TOML).
    overrides : list of dict or pandas.DataFrame
        One row per run: dotted scene keys (``"solver.friction_angle_deg"``,
        ``"simulation.particle_spacing"``, ...) to values, checked as the file's own values
        are. An empty dict runs the scene as written.
    frames : int, optional
        Frames per run, counted from the scene's start; ``None`` runs to the scene's end.
    quick : bool
        The scene's ``[quick]`` settings.
    checkpoint_dir : path, optional
        A directory shared by the workers for the runs' checkpoints (created if missing),
        named by the row and a digest of the scene file, its overrides, ``quick`` and
        ``frames``; a checkpoint of any other run is never resumed. It is kept after the
        sweep (the final state of each run: ``Simulation.load`` it), with a small JSON
        file beside each (the frame record and, once finished, the outcome): the same sweep
        run again resumes the unfinished runs and returns the finished ones without running
        them. ``None``: no checkpoints, and a run whose worker dies starts again from
        frame 0.
    checkpoint_every : int
        Frames between checkpoints (>= 1).
    retries : int
        Dask retries of a task that raised (a worker's death is rescheduled by Dask in any
        case, up to its ``distributed.scheduler.allowed-failures``).
    until_rest : dict, optional
        Stop each run once its material is at rest, as ``Simulation.run(until_rest=...)``:
        ``{}`` for granular codes' criterion with its default figures, or a dict changing
        them and giving ``region``, ``shape``, ``floor_y`` (see ``Simulation.run``). The
        criterion's samples at each checkpoint are kept beside it, so a run resumed after
        its worker died reaches the uninterrupted run's verdict at the same frame.
    repose : None, False or dict
        The angle of repose of each run's final particles (``Simulation.repose``): ``None``
        (default) measures the runs whose scene is granular (``[solver] kind =
        "granular"``) with ``repose()``'s defaults, a dict measures every run with those
        options (``{"shape": "conical"}``, ...), ``False`` measures none.

    Returns
    -------
    pandas.DataFrame
        One row per run, in the order of ``overrides``: the override columns; the outcome
        (``ending``: "completed", "stopped" or "diverged", ``reason``, ``frame``,
        ``time_s``); the statistics of the final frame record (``particles``,
        ``max_density_ratio``, ``mean_density_ratio``, ``kinetic_energy_j``,
        ``iterations``, ...; not its wall-clock ``phases_s`` and ``total_s``); with
        ``until_rest``, the verdict ``at_rest`` (bool), ``rest_from_s`` (s, or None),
        ``rest_summary`` (what misses and by how much) and, per quantity judged
        (``percentile_speed``, ``deep_speed``, ``angle_drift``), ``rest_<name>`` (its value
        over the window) and ``rest_<name>_misses_by`` (0 when within its bound);
        where measured, ``repose_angle_deg``, ``repose_resolution_deg``,
        ``repose_steepest_deg``, ``repose_pile_height_m`` and ``repose_error`` (None, or
        why the heap could not be measured, its angles then NaN);
        ``resumed_from_frame`` (0, or the checkpoint's frame the
        finishing attempt started from), ``checkpoint`` (its path or None) and ``wall_s``
        (the finishing attempt's wall time, s).
    """
    try:
        import pandas as pd
    except ImportError as e:  # pragma: no cover - the dask extra installs pandas
        raise ImportError(
            'run_scene_sweep returns a pandas DataFrame: pip install "partisim[dask]"'
        ) from e
    scene_path = Path(scene).resolve()
    if not scene_path.is_file():
        raise FileNotFoundError(f"scene = {str(scene)!r}: no such file")
    rows = _override_rows(overrides)
    if frames is not None:
        if isinstance(frames, (bool, np.bool_)) or not isinstance(frames, (int, np.integer)) or frames < 0:
            raise ValueError(f"frames = {frames!r}: must be None or an integer >= 0")
        frames = int(frames)
    if (
        isinstance(checkpoint_every, (bool, np.bool_))
        or not isinstance(checkpoint_every, (int, np.integer))
        or checkpoint_every < 1
    ):
        raise ValueError(f"checkpoint_every = {checkpoint_every!r}: must be an integer >= 1")
    if isinstance(retries, (bool, np.bool_)) or not isinstance(retries, (int, np.integer)) or retries < 0:
        raise ValueError(f"retries = {retries!r}: must be an integer >= 0")
    if until_rest is not None:
        if not isinstance(until_rest, Mapping):
            raise TypeError(
                f"until_rest: expected a dict (the rest criterion's figures, region, shape, floor_y), not {type(until_rest).__name__}"
            )
        if "resume" in until_rest:
            raise ValueError("until_rest: resume is the sweep's to carry between checkpoints")
        until_rest = {key: _plain(value) for key, value in until_rest.items()}
    if repose is not None and repose is not False and not isinstance(repose, Mapping):
        raise TypeError(
            f"repose: expected None, False or a dict of Simulation.repose options, not {repose!r}"
        )
    if isinstance(repose, Mapping):
        repose = {key: _plain(value) for key, value in repose.items()}
    ckpt_dir = None
    if checkpoint_dir is not None:
        ckpt_dir = Path(checkpoint_dir).resolve()
        ckpt_dir.mkdir(parents=True, exist_ok=True)
    quick = bool(quick)
    futures: List[Any] = []
    # A token per call in each task's key: Dask hands back the result of a task whose key it
    # still holds, so a second sweep over the same checkpoints submitted while the first's
    # results were not yet released would return the first call's rows (resumed_from_frame
    # and all) instead of reading the checkpoints again.
    call = uuid.uuid4().hex[:8]
    for i, row in enumerate(rows):
        digest = _run_key(scene_path, row, quick, frames, until_rest, repose)
        ckpt = None if ckpt_dir is None else str(ckpt_dir / f"run{i:04d}-{digest}.partisim")
        futures.append(
            client.submit(
                _run_scene,
                str(scene_path),
                row,
                quick,
                frames,
                ckpt,
                int(checkpoint_every),
                until_rest,
                repose,
                key=f"partisim-scene-run-{i:04d}-{digest}-{call}",
                retries=int(retries),
                pure=False,
            )
        )
    results = client.gather(futures)
    table = [{**row, **result} for row, result in zip(rows, results)]
    return pd.DataFrame(table)
