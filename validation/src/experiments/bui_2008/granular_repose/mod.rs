//! `granular-repose`: the angle of repose of poured heaps of the elastic–plastic granular
//! model of Bui, H. H., Fukagawa, R., Sako, K. & Ohno, S. (2008), "Lagrangian meshfree
//! particles method (SPH) for large deformation and failure flows of geomaterial using
//! elastic–plastic soil constitutive model", *International Journal for Numerical and
//! Analytical Methods in Geomechanics* 32(12), 1537–1570, doi:10.1002/nag.688 (crate
//! `elastoplastic-granular`), against the slope its yield cone predicts for a flank that
//! forms by flowing: `tan β = 3 α_φ` at zero dilatancy
//! (`ConeMatch::predicted_repose_angle_deg`; `docs/elastoplastic-granular.md`, "For a flank
//! that forms by flowing, the reduction is exact"), i.e. `β = θ` under
//! `cone_match = "simple-shear"` (`α_φ = tan θ/3`) and `β = atan(sin θ)` under
//! `"plane-strain"` (`α_φ = sin θ/3`). The thesis model's fixed-base heaps are the experiment
//! `granular-repose-thesis` (Neder 2024).
//!
//! **Formation** (the shipped scenes `scenes/granular_repose_poured_{20,30,40}.toml`,
//! `docs/elastoplastic-granular.md`): the funnel method (ISO 4324:1977; ASTM C1444-00).
//! Grains are poured a layer at a time (`[pour]`, [`elastoplastic_granular::Pour`]) from a
//! funnel 0.1 m wide at the middle of a period along `x` (periodic along `z` too: plane
//! strain without side walls) that follows the heap's top, onto a no-slip floor, until
//! 0.16 m² of cross-section is poured at 0.012 m² a second; the heap grows by avalanches down
//! its flanks, which stop at its toes: each flank is a flank formed by flowing, the case of
//! the prediction. The period (2.4 m at 20°, 1.6 m at 30° and 40°) keeps the toes clear of
//! the period's ends. Each scene runs with the match set by the experiment; θ = 0 (friction 0,
//! cohesion 0: a granular liquid) runs in the 40° scene and spreads over its floor, with the
//! density re-initialisation on (`ElastoplasticParams::density_reinit_interval_s` at
//! SPHinXsys's 2 ms: with the continuity equation alone it blew up at 26.1 s, a separated
//! grain's density collapsing; the heaps run the model's default, continuity alone).
//!
//! **Rest** ([`granular_measure::rest`] with [`RestSettings::default`](crate::scene_runs::RestSettings::default), judged on the frames
//! after the last layer): a run stops once the 99th-percentile speed of the grains and the
//! fastest of them two spacings below the surface have stayed below `0.05 √(g s)` (`s` the
//! spacing) for 0.5 s and the heap's angle has moved less than 0.3° over the last second
//! (θ = 0, which has no heap: the speeds only); the scene's duration is a cap, and a run that
//! reaches it is not at rest (a failing check with the verdict's margins).
//!
//! **Measure** ([`granular_measure::angle_of_repose`], planar, floor `y = 0`): the
//! free-surface profile (highest grain per bin of one spacing), each flank's least-squares
//! slope between 20 % and 80 % of the heap height, the mean of the two flanks; and the
//! steepest slope over a horizontal run of [`STEEPEST_RUN_M`].
//!
//! **Cases** ([`plan::plan`]). Both modes run the three heaps under each match and θ = 0
//! (quick mode at 20 mm, full mode at 10 mm), and the modulus check: the 30° simple-shear heap
//! at 20 mm with `10 E` and `viscosity_speed_m_s` held at the speed of sound of `E`, against
//! the same heap with `E` (the artificial viscosity scales with its velocity scale, and with
//! the sound speed it would change the heap: `docs/elastoplastic-granular.md`), within
//! [`SPACING_MODULUS_DEG`]; in quick mode the heap with `E` is the sweep's own (the velocity
//! scale defaults to the sound speed). Full mode adds that heap at 20 mm for the spacing
//! check (20 mm against the 10 mm heap, within [`SPACING_MODULUS_DEG`]).
//!
//! **Checks** ([`checks`]), per heap: no solver error; every layer poured; at rest before the
//! cap; the toes clear of the period's ends (a lone heap, not one that met its periodic
//! image); `|measured − predicted| ≤` [`TOLERANCE_QUICK_DEG`] (quick) or
//! [`TOLERANCE_FULL_DEG`] (full); the angle increases with θ under each match run at all
//! three angles. θ = 0: at rest (same criterion), spread over the whole floor and flat. Each
//! heap is one pour, and the pours are bit-reproducible; repeated pours with the rate changed
//! by 0.08 % scatter by about ±1.3° at 30° and 40° at 20 mm (29.92–32.73° at 30°,
//! `docs/elastoplastic-granular.md`), which the band, set by the measure and the flanks, does
//! not carry.
//!
//! The drained heaps (`scenes/granular_repose_{20,30,40}.toml`: a bed drained through a slot
//! in its floor plate) are kept as scenes, out of the experiment: the 40° one stands 5.4° low
//! at 20 mm (a face steeper than the flank at the slot's edge), the 20° one and θ = 0 blow up
//! while draining into the sump (`docs/elastoplastic-granular.md`).

