//! `validation repose DIR`: the angle of repose of the last (or a given) frame of a scene
//! run, measured with [`iisph_granular::measure::angle_of_repose`], so that any granular
//! scene's output can be measured, not only the experiment's.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use iisph_granular::measure::{angle_of_repose, ReposeOptions};

use crate::render::{frame_files, read_frame_positions, run_scene_of};

/// The shape argument of the command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Shape {
    /// A planar (2.5D) heap, its profile taken along x.
    Planar,
    /// An axisymmetric pile around the particles' centroid.
    Conical,
}

/// Measures frame `frame` (default: the last `frame_*.vtk`) of the run in `dir` and prints
/// the angle, the flanks and the resolution. The floor is the scene tank's bottom (or
/// y = 0 without a tank); the bins are one particle spacing wide.
pub fn measure_run(
    dir: &Path,
    frame: Option<PathBuf>,
    shape: Shape,
    scene: Option<&Path>,
    quick: bool,
) -> Result<()> {
    let scene = run_scene_of(dir, scene, quick)?;
    let file = match frame {
        Some(f) => f,
        None => frame_files(dir)?
            .pop()
            .with_context(|| format!("{}: no frame_*.vtk to measure", dir.display()))?,
    };
    let positions = read_frame_positions(&file)?;
    let s = scene.particle_spacing;
    let floor = scene.tank.map_or(0.0, |t| t.min.y);
    let opts = match shape {
        Shape::Planar => ReposeOptions::planar(floor, s),
        Shape::Conical => ReposeOptions::conical(floor, s),
    }
    .with_spacing(s);
    let m = angle_of_repose(&positions, &opts)
        .with_context(|| format!("measuring {}", file.display()))?;
    println!(
        "{}: angle of repose {:.2}° (resolution ±{:.2}°), pile height {:.4} m, {} particles",
        file.display(),
        m.angle_deg,
        m.resolution_deg.unwrap_or(f64::NAN),
        m.pile_height_m,
        positions.len()
    );
    for f in &m.flanks {
        println!(
            "  flank {}: {:.2}° over {:.4} m ({} surface points, rms residual {:.4} m)",
            if f.side < 0 { "left " } else { "right" },
            f.angle_deg,
            f.run_m,
            f.points,
            f.rms_residual_m
        );
    }
    Ok(())
}
