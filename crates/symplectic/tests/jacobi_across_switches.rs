//! The Jacobi constant of comets in the circular restricted three-body problem, carried by a
//! [`Population`] through repeated switches to the encounter mode and hand-backs.
//!
//! The Sun and one planet of Jupiter's mass on a circular orbit of 5.2 AU (its ephemeris
//! integrated by S6 at the shipped populations' 91.3125 d, read as a function of time by the
//! map and the encounter mode alike); twelve comets on near-circular orbits 4–14 % inside and
//! outside the planet's, which meet it again and again. Along the exact motion the Jacobi
//! constant `C_J = 2 Σ G m_j/|q − q_j| − v² + 2Ω (q × v)_z` (the bodies on the analytic
//! circle, an independent reference) is conserved; the comets' must stay within the bound
//! derived in [`jacobi_bound`] over 2000 years.

use symplectic::{
    Encounters, Ephemeris, Integrator, ParticleIntegrator, Planets, Population, PopulationMember,
    RemovalRules, Scheme, Variant, Vec3, G_AU3_PER_MSUN_DAY2,
};

const SUN_MASS: f64 = 1.0;
/// Jupiter's mass in solar masses.
const PLANET_MASS: f64 = 9.547_919e-4;
const PLANET_DISTANCE_AU: f64 = 5.2;
/// The planet's radius for collisions: 0.05 AU (0.14 Hill radius). A comet passing inside it
/// ends, so every encounter integrated stays outside it, where the bound's terms are taken.
const PLANET_RADIUS_AU: f64 = 0.05;
/// The removal rules: perihelion below 2.5 AU (so `r ≥ 2.5 AU` bounds the speeds and the
/// Sun's pull in the bound), unbound beyond 100 AU.
const MIN_PERIHELION_AU: f64 = 2.5;
/// The particle map's regularisation `B₁` (AU³/day², the Centaur population's).
const B1: f64 = 4e-6;
/// The first physical step of every comet (days).
const FIRST_STEP_DAYS: f64 = 0.5;
/// The planets' step (days): the shipped populations'.
const PLANET_STEP_DAYS: f64 = 91.3125;
/// The encounter integrator's tolerance (the default).
const TOLERANCE: f64 = 1e-12;
/// The ephemeris' largest distance from the analytic circle allowed (AU), checked in the
/// test: the quintic Hermite interpolant's error on a circle, `(ωτ)⁶/46080` of the radius
/// (6.1·10⁻¹⁰ AU at τ = 91.3125 d), and as much again for the S6 map's own error over the
/// span, rounded up; a fifth of the 10⁻⁸ AU required of Jupiter's trajectory.
const EPHEMERIS_ERROR_AU: f64 = 2e-9;
const YEARS: f64 = 2000.0;
const DAYS_PER_YEAR: f64 = 365.25;

/// The analytic circular motion of the Sun and the planet about their barycentre.
struct Circle {
    omega: f64,
}

impl Circle {
    fn new() -> Self {
        let gm = G_AU3_PER_MSUN_DAY2 * (SUN_MASS + PLANET_MASS);
        Self {
            omega: (gm / PLANET_DISTANCE_AU.powi(3)).sqrt(),
        }
    }

    /// Barycentric positions of the Sun and the planet at `t`.
    fn bodies(&self, t: f64) -> (Vec3, Vec3) {
        let (s, c) = (self.omega * t).sin_cos();
        let u = Vec3::new(c, s, 0.0);
        let total = SUN_MASS + PLANET_MASS;
        (
            -u * (PLANET_DISTANCE_AU * PLANET_MASS / total),
            u * (PLANET_DISTANCE_AU * SUN_MASS / total),
        )
    }

    fn jacobi(&self, m: &PopulationMember) -> f64 {
        let (t, q, v) = (m.particle.time, m.particle.position, m.particle.velocity);
        let (sun, planet) = self.bodies(t);
        let g = G_AU3_PER_MSUN_DAY2;
        2.0 * (g * SUN_MASS / (q - sun).norm() + g * PLANET_MASS / (q - planet).norm())
            - v.norm_squared()
            + 2.0 * self.omega * q.cross(&v).z
    }
}

