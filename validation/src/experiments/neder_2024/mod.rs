//! Neder (2024), granular matter with SPH (crate `iisph-granular`: IISPH after Ihmsen et al.
//! 2014, Drucker–Prager friction after Alduán & Otaduy 2011): the angle of repose, the
//! collapse of granular columns against Lube et al. (2005, planar; 2004, axisymmetric), the
//! convergence of the IISPH pressure solve the thesis builds on, and the cost of a granular
//! step. Shared here: scene variants edited from the shipped
//! files ([`scene_edit`]) and a scene run that keeps a blow-up as a result ([`run_scene`]).

pub mod granular_column_collapse;
pub mod granular_column_collapse_axisymmetric;
pub mod granular_performance;
pub mod granular_repose;
pub mod iisph_convergence;
pub mod scene_edit;

use anyhow::Result;
use sph_core::{Real, Vec3};
use sph_scene::Scene;

use crate::sim::scene_sim;
use crate::{Check, Context};

/// One frame of a run.
#[derive(Debug, Clone, Copy)]
pub struct FrameRow {
    /// Time at the end of the frame (s).
    pub t_s: f64,
    /// Kinetic energy (J).
    pub kinetic_energy_j: f64,
    /// Pressure iterations over the frame's substeps.
    pub iterations: usize,
    /// Substeps of the frame.
    pub substeps: usize,
    /// Substeps that hit the iteration cap.
    pub unconverged_substeps: usize,
    /// `max ρ/ρ0` at the end of the frame.
    pub max_density_ratio: f64,
    /// The solver's stopping-rule density error in the frame's last iteration.
    pub last_solve_error: f64,
    /// Wall-clock time of the frame's phases (s).
    pub wall_s: f64,
    /// Friction-stress iterations over the frame's substeps (granular; 0 for water).
    pub friction_iterations: usize,
    /// Substeps whose friction solve hit its cap (granular).
    pub unconverged_friction_substeps: usize,
    /// Residual of the frame's last friction solve (mean unyielded strain per step).
    pub last_friction_residual: f64,
    /// Largest particle speed at the end of the frame (m/s): of the particles in the
    /// [`RestCriterion`]'s region if there is one.
    pub max_speed_m_s: f64,
}

/// When a run counts as at rest and stops before the scene's duration (which is then a cap):
/// the largest speed of the particles in `region` has stayed below `speed_m_s` for `hold_s`
/// (checked at the end of each frame).
#[derive(Debug, Clone, Copy)]
pub struct RestCriterion {
    /// Speed bound (m/s).
    pub speed_m_s: f64,
    /// How long every particle must stay below it (s).
    pub hold_s: f64,
    /// The particles that count: those inside this box (m); `None` = all.
    pub region: Option<sph_core::Aabb<f64>>,
}

/// A scene run to its end (or to a blow-up).
#[derive(Debug, Clone)]
pub struct SceneRun {
    /// Particles simulated.
    pub particles: usize,
    /// Per-frame statistics.
    pub frames: Vec<FrameRow>,
    /// Positions (m) at the requested frames, `(frame, positions)`; frame 0 = initial.
    pub snapshots: Vec<(usize, Vec<Vec3<f64>>)>,
    /// Positions at the end of the run.
    pub final_positions: Vec<Vec3<f64>>,
    /// Potential energy of the initial state above the tank floor (J).
    pub initial_potential_energy_j: f64,
    /// The solver's error that ended the run early, if any.
    pub blow_up: Option<String>,
    /// With a [`RestCriterion`]: the time (s) from which the largest speed stayed below its
    /// bound for its hold time (the run stopped then); `None` if that did not happen before
    /// the scene's duration.
    pub rest_from_s: Option<f64>,
}

fn to_f64<R: Real>(p: &[Vec3<R>]) -> Vec<Vec3<f64>> {
    p.iter()
        .map(|v| Vec3::new(v.x.as_f64(), v.y.as_f64(), v.z.as_f64()))
        .collect()
}

