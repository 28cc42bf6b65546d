//! The population's own path through a close encounter — the map, the switch to the
//! encounter mode, the encounter, the hand-back and the map again — against an independent
//! code, comet by comet: REBOUND 5.2's IAS15 (H. Rein and D. S. Spiegel, "IAS15: a fast,
//! adaptive, high-order integrator for gravitational dynamics, accurate to machine precision
//! over a billion orbits", *MNRAS* 446, 1424–1437 (2015)) on the same initial states
//! (`reference-data/comet-encounters/`, provenance in its `SOURCE.md`).
//!
//! Eleven comets start outside 3 Hill radii of a giant planet and pass it at 0.05 to 2.9 Hill
//! radii (Jupiter 0.05, 0.1, 0.3, 1, 2, 2.9; Saturn 0.1, 1; Uranus 0.3; Neptune 0.1, 1). A
//! [`Population`] with the shipped Centaur population's settings (`populations/centaurs.toml`,
//! checked against the file below: planets S6 at 91.3125 d read by the map and the encounter
//! mode alike, the barycentric S2 map with `B₁ = 4·10⁻⁶`, the switch at 3 Hill radii, the
//! hand-back beyond 3.5, Bulirsch–Stoer at 10⁻¹²) but the map's first step, 0.2 d instead of
//! 20 d ([`FIRST_STEP_DAYS`]), integrates them to `t_end`, when they are again some 5 Hill
//! radii away, back in the map; each must have switched to the encounter mode and been
//! handed back.
//!
//! **The map's step.** The bound below holds IAS15's and the planets' errors, not the
//! second-order map's own truncation error over the 3.5 to 18.5 years of a pass outside the
//! switch radius, which no reference measures for us. At the shipped 20 d that error
//! dominates: measured 2026-12-05, |Δq| = 1.0·10⁻⁵ to 3.9·10⁻⁴ AU after the Jupiter passes
//! (3.9·10⁻⁴ at 0.05 Hill radii), 100 times less at 2 d (9.5·10⁻⁸ to 3.9·10⁻⁶ AU), as a
//! second-order map's `Δt²`. At 0.2 d it is below the bound, so that what is compared is the
//! switch, the encounter, the hand-back and the planets the comet feels, which the bound
//! covers. Our state at the comet's own time (past `t_end` by part of a map step) is
//! carried back to `t_end` by the encounter integrator at tolerance 10⁻¹⁴ among the
//! ephemeris' planets, and compared with IAS15's.
//!
//! **The bound** (per comet, fixed by the reference data, never by our own error estimate):
//!
//! `|Δq| ≤ 10 |q_IAS15(ε = 10⁻⁹) − q_IAS15(ε = 10⁻¹¹)| + √3 tol |q| + 3 S_q E_P`, and alike
//! for the velocity:
//!
//! 1. *IAS15's convergence*: the difference of its runs at its default `ε = 10⁻⁹` and at
//!    `10⁻¹¹` measures the error of the default run; we ask the population for no more than
//!    ten times that, an order of magnitude, the precision expected of a code compared at
//!    REBOUND's default setting; and the precision the encounter tolerance asks of the
//!    state, `tol` of its length per component (`√3 tol` in length), as in the single
//!    encounters' test (`tests/encounters.rs`).
//! 2. *The planets*: ours are an ephemeris (S6 at 91.3125 d, read through its interpolant),
//!    IAS15's are integrated with the comet; the two trajectories differ, by at most
//!    `E_P` = [`PLANET_ERROR_AU`] = 10⁻⁸ AU, the accuracy required of Jupiter's trajectory,
//!    checked here for the planet each comet passes against IAS15's own planets at eight
//!    times of the pass (`path_planets.csv`). How much the comet moves for a displacement of the
//!    planet is measured with IAS15 alone (`path_sensitivity.csv`): the planet's initial position
//!    moved by 10⁻⁷ AU along its radius, its motion and its orbit's normal in turn, the
//!    comet's change at `t_end` per unit displacement of the planet at the closest approach,
//!    `S_q` (`S_v`) the largest of the three. A displacement in any direction is a
//!    combination of the three, so the response is at most `√3 S E` for a linear response;
//!    the safety factor 3 covers that `√3` and the difference between the history of our
//!    planets' error (a phase error growing along the pass) and the runs' (a displacement
//!    that drifts as the shifted orbit does).
//! 3. Round-off and the transfer to `t_end` are below 10⁻¹³ AU, far inside either term
//!    (the smallest bound is printed).
//!
//! A miss fails with the figures.

