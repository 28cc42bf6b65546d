//! `pbf-performance` (Macklin & Müller 2013, Tables 1 and 2): time per step of the three
//! scenes with the paper's steps per frame and iterations, and the per-phase breakdown of a
//! frame, beside the paper's GTX 680 figures (`reference-data/pbf-performance/macklin_muller_2013_performance.csv`).
//!
//! Each scene (quick overrides in quick mode, paper scale in full mode) runs
//! [`WARM_UP_FRAMES`] frames, then [`MEASURED_FRAMES`] timed frames from which the time per
//! step (frame time / steps per frame) and the phase percentages are taken. This is a CPU
//! (rayon, this machine's cores) against the paper's GPU: the table is a record, not a race.
//!
//! What is checked is what a performance bug would change within one run: the constraint
//! solve's time per particle-iteration is the same in the three scenes within
//! [`SOLVE_COST_SPREAD`] (the solve costs `O(N × iterations × neighbours)` with the same
//! kernel, support and spacing ratio everywhere, so a scene-dependent slowdown — a lost
//! reordering, a neighbourhood blown up by clumping — shows as a spread).
//!
//! The neighbour search (build + query) of the dam break, in thread-seconds per particle per
//! step (wall time × threads, which can only overstate a parallel search's single-thread
//! cost), is recorded beside the CompactNSearch anchor of
//! `reference-data/neighbour-search/compactnsearch_anchor.csv` (SPlisHSPlasH's search on the
//! same dam-break spacing and support, one thread, timed once). It is a metric, not a check:
//! a timing against a figure taken outside the run measures the machine as much as the code.

use anyhow::Result;
use sph_core::Real;
use sph_scene::Scene;
use sph_sim::observe::Recorder;

use crate::helpers::stats::median;
use crate::helpers::{load_reference_csv, write_csv_rows, ReferenceTable};
use crate::scene_runs::{advance_frames, scene_sim, shipped_scene};
use crate::{fmt_num, Check, Context, Experiment, Outcome};

/// The experiment.
pub struct PbfPerformance;

/// Frames run before timing (the particles are reordered by cell and the buffers grown).
pub const WARM_UP_FRAMES: usize = 3;
/// Frames timed.
pub const MEASURED_FRAMES: usize = 10;
/// The scenes of Table 1, by file stem.
const SCENES: [&str; 3] = ["armadillo_splash", "dam_break", "bunny_drop"];
/// Largest ratio of the constraint solve's time per particle-iteration between two scenes:
/// the scenes differ in their share of free-surface particles (fewer neighbours) and in the
/// cache behaviour of their neighbourhoods, not in the work per neighbour; 1.5 leaves room
/// for those (measured 1.1–1.2 on this machine) and is missed by a twofold scene-dependent
/// slowdown.
pub const SOLVE_COST_SPREAD: f64 = 1.5;
/// Phase names of Table 2, in its order.
const PHASES: [&str; 5] = [
    "integrate",
    "create_hash_grid",
    "detect_neighbours",
    "constraint_solve",
    "velocity_update",
];

/// Timings of one scene: particles, steps/frame, iterations/step, ms per step, phase %.
struct Timing {
    particles: usize,
    steps: usize,
    iterations: usize,
    ms_per_step: f64,
    percent: [f64; 5],
    threads: usize,
    /// Constraint-solve wall time per particle per iteration (µs).
    solve_us_per_particle_iteration: f64,
    /// Neighbour search (build + query) wall time per particle per step (µs): the median
    /// over the measured frames (see [`median`]).
    search_us_per_particle: f64,
}

