"""Comet populations spread over a Dask cluster (optional: ``pip install "partisim[dask]"``).

Each task receives the :class:`~partisim.PopulationSpec` settings and its shard's particles
only, builds the planets itself from the same initial state, advances and returns its
shard; the shards are merged in identifier order. A particle's trajectory depends only on
its own initial state and the planet grid, so the result is bit-identical to one process.

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
``RAYON_NUM_THREADS`` in the worker's environment.
"""

from __future__ import annotations

import operator
from typing import Any, List

import numpy as np

from .comets import Population, PopulationSpec


def _run_shard(spec: PopulationSpec, to_years: float) -> Population:
    return spec.build().advance(to_years)


def run_population_dask(
    client: Any, population_spec: PopulationSpec, to_years: float, shards: int = 2
) -> Population:
    """Advances a population to ``to_years`` (years after the planets' epoch) as
    ``shards`` Dask tasks on ``client`` and merges them.

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
        equal size.

    Returns
    -------
    Population
        The merged population, equal bit for bit to ``population_spec.build().advance(to_years)``.
    """
    n = len(population_spec.particles)
    # Any integer as numpy has them (np.int64, ...), not a float or a bool.
    try:
        count = None if isinstance(shards, (bool, np.bool_)) else operator.index(shards)
    except TypeError:
        count = None
    if count is None or count < 1:
        raise ValueError(f"shards = {shards!r}: must be an integer >= 1")
    shards = min(count, max(n, 1))
    ids = population_spec.ids
    if ids is None:
        ids = np.arange(n, dtype=np.uint64)
    bounds = np.linspace(0, n, shards + 1).round().astype(int)
    futures: List[Any] = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        part = PopulationSpec(
            **{
                **population_spec.__dict__,
                "particles": np.ascontiguousarray(population_spec.particles[a:b]),
                "ids": np.ascontiguousarray(ids[a:b]),
            }
        )
        futures.append(client.submit(_run_shard, part, float(to_years), pure=False))
    return Population.merge(client.gather(futures))
