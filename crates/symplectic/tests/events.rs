//! The events of a population among the outer Solar System: recorded where an independent
//! scan of the step ends finds them, and the same bit for bit through checkpoints, shards
//! and threads, through the encounter mode.

use symplectic::classes::{inclination_to_plane, tisserand_jupiter};
/// Days per Julian year.
const DAYS_PER_YEAR: f64 = 365.25;
use symplectic::kepler::state_from_elements;
use symplectic::samples::{sample_elements, SampleRanges};
use symplectic::{
    outer_solar_system, ApproachRadius, BodyStates, Encounters, Ephemeris, EventKind, EventRules,
    Frame, Integrator, ParticleIntegrator, ParticleStatus, Population, RemovalRules, Scheme,
    Variant, Vec3,
};

/// Comets between Jupiter and Saturn (`a` 5.5–9 AU, `e` up to 0.4), which Jupiter scatters
/// within centuries: their perihelia and `T_J` move across the event values.
fn jupiter_crossers(n: usize, seed: u64, encounters: bool) -> Population {
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let mu = planets.g() * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
    let ranges = SampleRanges {
        perihelion: None,
        semi_major_axis: (5.5, 9.0),
        eccentricity: (0.1, 0.4),
        inclination: (0.0, 0.2),
    };
    let states: Vec<(Vec3, Vec3)> = sample_elements(&ranges, n, seed)
        .iter()
        .map(|el| state_from_elements(el, mu).unwrap())
        .collect();
    let ephemeris = Ephemeris::new(planets, Integrator::S2 { step: 365.25 }).unwrap();
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 4e-6).unwrap();
    let ids: Vec<u64> = (0..n as u64).collect();
    let rules = RemovalRules {
        min_perihelion: Some(1.0),
        ejection_distance: Some(100.0),
        ..RemovalRules::default()
    };
    let mut pop = Population::new(ephemeris, integ, rules, 0.0, 30.0, &states, &ids).unwrap();
    if encounters {
        pop.set_encounters(Some(Encounters::default())).unwrap();
    }
    pop.set_window_steps(7).unwrap();
    pop
}

fn rules() -> EventRules {
    EventRules {
        perihelion_below: vec![4.5, 4.0, 3.5],
        tisserand_crossing: true,
        close_approach: Some(ApproachRadius::HillRadii(2.0)),
        ..EventRules::default()
    }
}

