//! The end rules and the events of a population against closed-form Kepler orbits: a planet
//! of 10⁻¹⁵ solar masses leaves the comet on its two-body orbit about the Sun, whose
//! distance at any time follows from Kepler's equation, solved here by Newton's method,
//! independently of the crate.

use symplectic::solar_system::SUN_RADIUS_AU;
use symplectic::{
    ApproachRadius, DistanceFrame, DistanceLimit, Ephemeris, EventKind, EventRules, Integrator,
    ParticleIntegrator, ParticleStatus, Planets, Population, RemovalRules, Scheme, Variant, Vec3,
    G_AU3_PER_MSUN_DAY2, PAPER_B1,
};

/// Mass of the planet (solar masses): its pull on a comet 0.1 AU away is
/// `G m/d² ≈ 3·10⁻¹⁷` AU/day², 10⁻¹² of the Sun's at 5 AU; over the tests' spans it moves
/// the comet by far less than the tolerances below.
const PLANET_MASS: f64 = 1e-15;

/// The planet's circular orbit (AU) and its phase at `t = 0` (rad).
const PLANET_ORBIT_AU: f64 = 5.0;

fn mu() -> f64 {
    G_AU3_PER_MSUN_DAY2 * (1.0 + PLANET_MASS)
}

/// The Sun and one planet named Jupiter on a circular orbit of phase `phase` at `t = 0`.
fn quiet_planets(phase: f64) -> Planets {
    let g = G_AU3_PER_MSUN_DAY2;
    let speed = (mu() / PLANET_ORBIT_AU).sqrt();
    let (s, c) = phase.sin_cos();
    Planets::from_heliocentric(
        g,
        1.0,
        &[PLANET_MASS],
        &[Vec3::new(c, s, 0.0) * PLANET_ORBIT_AU],
        &[Vec3::new(-s, c, 0.0) * speed],
    )
    .and_then(|p| p.with_names_and_radii(&["Jupiter"], &[4.78e-4]))
    .unwrap()
}

/// A planar ellipse `a`, `e` with perihelion on the x axis.
#[derive(Clone, Copy)]
struct Ellipse {
    a: f64,
    e: f64,
}

impl Ellipse {
    fn mean_motion(&self) -> f64 {
        (mu() / self.a.powi(3)).sqrt()
    }

    /// Eccentric anomaly of mean anomaly `m` (Newton on `E − e sin E = M`).
    fn eccentric(&self, m: f64) -> f64 {
        let mut big_e = if self.e > 0.8 {
            std::f64::consts::PI
        } else {
            m
        };
        for _ in 0..60 {
            big_e -= (big_e - self.e * big_e.sin() - m) / (1.0 - self.e * big_e.cos());
        }
        big_e
    }

    /// Position and velocity at mean anomaly `m`.
    fn state(&self, m: f64) -> (Vec3, Vec3) {
        let big_e = self.eccentric(m);
        let (s, c) = big_e.sin_cos();
        let b = self.a * (1.0 - self.e * self.e).sqrt();
        let rate = self.mean_motion() / (1.0 - self.e * c);
        (
            Vec3::new(self.a * (c - self.e), b * s, 0.0),
            Vec3::new(-self.a * s * rate, b * c * rate, 0.0),
        )
    }

    /// The time after mean anomaly `m0` at which the eccentric anomaly is `big_e` (in
    /// `(E(m0), E(m0) + 2π)`).
    fn time_at(&self, m0: f64, big_e: f64) -> f64 {
        (big_e - self.e * big_e.sin() - m0) / self.mean_motion()
    }
}

/// A population of one comet on `orbit` from mean anomaly `m0` at `t = 0` (the planet
/// opposite its perihelion), planets' step 50 days (the interpolant's error, 1.6·10⁻⁴ AU for
/// Jupiter at 730.5 days, scales as the sixth power of the step: about 2·10⁻¹¹ AU), first
/// step `first_step` days.
fn comet(orbit: Ellipse, m0: f64, rules: RemovalRules, first_step: f64) -> Population {
    let planets = quiet_planets(std::f64::consts::PI);
    let ephemeris = Ephemeris::new(planets, Integrator::S6 { step: 50.0 }).unwrap();
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, PAPER_B1).unwrap();
    let state = orbit.state(m0);
    Population::new(ephemeris, integ, rules, 0.0, first_step, &[state], &[7]).unwrap()
}

