//! A population study run from its specification (feature `io`): snapshots, final table and
//! checkpoints in one output directory, resumed bit for bit after any interruption.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::io::{events_table, population_table, write_parquet, PopulationSpec, DAYS_PER_YEAR};
use crate::{Population, PopulationProgress, SwitchesPerEncounter, SymplecticError};

/// Name of the checkpoint in the output directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.json";
/// Name of the final table in the output directory.
pub const FINAL_TABLE: &str = "final.parquet";
pub use crate::io::EVENTS_TABLE;
/// Directory of the snapshot tables in the output directory.
pub const SNAPSHOT_DIR: &str = "snapshots";

const STUDY_FORMAT: &str = "symplectic-population-study";
/// 2: the population's encounter settings have a hand-back radius (a version 1 checkpoint
/// goes on handed back at its switch radius, as it was integrated).
/// 3: the population's end rules `sun_collision`, `min_distance`, `max_distance`, its event
/// rules and the members' event logs (read as off and empty from versions 1 and 2), and an
/// encounter in progress holds the particle only (and its `p₄`; one of versions 1 and 2,
/// the Sun, the planets and the particle, is converted when the member next steps).
const STUDY_VERSION: u32 = 3;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyCheckpoint {
    format: String,
    version: u32,
    /// The specification's text, to refuse resuming another study.
    spec: String,
    /// Index of the next snapshot to write.
    next_snapshot: u64,
    /// Index of the next checkpoint time.
    next_checkpoint: u64,
    population: Population,
}

/// What a study did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudySummary {
    /// Where the population ended.
    pub progress: PopulationProgress,
    /// Whether it resumed from a checkpoint.
    pub resumed: bool,
    /// Snapshots written by this call (a run resumed from a checkpoint older than the last
    /// snapshot rewrites the snapshots after it, identical).
    pub snapshots_written: u64,
    /// Checkpoints written by this call: at their cadence and at the end (and on Ctrl-C,
    /// which ends the call with an error instead of a summary).
    pub checkpoints_written: u64,
    /// Rows of the events table ([`EVENTS_TABLE`]).
    pub events: u64,
    /// Events that full logs did not keep (the population table's `events_dropped`).
    pub events_dropped: u64,
    /// Switches to the encounter mode per close encounter with a planet
    /// ([`Population::switches_per_encounter`]).
    pub switches_per_encounter: SwitchesPerEncounter,
}