/// Without the encounter mode (every step end a map step end), the first perihelion below
/// each value and the first crossing of `T_J = 3` are at the step ends where a scan of
/// each comet, stepped one step at a time on a copy, finds them with the crate's elements
/// ([`symplectic::kepler::elements`]) and [`tisserand_jupiter`] with the inclination to
/// Jupiter's heliocentric orbit plane at that time.
#[test]
fn first_perihelion_and_tisserand_events_are_where_a_scan_finds_them() {
    let n = 24;
    let span = 1000.0 * DAYS_PER_YEAR;
    let mut pop = jupiter_crossers(n, 11, false);
    pop.set_events(rules()).unwrap();
    pop.advance_to(span, |_| {}).unwrap();
    let plain = jupiter_crossers(n, 11, false);
    let jupiter = 1;
    let mu = plain.total_gm();
    let (mut perihelion_events, mut crossings) = (0, 0);
    for i in 0..n {
        let mut copy = plain.shard(i..i + 1).unwrap();
        let mut bodies = BodyStates::default();
        let mut expected = Vec::new();
        let mut reached = [false; 3];
        let mut last_t_j: Option<f64> = None;
        let mut crossed = false;
        while copy.members()[0].status == ParticleStatus::Active
            && copy.members()[0].particle.time < span
        {
            let t0 = copy.members()[0].particle.time;
            copy.advance_to(t0 + 1e-9, |_| {}).unwrap();
            let m = &copy.members()[0];
            if m.status != ParticleStatus::Active && m.particle.time == t0 {
                break; // a step that failed: no step end
            }
            let (q, v) = (m.particle.position, m.particle.velocity);
            let el = symplectic::kepler::elements(&q, &v, mu).unwrap();
            for (k, &value) in rules().perihelion_below.iter().enumerate() {
                if !reached[k] && el.perihelion < value {
                    reached[k] = true;
                    expected.push(("q", m.particle.time, value));
                }
            }
            copy.ephemeris()
                .interpolate(m.particle.time, &mut bodies, false)
                .unwrap();
            let normal = (bodies.positions[jupiter] - bodies.positions[0])
                .cross(&(bodies.velocities[jupiter] - bodies.velocities[0]));
            let t_j = tisserand_jupiter(
                el.semi_major_axis,
                el.eccentricity,
                inclination_to_plane(&q, &v, &normal.normalize()),
            );
            if !t_j.is_nan() {
                if let Some(before) = last_t_j.filter(|_| !crossed) {
                    if (before < 3.0) != (t_j < 3.0) {
                        crossed = true;
                        expected.push(("tj", m.particle.time, 3.0));
                    }
                }
                last_t_j = Some(t_j);
            }
        }
        let member = &pop.members()[i];
        let recorded: Vec<(&'static str, f64, f64)> = member
            .events
            .as_ref()
            .map(|log| {
                log.events
                    .iter()
                    .filter_map(|e| match e.kind {
                        EventKind::PerihelionBelow { threshold, .. } => {
                            Some(("q", e.time, threshold))
                        }
                        EventKind::TisserandCrossing { .. } => Some(("tj", e.time, 3.0)),
                        EventKind::CloseApproach { .. } => None,
                    })
                    .collect()
            })
            .unwrap_or_default();
        fn sorted(mut v: Vec<(&'static str, f64, f64)>) -> Vec<(&'static str, f64, f64)> {
            v.sort_by(|a, b| {
                a.1.total_cmp(&b.1)
                    .then(a.0.cmp(b.0))
                    .then(b.2.total_cmp(&a.2))
            });
            v
        }
        assert_eq!(sorted(recorded.clone()), sorted(expected), "comet {i}");
        perihelion_events += recorded.iter().filter(|e| e.0 == "q").count();
        crossings += recorded.iter().filter(|e| e.0 == "tj").count();
    }
    println!(
        "{perihelion_events} perihelion events, {crossings} crossings of T_J = 3 in {n} comets"
    );
    assert!(perihelion_events > 0 && crossings > 0);
}

/// Through the encounter mode: the events (close approaches included) are the same bit for
/// bit advanced at once or in chunks, on one or two threads, from a checkpoint taken while
/// a close approach is under way, and in shards merged.
#[test]
fn events_survive_checkpoints_shards_and_threads_bit_for_bit() {
    let n = 24;
    let span = 400.0 * DAYS_PER_YEAR;
    let build = || {
        let mut p = jupiter_crossers(n, 5, true);
        p.set_events(rules()).unwrap();
        p
    };
    let pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    };
    let mut whole = build();
    pool(1).install(|| whole.advance_to(span, |_| {}).unwrap());
    let approaches = whole
        .members()
        .iter()
        .filter_map(|m| m.events.as_ref())
        .flat_map(|log| log.events.iter())
        .filter(|e| matches!(e.kind, EventKind::CloseApproach { .. }))
        .count();
    println!("{approaches} close approaches within 2 Hill radii");
    assert!(approaches > 0);
    let mut two = build();
    pool(2).install(|| two.advance_to(span, |_| {}).unwrap());
    assert_eq!(two.members(), whole.members());
    // A checkpoint during a close approach.
    let dir = std::env::temp_dir().join(format!("events-resume-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("population.json");
    let mut first = build();
    let mut t = 0.0;
    let open = |p: &Population| {
        p.members().iter().any(|m| {
            m.events
                .as_ref()
                .is_some_and(|log| !log.open_approaches.is_empty())
        })
    };
    while !open(&first) && t < span {
        t += DAYS_PER_YEAR;
        first.advance_to(t, |_| {}).unwrap();
    }
    assert!(
        open(&first),
        "a close approach under way at a synchronisation"
    );
    first.save(&path).unwrap();
    let mut resumed = Population::load(&path).unwrap();
    assert_eq!(resumed, first);
    resumed.advance_to(span, |_| {}).unwrap();
    assert_eq!(resumed.members(), whole.members());
    std::fs::remove_dir_all(&dir).ok();
    let start = build();
    let shards: Vec<Population> = [0..7, 7..n]
        .into_iter()
        .map(|r| {
            let mut s = start.shard(r).unwrap();
            s.advance_to(span, |_| {}).unwrap();
            s
        })
        .collect();
    assert_eq!(
        Population::merge(shards).unwrap().members(),
        whole.members()
    );
    // Shards with other event rules are not of one population.
    let mut other = start.shard(0..7).unwrap();
    other.set_events(EventRules::default()).unwrap();
    let err = Population::merge(vec![other, start.shard(7..n).unwrap()]).unwrap_err();
    assert!(err.to_string().contains("event rules"), "{err}");
}

/// Bad event rules are refused by name.
#[test]
fn bad_event_rules_are_refused_by_name() {
    let mut pop = jupiter_crossers(2, 1, false);
    for (events, name) in [
        (
            EventRules {
                perihelion_below: vec![2.5, f64::NAN],
                ..EventRules::default()
            },
            "events.perihelion_below",
        ),
        (
            EventRules {
                close_approach: Some(ApproachRadius::HillRadii(-1.0)),
                ..EventRules::default()
            },
            "events.close_approach.hill_radii",
        ),
        (
            EventRules {
                perihelion_below: vec![1.0; 65],
                ..EventRules::default()
            },
            "events.perihelion_below",
        ),
        (
            EventRules {
                max_per_particle: 0,
                ..EventRules::default()
            },
            "events.max_per_particle",
        ),
    ] {
        let err = pop.set_events(events).unwrap_err().to_string();
        assert!(err.contains(name), "{err}");
    }
}
