//! `granular-repose-thesis`: the angle of repose of the fixed-base heaps of André Neder,
//! *Real-time Simulation of Granular Matter using Smoothed Particle Hydrodynamics*, Master's
//! thesis (M.Sc. Computervisualistik), Universität Koblenz, January 2024, §5.7: the thesis's
//! Drucker–Prager granular IISPH (crate `iisph-granular`) replayed against the slope its
//! yield cone predicts for a surface layer at rest in simple shear, `tan β = α/√2`
//! ([`iisph_granular::ConeMatch::predicted_repose_angle_deg`]), i.e. `β = θ` under
//! `cone_match = "simple-shear"` (`α = √2 tan θ`) and `β = atan(sin θ)` under
//! `"plane-strain"` (`α = √2 sin θ`): the same cones as the elastic–plastic model's poured
//! heaps of `granular-repose` (Bui et al. 2008).
//!
//! **Formation** (the shipped scenes `scenes/granular_repose_thesis_{20,30,40}.toml`): a
//! planar block 0.8 m wide on a raised base of the same width in a 0.03 m slab between walls;
//! the block fails and its excess flows off the base's edges, the toes pinned there (the
//! fixed-base method). θ = 0 runs in the 20° scene and drains off the base.
//!
//! **Rest and measure** as in `granular-repose` ([`crate::helpers::repose`]): granular codes'
//! rest criterion on the grains above the base (θ = 0: every grain, the speeds only), the
//! scene's duration a cap; the planar band fit 20–80 % of the heap above the base's top,
//! between its edges.
//!
//! **Cases** ([`plan::plan`]), full mode only (5 mm; quick mode runs none, CI's budget): the
//! three heaps under each match, θ = 0, a repeat with the block shifted by half a spacing
//! (`thesis/repeat/…`) and the 30° heap in a slab twice as deep (`thesis/wide/…`).
//!
//! **Checks** ([`checks`]), per heap: no solver error; at rest before the cap; formed by flow
//! (the apex below the block's top) and covering the base; `|measured − predicted| ≤`
//! [`TOLERANCE_QUICK_DEG`](crate::helpers::repose::TOLERANCE_QUICK_DEG) (the band the replay was documented with); the angle increases
//! with θ under each match. θ = 0: at rest, drained off the base and flat in the troughs.
//! Metrics: the friction solve over the last second (whether a heap's creep is the solver's),
//! the repeat's and the deeper slab's differences. The heaps creep and do not reach rest:
//! documented deviations (`reference-data/deviations.toml`).

pub mod checks;
pub mod plan;

use anyhow::Result;
use iisph_granular::ConeMatch;

use self::checks::{check_flat, check_heap, check_run, pair_metrics, rest_criterion, Base};
use self::plan::{plan, scene_for, Plan};
use crate::helpers::repose::{
    check_order, csv_row, final_profile, is_sweep, plot_repose, run_plans, write_repose_csv,
    HeapRun, Measured, ReposeFigures, STEEPEST_RUN_M,
};
use crate::helpers::Marker;
use crate::{Context, Experiment, Mode, Outcome};

/// The experiment.
pub struct GranularReposeThesis;

impl Experiment for GranularReposeThesis {
    fn id(&self) -> &'static str {
        "granular-repose-thesis"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["iisph-granular", "granular-measure"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &[
            "granular_repose_thesis_20",
            "granular_repose_thesis_30",
            "granular_repose_thesis_40",
        ]
    }

    fn source(&self) -> &'static str {
        "Neder (2024) granular IISPH, section 5.7: fixed-base heaps against the cone's repose slope tan(beta) = alpha/sqrt(2), beta = theta (simple-shear match) or atan(sin theta) (plane-strain match); full mode only"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        if ctx.mode == Mode::Quick {
            let mut out = Outcome::new();
            out.note("full mode only (`--full`): the fixed-base heaps at 5 mm cost more than the quick suite's budget; quick mode runs no heap and has no check");
            return Ok(out);
        }
        let runs = run_all(ctx)?;
        let mut out = judge(ctx, &runs)?;
        out.note(format!(
            "fixed-base heaps of the thesis model (granular IISPH): a planar block 0.8 m wide on a raised base of the same width in a 0.03 m slab between walls, its excess flowing off the base's edges; rest, 99th-percentile and deep (2 spacings) speeds of the grains above the base < 0.05 sqrt(g s) for 0.5 s and the angle moving < 0.3 deg over 1 s; angle = mean of both flanks' least-squares slopes between 20 % and 80 % of the heap height above the base, steepest over {STEEPEST_RUN_M} m; spacing 5 mm (full)"
        ));
        Ok(out)
    }
}

/// Every planned case run until at rest or to its cap.
fn run_all(ctx: &mut Context) -> Result<Vec<(Plan, HeapRun)>> {
    run_plans::<_, Base>(ctx, plan(ctx.mode), scene_for, rest_criterion)
}

/// The checks of every run, the order, the pairs' metrics, and the outputs.
fn judge(ctx: &mut Context, runs: &[(Plan, HeapRun)]) -> Result<Outcome> {
    let mut out = Outcome::new();
    let mut rows = Vec::new();
    let mut measured: Vec<(ConeMatch, f64, Measured)> = Vec::new();
    let mut by_tag: Vec<(String, Measured)> = Vec::new();
    let mut profiles = Vec::new();
    for (p, case) in runs {
        let Some(base) = check_run(&mut out, case)? else {
            continue;
        };
        if let (true, Some(profile)) = (is_sweep(&p.tag), final_profile(case)) {
            profiles.push((p.tag.clone(), profile));
        }
        if p.theta_deg == 0.0 {
            check_flat(&mut out, case, base)?;
            continue;
        }
        if let Some(m) = check_heap(&mut out, case, p.cone, base) {
            let predicted = p.cone.predicted_repose_angle_deg(p.theta_deg);
            rows.push(csv_row(case, p.cone.name(), predicted, &m));
            by_tag.push((p.tag.clone(), m));
            if is_sweep(&p.tag) {
                measured.push((p.cone, p.theta_deg, m));
            }
        }
    }
    check_order(&mut out, "thesis/", &measured);
    pair_metrics(&mut out, &by_tag);
    write_repose_csv(ctx, rows)?;
    let figures = ReposeFigures {
        model: "thesis IISPH",
        marker: Marker::Ring,
        heaps: "fixed-base heaps",
        profiles_title: "Surface profiles at the end of each run (fixed-base heaps: the base between its edges, the troughs beside it)",
    };
    plot_repose(ctx, &figures, &measured, &profiles)?;
    Ok(out)
}