use symplectic::{
    integrate_through, outer_solar_system, BodyStates, Encounters, Ephemeris, Frame, Integrator,
    ParticleIntegrator, ParticleStatus, Population, RemovalRules, Scheme, Variant, Vec3,
};

/// The planets' step of the shipped Centaur population (days).
const PLANET_STEP_DAYS: f64 = 91.3125;
/// Its map's `B₀` (AU²/day²) and `B₁` (AU³/day²).
const B0: f64 = 0.0;
const B1: f64 = 4e-6;
/// The map's first physical step (days): a hundredth of the shipped population's 20 d
/// (module docs, *The map's step*; the step law and everything else are the shipped ones).
const FIRST_STEP_DAYS: f64 = 0.2;
/// The shipped population's first step (days), checked against its file.
#[cfg(feature = "io")]
const SHIPPED_FIRST_STEP_DAYS: f64 = 20.0;
/// Its removal rules: perihelion below 2.5 AU, unbound beyond 100 AU.
const MIN_PERIHELION_AU: f64 = 2.5;
const EJECTION_DISTANCE_AU: f64 = 100.0;
/// Its encounters: switch at 3 Hill radii, hand-back beyond 3.5, tolerance 10⁻¹².
const ENCOUNTERS: Encounters = Encounters {
    hill_factor: 3.0,
    hand_back_hill_factor: 3.5,
    tolerance: 1e-12,
};
/// The accuracy required of the planets' trajectory (AU): the largest distance allowed
/// between the ephemeris' planet and IAS15's over the pass (checked), the `E_P` of the bound.
const PLANET_ERROR_AU: f64 = 1e-8;
/// The safety factor on the planets' term of the bound (module docs, item 2).
const PLANET_SAFETY: f64 = 3.0;
/// The factor on IAS15's convergence (module docs, item 1).
const CONVERGENCE_FACTOR: f64 = 10.0;

const INITIAL: &str = include_str!("../../../reference-data/comet-encounters/path_initial.csv");
const FINAL: &str = include_str!("../../../reference-data/comet-encounters/path_final.csv");
const PLANETS: &str = include_str!("../../../reference-data/comet-encounters/path_planets.csv");
const SENSITIVITY: &str =
    include_str!("../../../reference-data/comet-encounters/path_sensitivity.csv");

/// One comet of `path_initial.csv`.
struct Comet {
    planet: usize,
    closest_hill_radii: f64,
    state: (Vec3, Vec3),
    t_end: f64,
}

/// The rows of a CSV text after its header, split at commas.
fn rows(text: &str) -> Vec<Vec<&str>> {
    text.lines()
        .skip(1)
        .filter(|l| !l.is_empty())
        .map(|l| l.split(',').collect())
        .collect()
}

fn number(s: &str) -> f64 {
    s.parse().unwrap_or_else(|e| panic!("{s:?}: {e}"))
}

fn vec3(r: &[&str], from: usize) -> Vec3 {
    Vec3::new(number(r[from]), number(r[from + 1]), number(r[from + 2]))
}

/// The comets of `path_initial.csv` (the planets' rows are the ephemeris' epoch states, checked).
fn comets(epoch: &BodyStates) -> Vec<Comet> {
    let mut out = Vec::new();
    for r in rows(INITIAL) {
        // kind,index,planet,closest_hill_radii,gm,x,y,z,vx,vy,vz,t_end
        let (q, v) = (vec3(&r, 5), vec3(&r, 8));
        if r[0] == "body" {
            let j: usize = r[1].parse().unwrap();
            assert_eq!(q, epoch.positions[j], "body {j}'s position");
            assert_eq!(v, epoch.velocities[j], "body {j}'s velocity");
            continue;
        }
        assert_eq!(r[1].parse::<usize>().unwrap(), out.len(), "comets in order");
        out.push(Comet {
            planet: r[2].parse().unwrap(),
            closest_hill_radii: number(r[3]),
            state: (q, v),
            t_end: number(r[11]),
        });
    }
    out
}

/// IAS15's result for one comet: its state at `t_end` at ε = 10⁻⁹ and 10⁻¹¹, and its closest
/// approach (AU, sampled, ε = 10⁻⁹).
struct Ias15 {
    default: (Vec3, Vec3),
    tight: (Vec3, Vec3),
    closest: f64,
}

