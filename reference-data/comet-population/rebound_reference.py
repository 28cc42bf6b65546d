"""Reference for the `comet-population` experiment: the same initial conditions and removal
rule integrated by an independent code, REBOUND (WHFast, democratic heliocentric, test
particles), run once in a throwaway virtual environment (never a dependency):

    python3 -m venv /work/venvs/rebound-comets
    /work/venvs/rebound-comets/bin/pip install "rebound==5.2.*" numpy
    cargo run --release -p benches --example comet_throughput -- 1 1   # with the variable below
    COMET_THROUGHPUT_INITIAL=/tmp/bodies.csv target/release/examples/comet_throughput 1 1
    /work/venvs/rebound-comets/bin/python reference-data/comet-population/rebound_reference.py \
        /tmp/bodies.csv reference-data/comet-population/rebound_removals.csv

Planets: the Sun and four giants of `symplectic::outer_solar_system(Frame::EclipticJ2000)`, read
from the barycentric states the example writes (kind = body rows; G m in AU^3/day^2, so G = 1).
Particles: `symplectic::samples::NEAR_CIRCULAR` with seed 2021 (a 20-50 AU, e < 0.01, i < 1 deg,
angles uniform), drawn here with the same SplitMix64 sequence and turned into barycentric states
about G M (total mass). Removal: inside one Hill radius |Q_j - Q_sun| (m_j / 3 m_sun)^(1/3) of a
planet, checked at every step end, or unbound beyond 1000 AU. Output: one row per particle,
`id,a0_au,removal_time_years,reason` (removal time empty if it survived the span).
"""
import csv
import math
import sys

import numpy as np
import rebound

N = 10_000
SEED = 2021
YEARS = 10_000.0
TAU = 365.25
MASK = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed):
        self.x = seed

    def uniform(self):
        self.x = (self.x + 0x9E3779B97F4A7C15) & MASK
        z = self.x
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        return ((z ^ (z >> 31)) >> 11) * (1.0 / (1 << 53))

    def draw(self, lo, hi):
        return lo + (hi - lo) * self.uniform()


def near_circular(n, seed):
    r = SplitMix64(seed)
    out = []
    for _ in range(n):
        a = r.draw(20.0, 50.0)
        e = r.draw(0.0, 0.01)
        i = r.draw(0.0, math.pi / 180.0)
        node, peri, m = (r.draw(0.0, 2 * math.pi) for _ in range(3))
        out.append((a, e, i, node, peri, m))
    return out


def state(a, e, i, node, peri, m, mu):
    ea = m + e * math.sin(m)
    for _ in range(60):
        d = (ea - e * math.sin(ea) - m) / (1 - e * math.cos(ea))
        ea -= d
        if abs(d) < 1e-15:
            break
    b = a * math.sqrt(1 - e * e)
    n = math.sqrt(mu / a**3)
    edot = n / (1 - e * math.cos(ea))
    p = np.array([a * (math.cos(ea) - e), b * math.sin(ea), 0.0])
    v = np.array([-a * math.sin(ea) * edot, b * math.cos(ea) * edot, 0.0])

    def rz(t):
        c, s = math.cos(t), math.sin(t)
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])

    def rx(t):
        c, s = math.cos(t), math.sin(t)
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])

    rot = rz(node) @ rx(i) @ rz(peri)
    return rot @ p, rot @ v


def main(bodies_csv, out_csv):
    bodies = []
    with open(bodies_csv) as f:
        for row in csv.DictReader(f):
            if row["kind"] == "body":
                bodies.append([float(row[k]) for k in ("gm", "x", "y", "z", "vx", "vy", "vz")])
    mu = sum(b[0] for b in bodies)
    sim = rebound.Simulation()
    sim.G = 1.0
    for gm, x, y, z, vx, vy, vz in bodies:
        sim.add(m=gm, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)
    els = near_circular(N, SEED)
    for el in els:
        q, v = state(*el, mu)
        sim.add(m=0.0, x=q[0], y=q[1], z=q[2], vx=v[0], vy=v[1], vz=v[2])
    nb = len(bodies)
    sim.N_active = nb
    sim.testparticle_type = 0
    sim.integrator = "whfast"
    sim.integrator.coordinates = "democraticheliocentric"
    sim.integrator.safe_mode = 1
    sim.dt = TAU
    gm = np.array([b[0] for b in bodies])
    hill_c = np.cbrt(gm[1:] / (3 * gm[0]))
    removed = np.full(N, np.nan)
    reason = [""] * N
    xyz = np.zeros((sim.N, 3))
    vxyz = np.zeros((sim.N, 3))
    steps = int(round(YEARS * 365.25 / TAU))
    for k in range(1, steps + 1):
        sim.steps(1)
        sim.serialize_particle_data(xyz=xyz, vxvyvz=vxyz)
        sun = xyz[0]
        alive = np.isnan(removed)
        q = xyz[nb:]
        for j in range(1, nb):
            rh = np.linalg.norm(xyz[j] - sun) * hill_c[j - 1]
            hit = alive & (np.linalg.norm(q - xyz[j], axis=1) < rh)
            for idx in np.nonzero(hit)[0]:
                removed[idx] = sim.t / 365.25
                reason[idx] = f"hill_sphere_{j}"
            alive &= ~hit
        r = np.linalg.norm(q, axis=1)
        energy = 0.5 * np.sum(vxyz[nb:] ** 2, axis=1) - mu / r
        hit = alive & (energy >= 0) & (r > 1000.0)
        for idx in np.nonzero(hit)[0]:
            removed[idx] = sim.t / 365.25
            reason[idx] = "ejected"
    with open(out_csv, "w") as f:
        f.write(f"# rebound {rebound.__version__}, WHFast democratic heliocentric, tau = {TAU} d, "
                f"safe_mode = 1, N = {N}, seed = {SEED}, span = {YEARS} yr\n")
        f.write("id,a0_au,removal_time_years,reason\n")
        for idx, el in enumerate(els):
            t = "" if math.isnan(removed[idx]) else repr(float(removed[idx]))
            f.write(f"{idx},{el[0]!r},{t},{reason[idx]}\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
