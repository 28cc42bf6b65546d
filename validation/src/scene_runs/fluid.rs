//! A fluid scene run through the frame loop recording every frame (the PBF/PCISPH
//! experiments), which keeps a blow-up as a result instead of an error.
//!
//! A run also stops as diverged when a frame ends with `max ρ/ρ0 >` [`DIVERGED_DENSITY_RATIO`]:
//! the solver reports no error then (its state is finite and inside the tank), but a liquid
//! compressed to twice its rest density is no longer a simulation of water, and such clumped
//! states have hundreds of neighbours per particle, which makes every further step slow.

use anyhow::Result;
use sph_core::Real;
use sph_scene::{Scene, SolverKind};
use sph_sim::observe::{DensityLimit, Recorder};
use sph_sim::FrameRecord;

use super::{potential_energy_j, run_frames, scene_sim};
use crate::Context;

/// `max ρ/ρ0` above which a run counts as diverged (twice the rest density: 100 %
/// compression of a liquid whose solvers aim at 0.1–1 %).
pub const DIVERGED_DENSITY_RATIO: f64 = 2.0;

/// A run: the frames done, and the blow-up that ended it early, if any.
#[derive(Debug, Clone)]
pub struct FluidRun {
    /// Solver label, e.g. `"PBF 4x10"`.
    pub label: String,
    /// Particles simulated.
    pub particles: usize,
    /// The record of each completed frame.
    pub frames: Vec<FrameRecord>,
    /// Potential energy of the initial state above the tank floor, `Σ m_i |g| (y_i − y_floor)`
    /// (J): the most kinetic energy a scene starting at rest can ever have.
    pub initial_potential_energy_j: f64,
    /// Why the run stopped early: the solver's divergence report (`SolverError::BlowUp`), or a
    /// density above [`DIVERGED_DENSITY_RATIO`].
    pub blow_up: Option<String>,
}

impl FluidRun {
    /// Mean over the completed frames from `from_s` on of `f`.
    pub fn mean_from(&self, from_s: f64, f: impl Fn(&FrameRecord) -> f64) -> f64 {
        let v: Vec<f64> = self
            .frames
            .iter()
            .filter(|s| s.time_s >= from_s)
            .map(f)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    }
    /// Largest kinetic energy over the completed frames (J).
    pub fn peak_kinetic_energy(&self) -> f64 {
        self.frames
            .iter()
            .map(|s| s.kinetic_energy_j)
            .fold(f64::NAN, f64::max)
    }
    /// Bounded: no blow-up or divergence, and the kinetic energy never above the initial
    /// potential energy (energy conservation: a stable solver can only lose energy from a
    /// state at rest).
    pub fn bounded(&self) -> bool {
        self.blow_up.is_none() && self.peak_kinetic_energy() <= self.initial_potential_energy_j
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
    let mut sim = scene_sim::<R>(scene)?;
    let initial_potential_energy_j = potential_energy_j(&sim);
    let mut recorder = Recorder::default();
    let mut limit = DensityLimit {
        limit: DIVERGED_DENSITY_RATIO,
    };
    let frames = scene.frame_count();
    let outcome = run_frames(ctx, &mut sim, frames, &mut [&mut recorder, &mut limit])?;
    Ok(FluidRun {
        label,
        initial_potential_energy_j,
        particles: sim.state.len(),
        frames: recorder.records,
        blow_up: outcome.divergence().map(|d| d.to_string()),
    })
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
    scene.solver = scene.solver.with_kind(kind);
    scene.solver.common_mut().substeps = substeps;
    scene.solver.set_iterations(iterations);
    let name = kind.label();
    let walls = match scene.boundary.model {
        sph_scene::BoundaryModel::VolumeMap => "volume maps",
        sph_scene::BoundaryModel::Collision => "collision walls",
        sph_scene::BoundaryModel::Particles => "boundary particles",
    };
    let label = format!("{name} {substeps}×{iterations}, {walls}");
    sph_sim::with_precision!(scene.precision, R => run_in::<R>(ctx, &scene, label))
}