fn ias15(comet: usize) -> Ias15 {
    let mut default = None;
    let mut tight = None;
    let mut closest = f64::NAN;
    for r in rows(FINAL)
        .into_iter()
        .filter(|r| r[0] == comet.to_string())
    {
        // comet,planet,epsilon,t_end,closest,x,y,z,vx,vy,vz
        let state = (vec3(&r, 5), vec3(&r, 8));
        let epsilon = number(r[2]);
        if epsilon == 1e-9 {
            default = Some(state);
            closest = number(r[4]);
        } else if epsilon == 1e-11 {
            tight = Some(state);
        } else {
            panic!("path_final.csv: epsilon {epsilon}");
        }
    }
    Ias15 {
        default: default.expect("path_final.csv: the epsilon 1e-9 row"),
        tight: tight.expect("path_final.csv: the epsilon 1e-11 row"),
        closest,
    }
}

/// `(S_q, S_v)`: the comet's largest change of position and of velocity at `t_end` per unit
/// displacement of the planet at the closest approach, over the three directions.
fn sensitivity(comet: usize) -> (f64, f64) {
    let mut s = (0.0f64, 0.0f64);
    let mut runs = 0;
    for r in rows(SENSITIVITY)
        .into_iter()
        .filter(|r| r[0] == comet.to_string())
    {
        // comet,planet,direction,delta,planet_displacement_max,
        // planet_displacement_at_closest,comet_position_change,comet_velocity_change
        let moved = number(r[5]);
        s = (s.0.max(number(r[6]) / moved), s.1.max(number(r[7]) / moved));
        runs += 1;
    }
    assert_eq!(
        runs, 3,
        "path_sensitivity.csv: three directions for comet {comet}"
    );
    s
}

/// The largest distance between our ephemeris' `planet` (the population's: the same grid)
/// and IAS15's over comet `comet`'s pass.
fn planet_error(ephemeris: &mut Ephemeris, comet: usize, planet: usize) -> f64 {
    let mut bodies = BodyStates::default();
    let mut worst = 0.0f64;
    let mut samples = 0;
    for r in rows(PLANETS)
        .into_iter()
        .filter(|r| r[0] == comet.to_string() && r[2] == planet.to_string())
    {
        // comet,t,planet,x,y,z
        ephemeris.bodies_at(number(r[1]), &mut bodies).unwrap();
        worst = worst.max((bodies.positions[planet] - vec3(&r, 3)).norm());
        samples += 1;
    }
    assert_eq!(
        samples, 8,
        "path_planets.csv: eight times for comet {comet}"
    );
    worst
}

fn ephemeris() -> Ephemeris {
    Ephemeris::new(
        outer_solar_system(Frame::EclipticJ2000),
        Integrator::S6 {
            step: PLANET_STEP_DAYS,
        },
    )
    .unwrap()
}

/// The comets in a population with the shipped Centaur population's settings (the first step
/// [`FIRST_STEP_DAYS`]).
fn population(comets: &[Comet]) -> Population {
    let integrator = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, B0, B1).unwrap();
    let rules = RemovalRules {
        min_perihelion: Some(MIN_PERIHELION_AU),
        ejection_distance: Some(EJECTION_DISTANCE_AU),
        ..RemovalRules::default()
    };
    let states: Vec<_> = comets.iter().map(|c| c.state).collect();
    let ids: Vec<u64> = (0..comets.len() as u64).collect();
    let mut population = Population::new(
        ephemeris(),
        integrator,
        rules,
        0.0,
        FIRST_STEP_DAYS,
        &states,
        &ids,
    )
    .unwrap();
    population.set_encounters(Some(ENCOUNTERS)).unwrap();
    population
}

/// Hill radius of `planet` among `bodies` (AU).
fn hill_radius(bodies: &BodyStates, planet: usize) -> f64 {
    (bodies.positions[planet] - bodies.positions[0]).norm()
        * (bodies.gm[planet] / (3.0 * bodies.gm[0])).cbrt()
}

/// Member `i`'s state carried from its own time back to `t` (`≤` its time, far from every
/// planet) by the encounter integrator among the ephemeris' planets, every velocity reversed.
fn state_at(population: &Population, i: usize, t: f64) -> (Vec3, Vec3) {
    let p = &population.members()[i].particle;
    let mut bodies = BodyStates::default();
    population
        .ephemeris()
        .interpolate(p.time, &mut bodies, false)
        .unwrap();
    bodies.time = 0.0;
    bodies.velocities.iter_mut().for_each(|v| *v = -*v);
    let carry = Encounters {
        tolerance: 1e-14,
        ..ENCOUNTERS
    };
    let back = integrate_through(&bodies, p.position, -p.velocity, p.time - t, &carry).unwrap();
    (back.position, -back.velocity)
}

