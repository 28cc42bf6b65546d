//! Bad input gets a named error, never a panic (nor a non-finite result returned as Ok).

mod common;

use common::*;
use proptest::prelude::*;
use symplectic::{
    kepler, outer_solar_system, CometRun, Ephemeris, Frame, Integrator, Limits, ParticleIntegrator,
    ParticleScratch, Planets, Scheme, SymplecticError, Variant, Vec3,
};

/// Ordinary values mixed with the special ones (NaN, ±∞, 0, extremes).
fn value(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        30 => lo..hi,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(0.0),
        1 => Just(1e300),
        1 => Just(-1e-300),
    ]
}

fn vec3(lo: f64, hi: f64) -> impl Strategy<Value = Vec3> {
    (value(lo, hi), value(lo, hi), value(lo, hi)).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn kepler_drift_never_panics(r in vec3(-100.0, 100.0), v in vec3(-0.1, 0.1),
                                 mu in value(0.0, 1e-3), dt in value(-1e5, 1e5)) {
        let (mut r1, mut v1) = (r, v);
        if kepler::drift(&mut r1, &mut v1, mu, dt).is_ok() {
            prop_assert!(r1.iter().chain(v1.iter()).all(|x| x.is_finite()));
        }
        let _ = kepler::elements(&r, &v, mu);
    }

    #[test]
    fn planets_never_panic(masses in proptest::collection::vec(value(0.0, 1e-3), 1..4),
                           q in vec3(-30.0, 30.0), v in vec3(-0.01, 0.01),
                           sun in value(0.0, 2.0), step in value(-400.0, 400.0)) {
        let n = masses.len();
        // Planets spread around the given state, so that most cases are distinct bodies.
        let qs: Vec<Vec3> = (0..n).map(|k| q * (1.0 + k as f64)).collect();
        let vs: Vec<Vec3> = (0..n).map(|k| v / (1.0 + k as f64)).collect();
        if let Ok(mut p) = Planets::from_heliocentric(G, sun, &masses, &qs, &vs) {
            let integrator = Integrator::S6 { step };
            match integrator.run(&mut p, 3) {
                Ok(()) => prop_assert!(p.first_non_finite().is_none()),
                Err(e) => prop_assert!(!e.to_string().is_empty()),
            }
            let _ = Ephemeris::new(p, integrator);
        }
    }

    #[test]
    fn particles_never_panic(q in vec3(-150.0, 150.0), v in vec3(-0.003, 0.003),
                             dt0 in value(-500.0, 500.0), b1 in value(0.0, 1e-5),
                             mixed in any::<bool>(), t_end in value(0.0, 3650.0)) {
        let variant = if mixed { Variant::Mixed } else { Variant::Barycentric };
        let Ok(integ) = ParticleIntegrator::new(variant, Scheme::S2, 0.0, b1) else {
            return Ok(());
        };
        let mut eph = Ephemeris::new(outer_solar_system(Frame::EclipticJ2000),
                                     Integrator::S2 { step: 365.0 }).unwrap();
        let mut scratch = ParticleScratch::default();
        let Ok(p) = integ.particle(q, v, 0.0, dt0, &mut eph, &mut scratch) else {
            return Ok(());
        };
        // Keep the case short: a particle close to the Sun takes steps ∝ r.
        prop_assume!(q.norm() > 1.0 && dt0 > 1.0);
        let limits = Limits { min_perihelion: 0.5, ejection_distance: 1e4 };
        let mut run = CometRun::new(eph, integ, vec![p], limits);
        if run.advance_to(t_end.min(3650.0), |_, _, _| {}).is_ok() {
            let p = &run.particles[0].particle;
            prop_assert!(p.position.iter().chain(p.velocity.iter()).all(|x| x.is_finite()));
        }
        prop_assert!(run.elements(7).is_err());
    }
}

#[test]
fn named_errors() {
    // Zero planet mass, NaN state, mismatched lengths: InvalidParameter / InvalidState.
    let q = [Vec3::new(5.0, 0.0, 0.0)];
    let v = [Vec3::new(0.0, 7e-3, 0.0)];
    let e = Planets::from_heliocentric(G, 1.0, &[0.0], &q, &v).unwrap_err();
    assert!(e.to_string().contains("planet mass"), "{e}");
    let e = Planets::from_heliocentric(G, 1.0, &[1e-3], &[Vec3::new(f64::NAN, 0.0, 0.0)], &v)
        .unwrap_err();
    assert!(e.to_string().contains("planet 1"), "{e}");
    let mut p = outer_solar_system(Frame::Equatorial);
    let mut s = p.state_vector();
    s[7] = f64::INFINITY;
    let e = p.set_state_vector(&s).unwrap_err();
    assert!(e.to_string().contains("planet 2"), "{e}");
    // Two planets in the same place: the run stops with the step and the planet.
    let q2 = [Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.0, 0.0, 0.0)];
    let v2 = [v[0], v[0]];
    let mut p = Planets::from_heliocentric(G, 1.0, &[1e-3, 1e-3], &q2, &v2).unwrap();
    match (Integrator::S2 { step: 10.0 }).run(&mut p, 5) {
        Err(SymplecticError::BlowUp { step: 0, .. })
        | Err(SymplecticError::InvalidState { .. }) => {}
        other => panic!("expected a blow-up at step 0, got {other:?}"),
    }
    // B1 larger than G M: the Kepler part has no positive μ.
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 1.0).unwrap();
    let mut eph = Ephemeris::new(
        outer_solar_system(Frame::EclipticJ2000),
        Integrator::S2 { step: 365.0 },
    )
    .unwrap();
    let mut scratch = ParticleScratch::default();
    let row = &particle_rows()[0];
    let r = integ.particle(
        row.position,
        row.velocity,
        0.0,
        300.0,
        &mut eph,
        &mut scratch,
    );
    if let Ok(mut p) = r {
        let e = integ.step(&mut p, &mut eph, &mut scratch).unwrap_err();
        assert!(e.to_string().contains("B1"), "{e}");
    }
    // A time 2^52 planet steps away is refused, not integrated for ages.
    let mut far = Ephemeris::new(
        outer_solar_system(Frame::EclipticJ2000),
        Integrator::S2 { step: 365.0 },
    )
    .unwrap();
    let e = far.extend_to(1e300).unwrap_err();
    assert!(e.to_string().contains("2^52"), "{e}");
    // Non-finite end time and limits.
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 0.21e-6).unwrap();
    let p = integ
        .particle(
            row.position,
            row.velocity,
            0.0,
            300.0,
            &mut eph,
            &mut scratch,
        )
        .unwrap();
    let limits = Limits {
        min_perihelion: f64::NAN,
        ejection_distance: 1e3,
    };
    let mut run = CometRun::new(eph, integ, vec![p], limits);
    assert!(run
        .advance_to(f64::NAN, |_, _, _| {})
        .unwrap_err()
        .to_string()
        .contains("end time"));
    assert!(run
        .advance_to(1000.0, |_, _, _| {})
        .unwrap_err()
        .to_string()
        .contains("min_perihelion"));
}
