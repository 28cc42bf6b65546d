"""A Centaur population integrated through its close encounters by REBOUND's MERCURIUS: the
independent reference of the `centaur-population` experiment.

Reads initial.csv (the barycentric states of the Sun, the four giants and the comets, written
by `CENTAUR_THROUGHPUT_INITIAL=initial.csv centaur_throughput N ...`; G = 1 with the masses
set to G m, so that the units are AU and days), integrates the first N comets as test
particles with MERCURIUS (r_crit_hill = 3, time step DT_YEARS) for YEARS, and writes one row
per comet: id, end (`active`, `perihelion`, `ejected`, `collision_<planet>`), end time (days,
empty if active) and planet (empty unless a collision).

End rules, as symplectic's `RemovalRules` and encounter ends state them:
- collision: closer to a planet's centre than its equatorial radius, or to the Sun's than its
  nominal radius (sim.collision = "direct", the bodies' r set; the comet is removed in the
  collision callback at the time REBOUND reports it; `collision_sun` for the Sun);
- checked every CHECK_YEARS for the comets outside 3 Hill radii of every planet (where
  barycentric elements mean something): the barycentric osculating perihelion about
  G (M_sun + sum m_j) below 2.5 AU (`perihelion`), or unbound (v^2 r >= 2 G M) beyond 100 AU
  (`ejected`). The end time is the time of the check.

Usage: python mercurius_population.py initial.csv out.csv N YEARS [DT_YEARS] [CHECK_YEARS] [FIRST]

FIRST (default 0): integrate the N comets from the FIRST-th on (0-based, in file order), so that
a large sample can be split into processes run side by side.

`benches/scripts/centaurs_vs_mercurius.py` imports `read_initial`, `simulation` and `advance`
to run MERCURIUS under these end rules.
"""
import csv
import sys
import time

import numpy as np
import rebound

DAYS_PER_YEAR = 365.25
AU_KM = 149_597_870.7
# Equatorial (1 bar) radii, km: Archinal et al. 2018, Table 5 (as symplectic::GIANT_PLANET_RADII_KM).
RADII_KM = [71_492.0, 60_268.0, 25_559.0, 24_764.0]
# The IAU 2015 nominal solar radius, km (Resolution B3; as symplectic::SUN_RADIUS_AU).
SUN_RADIUS_KM = 695_700.0
NAMES = ["Jupiter", "Saturn", "Uranus", "Neptune"]
MIN_PERIHELION_AU = 2.5
EJECTION_DISTANCE_AU = 100.0
HILL_FACTOR = 3.0


def read_initial(src, n, first=0):
    """The bodies' rows and `n` comets' rows of initial.csv from the `first`-th comet on:
    (id, [gm, x, y, z, vx, vy, vz])."""
    bodies, comets = [], []
    with open(src) as f:
        for row in csv.DictReader(f):
            values = [float(row[k]) for k in ("gm", "x", "y", "z", "vx", "vy", "vz")]
            (bodies if row["kind"] == "body" else comets).append((int(row["id"]), values))
    return bodies, comets[first:first + n]


def simulation(bodies, comets, dt_years):
    """MERCURIUS (r_crit_hill = 3, dt = dt_years) on the bodies and the comets (test particles),
    collisions searched; returns (sim, ends): `ends[id] = (end, time_days, planet)`, filled by
    the collision callback here and by `advance`."""
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.integrator = "mercurius"
    sim.integrator.r_crit_hill = HILL_FACTOR
    sim.dt = dt_years * DAYS_PER_YEAR
    sim.collision = "direct"
    for k, (_, b) in enumerate(bodies):
        r = (SUN_RADIUS_KM if k == 0 else RADII_KM[k - 1]) / AU_KM
        sim.add(m=b[0], x=b[1], y=b[2], z=b[3], vx=b[4], vy=b[5], vz=b[6], r=r, name=f"body{k}")
    for cid, c in comets:
        sim.add(m=0.0, x=c[1], y=c[2], z=c[3], vx=c[4], vy=c[5], vz=c[6], r=0.0, name=str(cid))
    n_active = len(bodies)
    sim.N_active = n_active
    sim.testparticle_type = 0
    ends = {cid: ("active", None, None) for cid, _ in comets}

    def resolve(sim_pointer, collision):
        s = sim_pointer.contents
        i, j = collision.p1, collision.p2
        body, comet = (i, j) if i < n_active else (j, i)
        if comet < n_active:
            return 0
        cid = int(s.particles[comet].name)
        name = "Sun" if body == 0 else NAMES[body - 1]
        ends[cid] = ("collision_sun" if body == 0 else f"collision_{name}", s.t, name)
        return 2 if comet == j else 1

    sim.collision_resolve = resolve
    return sim, ends