#[test]
fn the_population_path_through_an_encounter_agrees_with_ias15() {
    let mut epoch = BodyStates::default();
    ephemeris().bodies_at(0.0, &mut epoch).unwrap();
    let comets = comets(&epoch);
    assert_eq!(comets.len(), 11);
    let mut population = population(&comets);
    let mut ours = ephemeris();
    let mut order: Vec<usize> = (0..comets.len()).collect();
    order.sort_by(|&a, &b| comets[a].t_end.total_cmp(&comets[b].t_end));
    let mut failures = Vec::new();
    for k in order {
        let c = &comets[k];
        population.advance_to(c.t_end, |_| {}).unwrap();
        let m = &population.members()[k];
        let start = (c.state.0 - epoch.positions[c.planet]).norm() / hill_radius(&epoch, c.planet);
        assert!(
            start > 3.0,
            "comet {k} starts at {start} R_H, inside the switch radius"
        );
        assert_eq!(m.status, ParticleStatus::Active, "comet {k}");
        assert!(
            m.encounters_begun >= 1 && m.encounter.is_none(),
            "comet {k}: {} switches, in the encounter mode at the end: {}",
            m.encounters_begun,
            m.encounter.is_some()
        );
        let planets = planet_error(&mut ours, k, c.planet);
        assert!(
            planets <= PLANET_ERROR_AU,
            "comet {k}: planet {} {planets:e} AU from IAS15's, above the {PLANET_ERROR_AU:e} AU the bound allows",
            c.planet
        );
        let reference = ias15(k);
        let (s_q, s_v) = sensitivity(k);
        let (q, v) = state_at(&population, k, c.t_end);
        let (ref_q, ref_v) = reference.tight;
        let precision = 3f64.sqrt() * ENCOUNTERS.tolerance;
        let bound_q = CONVERGENCE_FACTOR * (reference.default.0 - ref_q).norm()
            + precision * ref_q.norm()
            + PLANET_SAFETY * s_q * PLANET_ERROR_AU;
        let bound_v = CONVERGENCE_FACTOR * (reference.default.1 - ref_v).norm()
            + precision * ref_v.norm()
            + PLANET_SAFETY * s_v * PLANET_ERROR_AU;
        let (dq, dv) = ((q - ref_q).norm(), (v - ref_v).norm());
        let mut hill_bodies = BodyStates::default();
        ours.bodies_at(c.t_end / 2.0, &mut hill_bodies).unwrap();
        let closest = reference.closest / hill_radius(&hill_bodies, c.planet);
        let line = format!(
            "comet {k}: planet {}, closest {closest:.3} R_H (set up at {}), from {start:.2} R_H, {} switch(es): \
             |dq| {dq:.3e} AU (bound {bound_q:.3e}: IAS15 {:.2e}, S_q {s_q:.3e}), \
             |dv| {dv:.3e} AU/d (bound {bound_v:.3e}: IAS15 {:.2e}, S_v {s_v:.3e}), planets {planets:.2e} AU",
            c.planet,
            c.closest_hill_radii,
            m.encounters_begun,
            (reference.default.0 - ref_q).norm(),
            (reference.default.1 - ref_v).norm(),
        );
        println!("{line}");
        if dq > bound_q || dv > bound_v {
            failures.push(format!("FAIL {line}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The settings above are the shipped population's (`populations/centaurs.toml`).
#[cfg(feature = "io")]
#[test]
fn the_settings_are_those_of_the_shipped_centaur_population() {
    use symplectic::io::PopulationSpec;
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../populations/centaurs.toml");
    let spec = PopulationSpec::from_file(&path).unwrap();
    assert_eq!(
        spec.ephemeris().unwrap().integrator(),
        Integrator::S6 {
            step: PLANET_STEP_DAYS
        }
    );
    assert_eq!(
        spec.particle_integrator().unwrap(),
        ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, B0, B1).unwrap()
    );
    assert_eq!(spec.integrator.initial_step_days, SHIPPED_FIRST_STEP_DAYS);
    assert_eq!(spec.removal.min_perihelion, Some(MIN_PERIHELION_AU));
    assert_eq!(spec.removal.ejection_distance, Some(EJECTION_DISTANCE_AU));
    assert_eq!(spec.encounters, Some(ENCOUNTERS));
}