/// The first step end at or after `t` of the comet of `pop` run without rules (the
/// trajectory does not depend on where the population synchronises).
fn first_step_end_after(mut pop: Population, t: f64) -> f64 {
    pop.advance_to(t, |_| {}).unwrap();
    assert_eq!(pop.members()[0].status, ParticleStatus::Active);
    pop.members()[0].particle.time
}

/// The map's distance at a step end against the closed form. The map is second order in its
/// step (Chegodaeva 2004: the regularised time advances by `h/F₀` in the drift and the
/// kicks change `p₄`, so the comet's phase carries an `O(h²)` error even on a two-body
/// orbit). Measured (2026-12-05, printed by each test): at `r` = 8 AU 5.5·10⁻⁸ AU with a
/// first step of 30 days, 5.4·10⁻¹⁰ with 3, 6·10⁻¹¹ with 1; at the close approach
/// 2.2·10⁻⁷ AU with 10 days, 1.9·10⁻⁸ with 3, 2.2·10⁻⁹ with 1; at `r` = 12 AU from
/// perihelion 1.5·10⁻⁸ with 3, 1.7·10⁻⁹ with 1: the `h²` scaling. The tests take 1 day;
/// the 10⁻¹⁵ planet and the interpolant's 2·10⁻¹¹ AU add less. 10⁻⁸ AU is 4.5 times the
/// largest of these.
const KEPLER_TOLERANCE_AU: f64 = 1e-8;

/// First physical step (days) of the comets whose distance is compared with the closed form.
const FINE_STEP_DAYS: f64 = 1.0;

/// `r < R` (heliocentric): the rule ends the comet at the first step end after the
/// analytic crossing, with the distance of the closed-form orbit then.
#[test]
fn min_distance_ends_at_the_first_step_after_the_analytic_crossing() {
    let orbit = Ellipse { a: 10.0, e: 0.5 };
    let limit = 8.0;
    // From aphelion (M = π) inbound: r = a(1 − e cos E) = R at cos E = (1 − R/a)/e.
    let big_e = 2.0 * std::f64::consts::PI - ((1.0 - limit / orbit.a) / orbit.e).acos();
    let crossing = orbit.time_at(std::f64::consts::PI, big_e);
    let rules = RemovalRules {
        min_distance: Some(DistanceLimit {
            distance: limit,
            frame: DistanceFrame::Heliocentric,
        }),
        ..RemovalRules::default()
    };
    let free = comet(
        orbit,
        std::f64::consts::PI,
        RemovalRules::default(),
        FINE_STEP_DAYS,
    );
    let expected_time = first_step_end_after(free, crossing);
    let mut pop = comet(orbit, std::f64::consts::PI, rules, FINE_STEP_DAYS);
    pop.advance_to(2.0 * crossing, |_| {}).unwrap();
    let ParticleStatus::InsideMinDistance {
        time,
        distance,
        frame,
    } = pop.members()[0].status
    else {
        panic!("{:?}", pop.members()[0].status)
    };
    assert_eq!(time.to_bits(), expected_time.to_bits());
    assert_eq!(frame, DistanceFrame::Heliocentric);
    let m = std::f64::consts::PI + orbit.mean_motion() * time;
    let analytic = orbit.state(m).0.norm();
    assert!(
        distance < limit && analytic < limit,
        "{distance} {analytic}"
    );
    println!(
        "min_distance: map − closed form {:.2e} AU",
        distance - analytic
    );
    assert!(
        (distance - analytic).abs() < KEPLER_TOLERANCE_AU,
        "{distance} vs {analytic}"
    );
}

