//! `pbf-convergence` (Macklin & Müller 2013, Fig. 6): density error against the number of
//! Jacobi iterations at `t = 1.0 s` in the dam break.
//!
//! The dam break (`scenes/dam_break.toml`, quick overrides in quick mode) is run with its own
//! settings to `t = 1.0 s`. From that state, one step of Algorithm 1 of the scene's length
//! `Δt = frame_dt / substeps` is taken with `k = 1 … 40` iterations (each from a copy of the
//! same state), and the density error after the solve is recorded from the particles'
//! densities at their final positions: the average compression
//! `(1/N) Σ_i max(ρ_i/ρ0 − 1, 0)` (the error measure of SPlisHSPlasH's PBF and of PCISPH's
//! target; particles below the rest density at the free surface do not count) and the
//! largest one, `max_i ρ_i/ρ0 − 1`.
//!
//! The baseline is the error before any iteration: the same step's advection alone
//! (`x* = x + Δt (v + Δt g)` followed by the boundary's contact response, lines 1–3 of
//! Algorithm 1), its density summed directly (Poly6 over a fresh neighbour search, plus
//! `ρ0 Ψ` for a volume-map boundary). The checks require the iterations to remove a stated
//! share of it, for the average and for the largest compression.
//!
//! For comparison (no check), the same sweep from the same state with SPlisHSPlasH's form of
//! the constraint: unilateral `C_i = max(ρ_i/ρ0 − 1, 0)`, `ε = 10⁻⁶ m⁻²`, no `s_corr`
//! ([`pbf::PbfParams::clamp_negative_constraint`]), the form of the accuracy-matched
//! side-by-side in the `pbf` crate documentation.

use anyhow::Result;
use pbf::{ParticleSet, Pbf};
use sph_core::Real;
use sph_scene::{Scene, SolverParams};

use crate::helpers::{plot_xy, write_csv_rows, Legend, PlotSpec, Series, SeriesStyle};
use crate::scene_runs::{advance_frames, scene_sim, shipped_scene};
use crate::{Check, Context, Experiment, Outcome};

/// The experiment.
pub struct PbfConvergence;

/// Time of the paper's figure (s).
const T_FIGURE_S: f64 = 1.0;
/// Iteration counts tried.
const ITERATIONS: [usize; 11] = [1, 2, 3, 4, 6, 8, 10, 15, 20, 30, 40];
/// Density-error target of PCISPH (Solenthaler & Pajarola 2009, §4: "density fluctuations
/// ... below 1 %"), which the PBF paper says its solver matches (§8, Fig. 4).
const TARGET_COMPRESSION: f64 = 0.01;

/// Share of the one-iteration error that 40 iterations must remove at least: half. A
/// converging Jacobi solve reduces the error geometrically with the iteration count (Fig. 6
/// of the paper falls by about an order of magnitude from 1 to 40 iterations); a solve that
/// stalls after the first iteration — a halved `λ`, a wrong gradient — does not halve it.
const REDUCTION_1_TO_40: f64 = 0.5;

/// SPlisHSPlasH's CFM relaxation `ε` (m⁻², its `TimeStepPBF`), for the comparison series.
const SPLISHSPLASH_EPSILON: f64 = 1e-6;

/// One row of the sweep: iterations, largest compression `max ρ/ρ0 − 1`, average
/// compression `mean max(ρ/ρ0 − 1, 0)`; the same two for SPlisHSPlasH's form; the same two
/// for the paper's form without the artificial pressure `s_corr` (a diagnostic).
type Row = (usize, f64, f64, f64, f64, f64, f64);

/// Largest and average compression after one step of `p` from `state`.
fn one_step<R: Real>(
    scene: &Scene,
    p: pbf::PbfParams<R>,
    state: &ParticleSet<R>,
) -> Result<(f64, f64)> {
    let mut solver = Pbf::new(p, scene.build_solids::<R>()?)?;
    let mut state = state.clone();
    let stats = solver.step(&mut state)?;
    let rho0 = solver.params().common.rest_density.as_f64();
    let avg = state
        .densities
        .iter()
        .map(|d| (d.as_f64() / rho0 - 1.0).max(0.0))
        .sum::<f64>()
        / state.len().max(1) as f64;
    Ok((stats.max_density_ratio - 1.0, avg))
}