fn population(circle: &Circle) -> Population {
    let speed = PLANET_DISTANCE_AU * circle.omega;
    let planets = Planets::from_heliocentric(
        G_AU3_PER_MSUN_DAY2,
        SUN_MASS,
        &[PLANET_MASS],
        &[Vec3::new(PLANET_DISTANCE_AU, 0.0, 0.0)],
        &[Vec3::new(0.0, speed, 0.0)],
    )
    .and_then(|p| p.with_names_and_radii(&["planet"], &[PLANET_RADIUS_AU]))
    .unwrap();
    let ephemeris = Ephemeris::new(
        planets,
        Integrator::S6 {
            step: PLANET_STEP_DAYS,
        },
    )
    .unwrap();
    let integrator = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, B1).unwrap();
    let gm = G_AU3_PER_MSUN_DAY2 * (SUN_MASS + PLANET_MASS);
    let offsets = [
        0.04, 0.06, 0.08, 0.10, 0.12, 0.14, -0.04, -0.06, -0.08, -0.10, -0.12, -0.14,
    ];
    let states: Vec<(Vec3, Vec3)> = offsets
        .iter()
        .enumerate()
        .map(|(k, x)| {
            // Circular orbits inclined by 2° to 7.5° (shallower encounters than coplanar
            // ones), at phases spread around the orbit.
            let r = PLANET_DISTANCE_AU * (1.0 + x);
            let (s, c) = (2.0 + 0.5 * k as f64).sin_cos();
            let (si, ci) = (2.0 + 0.5 * k as f64).to_radians().sin_cos();
            let v = (gm / r).sqrt();
            (
                Vec3::new(r * c, r * s, 0.0),
                Vec3::new(-v * s * ci, v * c * ci, v * si),
            )
        })
        .collect();
    let ids: Vec<u64> = (0..states.len() as u64).collect();
    let rules = RemovalRules {
        min_perihelion: Some(MIN_PERIHELION_AU),
        ejection_distance: Some(100.0),
        ..RemovalRules::default()
    };
    let mut population = Population::new(
        ephemeris,
        integrator,
        rules,
        0.0,
        FIRST_STEP_DAYS,
        &states,
        &ids,
    )
    .unwrap();
    let encounters = Encounters {
        tolerance: TOLERANCE,
        ..Encounters::default()
    };
    population.set_encounters(Some(encounters)).unwrap();
    population
}

/// The largest change of `C_J` allowed for member `m` (AU²/day²), from the map's order and
/// step, the encounter tolerance and the ephemeris error, each term a bound on its share:
///
/// `C_J = −2(H + p₄) + 2(p₄ + Ω L_z)`. With the planet exactly on its circle, every piece of
/// the map (the Kepler drift, rotation-invariant and independent of `t`; the kick, invariant
/// under a rotation by `Ωδ` together with `t → t + δ`) conserves `p₄ + Ω L_z` exactly, so
/// the map changes `C_J` only through its error in `H + p₄`:
///
/// 1. *The map* (second order, physical step `Δt`): the modified Hamiltonian of the
///    kick–drift–kick splitting is `H + Δt² ({B,{B,A}}/12 − {A,{A,B}}/24) + O(Δt⁴)` (Hairer,
///    Lubich & Wanner, *Geometric Numerical Integration*, 2nd ed., §IX.3), with `A` the Kepler
///    part and `B` the perturbation of each body: `{B,{B,A}} = |∇Φ_j|² ≤ g_j²`, and
///    `{A,{A,B}}`, the second derivative of `Φ_j` along the Kepler flow, at most
///    `w² k_j + g_j a_K` (`g_j`, `k_j` the perturbing acceleration and its gradient, `w` the
///    comet's speed relative to the body, `a_K` the Kepler acceleration). `H + p₄` stays
///    within `±` that difference, `C_J` within twice the range: `4 Δt² Σ_j (g_j²/12 +
///    (w² k_j + g_j a_K)/24)`. The map runs outside 3 Hill radii of the planet (`g = G m/d²`,
///    `k = 2 G m/d³` at `d = 3 R_H`) and, for the Sun's offset from the barycentre `s = a m/M`,
///    `g ≤ 2 G m₀ s/r³`, `k ≤ 6 G m₀ s/r⁴`; with `r ≥ 2.5 AU` (the perihelion rule)
///    `a_K ≤ G M/r²` and `w ≤ √(2 G M/r) + Ω a`. `Δt = h/F₀` with `F₀ ≥ 0.9 B₁/r` (the Sun's
///    offset term is at most 6 % of `B₁/r` at the planet), at `r = a + 3 R_H`.
/// 2. *The encounter mode*: each step's error is at most `tol` of the position's and the
///    velocity's length per component (the controller's test), `√3 tol` in length, so
///    `|ΔC_J| ≤ 2√3 tol (g_max |q| + 2 (|v| + Ω|q|) |v|)` per step with `g_max = G m/R² +
///    G M/r²` outside the planet's radius `R`; at most one step per 15 evaluations of the
///    right-hand side (the extrapolation's first accepted row costs `3 + 5 + 7`), which the
///    comet's interpolation count records (one per evaluation).
/// 3. *The ephemeris*: the planet off its circle by `δ ≤` [`EPHEMERIS_ERROR_AU`] adds a
///    dipole `δΦ` whose gradient is at most `2 G m δ/d³`; `dC_J/dt = −2 (∂_t + Ω ∂_φ) δΦ`,
///    whose integral over an encounter is at most `2|ΔδΦ| + 2 ∫|v_rot| |∇δΦ| dt ≤ 12 G m
///    δ/R²` for a pass outside `R` (`∫ ds/d³ ≤ 2/d_min²` along a straight pass, doubled for
///    the bend), per encounter begun.
fn jacobi_bound(m: &PopulationMember, circle: &Circle) -> f64 {
    let g = G_AU3_PER_MSUN_DAY2;
    let (gm_sun, gm_planet) = (g * SUN_MASS, g * PLANET_MASS);
    let gm = gm_sun + gm_planet;
    let hill = PLANET_DISTANCE_AU * (PLANET_MASS / (3.0 * SUN_MASS)).cbrt();
    let r_min = MIN_PERIHELION_AU;
    let omega = circle.omega;
    let planet_speed = omega * PLANET_DISTANCE_AU;
    let w = (2.0 * gm / r_min).sqrt() + planet_speed;
    let a_kepler = gm / (r_min * r_min);
    // 1. The map.
    let d = 3.0 * hill;
    let (g_planet, k_planet) = (gm_planet / (d * d), 2.0 * gm_planet / (d * d * d));
    let sun_offset = PLANET_DISTANCE_AU * PLANET_MASS / (SUN_MASS + PLANET_MASS);
    let g_sun = 2.0 * gm_sun * sun_offset / r_min.powi(3);
    let k_sun = 6.0 * gm_sun * sun_offset / r_min.powi(4);
    let r_near = PLANET_DISTANCE_AU + d;
    let dt = m.particle.step * r_near / (0.9 * B1);
    let term = |g: f64, k: f64| g * g / 12.0 + (w * w * k + g * a_kepler) / 24.0;
    let map = 4.0 * dt * dt * (term(g_planet, k_planet) + term(g_sun, k_sun));
    // 2. The encounter mode.
    let q_max = PLANET_DISTANCE_AU + d;
    let v_max = (2.0 * gm / r_min).sqrt();
    let g_max = gm_planet / PLANET_RADIUS_AU.powi(2) + gm / (r_min * r_min);
    let per_step =
        2.0 * 3f64.sqrt() * TOLERANCE * (g_max * q_max + 2.0 * (v_max + omega * q_max) * v_max);
    let encounter_steps = m.particle.work.interpolations as f64 / 15.0;
    let encounter = per_step * encounter_steps;
    // 3. The ephemeris.
    let ephemeris = f64::from(m.encounters_begun) * 12.0 * gm_planet * EPHEMERIS_ERROR_AU
        / PLANET_RADIUS_AU.powi(2);
    map + encounter + ephemeris
}

