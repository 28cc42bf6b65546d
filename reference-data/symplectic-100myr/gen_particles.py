#!/usr/bin/env python3
"""Derive the test particles' initial state vectors of Chegodaeva (2004) from their elements.

Written for this project (plain Python 3, no packages), independently of the Rust code that
reads its output. Run from anywhere:  python3 reference-data/symplectic-100myr/gen_particles.py
It writes particles.csv beside this script. See SOURCE.md for the choices made.
"""
import math
import os

G = 2.95912208286e-4          # AU^3 Msun^-1 day^-2 (Hairer, Lubich & Wanner, Table 2.1)
M_SUN = 1.00000597682         # Msun, inner planets included (same table)
MU = G * M_SUN                # heliocentric two-body parameter of a massless particle

# name, a (AU), q (AU), e as printed, i (deg), starting distance (AU), initial steps S2/S6 (day)
PARTICLES = [
    ("particle1", 60.91, 30.01, 0.50, 16.0, 91.0, 298.0, 910.0),
    ("particle2", 97.12, 30.2, 0.68, 13.0, 96.0, 310.0, 953.0),
]


def state(a, q, inc_deg, r):
    """Heliocentric ecliptic state for Omega = omega = 0, outbound (true anomaly in (0, pi))."""
    e = 1.0 - q / a                    # from a and q; the printed e is this to 2 digits, truncated
    p = a * (1.0 - e * e)
    cos_f = (p / r - 1.0) / e
    if not -1.0 <= cos_f <= 1.0:
        raise ValueError(f"r = {r} AU is not on the orbit a = {a}, q = {q}")
    f = math.acos(cos_f)               # in [0, pi]: r increasing (outbound branch)
    sin_f = math.sin(f)
    x_orb, y_orb = r * cos_f, r * sin_f
    k = math.sqrt(MU / p)
    vx_orb, vy_orb = -k * sin_f, k * (e + cos_f)
    i = math.radians(inc_deg)
    # Omega = 0, omega = 0: perihelion on the ascending node, the +x axis; rotate by i about x.
    pos = (x_orb, y_orb * math.cos(i), y_orb * math.sin(i))
    vel = (vx_orb, vy_orb * math.cos(i), vy_orb * math.sin(i))
    return e, math.degrees(f), pos, vel


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "particles.csv")
    with open(out, "w") as fh:
        fh.write("# Test particles of Chegodaeva (2004), 'Numerical experiments'; derived by gen_particles.py.\n")
        fh.write("# Heliocentric ECLIPTIC frame (J2000 obliquity 84381.448 arcsec), epoch of outer_solar_system.csv;\n")
        fh.write("# AU, AU/day, days. Omega = omega = 0, outbound branch, e = 1 - q/a, mu = G*M_sun. See SOURCE.md.\n")
        fh.write("name,a_au,q_au,e,i_deg,r0_au,true_anomaly_deg,x,y,z,vx,vy,vz,dt0_s2_day,dt0_s6_day\n")
        for name, a, q, _e_printed, inc, r, dt2, dt6 in PARTICLES:
            e, f, pos, vel = state(a, q, inc, r)
            vals = [a, q, e, inc, r, f, *pos, *vel, dt2, dt6]
            fh.write(name + "," + ",".join(repr(v) for v in vals) + "\n")
    print("wrote", out)


if __name__ == "__main__":
    main()
