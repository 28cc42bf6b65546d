//! `Population`: parallel test particles against one shared ephemeris, checked against the
//! naive oracle (each particle alone with `ParticleIntegrator::step` and a mutable
//! `Ephemeris`), across threads, shards and checkpoints.

use proptest::prelude::*;
use symplectic::kepler::state_from_elements;
use symplectic::samples::{sample_elements, SampleRanges, SCATTERED_DISK};
use symplectic::{
    outer_solar_system, Encounters, Ephemeris, Frame, Integrator, ParticleIntegrator,
    ParticleScratch, ParticleStatus, Population, RemovalRules, Scheme, TestParticle, Variant, Vec3,
};

const DAYS_PER_YEAR: f64 = 365.25;

fn ephemeris() -> Ephemeris {
    Ephemeris::new(
        outer_solar_system(Frame::EclipticJ2000),
        Integrator::S2 { step: 365.25 },
    )
    .unwrap()
}

/// States in the variant's coordinates from barycentric elements (`μ = G M`).
fn states(variant: Variant, ranges: &SampleRanges, n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let g = planets.g();
    let mu = g * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
    let (sun, _) = planets.sun_barycentric_state();
    sample_elements(ranges, n, seed)
        .iter()
        .map(|el| {
            let (q, v) = state_from_elements(el, mu).unwrap();
            match variant {
                Variant::Barycentric => (q, v),
                Variant::Mixed => (q - sun, v),
            }
        })
        .collect()
}

fn population(
    integ: ParticleIntegrator,
    rules: RemovalRules,
    states: &[(Vec3, Vec3)],
) -> Population {
    let ids: Vec<u64> = (0..states.len() as u64).collect();
    Population::new(ephemeris(), integ, rules, 0.0, 300.0, states, &ids).unwrap()
}

/// The oracle: one particle alone, stepped while its time is before `t_end`.
fn alone(integ: ParticleIntegrator, state: (Vec3, Vec3), t_end: f64) -> TestParticle {
    let mut eph = ephemeris();
    let mut scratch = ParticleScratch::default();
    let mut p = integ
        .particle(state.0, state.1, 0.0, 300.0, &mut eph, &mut scratch)
        .unwrap();
    while p.time < t_end {
        integ.step(&mut p, &mut eph, &mut scratch).unwrap();
    }
    p
}

fn same_state(a: &TestParticle, b: &TestParticle) -> bool {
    let bits = |p: &TestParticle| {
        let mut v: Vec<u64> = p
            .position
            .iter()
            .chain(p.velocity.iter())
            .map(|x| x.to_bits())
            .collect();
        v.extend([p.time.to_bits(), p.p4.to_bits(), p.step.to_bits(), p.steps]);
        v
    };
    bits(a) == bits(b)
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    /// Each particle of a population equals, bit for bit, the same particle integrated alone
    /// with the existing single-particle path, for both variants, both schemes and any window.
    #[test]
    fn population_equals_particles_alone(
        seed in 0u64..1000,
        mixed in any::<bool>(),
        s6 in any::<bool>(),
        window in 1u32..40,
    ) {
        let variant = if mixed { Variant::Mixed } else { Variant::Barycentric };
        let scheme = if s6 { Scheme::S6 } else { Scheme::S2 };
        // The mixed variant needs a larger B1 for its domain (MIXED_DOMAIN_MIN_RATIO).
        let b1 = if mixed { 5e-6 } else { 0.21e-6 };
        let integ = ParticleIntegrator::new(variant, scheme, 0.0, b1).unwrap();
        let st = states(variant, &SCATTERED_DISK, 5, seed);
        let mut pop = population(integ, RemovalRules::default(), &st);
        pop.set_window_steps(window).unwrap();
        let t_end = 60.0 * DAYS_PER_YEAR;
        pop.advance_to(t_end, |_| {}).unwrap();
        for (m, s) in pop.members().iter().zip(&st) {
            prop_assert_eq!(&m.status, &ParticleStatus::Active);
            let oracle = alone(integ, *s, t_end);
            prop_assert!(same_state(&m.particle, &oracle), "particle {}: {:?} vs {:?}", m.id, m.particle, oracle);
        }
    }
}

