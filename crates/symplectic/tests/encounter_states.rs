//! The encounter state of population members ([`Encounters`]): cleared when a member is
//! removed inside an encounter, and written to the population table (`in_encounter`) for
//! active members only.

use symplectic::{
    outer_solar_system, BodyStates, Encounters, Ephemeris, Frame, Integrator, ParticleIntegrator,
    ParticleStatus, Population, RemovalRules, Scheme, Variant, Vec3,
};

const DAYS_PER_YEAR: f64 = 365.25;

fn ephemeris() -> Ephemeris {
    Ephemeris::new(
        outer_solar_system(Frame::EclipticJ2000),
        Integrator::S2 { step: 365.25 },
    )
    .unwrap()
}

/// The Sun and the planets (barycentric) at `t = 0`.
fn bodies_at_epoch() -> BodyStates {
    let mut bodies = BodyStates::default();
    ephemeris().bodies_at(0.0, &mut bodies).unwrap();
    bodies
}

/// Jupiter's (planet 1) barycentric state at `t = 0`, and its Hill radius
/// `|Q_J| (m_J/3m₀)^{1/3}` with `Q_J` heliocentric, as the population computes it.
fn jupiter() -> (Vec3, Vec3, f64) {
    let b = bodies_at_epoch();
    let hill = (b.positions[1] - b.positions[0]).norm() * (b.gm[1] / (3.0 * b.gm[0])).cbrt();
    (b.positions[1], b.velocities[1], hill)
}

/// A comet on Jupiter's heliocentric two-body orbit (about `G(m₀ + m_J)`), `lag_days` behind
/// it: Jupiter's heliocentric state drifted back by `lag_days`, barycentric.
fn co_orbital(lag_days: f64) -> (Vec3, Vec3) {
    let b = bodies_at_epoch();
    let mut q = b.positions[1] - b.positions[0];
    let mut v = b.velocities[1] - b.velocities[0];
    symplectic::kepler::drift(&mut q, &mut v, b.gm[0] + b.gm[1], -lag_days).unwrap();
    (q + b.positions[0], v + b.velocities[0])
}

/// A population through encounters (barycentric S2, `B₁ = 4·10⁻⁶` as the Centaur tests),
/// removed below q = 2.5 AU or beyond 100 AU unbound, first steps of one day.
fn population(states: &[(Vec3, Vec3)], encounters: Encounters) -> Population {
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 4e-6).unwrap();
    let rules = RemovalRules {
        hill_factor: None,
        min_perihelion: Some(2.5),
        ejection_distance: Some(100.0),
    };
    let ids: Vec<u64> = (0..states.len() as u64).collect();
    let mut pop = Population::new(ephemeris(), integ, rules, 0.0, 1.0, states, &ids).unwrap();
    pop.set_encounters(Some(encounters)).unwrap();
    pop
}

/// Comet 0 falls straight into Jupiter from 0.3 AU at 0.02 AU/day and ends in a collision
/// inside the encounter mode; comet 1 trails Jupiter on its orbit at about 2 Hill radii and
/// is still in the encounter mode after a year. The removed comet holds no encounter state
/// and is not flagged `in_encounter`; the other is.
#[test]
fn a_comet_removed_in_an_encounter_is_no_longer_in_it() {
    let (q_j, v_j, hill) = jupiter();
    let towards = (q_j / q_j.norm()) * 0.3;
    let falling = (q_j + towards, v_j - towards / towards.norm() * 0.02);
    // 2 Hill radii along the orbit at Jupiter's ≈ 0.0075 AU/day (checked below).
    let trailing = co_orbital(2.0 * hill / 0.0075);
    let start_ratio = (trailing.0 - q_j).norm() / hill;
    assert!((1.5..2.5).contains(&start_ratio), "{start_ratio} Hill radii");
    let mut pop = population(&[falling, trailing], Encounters::default());
    pop.advance_to(DAYS_PER_YEAR, |_| {}).unwrap();
    let [fell, trails] = pop.members() else {
        panic!("two members")
    };
    // At 0.02 AU/day from 0.3 AU the comet reaches Jupiter within 15 days, in the encounter
    // mode (it switched at its first step's end, 0.85 Hill radii from Jupiter).
    match fell.status {
        ParticleStatus::Collision { planet, time, .. } => {
            assert_eq!(planet, 1, "Jupiter");
            assert!(time < 15.0, "collision at {time} days");
        }
        ref s => panic!("expected a collision with Jupiter, got {s:?}"),
    }
    assert!(fell.encounter.is_none(), "removed, still in the encounter mode");
    assert_eq!(trails.status, ParticleStatus::Active);
    assert!(trails.encounter.is_some(), "trailing Jupiter, not in an encounter");
    #[cfg(feature = "io")]
    {
        let table = symplectic::io::population_table(&pop).unwrap();
        let flag = table
            .column_by_name("in_encounter")
            .unwrap()
            .as_any()
            .downcast_ref::<arrow_array::BooleanArray>()
            .unwrap();
        assert_eq!((flag.value(0), flag.value(1)), (false, true));
    }
}
