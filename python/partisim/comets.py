"""Comet populations (crate ``symplectic``): test particles among the giant planets,
integrated with Chegodaeva (2004)'s variable-step symplectic maps against one shared planet
ephemeris.

Units: AU, days, degrees in elements; spans in years (Julian, 365.25 days).
"""

from __future__ import annotations

import json
import operator
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Union

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
        ``hill_factor``, ``min_perihelion`` (AU), ``ejection_distance`` (AU, unbound only),
        ``sun_collision`` (bool: closer than the IAU nominal solar radius, or past a perihelion
        below it within the last step), ``min_distance`` and ``max_distance`` (dicts
        ``{"distance": AU, "frame": "heliocentric" or "barycentric"}``; the maximum applies
        bound or not); a rule left out is not applied. A particle that enters
        ``hill_factor`` Hill radii of a planet stops with the status ``hill_sphere_<planet>``
        (``hill_sphere_Jupiter`` ...); the others with ``perihelion``, ``ejected``,
        ``collision_sun``, ``min_distance_<frame>``, ``max_distance_<frame>``.
    events : dict
        What is recorded without removing (the ``[events]`` table of a population file):
        ``perihelion_below`` (list of AU: the first time the perihelion falls below each),
        ``tisserand_crossing`` (bool: the first crossing of T_J = 3),
        ``close_approach`` (``{"hill_radii": f}`` or ``{"au": r}``: each passage inside that
        radius of a planet, with the smallest distance and its time), ``max_per_particle``
        (events kept per particle, default 1000; more are counted in the table's
        ``events_dropped``). Read them with :meth:`Population.events_table`.
    encounters : dict or None
        Integrate the particles through close encounters instead of removing them (the
        ``[encounters]`` table of a population file): ``{}`` takes the defaults, or give
        ``hill_factor`` (Hill radii where the encounter integrator takes over, default 3),
        ``hand_back_hill_factor`` (Hill radii beyond which it hands the particle back to the
        map, at least ``hill_factor``, default 3.5) and ``tolerance`` (its relative error per
        step, default 1e-12). Barycentric variant
        only, and not with the removal rule ``hill_factor``. A particle that hits a planet
        stops with the status ``collision_<planet>``. ``None`` (default): off.

    Limits (each named in the error that refuses it): ``planet_step_days`` must leave the
    planets' grid of one particle step under ``MAX_STEP_GRID_BYTES`` (1 GiB: with the default
    first step of 547.875 days, at least about 2·10⁻⁴ days); ``initial_step_days`` must move
    a time of the first synchronisation window's size in float64.
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
    removal: Dict[str, Any] = field(default_factory=dict)
    encounters: Optional[Dict[str, float]] = None
    events: Dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.particles = _float_rows(self.particles)
        if self.ids is not None:
            self.ids = _identifiers(self.ids)

    def settings_json(self) -> str:
        """The specification's tables as JSON (checked by the crate as a population file's
        tables are; errors name this class's keywords)."""
        integrator: Dict[str, Any] = {
            "variant": self.variant,
            "scheme": self.scheme,
            "b0": _number("b0", self.b0),
            "b1": _number("b1", self.b1),
            "initial_step_days": _number("initial_step_days", self.initial_step_days),
        }
        if self.window_steps is not None:
            integrator["window_steps"] = _integer("window_steps", self.window_steps)
        spec = {
            "planets": {
                "system": "outer_solar_system",
                "frame": self.frame,
                "scheme": self.planet_scheme,
                "step_days": _number("planet_step_days", self.planet_step_days),
            },
            "integrator": integrator,
            # The particles come as an array; the file and span fields are the TOML file's
            # and unused here.
            "particles": {
                "file": "(array)",
                "kind": self.kind,
                "epoch_days": _number("epoch_days", self.epoch_days),
            },
            "span": {"years": 1.0, "snapshot_every_years": 1.0},
            "removal": {k: _setting(f"removal[{k!r}]", v) for k, v in dict(self.removal).items()},
            "events": {k: _setting(f"events[{k!r}]", v) for k, v in dict(self.events).items()},
        }
        if self.encounters is not None:
            spec["encounters"] = {
                k: _number(f"encounters[{k!r}]", v) for k, v in dict(self.encounters).items()
            }
        return json.dumps(spec)

    def build(self, rows: Optional[slice] = None) -> "Population":
        """The population at its epoch (``rows``: only those particles, a shard)."""
        particles = self.particles if rows is None else self.particles[rows]
        ids = self.ids
        if rows is not None:
            # The default identifiers are the row numbers, here those of the shard.
            full = np.arange(len(self.particles), dtype=np.uint64) if ids is None else ids
            ids = full[rows]
        # ids=None: 0..N made on the Rust side, after the rows are counted against memory.
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
    particles : array-like, shape (N, 6)
        Elements or states, as ``kind`` says (see :class:`PopulationSpec`); lists and
        integer arrays are converted to float64 as numpy does (a float32 array is refused:
        orbits need float64).
    **settings
        The other fields of :class:`PopulationSpec` (``kind``, ``ids``, ``scheme``,
        ``planet_scheme``, ``planet_step_days``, ``b1``, ``initial_step_days``,
        ``removal``, ``encounters``, ...).

    Notes
    -----
    Each particle is on its own clock: the particles take variable steps (Chegodaeva's
    regularised time) and meet only at synchronisation windows. :attr:`time_years` is the
    time every active particle has reached; each one's own time (``table()["time_days"]``)
    is up to one of its steps past it. :attr:`states` and :meth:`elements` are at the
    particles' own times; ``elements(at_time=...)`` and :meth:`states_at` put them at one.

    Errors are :class:`partisim.PartisimError` naming the setting (by its keyword here, by
    its key in a population file) or the file; every limit (file sizes, snapshot counts,
    steps) is named in the error that refuses it.
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
        """A population TOML file and its particle CSV (the input of ``particles comets``).

        Only regular files are read (a named pipe or a device such as ``/dev/zero`` is
        refused before it is opened); the specification up to 1 MiB, the particle file's
        lines counted against the memory available before any row is kept. Errors name the
        file and the key or the line and column. Ctrl-C stops the reading
        (``KeyboardInterrupt``)."""
        return cls._wrap(_partisim.Population.from_spec_file(str(path)))

    @classmethod
    def load(cls, path: str) -> "Population":
        """A population written by :meth:`save` (refuses foreign or truncated files, a
        file that is not a regular one, and one larger than the memory available)."""
        return cls._wrap(_partisim.Population.load(str(path)))

    def save(self, path: str) -> None:
        """Writes the whole population atomically (JSON, about 470 bytes per particle,
        through a buffer: 50,000 comets in about 0.05 s); :meth:`load` resumes it bit for
        bit."""
        self._inner.save(str(path))

    def advance(
        self,
        to_years: float,
        progress: Optional[bool] = None,
        callback: Optional[Callable[[Dict[str, Any]], Any]] = None,
    ) -> "Population":
        """Advances every active particle to ``to_years`` (years after the planets' epoch);
        returns ``self``.

        The run goes one synchronisation window at a time (``window_steps`` planet steps:
        512 years with the defaults). Each particle keeps its own clock: its variable steps
        stop at the first step end at or after ``to_years``, so after the call a particle's
        own time (``table()["time_days"]``) is up to one of its steps (1.5 years with the
        default first step) past :attr:`time_years`, the time every active particle has
        reached.

        Parameters
        ----------
        to_years : float
            End time, years after the planets' epoch (1994-09-05 0h).
        progress : bool or None
            A progress bar (``partisim.progress``: tqdm in Jupyter and on a terminal when
            installed); ``None``: on when standard error is a terminal or in Jupyter.
        callback : callable or None
            ``callback(info)`` after each window, ``info`` a dict: ``time_years``,
            ``time_days``, ``active``, ``removed``, ``particle_steps``. Returning something
            true (``True``, a non-empty string, ...) stops the run there, ``None`` or
            anything false goes on: the rule of ``Simulation.run``'s callback too. The
            population stays usable and goes on with the next call.

        Ctrl-C stops within a window with ``KeyboardInterrupt``, each particle where it
        was; the population goes on from there with the next call, its trajectories the
        same as an uninterrupted run's.
        """
        from .progress import make_progress

        end_days = float(to_years) * DAYS_PER_YEAR
        if not np.isfinite(end_days):
            raise ValueError(f"to_years = {to_years}: must be finite")
        start = self.time_days
        total = max(int(np.ceil((end_days - start) / DAYS_PER_YEAR)), 0)
        bar = make_progress(total, progress, "years")
        done = [0]

        def on_window(info: Dict[str, Any]) -> bool:
            years = int((info["time_days"] - start) // DAYS_PER_YEAR)
            bar.update(max(min(years, total) - done[0], 0))
            done[0] = max(done[0], min(years, total))
            info["time_years"] = info["time_days"] / DAYS_PER_YEAR
            return bool(callback(info)) if callback is not None else False

        try:
            self._inner.advance_to_days(end_days, on_window)
        finally:
            bar.close()
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
        """Each particle's status, identifier order:

        - ``active``: still integrated;
        - ``hill_sphere_<planet>`` (``hill_sphere_Neptune`` ...): entered ``removal
          ["hill_factor"]`` Hill radii of that planet, where the method no longer holds;
        - ``collision_<planet>``: came within the planet's radius while integrated through an
          encounter (``encounters`` set);
        - ``perihelion``: its osculating perihelion fell below ``removal["min_perihelion"]``;
        - ``ejected``: unbound (e >= 1) beyond ``removal["ejection_distance"]``;
        - ``regularisation_lost``: Chegodaeva's regularising functions K0/r or K1/r stopped
          being positive, i.e. ``b0``, ``b1`` no longer dominate the planets' perturbation on
          this orbit (her condition 35: typically a close approach to a planet without an
          encounter rule, or the mixed variant outside its domain); the particle stops at
          its last good state. Larger ``b1`` or a ``hill_factor`` rule avoids it;
        - ``failed``: a step failed for another reason (non-finite state).
        """
        return self._inner.status

    @property
    def ids(self) -> np.ndarray:
        """Identifiers (uint64), in member order (identifier order after a merge)."""
        return self._inner.ids

    @property
    def states(self) -> np.ndarray:
        """Barycentric states, shape (N, 6): x, y, z (AU), vx, vy, vz (AU/day), each
        particle at its own time (``table()["time_days"]``: up to one of its steps past
        :attr:`time_years`; a removed particle at its removal). :meth:`states_at` gives them
        at one time."""
        return self._inner.states

    def states_at(self, at_time: Optional[float] = None) -> "tuple[np.ndarray, np.ndarray]":
        """Barycentric states (N, 6) and their times (N,), in days: with ``at_time`` (years
        after the planets' epoch) every active particle's state carried from its own time to
        ``at_time`` along its osculating orbit about the barycentre (a Kepler drift about
        ``G M``, the planets' pull over that interval, less than one of its steps, left
        out); removed particles stay at their own time. ``at_time=None``: each at its own."""
        at_days = None if at_time is None else float(at_time) * DAYS_PER_YEAR
        return self._inner.states_at_days(at_days)

    def elements(self, at_time: Optional[float] = None) -> Dict[str, np.ndarray]:
        """Barycentric osculating elements about ``G M`` (the Sun and planets' total mass),
        a dict of arrays of shape (N,), identifier order:

        - ``a_au``: semi-major axis (AU; negative for a hyperbola),
        - ``e``: eccentricity,
        - ``i_deg``: inclination to the frame's reference plane (degrees),
        - ``node_deg``: longitude of the ascending node Ω (degrees, 0 for i = 0),
        - ``peri_deg``: argument of perihelion ω (degrees, 0 for e = 0),
        - ``mean_anomaly_deg``: mean anomaly M (degrees; e sinh H − H for a hyperbola),
        - ``q_au``: perihelion distance (AU),
        - ``time_days``: the time each row holds at (days after the planets' epoch).

        Each particle is on its own clock: without ``at_time`` each row is at the particle's
        own time, up to one of its steps past :attr:`time_years`. With ``at_time`` (years)
        every active particle is carried to that one time as :meth:`states_at` does.
        """
        at_days = None if at_time is None else float(at_time) * DAYS_PER_YEAR
        return self._inner.elements(at_days)

    def table(self) -> Dict[str, Union[np.ndarray, List[str]]]:
        """The snapshot table (``cargo xtask comets``' Parquet columns) as a dict:
        ``pandas.DataFrame(p.table())`` or ``polars.DataFrame(p.table())``."""
        return self._inner.table()

    def write_parquet(self, path: str) -> None:
        """Writes the snapshot table as Parquet (``pandas.read_parquet``,
        ``polars.read_parquet``)."""
        self._inner.write_parquet(str(path))

    def events_table(self) -> Dict[str, Union[np.ndarray, List[str]]]:
        """The events so far (the study's ``events.parquet``) as a dict, one row per event:
        ``id``, ``event`` (``perihelion_below``, ``tisserand_crossing``, ``close_approach``),
        ``time_days``, ``threshold_au``, ``perihelion_au``, ``tisserand_before``,
        ``tisserand_after``, ``planet``, ``min_distance_au``, ``radius_au`` (NaN where a
        column does not apply) and ``ongoing`` (a close approach still under way)."""
        return self._inner.events_table()

    def write_events_parquet(self, path: str) -> None:
        """Writes the events table as Parquet."""
        self._inner.write_events_parquet(str(path))

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


def _number(name: str, value: Any) -> float:
    """A setting as a finite float (JSON has no NaN or infinity), named if it is not one."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"PopulationSpec {name} = {value!r}: expected a number") from None
    if not np.isfinite(x):
        raise _partisim.PartisimError(f"PopulationSpec {name} = {x}: must be a finite number")
    return x


def _setting(name: str, value: Any) -> Any:
    """A rule's value for JSON: a bool kept, a number as :func:`_number`, a dict or a list
    converted item by item (named ``name[key]``, ``name[index]``)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, str):
        return value
    if isinstance(value, (int, np.integer)):
        # An integer stays one (``max_per_particle``); a float field takes it as well.
        return int(value)
    if isinstance(value, dict):
        return {k: _setting(f"{name}[{k!r}]", v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_setting(f"{name}[{i}]", v) for i, v in enumerate(value)]
    return _number(name, value)


def _integer(name: str, value: Any) -> int:
    """A setting as an int (Python's or numpy's integers, not a float), named if not one."""
    try:
        return operator.index(value)
    except TypeError:
        raise TypeError(f"PopulationSpec {name} = {value!r}: expected an integer") from None


def _float_rows(particles: Any) -> np.ndarray:
    """Particle rows as numpy converts them: lists and integer arrays become float64; a
    float32 array is kept (and refused by name: orbits need float64)."""
    if isinstance(particles, np.ndarray) and particles.dtype == np.float32:
        return particles
    a = np.asarray(particles)
    if a.dtype.kind in "biuf":
        return a.astype(np.float64, copy=False)
    return a


def _identifiers(ids: Any) -> np.ndarray:
    """Identifiers as uint64: lists and arrays of any integer type with values >= 0."""
    a = np.asarray(ids)
    if a.dtype.kind == "i":
        if a.size and a.min() < 0:
            raise ValueError(f"ids: {int(a.min())} is negative; identifiers are >= 0")
        return a.astype(np.uint64)
    if a.dtype.kind == "u":
        return a.astype(np.uint64, copy=False)
    if a.dtype.kind == "b" or a.size == 0:
        return a.astype(np.uint64)
    raise TypeError(f"ids: expected integers, got an array of {a.dtype}")


def _from_bytes(data: bytes) -> Population:
    return Population._wrap(_partisim.Population.from_bytes(data))