def advance(sim, ends, n_active, t_end, check, progress=None):
    """Integrates to `t_end` (days) in chunks of `check` days, removing after each chunk the
    comets outside 3 Hill radii of every planet whose barycentric perihelion is below 2.5 AU or
    that are unbound beyond 100 AU; returns the number of chunks. `progress = (chunks,
    callback)`: `callback()` after every `chunks` chunks."""
    gm = np.array([sim.particles[k].m for k in range(n_active)])
    gm_total = gm.sum()
    steps = 0
    t = sim.t
    while t < t_end and sim.N > n_active:
        t = min(t + check, t_end)
        sim.integrate(t, exact_finish_time=0)
        steps += 1
        xyz = np.zeros((sim.N, 3))
        vxyz = np.zeros((sim.N, 3))
        sim.serialize_particle_data(xyz=xyz, vxvyvz=vxyz)
        com = gm @ xyz[:n_active] / gm_total
        vcom = gm @ vxyz[:n_active] / gm_total
        q = xyz[n_active:] - com
        v = vxyz[n_active:] - vcom
        sun = xyz[0]
        near = np.zeros(len(q), dtype=bool)
        for k in range(1, n_active):
            hill = np.linalg.norm(xyz[k] - sun) * (gm[k] / (3.0 * gm[0])) ** (1.0 / 3.0)
            near |= np.linalg.norm(xyz[n_active:] - xyz[k], axis=1) < HILL_FACTOR * hill
        r = np.linalg.norm(q, axis=1)
        v2 = np.einsum("ij,ij->i", v, v)
        h2 = np.einsum("ij,ij->i", np.cross(q, v), np.cross(q, v))
        energy = 0.5 * v2 - gm_total / r
        e = np.sqrt(np.maximum(1.0 + 2.0 * energy * h2 / gm_total**2, 0.0))
        perihelion = h2 / (gm_total * (1.0 + e))
        ejected = (~near) & (v2 * r >= 2.0 * gm_total) & (r > EJECTION_DISTANCE_AU)
        low = (~near) & (~ejected) & (perihelion < MIN_PERIHELION_AU)
        # Removed by index, from the last, so that the indices still to remove stay valid.
        for idx in np.nonzero(ejected | low)[0][::-1]:
            index = n_active + int(idx)
            cid = int(sim.particles[index].name)
            ends[cid] = ("ejected" if ejected[idx] else "perihelion", sim.t, None)
            sim.remove(index)
        if progress and steps % progress[0] == 0:
            progress[1]()
    return steps


def write_ends(dst, comets, ends):
    """One row per comet: id, end, end time (days; empty if active), planet."""
    with open(dst, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["id", "end", "end_time_days", "planet"])
        for cid, _ in comets:
            end, t_e, planet = ends[cid]
            w.writerow([cid, end, "" if t_e is None else repr(t_e), planet or ""])


def main(src, dst, n, years, dt_years=0.1, check_years=1.0, first=0):
    bodies, comets = read_initial(src, n, first)
    sim, ends = simulation(bodies, comets, dt_years)
    n_active = len(bodies)
    start = time.time()

    def partial():
        # The ends so far, `active` meaning active at the time printed: a long run that is
        # stopped still leaves a reference censored at that time.
        write_ends(dst + ".partial", comets, ends)
        print(f"t = {sim.t / DAYS_PER_YEAR:.0f} yr, {sim.N - n_active} active, "
              f"{time.time() - start:.0f} s, ends so far in {dst}.partial",
              file=sys.stderr, flush=True)

    advance(sim, ends, n_active, years * DAYS_PER_YEAR, check_years * DAYS_PER_YEAR,
            (10000, partial))
    seconds = time.time() - start
    left = {int(sim.particles[k].name) for k in range(n_active, sim.N)}
    if left != {cid for cid, v in ends.items() if v[0] == "active"}:
        sys.exit("the comets left in the simulation are not those recorded as active")
    write_ends(dst, comets, ends)
    print(f"rebound {rebound.__version__} mercurius n={len(comets)} first={first} years={years} "
          f"dt_years={dt_years} check_years={check_years} seconds={seconds:.1f} "
          f"active={sum(1 for v in ends.values() if v[0] == 'active')}", file=sys.stderr)


if __name__ == "__main__":
    a = sys.argv[1:]
    if len(a) < 4:
        sys.exit(__doc__)
    main(a[0], a[1], int(a[2]), float(a[3]), *(float(x) for x in a[4:6]),
         *(int(x) for x in a[6:7]))
