"""Single close encounters integrated by REBOUND's IAS15: the reference for
symplectic's encounter integrator (crates/symplectic/tests/encounters.rs).

Reads initial.csv (written by `cargo run --release -p symplectic --example encounter_cases`),
integrates each case (the Sun, four giants, one massless particle; G = 1 with the masses
set to G m in AU^3/day^2, so that the units are AU and days) to its t_end with IAS15 at
epsilon = 1e-9 (REBOUND's default) and at 1e-11, and writes final.csv: the particle's and the
planet's barycentric states at t_end for both epsilons, and the smallest particle-planet
distance sampled every t_end/20000 days (epsilon = 1e-9).

Usage: python ias15_encounters.py initial.csv final.csv
"""
import csv
import sys

import rebound


def run(bodies, particle, planet, t_end, epsilon, samples=0):
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    for b in bodies:
        sim.add(m=b[0], x=b[1], y=b[2], z=b[3], vx=b[4], vy=b[5], vz=b[6])
    sim.add(m=0.0, x=particle[1], y=particle[2], z=particle[3],
            vx=particle[4], vy=particle[5], vz=particle[6])
    sim.N_active = len(bodies)
    sim.testparticle_type = 0
    closest = float("inf")
    if samples:
        for k in range(1, samples + 1):
            sim.integrate(t_end * k / samples, exact_finish_time=1)
            p, q = sim.particles[-1], sim.particles[planet]
            d = ((p.x - q.x) ** 2 + (p.y - q.y) ** 2 + (p.z - q.z) ** 2) ** 0.5
            closest = min(closest, d)
    else:
        sim.integrate(t_end, exact_finish_time=1)
    p, q = sim.particles[-1], sim.particles[planet]
    return [p.x, p.y, p.z, p.vx, p.vy, p.vz], [q.x, q.y, q.z, q.vx, q.vy, q.vz], closest


def main(src, dst):
    cases = {}
    with open(src) as f:
        for row in csv.DictReader(f):
            c = cases.setdefault(int(row["case"]), {"bodies": [], "particle": None})
            values = [float(row[k]) for k in ("gm", "x", "y", "z", "vx", "vy", "vz")]
            c["t_end"] = float(row["t_end"])
            if row["kind"] == "body":
                c["bodies"].append(values)
            else:
                c["particle"] = values
                c["planet"] = int(row["index"])
    with open(dst, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "planet", "epsilon", "t_end", "closest",
                    "x", "y", "z", "vx", "vy", "vz",
                    "planet_x", "planet_y", "planet_z", "planet_vx", "planet_vy", "planet_vz"])
        for case, c in sorted(cases.items()):
            for epsilon, samples in ((1e-9, 20000), (1e-11, 0)):
                part, planet, closest = run(c["bodies"], c["particle"], c["planet"],
                                            c["t_end"], epsilon, samples)
                w.writerow([case, c["planet"], repr(epsilon), repr(c["t_end"]),
                            repr(closest) if samples else ""]
                           + [repr(x) for x in part] + [repr(x) for x in planet])


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
