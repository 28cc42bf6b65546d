//! Running a scene file: the particle state and the solver a [`Scene`] describes, advanced
//! frame by frame ([`SceneSim`]), and the `cargo xtask run SCENE` driver ([`run_scene`]) that
//! writes ParaView frames and a CSV of per-frame statistics.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{ensure, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use pbf::{FluidSolver, Pbf, PbfParams, Pcisph, PcisphParams, StepStats};
use sph_core::{apply_permutation, ParticleSet, Real, Vec3};
use sph_scene::{PbfSpec, PcisphSpec, Precision, Scene, SolverSpec};

use crate::helpers::vtk::{write_particle_frame, ParticleFrame};
use crate::{workspace_root, Mode};

/// Absolute-value conversion of a scene number to the solver's precision.
fn r<R: Real>(x: f64) -> R {
    R::of_f64(x)
}

fn vec3<R: Real>(v: [f64; 3]) -> Vec3<R> {
    Vec3::new(r(v[0]), r(v[1]), r(v[2]))
}

/// The shipped scene `scenes/<name>.toml`, with its `[quick]` overrides in quick mode.
pub fn shipped_scene(name: &str, mode: Mode) -> Result<Scene> {
    let scene = Scene::load(&workspace_root().join("scenes").join(format!("{name}.toml")))?;
    Ok(mode.pick(scene.quick(), scene))
}

/// The PBF parameters a scene asks for: [`PbfParams::for_spacing`] at the scene's spacing,
/// then the scene's frame length, gravity, and the substeps, iterations and overrides of its
/// `[solver]` settings `s` (`SolverSpec::Pbf(s)`).
pub fn pbf_params<R: Real>(scene: &Scene, s: &PbfSpec) -> Result<PbfParams<R>> {
    let mut p = PbfParams::<R>::for_spacing(r(scene.particle_spacing));
    if let Some(ratio) = s.support_over_spacing {
        p.support_radius = r::<R>(scene.particle_spacing * ratio);
    }
    if let Some(rho0) = s.rest_density {
        p.rest_density = r(rho0);
    }
    let relative_cfm = s.relative_cfm.unwrap_or(pbf::DEFAULT_RELATIVE_CFM);
    let d_ref = p.reference_denominator().with_context(|| {
        format!(
            "{}: no reference denominator for this spacing",
            scene.source.display()
        )
    })?;
    p.cfm_epsilon = d_ref * r::<R>(relative_cfm);
    p.dt = r(scene.frame_dt_s);
    p.gravity = vec3(scene.gravity);
    p.substeps = s.substeps;
    p.solver_iterations = s.iterations;
    if let Some(k) = s.scorr_k {
        p.scorr_k = r(k);
    }
    if let Some(n) = s.scorr_n {
        p.scorr_n = n;
    }
    if let Some(dq) = s.scorr_delta_q {
        p.scorr_delta_q = r(dq);
    }
    if let Some(e) = s.vorticity_epsilon {
        p.vorticity_epsilon = r(e);
    }
    if let Some(c) = s.xsph_c {
        p.xsph_c = r(c);
    }
    if let Some(k) = s.reorder_every {
        p.reorder_every = k;
    }
    if let Some(c) = s.clamp_negative_constraint {
        p.clamp_negative_constraint = c;
    }
    if let Some(t) = s.mean_compression_tolerance {
        p.mean_compression_tolerance = Some(r(t));
        p.min_solver_iterations = s
            .min_iterations
            .unwrap_or(p.min_solver_iterations.min(s.iterations));
    }
    p.validate()
        .with_context(|| format!("{}: solver parameters", scene.source.display()))?;
    Ok(p)
}

/// The PCISPH parameters a scene asks for: [`PcisphParams::for_spacing`] at the scene's
/// spacing, then the scene's frame length, gravity, and the substeps, iterations and
/// overrides of its `[solver]` settings `s` (`SolverSpec::Pcisph(s)`).
pub fn pcisph_params<R: Real>(scene: &Scene, s: &PcisphSpec) -> Result<PcisphParams<R>> {
    let mut p = PcisphParams::<R>::for_spacing(r(scene.particle_spacing));
    if let Some(ratio) = s.support_over_spacing {
        p.support_radius = r::<R>(scene.particle_spacing * ratio);
    }
    if let Some(rho0) = s.rest_density {
        p.rest_density = r(rho0);
    }
    p.dt = r(scene.frame_dt_s);
    p.gravity = vec3(scene.gravity);
    p.substeps = s.substeps;
    p.pressure_iterations = s.iterations;
    if let Some(c) = s.xsph_c {
        p.xsph_c = r(c);
    }
    if let Some(k) = s.reorder_every {
        p.reorder_every = k;
    }
    if let Some(c) = s.clamp_negative_pressure {
        p.clamp_negative_pressure = c;
    }
    if let Some(t) = s.density_error_tolerance {
        p.density_error_tolerance = Some(r(t));
    }
    p.validate()
        .with_context(|| format!("{}: solver parameters", scene.source.display()))?;
    Ok(p)
}

