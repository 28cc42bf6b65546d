//! `cargo xtask run SCENE`: a scene file run frame by frame with a progress bar, ParaView
//! frames and a CSV of per-frame statistics.

use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use sph_core::Real;
use sph_scene::{Precision, Scene};
use sph_solver::StepStats;

use crate::{SceneSim, SimError};

/// Options of [`run_scene`].
#[derive(Debug, Clone)]
pub struct SceneRunOptions {
    /// Apply the scene's `[quick]` overrides.
    pub quick: bool,
    /// Output directory (frames and statistics); created if missing.
    pub out_dir: PathBuf,
    /// Stop after this many frames (default: the scene's duration); must be ≥ 1.
    pub max_frames: Option<usize>,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

/// The columns of the statistics CSV before the solver's phase times.
pub const STATS_COLUMNS: [&str; 9] = [
    "frame",
    "time_s",
    "particles",
    "max_density_ratio",
    "mean_density_ratio",
    "iterations",
    "unconverged_substeps",
    "neighbour_pairs",
    "kinetic_energy_j",
];

/// The header of the statistics CSV for a solver with phases `phases`: [`STATS_COLUMNS`],
/// then `<phase>_s` for each phase, then `total_s`.
pub fn stats_header(phases: &[&str]) -> Vec<String> {
    STATS_COLUMNS
        .iter()
        .map(|s| s.to_string())
        .chain(phases.iter().map(|p| format!("{p}_s")))
        .chain(std::iter::once("total_s".to_string()))
        .collect()
}

/// One row of the statistics CSV (see [`stats_header`]).
pub fn stats_row(frame: usize, time_s: f64, particles: usize, s: &StepStats) -> Vec<String> {
    let mut row = vec![
        frame.to_string(),
        format!("{time_s:.6}"),
        particles.to_string(),
        format!("{:.6}", s.max_density_ratio),
        format!("{:.6}", s.mean_density_ratio),
        s.iterations.to_string(),
        s.unconverged_substeps.to_string(),
        s.neighbour_pairs.to_string(),
        format!("{:.6e}", s.kinetic_energy),
    ];
    row.extend(s.phases.iter().map(|(_, secs)| format!("{secs:.6e}")));
    row.push(format!("{:.6e}", s.total_s()));
    row
}

/// Creates `dir` (and its parents) or names why it cannot be an output directory.
pub fn create_output_dir(dir: &Path) -> Result<(), SimError> {
    if dir.exists() && !dir.is_dir() {
        return Err(SimError::output(
            dir,
            "exists and is not a directory (give a directory for the output)",
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| SimError::output(dir, e))
}

/// Loads the scene at `path` and runs it: a progress bar, `frame_NNNNN.vtk` every
/// `output.every_frames` frames (when `output.vtk`; with `passive_NNNNN.vtk` beside it when
/// the solver advects passive points, e.g. a granular scene's upscaling), and `stats.csv` (one row per frame,
/// [`stats_header`]) in `opts.out_dir`. A blow-up stops the run with an error naming the
/// frame, step and particle; the statistics up to it are kept.
pub fn run_scene(path: &Path, opts: &SceneRunOptions) -> Result<(), SimError> {
    let scene = Scene::load(path)?;
    let scene = if opts.quick { scene.quick() } else { scene };
    match scene.precision {
        Precision::F32 => run_scene_in::<f32>(&scene, opts),
        Precision::F64 => run_scene_in::<f64>(&scene, opts),
    }
}

fn run_scene_in<R: Real>(scene: &Scene, opts: &SceneRunOptions) -> Result<(), SimError> {
    if opts.max_frames == Some(0) {
        return Err(SimError::Invalid(
            "--frames 0: nothing to run (give at least 1 frame)".into(),
        ));
    }
    create_output_dir(&opts.out_dir)?;
    let t0 = Instant::now();
    let mut sim = SceneSim::<R>::new(scene)?;
    let frames = opts
        .max_frames
        .map_or(scene.frame_count(), |m| m.min(scene.frame_count()));
    eprintln!(
        "{}: {} particles, solver {}, boundary {}, {} frames of {} s, set-up {:.2} s -> {}",
        scene.name,
        sim.state.len(),
        sim.solver().name(),
        sim.solver().boundary().name(),
        frames,
        scene.frame_dt_s,
        t0.elapsed().as_secs_f64(),
        opts.out_dir.display()
    );
    if let Some(c) = &sim.calibration {
        eprintln!(
            "initial masses calibrated: max rho/rho0 {:.4} -> {:.6} in {} iterations, {} particles lowered (smallest mass x{:.3}), total mass x{:.4}",
            c.max_density_ratio_before,
            c.max_density_ratio_after,
            c.iterations,
            c.lowered,
            c.min_mass_ratio,
            c.total_mass_ratio
        );
    }
    let stats_path = opts.out_dir.join("stats.csv");
    let csv_err = |e: csv::Error| SimError::output(&stats_path, e);
    let mut csv = csv::Writer::from_path(&stats_path).map_err(csv_err)?;
    csv.write_record(stats_header(sim.solver().phase_names()))
        .map_err(csv_err)?;
    let every = scene.output.every_frames.max(1);
    let vtk_path = |f: usize| opts.out_dir.join(format!("frame_{f:05}.vtk"));
    let passive_path = |f: usize| opts.out_dir.join(format!("passive_{f:05}.vtk"));
    if scene.output.vtk {
        sim.write_vtk(&vtk_path(0))?;
        sim.write_passive_vtk(&passive_path(0))?;
    }
    let bar = if opts.progress {
        ProgressBar::new(frames as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} frames ETA {eta} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut result = Ok(());
    for _ in 0..frames {
        match sim.advance() {
            Ok(stats) => {
                csv.write_record(stats_row(sim.frame, sim.time_s, sim.state.len(), &stats))
                    .map_err(csv_err)?;
                bar.set_message(format!(
                    "rho_max/rho0 {:.4}, {:.1} ms/frame",
                    stats.max_density_ratio,
                    stats.total_s() * 1e3
                ));
                if scene.output.vtk && sim.frame % every == 0 {
                    sim.write_vtk(&vtk_path(sim.frame))?;
                    sim.write_passive_vtk(&passive_path(sim.frame))?;
                }
                bar.inc(1);
            }
            Err(e) => {
                result = Err(e);
                break;
            }
        }
    }
    bar.finish();
    csv.flush().map_err(|e| SimError::output(&stats_path, e))?;
    eprintln!(
        "{}: {} frames in {:.1} s; statistics in {}",
        scene.name,
        sim.frame,
        t0.elapsed().as_secs_f64(),
        stats_path.display()
    );
    result
}