/// `r > R` bound (barycentric): the ellipse's aphelion is beyond R, so the rule ends it at
/// the first step end after the outbound crossing, while the unbound-only rule
/// `ejection_distance` at the same R keeps it (e = 0.5 < 1: bound).
#[test]
fn max_distance_ends_a_bound_orbit_that_ejection_keeps() {
    let orbit = Ellipse { a: 10.0, e: 0.5 };
    let limit = 12.0;
    let big_e = ((1.0 - limit / orbit.a) / orbit.e).acos();
    let crossing = orbit.time_at(0.0, big_e);
    let far = DistanceLimit {
        distance: limit,
        frame: DistanceFrame::Barycentric,
    };
    let rules = RemovalRules {
        max_distance: Some(far),
        ..RemovalRules::default()
    };
    let free = comet(orbit, 0.0, RemovalRules::default(), FINE_STEP_DAYS);
    let expected_time = first_step_end_after(free, crossing);
    let mut pop = comet(orbit, 0.0, rules, FINE_STEP_DAYS);
    pop.advance_to(2.0 * crossing, |_| {}).unwrap();
    let ParticleStatus::BeyondMaxDistance { time, distance, .. } = pop.members()[0].status else {
        panic!("{:?}", pop.members()[0].status)
    };
    assert_eq!(time.to_bits(), expected_time.to_bits());
    let analytic = orbit.state(orbit.mean_motion() * time).0.norm();
    println!(
        "max_distance: map − closed form {:.2e} AU",
        distance - analytic
    );
    assert!(distance > limit && (distance - analytic).abs() < KEPLER_TOLERANCE_AU);
    let ejection = RemovalRules {
        ejection_distance: Some(limit),
        ..RemovalRules::default()
    };
    let mut kept = comet(orbit, 0.0, ejection, FINE_STEP_DAYS);
    kept.advance_to(2.0 * crossing, |_| {}).unwrap();
    assert_eq!(kept.members()[0].status, ParticleStatus::Active);
}

/// A comet of perihelion 0.002 AU (inside the solar radius, 0.00465 AU) collides with the
/// Sun on its first passage: at the first step end after it enters the solar radius
/// (analytic time), whether that step end is inside the Sun or past perihelion; one of
/// perihelion 0.006 AU passes and stays active.
#[test]
fn a_sun_grazer_collides_and_a_near_miss_does_not() {
    let rules = RemovalRules {
        sun_collision: true,
        ..RemovalRules::default()
    };
    let pi = std::f64::consts::PI;
    let hit = Ellipse { a: 1.0, e: 0.998 };
    // Inbound from aphelion: r = R_☉ at cos E = (1 − R/a)/e, E in (π, 2π).
    let big_e = 2.0 * pi - ((1.0 - SUN_RADIUS_AU / hit.a) / hit.e).acos();
    let entry = hit.time_at(pi, big_e);
    let perihelion = hit.time_at(pi, 2.0 * pi);
    let free = comet(hit, pi, RemovalRules::default(), 5.0);
    let expected_time = first_step_end_after(free.clone(), entry);
    // Without the rule the comet passes (the map goes through the perihelion).
    let mut passed = free;
    passed.advance_to(perihelion + 10.0, |_| {}).unwrap();
    assert_eq!(passed.members()[0].status, ParticleStatus::Active);
    let mut pop = comet(hit, pi, rules, 5.0);
    pop.advance_to(perihelion + 10.0, |_| {}).unwrap();
    let ParticleStatus::SunCollision { time, distance } = pop.members()[0].status else {
        panic!("{:?}", pop.members()[0].status)
    };
    assert_eq!(time.to_bits(), expected_time.to_bits());
    // Inside the Sun at the step end, or the perihelion 0.002 AU passed within the step.
    let q = hit.a * (1.0 - hit.e);
    assert!(
        distance < SUN_RADIUS_AU && (distance >= q - KEPLER_TOLERANCE_AU),
        "{distance}"
    );
    let miss = Ellipse { a: 1.0, e: 0.994 };
    let mut kept = comet(miss, pi, rules, 5.0);
    kept.advance_to(miss.time_at(pi, 2.0 * pi) + 10.0, |_| {})
        .unwrap();
    assert_eq!(kept.members()[0].status, ParticleStatus::Active);
}

