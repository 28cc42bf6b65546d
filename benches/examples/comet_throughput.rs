//! Throughput of `symplectic::Population` with a fixed interface, for comparison with other
//! codes:
//!
//! `cargo run --release -p benches --example comet_throughput -- N YEARS [s2|s6]`
//!
//! builds the issue-21 population (the four giant planets of `outer_solar_system`, ecliptic
//! J2000, planets by S2 at τ = 365.25 d; `N` comets with barycentric perihelia 32–40 AU,
//! semi-major axes 40–100 AU, inclinations 0–30°, random angles, seed 2026 through
//! `symplectic::samples`; barycentric variant, `B₀ = 0`, `B₁ = 0.21·10⁻⁶`, first step
//! 365.25 d), advances it `YEARS` years on `RAYON_NUM_THREADS` threads and prints as its last
//! line
//!
//! `particles=N particle_years_per_s=X particle_steps_per_s=Y threads=T ...`
//!
//! followed by the wall time, the steps per particle-year and the median and largest
//! extended-Hamiltonian error `|H + p₄|/|H|` of the surviving particles. The clock covers
//! `advance_to` only (not building the particles).
use std::time::Instant;

use symplectic::kepler::state_from_elements;
use symplectic::samples::{sample_elements, SCATTERED_DISK};
use symplectic::{
    outer_solar_system, Ephemeris, Frame, Integrator, ParticleIntegrator, Population,
    RemovalRules, Scheme, Variant,
};

const DAYS_PER_YEAR: f64 = 365.25;
const SEED: u64 = 2026;

fn main() {
    if let Err(e) = run() {
        eprintln!("comet_throughput: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: comet_throughput N YEARS [s2|s6]";
    let n: usize = args.first().and_then(|s| s.parse().ok()).ok_or(usage)?;
    let years: f64 = args.get(1).and_then(|s| s.parse().ok()).ok_or(usage)?;
    let scheme = match args.get(2).map(String::as_str) {
        None | Some("s2") => Scheme::S2,
        Some("s6") => Scheme::S6,
        Some(other) => return Err(format!("unknown scheme {other:?}; {usage}")),
    };
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let g = planets.g();
    let mu = g * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
    let states = sample_elements(&SCATTERED_DISK, n, SEED)
        .iter()
        .map(|el| state_from_elements(el, mu))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())?;
    let ids: Vec<u64> = (0..n as u64).collect();
    let ephemeris = Ephemeris::new(planets, Integrator::S2 { step: DAYS_PER_YEAR })
        .map_err(|e| e.to_string())?;
    let integrator = ParticleIntegrator::new(Variant::Barycentric, scheme, 0.0, 0.21e-6)
        .map_err(|e| e.to_string())?;
    let rules = RemovalRules {
        hill_factor: Some(1.0),
        min_perihelion: Some(26.0),
        ejection_distance: Some(1000.0),
    };
    let mut population = Population::new(
        ephemeris,
        integrator,
        rules,
        0.0,
        DAYS_PER_YEAR,
        &states,
        &ids,
    )
    .map_err(|e| e.to_string())?;
    let start = Instant::now();
    let progress = population
        .advance_to(years * DAYS_PER_YEAR, |_| {})
        .map_err(|e| e.to_string())?;
    let seconds = start.elapsed().as_secs_f64();
    let particle_years: f64 = population
        .members()
        .iter()
        .map(|m| m.particle.time / DAYS_PER_YEAR)
        .sum();
    let mut errors: Vec<f64> = (0..n)
        .filter(|&i| population.members()[i].status == symplectic::ParticleStatus::Active)
        .filter_map(|i| population.relative_error(i))
        .map(f64::abs)
        .collect();
    errors.sort_by(f64::total_cmp);
    let median = errors.get(errors.len() / 2).copied().unwrap_or(f64::NAN);
    let largest = errors.last().copied().unwrap_or(f64::NAN);
    println!(
        "particles={n} particle_years_per_s={:.4e} particle_steps_per_s={:.4e} threads={} \
         seconds={seconds:.3} steps_per_particle_year={:.4} removed={} \
         median_rel_energy_error={median:.3e} max_rel_energy_error={largest:.3e}",
        particle_years / seconds,
        progress.particle_steps as f64 / seconds,
        rayon::current_num_threads(),
        progress.particle_steps as f64 / particle_years,
        progress.removed,
    );
    Ok(())
}
