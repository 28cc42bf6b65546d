//! Throughput of `symplectic::Population` with a fixed interface, for comparison with other
//! codes:
//!
//! `cargo run --release -p benches --example comet_throughput -- N YEARS [s2|s6] [DT0_DAYS] [PLANETS] [PLANET_STEP_DAYS]`
//!
//! builds the scattered-disk population: the four giant planets of `outer_solar_system` (ecliptic
//! J2000) integrated by `PLANETS` (`s2` or `s6`, default `s6`: the planets are shared by every
//! particle, so their accuracy costs little per particle) at `PLANET_STEP_DAYS` (default
//! 730.5 d); `N` comets with barycentric perihelia 32–40 AU, semi-major axes 40–100 AU,
//! inclinations 0–30°, random angles, seed 2026 through `symplectic::samples`, integrated by
//! the first scheme (default S2), barycentric variant, `B₀ = 0`, `B₁ = 0.21·10⁻⁶`, first step
//! `DT0_DAYS` (default 547.875 d). The defaults are the configuration whose median position
//! error at 10 kyr is below REBOUND WHFast's at τ = 365.25 d (`docs/performance.md`).
//! Removal at Hill-sphere entry, perihelion below 26 AU or ejection beyond 1000 AU. It
//! advances the population `YEARS` years on `RAYON_NUM_THREADS` threads and prints as its
//! last line
//!
//! `particles=N particle_years_per_s=X particle_steps_per_s=Y threads=T ...`
//!
//! followed by the wall time, the steps per particle-year, the median and largest
//! extended-Hamiltonian error `|H + p₄|/|H|` of the surviving particles, the bytes per
//! particle and the Kepler iterations per solve. The clock covers `advance_to` only (not
//! building the particles).
//!
//! For side-by-side runs with other codes, `COMET_THROUGHPUT_INITIAL=FILE` writes the
//! initial barycentric states of the planets and particles (CSV: `kind,id,gm,x,y,z,vx,vy,vz`,
//! AU, AU/day, `G m` in AU³/day²) and `COMET_THROUGHPUT_FINAL=FILE` the particles at the end
//! (`id,status,time,x,y,z,vx,vy,vz`, each at its own time).
use std::time::Instant;

use symplectic::{outer_solar_system, Frame, Integrator, Population, Scheme};

const DAYS_PER_YEAR: f64 = 365.25;

fn main() {
    if let Err(e) = run() {
        eprintln!("comet_throughput: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: comet_throughput N YEARS [s2|s6] [DT0_DAYS] [s2|s6] [PLANET_STEP_DAYS]";
    let n: usize = args.first().and_then(|s| s.parse().ok()).ok_or(usage)?;
    let years: f64 = args.get(1).and_then(|s| s.parse().ok()).ok_or(usage)?;
    let scheme = match args.get(2).map(String::as_str) {
        None | Some("s2") => Scheme::S2,
        Some("s6") => Scheme::S6,
        Some(other) => return Err(format!("unknown scheme {other:?}; {usage}")),
    };
    let dt0: f64 = match args.get(3) {
        None => 1.5 * DAYS_PER_YEAR,
        Some(s) => s.parse().map_err(|_| usage)?,
    };
    let planet_step: f64 = match args.get(5) {
        None => 2.0 * DAYS_PER_YEAR,
        Some(s) => s.parse().map_err(|_| usage)?,
    };
    let planet_map = match args.get(4).map(String::as_str) {
        None | Some("s6") => Integrator::S6 { step: planet_step },
        Some("s2") => Integrator::S2 { step: planet_step },
        Some(other) => return Err(format!("unknown planet map {other:?}; {usage}")),
    };
    let (mut population, states) = benches::scattered_disk_population(n, scheme, dt0, planet_map)?;
    if let Ok(path) = std::env::var("COMET_THROUGHPUT_INITIAL") {
        benches::write_comet_states(&path, &outer_solar_system(Frame::EclipticJ2000), &states)
            .map_err(|e| format!("{path}: {e}"))?;
    }
    let start = Instant::now();
    let progress = population
        .advance_to(years * DAYS_PER_YEAR, |_| {})
        .map_err(|e| e.to_string())?;
    let seconds = start.elapsed().as_secs_f64();
    if let Ok(path) = std::env::var("COMET_THROUGHPUT_FINAL") {
        write_final(&path, &population).map_err(|e| format!("{path}: {e}"))?;
    }
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
         median_rel_energy_error={median:.3e} max_rel_energy_error={largest:.3e} \
         bytes_per_particle={} kepler_iterations_per_solve={:.3}",
        particle_years / seconds,
        progress.particle_steps as f64 / seconds,
        rayon::current_num_threads(),
        progress.particle_steps as f64 / particle_years,
        progress.removed,
        Population::bytes_per_particle(),
        {
            let w = population.work();
            w.kepler_iterations as f64 / w.kepler_solves as f64
        },
    );
    Ok(())
}

fn write_final(path: &str, population: &Population) -> std::io::Result<()> {
    use std::fmt::Write as _;
    let mut out = String::from("id,status,time,x,y,z,vx,vy,vz\n");
    for (i, m) in population.members().iter().enumerate() {
        let q = population.barycentric_position(i);
        let v = m.particle.velocity;
        let status = if m.status == symplectic::ParticleStatus::Active {
            "active"
        } else {
            "removed"
        };
        writeln!(
            out,
            "{},{status},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            m.id, m.particle.time, q.x, q.y, q.z, v.x, v.y, v.z
        )
        .ok();
    }
    std::fs::write(path, out)
}
