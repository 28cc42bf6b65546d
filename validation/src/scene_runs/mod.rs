//! The experiments' scene runs, shared by every paper folder: the one loader of shipped
//! scenes and the edits of their variants ([`load`]), the simulation and frame loop of a
//! scene ([`frames`]), the energy measures ([`energy`]), a scene run to its end or to rest
//! that keeps a blow-up as a result ([`run_scene`], [`run_scene_until_rest`],
//! [`solver_error_check`]), a fluid run with a solver set ([`fluid`]) and finished runs kept
//! on disk so that a long experiment resumes ([`store`]).

pub mod energy;
pub mod fluid;
pub mod frames;
pub mod load;
pub mod store;

use anyhow::Result;
use sph_core::{Real, Vec3};
use sph_scene::Scene;
use sph_sim::observe::{positions_f64, Recorder, RestObserver, Snapshots};
use sph_sim::{FrameObserver, FrameRecord};

use crate::{Check, Context};

pub use energy::potential_energy_j;
pub use fluid::{run_fluid, FluidRun, DIVERGED_DENSITY_RATIO};
pub use frames::{advance_frames, run_frames, scene_sim, volume_map_cache, SceneSim};
pub use load::{iisph_solver, set_block_and_tank, shipped_scene};
pub use sph_sim::observe::{RestCriterion, RestSettings, RestVerdict};
pub use store::RunStore;

/// A scene run to its end (or to a blow-up); its serde form is what [`store`] keeps.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SceneRun {
    /// Particles simulated.
    pub particles: usize,
    /// The record of each completed frame.
    pub frames: Vec<FrameRecord>,
    /// With a [`RestCriterion`]: its verdict at the end of the run (every quantity judged
    /// with its bound and by how much it misses).
    pub rest_verdict: Option<RestVerdict>,
    /// Positions (m) at the requested frames, `(frame, positions)`, in the scene's initial
    /// order (element `k` is the particle with id `k`); frame 0 = initial.
    pub snapshots: Vec<(usize, Vec<Vec3<f64>>)>,
    /// The solver's fields kept at the requested frames ([`run_scene_until_rest_keeping`]):
    /// `(frame, name, values per particle, values)`, in the scene's initial order.
    pub snapshot_fields: Vec<(usize, String, usize, Vec<f64>)>,
    /// Positions at the end of the run.
    pub final_positions: Vec<Vec3<f64>>,
    /// For each of [`SceneRun::final_positions`], the particle's index in the scene's
    /// initial order (the solver reorders particles by cell).
    pub final_ids: Vec<u32>,
    /// Potential energy of the initial state above the tank floor (J).
    pub initial_potential_energy_j: f64,
    /// The solver's blow-up that ended the run early, if any.
    pub blow_up: Option<String>,
    /// With a [`RestCriterion`]: the time (s) from which the heap was at rest by it (the run
    /// stopped once it was); `None` if that did not happen before the scene's duration.
    pub rest_from_s: Option<f64>,
    /// Whether the scene's pour (if any) placed all its grains.
    pub pour_finished: bool,
}

fn run_in<R: Real>(
    ctx: &Context,
    scene: &Scene,
    snapshot_frames: &[usize],
    fields: &[&str],
    rest: Option<RestCriterion>,
) -> Result<SceneRun> {
    let mut sim = scene_sim::<R>(scene)?;
    let initial_potential_energy_j = potential_energy_j(&sim);
    let mut recorder = Recorder::default();
    let mut snapshots = Snapshots::at(snapshot_frames).with_fields(fields);
    let mut rest = rest.map(RestObserver::new);
    let mut observers: Vec<&mut dyn FrameObserver<R>> = vec![&mut recorder, &mut snapshots];
    if let Some(r) = rest.as_mut() {
        observers.push(r);
    }
    let outcome = run_frames(ctx, &mut sim, scene.frame_count(), &mut observers)?;
    Ok(SceneRun {
        particles: sim.state.len(),
        frames: recorder.records,
        rest_verdict: rest.as_ref().and_then(|r| r.verdict),
        snapshots: snapshots.taken,
        snapshot_fields: snapshots.taken_fields,
        final_positions: positions_f64(&sim.state.positions),
        final_ids: sim.ids.clone(),
        initial_potential_energy_j,
        blow_up: outcome.divergence().map(|d| d.to_string()),
        rest_from_s: rest.and_then(|r| r.rest_from_s),
        pour_finished: sim.pour_finished(),
    })
}

/// Runs `scene` to its end in its precision, keeping the positions at `snapshot_frames`. A
/// solver error during a frame ends the run and is kept in [`SceneRun::blow_up`]; set-up
/// errors (the scene, the solver factory) are returned.
pub fn run_scene(ctx: &Context, scene: &Scene, snapshot_frames: &[usize]) -> Result<SceneRun> {
    sph_sim::with_precision!(scene.precision, R => run_in::<R>(ctx, scene, snapshot_frames, &[], None))
}

/// Runs `scene` until it is at rest by `rest` ([`SceneRun::rest_from_s`]) or to its end (its
/// duration is the cap), as [`run_scene`] otherwise.
pub fn run_scene_until_rest(ctx: &Context, scene: &Scene, rest: RestCriterion) -> Result<SceneRun> {
    run_scene_until_rest_keeping(ctx, scene, &[], &[], rest)
}

/// [`run_scene_until_rest`], keeping the positions at `snapshot_frames` as [`run_scene`]
/// does, and the solver's fields named in `fields` ([`SceneRun::snapshot_fields`]).
pub fn run_scene_until_rest_keeping(
    ctx: &Context,
    scene: &Scene,
    snapshot_frames: &[usize],
    fields: &[&str],
    rest: RestCriterion,
) -> Result<SceneRun> {
    sph_sim::with_precision!(scene.precision, R => run_in::<R>(ctx, scene, snapshot_frames, fields, Some(rest)))
}

/// The failing check of a run that a solver error (a blow-up) ended early: a blow-up is an
/// error, not a result.
pub fn solver_error_check(tag: &str, error: &str) -> Check {
    Check::equals(
        format!("{tag}/completed without a solver error"),
        0.0,
        1.0,
        format!("a blow-up is an error, not a result: {error}"),
    )
}
