//! Shared by the PBF/PCISPH experiments: a scene run recording the density and energy of
//! every frame, which keeps a blow-up as a result instead of an error.

use anyhow::Result;
use pbf::PbfError;
use sph_core::Real;
use sph_scene::{Precision, Scene, SolverKind};

use crate::sim::SceneSim;
use crate::Context;

/// One frame's statistics.
#[derive(Debug, Clone, Copy)]
pub struct FrameStats {
    /// Time at the end of the frame (s).
    pub t_s: f64,
    /// `max ρ/ρ0`.
    pub max_density_ratio: f64,
    /// `mean ρ/ρ0`.
    pub mean_density_ratio: f64,
    /// Kinetic energy (J).
    pub kinetic_energy_j: f64,
    /// Wall-clock time of the frame (s).
    pub wall_s: f64,
}

/// A run: the frames done, and the blow-up that ended it early, if any.
#[derive(Debug, Clone)]
pub struct FluidRun {
    /// Solver label, e.g. `"PBF 4x10"`.
    pub label: String,
    /// Particles simulated.
    pub particles: usize,
    /// Statistics of each completed frame.
    pub frames: Vec<FrameStats>,
    /// The solver's divergence report (`PbfError::BlowUp`), when the run stopped early.
    pub blow_up: Option<String>,
}

impl FluidRun {
    /// Mean over the completed frames from `from_s` on of `f`.
    pub fn mean_from(&self, from_s: f64, f: impl Fn(&FrameStats) -> f64) -> f64 {
        let v: Vec<f64> = self
            .frames
            .iter()
            .filter(|s| s.t_s >= from_s)
            .map(f)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    }
    /// Largest `max ρ/ρ0` over the completed frames.
    pub fn peak_density_ratio(&self) -> f64 {
        self.frames
            .iter()
            .map(|s| s.max_density_ratio)
            .fold(f64::NAN, f64::max)
    }
}

fn run_in<R: Real>(ctx: &Context, scene: &Scene, label: String) -> Result<FluidRun> {
    let mut sim = SceneSim::<R>::new(scene)?;
    let frames = sim.frames_total();
    let mut run = FluidRun {
        label,
        particles: sim.state.len(),
        frames: Vec::with_capacity(frames),
        blow_up: None,
    };
    for _ in 0..frames {
        match sim.advance() {
            Ok(s) => run.frames.push(FrameStats {
                t_s: sim.time_s,
                max_density_ratio: s.max_density_ratio,
                mean_density_ratio: s.mean_density_ratio,
                kinetic_energy_j: s.kinetic_energy,
                wall_s: s.total_s(),
            }),
            Err(e) => match e.downcast_ref::<PbfError>() {
                Some(PbfError::BlowUp { .. }) => {
                    run.blow_up = Some(format!("{e:#}"));
                    break;
                }
                _ => return Err(e),
            },
        }
        ctx.progress.inc(1);
    }
    Ok(run)
}

/// Runs `scene` with the given solver, substeps and iterations (everything else as in the
/// scene), in the scene's precision.
pub fn run_fluid(
    ctx: &Context,
    scene: &Scene,
    kind: SolverKind,
    substeps: usize,
    iterations: usize,
) -> Result<FluidRun> {
    let mut scene = scene.clone();
    scene.solver.kind = kind;
    scene.solver.substeps = substeps;
    scene.solver.iterations = iterations;
    let name = match kind {
        SolverKind::Pbf => "PBF",
        SolverKind::Pcisph => "PCISPH",
        #[allow(unreachable_patterns)]
        _ => "solver",
    };
    let label = format!("{name} {substeps}×{iterations}");
    match scene.precision {
        Precision::F32 => run_in::<f32>(ctx, &scene, label),
        Precision::F64 => run_in::<f64>(ctx, &scene, label),
    }
}

/// Frames of a scene's duration.
pub fn frame_count(scene: &Scene) -> usize {
    (scene.duration_s / scene.frame_dt_s - 1e-9).ceil().max(0.0) as usize
}
