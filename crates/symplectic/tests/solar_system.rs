//! The shipped outer Solar System against the reference table, and the work counters against
//! the stage tables of the maps.

mod common;

use common::*;
use symplectic::{
    outer_solar_system, Ephemeris, Frame, Integrator, ParticleIntegrator, ParticleScratch, Scheme,
    Variant, WorkCounters, G_AU3_PER_MSUN_DAY2,
};

#[test]
fn shipped_system_is_the_reference_table() {
    // reference-data/symplectic-100myr/outer_solar_system.csv (Hairer, Lubich & Wanner, Table 2.1),
    // parsed independently by the test fixture: every value identical, in both frames.
    let (m, q, v) = outer_solar_system_table();
    assert_eq!(G_AU3_PER_MSUN_DAY2, G);
    assert_eq!(symplectic::solar_system::SUN_MASS_WITH_INNER_PLANETS, m[0]);
    for (k, p) in symplectic::solar_system::GIANT_PLANETS.iter().enumerate() {
        assert_eq!(p.mass_msun, m[k + 1], "{} mass", p.name);
        assert_eq!(
            p.position_au,
            [q[k + 1].x, q[k + 1].y, q[k + 1].z],
            "{}",
            p.name
        );
        assert_eq!(
            p.velocity_au_per_day,
            [v[k + 1].x, v[k + 1].y, v[k + 1].z],
            "{}",
            p.name
        );
    }
    assert_eq!(
        outer_solar_system(Frame::Equatorial).state_vector(),
        common::outer_solar_system().state_vector()
    );
    assert_eq!(
        outer_solar_system(Frame::EclipticJ2000).state_vector(),
        outer_solar_system_ecliptic().state_vector()
    );
}

#[test]
fn work_counters_follow_the_stage_tables() {
    // Four planets: n = 4 Kepler solves per Kepler stage, n(n−1)/2 = 6 pair forces per kick.
    // S2 = C/2 B/2 A B/2 C/2: 1 Kepler stage, 2 kicks; S6 (eq. 7): 3 Kepler stages, 4 kicks.
    for (integrator, kepler, forces) in [
        (Integrator::S2 { step: 365.0 }, 4, 12),
        (Integrator::S6 { step: 365.0 }, 12, 24),
    ] {
        let mut p = outer_solar_system(Frame::Equatorial);
        integrator.run(&mut p, 10).unwrap();
        let w = p.work();
        assert_eq!(w.kepler_solves, 10 * kepler, "{}", integrator.name());
        assert_eq!(w.force_evaluations, 10 * forces, "{}", integrator.name());
        assert!(w.kepler_iterations >= w.kepler_solves);
    }
    // A particle step: one Kepler solve per E0 stage, n + 1 = 5 body forces per E1 stage.
    for (scheme, kepler, kicks) in [(Scheme::S2, 1, 2), (Scheme::S6, 3, 4)] {
        let integ = ParticleIntegrator::new(Variant::Barycentric, scheme, 0.0, 0.21e-6).unwrap();
        let planets = outer_solar_system(Frame::EclipticJ2000);
        let row = &particle_rows()[0];
        let (q, v) = barycentric_particle(&planets, row.position, row.velocity);
        let mut eph = Ephemeris::new(planets, Integrator::S2 { step: 365.0 }).unwrap();
        let mut scratch = ParticleScratch::default();
        let mut p = integ
            .particle(q, v, 0.0, 300.0, &mut eph, &mut scratch)
            .unwrap();
        let before = eph.work();
        for _ in 0..7 {
            integ.step(&mut p, &mut eph, &mut scratch).unwrap();
        }
        assert_eq!(p.work.kepler_solves, 7 * kepler, "{scheme:?}");
        assert_eq!(p.work.force_evaluations, 7 * kicks * 5, "{scheme:?}");
        // One interpolation per E1 stage (each follows a drift, or starts the step).
        let interpolations = eph.work().interpolations - before.interpolations;
        assert_eq!(interpolations, 7 * kicks, "{scheme:?}");
        let total: WorkCounters = [p.work, eph.work()].into_iter().sum();
        assert_eq!(
            total.kepler_solves,
            p.work.kepler_solves + eph.work().kepler_solves
        );
    }
}
