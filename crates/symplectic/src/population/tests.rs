//! The lanes against the scalar path, bit for bit.

use proptest::prelude::*;

use super::*;
use crate::kepler::state_from_elements;
use crate::samples::{sample_elements, SampleRanges};
use crate::{outer_solar_system, Frame, Integrator, Scheme};

/// Comets from Saturn's distance to the scattered disk: some enter a Hill sphere, some
/// fall below the perihelion limit, some lose the regularisation (a `B₁` far below the
/// paper's, or perihelia below the ≈ 26 AU of its condition 35) and are redone by the
/// scalar path.
fn population(n: usize, seed: u64, scheme: Scheme, b1: f64, rules: RemovalRules) -> Population {
    let ranges = SampleRanges {
        perihelion: None,
        semi_major_axis: (12.0, 70.0),
        eccentricity: (0.0, 0.5),
        inclination: (0.0, 0.4),
    };
    population_in(&ranges, n, seed, scheme, b1, rules)
}

/// [`population`] drawn from `ranges`.
fn population_in(
    ranges: &SampleRanges,
    n: usize,
    seed: u64,
    scheme: Scheme,
    b1: f64,
    rules: RemovalRules,
) -> Population {
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let mu = planets.g() * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
    let ephemeris = Ephemeris::new(planets, Integrator::S6 { step: 730.5 }).unwrap();
    let integ = ParticleIntegrator::new(Variant::Barycentric, scheme, 0.0, b1).unwrap();
    // Orbits where K₀/r or K₁/r is not positive at the start cannot be built: left out.
    let (mut eph, mut scratch) = (ephemeris.clone(), crate::ParticleScratch::default());
    let states: Vec<(Vec3, Vec3)> = sample_elements(ranges, n, seed)
        .iter()
        .map(|el| state_from_elements(el, mu).unwrap())
        .filter(|&(q, v)| {
            integ
                .particle(q, v, 0.0, 400.0, &mut eph, &mut scratch)
                .is_ok()
        })
        .collect();
    let ids: Vec<u64> = (0..states.len() as u64).collect();
    Population::new(ephemeris, integ, rules, 0.0, 400.0, &states, &ids).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// The lanes give the population of the scalar path bit for bit: every member's
    /// state, status (rule, time, figures), step and work counts, events, on one or two
    /// threads.
    #[test]
    fn lanes_equal_the_scalar_path(
        seed in 0u64..10_000,
        n in 1usize..23,
        s6 in any::<bool>(),
        window in 1u32..40,
        two_threads in any::<bool>(),
        small_b1 in any::<bool>(),
        hill in prop::option::of(0.5f64..3.0),
        min_perihelion in prop::option::of(5.0f64..30.0),
        ejection in prop::option::of(60.0f64..200.0),
        encounters in any::<bool>(),
        events in any::<bool>(),
        geometric in any::<bool>(),
    ) {
        let scheme = if s6 { Scheme::S6 } else { Scheme::S2 };
        let distance = |distance, frame| Some(DistanceLimit { distance, frame });
        let rules = RemovalRules {
            hill_factor: hill,
            min_perihelion,
            ejection_distance: ejection,
            // The geometric rules, flagged by the lanes' wider test (with the events, every
            // lane goes through the scalar checks).
            sun_collision: geometric,
            min_distance: distance(8.0, DistanceFrame::Heliocentric).filter(|_| geometric),
            max_distance: distance(90.0, DistanceFrame::Barycentric).filter(|_| geometric),
        };
        let b1 = if small_b1 { 3e-8 } else { crate::PAPER_B1 };
        let mut start = population(n, seed, scheme, b1, rules);
        start.set_window_steps(window).unwrap();
        if events {
            start.set_events(EventRules {
                perihelion_below: vec![20.0, 12.0],
                tisserand_crossing: true,
                close_approach: Some(ApproachRadius::HillRadii(5.0)),
                ..EventRules::default()
            }).unwrap();
        }
        if encounters && hill.is_none() {
            start.set_encounters(Some(crate::Encounters::default())).unwrap();
        }
        let t_end = 400.0 * 365.25;
        let threads = if two_threads { 2 } else { 1 };
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let run = |path: StepPath| {
            let mut p = start.clone();
            pool.install(|| p.advance_with(t_end, path, |_| {})).unwrap();
            p
        };
        let (lanes, scalar) = (run(StepPath::Lanes), run(StepPath::Scalar));
        let portable = run(StepPath::PortableLanes);
        prop_assert_eq!(lanes.members(), portable.members());
        prop_assert!(lanes.members().iter().all(|m| m.particle.steps > 0 || m.status != ParticleStatus::Active));
        prop_assert_eq!(lanes.members(), scalar.members());
        prop_assert_eq!(lanes.progress(), scalar.progress());
        prop_assert_eq!(lanes.work(), scalar.work());
    }
}

/// The test population exercises what the lanes hand to the scalar path: removals by
/// each rule and the loss of the regularisation.
#[test]
fn lanes_test_population_meets_every_outcome() {
    let rules = RemovalRules {
        hill_factor: Some(1.0),
        min_perihelion: Some(8.0),
        ejection_distance: Some(100.0),
        ..RemovalRules::default()
    };
    let mut p = population(200, 3, Scheme::S2, 3e-8, rules);
    p.advance_to(400.0 * 365.25, |_| {}).unwrap();
    let count =
        |f: fn(&ParticleStatus) -> bool| p.members().iter().filter(|m| f(&m.status)).count();
    let hill = count(|s| matches!(s, ParticleStatus::HillSphereEntry { .. }));
    let perihelion = count(|s| matches!(s, ParticleStatus::PerihelionBelowLimit { .. }));
    let lost = count(|s| matches!(s, ParticleStatus::RegularisationLost { .. }));
    let active = count(|s| matches!(s, ParticleStatus::Active));
    assert!(
        hill > 0 && perihelion > 0 && lost > 0 && active > 0,
        "{hill} {perihelion} {lost} {active}"
    );
}

/// Comets that graze the Sun (perihelia 0.002–0.008 AU about the solar radius, 0.00465 AU):
/// the lanes' wide Sun test hands each passage to the scalar rule, and the population equals
/// the scalar path's bit for bit, with comets ended by the collision (most of the others
/// lose the map's regularisation in the Sun's vicinity, also a scalar outcome).
#[test]
fn sun_grazers_in_the_lanes_equal_the_scalar_path() {
    let ranges = SampleRanges {
        perihelion: Some((0.002, 0.008)),
        semi_major_axis: (2.0, 6.0),
        eccentricity: (0.0, 0.0),
        inclination: (0.0, 0.4),
    };
    let rules = RemovalRules {
        sun_collision: true,
        min_distance: Some(DistanceLimit {
            distance: 0.001,
            frame: DistanceFrame::Barycentric,
        }),
        ..RemovalRules::default()
    };
    let start = population_in(&ranges, 64, 11, Scheme::S2, 4e-6, rules);
    let run = |path: StepPath| {
        let mut p = start.clone();
        p.advance_with(20.0 * 365.25, path, |_| {}).unwrap();
        p
    };
    let (lanes, scalar) = (run(StepPath::Lanes), run(StepPath::Scalar));
    assert_eq!(lanes.members(), scalar.members());
    assert_eq!(lanes.work(), scalar.work());
    let hit = lanes
        .members()
        .iter()
        .filter(|m| matches!(m.status, ParticleStatus::SunCollision { .. }))
        .count();
    assert!(hit >= 3, "{hit} collided");
}
