//! `pbf-stability` (Macklin & Müller 2013, §8): in the bunny drop, "PCISPH is not stable with
//! less than 10 sub-steps per frame (Δt = 0.0016 s). In contrast our algorithm is stable with
//! a single step (Δt = 0.016 s)."
//!
//! Runs: PBF with 1 step per 16 ms frame (10 iterations, the bunny drop's), and PCISPH with
//! 1, 2, 5 and 10 sub-steps (4 iterations each, the paper's PCISPH setting; negative
//! pressures clamped, the `Pcisph` default). A run is *bounded* when it completes without a
//! blow-up ([`pbf::PbfError::BlowUp`] or a density above twice the rest density) and its
//! kinetic energy never exceeds the initial potential energy (energy conservation). PCISPH
//! runs are *stable* when bounded and their compression `max ρ/ρ0 − 1`, averaged over the
//! frames after the bunny hits the pool, is at most [`STABLE_COMPRESSION`] (the "stated
//! density error" of the issue); PBF's compression at one step per frame is reported, the
//! paper claims only that it stays stable.

use anyhow::Result;
use sph_scene::SolverKind;

use crate::experiments::fluid_runs::{run_fluid, FluidRun};
use crate::helpers::{plot_xy, write_csv_rows, Legend, PlotSpec, Series};
use crate::sim::shipped_scene;
use crate::{fmt_num, Check, Context, Experiment, Outcome};

/// The experiment.
pub struct PbfStability;

/// Largest time-averaged compression of a stable PCISPH run (the "stated density error"):
/// ten times PCISPH's own 1 % target (Solenthaler & Pajarola 2009), a compression that
/// visibly changes the volume of the liquid; this project's bound, the paper states none.
pub const STABLE_COMPRESSION: f64 = 0.10;
/// Frames after this time are averaged (s): after the bunny's impact.
const FROM_S: f64 = 0.4;
/// PCISPH sub-steps per frame tried.
const PCISPH_SUBSTEPS: [usize; 4] = [1, 2, 5, 10];

fn compression(run: &FluidRun) -> f64 {
    if run.frames.iter().any(|s| s.t_s >= FROM_S) {
        run.mean_from(FROM_S, |s| s.max_density_ratio - 1.0)
    } else {
        f64::INFINITY
    }
}

fn stable(run: &FluidRun) -> bool {
    run.bounded() && compression(run) <= STABLE_COMPRESSION
}

impl Experiment for PbfStability {
    fn id(&self) -> &'static str {
        "pbf-stability"
    }

    fn source(&self) -> &'static str {
        "Macklin & Müller (2013) Position Based Fluids, §8: PBF stable at one step per 16 ms frame, PCISPH needs 10 sub-steps"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let scene = shipped_scene("bunny_drop", ctx.mode)?;
        ctx.progress
            .set_length(((1 + PCISPH_SUBSTEPS.len()) * scene.frame_count()) as u64);
        let mut runs = vec![run_fluid(ctx, &scene, SolverKind::Pbf, 1, 10)?];
        for k in PCISPH_SUBSTEPS {
            runs.push(run_fluid(ctx, &scene, SolverKind::Pcisph, k, 4)?);
        }
        let mut out = Outcome::new();
        out.metric("particles", runs[0].particles as f64);
        let mut rows = Vec::new();
        for run in &runs {
            let c = compression(run);
            let frames_done = run.frames.len();
            out.metric(
                format!("{}/frames_completed", run.label),
                frames_done as f64,
            );
            out.metric(format!("{}/mean_compression_after_impact", run.label), c);
            out.metric(
                format!("{}/peak_density_ratio", run.label),
                run.peak_density_ratio(),
            );
            let what = match &run.blow_up {
                Some(e) => format!("blew up after {frames_done} frames: {e}"),
                None => format!(
                    "completed; mean compression after impact {}, peak kinetic energy {} J (initial potential energy {} J)",
                    fmt_num(c),
                    fmt_num(run.peak_kinetic_energy()),
                    fmt_num(run.initial_potential_energy_j)
                ),
            };
            out.note(format!("{}: {what}", run.label));
            rows.push(vec![
                run.label.clone(),
                frames_done.to_string(),
                run.blow_up.is_some().to_string(),
                format!("{:.6e}", run.peak_kinetic_energy()),
                format!("{:.6e}", run.initial_potential_energy_j),
                run.bounded().to_string(),
                format!("{c:.6}"),
                format!("{:.6}", run.peak_density_ratio()),
                stable(run).to_string(),
            ]);
        }
        write_csv_rows(
            &ctx.path("stability.csv"),
            &[
                "run",
                "frames_completed",
                "blew_up",
                "peak_kinetic_energy_j",
                "initial_potential_energy_j",
                "bounded",
                "mean_compression_after_impact",
                "peak_density_ratio",
                "stable",
            ],
            rows,
        )?;
        ctx.add_file(
            "stability.csv",
            "one row per run: frames completed, blow-up, compression, verdict",
        );
        out.check(Check::equals(
            "PBF 1 step/frame bounded",
            runs[0].bounded() as u8 as f64,
            1.0,
            "§8 of the paper (\"stable with a single step\"); bounded = no blow-up and kinetic energy <= initial potential energy (energy conservation)",
        ));
        let origin = "§8 of the paper; stable = bounded and mean compression after impact <= 10 % (this project's bound)";
        for run in &runs[1..] {
            let expect_stable = run.label.starts_with("PCISPH 10×");
            out.check(Check::equals(
                format!("{} stable", run.label),
                stable(run) as u8 as f64,
                expect_stable as u8 as f64,
                origin,
            ));
        }
        let series = runs
            .iter()
            .enumerate()
            .map(|(i, run)| {
                Series::line(
                    run.label.clone(),
                    run.frames
                        .iter()
                        .map(|s| (s.t_s, s.max_density_ratio))
                        .collect(),
                    i,
                )
            })
            .collect();
        let spec = PlotSpec {
            legend: Legend::UpperRight,
            log_y: true,
            series,
            ..PlotSpec::new(
                "Bunny drop: max density per frame",
                "t (s)",
                "max density / rest density",
            )
        };
        plot_xy(&ctx.path("stability.png"), &spec)?;
        ctx.add_plot("stability.png", "max density per frame for PBF at one step per frame and PCISPH at 1–10 sub-steps (a curve that stops blew up)");
        Ok(out)
    }
}