fn max_speed<R: Real>(x: &[Vec3<R>], v: &[Vec3<R>], region: Option<sph_core::Aabb<f64>>) -> f64 {
    let inside = |p: &Vec3<R>| {
        region
            .is_none_or(|b| (0..3).all(|a| p[a].as_f64() >= b.min[a] && p[a].as_f64() <= b.max[a]))
    };
    x.iter()
        .zip(v)
        .filter(|(p, _)| inside(p))
        .map(|(_, v)| v.norm().as_f64())
        .fold(0.0, f64::max)
}

fn run_in<R: Real>(
    ctx: &Context,
    scene: &Scene,
    snapshot_frames: &[usize],
    rest: Option<RestCriterion>,
) -> Result<SceneRun> {
    let mut sim = scene_sim::<R>(scene)?;
    let frames = scene.frame_count();
    let initial_potential_energy_j =
        crate::experiments::macklin_muller_2013::fluid_runs::potential_energy_j(&sim);
    let mut run = SceneRun {
        particles: sim.state.len(),
        frames: Vec::with_capacity(frames),
        snapshots: Vec::new(),
        final_positions: Vec::new(),
        initial_potential_energy_j,
        blow_up: None,
        rest_from_s: None,
    };
    let mut below_since: Option<f64> = None;
    if snapshot_frames.contains(&0) {
        run.snapshots.push((0, to_f64(&sim.state.positions)));
    }
    for _ in 0..frames {
        match sim.advance() {
            Ok(s) => run.frames.push(FrameRow {
                t_s: sim.time_s,
                kinetic_energy_j: s.kinetic_energy,
                iterations: s.iterations,
                substeps: s.substeps,
                unconverged_substeps: s.unconverged_substeps,
                max_density_ratio: s.max_density_ratio,
                last_solve_error: s.last_solve_error,
                friction_iterations: s.friction_iterations,
                unconverged_friction_substeps: s.unconverged_friction_substeps,
                last_friction_residual: s.last_friction_residual,
                wall_s: s.total_s(),
                max_speed_m_s: max_speed(
                    &sim.state.positions,
                    &sim.state.velocities,
                    rest.and_then(|c| c.region),
                ),
            }),
            Err(e) => {
                run.blow_up = Some(format!("{e:#}"));
                break;
            }
        }
        if snapshot_frames.contains(&sim.frame) {
            run.snapshots
                .push((sim.frame, to_f64(&sim.state.positions)));
        }
        ctx.progress.inc(1);
        if let (Some(c), Some(f)) = (rest, run.frames.last()) {
            // The frame's start time: the speeds of the previous frame's end held since then.
            let t_start = f.t_s - scene.frame_dt_s;
            if f.max_speed_m_s < c.speed_m_s {
                let since = *below_since.get_or_insert(t_start);
                if f.t_s - since >= c.hold_s - 1e-9 {
                    run.rest_from_s = Some(since);
                    ctx.progress.inc((frames - sim.frame) as u64);
                    break;
                }
            } else {
                below_since = None;
            }
        }
    }
    run.final_positions = to_f64(&sim.state.positions);
    Ok(run)
}

/// Runs `scene` to its end in its precision, keeping the positions at `snapshot_frames`. A
/// solver error during a frame ends the run and is kept in [`SceneRun::blow_up`]; set-up
/// errors (the scene, the solver factory) are returned.
pub fn run_scene(ctx: &Context, scene: &Scene, snapshot_frames: &[usize]) -> Result<SceneRun> {
    sph_sim::with_precision!(scene.precision, R => run_in::<R>(ctx, scene, snapshot_frames, None))
}

/// Runs `scene` until it is at rest by `rest` ([`SceneRun::rest_from_s`]) or to its end (its
/// duration is the cap), as [`run_scene`] otherwise.
pub fn run_scene_until_rest(ctx: &Context, scene: &Scene, rest: RestCriterion) -> Result<SceneRun> {
    sph_sim::with_precision!(scene.precision, R => run_in::<R>(ctx, scene, &[], Some(rest)))
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