/// Largest and average compression of the advection alone (no constraint iteration) of one
/// step of `p` from `state`: the 0-iteration baseline.
fn advected<R: Real>(
    scene: &Scene,
    p: &pbf::PbfParams<R>,
    state: &ParticleSet<R>,
) -> Result<(f64, f64)> {
    use sph_kernels::{Kernel, KernelKind};
    let solver = Pbf::new(p.clone(), scene.build_solids::<R>()?)?;
    let boundary = solver.boundary();
    let dt = p.common.dt;
    let g = p.common.gravity;
    let predicted: Vec<_> = state
        .positions
        .iter()
        .zip(&state.velocities)
        .map(|(x, v)| boundary.project(*x + (*v + g * dt) * dt))
        .collect();
    let h = p.common.support_radius;
    let w = KernelKind::Poly6.build(h)?;
    let mut search = p.common.neighbour_method.build::<R>();
    let mut lists = neighbour_search::NeighbourLists::new();
    search.search(&predicted, h, &mut lists)?;
    let rho0 = p.common.rest_density.as_f64();
    let (mut max, mut sum) = (f64::NEG_INFINITY, 0.0);
    for (i, xi) in predicted.iter().enumerate() {
        let mut rho = state.masses[i].as_f64() * w.value(R::zero()).as_f64();
        for &j in lists.neighbours(i) {
            let j = j as usize;
            if j != i {
                let r = (*xi - predicted[j]).norm();
                rho += state.masses[j].as_f64() * w.value(r).as_f64();
            }
        }
        rho += rho0 * boundary.sample(xi).volume.as_f64();
        let c = rho / rho0 - 1.0;
        max = max.max(c);
        sum += c.max(0.0);
    }
    Ok((max, sum / predicted.len().max(1) as f64))
}

fn sweep<R: Real>(ctx: &Context, scene: &Scene) -> Result<(Vec<Row>, usize)> {
    let mut sim = scene_sim::<R>(scene)?;
    let frames = (T_FIGURE_S / scene.frame_dt_s).round() as usize;
    ctx.progress
        .set_length((frames + 2 * ITERATIONS.len()) as u64);
    ctx.progress
        .set_message("frames to t = 1 s, then one-step solves");
    advance_frames(ctx, &mut sim, frames, &mut [])?;
    let SolverParams::Pbf(base) = scene.solver_params::<R>()? else {
        anyhow::bail!(
            "{}: the convergence sweep needs a PBF scene, not kind = \"{}\"",
            scene.source.display(),
            scene.solver.kind_name()
        );
    };
    let mut rows = Vec::new();
    {
        let mut p = base.clone();
        p.common.dt = base.substep_dt();
        p.common.substeps = 1;
        let (max, avg) = advected(scene, &p, &sim.state)?;
        rows.push((0, max, avg, max, avg, max, avg));
    }
    for k in ITERATIONS {
        let mut p = base.clone();
        p.common.dt = base.substep_dt();
        p.common.substeps = 1;
        p.solver_iterations = k;
        p.common.reorder_every = 0;
        let (max, avg) = one_step(scene, p.clone(), &sim.state)?;
        ctx.progress.inc(1);
        let mut no_scorr = p.clone();
        no_scorr.scorr_k = R::zero();
        let (max_ns, avg_ns) = one_step(scene, no_scorr, &sim.state)?;
        p.clamp_negative_constraint = true;
        p.cfm_epsilon = R::of_f64(SPLISHSPLASH_EPSILON);
        p.scorr_k = R::zero();
        let (max_u, avg_u) = one_step(scene, p, &sim.state)?;
        ctx.progress.inc(1);
        rows.push((k, max, avg, max_u, avg_u, max_ns, avg_ns));
    }
    Ok((rows, sim.state.len()))
}

fn write_convergence(ctx: &mut Context, rows: &[Row]) -> Result<()> {
    write_csv_rows(
        &ctx.path("convergence.csv"),
        &[
            "iterations",
            "max_compression",
            "average_compression",
            "unilateral_max_compression",
            "unilateral_average_compression",
            "no_scorr_max_compression",
            "no_scorr_average_compression",
        ],
        rows.iter().map(|&(k, c, m, cu, mu, cn, mn)| {
            vec![
                k.to_string(),
                format!("{c:.6e}"),
                format!("{m:.6e}"),
                format!("{cu:.6e}"),
                format!("{mu:.6e}"),
                format!("{cn:.6e}"),
                format!("{mn:.6e}"),
            ]
        }),
    )?;
    ctx.add_file(
        "convergence.csv",
        "density error after one step against the iteration count, at t = 1.0 s",
    );
    Ok(())
}

/// The errors per iteration count (metrics) and the note comparing the two forms.
fn convergence_metrics(out: &mut Outcome, rows: &[Row]) {
    for &(k, c, m, cu, mu, cn, mn) in &rows[1..] {
        out.metric(format!("no_scorr_max_compression_{k}_iterations"), cn);
        out.metric(format!("no_scorr_average_compression_{k}_iterations"), mn);
        out.metric(format!("max_compression_{k}_iterations"), c);
        out.metric(format!("average_compression_{k}_iterations"), m);
        out.metric(format!("unilateral_max_compression_{k}_iterations"), cu);
        out.metric(format!("unilateral_average_compression_{k}_iterations"), mu);
    }
    if let (Some(first), Some(last)) = (rows.get(1), rows.last()) {
        out.note(format!(
            "Average compression after {} → {} iterations: paper's form {:.3e} → {:.3e}; \
             SPlisHSPlasH's form (unilateral C, ε = 1e-6 m⁻², no s_corr; no check) \
             {:.3e} → {:.3e}.",
            first.0, last.0, first.2, last.2, first.4, last.4
        ));
    }
}

