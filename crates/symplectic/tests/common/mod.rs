//! Shared test fixtures: the outer Solar System of reference-data and an independent RK4
//! integrator in inertial barycentric coordinates (the oracle for trajectories).
#![allow(dead_code)]

use symplectic::{Planets, Vec3};

pub const G: f64 = 2.959_122_082_86e-4;

/// (masses incl. the Sun first, heliocentric positions, heliocentric velocities), from
/// `reference-data/symplectic-100myr/outer_solar_system.csv`.
pub fn outer_solar_system_table() -> (Vec<f64>, Vec<Vec3>, Vec<Vec3>) {
    let text = include_str!("../data/outer_solar_system.csv");
    let (mut m, mut q, mut v) = (vec![], vec![], vec![]);
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<f64> = line
            .split(',')
            .skip(1)
            .map(|x| x.trim().parse().unwrap())
            .collect();
        m.push(f[0]);
        q.push(Vec3::new(f[1], f[2], f[3]));
        v.push(Vec3::new(f[4], f[5], f[6]));
    }
    (m, q, v)
}

pub fn outer_solar_system() -> Planets {
    let (m, q, v) = outer_solar_system_table();
    Planets::from_heliocentric(G, m[0], &m[1..], &q[1..], &v[1..]).unwrap()
}

/// Inertial barycentric positions and velocities (Sun first) of a [`Planets`] state.
pub fn to_inertial(p: &Planets) -> (Vec<f64>, Vec<Vec3>, Vec<Vec3>) {
    let m0 = p.sun_mass();
    let total = m0 + p.masses().iter().sum::<f64>();
    let sun_q = -p
        .masses()
        .iter()
        .zip(p.positions())
        .map(|(&m, q)| q * m)
        .sum::<Vec3>()
        / total;
    let sun_v = -p.momenta().iter().sum::<Vec3>() / m0;
    let mut m = vec![m0];
    let mut q = vec![sun_q];
    let mut v = vec![sun_v];
    for ((&mi, qi), pi) in p.masses().iter().zip(p.positions()).zip(p.momenta()) {
        m.push(mi);
        q.push(qi + sun_q);
        v.push(pi / mi);
    }
    (m, q, v)
}

pub fn inertial_energy(m: &[f64], q: &[Vec3], v: &[Vec3]) -> f64 {
    let mut e = 0.0;
    for i in 0..m.len() {
        e += 0.5 * m[i] * v[i].norm_squared();
        for j in i + 1..m.len() {
            e -= G * m[i] * m[j] / (q[i] - q[j]).norm();
        }
    }
    e
}

fn accelerations(m: &[f64], q: &[Vec3]) -> Vec<Vec3> {
    let mut a = vec![Vec3::zeros(); m.len()];
    for i in 0..m.len() {
        for j in i + 1..m.len() {
            let d = q[j] - q[i];
            let r3 = d.norm_squared() * d.norm();
            a[i] += d * (G * m[j] / r3);
            a[j] -= d * (G * m[i] / r3);
        }
    }
    a
}

/// Classical RK4 on the inertial N-body equations: `steps` steps of `dt`.
pub fn rk4(m: &[f64], q: &mut [Vec3], v: &mut [Vec3], dt: f64, steps: usize) {
    let n = m.len();
    for _ in 0..steps {
        let q0 = q.to_vec();
        let v0 = v.to_vec();
        let k1v = accelerations(m, &q0);
        let k1q = v0.clone();
        let q1: Vec<Vec3> = (0..n).map(|i| q0[i] + k1q[i] * (0.5 * dt)).collect();
        let v1: Vec<Vec3> = (0..n).map(|i| v0[i] + k1v[i] * (0.5 * dt)).collect();
        let k2v = accelerations(m, &q1);
        let k2q = v1.clone();
        let q2: Vec<Vec3> = (0..n).map(|i| q0[i] + k2q[i] * (0.5 * dt)).collect();
        let v2: Vec<Vec3> = (0..n).map(|i| v0[i] + k2v[i] * (0.5 * dt)).collect();
        let k3v = accelerations(m, &q2);
        let k3q = v2.clone();
        let q3: Vec<Vec3> = (0..n).map(|i| q0[i] + k3q[i] * dt).collect();
        let v3: Vec<Vec3> = (0..n).map(|i| v0[i] + k3v[i] * dt).collect();
        let k4v = accelerations(m, &q3);
        let k4q = v3;
        for i in 0..n {
            q[i] = q0[i] + (k1q[i] + k2q[i] * 2.0 + k3q[i] * 2.0 + k4q[i]) * (dt / 6.0);
            v[i] = v0[i] + (k1v[i] + k2v[i] * 2.0 + k3v[i] * 2.0 + k4v[i]) * (dt / 6.0);
        }
    }
}

/// The outer Solar System rotated to the ecliptic frame of J2000.
pub fn outer_solar_system_ecliptic() -> Planets {
    let (m, q, v) = outer_solar_system_table();
    let q: Vec<Vec3> = q.iter().map(symplectic::equatorial_to_ecliptic).collect();
    let v: Vec<Vec3> = v.iter().map(symplectic::equatorial_to_ecliptic).collect();
    Planets::from_heliocentric(G, m[0], &m[1..], &q[1..], &v[1..]).unwrap()
}

/// One row of `reference-data/symplectic-100myr/particles.csv`.
#[derive(Debug, Clone)]
pub struct ParticleRow {
    pub a: f64,
    pub q: f64,
    pub i_deg: f64,
    pub r0: f64,
    /// Heliocentric ecliptic position and velocity.
    pub position: Vec3,
    pub velocity: Vec3,
    pub dt0_s2: f64,
    pub dt0_s6: f64,
}

pub fn particle_rows() -> Vec<ParticleRow> {
    let text = include_str!("../data/particles.csv");
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|line| {
            let f: Vec<f64> = line
                .split(',')
                .skip(1)
                .map(|x| x.trim().parse().unwrap())
                .collect();
            ParticleRow {
                a: f[0],
                q: f[1],
                i_deg: f[3],
                r0: f[4],
                position: Vec3::new(f[6], f[7], f[8]),
                velocity: Vec3::new(f[9], f[10], f[11]),
                dt0_s2: f[12],
                dt0_s6: f[13],
            }
        })
        .collect()
}

/// Barycentric position and velocity of a heliocentric particle state, at the planets' time.
pub fn barycentric_particle(planets: &Planets, position: Vec3, velocity: Vec3) -> (Vec3, Vec3) {
    let (_, q, v) = to_inertial(planets);
    (position + q[0], velocity + v[0])
}
