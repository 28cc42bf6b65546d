//! Throughput of `symplectic::Population` on Centaurs integrated through their close
//! encounters, with the interface of `comet_throughput`:
//!
//! `cargo run --release -p benches --example centaur_throughput -- N YEARS [FIRST_STEP] [TOLERANCE] [SEED] [PLANET_STEP_DAYS]`
//!
//! builds `benches::centaur_population` (the four giants, S6 at `PLANET_STEP_DAYS`, default
//! 91.3125 d as in `populations/centaurs.toml`; `N` comets with
//! `a` 5.5–30 AU, `e` 0–0.2, `i` 0–10°; S2 barycentric with `B₁ = 4·10⁻⁶`, a first step of
//! `FIRST_STEP` days per AU of initial distance, or of that many days for every comet if it
//! ends in `d` (default `20d`, the population file's `initial_step_days`); encounters
//! inside 3 Hill radii by Bulirsch–Stoer at `TOLERANCE` (default 10⁻¹²); removal below
//! q = 2.5 AU, unbound beyond 100 AU, or at a collision with a planet or the Sun), advances it `YEARS` years on `RAYON_NUM_THREADS`
//! threads and prints as its last line
//!
//! `particles=N particle_years_per_s=X particle_steps_per_s=Y threads=T seconds=S
//! bytes_per_particle=B active=A ...`
//!
//! with the counts of each end and of each orbital region (labels as in the Parquet tables)
//! of the active comets. The particle-years count each comet until its end. The clock covers
//! `advance_to` only. `CENTAUR_THROUGHPUT_INITIAL=FILE` writes the initial barycentric states
//! (as `comet_throughput` does) and `CENTAUR_THROUGHPUT_FINAL=FILE` each comet's status
//! and its own time and barycentric position then, its end's if it ended
//! (`id,status,time_days,x,y,z`; days, AU).
use std::collections::BTreeMap;
use std::time::Instant;

use symplectic::io::status_label;
use symplectic::{orbital_region, ParticleStatus};

const DAYS_PER_YEAR: f64 = 365.25;

fn main() {
    if let Err(e) = run() {
        eprintln!("centaur_throughput: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage =
        "usage: centaur_throughput N YEARS [FIRST_STEP (days per AU, or days for all: 20d)] [TOLERANCE] [SEED] [PLANET_STEP_DAYS]";
    let n: usize = args.first().and_then(|s| s.parse().ok()).ok_or(usage)?;
    let years: f64 = args.get(1).and_then(|s| s.parse().ok()).ok_or(usage)?;
    let arg = |i: usize, default: f64| -> Result<f64, String> {
        args.get(i)
            .map_or(Ok(default), |s| s.parse().map_err(|_| usage.to_string()))
    };
    let first_step = match args.get(2) {
        None => benches::FirstStep::Days(20.0),
        Some(s) => match s.strip_suffix('d') {
            Some(days) => benches::FirstStep::Days(days.parse().map_err(|_| usage.to_string())?),
            None => benches::FirstStep::PerAuDays(s.parse().map_err(|_| usage.to_string())?),
        },
    };
    let tolerance = arg(3, symplectic::DEFAULT_ENCOUNTER_TOLERANCE)?;
    let seed = arg(4, benches::CENTAUR_SEED as f64)? as u64;
    let planet_step = arg(5, 91.3125)?;
    let (mut population, states) =
        benches::centaur_population(n, seed, first_step, tolerance, planet_step)?;
    if let Ok(path) = std::env::var("CENTAUR_THROUGHPUT_INITIAL") {
        let planets = population.ephemeris().planets().clone();
        benches::write_comet_states(&path, &planets, &states)
            .map_err(|e| format!("{path}: {e}"))?;
    }
    let start = Instant::now();
    let progress = population
        .advance_to(years * DAYS_PER_YEAR, |_| {})
        .map_err(|e| e.to_string())?;
    let seconds = start.elapsed().as_secs_f64();
    let end = years * DAYS_PER_YEAR;
    let planets = population.ephemeris().planets().clone();
    let mut ends: BTreeMap<String, usize> = BTreeMap::new();
    let mut classes: BTreeMap<&str, usize> = BTreeMap::new();
    let mut final_rows = String::from("id,status,time_days,x,y,z\n");
    for (i, m) in population.members().iter().enumerate() {
        let (label, time) = status_label(&m.status, &planets);
        *ends.entry(label.clone()).or_default() += 1;
        let time = if time.is_nan() { m.particle.time } else { time };
        let q = m.particle.position;
        final_rows.push_str(&format!(
            "{},{label},{time:e},{:e},{:e},{:e}\n",
            m.id, q.x, q.y, q.z
        ));
        if m.status == ParticleStatus::Active {
            let el = population.elements(i).map_err(|e| e.to_string())?;
            *classes.entry(orbital_region(&el).label()).or_default() += 1;
        }
    }
    if let Ok(path) = std::env::var("CENTAUR_THROUGHPUT_FINAL") {
        std::fs::write(&path, final_rows).map_err(|e| format!("{path}: {e}"))?;
    }
    let particle_years: f64 = population
        .members()
        .iter()
        .map(|m| m.particle.time.min(end) / DAYS_PER_YEAR)
        .sum();
    let ends: Vec<String> = ends.iter().map(|(k, v)| format!("end_{k}={v}")).collect();
    let classes: Vec<String> = classes
        .iter()
        .map(|(k, v)| format!("class_{k}={v}"))
        .collect();
    println!(
        "particles={n} particle_years_per_s={:.4e} particle_steps_per_s={:.4e} threads={} \
         seconds={seconds:.3} bytes_per_particle={} active={} {} {}",
        particle_years / seconds,
        progress.particle_steps as f64 / seconds,
        rayon::current_num_threads(),
        symplectic::Population::bytes_per_particle(),
        progress.active,
        ends.join(" "),
        classes.join(" "),
    );
    Ok(())
}
