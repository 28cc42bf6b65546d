//! The Centaurs of `centaur-population`, run from the initial states that MERCURIUS ran (the
//! first comets of `reference-data/centaur-population/initial_1000.csv` or
//! `initial_20000.csv`), with the settings of `populations/centaurs.toml`, and resumable: a
//! checkpoint in the experiment's output directory at a fixed cadence of simulated time,
//! written atomically, from which a killed run goes on bit for bit.

use std::path::Path;

use anyhow::{bail, Context as _, Result};
use serde::{Deserialize, Serialize};
use symplectic::io::{status_label, ParticleKind, ParticleRow, PopulationSpec};
use symplectic::{load_checkpoint, save_checkpoint, Population};

use crate::helpers::load_reference_csv;
use crate::helpers::solar_system::DAYS_PER_YEAR;
use crate::{workspace_root, Context};

/// Comets' initial barycentric states (the Sun and the giants' rows beside them) in a file of
/// the reference data, the same file MERCURIUS's ends were computed from: its first
/// `comets` comets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Sample {
    /// The file, relative to the reference-data directory.
    pub initial: &'static str,
    /// How many comets, from the first.
    pub comets: usize,
}

/// Name of the run's checkpoint in the experiment's output directory.
const CHECKPOINT_FILE: &str = "population_checkpoint.json";

/// What a checkpoint holds: what defines the run (to refuse resuming another), and the
/// population at its time.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RunCheckpoint {
    /// The population file's text.
    spec: String,
    /// The initial states' file and the number of comets (the states are versioned with the
    /// code).
    initial: String,
    comets: usize,
    /// The run's span (years).
    span_years: f64,
    /// The modification time of the executable that wrote it (seconds since the Unix
    /// epoch): a checkpoint of another build is not resumed.
    build: u64,
    /// The population at the checkpoint.
    population: Population,
}

/// How a comet ended: the label (`active`, `perihelion`, `ejected`, `collision_<planet>`,
/// anything else from our code) and the time in years (∞ if active at the span's end).
pub(crate) type Ends = Vec<(String, f64)>;

/// The sample's comets' initial states as particle rows (barycentric states, AU and AU/day).
fn initial_rows(ctx: &Context, sample: Sample) -> Result<Vec<ParticleRow>> {
    let table = load_reference_csv(
        ctx,
        sample.initial,
        &["kind", "id", "gm", "x", "y", "z", "vx", "vy", "vz"],
    )?;
    let mut rows = Vec::new();
    for i in 0..table.len() {
        if rows.len() == sample.comets {
            break;
        }
        if table.text(i, "kind")? != "particle" {
            continue;
        }
        let mut values = [0.0; 6];
        for (v, col) in values.iter_mut().zip(["x", "y", "z", "vx", "vy", "vz"]) {
            *v = table.number(i, col)?;
        }
        let id = table.number(i, "id")?;
        if id != rows.len() as f64 {
            bail!(
                "{}: line {}: comet id {id}, expected {} (comets in id order from 0)",
                sample.initial,
                i + 2,
                rows.len()
            );
        }
        rows.push(ParticleRow {
            line: i as u64 + 2,
            id: id as u64,
            values,
        });
    }
    if rows.len() < sample.comets {
        bail!(
            "{}: {} comets, {} expected",
            sample.initial,
            rows.len(),
            sample.comets
        );
    }
    Ok(rows)
}

/// Seconds since the Unix epoch at which the running executable was last modified (0 if the
/// system cannot say).
fn build_stamp() -> u64 {
    std::env::current_exe()
        .and_then(std::fs::metadata)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_secs())
}

/// What [`run_ours`] returns.
pub(crate) struct OursRun {
    /// Each comet's end, in id order, censored at the span.
    pub ends: Ends,
    /// Switches to the encounter integrator of all comets
    /// (`PopulationProgress::encounters_begun`).
    pub encounters_begun: u64,
    /// Switches per close encounter with a planet (`Population::switches_per_encounter`).
    pub switches_per_encounter: symplectic::SwitchesPerEncounter,
    /// The checkpoint's time the run resumed from (years), if it did.
    pub resumed_from_years: Option<f64>,
}

/// `populations/centaurs.toml`'s text, and its population built from the sample.
fn fresh(ctx: &Context, sample: Sample) -> Result<(String, Population)> {
    let spec_path = workspace_root().join("populations/centaurs.toml");
    let spec_text = std::fs::read_to_string(&spec_path)
        .with_context(|| format!("reading {}", spec_path.display()))?;
    let mut spec = PopulationSpec::parse(&spec_text, &spec_path)?;
    spec.particles.kind = ParticleKind::BarycentricState;
    let rows = initial_rows(ctx, sample)?;
    let population = spec.population_from_rows(&rows, Path::new(sample.initial))?;
    Ok((spec_text, population))
}

