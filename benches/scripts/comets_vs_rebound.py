"""Side by side: symplectic::Population (the comet_throughput example) and REBOUND WHFast with
test particles, on the same planets and the same comets, run back to back by this one script.

Needs REBOUND in a throwaway virtual environment (never a dependency of the workspace):
    python3 -m venv /work/venvs/rebound-comets && /work/venvs/rebound-comets/bin/pip install "rebound==5.2.*"
Run from the workspace root, after `cargo build --release -p benches --example comet_throughput`:
    flock /work/bench.lock /work/venvs/rebound-comets/bin/python benches/scripts/comets_vs_rebound.py throughput
    flock /work/bench.lock /work/venvs/rebound-comets/bin/python benches/scripts/comets_vs_rebound.py accuracy

throughput: particle-years per second for N = 10 … 10^6 (span chosen per N, printed), ours (the
default configuration) on 1 and 2 threads (RAYON_NUM_THREADS), REBOUND WHFast at tau = 365.25 d
on 1 thread (OMP_NUM_THREADS=1).
accuracy: N = 200 comets for 10 kyr; the median over particles of the distance to a converged
reference (REBOUND IAS15, evaluated at each particle's own final time), ours (particles S2 or
S6 at several first steps, planets S2 or S6) against REBOUND WHFast at tau = 365.25 d.
`throughput SCHEME DT0 PLANETS PLANET_STEP` measures another configuration of ours (e.g.
`throughput s2 730.5 s6 730.5`). `accuracy K` runs only the first K configurations (the first is the default: S2 particles,
first step 547.875 d, S6 planets at 730.5 d).
"""
import csv
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import rebound

EXAMPLE = "target/release/examples/comet_throughput"
YEAR = 365.25


# Our default configuration (the example's): S2 particles with first step 1.5 yr, planets S6 at
# 2 yr. The accuracy mode shows its median error at 10 kyr below WHFast's at tau = 1 yr.
DEFAULT = ("s2", 1.5 * YEAR, "s6", 2.0 * YEAR)


