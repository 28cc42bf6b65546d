"""Comet populations: one process against the Population's own shard/merge, a 2-worker
Dask LocalCluster, a checkpoint round trip and Parquet snapshots."""

import pickle

import numpy as np
import pytest

import partisim
from partisim import PopulationSpec

YEARS = 200.0


def comets(n=24, seed=5):
    rng = np.random.default_rng(seed)
    q = rng.uniform(32.0, 40.0, n)
    a = rng.uniform(40.0, 100.0, n)
    e = 1.0 - q / a
    angles = rng.uniform(0.0, 360.0, (n, 3))
    return np.column_stack([a, e, rng.uniform(0.0, 20.0, n), angles])


def spec(n=24):
    return PopulationSpec(particles=comets(n), planet_step_days=365.25, initial_step_days=365.25,
                          window_steps=16, removal={"hill_factor": 1.0, "min_perihelion": 26.0})


def same(a: partisim.Population, b: partisim.Population):
    assert np.array_equal(a.ids, b.ids)
    assert a.states.tobytes() == b.states.tobytes()  # bit for bit
    assert a.status == b.status
    assert a.particle_steps == b.particle_steps


def test_population_advances_and_reports():
    pop = partisim.Population(partisim.outer_solar_system(), comets(), planet_step_days=365.25,
                              initial_step_days=365.25)
    assert len(pop) == 24 and pop.time_years == 0.0
    pop.advance(YEARS)
    assert pop.time_years == pytest.approx(YEARS, rel=1e-12)
    el = pop.elements()
    # 200 years among the giants: semi-major axes change by well under 10 % (scattered-disk
    # orbits with perihelia beyond Neptune's orbit are perturbed weakly on this span).
    np.testing.assert_allclose(el["a_au"], comets()[:, 0], rtol=0.1)
    assert set(pop.status) <= {"active", "hill_sphere_Neptune", "perihelion", "ejected"}


def test_statuses_name_the_planet():
    """A comet placed 0.9 Neptune Hill radii behind Neptune on its orbit, with its velocity,
    is inside the Hill sphere at its first step: its status names Neptune, in the status
    list, the table and the Parquet file (it used to read ``hill_sphere_4``)."""
    planets = partisim.outer_solar_system()
    q = planets.positions_au[3]
    v = planets.velocities_au_per_day[3]
    # Neptune's Hill radius |Q| (m / 3 M_sun)^(1/3) ≈ 0.77 AU.
    hill = np.linalg.norm(q) * (planets.masses_msun[3] / 3.0) ** (1.0 / 3.0)
    offset = -0.9 * hill * v / np.linalg.norm(v)
    states = np.array([np.concatenate([q + offset, v]), np.concatenate([2.0 * q, 0.5 * v])])
    pop = partisim.Population(planets, states, kind="heliocentric_state",
                              planet_step_days=365.25, initial_step_days=30.0,
                              removal={"hill_factor": 1.0})
    pop.advance(10.0)
    assert pop.status == ["hill_sphere_Neptune", "active"]
    assert pop.table()["status"] == ["hill_sphere_Neptune", "active"]


def test_array_likes_and_numpy_integers():
    """Lists and integer arrays are taken as numpy converts them; the same population."""
    rows = comets(4)
    a = partisim.Population(partisim.outer_solar_system(), rows, ids=np.arange(4, dtype=np.uint64))
    b = partisim.Population(partisim.outer_solar_system(), rows.tolist(), ids=[0, 1, 2, 3])
    c = partisim.Population(partisim.outer_solar_system(), rows,
                            ids=np.arange(4, dtype=np.int32), window_steps=np.int64(256))
    for p in (b, c):
        same(p, a)
    whole = np.tile([60, 0, 10, 20, 30, 40], (2, 1))  # integers: a circular orbit
    whole[:, 1] = 0
    assert len(partisim.Population(partisim.outer_solar_system(), whole)) == 2


