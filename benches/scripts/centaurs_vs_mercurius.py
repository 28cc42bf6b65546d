"""Side by side: symplectic::Population through close encounters (the centaur_throughput
example) and REBOUND MERCURIUS with test particles, on the same planets and the same Centaurs,
run back to back by this one script.

Needs REBOUND in a throwaway virtual environment (never a dependency of the workspace):
    python3 -m venv /work/venv-rebound && /work/venv-rebound/bin/pip install "rebound==5.2.*"
Run from the workspace root, after `cargo build --release -p benches --example centaur_throughput`:
    flock /tmp/build.lock /work/venv-rebound/bin/python benches/scripts/centaurs_vs_mercurius.py accuracy
    flock /tmp/build.lock /work/venv-rebound/bin/python benches/scripts/centaurs_vs_mercurius.py scaling

accuracy [N] [YEARS] [RATE_YEARS]: N = 300 Centaurs (benches::centaur_population, seed 2027) for 1 kyr.
Each code's position error of each comet at its final time against IAS15 (REBOUND, epsilon =
1e-9, the comet alone with the Sun and four giants, stopped at that code's final time of that
comet); the median and 90th percentile over the comets active in every run. Ours at several
first steps per AU and planet steps (the encounter tolerance at its default 1e-12), MERCURIUS (r_crit_hill = 3)
at several dt. Then the particle-years per second of each configuration on one thread
(RAYON_NUM_THREADS = OMP_NUM_THREADS = 1) over RATE_YEARS = 10 kyr, best of 3 interleaved
runs (RATE_YEARS = 0: no rates, the errors only).
scaling: ours at N = 1000, 10 kyr, on 1 and 2 threads, best of 3 interleaved runs; the ratio.
"""
import csv
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import rebound

EXAMPLE = "target/release/examples/centaur_throughput"
YEAR = 365.25
AU_KM = 149_597_870.7
RADII_KM = [71_492.0, 60_268.0, 25_559.0, 24_764.0]
# (first step in days per AU of initial distance, planets' S6 step in days): the default
# (2, 730.5) and other comet and planet steps.
OURS = [(4.0, 730.5), (2.0, 730.5), (1.0, 730.5), (0.5, 730.5), (2.0, 365.25), (2.0, 182.625),
        (1.0, 182.625)]
MERCURIUS_DT_YEARS = [0.4, 0.2, 0.1, 0.05]
REPEATS = 3


def run_ours(n, years, step_per_au=2.0, threads=1, initial=None, final=None, planet_step=730.5):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    if initial:
        env["CENTAUR_THROUGHPUT_INITIAL"] = initial
    if final:
        env["CENTAUR_THROUGHPUT_FINAL"] = final
    args = [str(n), repr(years), repr(step_per_au), "1e-12", "2027", repr(planet_step)]
    out = subprocess.run([EXAMPLE] + args, env=env,
                         check=True, capture_output=True, text=True).stdout
    last = out.strip().splitlines()[-1]
    return dict(kv.split("=") for kv in last.split())


def read_initial(path):
    bodies, particles = [], []
    with open(path) as f:
        for row in csv.DictReader(f):
            vals = [float(row[k]) for k in ("gm", "x", "y", "z", "vx", "vy", "vz")]
            (bodies if row["kind"] == "body" else particles).append(vals)
    return bodies, particles


def simulation(bodies, particles, integrator, dt=None):
    sim = rebound.Simulation()
    sim.G = 1.0  # masses given as G m (AU^3/day^2)
    for k, (gm, x, y, z, vx, vy, vz) in enumerate(bodies):
        r = 0.0 if k == 0 else RADII_KM[k - 1] / AU_KM
        sim.add(m=gm, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz, r=r)
    for _, x, y, z, vx, vy, vz in particles:
        sim.add(m=0.0, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)
    sim.N_active = len(bodies)
    sim.testparticle_type = 0
    sim.integrator = integrator
    if integrator == "mercurius":
        sim.integrator.r_crit_hill = 3.0
        sim.dt = dt
    return sim


def mercurius_positions(bodies, particles, dt, years):
    sim = simulation(bodies, particles, "mercurius", dt)
    sim.integrate(years * YEAR, exact_finish_time=0)
    nb = len(bodies)
    pos = np.array([[p.x, p.y, p.z] for p in sim.particles[nb:]])
    return sim.t, pos