/// Monotone convergence, the first iteration's effect, 1 → 40 reduction, the 1 % target.
fn check_convergence(out: &mut Outcome, rows: &[Row]) {
    // Fig. 6 shows the error falling with every added iteration (from the first on).
    let increases = rows[1..]
        .windows(2)
        .filter(|w| w[1].2 > w[0].2 * (1.0 + 1e-3))
        .count();
    out.check(Check::equals(
        "average compression non-increasing with iterations (count of increases)",
        increases as f64,
        0.0,
        "Fig. 6 of the paper: monotone convergence (0.1 % slack for single-precision round-off)",
    ));
    let at = |k: usize| rows.iter().find(|r| r.0 == k).copied();
    if let (Some(r0), Some(r1), Some(r40)) = (at(0), at(1), at(40)) {
        for (what, e0, e1, e40) in [
            ("average", r0.2, r1.2, r40.2),
            ("largest", r0.1, r1.1, r40.1),
        ] {
            out.metric(format!("{what}_compression_0_iterations"), e0);
            out.check(Check::less_than(
                format!("{what} compression: 1 iteration over the advection baseline"),
                e1 / e0,
                1.0,
                "Algorithm 1: each Jacobi iteration moves the particles towards C_i = 0, so the first one lowers the error the advection left (a sign error or a dropped lambda would not)",
            ));
            out.check(Check::at_most(
                format!("{what} compression: 40 iterations over 1 iteration"),
                e40 / e1,
                REDUCTION_1_TO_40,
                "Fig. 6 of the paper: the error keeps falling with the iterations, about tenfold from 1 to 40; at least half (a solve that stalls after one iteration, e.g. a halved lambda, stays above)",
            ));
        }
    }
    let last = rows.last().map_or(f64::NAN, |r| r.2);
    out.check(Check::less_than(
        "average compression after 40 iterations",
        last,
        TARGET_COMPRESSION,
        "PCISPH's 1 % density-error target (Solenthaler & Pajarola 2009), which §8 of the PBF paper says PBF matches",
    ));
}

fn plot_convergence(ctx: &mut Context, rows: &[Row], particles: usize) -> Result<()> {
    let spec = PlotSpec {
        legend: Legend::LowerLeft,
        log_y: true,
        series: vec![
            Series::styled(
                "largest compression max ρ/ρ0 − 1",
                rows.iter().map(|&(k, c, ..)| (k as f64, c)).collect(),
                SeriesStyle::LineMarkers(crate::helpers::Marker::Circle),
                0,
            ),
            Series::styled(
                "average compression mean max(ρ/ρ0 − 1, 0)",
                rows.iter().map(|&(k, _, m, ..)| (k as f64, m)).collect(),
                SeriesStyle::LineMarkers(crate::helpers::Marker::Triangle),
                1,
            ),
            Series::styled(
                "average compression, SPlisHSPlasH's unilateral form",
                rows.iter()
                    .map(|&(k, _, _, _, mu, ..)| (k as f64, mu))
                    .collect(),
                SeriesStyle::LineMarkers(crate::helpers::Marker::Cross),
                2,
            ),
            Series::styled(
                "1 % (PCISPH target)",
                vec![(0.0, TARGET_COMPRESSION), (41.0, TARGET_COMPRESSION)],
                SeriesStyle::Dashed,
                7,
            ),
        ],
        ..PlotSpec::new(
            format!("PBF convergence at t = 1.0 s, dam break ({particles} particles)"),
            "Jacobi iterations in the step (0 = advection only)",
            "density error",
        )
    };
    plot_xy(&ctx.path("convergence.png"), &spec)?;
    ctx.add_plot(
        "convergence.png",
        "density error after one step against the number of iterations (Fig. 6)",
    );
    Ok(())
}

impl Experiment for PbfConvergence {
    fn id(&self) -> &'static str {
        "pbf-convergence"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["pbf"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &["dam_break"]
    }

    fn source(&self) -> &'static str {
        "Macklin & Müller (2013) Position Based Fluids, Fig. 6: convergence over iterations at t = 1.0 s, dam break"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let scene = shipped_scene("dam_break", ctx.mode)?;
        let (rows, particles) =
            sph_sim::with_precision!(scene.precision, R => sweep::<R>(ctx, &scene)?);
        write_convergence(ctx, &rows)?;
        let mut out = Outcome::new();
        out.metric("particles", particles as f64);
        convergence_metrics(&mut out, &rows);
        check_convergence(&mut out, &rows);
        plot_convergence(ctx, &rows, particles)?;
        Ok(out)
    }
}
