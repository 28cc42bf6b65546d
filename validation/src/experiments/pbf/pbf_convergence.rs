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
//! For comparison (no check), the same sweep from the same state with SPlisHSPlasH's form of
//! the constraint: unilateral `C_i = max(ρ_i/ρ0 − 1, 0)`, `ε = 10⁻⁶ m⁻²`, no `s_corr`
//! ([`pbf::PbfParams::clamp_negative_constraint`]), the form of the accuracy-matched
//! side-by-side in the `pbf` crate documentation.

use anyhow::Result;
use pbf::{ParticleSet, Pbf};
use sph_core::Real;
use sph_scene::{Precision, Scene, SolverSpec};

use crate::helpers::{plot_xy, write_csv_rows, Legend, PlotSpec, Series, SeriesStyle};
use crate::sim::{pbf_params, shipped_scene, SceneSim};
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

/// SPlisHSPlasH's CFM relaxation `ε` (m⁻², its `TimeStepPBF`), for the comparison series.
const SPLISHSPLASH_EPSILON: f64 = 1e-6;

/// One row of the sweep: iterations, largest compression `max ρ/ρ0 − 1`, average
/// compression `mean max(ρ/ρ0 − 1, 0)`; the same two for SPlisHSPlasH's form.
type Row = (usize, f64, f64, f64, f64);

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

fn sweep<R: Real>(ctx: &Context, scene: &Scene) -> Result<(Vec<Row>, usize)> {
    let mut sim = SceneSim::<R>::new(scene)?;
    let frames = (T_FIGURE_S / scene.frame_dt_s).round() as usize;
    ctx.progress
        .set_length((frames + 2 * ITERATIONS.len()) as u64);
    for _ in 0..frames {
        sim.advance()?;
        ctx.progress.inc(1);
    }
    let SolverSpec::Pbf(spec) = &scene.solver else {
        anyhow::bail!(
            "{}: the convergence sweep needs a PBF scene, not kind = \"{}\"",
            scene.source.display(),
            scene.solver.kind_name()
        );
    };
    let base = pbf_params::<R>(scene, spec)?;
    let mut rows = Vec::new();
    for k in ITERATIONS {
        let mut p = base.clone();
        p.common.dt = base.substep_dt();
        p.common.substeps = 1;
        p.solver_iterations = k;
        p.common.reorder_every = 0;
        let (max, avg) = one_step(scene, p.clone(), &sim.state)?;
        ctx.progress.inc(1);
        p.clamp_negative_constraint = true;
        p.cfm_epsilon = R::of_f64(SPLISHSPLASH_EPSILON);
        p.scorr_k = R::zero();
        let (max_u, avg_u) = one_step(scene, p, &sim.state)?;
        ctx.progress.inc(1);
        rows.push((k, max, avg, max_u, avg_u));
    }
    Ok((rows, sim.state.len()))
}

impl Experiment for PbfConvergence {
    fn id(&self) -> &'static str {
        "pbf-convergence"
    }

    fn source(&self) -> &'static str {
        "Macklin & Müller (2013) Position Based Fluids, Fig. 6: convergence over iterations at t = 1.0 s, dam break"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let scene = shipped_scene("dam_break", ctx.mode)?;
        let (rows, particles) = match scene.precision {
            Precision::F32 => sweep::<f32>(ctx, &scene)?,
            Precision::F64 => sweep::<f64>(ctx, &scene)?,
        };
        write_csv_rows(
            &ctx.path("convergence.csv"),
            &[
                "iterations",
                "max_compression",
                "average_compression",
                "unilateral_max_compression",
                "unilateral_average_compression",
            ],
            rows.iter().map(|&(k, c, m, cu, mu)| {
                vec![
                    k.to_string(),
                    format!("{c:.6e}"),
                    format!("{m:.6e}"),
                    format!("{cu:.6e}"),
                    format!("{mu:.6e}"),
                ]
            }),
        )?;
        ctx.add_file(
            "convergence.csv",
            "density error after one step against the iteration count, at t = 1.0 s",
        );
        let mut out = Outcome::new();
        out.metric("particles", particles as f64);
        for &(k, c, m, cu, mu) in &rows {
            out.metric(format!("max_compression_{k}_iterations"), c);
            out.metric(format!("average_compression_{k}_iterations"), m);
            out.metric(format!("unilateral_max_compression_{k}_iterations"), cu);
            out.metric(format!("unilateral_average_compression_{k}_iterations"), mu);
        }
        if let (Some(first), Some(last)) = (rows.first(), rows.last()) {
            out.note(format!(
                "Average compression after {} → {} iterations: paper's form {:.3e} → {:.3e}; \
                 SPlisHSPlasH's form (unilateral C, ε = 1e-6 m⁻², no s_corr; no check) \
                 {:.3e} → {:.3e}.",
                first.0, last.0, first.2, last.2, first.4, last.4
            ));
        }
        // Fig. 6 shows the error falling with every added iteration.
        let increases = rows
            .windows(2)
            .filter(|w| w[1].2 > w[0].2 * (1.0 + 1e-3))
            .count();
        out.check(Check::equals(
            "average compression non-increasing with iterations (count of increases)",
            increases as f64,
            0.0,
            "Fig. 6 of the paper: monotone convergence (0.1 % slack for single-precision round-off)",
        ));
        let last = rows.last().map_or(f64::NAN, |r| r.2);
        out.check(Check::less_than(
            "average compression after 40 iterations",
            last,
            TARGET_COMPRESSION,
            "PCISPH's 1 % density-error target (Solenthaler & Pajarola 2009), which §8 of the PBF paper says PBF matches",
        ));
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
                    rows.iter().map(|&(k, .., mu)| (k as f64, mu)).collect(),
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
                "Jacobi iterations in the step",
                "density error",
            )
        };
        plot_xy(&ctx.path("convergence.png"), &spec)?;
        ctx.add_plot(
            "convergence.png",
            "density error after one step against the number of iterations (Fig. 6)",
        );
        Ok(out)
    }
}