def mercurius_rate(bodies, particles, dt, years):
    sim = simulation(bodies, particles, "mercurius", dt)
    t0 = time.perf_counter()
    sim.integrate(years * YEAR, exact_finish_time=0)
    return len(particles) * sim.t / YEAR / (time.perf_counter() - t0)


def ias15_at(bodies, particle, times):
    """The comet's IAS15 positions at each of `times` (sorted), alone with the five bodies."""
    sim = simulation(bodies, [particle], "ias15")
    out = []
    for t in times:
        sim.integrate(t, exact_finish_time=1)
        p = sim.particles[len(bodies)]
        out.append([p.x, p.y, p.z])
    return out


def accuracy(n=300, years=1000.0, rate_years=10_000.0):
    tmp = tempfile.mkdtemp()
    init, fin = os.path.join(tmp, "init.csv"), os.path.join(tmp, "final.csv")
    run_ours(n, 0.001, initial=init)
    bodies, particles = read_initial(init)
    runs = {}  # label -> (times per comet, positions per comet, active mask)
    for s, ps in OURS:
        line = run_ours(n, years, step_per_au=s, final=fin, planet_step=ps)
        with open(fin) as f:
            rows = sorted(csv.DictReader(f), key=lambda r: int(r["id"]))
        runs[f"ours step_per_au={s:g}d planets={ps:g}d"] = (
            np.array([float(r["time_days"]) for r in rows]),
            np.array([[float(r[c]) for c in "xyz"] for r in rows]),
            np.array([r["status"] == "active" for r in rows]),
            float(line["particle_steps_per_s"]) / float(line["particle_years_per_s"]),
        )
    for dt in MERCURIUS_DT_YEARS:
        t, pos = mercurius_positions(bodies, particles, dt * YEAR, years)
        runs[f"mercurius dt={dt:g}yr"] = (np.full(n, t), pos, np.ones(n, dtype=bool), 1.0 / dt)
    active = np.logical_and.reduce([r[2] for r in runs.values()])
    errors = {label: np.full(n, np.nan) for label in runs}
    for i in np.nonzero(active)[0]:
        times = sorted({float(r[0][i]) for r in runs.values()})
        ref = dict(zip(times, ias15_at(bodies, particles[i], times)))
        for label, r in runs.items():
            errors[label][i] = np.linalg.norm(r[1][i] - np.array(ref[float(r[0][i])]))
    print(f"# n={n} years={years:g}, {int(active.sum())} comets active in every run; reference IAS15 "
          f"(rebound {rebound.__version__}, epsilon 1e-9, each comet alone with the five bodies); "
          f"rates: {rate_years:g} yr, one thread, best of {REPEATS}; load {os.getloadavg()[0]:.2f}")
    rates = {label: float("nan") if rate_years <= 0 else 0.0 for label in runs}
    for _ in range(REPEATS if rate_years > 0 else 0):
        for s, ps in OURS:
            label = f"ours step_per_au={s:g}d planets={ps:g}d"
            rate = float(run_ours(n, rate_years, step_per_au=s, planet_step=ps)["particle_years_per_s"])
            rates[label] = max(rates[label], rate)
        for dt in MERCURIUS_DT_YEARS:
            label = f"mercurius dt={dt:g}yr"
            rates[label] = max(rates[label], mercurius_rate(bodies, particles, dt * YEAR, rate_years))
    for label, r in runs.items():
        e = errors[label][active]
        print(f"{label} steps_per_particle_year={r[3]:.3f} median_error_au={np.median(e):.4e} "
              f"p90_error_au={np.percentile(e, 90):.4e} particle_years_per_s={rates[label]:.4e}",
              flush=True)


def scaling(n=1000, years=10_000.0):
    best = {1: 0.0, 2: 0.0}
    for _ in range(REPEATS):
        for threads in (1, 2):
            rate = float(run_ours(n, years, threads=threads)["particle_years_per_s"])
            best[threads] = max(best[threads], rate)
    print(f"n={n} years={years:g} one_thread={best[1]:.4e} two_threads={best[2]:.4e} "
          f"ratio={best[2] / best[1]:.3f} load={os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    mode, args = sys.argv[1], [float(a) for a in sys.argv[2:]]
    if mode == "accuracy":
        accuracy(int(args[0]) if args else 300, *args[1:3])
    else:
        scaling(int(args[0]) if args else 1000, *args[1:2])