#[test]
fn one_and_two_threads_are_bit_identical() {
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 0.21e-6).unwrap();
    let st = states(Variant::Barycentric, &SCATTERED_DISK, 200, 7);
    let run = |threads| {
        in_pool(threads, || {
            let mut pop = population(integ, RemovalRules::default(), &st);
            pop.set_window_steps(16).unwrap();
            pop.advance_to(300.0 * DAYS_PER_YEAR, |_| {}).unwrap();
            pop
        })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.members().iter().all(|m| m.particle.steps > 50));
    assert_eq!(one, two);
    assert_eq!(
        serde_json::to_string(&one).unwrap(),
        serde_json::to_string(&two).unwrap()
    );
}

#[test]
fn shards_run_separately_and_merged_equal_the_whole() {
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S6, 0.0, 0.21e-6).unwrap();
    let st = states(Variant::Barycentric, &SCATTERED_DISK, 30, 11);
    let t_end = 200.0 * DAYS_PER_YEAR;
    let mut whole = population(integ, RemovalRules::default(), &st);
    whole.advance_to(t_end, |_| {}).unwrap();
    let start = population(integ, RemovalRules::default(), &st);
    let shards: Vec<Population> = [0..7, 7..8, 8..30]
        .into_iter()
        .map(|r| {
            let mut s = start.shard(r).unwrap();
            s.set_window_steps(5).unwrap();
            s.advance_to(t_end, |_| {}).unwrap();
            s
        })
        .collect();
    let merged = Population::merge(shards).unwrap();
    assert_eq!(merged.members(), whole.members());
    assert_eq!(merged.time(), whole.time());
    // And the merged population goes on exactly like the whole one.
    let (mut a, mut b) = (merged, whole);
    a.advance_to(2.0 * t_end, |_| {}).unwrap();
    b.advance_to(2.0 * t_end, |_| {}).unwrap();
    assert_eq!(a.members(), b.members());
}

#[test]
fn checkpoint_resumes_bit_for_bit_and_refuses_foreign_files() {
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 0.21e-6).unwrap();
    let st = states(Variant::Barycentric, &SCATTERED_DISK, 20, 3);
    let dir = std::env::temp_dir().join(format!("population-ckpt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("population.json");
    let mut straight = population(integ, RemovalRules::default(), &st);
    straight.advance_to(400.0 * DAYS_PER_YEAR, |_| {}).unwrap();
    let mut first = population(integ, RemovalRules::default(), &st);
    first.advance_to(150.0 * DAYS_PER_YEAR, |_| {}).unwrap();
    first.save(&path).unwrap();
    let mut resumed = Population::load(&path).unwrap();
    assert_eq!(resumed, first);
    resumed.advance_to(400.0 * DAYS_PER_YEAR, |_| {}).unwrap();
    assert_eq!(resumed.members(), straight.members());
    // Truncated and foreign files are refused by name.
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    assert!(Population::load(&path)
        .unwrap_err()
        .to_string()
        .contains("malformed checkpoint"));
    std::fs::write(&path, text.replace("symplectic-population", "other")).unwrap();
    assert!(Population::load(&path)
        .unwrap_err()
        .to_string()
        .contains("expected \"symplectic-population\""));
    std::fs::remove_dir_all(&dir).ok();
}

/// Removal rules: a particle crossing Neptune's orbit meets the Hill-sphere rule or the
/// perihelion rule; removed particles keep their state and never stop the others.
#[test]
fn removal_is_per_particle_with_reason_and_time() {
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 2e-6).unwrap();
    let ranges = SampleRanges {
        perihelion: None,
        semi_major_axis: (24.0, 36.0),
        eccentricity: (0.0, 0.05),
        inclination: (0.0, 0.02),
    };
    let st = states(Variant::Barycentric, &ranges, 64, 5);
    let rules = RemovalRules {
        hill_factor: Some(1.0),
        min_perihelion: Some(5.0),
        ejection_distance: Some(1000.0),
        ..RemovalRules::default()
    };
    let mut pop = population(integ, rules, &st);
    let end = 3000.0 * DAYS_PER_YEAR;
    let progress = pop.advance_to(end, |_| {}).unwrap();
    assert!(
        progress.removed > 0,
        "Neptune-crossing orbits for 3 kyr: some must be removed"
    );
    assert!(progress.active > 0);
    let planets = outer_solar_system(Frame::EclipticJ2000);
    for m in pop.members() {
        match &m.status {
            ParticleStatus::Active => assert!(m.particle.time >= end),
            ParticleStatus::HillSphereEntry {
                time,
                planet,
                distance,
                hill_radius,
                ..
            } => {
                assert_eq!(*time, m.particle.time);
                assert!(distance < hill_radius && (1..=4).contains(planet));
                // Independent check of the Hill radius: a_j (m_j/3m0)^(1/3) with a_j within
                // 10 % of the planet's distance (the giants' eccentricities are below 0.06).
                let m_ratio = planets.masses()[planet - 1] / (3.0 * planets.sun_mass());
                let a_j = [5.2, 9.55, 19.2, 30.1][planet - 1];
                let expected = a_j * m_ratio.cbrt();
                assert!(
                    (hill_radius / expected - 1.0).abs() < 0.1,
                    "{hill_radius} vs {expected}"
                );
            }
            other => assert!(m.particle.time < end, "{other:?}"),
        }
    }
}

