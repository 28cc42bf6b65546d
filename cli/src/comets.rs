//! `particles comets POPULATION.toml [--out DIR]`: a population study of test particles among
//! the planets ([`symplectic::study::run_study`]): snapshots, a final table and an events
//! table in Parquet,
//! checkpoints, resumed bit for bit by running the same command again.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use symplectic::io::{PopulationSpec, DAYS_PER_YEAR};
use symplectic::study::{run_study, EVENTS_TABLE, FINAL_TABLE, SNAPSHOT_DIR};
use symplectic::SymplecticError;

/// Arguments of `particles comets`.
#[derive(clap::Args)]
pub struct CometsArgs {
    /// The population specification (TOML: `[planets]`, `[integrator]`, `[particles]`,
    /// `[span]`, `[removal]`, `[encounters]`, `[events]`; see `populations/scattered-disk.toml`).
    pub population: PathBuf,
    /// Output directory [default: comets-STEM in the current directory, STEM the TOML file name without .toml]. If
    /// it holds a checkpoint of the same specification, the study resumes from it.
    #[arg(long, value_name = "DIR", value_parser = crate::directory)]
    pub out: Option<PathBuf>,
}

/// Runs the study with a progress bar (simulated years, particle-years per second).
pub fn run(args: &CometsArgs) -> Result<()> {
    let spec = PopulationSpec::from_file(&args.population)?;
    let out = match &args.out {
        Some(o) => o.clone(),
        None => {
            let stem = args
                .population
                .file_stem()
                .map_or("population".into(), |s| s.to_string_lossy().into_owned());
            PathBuf::from(format!("comets-{stem}"))
        }
    };
    let bar = ProgressBar::new(spec.span.years.ceil() as u64);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} yr, {msg}")
            .context("progress bar template")?
            .progress_chars("=> "),
    );
    let epoch = spec.particles.epoch_days;
    // Ctrl-C asks the study to stop (it saves its state and returns); a second one ends
    // the process at once.
    ctrlc::set_handler(|| {
        if symplectic::guard::stop_requested() {
            std::process::exit(130);
        }
        symplectic::guard::request_stop();
    })
    .context("installing the Ctrl-C handler")?;
    let start = Instant::now();
    let (mut particle_years, mut last_time) = (0.0f64, f64::NAN);
    let result = run_study(&args.population, &out, |p| {
        if last_time.is_finite() {
            particle_years += (p.time - last_time) / DAYS_PER_YEAR * p.active as f64;
        }
        last_time = p.time;
        bar.set_position(((p.time - epoch) / DAYS_PER_YEAR).max(0.0) as u64);
        bar.set_message(format!(
            "{} active, {} removed, {:.3e} particle-yr/s",
            p.active,
            p.removed,
            particle_years / start.elapsed().as_secs_f64().max(1e-9)
        ));
    });
    let summary = match result {
        Err(SymplecticError::Interrupted { .. }) => {
            bar.abandon();
            bail!(
                "interrupted (Ctrl-C) at t = {:.1} years: the state is saved in {}; run the same command again to resume",
                (last_time - epoch) / DAYS_PER_YEAR,
                out.join(symplectic::study::CHECKPOINT_FILE).display()
            );
        }
        other => other?,
    };
    bar.finish();
    let p = summary.progress;
    println!(
        "{}: {} particles active, {} removed; {} particle steps; {} switches to the encounter integrator ({} close encounters with a planet, {:.2} switches per encounter, at most {}); {}{} snapshots written to {}, final table {}, {} events to {}{}",
        args.population.display(),
        p.active,
        p.removed,
        p.particle_steps,
        p.encounters_begun,
        summary.switches_per_encounter.encounters,
        summary.switches_per_encounter.mean(),
        summary.switches_per_encounter.max,
        if summary.resumed { "resumed; " } else { "" },
        summary.snapshots_written,
        out.join(SNAPSHOT_DIR).display(),
        out.join(FINAL_TABLE).display(),
        summary.events,
        out.join(EVENTS_TABLE).display(),
        if summary.events_dropped > 0 {
            format!(
                " ({} more not kept: logs full, see events.max_per_particle)",
                summary.events_dropped
            )
        } else {
            String::new()
        },
    );
    Ok(())
}