/// A scene being simulated in precision `R`.
pub struct SceneSim<R: Real> {
    /// The scene (with quick-mode overrides applied if asked for).
    pub scene: Scene,
    /// The particles (reordered by cell by the solver from time to time).
    pub state: ParticleSet<R>,
    /// For each particle of `state`, its index in the scene's initial order.
    pub ids: Vec<u32>,
    /// Frames done.
    pub frame: usize,
    /// Simulated time (s).
    pub time_s: f64,
    solver: Box<dyn FluidSolver<R>>,
    id_scratch: Vec<u32>,
}

impl<R: Real> std::fmt::Debug for SceneSim<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneSim")
            .field("scene", &self.scene.name)
            .field("particles", &self.state.len())
            .field("solver", &self.solver.name())
            .field("frame", &self.frame)
            .finish()
    }
}

impl<R: Real> SceneSim<R> {
    /// Samples the scene's fluid, builds its solids and solver. Fails (naming the scene file)
    /// when the scene cannot be built.
    pub fn new(scene: &Scene) -> Result<Self> {
        let file = scene.source.display().to_string();
        let positions = scene.fluid_positions::<R>()?;
        let solids = scene.build_solids::<R>()?;
        let (solver, mass, rho0): (Box<dyn FluidSolver<R>>, R, R) = match &scene.solver {
            SolverSpec::Pbf(s) => {
                let p = pbf_params::<R>(scene, s)?;
                let (m, rho0) = (p.particle_mass(), p.rest_density);
                (
                    Box::new(Pbf::new(p, solids).with_context(|| file.clone())?),
                    m,
                    rho0,
                )
            }
            SolverSpec::Pcisph(s) => {
                let p = pcisph_params::<R>(scene, s)?;
                let (m, rho0) = (p.particle_mass(), p.rest_density);
                (
                    Box::new(Pcisph::new(p, solids).with_context(|| file.clone())?),
                    m,
                    rho0,
                )
            }
        };
        let mut state = ParticleSet::from_positions(positions, mass, rho0);
        Self::set_initial_velocities(scene, &mut state)?;
        Ok(Self::assemble(scene, state, solver))
    }

    fn set_initial_velocities(scene: &Scene, state: &mut ParticleSet<R>) -> Result<()> {
        let velocities = scene.fluid_velocities::<R>()?;
        ensure!(
            velocities.len() == state.len(),
            "{}: {} initial velocities for {} particles",
            scene.source.display(),
            velocities.len(),
            state.len()
        );
        state.velocities = velocities;
        Ok(())
    }

    fn assemble(scene: &Scene, state: ParticleSet<R>, solver: Box<dyn FluidSolver<R>>) -> Self {
        let n = state.len() as u32;
        Self {
            scene: scene.clone(),
            state,
            ids: (0..n).collect(),
            frame: 0,
            time_s: 0.0,
            solver,
            id_scratch: Vec::new(),
        }
    }

    /// The solver.
    pub fn solver(&self) -> &dyn FluidSolver<R> {
        &*self.solver
    }

    /// Advances one frame (`frame_dt`); keeps [`SceneSim::ids`] in step with the solver's
    /// reordering. A blow-up is an error naming the frame and the solver's step and particle.
    pub fn advance(&mut self) -> Result<StepStats> {
        let stats = self.solver.step(&mut self.state).with_context(|| {
            format!(
                "{}: frame {} (t = {:.4} s)",
                self.scene.source.display(),
                self.frame,
                self.time_s
            )
        })?;
        if let Some(perm) = self.solver.last_permutation() {
            apply_permutation(&mut self.ids, perm, &mut self.id_scratch);
        }
        self.frame += 1;
        self.time_s = self.frame as f64 * self.scene.frame_dt_s;
        Ok(stats)
    }

    /// Writes the current frame to `path` (legacy VTK).
    pub fn write_vtk(&self, path: &Path) -> Result<()> {
        write_particle_frame(
            path,
            &ParticleFrame {
                time_s: self.time_s,
                positions: &self.state.positions,
                velocities: &self.state.velocities,
                densities: &self.state.densities,
                ids: &self.ids,
            },
        )
    }
}