def test_advance_callback_sees_each_window_and_can_stop():
    pop = spec().build()  # windows of 16 planet steps of a year
    seen = []

    def stop_at_second(info):
        seen.append(info)
        return len(seen) == 2

    pop.advance(YEARS, progress=False, callback=stop_at_second)
    assert [round(i["time_years"]) for i in seen] == [16, 32]
    assert pop.time_years == pytest.approx(32.0) and seen[-1]["active"] + seen[-1]["removed"] == 24
    pop.advance(YEARS, progress=False)  # goes on, as an uninterrupted run
    same(pop, spec().build().advance(YEARS, progress=False))


def test_shards_merged_equal_one_run():
    whole = spec().build().advance(YEARS)
    parts = [spec().build(slice(0, 10)).advance(YEARS), spec().build(slice(10, 24)).advance(YEARS)]
    same(partisim.Population.merge(parts), whole)


def test_dask_local_cluster_equals_one_process():
    distributed = pytest.importorskip("dask.distributed")
    from partisim.dask import run_population_dask

    whole = spec().build().advance(YEARS)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        merged = run_population_dask(client, spec(), YEARS, shards=np.int64(2))
    same(merged, whole)


def test_checkpoint_pickle_and_parquet(tmp_path):
    pop = spec().build().advance(YEARS / 2)
    pop.save(tmp_path / "pop.ckpt")
    back = partisim.Population.load(tmp_path / "pop.ckpt")
    same(back, pop)
    same(pickle.loads(pickle.dumps(pop)), pop)
    back.advance(YEARS)
    same(back, spec().build().advance(YEARS))  # a resumed population continues bit for bit
    (tmp_path / "bad.ckpt").write_bytes(b"not a checkpoint")
    with pytest.raises(partisim.PartisimError):
        partisim.Population.load(tmp_path / "bad.ckpt")
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    pop.write_parquet(tmp_path / "snap.parquet")
    df = pd.read_parquet(tmp_path / "snap.parquet")
    table = pop.table()
    assert list(df["id"]) == list(table["id"]) and list(df["status"]) == table["status"]
    assert np.array_equal(df["a_au"].to_numpy(), table["a_au"])


def test_bad_input_raises_clear_errors():
    planets = partisim.outer_solar_system()
    with pytest.raises(ValueError, match=r"particles: expected shape \(N, 6\)"):
        partisim.Population(planets, np.zeros((3, 5)))
    with pytest.raises(TypeError, match="float64"):
        partisim.Population(planets, comets().astype(np.float32))
    bad = comets()
    bad[2, 3] = np.nan
    with pytest.raises(partisim.PartisimError, match="particles: line 2, column node.*not a finite number|not a finite number"):
        partisim.Population(planets, bad)
    # Settings named by the caller's keyword, never a line or column of generated text.
    with pytest.raises(partisim.PartisimError, match="PopulationSpec scheme") as err:
        partisim.Population(planets, comets(), scheme="s4")
    assert "line" not in str(err.value) and "column" not in str(err.value)
    with pytest.raises(partisim.PartisimError, match="PopulationSpec planet_step_days"):
        partisim.Population(planets, comets(), planet_step_days=-1.0)
    with pytest.raises(partisim.PartisimError, match="appears twice"):
        partisim.Population(planets, comets(3), ids=np.array([1, 1, 2], dtype=np.uint64))
    with pytest.raises(ValueError, match="frame"):
        partisim.outer_solar_system("galactic")


def test_six_elements_and_states_at_one_time():
    """The six elements read back the particles' initial elements at the epoch (before any
    step every particle is at t = 0); ``at_time`` puts every active particle at one time."""
    rows = comets(6)
    pop = spec(6).build()
    el = pop.elements()
    # Barycentric elements about G M against the input barycentric elements: round-off of
    # the state conversion and back (1e-9, the Kepler solve's conditioning on f64).
    for k, name in enumerate(["a_au", "e", "i_deg", "node_deg", "peri_deg", "mean_anomaly_deg"]):
        np.testing.assert_allclose(el[name], rows[:, k], rtol=1e-9, atol=1e-9)
    pop.advance(50.0, progress=False)
    own = pop.elements()
    assert (own["time_days"] >= pop.time_days).all() and len(set(own["time_days"])) > 1
    at = pop.elements(at_time=50.0)
    assert (at["time_days"] == 50.0 * 365.25).all()
    # Carried along an osculating orbit a and e do not change (a Kepler drift).
    np.testing.assert_allclose(at["a_au"], own["a_au"], rtol=1e-9)
    states, times = pop.states_at(50.0)
    assert states.shape == (6, 6) and (times == 50.0 * 365.25).all()


