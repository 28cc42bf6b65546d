"""Comets passing a giant planet, integrated by REBOUND's IAS15: the reference for the
population path of symplectic (crates/symplectic/tests/population_path.rs).

Reads path_initial.csv (written by `cargo run --release -p symplectic --example path_bodies`):
the Sun and the four giants at the epoch and, per comet, its barycentric state at the epoch
and t_end. G = 1 with the masses set to G m (AU^3/day^2), so that the units are AU and days;
the comet is a test particle (N_active = 5, testparticle_type = 0). Writes:

- path_final.csv: per comet and epsilon (1e-9, REBOUND's default, and 1e-11), the comet's
  barycentric state at t_end (exact_finish_time = 1); for epsilon = 1e-9 also its smallest
  distance from the planet it passes, sampled every t_end/20000 days;
- path_planets.csv: per comet, the four planets' barycentric positions at t_end * k/8,
  k = 1..8 (epsilon = 1e-11), for the planets' own error against IAS15's;
- path_sensitivity.csv: per comet, the comet's response to a displacement of the planet it
  passes: the planet's initial position moved by DELTA along its heliocentric radius, its
  direction of motion and the normal of its orbit in turn (epsilon = 1e-11), the largest
  change of the comet's position and velocity at t_end (against the unmoved run, sampled
  alike), and the planet's own displacement, largest over the pass (sampled 64 times) and
  at the closest approach (t_end/2, where the comets are set up): per run; the ratios are
  the comet's sensitivity to an error of the planet's trajectory.

Usage: python ias15_path.py path_initial.csv path_final.csv path_planets.csv path_sensitivity.csv
"""
import csv
import math
import sys

import rebound

# The planet's initial displacement of the sensitivity runs (AU): large against IAS15's
# error (some 1e-12 AU here), small enough for the comet's response to stay linear (the
# closest approach is 0.0177 AU or more).
DELTA = 1e-7
PLANET_SAMPLES = 8
DISPLACEMENT_SAMPLES = 64


def simulation(bodies, comet, epsilon, shift=None):
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    for j, b in enumerate(bodies):
        q = list(b[1:4])
        if shift is not None and shift[0] == j:
            q = [q[c] + shift[1][c] for c in range(3)]
        sim.add(m=b[0], x=q[0], y=q[1], z=q[2], vx=b[4], vy=b[5], vz=b[6])
    sim.add(m=0.0, x=comet[1], y=comet[2], z=comet[3],
            vx=comet[4], vy=comet[5], vz=comet[6])
    sim.N_active = len(bodies)
    sim.testparticle_type = 0
    return sim


def state(p):
    return [p.x, p.y, p.z, p.vx, p.vy, p.vz]


def distance(a, b):
    return math.sqrt(sum((a[c] - b[c]) ** 2 for c in range(len(a))))


def final_state(bodies, comet, planet, t_end, epsilon, samples):
    sim = simulation(bodies, comet, epsilon)
    closest = float("inf")
    for k in range(1, samples + 1):
        sim.integrate(t_end * k / samples, exact_finish_time=1)
        p, q = sim.particles[-1], sim.particles[planet]
        closest = min(closest, distance(state(p)[:3], state(q)[:3]))
    return state(sim.particles[-1]), closest


def planet_positions(bodies, comet, t_end):
    sim = simulation(bodies, comet, 1e-11)
    rows = []
    for k in range(1, PLANET_SAMPLES + 1):
        t = t_end * k / PLANET_SAMPLES
        sim.integrate(t, exact_finish_time=1)
        for j in range(1, len(bodies)):
            rows.append((t, j, state(sim.particles[j])[:3]))
    return rows


def directions(bodies, planet):
    sun, b = bodies[0], bodies[planet]
    r = [b[1 + c] - sun[1 + c] for c in range(3)]
    v = [b[4 + c] - sun[4 + c] for c in range(3)]
    n = [r[1] * v[2] - r[2] * v[1], r[2] * v[0] - r[0] * v[2], r[0] * v[1] - r[1] * v[0]]
    unit = lambda x: [c / math.sqrt(sum(y * y for y in x)) for c in x]
    return {"radial": unit(r), "along": unit(v), "normal": unit(n)}


def sensitivity(bodies, comet, planet, t_end):
    """The largest comet change at t_end and planet displacement over the pass, per run."""
    base = simulation(bodies, comet, 1e-11)
    base_planet = []
    for k in range(1, DISPLACEMENT_SAMPLES + 1):
        base.integrate(t_end * k / DISPLACEMENT_SAMPLES, exact_finish_time=1)
        base_planet.append(state(base.particles[planet])[:3])
    nominal = state(base.particles[-1])
    out = []
    for name, d in directions(bodies, planet).items():
        sim = simulation(bodies, comet, 1e-11, (planet, [DELTA * c for c in d]))
        moved, at_closest = 0.0, 0.0
        for k in range(1, DISPLACEMENT_SAMPLES + 1):
            sim.integrate(t_end * k / DISPLACEMENT_SAMPLES, exact_finish_time=1)
            shift = distance(state(sim.particles[planet])[:3], base_planet[k - 1])
            moved = max(moved, shift)
            if 2 * k == DISPLACEMENT_SAMPLES:
                at_closest = shift
        s = state(sim.particles[-1])
        out.append((name, moved, at_closest, distance(s[:3], nominal[:3]),
                    distance(s[3:], nominal[3:])))
    return out


def read(src):
    bodies, comets = [], []
    with open(src) as f:
        for row in csv.DictReader(f):
            values = [float(row[k]) for k in ("gm", "x", "y", "z", "vx", "vy", "vz")]
            if row["kind"] == "body":
                bodies.append(values)
            else:
                comets.append((int(row["index"]), int(row["planet"]), values,
                               float(row["t_end"])))
    return bodies, comets


def main(src, final_dst, planets_dst, sensitivity_dst):
    bodies, comets = read(src)
    with open(final_dst, "w", newline="") as f, open(planets_dst, "w", newline="") as g, \
            open(sensitivity_dst, "w", newline="") as h:
        final = csv.writer(f)
        final.writerow(["comet", "planet", "epsilon", "t_end", "closest",
                        "x", "y", "z", "vx", "vy", "vz"])
        planets = csv.writer(g)
        planets.writerow(["comet", "t", "planet", "x", "y", "z"])
        sens = csv.writer(h)
        sens.writerow(["comet", "planet", "direction", "delta", "planet_displacement_max",
                       "planet_displacement_at_closest", "comet_position_change",
                       "comet_velocity_change"])
        for index, planet, comet, t_end in comets:
            for epsilon, samples in ((1e-9, 20000), (1e-11, 1)):
                s, closest = final_state(bodies, comet, planet, t_end, epsilon, samples)
                final.writerow([index, planet, repr(epsilon), repr(t_end),
                                repr(closest) if samples > 1 else ""]
                               + [repr(x) for x in s])
            for t, j, q in planet_positions(bodies, comet, t_end):
                planets.writerow([index, repr(t), j] + [repr(x) for x in q])
            for name, moved, at_closest, dq, dv in sensitivity(bodies, comet, planet, t_end):
                sens.writerow([index, planet, name, repr(DELTA), repr(moved), repr(at_closest),
                               repr(dq), repr(dv)])
            print(f"comet {index} done", file=sys.stderr)


if __name__ == "__main__":
    main(*sys.argv[1:5])
