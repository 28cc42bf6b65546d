//! One planetary step of S2 and S6 (outer Solar System, four planets, τ = 365 d):
//! `cargo bench -p benches --bench symplectic`. Peer anchor (issue #4): REBOUND 5.2 WHFast,
//! democratic heliocentric, ≈ 0.55 µs per step on one core of this machine (not run here).
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use symplectic::{Integrator, Planets, Vec3};

fn outer_solar_system() -> Planets {
    // Hairer, Lubich & Wanner, Table 2.1 (reference-data/symplectic/outer_solar_system.csv).
    let text = include_str!("../../reference-data/symplectic/outer_solar_system.csv");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| {
            l.split(',')
                .skip(1)
                .map(|x| x.trim().parse().unwrap())
                .collect()
        })
        .collect();
    let m: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let q: Vec<Vec3> = rows.iter().map(|r| Vec3::new(r[1], r[2], r[3])).collect();
    let v: Vec<Vec3> = rows.iter().map(|r| Vec3::new(r[4], r[5], r[6])).collect();
    Planets::from_heliocentric(2.959_122_082_86e-4, m[0], &m[1..], &q[1..], &v[1..]).unwrap()
}

fn planet_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("planet-step");
    for integrator in [
        Integrator::S2 { step: 365.0 },
        Integrator::S6 { step: 365.0 },
    ] {
        let mut p = outer_solar_system();
        group.bench_function(integrator.name(), |b| {
            b.iter(|| integrator.step(black_box(&mut p)).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, planet_step);
criterion_main!(benches);
