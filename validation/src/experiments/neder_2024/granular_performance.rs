//! `granular-performance`: time per step and per particle of the IISPH granular solver
//! (Neder 2024) on a 100,000-particle pile, per phase, on 2 threads (and, in full mode, on 1).
//!
//! The pile: the 30° repose scene (`scenes/granular_repose_thesis_30.toml`) without its base (the
//! solid) and with the thesis's cone (`cone_match` plane strain, as when the figures in
//! `docs/performance.md` were taken), with a block of 0.4 × 0.25 × 0.125 m at a spacing of 5 mm (80 × 50 × 25 = 100,000 particles) resting on the
//! floor of a 1.2 m long tank, 1 ms steps, one step per frame. [`WARM_UP_STEPS`] steps are run
//! first (buffers grown, particles reordered by cell), then the measured steps (quick: 5,
//! full: 50). Timings are metrics, not checks: they depend on the machine and its load.
//!
//! The same pile as water (`kind = "iisph"`, every other setting equal) is timed beside it;
//! the ratio of the step times is a metric (the task's target: the granular step within
//! 1.5× of the water step).
//!
//! Checks (things that can fail for real): the steps complete without a solver error and
//! without a step at the iteration cap, the pile has the 100,000 particles the task states, and
//! the solver's phase breakdown accounts for the step (the sum of the phase times is 90–100 %
//! of the wall-clock time of `step`, measured around it: a phase left out of the breakdown
//! would show here).

use anyhow::{anyhow, Result};
use sph_core::Real;
use sph_scene::{Scene, SolverKind};
use sph_sim::observe::{FrameTimer, Recorder};

use crate::helpers::write_csv_rows;
use crate::scene_runs::{advance_frames, scene_sim};
use crate::scene_runs::{set_block_and_tank, shipped_scene, solver_error_check};
use crate::{Check, Context, Experiment, Mode, Outcome};

/// The experiment.
pub struct GranularPerformance;

/// Steps run before timing.
pub const WARM_UP_STEPS: usize = 3;
/// Particles of the pile.
const PARTICLES: usize = 100_000;

fn pile_scene(mode: Mode, measured_steps: usize) -> Result<Scene> {
    let mut scene = shipped_scene("granular_repose_thesis_30", mode)?;
    scene.particle_spacing = 0.005;
    scene.frame_dt_s = 0.001;
    scene.duration_s = 0.001 * (WARM_UP_STEPS + measured_steps) as f64;
    scene.solver.common_mut().substeps = 1;
    scene.output.vtk = false;
    scene.solids.clear();
    if let sph_scene::SolverSpec::Granular(g) = &mut scene.solver {
        g.cone_match = Some(iisph_granular::ConeMatch::PlaneStrain);
    }
    set_block_and_tank(
        &mut scene,
        [0.4, 0.0, 0.0],
        [0.8, 0.25, 0.125],
        [0.0, 0.0, 0.0],
        [1.2, 0.3, 0.125],
    );
    scene.check()?;
    Ok(scene)
}

/// One timed run: per-phase seconds summed over the measured steps, the wall time of
/// each frame ([`FrameTimer`]: the step, its record and the recorder) summed likewise, steps, iterations, unconverged steps.
struct Timed {
    threads: usize,
    particles: usize,
    phases: Vec<(&'static str, f64)>,
    wall_s: f64,
    steps: usize,
    iterations: usize,
    unconverged: usize,
    friction_iterations: usize,
    friction_unconverged: usize,
}

fn time_in<R: Real>(ctx: &Context, scene: &Scene, threads: usize) -> Result<Timed> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow!("thread pool of {threads}: {e}"))?;
    pool.install(|| -> Result<Timed> {
        let mut sim = scene_sim::<R>(scene)?;
        let steps = scene.frame_count();
        let mut t = Timed {
            threads,
            particles: sim.state.len(),
            phases: Vec::new(),
            wall_s: 0.0,
            steps: 0,
            iterations: 0,
            unconverged: 0,
            friction_iterations: 0,
            friction_unconverged: 0,
        };
        let mut recorder = Recorder::default();
        let mut timer = FrameTimer::default();
        advance_frames(ctx, &mut sim, steps, &mut [&mut recorder, &mut timer])?;
        let measured = recorder.records.iter().zip(&timer.frame_s);
        for (s, wall) in measured.skip(WARM_UP_STEPS) {
            if t.phases.is_empty() {
                t.phases = s.phases.iter().map(|(n, _)| (n, 0.0)).collect();
            }
            for (acc, (_, secs)) in t.phases.iter_mut().zip(s.phases.iter()) {
                acc.1 += secs;
            }
            t.wall_s += wall;
            t.steps += s.substeps;
            t.iterations += s.iterations;
            t.unconverged += s.unconverged_substeps;
            t.friction_iterations += s.friction_iterations;
            t.friction_unconverged += s.unconverged_friction_substeps;
        }
        Ok(t)
    })
}

impl Experiment for GranularPerformance {
    fn id(&self) -> &'static str {
        "granular-performance"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["iisph-granular"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &["granular_repose_thesis_30"]
    }