/// A close approach to the planet (1 AU): the event holds the smallest distance to the
/// planet over the comet's step ends, and its time, both from the closed-form orbits of the
/// comet and the planet at the step ends (enumerated one by one on a copy); the sampled
/// minimum is never below the true one (dense closed-form scan).
#[test]
fn a_close_approach_is_recorded_at_its_closed_form_minimum_over_the_step_ends() {
    let orbit = Ellipse { a: 8.0, e: 0.5 };
    // The comet crosses r = 5 AU outbound at cos E = (1 − 5/a)/e; the planet is put 0.03
    // rad ahead of that point then.
    let big_e = ((1.0 - PLANET_ORBIT_AU / orbit.a) / orbit.e).acos();
    let crossing = orbit.time_at(0.0, big_e);
    let at_crossing = orbit.state(orbit.mean_motion() * crossing).0;
    let n_planet = (mu() / PLANET_ORBIT_AU.powi(3)).sqrt();
    let phase = at_crossing.y.atan2(at_crossing.x) - n_planet * crossing + 0.03;
    let planet_at = |t: f64| {
        let (s, c) = (phase + n_planet * t).sin_cos();
        Vec3::new(c, s, 0.0) * PLANET_ORBIT_AU
    };
    // Heliocentric distances: the barycentre is within 5·10⁻¹⁵ AU of the Sun.
    let distance_at = |t: f64| (orbit.state(orbit.mean_motion() * t).0 - planet_at(t)).norm();
    let build = |events: EventRules| {
        let ephemeris =
            Ephemeris::new(quiet_planets(phase), Integrator::S6 { step: 50.0 }).unwrap();
        let integ =
            ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, PAPER_B1).unwrap();
        let state = orbit.state(0.0);
        let mut p = Population::new(
            ephemeris,
            integ,
            RemovalRules::default(),
            0.0,
            FINE_STEP_DAYS,
            &[state],
            &[7],
        )
        .unwrap();
        p.set_events(events).unwrap();
        p
    };
    let radius = 1.0;
    let mut pop = build(EventRules {
        close_approach: Some(ApproachRadius::Au(radius)),
        ..EventRules::default()
    });
    let span = 2.0 * crossing;
    pop.advance_to(span, |_| {}).unwrap();
    let log = pop.members()[0].events.as_ref().expect("an event log");
    assert!(log.open_approaches.is_empty());
    let [event] = log.events[..] else {
        panic!("{:?}", log.events)
    };
    let EventKind::CloseApproach {
        planet,
        min_distance,
        ..
    } = event.kind
    else {
        panic!("{event:?}")
    };
    assert_eq!(planet, 1);
    // The step ends one by one (each call takes one step), their closed-form distances.
    let mut copy = build(EventRules::default());
    let mut best = (f64::NAN, f64::INFINITY);
    while copy.members()[0].particle.time < span {
        let t = copy.members()[0].particle.time;
        let d = distance_at(t);
        if d < best.1 {
            best = (t, d);
        }
        copy.advance_to(t + 1e-9, |_| {}).unwrap();
    }
    assert!(best.1 < radius, "the orbits pass within {radius} AU");
    println!(
        "close approach: map − closed form {:.2e} AU",
        min_distance - best.1
    );
    assert_eq!(event.time.to_bits(), best.0.to_bits());
    assert!(
        (min_distance - best.1).abs() < KEPLER_TOLERANCE_AU,
        "{min_distance} vs closed form {}",
        best.1
    );
    // The true minimum (closed form, 0.01-day grid around the crossing) is below or at the
    // sampled one.
    let true_min = (0..=40_000)
        .map(|k| distance_at(crossing - 200.0 + 0.01 * f64::from(k)))
        .fold(f64::INFINITY, f64::min);
    assert!(true_min <= min_distance + KEPLER_TOLERANCE_AU);
    println!(
        "close approach: sampled minimum {min_distance:.6} AU at t = {:.3} d, closed-form minimum {true_min:.6} AU",
        event.time
    );
}