/// Options of [`run_scene`].
#[derive(Debug, Clone)]
pub struct SceneRunOptions {
    /// Apply the scene's `[quick]` overrides.
    pub quick: bool,
    /// Output directory (frames and statistics).
    pub out_dir: PathBuf,
    /// Stop after this many frames (default: the scene's duration).
    pub max_frames: Option<usize>,
}

/// Header of the per-frame statistics CSV written by [`run_scene`].
pub const STATS_HEADER: [&str; 16] = [
    "frame",
    "time_s",
    "particles",
    "max_density_ratio",
    "mean_density_ratio",
    "iterations",
    "unconverged_substeps",
    "neighbour_pairs",
    "kinetic_energy_j",
    "integrate_s",
    "create_hash_grid_s",
    "detect_neighbours_s",
    "constraint_solve_s",
    "velocity_update_s",
    "reorder_s",
    "total_s",
];

/// One row of the statistics CSV.
pub fn stats_row(frame: usize, time_s: f64, particles: usize, s: &StepStats) -> Vec<String> {
    vec![
        frame.to_string(),
        format!("{time_s:.6}"),
        particles.to_string(),
        format!("{:.6}", s.max_density_ratio),
        format!("{:.6}", s.mean_density_ratio),
        s.iterations.to_string(),
        s.unconverged_substeps.to_string(),
        s.neighbour_pairs.to_string(),
        format!("{:.6e}", s.kinetic_energy),
        format!("{:.6e}", s.integrate_s),
        format!("{:.6e}", s.create_hash_grid_s),
        format!("{:.6e}", s.detect_neighbours_s),
        format!("{:.6e}", s.constraint_solve_s),
        format!("{:.6e}", s.velocity_update_s),
        format!("{:.6e}", s.reorder_s),
        format!("{:.6e}", s.total_s()),
    ]
}

/// Loads the scene at `path` and runs it (`cargo xtask run SCENE`): a progress bar,
/// `frame_NNNNN.vtk` every `output.every_frames` frames (when `output.vtk`), and `stats.csv`
/// (one row per frame, [`STATS_HEADER`]) in `opts.out_dir`. A blow-up stops the run with an
/// error naming the frame, step and particle; the statistics up to it are kept.
pub fn run_scene(path: &Path, opts: &SceneRunOptions) -> Result<()> {
    let scene = Scene::load(path)?;
    let scene = if opts.quick { scene.quick() } else { scene };
    match scene.precision {
        Precision::F32 => run_scene_in::<f32>(&scene, opts),
        Precision::F64 => run_scene_in::<f64>(&scene, opts),
    }
}

fn run_scene_in<R: Real>(scene: &Scene, opts: &SceneRunOptions) -> Result<()> {
    std::fs::create_dir_all(&opts.out_dir)
        .with_context(|| format!("creating {}", opts.out_dir.display()))?;
    let t0 = Instant::now();
    let mut sim = SceneSim::<R>::new(scene)?;
    let frames = opts
        .max_frames
        .map_or(scene.frame_count(), |m| m.min(scene.frame_count()));
    eprintln!(
        "{}: {} particles, solver {}, {} frames of {} s, set-up {:.2} s -> {}",
        scene.name,
        sim.state.len(),
        sim.solver().name(),
        frames,
        scene.frame_dt_s,
        t0.elapsed().as_secs_f64(),
        opts.out_dir.display()
    );
    let stats_path = opts.out_dir.join("stats.csv");
    let mut csv = csv::Writer::from_path(&stats_path)
        .with_context(|| format!("creating {}", stats_path.display()))?;
    csv.write_record(STATS_HEADER)?;
    let every = scene.output.every_frames.max(1);
    let vtk_path = |f: usize| opts.out_dir.join(format!("frame_{f:05}.vtk"));
    if scene.output.vtk {
        sim.write_vtk(&vtk_path(0))?;
    }
    let bar = ProgressBar::new(frames as u64);
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
                csv.write_record(stats_row(sim.frame, sim.time_s, sim.state.len(), &stats))?;
                bar.set_message(format!(
                    "rho_max/rho0 {:.4}, {:.1} ms/frame",
                    stats.max_density_ratio,
                    stats.total_s() * 1e3
                ));
                if scene.output.vtk && sim.frame % every == 0 {
                    sim.write_vtk(&vtk_path(sim.frame))?;
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
    csv.flush()?;
    eprintln!(
        "{}: {} frames in {:.1} s; statistics in {}",
        scene.name,
        sim.frame,
        t0.elapsed().as_secs_f64(),
        stats_path.display()
    );
    result
}