    fn source(&self) -> &'static str {
        "Neder (2024) granular IISPH: cost of a step of a 100k-particle pile, per phase"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let measured = ctx.mode.pick(5, 50);
        let scene = pile_scene(ctx.mode, measured)?;
        // The same pile as water (friction off, every other setting equal): the reference of
        // the granular step's cost.
        let mut water = scene.clone();
        water.solver = scene.solver.with_kind(SolverKind::Iisph);
        let thread_counts: Vec<usize> = ctx.mode.pick(vec![2], vec![1, 2]);
        ctx.progress
            .set_length((2 * thread_counts.len() * scene.frame_count()) as u64);
        let mut out = Outcome::new();
        let mut rows = Vec::new();
        for &threads in &thread_counts {
            let water_ms =
                sph_sim::with_precision!(water.precision, R => time_in::<R>(ctx, &water, threads))
                    .map(|w| {
                        (
                            1e3 * w.wall_s / w.steps.max(1) as f64,
                            w.iterations as f64 / w.steps.max(1) as f64,
                        )
                    });
            let t =
                sph_sim::with_precision!(scene.precision, R => time_in::<R>(ctx, &scene, threads));
            let t = match t {
                Ok(t) => t,
                Err(e) => {
                    out.check(solver_error_check(
                        &format!("threads={threads}"),
                        &format!("{e:#}"),
                    ));
                    continue;
                }
            };
            let tag = format!("threads={}", t.threads);
            let steps = t.steps.max(1) as f64;
            let per_step_ms = 1e3 * t.wall_s / steps;
            let per_particle_ns = 1e9 * t.wall_s / steps / t.particles as f64;
            out.metric(format!("{tag}/ms_per_step"), per_step_ms);
            out.metric(format!("{tag}/ns_per_particle_step"), per_particle_ns);
            out.metric(
                format!("{tag}/iterations_per_step"),
                t.iterations as f64 / steps,
            );
            match water_ms {
                Ok((ms, iterations)) => {
                    out.metric(format!("{tag}/water_ms_per_step"), ms);
                    out.metric(format!("{tag}/water_iterations_per_step"), iterations);
                    out.metric(format!("{tag}/granular_over_water_step"), per_step_ms / ms);
                    out.note(format!(
                        "{threads} threads: the same pile as water takes {ms:.1} ms per step ({iterations:.2} iterations); granular / water = {:.2} (the task's target: at most 1.5)",
                        per_step_ms / ms
                    ));
                }
                Err(e) => out.check(solver_error_check(
                    &format!("water threads={threads}"),
                    &format!("{e:#}"),
                )),
            }
            out.metric(
                format!("{tag}/friction_iterations_per_step"),
                t.friction_iterations as f64 / steps,
            );
            out.metric(
                format!("{tag}/steps_at_the_friction_cap"),
                t.friction_unconverged as f64,
            );
            let phase_sum: f64 = t.phases.iter().map(|p| p.1).sum();
            for (name, secs) in &t.phases {
                out.metric(format!("{tag}/{name}_ms_per_step"), 1e3 * secs / steps);
                rows.push(vec![
                    t.threads.to_string(),
                    name.to_string(),
                    format!("{:.4}", 1e3 * secs / steps),
                    format!("{:.3}", 1e9 * secs / steps / t.particles as f64),
                    format!("{:.1}", 100.0 * secs / phase_sum),
                ]);
            }
            rows.push(vec![
                t.threads.to_string(),
                "step (wall clock)".into(),
                format!("{per_step_ms:.4}"),
                format!("{per_particle_ns:.3}"),
                "100".into(),
            ]);
            out.check(Check::equals(
                format!("{tag}/particles"),
                t.particles as f64,
                PARTICLES as f64,
                "the task: a 100k-particle pile",
            ));
            out.check(Check::equals(
                format!("{tag}/steps at the iteration cap"),
                t.unconverged as f64,
                0.0,
                "a pile at rest needs few iterations; a step at the cap is a solver problem, not a cost",
            ));
            out.check(Check::within(
                format!("{tag}/phase breakdown / wall time of the step"),
                phase_sum / t.wall_s,
                0.9,
                1.0 + 1e-6,
                "definition: the phases must account for the step (10 % allowed for the call and statistics overhead)",
            ));
            out.note(format!(
                "{} threads: {per_step_ms:.1} ms per step, {per_particle_ns:.0} ns per particle and step, {:.2} pressure and {:.2} friction iterations per step ({} particles, {} measured steps)",
                t.threads,
                t.iterations as f64 / steps,
                t.friction_iterations as f64 / steps,
                t.particles,
                t.steps
            ));
        }
        write_csv_rows(
            &ctx.path("phases.csv"),
            &[
                "threads",
                "phase",
                "ms_per_step",
                "ns_per_particle_step",
                "percent_of_phases",
            ],
            rows,
        )?;
        ctx.add_file(
            "phases.csv",
            "time per step and per particle of each phase of the granular step",
        );
        Ok(out)
    }
}
