"""Side by side at matched accuracy: symplectic::Population through close encounters (the
centaur_throughput example) and REBOUND MERCURIUS with test particles, on the same planets, the
same Centaurs and the same end rules, run back to back by this one script.

Needs REBOUND in a throwaway virtual environment (never a dependency of the workspace):
    python3 -m venv /tmp/reb43 && /tmp/reb43/bin/pip install "rebound==5.2.*"
Run from the workspace root, after `cargo build --release -p benches --example centaur_throughput`
(CARGO_TARGET_DIR or target/; CENTAUR_THROUGHPUT=PATH names the binary), holding the build lock
for the whole run so that nothing else runs during the timings:
    flock /tmp/build.lock /tmp/reb43/bin/python benches/scripts/centaurs_vs_mercurius.py matched [N] [YEARS] [RATE_YEARS]

matched: N = 300 Centaurs (benches::centaur_population, seed 2027: the comets of
populations/centaurs.csv) for YEARS = 1 kyr, each code at several settings. End rules on both
sides (those of populations/centaurs.toml): collision with a planet's equatorial radius or the
Sun's nominal radius, barycentric q < 2.5 AU, unbound beyond 100 AU. Ours checks them at every
step; MERCURIUS searches collisions (sim.collision = "direct", the bodies' r set) and the
driver of reference-data/centaur-population/mercurius_population.py (imported) removes the
others once per simulated year outside 3 Hill radii.
Error: each comet's position at its final time against IAS15 (REBOUND, epsilon = 1e-11, the
comet alone with the Sun and the four giants; the reference's own error is the distance to
IAS15 at epsilon = 1e-9, printed) over the comets active in every run: median and 90th
percentile.
Speed: particle-years per second of wall time over RATE_YEARS = 10 kyr (each comet counted
until its end), best of 3 interleaved runs; ours on 1 and 2 threads (RAYON_NUM_THREADS),
MERCURIUS on one (it has no threads for test particles; OMP_NUM_THREADS = 1).
Matched accuracy: for each setting of ours, MERCURIUS' speed at the same 90th-percentile error,
interpolated log-log between its two settings that bracket it (blank outside their range).
"""
import csv
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import rebound

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "../../reference-data/centaur-population"))
import mercurius_population as mp  # noqa: E402

EXAMPLE = os.environ.get("CENTAUR_THROUGHPUT", os.path.join(
    os.environ.get("CARGO_TARGET_DIR", "target"), "release/examples/centaur_throughput"))
YEAR = 365.25
# Ours: (first step: days per AU of initial distance, or "20d" = 20 d for every comet as in
# populations/centaurs.toml; planets' S6 step, days; encounter tolerance).
OURS = [("20d", 91.3125, 1e-12), ("40d", 91.3125, 1e-12), ("10d", 91.3125, 1e-12),
        ("5d", 91.3125, 1e-12), ("20d", 91.3125, 1e-10)]
MERCURIUS_DT_YEARS = [0.4, 0.2, 0.1, 0.05, 0.025]
REPEATS = 3
IAS15_EPSILON = 1e-11
IAS15_CHECK_EPSILON = 1e-9


def run_ours(n, years, setting, threads=1, initial=None, final=None):
    first, planet_step, tol = setting
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    if initial:
        env["CENTAUR_THROUGHPUT_INITIAL"] = initial
    if final:
        env["CENTAUR_THROUGHPUT_FINAL"] = final
    args = [str(n), repr(years), first, repr(tol), "2027", repr(planet_step)]
    out = subprocess.run([EXAMPLE] + args, env=env,
                         check=True, capture_output=True, text=True).stdout
    last = out.strip().splitlines()[-1]
    return dict(kv.split("=") for kv in last.split())


def label_ours(setting):
    first, planet_step, tol = setting
    return f"ours first={first} planets={planet_step:g}d tol={tol:g}"


def mercurius_run(bodies, comets, dt_years, years):
    """MERCURIUS under the end rules: (final time, ids -> position or None if ended,
    particle-years, seconds)."""
    sim, ends = mp.simulation(bodies, comets, dt_years)
    nb = len(bodies)
    t0 = time.perf_counter()
    mp.advance(sim, ends, nb, years * YEAR, YEAR)
    seconds = time.perf_counter() - t0
    pos = {cid: None for cid, _ in comets}
    for p in sim.particles[nb:]:
        pos[int(p.name)] = np.array([p.x, p.y, p.z])
    particle_years = sum((sim.t if e[1] is None else e[1]) for e in ends.values()) / YEAR
    return sim.t, pos, particle_years, seconds


def ias15_at(bodies, comet, times, epsilon):
    """The comet's IAS15 positions at each of `times` (sorted), alone with the five bodies."""
    sim = rebound.Simulation()
    sim.G = 1.0
    for _, (gm, x, y, z, vx, vy, vz) in bodies:
        sim.add(m=gm, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)
    _, (_, x, y, z, vx, vy, vz) = comet
    sim.add(m=0.0, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)
    sim.N_active = len(bodies)
    sim.testparticle_type = 0
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    out = []
    for t in times:
        sim.integrate(t, exact_finish_time=1)
        p = sim.particles[len(bodies)]
        out.append(np.array([p.x, p.y, p.z]))
    return out