fn time_scene<R: Real>(ctx: &Context, scene: &Scene) -> Result<Timing> {
    let mut sim = scene_sim::<R>(scene)?;
    advance_frames(ctx, &mut sim, WARM_UP_FRAMES, &mut [])?;
    let mut measured = Recorder::default();
    advance_frames(ctx, &mut sim, MEASURED_FRAMES, &mut [&mut measured])?;
    let mut phases = [0.0f64; 5];
    let mut total = 0.0;
    let mut iterations_done = 0usize;
    let mut search_per_frame = Vec::with_capacity(MEASURED_FRAMES);
    for s in &measured.records {
        search_per_frame.push(s.phase_s("create_hash_grid") + s.phase_s("detect_neighbours"));
        iterations_done += s.iterations;
        let p = [
            s.phase_s("integrate"),
            s.phase_s("create_hash_grid"),
            s.phase_s("detect_neighbours"),
            s.phase_s("constraint_solve"),
            s.phase_s("velocity_update") + s.phase_s("reorder"),
        ];
        for (a, b) in phases.iter_mut().zip(p) {
            *a += b;
        }
        total += s.total_s;
    }
    let steps = scene.solver.substeps();
    let n = sim.state.len() as f64;
    Ok(Timing {
        solve_us_per_particle_iteration: 1e6 * phases[3] / (n * iterations_done.max(1) as f64),
        // The median, not the mean, of the search's cost per frame: wall-clock noise on a
        // shared machine is one-sided (a preempted thread only adds time), and one preempted
        // frame of ten moved the mean by up to 20 % on this machine (2026-11-25: 0.85-0.89 of
        // the anchor in most quick runs, 1.01 and 1.20 in two); the phase table keeps the means.
        search_us_per_particle: 1e6 * median(&search_per_frame) / (n * steps as f64),
        particles: sim.state.len(),
        steps,
        iterations: scene.solver.iterations(),
        ms_per_step: 1e3 * total / (MEASURED_FRAMES * steps) as f64,
        percent: phases.map(|p| 100.0 * p / total),
        threads: rayon::current_num_threads(),
    })
}

/// Table 1 of the paper (particles, steps, iterations, time per step, phase percentages).
fn load_paper(ctx: &Context) -> Result<ReferenceTable> {
    load_reference_csv(
        ctx,
        "pbf-performance/macklin_muller_2013_performance.csv",
        &[
            "scene",
            "particles",
            "steps_per_frame",
            "iterations_per_step",
            "time_per_step_ms",
        ],
    )
}

/// CompactNSearch's time per particle per step (µs, one thread).
fn load_anchor_us(ctx: &Context) -> Result<f64> {
    let anchor = load_reference_csv(
        ctx,
        "neighbour-search/compactnsearch_anchor.csv",
        &["method", "us_per_particle", "threads"],
    )?;
    let anchor_row = anchor.find(&[("method", "compactnsearch")])?;
    anchor.number(anchor_row, "us_per_particle")
}

/// One scene's metrics; for the dam break, the neighbour search against the anchor.
fn scene_metrics(out: &mut Outcome, name: &str, t: &Timing, anchor_us: f64) {
    out.metric(format!("{name}/particles"), t.particles as f64);
    out.metric(format!("{name}/ms_per_step"), t.ms_per_step);
    out.metric(
        format!("{name}/us_per_particle_step"),
        1e3 * t.ms_per_step / t.particles as f64,
    );
    for (p, v) in PHASES.iter().zip(t.percent) {
        out.metric(format!("{name}/{p}_percent"), v);
    }
    // Table 2: the constraint solve is the largest phase in both scenes (a record).
    let largest = t.percent.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    out.metric(
        format!("{name}/constraint_solve_is_largest_phase"),
        (t.percent[3] == largest) as u8 as f64,
    );
    out.metric(
        format!("{name}/solve_us_per_particle_iteration"),
        t.solve_us_per_particle_iteration,
    );
    out.metric(
        format!("{name}/search_us_per_particle_step"),
        t.search_us_per_particle,
    );
    if name == "dam_break" {
        // A record, not a check: the anchor was timed once, on one machine, outside this run,
        // and a timing against it measures the machine and its load as much as the search
        // (0.85-1.20 of the anchor in quick runs here, 1.16 on the CI machine). The search's
        // speed is measured by `cargo bench -p benches --bench neighbour_search` (docs/performance.md).
        let thread_us = t.search_us_per_particle * t.threads as f64;
        out.metric("dam_break/search_thread_us_per_particle_step", thread_us);
        out.metric(
            "dam_break/search_thread_us_over_compactnsearch_anchor",
            thread_us / anchor_us,
        );
        out.note(format!(
            "Dam-break neighbour search: {} thread-µs per particle-step, {}× the CompactNSearch anchor of {} µs (SPlisHSPlasH, one thread, timed once on the maintainers' machine; a record, not a check).",
            fmt_num(thread_us),
            fmt_num(thread_us / anchor_us),
            fmt_num(anchor_us),
        ));
    }
}