def run_ours(n, years, scheme=DEFAULT[0], dt0=DEFAULT[1], threads=1, initial=None, final=None,
             planets=DEFAULT[2], planet_step=DEFAULT[3]):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    if initial:
        env["COMET_THROUGHPUT_INITIAL"] = initial
    if final:
        env["COMET_THROUGHPUT_FINAL"] = final
    out = subprocess.run([EXAMPLE, str(n), str(years), scheme, repr(dt0), planets, repr(planet_step)], env=env,
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


def rebound_sim(bodies, particles, integrator="whfast", dt=YEAR):
    sim = rebound.Simulation()
    sim.G = 1.0  # masses given as G m (AU^3/day^2)
    for gm, x, y, z, vx, vy, vz in bodies:
        sim.add(m=gm, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)
    for _, x, y, z, vx, vy, vz in particles:
        sim.add(m=0.0, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)
    sim.N_active = len(bodies)
    sim.testparticle_type = 0
    sim.integrator = integrator
    if integrator == "whfast":
        sim.dt = dt
        sim.integrator.coordinates = "democraticheliocentric"
        sim.integrator.safe_mode = 0
    else:
        sim.dt = 1.0
    return sim


REPEATS = 3


def throughput(config=DEFAULT):
    scheme, dt0, planets, planet_step = config
    print(f"# ours: particles {scheme}, first step {dt0} d, planets {planets} at {planet_step} d; "
          "REBOUND WHFast tau = 365.25 d; best of 3 interleaved runs each; load = 1-minute load average before the row")
    print("# N years ours_1t ours_2t rebound_1t (particle-years per second) ratio_1t ratio_2t_over_1t load")
    tmp = tempfile.mkdtemp()
    for n in [10, 100, 1000, 10_000, 100_000, 1_000_000]:
        load = os.getloadavg()[0]
        years = max(2.0, min(20_000.0, 2.0e6 / n))
        init = os.path.join(tmp, "init.csv")
        run_ours(n, 1.0, scheme, dt0, initial=init, planets=planets, planet_step=planet_step)
        bodies, particles = read_initial(init)

        def ours(threads):
            line = run_ours(n, years, scheme, dt0, threads=threads, planets=planets, planet_step=planet_step)
            return float(line["particle_years_per_s"])

        def rebound_once():
            sim = rebound_sim(bodies, particles)
            t0 = time.perf_counter()
            sim.integrate(years * YEAR, exact_finish_time=0)
            return n * sim.t / YEAR / (time.perf_counter() - t0)

        # Best of REPEATS interleaved runs of each: on a shared machine a run is only ever
        # slowed down by others, so the fastest is the closest to the program's own speed.
        o1 = o2 = rb = 0.0
        for _ in range(REPEATS):
            o1, o2, rb = max(o1, ours(1)), max(o2, ours(2)), max(rb, rebound_once())
        print(f"{n} {years:g} {o1:.4g} {o2:.4g} {rb:.4g} {o1 / rb:.3f} {o2 / o1:.3f} {load:.2f}", flush=True)


def accuracy(n=200, years=10_000.0):
    tmp = tempfile.mkdtemp()
    init, fin = os.path.join(tmp, "init.csv"), os.path.join(tmp, "final.csv")
    run_ours(n, 1.0, initial=init)
    bodies, particles = read_initial(init)
    # REBOUND WHFast at tau = 365.25 d, at 10 kyr exactly.
    wh = rebound_sim(bodies, particles)
    wh.integrate(years * YEAR, exact_finish_time=0)
    nb = len(bodies)
    wh_t = wh.t
    wh_pos = np.array([[wh.particles[nb + i].x, wh.particles[nb + i].y, wh.particles[nb + i].z] for i in range(n)])
    # Ours, several configurations, each particle at its own final time.
    runs = {}
    # (particle scheme, first particle step, planet map, planet step): the default (the
    # throughput mode's configuration) first, then other particle and planet steps, then the
    # planets by S2, then S6 throughout.
    configs = [DEFAULT, ("s2", 547.875, "s6", 365.25), ("s2", 730.5, "s6", 730.5),
               ("s2", 730.5, "s6", 365.25), ("s2", 365.25, "s6", 365.25), ("s2", 182.625, "s6", 365.25),
               ("s2", 365.25, "s2", 365.25), ("s2", 365.25, "s2", 182.625),
               ("s6", 365.25, "s6", 365.25), ("s6", 730.5, "s6", 730.5)]
    if len(sys.argv) > 2:
        configs = configs[:int(sys.argv[2])]
    for scheme, dt0, planets, planet_step in configs:
        key = (scheme, dt0, planets, planet_step)
        line = run_ours(n, years, scheme=scheme, dt0=dt0, final=fin, planets=planets, planet_step=planet_step)
        with open(fin) as f:
            rows = list(csv.DictReader(f))
        runs[key] = (line, rows)
    # Reference: IAS15, stopped at every time needed (sorted), recording the particle asked for.
    ref = rebound_sim(bodies, particles, integrator="ias15")
    wanted = [(wh_t, -1)]
    for key, (_, rows) in runs.items():
        for r in rows:
            wanted.append((float(r["time"]), (key, int(r["id"]))))
    wanted.sort(key=lambda w: w[0])
    ref_at = {}
    ref_wh = None
    for t, tag in wanted:
        ref.integrate(t, exact_finish_time=1)
        if tag == -1:
            ref_wh = np.array([[ref.particles[nb + i].x, ref.particles[nb + i].y, ref.particles[nb + i].z] for i in range(n)])
        else:
            p = ref.particles[nb + tag[1]]
            ref_at[tag] = np.array([p.x, p.y, p.z])
    err_wh = np.linalg.norm(wh_pos - ref_wh, axis=1)
    print(f"# n={n} years={years:g} reference=IAS15 (rebound {rebound.__version__})")
    print(f"rebound_whfast tau=365.25 median_error_au={np.median(err_wh):.4e} p90_error_au={np.percentile(err_wh, 90):.4e}")
    for key, (line, rows) in runs.items():
        errs = np.array([np.linalg.norm(np.array([float(r[c]) for c in "xyz"]) - ref_at[(key, int(r["id"]))])
                         for r in rows if r["status"] == "active"])
        print(f"ours {key[0]} dt0={key[1]} planets={key[2]} planet_step={key[3]} steps_per_particle_year={float(line['steps_per_particle_year']):.4f} "
              f"median_error_au={np.median(errs):.4e} p90_error_au={np.percentile(errs, 90):.4e} active={len(errs)}")


if __name__ == "__main__":
    if sys.argv[1] == "throughput" and len(sys.argv) == 6:
        # throughput SCHEME DT0 PLANETS PLANET_STEP: another configuration of ours.
        throughput((sys.argv[2], float(sys.argv[3]), sys.argv[4], float(sys.argv[5])))
    else:
        {"throughput": throughput, "accuracy": accuracy}[sys.argv[1]]()