#[test]
fn bytes_per_particle_is_stated() {
    assert!(
        Population::bytes_per_particle() <= 256,
        "{}",
        Population::bytes_per_particle()
    );
}

/// Centaur-like orbits among the giants (`a` 6–30 AU, `e` < 0.3), integrated through their
/// encounters ([`Encounters`]) with `B₁ = 4·10⁻⁶`, removed only below q = 2.5 AU, beyond
/// 100 AU unbound, or at a collision.
fn centaurs(n: usize, seed: u64) -> Population {
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 4e-6).unwrap();
    let ranges = SampleRanges {
        perihelion: None,
        semi_major_axis: (6.0, 30.0),
        eccentricity: (0.0, 0.3),
        inclination: (0.0, 0.3),
    };
    let st = states(Variant::Barycentric, &ranges, n, seed);
    let rules = RemovalRules {
        hill_factor: None,
        min_perihelion: Some(2.5),
        ejection_distance: Some(100.0),
        ..RemovalRules::default()
    };
    let ids: Vec<u64> = (0..n as u64).collect();
    let mut pop = Population::new(ephemeris(), integ, rules, 0.0, 30.0, &st, &ids).unwrap();
    pop.set_encounters(Some(Encounters::default())).unwrap();
    pop.set_window_steps(7).unwrap();
    pop
}

/// Advances in chunks of one year to `years`, counting the members seen in the encounter
/// mode at a synchronisation.
fn advance_counting_encounters(pop: &mut Population, years: f64) -> usize {
    let mut seen = std::collections::BTreeSet::new();
    let mut t = pop.time();
    while t < years * DAYS_PER_YEAR {
        t += DAYS_PER_YEAR;
        pop.advance_to(t, |_| {}).unwrap();
        seen.extend(
            pop.members()
                .iter()
                .filter(|m| m.encounter.is_some())
                .map(|m| m.id),
        );
    }
    seen.len()
}

