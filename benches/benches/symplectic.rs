//! One planetary step of S2 and S6 (outer Solar System, four planets, τ = 365 d) and one
//! test-particle step (Chegodaeva's particle 1, barycentric variant, B₁ = 0.21e-6, planets
//! interpolated from a pre-computed ephemeris), and a population of comets advanced by one
//! synchronisation window: `cargo bench -p benches --bench symplectic`.
//! The `symplectic-100myr` experiment weights its counted steps with these costs.
//! Peer anchor: REBOUND 5.2 WHFast, democratic heliocentric, ≈ 0.55 µs per step on
//! one core of this machine; measured here with REBOUND 5.2.2 (safe_mode 0, 1e6 steps):
//! 0.71–0.85 µs per step (script outside the repository; the figures belong in the workspace's
//! performance table, `docs/performance.md`).
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use symplectic::{
    Ephemeris, Integrator, ParticleIntegrator, ParticleScratch, Planets, Scheme, Variant, Vec3,
};

fn outer_solar_system() -> Planets {
    // Hairer, Lubich & Wanner, Table 2.1 (reference-data/symplectic-100myr/outer_solar_system.csv).
    let text = include_str!("../../reference-data/symplectic-100myr/outer_solar_system.csv");
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

fn ecliptic(v: Vec3) -> Vec3 {
    symplectic::equatorial_to_ecliptic(&v)
}

fn particle_step(c: &mut Criterion) {
    let equatorial = outer_solar_system();
    let rot = |vs: &[Vec3]| vs.iter().map(|v| ecliptic(*v)).collect::<Vec<_>>();
    let planets = Planets::from_heliocentric(
        equatorial.g(),
        equatorial.sun_mass(),
        equatorial.masses(),
        &rot(equatorial.positions()),
        &rot(&equatorial.heliocentric_velocities()),
    )
    .unwrap();
    // Particle 1 of reference-data/symplectic-100myr/particles.csv (heliocentric ecliptic).
    let text = include_str!("../../reference-data/symplectic-100myr/particles.csv");
    let row: Vec<f64> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .nth(1)
        .unwrap()
        .split(',')
        .skip(1)
        .map(|x| x.trim().parse().unwrap())
        .collect();
    let (sun_q, sun_v) = planets.sun_barycentric_state();
    let q = Vec3::new(row[6], row[7], row[8]) + sun_q;
    let v = Vec3::new(row[9], row[10], row[11]) + sun_v;
    let mut group = c.benchmark_group("particle-step");
    for (scheme, dt0) in [(Scheme::S2, 298.0), (Scheme::S6, 910.0)] {
        let mut eph = Ephemeris::new(planets.clone(), Integrator::S2 { step: 365.0 }).unwrap();
        let integ = ParticleIntegrator::new(Variant::Barycentric, scheme, 0.0, 0.21e-6).unwrap();
        let mut scratch = ParticleScratch::default();
        let start = integ
            .particle(q, v, 0.0, dt0, &mut eph, &mut scratch)
            .unwrap();
        // Cover the first step so that the timed steps interpolate only.
        eph.extend_to(20.0 * 365.25).unwrap();
        group.bench_function(format!("{scheme:?}"), |b| {
            b.iter_batched_ref(
                || start.clone(),
                |p| integ.step(p, &mut eph, &mut scratch).unwrap(),
                criterion::BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

/// `Population::advance_to` over one synchronisation window (256 planet steps, 512 years) of
/// the scattered-disk comets (S2 at a first step of 547.875 d, planets S6 at 730.5 d: the
/// `comet_throughput` defaults), from the end of a first window (so that the ephemeris is
/// in its steady state: each window integrates the next window's planets), for N = 10, 10³
/// and 10⁴ on rayon's threads (`RAYON_NUM_THREADS`); the throughput is in particle-years
/// (criterion's "elements" per second). The peer figures (REBOUND WHFast,
/// the same comets) come from `benches/scripts/comets_vs_rebound.py` (`docs/performance.md`).
fn population_window(c: &mut Criterion) {
    let window_years = f64::from(symplectic::DEFAULT_WINDOW_STEPS) * 2.0;
    let mut group = c.benchmark_group("population-window");
    group.sample_size(10);
    for n in [10usize, 1_000, 10_000] {
        let (mut start, _) = benches::scattered_disk_population(
            n,
            Scheme::S2,
            547.875,
            Integrator::S6 { step: 730.5 },
        )
        .unwrap();
        start.advance_to(window_years * 365.25, |_| {}).unwrap();
        group.throughput(criterion::Throughput::Elements(
            (n as f64 * window_years) as u64,
        ));
        group.bench_function(format!("n{n}"), |b| {
            b.iter_batched_ref(
                || start.clone(),
                |p| p.advance_to(2.0 * window_years * 365.25, |_| {}).unwrap(),
                criterion::BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, planet_step, particle_step, population_window);
criterion_main!(benches);