#[test]
fn jacobi_constant_held_through_repeated_switches() {
    let circle = Circle::new();
    let mut population = population(&circle);
    let start: Vec<f64> = population
        .members()
        .iter()
        .map(|m| circle.jacobi(m))
        .collect();
    let mut worst = vec![0.0f64; start.len()];
    let mut planet_error = 0.0f64;
    let mut bodies = symplectic::BodyStates::default();
    let mut t = 0.0;
    while t < YEARS * DAYS_PER_YEAR {
        t += 5.0 * DAYS_PER_YEAR;
        population.advance_to(t, |_| {}).unwrap();
        for (i, m) in population.members().iter().enumerate() {
            worst[i] = worst[i].max((circle.jacobi(m) - start[i]).abs());
        }
        // The ephemeris against the analytic circle, 16 times per grid interval of the last
        // five years.
        let e = population.ephemeris();
        let mut s = e.oldest_time().max(t - 5.0 * DAYS_PER_YEAR);
        while s <= e.newest_time() {
            e.interpolate(s, &mut bodies, false).unwrap();
            planet_error = planet_error.max((bodies.positions[1] - circle.bodies(s).1).norm());
            s += PLANET_STEP_DAYS / 16.0;
        }
    }
    for (i, m) in population.members().iter().enumerate() {
        let bound = jacobi_bound(m, &circle);
        println!(
            "comet {i}: {} switches, |ΔC_J| {:.3e} (relative {:.3e}), bound {bound:.3e}, {:?}",
            m.encounters_begun,
            worst[i],
            worst[i] / start[i].abs(),
            m.status
        );
        assert!(
            worst[i] <= bound,
            "comet {i}: |ΔC_J| {:e} above the bound {bound:e} after {} switches",
            worst[i],
            m.encounters_begun
        );
    }
    let switches: u32 = population
        .members()
        .iter()
        .map(|m| m.encounters_begun)
        .sum();
    // Repeated encounters: the comets inside the planet's orbit and outside it meet it many
    // times in 2000 years (synodic periods of 80 to 200 years).
    assert!(switches >= 40, "{switches} switches in all");
    // The accuracy required of the planets' trajectory, used in the bound's third term.
    assert!(
        planet_error <= EPHEMERIS_ERROR_AU,
        "planet {planet_error:e} AU off its circle"
    );
}
