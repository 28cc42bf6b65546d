"""Comet populations (crate ``symplectic``): test particles among the giant planets,
integrated with Chegodaeva (2004)'s variable-step symplectic maps against one shared planet
ephemeris.

Units: AU, days, degrees in elements; spans in years (Julian, 365.25 days).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Union

import numpy as np

from . import _partisim

DAYS_PER_YEAR = 365.25

KINDS = (
    "barycentric_elements",
    "heliocentric_elements",
    "barycentric_state",
    "heliocentric_state",
)


@dataclass(frozen=True)
class Planets:
    """The planets a population moves among: the Sun (carrying the inner planets' masses)
    and Jupiter, Saturn, Uranus, Neptune at the epoch 1994-09-05 0h (``t = 0``).

    Attributes
    ----------
    frame : str
        ``"ecliptic_j2000"`` or ``"equatorial"``.
    names : list of str
        The giants' names.
    masses_msun : ndarray, shape (4,)
        Masses of the giants (solar masses).
    positions_au, velocities_au_per_day : ndarray, shape (4, 3)
        Heliocentric positions (AU) and velocities (AU/day) of the giants at the epoch.
    """

    frame: str
    names: List[str]
    masses_msun: np.ndarray
    positions_au: np.ndarray
    velocities_au_per_day: np.ndarray


def outer_solar_system(frame: str = "ecliptic_j2000") -> Planets:
    """The Sun and the four giant planets (the crate's ``outer_solar_system``)."""
    t = _partisim.outer_solar_system_table(frame)
    return Planets(
        frame=frame,
        names=list(t["names"]),
        masses_msun=t["masses_msun"],
        positions_au=t["positions_au"],
        velocities_au_per_day=t["velocities_au_per_day"],
    )


@dataclass
class PopulationSpec:
    """Everything that defines a population at its epoch: the settings of a population
    TOML file (``cargo xtask comets``) and the particles. Small and picklable: this, and
    nothing else, is what :func:`partisim.dask.run_population_dask` sends to each task.

    Attributes
    ----------
    particles : ndarray, shape (N, 6), float64
        One row per particle, as ``kind`` says: elements ``a`` (AU; < 0 with ``e > 1`` for
        a hyperbola), ``e``, ``i``, ``node``, ``peri``, ``mean_anomaly`` (degrees), or a state
        ``x, y, z`` (AU), ``vx, vy, vz`` (AU/day).
    kind : str
        One of ``barycentric_elements`` (default), ``heliocentric_elements``,
        ``barycentric_state``, ``heliocentric_state``.
    ids : ndarray, shape (N,), uint64, optional
        Distinct identifiers (default ``0..N``).
    frame : str
        The planets' frame (particles are read in it).
    planet_scheme : str
        ``"s6"`` (default) or ``"s2"``: the planets' map.
    planet_step_days : float
        The planets' fixed step (days), the ephemeris grid spacing.
    variant : str
        ``"barycentric"`` (default) or ``"mixed"``: the particles' coordinates.
    scheme : str
        ``"s2"`` (default) or ``"s6"``: the particles' map.
    b0, b1 : float
        Emel'yanenko's step-function parameters ``B0`` (AU²/day²) and ``B1`` (AU³/day²).
    initial_step_days : float
        Every particle's first physical step (days).
    epoch_days : float
        Epoch of the rows (days after the planets' epoch, >= 0).
    window_steps : int, optional
        Planet steps per synchronisation window (the crate's default if None).
    removal : dict
        ``hill_factor``, ``min_perihelion`` (AU), ``ejection_distance`` (AU); a rule left out
        is not applied.
    """

    particles: np.ndarray
    kind: str = "barycentric_elements"
    ids: Optional[np.ndarray] = None
    frame: str = "ecliptic_j2000"
    planet_scheme: str = "s6"
    planet_step_days: float = 730.5
    variant: str = "barycentric"
    scheme: str = "s2"
    b0: float = 0.0
    b1: float = 0.21e-6
    initial_step_days: float = 547.875
    epoch_days: float = 0.0
    window_steps: Optional[int] = None
    removal: Dict[str, float] = field(default_factory=dict)

    def settings_json(self) -> str:
        """The specification's tables as JSON (checked by the crate's TOML reader)."""
        integrator: Dict[str, Any] = {
            "variant": self.variant,
            "scheme": self.scheme,
            "b0": float(self.b0),
            "b1": float(self.b1),
            "initial_step_days": float(self.initial_step_days),
        }
        if self.window_steps is not None:
            integrator["window_steps"] = int(self.window_steps)
        spec = {
            "planets": {
                "system": "outer_solar_system",
                "frame": self.frame,
                "scheme": self.planet_scheme,
                "step_days": float(self.planet_step_days),
            },
            "integrator": integrator,
            # The particles come as an array; the file and span fields are the TOML file's
            # and unused here.
            "particles": {"file": "(array)", "kind": self.kind, "epoch_days": float(self.epoch_days)},
            "span": {"years": 1.0, "snapshot_every_years": 1.0},
            "removal": {k: float(v) for k, v in self.removal.items()},
        }
        return json.dumps(spec)

    def build(self, rows: Optional[slice] = None) -> "Population":
        """The population at its epoch (``rows``: only those particles, a shard)."""
        particles = self.particles if rows is None else self.particles[rows]
        ids = self.ids
        if ids is None:
            ids = np.arange(len(self.particles), dtype=np.uint64)
        if rows is not None:
            ids = ids[rows]
        return Population._wrap(
            _partisim.Population.from_spec_json(self.settings_json(), particles, ids)
        )


class Population:
    """A population of test particles (``symplectic::Population``).

    Build one from the planets and an ``(N, 6)`` array (keywords as in
    :class:`PopulationSpec`), from a :class:`PopulationSpec` (:meth:`PopulationSpec.build`),
    from a population TOML file (:meth:`from_file`) or a checkpoint (:meth:`load`).

    Parameters
    ----------
    planets : Planets
        :func:`outer_solar_system` in the frame of the particles.
    particles : ndarray, shape (N, 6), float64
        Elements or states, as ``kind`` says (see :class:`PopulationSpec`).
    **settings
        The other fields of :class:`PopulationSpec` (``kind``, ``ids``, ``scheme``,
        ``planet_scheme``, ``planet_step_days``, ``b1``, ``initial_step_days``,
        ``removal``, ...).
    """

    def __init__(self, planets: Planets, particles: np.ndarray, **settings: Any) -> None:
        spec = PopulationSpec(particles=particles, frame=planets.frame, **settings)
        self._inner = spec.build()._inner
        self.spec: Optional[PopulationSpec] = spec

    @classmethod
    def _wrap(cls, inner: Any) -> "Population":
        p = cls.__new__(cls)
        p._inner = inner
        p.spec = None
        return p

    @classmethod
    def from_file(cls, path: str) -> "Population":
        """A population TOML file and its particle CSV (the input of ``cargo xtask comets``)."""
        return cls._wrap(_partisim.Population.from_spec_file(str(path)))

    @classmethod
    def load(cls, path: str) -> "Population":
        """A population written by :meth:`save` (refuses foreign or truncated files)."""
        return cls._wrap(_partisim.Population.load(str(path)))

    def save(self, path: str) -> None:
        """Writes the whole population atomically; :meth:`load` resumes it bit for bit."""
        self._inner.save(str(path))

    def advance(self, to_years: float) -> "Population":
        """Advances every active particle to ``to_years`` (years after the planets' epoch);
        returns ``self``. Ctrl-C stops between synchronisation windows."""
        self._inner.advance_to_days(float(to_years) * DAYS_PER_YEAR)
        return self

    @property
    def time_years(self) -> float:
        """The population's time (years after the planets' epoch)."""
        return self._inner.time_days / DAYS_PER_YEAR

    @property
    def time_days(self) -> float:
        """The population's time (days after the planets' epoch)."""
        return self._inner.time_days

    @property
    def particle_steps(self) -> int:
        """Particle steps done in total."""
        return self._inner.particle_steps

    @property
    def status(self) -> List[str]:
        """Each particle's status: ``active``, ``hill_sphere_<planet name>``,
        ``collision_<planet name>`` (with ``[encounters]``), ``perihelion``, ``ejected``,
        ``regularisation_lost`` or ``failed`` (identifier order)."""
        return self._inner.status

    @property
    def ids(self) -> np.ndarray:
        """Identifiers (uint64), in member order (identifier order after a merge)."""
        return self._inner.ids

    @property
    def states(self) -> np.ndarray:
        """Barycentric states (N, 6): x, y, z (AU), vx, vy, vz (AU/day)."""
        return self._inner.states

    @property
    def elements(self) -> Dict[str, np.ndarray]:
        """Barycentric osculating elements: ``a_au``, ``e``, ``i_deg``, ``q_au``."""
        t = self._inner.table()
        return {k: t[k] for k in ("a_au", "e", "i_deg", "q_au")}

    def table(self) -> Dict[str, Union[np.ndarray, List[str]]]:
        """The snapshot table (``cargo xtask comets``' Parquet columns) as a dict:
        ``pandas.DataFrame(p.table())`` or ``polars.DataFrame(p.table())``."""
        return self._inner.table()

    def write_parquet(self, path: str) -> None:
        """Writes the snapshot table as Parquet (``pandas.read_parquet``,
        ``polars.read_parquet``)."""
        self._inner.write_parquet(str(path))

    def shard(self, start: int, stop: int) -> "Population":
        """Members ``start:stop`` as a population of their own."""
        return Population._wrap(self._inner.shard(int(start), int(stop)))

    @staticmethod
    def merge(shards: List["Population"]) -> "Population":
        """Joins shards advanced to the same time (bit-identical to the whole run)."""
        return Population._wrap(_partisim.Population.merge([s._inner for s in shards]))

    def __len__(self) -> int:
        return len(self._inner)

    def __reduce__(self):
        return (_from_bytes, (bytes(self._inner.to_bytes()),))

    def __repr__(self) -> str:
        active = sum(s == "active" for s in self.status)
        return f"Population({len(self)} particles, {active} active, t = {self.time_years:.6g} yr)"


def _from_bytes(data: bytes) -> Population:
    return Population._wrap(_partisim.Population.from_bytes(data))