/// Runs the study of `spec_path` into `out_dir`: snapshot tables
/// `snapshots/snapshot_NNNNNN.parquet` at every `span.snapshot_every_years` from the epoch
/// (the first at the epoch), `final.parquet` and `events.parquet` (every particle's events,
/// [`events_table`]; no rows if the specification records none) at the end, and
/// `checkpoint.json` at every
/// `span.checkpoint_every_years` from the epoch (at every snapshot if it is not given), at
/// the end, and when stopped by Ctrl-C. If `out_dir` holds a checkpoint of the same
/// specification, the study resumes from it; the files it writes are then identical to
/// those of an uninterrupted run: a checkpoint older than the last snapshot (a run killed
/// between checkpoints) holds the index of the first snapshot after it, and the snapshots
/// from there on are written again, identical (the population is a deterministic function
/// of its checkpoint). A bad specification or particle file is refused before anything is
/// written. `on_sync` sees the progress after every synchronisation window.
pub fn run_study(
    spec_path: &Path,
    out_dir: &Path,
    mut on_sync: impl FnMut(&PopulationProgress),
) -> Result<StudySummary, SymplecticError> {
    let spec_text = crate::io::read_spec_text(spec_path)?;
    let spec = PopulationSpec::parse(&spec_text, spec_path)?;
    let checkpoint_path = out_dir.join(CHECKPOINT_FILE);
    let (mut state, resumed) = if checkpoint_path.exists() {
        let mut c: StudyCheckpoint = crate::load_checkpoint(&checkpoint_path)?;
        if c.format != STUDY_FORMAT || !(1..=STUDY_VERSION).contains(&c.version) {
            return Err(SymplecticError::Checkpoint {
                path: checkpoint_path.display().to_string(),
                reason: format!(
                    "format {:?} version {}, expected {STUDY_FORMAT:?} version 1 to {STUDY_VERSION}",
                    c.format, c.version
                ),
            });
        }
        if c.version == 1 {
            c.population.keep_version_1_hand_back();
        }
        c.version = STUDY_VERSION;
        if c.spec != spec_text {
            return Err(SymplecticError::Checkpoint {
                path: checkpoint_path.display().to_string(),
                reason: format!("belongs to another specification than {}; remove it or choose another output directory", spec_path.display()),
            });
        }
        (c, true)
    } else {
        let population = spec.population(spec_path)?;
        let c = StudyCheckpoint {
            format: STUDY_FORMAT.into(),
            version: STUDY_VERSION,
            spec: spec_text.clone(),
            next_snapshot: 0,
            next_checkpoint: 1,
            population,
        };
        (c, false)
    };
    let output = |e: std::io::Error, p: &Path| SymplecticError::Output {
        path: p.display().to_string(),
        reason: e.to_string(),
    };
    let snap_dir = out_dir.join(SNAPSHOT_DIR);
    std::fs::create_dir_all(&snap_dir).map_err(|e| output(e, &snap_dir))?;
    remove_stale_temporaries(out_dir).map_err(|e| output(e, out_dir))?;
    remove_stale_temporaries(&snap_dir).map_err(|e| output(e, &snap_dir))?;
    let epoch = spec.particles.epoch_days;
    let end = epoch + spec.span.years * DAYS_PER_YEAR;
    let snap_every = spec.span.snapshot_every_years * DAYS_PER_YEAR;
    // Without a cadence of their own, checkpoints go with the snapshots.
    let ck_every = spec.span.checkpoint_every_years.map(|y| y * DAYS_PER_YEAR);
    let snap_time = |k: u64| (epoch + k as f64 * snap_every).min(end);
    let ck_time = |k: u64| ck_every.map_or(f64::INFINITY, |every| epoch + k as f64 * every);
    let (mut written, mut checkpoints) = (0, 0);
    loop {
        let next_snap = snap_time(state.next_snapshot);
        let next_ck = ck_time(state.next_checkpoint);
        let done_snapshots = epoch + (state.next_snapshot as f64 - 1.0) * snap_every >= end
            && state.next_snapshot > 0;
        if done_snapshots {
            break;
        }
        let t = next_snap.min(next_ck).min(end);
        if let Err(e) = state.population.advance_to(t, &mut on_sync) {
            // Ctrl-C: the state where it stopped is a checkpoint like any other (a resumed
            // run continues bit for bit from wherever the particles stopped).
            if matches!(e, SymplecticError::Interrupted { .. }) {
                crate::save_checkpoint(&checkpoint_path, &state)?;
            }
            return Err(e);
        }
        let snapshot_due = t == next_snap;
        if snapshot_due {
            let path = snapshot_path(&snap_dir, state.next_snapshot);
            write_parquet(&path, &population_table(&state.population)?)?;
            written += 1;
            state.next_snapshot += 1;
        }
        let checkpoint_due = t == next_ck;
        if checkpoint_due {
            state.next_checkpoint += 1;
        }
        // At its own cadence (with the snapshots if it has none) and at the end: a rerun
        // over a finished directory then resumes at the end.
        if checkpoint_due || (ck_every.is_none() && snapshot_due) || t >= end {
            crate::save_checkpoint(&checkpoint_path, &state)?;
            checkpoints += 1;
        }
    }
    state.population.advance_to(end, &mut on_sync)?;
    let final_path = out_dir.join(FINAL_TABLE);
    write_parquet(&final_path, &population_table(&state.population)?)?;
    let events_path = out_dir.join(EVENTS_TABLE);
    let events = events_table(&state.population)?;
    write_parquet(&events_path, &events)?;
    let events_dropped = state
        .population
        .members()
        .iter()
        .filter_map(|m| m.events.as_ref())
        .map(|log| log.dropped)
        .sum();
    Ok(StudySummary {
        progress: state.population.progress(),
        resumed,
        snapshots_written: written,
        checkpoints_written: checkpoints,
        events: events.num_rows() as u64,
        events_dropped,
        switches_per_encounter: state.population.switches_per_encounter(),
    })
}

/// Removes what a killed run's atomic writes left in `dir`: a write is a temporary file,
/// linked as `.<name>.<six letters or digits>` just before it is renamed to `<name>`, so a kill
/// between the two leaves it behind (the renamed file is complete either way). Only names of
/// files a study writes are touched.
fn remove_stale_temporaries(dir: &Path) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        if is_study_temporary(name) && entry.file_type()?.is_file() {
            std::fs::remove_file(entry.path())?;
        }
    }
    Ok(())
}

/// Whether `name` is `.<target>.<6 alphanumerics>` for a file a study writes.
fn is_study_temporary(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('.') else {
        return false;
    };
    let Some((target, suffix)) = rest.rsplit_once('.') else {
        return false;
    };
    let is_snapshot = target
        .strip_prefix("snapshot_")
        .and_then(|t| t.strip_suffix(".parquet"))
        .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()));
    suffix.len() == 6
        && suffix.bytes().all(|b| b.is_ascii_alphanumeric())
        && (target == CHECKPOINT_FILE
            || target == FINAL_TABLE
            || target == EVENTS_TABLE
            || is_snapshot)
}

/// Path of snapshot `k`.
pub fn snapshot_path(dir: &Path, k: u64) -> PathBuf {
    dir.join(format!("snapshot_{k:06}.parquet"))
}

#[cfg(test)]
mod tests {
    use super::is_study_temporary;

    #[test]
    fn only_temporaries_of_the_study_files_are_recognised() {
        for name in [
            ".checkpoint.json.aW2s2a",
            ".final.parquet.000000",
            ".snapshot_000012.parquet.Zz9yQ1",
        ] {
            assert!(is_study_temporary(name), "{name}");
        }
        for name in [
            "checkpoint.json",
            ".checkpoint.json",
            ".checkpoint.json.aW2s2",
            ".checkpoint.json.aW2s2a7",
            ".checkpoint.json.aW2-2a",
            ".notes.txt.aW2s2a",
            ".snapshot_.parquet.aW2s2a",
            ".snapshot_00x.parquet.aW2s2a",
        ] {
            assert!(!is_study_temporary(name), "{name}");
        }
    }
}