pub mod checks;
pub mod plan;

use anyhow::Result;
use elastoplastic_granular::ConeMatch;

use self::checks::{check_flat, check_heap, check_pairs, check_run, rest_criterion, Floor};
pub use self::checks::{SPACING_MODULUS_DEG, TOLERANCE_FULL_DEG};
use self::plan::{plan, scene_for, Plan};
use crate::helpers::repose::{
    check_order, csv_row, final_profile, is_sweep, plot_repose, run_plans, write_repose_csv,
    HeapRun, Measured, ReposeFigures,
};
pub use crate::helpers::repose::{STEEPEST_RUN_M, TOLERANCE_QUICK_DEG};
use crate::helpers::Marker;
use crate::{Context, Experiment, Mode, Outcome};

/// The experiment.
pub struct GranularRepose;

impl Experiment for GranularRepose {
    fn id(&self) -> &'static str {
        "granular-repose"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["elastoplastic-granular", "granular-measure"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &[
            "granular_repose_poured_20",
            "granular_repose_poured_30",
            "granular_repose_poured_40",
        ]
    }

    fn source(&self) -> &'static str {
        "Bui, Fukagawa, Sako & Ohno (2008) elastic-plastic SPH: poured heaps at rest against the cone's repose slope tan(beta) = 3 alpha_phi, beta = theta (simple-shear match) or atan(sin theta) (plane-strain match)"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let runs = run_all(ctx)?;
        let mut out = judge(ctx, &runs)?;
        out.note(format!(
            "heaps of the elastic-plastic model poured from a funnel 0.1 m wide onto a no-slip floor, periodic (2.4 m at 20 deg, 1.6 m at 30 and 40 deg), 0.16 m2 of cross-section at 0.012 m2/s; rest, judged after the last layer, 99th-percentile and deep (2 spacings) speeds < 0.05 sqrt(g s) for 0.5 s and the angle moving < 0.3 deg over 1 s; angle = mean of both flanks' least-squares slopes between 20 % and 80 % of the heap height, steepest over {STEEPEST_RUN_M} m; {}",
            match ctx.mode {
                Mode::Quick => "spacing 20 mm (quick)",
                Mode::Full => "spacing 10 mm (full)",
            }
        ));
        Ok(out)
    }
}

/// Every planned case run until at rest or to its cap.
fn run_all(ctx: &mut Context) -> Result<Vec<(Plan, HeapRun)>> {
    run_plans::<_, Floor>(ctx, plan(ctx.mode), scene_for, rest_criterion)
}

/// The checks of every run, the order, the pairs, and the outputs.
fn judge(ctx: &mut Context, runs: &[(Plan, HeapRun)]) -> Result<Outcome> {
    let tolerance = ctx.mode.pick(TOLERANCE_QUICK_DEG, TOLERANCE_FULL_DEG);
    let mut out = Outcome::new();
    let mut rows = Vec::new();
    let mut measured: Vec<(ConeMatch, f64, Measured)> = Vec::new();
    let mut by_tag: Vec<(String, Measured)> = Vec::new();
    let mut profiles = Vec::new();
    for (p, case) in runs {
        let Some(floor) = check_run(&mut out, case)? else {
            continue;
        };
        if let (true, Some(profile)) = (is_sweep(&p.tag), final_profile(case)) {
            profiles.push((p.tag.clone(), profile));
        }
        if p.theta_deg == 0.0 {
            check_flat(&mut out, case, floor)?;
            continue;
        }
        if let Some(m) = check_heap(&mut out, case, p.cone, floor, tolerance) {
            let predicted = p.cone.predicted_repose_angle_deg(p.theta_deg);
            rows.push(csv_row(case, p.cone.name(), predicted, &m));
            by_tag.push((p.tag.clone(), m));
            if is_sweep(&p.tag) {
                measured.push((p.cone, p.theta_deg, m));
            }
        }
    }
    check_order(&mut out, "", &measured);
    check_pairs(&mut out, &by_tag, ctx.mode);
    write_repose_csv(ctx, rows)?;
    let figures = ReposeFigures {
        model: "elastic-plastic",
        marker: Marker::Circle,
        heaps: "poured heaps",
        profiles_title: "Surface profiles at the end of each run (poured heaps: the floor at y = 0, the funnel at the period's middle)",
    };
    plot_repose(ctx, &figures, &measured, &profiles)?;
    Ok(out)
}