def interpolate_speed(p90, points):
    """MERCURIUS' speed at 90th-percentile error `p90`, log-log between the bracketing points
    (error, speed); None outside their range."""
    pts = sorted(points)
    for (e0, s0), (e1, s1) in zip(pts, pts[1:]):
        if e0 <= p90 <= e1:
            w = np.log(p90 / e0) / np.log(e1 / e0)
            return float(np.exp(np.log(s0) + w * np.log(s1 / s0)))
    return None


def matched(n=300, years=1000.0, rate_years=10_000.0):
    tmp = tempfile.mkdtemp()
    init, fin = os.path.join(tmp, "init.csv"), os.path.join(tmp, "final.csv")
    run_ours(n, 0.001, OURS[0], initial=init)
    bodies, comets = mp.read_initial(init, n)
    ids = [cid for cid, _ in comets]
    runs = {}  # label -> {id: (time, position or None)}, steps per particle-year
    for s in OURS:
        line = run_ours(n, years, s, final=fin)
        with open(fin) as f:
            rows = {int(r["id"]): r for r in csv.DictReader(f)}
        runs[label_ours(s)] = ({cid: (float(rows[cid]["time_days"]),
                                      np.array([float(rows[cid][c]) for c in "xyz"])
                                      if rows[cid]["status"] == "active" else None) for cid in ids},
                               float(line["particle_steps_per_s"]) / float(line["particle_years_per_s"]))
    for dt in MERCURIUS_DT_YEARS:
        t, pos, _, _ = mercurius_run(bodies, comets, dt, years)
        runs[f"mercurius dt={dt:g}yr"] = ({cid: (t, pos[cid]) for cid in ids}, 1.0 / dt)
    active = [i for i, cid in enumerate(ids) if all(r[0][cid][1] is not None for r in runs.values())]
    errors = {label: [] for label in runs}
    reference_error = []
    for i in active:
        cid = ids[i]
        times = sorted({r[0][cid][0] for r in runs.values()})
        ref = dict(zip(times, ias15_at(bodies, comets[i], times, IAS15_EPSILON)))
        check = ias15_at(bodies, comets[i], times[-1:], IAS15_CHECK_EPSILON)[0]
        reference_error.append(np.linalg.norm(check - ref[times[-1]]))
        for label, r in runs.items():
            t, q = r[0][cid]
            errors[label].append(np.linalg.norm(q - ref[t]))
    print(f"# n={n} years={years:g}: {len(active)} comets active in every run; reference IAS15 "
          f"(rebound {rebound.__version__}, epsilon {IAS15_EPSILON:g}); IAS15 at epsilon "
          f"{IAS15_CHECK_EPSILON:g} differs from it by median {np.median(reference_error):.2e} AU, "
          f"90th percentile {np.percentile(reference_error, 90):.2e} AU", flush=True)
    rates = {label: {} for label in runs}
    loads = []
    for _ in range(REPEATS if rate_years > 0 else 0):
        loads.append(os.getloadavg()[0])
        for s in OURS:
            for threads in (1, 2):
                rate = float(run_ours(n, rate_years, s, threads=threads)["particle_years_per_s"])
                rates[label_ours(s)][threads] = max(rates[label_ours(s)].get(threads, 0.0), rate)
        for dt in MERCURIUS_DT_YEARS:
            _, _, py, sec = mercurius_run(bodies, comets, dt, rate_years)
            label = f"mercurius dt={dt:g}yr"
            rates[label][1] = max(rates[label].get(1, 0.0), py / sec)
    print(f"# rates: {rate_years:g} yr, best of {REPEATS}; load average (1 min) before each "
          f"round {', '.join(f'{x:.2f}' for x in loads)}", flush=True)
    merc = [(np.percentile(errors[f"mercurius dt={dt:g}yr"], 90), rates[f"mercurius dt={dt:g}yr"][1])
            for dt in MERCURIUS_DT_YEARS if rates[f"mercurius dt={dt:g}yr"]]
    for label, r in runs.items():
        e = np.array(errors[label])
        p90 = np.percentile(e, 90)
        one, two = rates[label].get(1, float("nan")), rates[label].get(2, float("nan"))
        line = (f"{label} steps_per_particle_year={r[1]:.3f} median_error_au={np.median(e):.3e} "
                f"p90_error_au={p90:.3e} py_per_s_1thread={one:.3e} py_per_s_2threads={two:.3e}")
        if label.startswith("ours") and merc:
            m = interpolate_speed(p90, merc)
            if m:
                line += (f" mercurius_at_same_p90={m:.3e} ratio_1thread={one / m:.2f} "
                         f"ratio_2threads={two / m:.2f}")
        print(line, flush=True)


if __name__ == "__main__":
    mode, args = sys.argv[1], [float(a) for a in sys.argv[2:]]
    if mode != "matched":
        sys.exit(__doc__)
    matched(int(args[0]) if args else 300, *args[1:3])
