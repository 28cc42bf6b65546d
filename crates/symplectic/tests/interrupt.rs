//! Ctrl-C ([`symplectic::guard::request_stop`]) stops a population within a window, and the
//! population goes on from there bit for bit as if never stopped. Alone in its test binary:
//! the stop request is process-wide.

use symplectic::guard::{clear_stop, request_stop};
use symplectic::{
    outer_solar_system, Ephemeris, Frame, Integrator, ParticleIntegrator, Population, RemovalRules,
    Scheme, SymplecticError, Variant, Vec3,
};

fn population() -> Population {
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let ephemeris = Ephemeris::new(planets, Integrator::S2 { step: 365.25 }).unwrap();
    let integrator =
        ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 0.21e-6).unwrap();
    // Circular orbits at 40–60 AU (speed sqrt(GM/r), GM ≈ 2.96e-4 AU³/day²).
    let states: Vec<(Vec3, Vec3)> = (0..64)
        .map(|k| {
            let r = 40.0 + k as f64 * 0.3;
            let phase = k as f64 * 0.7;
            let v = (2.96e-4 / r).sqrt();
            (
                Vec3::new(r * phase.cos(), r * phase.sin(), 0.1 * r),
                Vec3::new(-v * phase.sin(), v * phase.cos(), 0.0),
            )
        })
        .collect();
    let ids: Vec<u64> = (0..64).collect();
    let mut p = Population::new(
        ephemeris,
        integrator,
        RemovalRules::default(),
        0.0,
        365.25,
        &states,
        &ids,
    )
    .unwrap();
    p.set_window_steps(8).unwrap();
    p
}

#[test]
fn a_stopped_population_goes_on_bit_for_bit() {
    let end = 200.0 * 365.25;
    let mut whole = population();
    whole.advance_to(end, |_| {}).unwrap();

    let mut stopped = population();
    let mut windows = 0;
    // The stop asked after the second window: the run returns Interrupted at its next check.
    let e = stopped
        .advance_to(end, |_| {
            windows += 1;
            if windows == 2 {
                request_stop();
            }
        })
        .unwrap_err();
    assert!(matches!(e, SymplecticError::Interrupted { .. }), "{e}");
    assert!(stopped.time() < end, "stopped at {}", stopped.time());
    // A stop request left standing stops the next call at once.
    let t = stopped.time();
    assert!(stopped.advance_to(end, |_| {}).is_err() && stopped.time() == t);
    clear_stop();
    stopped.advance_to(end, |_| {}).unwrap();
    // The trajectories bit for bit (the work counters may differ: a chunk's lanes take
    // their members in another order after a stop, which costs an interpolation more).
    let trajectory = |p: &Population| -> Vec<_> {
        p.members()
            .iter()
            .map(|m| {
                let q = &m.particle;
                (
                    m.id,
                    q.time.to_bits(),
                    q.position,
                    q.velocity,
                    q.p4.to_bits(),
                    q.steps,
                    m.status.clone(),
                )
            })
            .collect()
    };
    assert_eq!(trajectory(&stopped), trajectory(&whole));
}