/// One scene's row of `performance.md`, the paper's figures in parentheses.
fn markdown_row(name: &str, t: &Timing, paper: &ReferenceTable) -> Result<String> {
    let row = paper.find(&[("scene", name)])?;
    let paper_ms = paper.number(row, "time_per_step_ms")?;
    let paper_n = paper.number(row, "particles")?;
    let paper_pct: Vec<String> = PHASES
        .iter()
        .map(|p| {
            paper
                .number(row, &format!("{p}_percent"))
                .map_or("–".to_string(), fmt_num)
        })
        .collect();
    Ok(format!(
        "| {name} | {} ({}) | {} | {} | {} ({}) | {} | {} |\n",
        t.particles,
        fmt_num(paper_n),
        t.steps,
        t.iterations,
        fmt_num(t.ms_per_step),
        fmt_num(paper_ms),
        fmt_num(1e3 * t.ms_per_step / t.particles as f64),
        t.percent
            .iter()
            .zip(&paper_pct)
            .map(|(v, p)| format!("{:.1} ({p})", v))
            .collect::<Vec<_>>()
            .join(" | "),
    ))
}

/// One scene's row of `performance.csv`.
fn csv_row(name: &str, t: &Timing) -> Vec<String> {
    let mut r = vec![
        name.to_string(),
        t.particles.to_string(),
        t.steps.to_string(),
        t.iterations.to_string(),
        format!("{:.4}", t.ms_per_step),
        t.threads.to_string(),
    ];
    r.extend(t.percent.iter().map(|v| format!("{v:.2}")));
    r
}

fn write_performance_csv(ctx: &mut Context, rows: Vec<Vec<String>>) -> Result<()> {
    let mut header = vec![
        "scene",
        "particles",
        "steps_per_frame",
        "iterations_per_step",
        "ms_per_step",
        "threads",
    ];
    header.extend(PHASES.iter().map(|p| match *p {
        "integrate" => "integrate_percent",
        "create_hash_grid" => "create_hash_grid_percent",
        "detect_neighbours" => "detect_neighbours_percent",
        "constraint_solve" => "constraint_solve_percent",
        _ => "velocity_update_percent",
    }));
    write_csv_rows(&ctx.path("performance.csv"), &header, rows)?;
    ctx.add_file(
        "performance.csv",
        "time per step and phase percentages of each scene (this machine)",
    );
    Ok(())
}

/// The constraint solve's cost per particle-iteration is the same in every scene.
fn check_solve_spread(out: &mut Outcome, solve_costs: &[f64]) {
    let (lo, hi) = solve_costs
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &c| {
            (lo.min(c), hi.max(c))
        });
    out.check(Check::at_most(
        "constraint solve time per particle-iteration, slowest scene over fastest",
        hi / lo,
        SOLVE_COST_SPREAD,
        "the solve costs O(N x iterations x neighbours) with the same kernel, support and spacing ratio in the three scenes; 1.5 allows for free-surface share and cache effects (1.1-1.2 seen), a twofold scene-dependent slowdown misses it",
    ));
}

impl Experiment for PbfPerformance {
    fn id(&self) -> &'static str {
        "pbf-performance"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["pbf", "neighbour-search"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &["armadillo_splash", "dam_break", "bunny_drop"]
    }

    fn source(&self) -> &'static str {
        "Macklin & Müller (2013) Position Based Fluids, Tables 1 and 2: time per step and frame breakdown"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let paper = load_paper(ctx)?;
        ctx.progress
            .set_length((SCENES.len() * (WARM_UP_FRAMES + MEASURED_FRAMES)) as u64);
        ctx.progress.set_message("frames of 3 scenes");
        let anchor_us = load_anchor_us(ctx)?;
        let mut out = Outcome::new();
        let mut rows = Vec::new();
        let mut solve_costs = Vec::new();
        let mut md = String::from(
            "| scene | particles (paper) | steps/frame | iters/step | time/step ms (paper, GTX 680) | µs per particle-step | Integrate % | Create Hash Grid % | Detect Neighbors % | Constraint Solve % | Velocity Update % |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for name in SCENES {
            let scene = shipped_scene(name, ctx.mode)?;
            let t = sph_sim::with_precision!(scene.precision, R => time_scene::<R>(ctx, &scene)?);
            scene_metrics(&mut out, name, &t, anchor_us);
            solve_costs.push(t.solve_us_per_particle_iteration);
            md.push_str(&markdown_row(name, &t, &paper)?);
            rows.push(csv_row(name, &t));
        }
        check_solve_spread(&mut out, &solve_costs);
        write_performance_csv(ctx, rows)?;
        md.push_str(&format!(
            "\nThis machine, {} rayon threads, CPU; in parentheses the paper's GTX 680 figures (Tables 1 and 2). Reorder time is counted in Velocity Update.\n",
            rayon::current_num_threads()
        ));
        std::fs::write(ctx.path("performance.md"), &md)?;
        ctx.add_file(
            "performance.md",
            "Tables 1 and 2 side by side with the paper's figures",
        );
        out.note(md);
        Ok(out)
    }
}