/// Runs the sample's comets with `populations/centaurs.toml`'s settings for `span_years`.
/// With `checkpoint_every_years`, the population is written to the output directory at every
/// multiple of that cadence (atomically) and a run of the same build, specification, comets
/// and span resumes from it; the checkpoint is removed once the run ends.
pub(crate) fn run_ours(
    ctx: &Context,
    sample: Sample,
    span_years: f64,
    checkpoint_every_years: Option<f64>,
) -> Result<OursRun> {
    let (spec_text, mut population) = fresh(ctx, sample)?;
    let comets = population.members().len();
    let checkpoint = ctx.path(CHECKPOINT_FILE);
    let build = build_stamp();
    let mut resumed_from_years = None;
    if checkpoint_every_years.is_some() && checkpoint.exists() {
        let c: RunCheckpoint = load_checkpoint(&checkpoint)?;
        if c.spec == spec_text
            && c.initial == sample.initial
            && c.comets == comets
            && c.span_years == span_years
            && c.build == build
        {
            resumed_from_years = Some(c.population.time() / DAYS_PER_YEAR);
            population = c.population;
        }
    }
    ctx.progress.set_length(span_years as u64);
    let end = span_years * DAYS_PER_YEAR;
    let every = checkpoint_every_years.map_or(end, |y| y * DAYS_PER_YEAR);
    loop {
        // The next multiple of the cadence after the population's time (a resumed run
        // continues the uninterrupted run's sequence of stops).
        let next = ((population.time() / every).floor() + 1.0) * every;
        let t = next.min(end);
        population.advance_to(t, |p| {
            ctx.progress.set_position((p.time / DAYS_PER_YEAR) as u64)
        })?;
        if t >= end {
            break;
        }
        if checkpoint_every_years.is_some() {
            let c = RunCheckpoint {
                spec: spec_text.clone(),
                initial: sample.initial.to_string(),
                comets,
                span_years,
                build,
                population,
            };
            save_checkpoint(&checkpoint, &c)?;
            population = c.population;
        }
    }
    if checkpoint.exists() {
        std::fs::remove_file(&checkpoint)
            .with_context(|| format!("removing {}", checkpoint.display()))?;
    }
    let planets = population.ephemeris().planets().clone();
    let ends = population
        .members()
        .iter()
        .map(|m| {
            let (label, t) = status_label(&m.status, &planets);
            censor(label, t / DAYS_PER_YEAR, span_years)
        })
        .collect();
    Ok(OursRun {
        ends,
        encounters_begun: population.progress().encounters_begun,
        switches_per_encounter: population.switches_per_encounter(),
        resumed_from_years,
    })
}

/// An end after `span` years counts as active (both codes are compared over the same span).
pub(crate) fn censor(label: String, years: f64, span: f64) -> (String, f64) {
    if label == "active" || years > span {
        ("active".into(), f64::INFINITY)
    } else {
        (label, years)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{reference_data_dir, Mode};
    use indicatif::ProgressBar;

    /// A run killed after its checkpoint at 1 kyr and started again ends as the
    /// uninterrupted run, bit for bit; a checkpoint of another span is not resumed.
    #[test]
    fn a_killed_run_resumes_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("centaur-sample-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ctx = Context::new(
            Mode::Full,
            dir.clone(),
            reference_data_dir(),
            ProgressBar::hidden(),
        );
        let span = 2_000.0;
        let sample = Sample {
            initial: "centaur-population/initial_1000.csv",
            comets: 1_000,
        };
        let whole = run_ours(&ctx, sample, span, None).unwrap();
        assert!(
            whole.ends.iter().any(|(l, _)| l != "active"),
            "no comet ended: nothing to compare"
        );
        // What the killed run left: its checkpoint at 1 kyr, written as run_ours writes it.
        let (spec, mut population) = fresh(&ctx, sample).unwrap();
        population
            .advance_to(1_000.0 * DAYS_PER_YEAR, |_| {})
            .unwrap();
        let killed = |span_years: f64, population: Population| RunCheckpoint {
            spec: spec.clone(),
            initial: sample.initial.to_string(),
            comets: population.members().len(),
            span_years,
            build: build_stamp(),
            population,
        };
        save_checkpoint(
            &ctx.path(CHECKPOINT_FILE),
            &killed(span, population.clone()),
        )
        .unwrap();
        let resumed = run_ours(&ctx, sample, span, Some(1_000.0)).unwrap();
        assert_eq!(resumed.resumed_from_years, Some(1_000.0));
        assert_eq!(resumed.ends, whole.ends);
        assert_eq!(resumed.encounters_begun, whole.encounters_begun);
        assert!(
            !ctx.path(CHECKPOINT_FILE).exists(),
            "the finished run's checkpoint stays"
        );
        save_checkpoint(&ctx.path(CHECKPOINT_FILE), &killed(3_000.0, population)).unwrap();
        let other = run_ours(&ctx, sample, span, Some(1_000.0)).unwrap();
        assert_eq!(other.resumed_from_years, None);
        assert_eq!(other.ends, whole.ends);
        std::fs::remove_dir_all(&dir).ok();
    }
}