/// Through encounters, the population stays a deterministic function of its input: one and
/// two threads, shards merged, and a checkpoint taken while members are in the encounter mode
/// all give the same members bit for bit; nobody is removed for lost regularisation.
#[test]
fn encounters_keep_the_population_bit_identical() {
    let years = 600.0;
    let mut one = centaurs(60, 5);
    let in_encounters = in_pool(1, || advance_counting_encounters(&mut one, years));
    println!("{in_encounters} of 60 members seen in the encounter mode");
    assert!(in_encounters >= 3, "{in_encounters} members met a planet");
    let mut two = centaurs(60, 5);
    in_pool(2, || two.advance_to(years * DAYS_PER_YEAR, |_| {}).unwrap());
    // `one` advanced in chunks, `two` at once: other windows, the same trajectories.
    assert_eq!(one.members(), two.members());
    assert!(one
        .members()
        .iter()
        .all(|m| !matches!(m.status, ParticleStatus::RegularisationLost { .. })));
    // Shards.
    let start = centaurs(60, 5);
    let shards: Vec<Population> = [0..5, 5..60]
        .into_iter()
        .map(|r| {
            let mut s = start.shard(r).unwrap();
            s.set_window_steps(3).unwrap();
            s.advance_to(years * DAYS_PER_YEAR, |_| {}).unwrap();
            s
        })
        .collect();
    assert_eq!(Population::merge(shards).unwrap().members(), one.members());
    // A checkpoint with members in the encounter mode.
    let dir = std::env::temp_dir().join(format!("population-enc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("population.json");
    let mut first = centaurs(60, 5);
    let mut t = 0.0;
    loop {
        t += 5.0 * DAYS_PER_YEAR;
        first.advance_to(t, |_| {}).unwrap();
        if first.members().iter().any(|m| m.encounter.is_some()) || t > years * DAYS_PER_YEAR {
            break;
        }
    }
    assert!(first.members().iter().any(|m| m.encounter.is_some()));
    first.save(&path).unwrap();
    let mut resumed = Population::load(&path).unwrap();
    assert_eq!(resumed, first);
    resumed.advance_to(years * DAYS_PER_YEAR, |_| {}).unwrap();
    assert_eq!(resumed.members(), one.members());
    std::fs::remove_dir_all(&dir).ok();
}

/// Without encounters the same comets are removed at Hill-sphere entry or for lost
/// regularisation; with them, the ones that entered a Hill sphere (one Hill radius) went on,
/// and those still active have a finite state past the end.
#[test]
fn encounters_carry_comets_that_the_removal_rule_stops() {
    let years = 300.0;
    let mut with = centaurs(40, 9);
    with.advance_to(years * DAYS_PER_YEAR, |_| {}).unwrap();
    let mut without = centaurs(40, 9);
    without.set_encounters(None).unwrap();
    let rules = RemovalRules {
        hill_factor: Some(1.0),
        ..without.rules()
    };
    let ids: Vec<u64> = (0..40).collect();
    let st: Vec<(Vec3, Vec3)> = without
        .members()
        .iter()
        .map(|m| (m.particle.position, m.particle.velocity))
        .collect();
    let mut without = Population::new(
        ephemeris(),
        without.integrator(),
        rules,
        0.0,
        30.0,
        &st,
        &ids,
    )
    .unwrap();
    without.advance_to(years * DAYS_PER_YEAR, |_| {}).unwrap();
    let stopped: Vec<u64> = without
        .members()
        .iter()
        .filter(|m| {
            matches!(
                m.status,
                ParticleStatus::HillSphereEntry { .. } | ParticleStatus::RegularisationLost { .. }
            )
        })
        .map(|m| m.id)
        .collect();
    assert!(!stopped.is_empty());
    let went_on = with
        .members()
        .iter()
        .filter(|m| stopped.contains(&m.id) && m.status == ParticleStatus::Active)
        .count();
    assert!(went_on > 0, "of {} stopped, none went on", stopped.len());
    for m in with.members() {
        assert!(
            !matches!(
                m.status,
                ParticleStatus::RegularisationLost { .. }
                    | ParticleStatus::IntegrationFailed { .. }
                    | ParticleStatus::HillSphereEntry { .. }
            ),
            "{}: {:?}",
            m.id,
            m.status
        );
        if m.status == ParticleStatus::Active {
            assert!(m.particle.time >= years * DAYS_PER_YEAR);
            assert!(m.particle.position.iter().all(|x| x.is_finite()));
        }
    }
}
