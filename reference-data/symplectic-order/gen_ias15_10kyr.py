#!/usr/bin/env python3
"""Reference solution for the outer Solar System: REBOUND's IAS15 over 10,000 years.

Reads outer_solar_system.csv (beside this script), integrates Sun + Jupiter + Saturn + Uranus
+ Neptune with IAS15 and writes heliocentric positions and velocities of the planets at
t = 1000 yr and 10,000 yr (1 yr = 365.25 d). See SOURCE_ias15_10kyr.md.

    python3 gen_ias15_10kyr.py [--epsilon 0] [--dt 10] [--out ias15_10kyr.csv]
"""
import argparse
import csv
import os
import sys

import rebound

HERE = os.path.dirname(os.path.abspath(__file__))
G = 2.95912208286e-4  # AU^3 Msun^-1 day^-2 (Hairer, Lubich & Wanner, Sec. I.2.4)
DAYS_PER_YEAR = 365.25
CHECKPOINTS_YR = (1000, 10000)


def read_initial_conditions(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    # Fixed step (epsilon = 0): with an integer step in days the time t stays exact, whereas
    # adaptive steps (REBOUND's default epsilon = 1e-9) leave a round-off error of up to ~5e-8 d
    # in t at 10 kyr, i.e. up to ~4e-10 AU along the orbits. See SOURCE_ias15_10kyr.md.
    ap.add_argument("--epsilon", type=float, default=0.0,
                    help="IAS15 epsilon; 0 (default) = fixed step --dt, 1e-9 = REBOUND's adaptive")
    ap.add_argument("--dt", type=float, default=10.0,
                    help="IAS15 step in days (fixed if epsilon = 0, else the first step); default 10")
    ap.add_argument("--out", default=os.path.join(HERE, "ias15_10kyr.csv"))
    args = ap.parse_args()

    bodies = read_initial_conditions(os.path.join(HERE, "outer_solar_system.csv"))
    sim = rebound.Simulation()
    sim.G = G
    sim.integrator = "ias15"
    sim.integrator.epsilon = args.epsilon
    sim.exact_finish_time = 1
    sim.dt = args.dt
    for b in bodies:
        sim.add(m=float(b["m"]), x=float(b["x"]), y=float(b["y"]), z=float(b["z"]),
                vx=float(b["vx"]), vy=float(b["vy"]), vz=float(b["vz"]))
    # The heliocentric frame of the table drifts (6.8e-6 AU/day, ~25 AU in 10 kyr); integrate
    # in the barycentric frame to keep coordinates small. Output is heliocentric again.
    sim.move_to_com()
    e0 = sim.energy()

    rows, notes = [], []
    for years in CHECKPOINTS_YR:
        t = years * DAYS_PER_YEAR
        sim.integrate(t, exact_finish_time=1)
        de = (sim.energy() - e0) / abs(e0)
        notes.append(f"t = {years} yr: relative energy error {de:.3e}, IAS15 steps so far "
                     f"{sim.steps_done}")
        sun = sim.particles[0]
        for b, p in zip(bodies[1:], sim.particles[1:]):
            vals = (p.x - sun.x, p.y - sun.y, p.z - sun.z,
                    p.vx - sun.vx, p.vy - sun.vy, p.vz - sun.vz)
            rows.append([b["body"], f"{sim.t:.17g}"] + [f"{v:.17g}" for v in vals])

    with open(args.out, "w", newline="") as f:
        f.write(
            "# Outer Solar System (Hairer, Lubich & Wanner, GNI 2nd ed., Table 2.1) integrated with\n"
            f"# REBOUND {rebound.__version__} IAS15, epsilon = {args.epsilon:g}"
            + (f", fixed dt = {args.dt:g} d" if args.epsilon == 0 else " (adaptive)")
            + ", exact_finish_time = 1, "
            f"G = {G!r} AU^3 Msun^-1 day^-2.\n"
            "# Heliocentric, equatorial frame; positions in AU, velocities in AU/day; t_day from the\n"
            f"# epoch 1994-09-05 0h, 1 yr = {DAYS_PER_YEAR} d. Made by gen_ias15_10kyr.py; see "
            "SOURCE_ias15_10kyr.md.\n")
        for n in notes:
            f.write(f"# {n}\n")
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["body", "t_day", "x_au", "y_au", "z_au",
                    "vx_au_per_day", "vy_au_per_day", "vz_au_per_day"])
        w.writerows(rows)
    print("\n".join(notes), file=sys.stderr)


if __name__ == "__main__":
    main()
