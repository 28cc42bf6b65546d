//! `particles repose DIR`: the angle of repose of the last (or a given) frame of a scene
//! run, measured with [`granular_measure::angle_of_repose`], so that any granular
//! scene's output can be measured, not only the experiment's.

use std::path::PathBuf;

use anyhow::{Context, Result};
use granular_measure::{angle_of_repose, ReposeOptions};
use sph_sim::RunDir;

use crate::render::scene_of_run;

/// The shape of the heap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Shape {
    /// A planar (2.5D) heap, its profile taken along x.
    Planar,
    /// An axisymmetric pile around the particles' centroid.
    Conical,
}

/// Arguments of `particles repose`.
#[derive(Debug, clap::Args)]
pub struct ReposeArgs {
    /// The run's output directory.
    dir: PathBuf,
    /// The frame to measure [default: the last `frame_*.vtk` in DIR].
    #[arg(long, value_name = "FILE")]
    frame: Option<PathBuf>,
    /// Planar heap (profile along x) or conical pile.
    #[arg(long, value_enum, default_value = "planar")]
    shape: Shape,
    /// The scene file [default: the one recorded by `run` in DIR].
    #[arg(long, value_name = "PATH")]
    scene: Option<PathBuf>,
    /// With --scene: apply its `[quick]` overrides.
    #[arg(long)]
    quick: bool,
}

/// Measures the frame and prints the angle, the flanks and the resolution. The floor is the
/// scene tank's bottom (or y = 0 without a tank); the bins are one particle spacing wide.
pub fn run(a: &ReposeArgs) -> Result<()> {
    let run = RunDir::new(&a.dir);
    let scene = scene_of_run(&run, a.scene.as_deref(), a.quick)?;
    let file = match &a.frame {
        Some(f) => f.clone(),
        None => run
            .frames()?
            .pop()
            .map(|(_, p)| p)
            .with_context(|| format!("{}: no frame_*.vtk to measure", a.dir.display()))?,
    };
    let positions = sph_sim::vtk::read_positions(&file)?;
    let s = scene.particle_spacing;
    let floor = scene.tank.map_or(0.0, |t| t.min.y);
    let opts = match a.shape {
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