def test_encounters_from_python_reach_a_collision():
    """``encounters={}`` (the population file's ``[encounters]`` with its defaults) from
    Python: a comet 2 Neptune Hill radii behind Neptune, overtaking it head-on at
    0.002 AU/day (3.5 km/s) along its orbit, is integrated through the encounter instead of
    removed at the Hill sphere, and hits the planet: ``collision_Neptune``."""
    planets = partisim.outer_solar_system()
    q, v = planets.positions_au[3], planets.velocities_au_per_day[3]
    hill = np.linalg.norm(q) * (planets.masses_msun[3] / 3.0) ** (1.0 / 3.0)
    u = v / np.linalg.norm(v)
    states = np.array([np.concatenate([q - 2.0 * hill * u, v + 0.002 * u]),
                       np.concatenate([2.0 * q, 0.5 * v])])
    pop = partisim.Population(planets, states, kind="heliocentric_state", planet_step_days=365.25,
                              initial_step_days=30.0, encounters={})
    pop.advance(0.5, progress=False)
    assert pop.status == ["active", "active"] and list(pop.table()["in_encounter"]) == [True, False]
    pop.advance(10.0, progress=False)
    assert pop.status == ["collision_Neptune", "active"]


def test_end_rules_and_events_table_from_python():
    """End rules and events from Python (the population file's ``[removal]`` keys and
    ``[events]`` table): every comet of perihelion 32-40 AU is below 50 AU from its first
    step, one event each; the table reads back from Parquet as the dict gives it, and a
    sharded run merged gives the same table."""
    n = 6
    settings = dict(planet_step_days=365.25, initial_step_days=365.25,
                    removal={"sun_collision": True, "min_perihelion": 26.0,
                             "max_distance": {"distance": 400.0, "frame": "barycentric"}},
                    events={"perihelion_below": [50.0], "tisserand_crossing": True,
                            "close_approach": {"hill_radii": 1.0}, "max_per_particle": 100})
    s = PopulationSpec(particles=comets(n), **settings)
    pop = s.build()
    pop.advance(20.0, progress=False)
    t = pop.events_table()
    below = [i for i, e in enumerate(t["event"]) if e == "perihelion_below"]
    assert sorted(t["id"][below].tolist()) == list(range(n))
    assert (t["perihelion_au"][below] < 50.0).all() and (t["threshold_au"][below] == 50.0).all()
    assert (t["time_days"][below] > 0.0).all()
    assert list(pop.table()["events_dropped"]) == [0] * n
    shards = [s.build(slice(0, 2)), s.build(slice(2, n))]
    for sh in shards:
        sh.advance(20.0, progress=False)
    merged = partisim.Population.merge(shards).events_table()
    for k in t:
        assert np.array_equal(np.asarray(merged[k]), np.asarray(t[k]), equal_nan=k not in ("id", "event", "planet", "ongoing")), k


def test_events_parquet_reads_back(tmp_path):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    pop = partisim.Population(partisim.outer_solar_system(), comets(4), planet_step_days=365.25,
                              initial_step_days=365.25, events={"perihelion_below": [45.0, 50.0]})
    pop.advance(5.0, progress=False)
    path = tmp_path / "events.parquet"
    pop.write_events_parquet(path)
    df = pd.read_parquet(path)
    t = pop.events_table()
    assert list(df.columns) == list(t.keys())
    assert df["event"].tolist() == t["event"] and len(df) >= 4
    np.testing.assert_array_equal(df["time_days"].to_numpy(), t["time_days"])
