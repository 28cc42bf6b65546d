//! `granular-repose`: the angle of repose of a heap formed on a fixed base, against the angle
//! the yield cone predicts for each of its matchings (crate `iisph-granular`, "The yield
//! cone's matching and the angle of repose"): `β = θ` with `cone_match = "simple-shear"`
//! (`α = √2 tan θ`), `β = atan(sin θ)` with the thesis's `"plane-strain"` (`α = √2 sin θ`,
//! Neder 2024 eq. 14; Davis 1968 at zero dilatancy).
//!
//! **Formation** (the shipped scenes `scenes/granular_repose_{20,30,40}.toml`): a planar block
//! 0.8 m wide stands on a raised base of the same width (a solid box) in a 0.05 m deep slab
//! between walls; released, its sides fail and the excess flows off the base's edges, leaving
//! a heap whose toes are pinned at the edges (the fixed-base method; the block is only
//! 0.05–0.07 m taller than the predicted heap, so little material flows and the flanks are set
//! by surface avalanches that stop, not by a runout). Each scene runs with both matchings
//! (the scenes choose simple shear; plane strain is the same scene with the field changed).
//!
//! **Rest** ([`granular_measure::rest`] with its default figures): a run stops once the
//! 99th-percentile speed of the heap's particles (those above the base, between its edges;
//! all particles for θ = 0) and the fastest of them two spacings below the surface have
//! stayed below `0.05 √(g s)` (`s` the particle spacing, the grain size) for 0.5 s and the
//! heap's angle has moved less than 0.3° over the last second (θ = 0, which has no heap:
//! the speeds only); the scene's duration is a cap, and a run that reaches it is not at
//! rest (a failing check with the verdict's margins).
//!
//! **Measure** ([`granular_measure::angle_of_repose`] on the particles above the base,
//! between its edges): the free-surface profile (highest particle per bin of one spacing),
//! each flank's least-squares slope between 20 % and 80 % of the heap height (away from the
//! rounded crest and the toe), the mean of the two flanks; and the steepest slope over a
//! horizontal run of [`STEEPEST_RUN_M`]. On lattice heaps of this size at the quick spacing
//! (10 mm, heaps 14–34 particles tall) both are within 0.8° of the true angle for 15°–42°
//! (`iisph-granular/tests/measure.rs`, `quick_repose_heap_measured_within_one_degree`).
//!
//! In full mode (and in quick mode with `DIAG_WIDE_IN_QUICK`) the 30° simple-shear heap also
//! runs in a slab twice as deep (`wide/…` metrics): the side walls' share in the angle.
//!
//! **Checks**, per matching and θ ∈ {20°, 30°, 40°}: at rest before the cap; the heap is a
//! heap (its apex below the block's top, so it formed by flow; material at both edges of the
//! base); `|measured − predicted| ≤` [`TOLERANCE_DEG`]; the angle increases with θ. The spread
//! of repeated runs is measured on one case run again with the block shifted by half a
//! spacing (`repeat/…` metrics) and from the two flanks of every heap. θ = 0 (no yield
//! stress): the material drains off the base like a liquid, comes to rest (same criterion),
//! and its surface in the troughs is flat.

use anyhow::Result;
use granular_measure::{angle_of_repose, surface_profile, PileShape, ReposeOptions};
use iisph_granular::ConeMatch;
use sph_core::Vec3;
use sph_scene::{FluidSpec, Scene, SolidSpec, SolverSpec};

use super::scene_edit::shipped;
use super::{run_scene_until_rest, solver_error_check, RestCriterion, RestSettings, SceneRun};
use crate::helpers::{plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle};
use crate::{Check, Context, Experiment, Outcome};

/// The experiment.
pub struct GranularRepose;

/// The friction angles (degrees), each with its shipped scene `granular_repose_<θ>`.
const THETAS: [f64; 3] = [20.0, 30.0, 40.0];
/// The matchings swept.
const MATCHES: [ConeMatch; 2] = [ConeMatch::SimpleShear, ConeMatch::PlaneStrain];
/// Horizontal run of the steepest-slope measure (m): 20 spacings in quick mode, the shortest
/// run that does not follow the lattice's steps (see the module docs).
pub const STEEPEST_RUN_M: f64 = 0.2;
/// Band of the comparison with the prediction (degrees): ±2°, made of the
/// measure's resolution on lattice heaps (≤ 0.8° in quick mode) and the spread of repeated
/// runs (measured: the `repeat/…` and `…/flank_difference_deg` metrics).
pub const TOLERANCE_DEG: f64 = 2.0;
/// θ = 0: largest fraction of the particles left on the base.
const DRAINED_FRACTION: f64 = 0.02;
/// θ = 0: largest relief of the troughs' surface, as a fraction of the layer's thickness
/// (a-priori bound of this project: a liquid at rest is flat; half the layer allows a
/// particle's roughness on a layer of about ten particles).
const FLAT_RELIEF_FRACTION: f64 = 0.5;

/// Full mode also runs the 30° simple-shear heap in a slab this many times deeper (the
/// `wide/…` metrics), to show the side walls' share in the angle.
const WIDE_SLAB_FACTOR: f64 = 2.0;
/// Whether quick mode runs the deeper slab too (a diagnostic: set it to measure the side
/// walls' share without a full run; off, as quick mode must stay within its time).
const DIAG_WIDE_IN_QUICK: bool = false;

/// Deepens the slab (tank, base and block along z) by `factor`.
fn widen(scene: &mut Scene, factor: f64) -> Result<()> {
    if let Some(t) = &mut scene.tank {
        t.max.z = t.min.z + factor * (t.max.z - t.min.z);
    }
    for solid in &mut scene.solids {
        if let SolidSpec::Box { min, max } = solid {
            max[2] = min[2] + factor * (max[2] - min[2]);
        }
    }
    for fluid in &mut scene.fluids {
        if let FluidSpec::Block { min, max, .. } = fluid {
            max[2] = min[2] + factor * (max[2] - min[2]);
        }
    }
    scene.check()?;
    Ok(())
}

/// The geometry of a fixed-base scene: the base (the first solid, a box) and the block.
#[derive(Debug, Clone, Copy)]
struct Base {
    x0: f64,
    x1: f64,
    top_y: f64,
    block_top_y: f64,
}

fn base_of(scene: &Scene) -> Result<Base> {
    let (Some(SolidSpec::Box { min, max }), Some(FluidSpec::Block { max: bmax, .. })) =
        (scene.solids.first(), scene.fluids.first())
    else {
        anyhow::bail!(
            "{}: a repose scene needs a box solid (the base) and a fluid block",
            scene.source.display()
        );
    };
    Ok(Base {
        x0: min[0],
        x1: max[0],
        top_y: max[1],
        block_top_y: bmax[1],
    })
}

/// The shipped scene of `theta_deg` (or the 20° one for θ = 0) with the friction angle and
/// the match set, the block shifted by `shift_m` along x.
fn scene_for(theta_deg: f64, cone: ConeMatch, shift_m: f64, ctx: &Context) -> Result<Scene> {
    let name = format!("granular_repose_{:.0}", theta_deg.max(20.0));
    let mut scene = shipped(&name, ctx.mode)?;
    let SolverSpec::Granular(granular) = &mut scene.solver else {
        anyhow::bail!(
            "{}: the repose sweep needs kind = \"granular\", not \"{}\"",
            scene.source.display(),
            scene.solver.kind_name()
        );
    };
    granular.friction_angle_deg = theta_deg;
    granular.cone_match = Some(cone);
    if let Some(FluidSpec::Block { min, max, .. }) = scene.fluids.first_mut() {
        min[0] += shift_m;
        max[0] += shift_m;
    }
    scene.check()?;
    Ok(scene)
}

/// The rest criterion of a run: the heap's particles (above the base, between its edges,
/// the base's top its floor) for θ > 0, all particles and the speeds only for θ = 0 (which
/// must come to rest everywhere and leaves no heap).
fn rest_criterion(scene: &Scene, theta_deg: f64) -> RestCriterion {
    let base = base_of(scene).ok();
    let region = base.filter(|_| theta_deg > 0.0).map(|b| sph_core::Aabb {
        min: Vec3::new(b.x0, b.top_y, f64::NEG_INFINITY),
        max: Vec3::new(b.x1, f64::INFINITY, f64::INFINITY),
    });
    let settings = RestSettings {
        angle_drift_deg: RestSettings::default()
            .angle_drift_deg
            .filter(|_| theta_deg > 0.0),
        ..RestSettings::default()
    };
    RestCriterion {
        settings,
        region,
        floor_y: base.map(|b| b.top_y),
        ..RestCriterion::default()
    }
}

/// One run: the case, its scene and what it gave.
struct Case {
    tag: String,
    theta_deg: f64,
    cone: ConeMatch,
    scene: Scene,
    run: SceneRun,
    /// Wall-clock time of the run (s).
    wall_s: f64,
}

/// The measured heap of a case.
#[derive(Debug, Clone, Copy)]
struct Measured {
    angle_deg: f64,
    steepest_deg: f64,
    flank_difference_deg: f64,
    height_m: f64,
}

impl Experiment for GranularRepose {
    fn id(&self) -> &'static str {
        "granular-repose"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["iisph-granular", "granular-measure"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &[
            "granular_repose_20",
            "granular_repose_30",
            "granular_repose_40",
        ]
    }

    fn source(&self) -> &'static str {
        "Neder (2024) Drucker-Prager granular IISPH: fixed-base heaps at rest against the yield cone's prediction, beta = theta (simple-shear match) or atan(sin theta) (plane-strain match, eq. 14)"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let mut plan: Vec<(String, f64, ConeMatch, f64)> = Vec::new();
        for cone in MATCHES {
            for theta in THETAS {
                plan.push((
                    format!("{}/theta={theta:.0}", cone.name()),
                    theta,
                    cone,
                    0.0,
                ));
            }
        }
        plan.push(("theta=0".into(), 0.0, ConeMatch::SimpleShear, 0.0));
        let repeat_shift = 0.5 * shipped("granular_repose_30", ctx.mode)?.particle_spacing;
        plan.push((
            "repeat/simple-shear/theta=30".into(),
            30.0,
            ConeMatch::SimpleShear,
            repeat_shift,
        ));
        let wide = ctx.mode == crate::Mode::Full || DIAG_WIDE_IN_QUICK;
        if wide {
            plan.push((
                "wide/simple-shear/theta=30".into(),
                30.0,
                ConeMatch::SimpleShear,
                0.0,
            ));
        }
        let scenes: Vec<Scene> = plan
            .iter()
            .map(|(tag, t, c, shift)| {
                let mut scene = scene_for(*t, *c, *shift, ctx)?;
                if tag.starts_with("wide/") {
                    widen(&mut scene, WIDE_SLAB_FACTOR)?;
                }
                Ok(scene)
            })
            .collect::<Result<_>>()?;
        ctx.progress
            .set_length(scenes.iter().map(|s| s.frame_count() as u64).sum());
        let mut cases = Vec::new();
        for ((tag, theta_deg, cone, _), scene) in plan.into_iter().zip(scenes) {
            let t0 = std::time::Instant::now();
            let run = run_scene_until_rest(ctx, &scene, rest_criterion(&scene, theta_deg))?;
            // On stderr, not through the progress bar (hidden when not a terminal): a
            // diagnostic line per run.
            let angle = base_of(&scene)
                .ok()
                .and_then(|b| {
                    let opts = ReposeOptions::planar(b.top_y, scene.particle_spacing);
                    angle_of_repose(&on_base(&run.final_positions, b), &opts).ok()
                })
                .map_or(f64::NAN, |m| m.angle_deg);
            eprintln!(
                "{}",
                format_args!(
                    "  {tag}: angle {angle:.2} deg, {} particles, {} at {:.2} s, {:.0} s wall",
                    run.particles,
                    if run.rest_from_s.is_some() {
                        "at rest"
                    } else {
                        "NOT at rest"
                    },
                    run.rest_from_s
                        .unwrap_or(run.frames.last().map_or(0.0, |f| f.time_s)),
                    t0.elapsed().as_secs_f64()
                )
            );
            cases.push(Case {
                tag,
                theta_deg,
                cone,
                scene,
                run,
                wall_s: t0.elapsed().as_secs_f64(),
            });
        }

        let mut out = Outcome::new();
        let mut rows = Vec::new();
        let mut measured: Vec<(ConeMatch, f64, Measured)> = Vec::new();
        let mut by_tag: Vec<(String, Measured)> = Vec::new();
        let mut profiles = Vec::new();
        for case in &cases {
            let Some(base) = check_run(&mut out, case)? else {
                continue;
            };
            if let Ok(p) = surface_profile(
                &case.run.final_positions,
                PileShape::Planar,
                case.scene.particle_spacing,
            ) {
                if is_sweep(&case.tag) {
                    profiles.push((case.tag.clone(), p.iter().map(|p| (p.d_m, p.y_m)).collect()));
                }
            }
            if case.theta_deg == 0.0 {
                check_drained(&mut out, case, base)?;
                continue;
            }
            if let Some(m) = check_heap(&mut out, case, base) {
                rows.push(vec![
                    case.tag.clone(),
                    format!("{}", case.theta_deg),
                    case.cone.name().to_string(),
                    format!(
                        "{:.3}",
                        case.cone.predicted_repose_angle_deg(case.theta_deg)
                    ),
                    format!("{:.3}", m.angle_deg),
                    format!("{:.3}", m.steepest_deg),
                    format!("{:.3}", m.flank_difference_deg),
                    format!("{:.4}", m.height_m),
                    format!("{:.3}", case.run.rest_from_s.unwrap_or(f64::NAN)),
                    case.run.particles.to_string(),
                ]);
                by_tag.push((case.tag.clone(), m));
                if is_sweep(&case.tag) {
                    measured.push((case.cone, case.theta_deg, m));
                }
            }
        }
        check_order_and_spread(&mut out, &measured, &by_tag);
        write_csv_rows(
            &ctx.path("repose.csv"),
            &[
                "case",
                "theta_deg",
                "cone_match",
                "predicted_deg",
                "measured_deg",
                "steepest_deg",
                "flank_difference_deg",
                "heap_height_m",
                "rest_from_s",
                "particles",
            ],
            rows,
        )?;
        ctx.add_file(
            "repose.csv",
            "measured angle of repose (band fit and steepest 0.2 m) per matching and friction angle, with the prediction and the time of rest",
        );
        plot_angles(ctx, &measured)?;
        plot_profiles(ctx, &profiles)?;
        out.note(format!(
            "fixed-base heaps; rest = 99th-percentile and deep (2 spacings) speeds < 0.05 sqrt(g s) for 0.5 s and the angle moving < 0.3 deg over 1 s; angle = mean of both flanks' least-squares slopes between 20 % and 80 % of the heap height, steepest over {STEEPEST_RUN_M} m; {}",
            if ctx.mode == crate::Mode::Quick { "spacing 10 mm (quick)" } else { "spacing 5 mm (full)" }
        ));
        Ok(out)
    }
}

/// The checks every run has: no solver error, at rest before the cap. Returns the base when
/// the run can be measured.
fn check_run(out: &mut Outcome, case: &Case) -> Result<Option<Base>> {
    let tag = &case.tag;
    out.metric(format!("{tag}/particles"), case.run.particles as f64);
    out.metric(format!("{tag}/wall_s"), case.wall_s);
    if let Some(e) = &case.run.blow_up {
        out.check(solver_error_check(tag, e));
        return Ok(None);
    }
    let end_t = case.run.frames.last().map_or(f64::NAN, |f| f.time_s);
    out.metric(format!("{tag}/end_time_s"), end_t);
    let (capped, substeps, residual) = last_second_friction(&case.run.frames, end_t);
    out.metric(
        format!("{tag}/last_second/friction_capped_substep_fraction"),
        capped,
    );
    out.metric(
        format!("{tag}/last_second/friction_iterations_per_substep"),
        substeps,
    );
    out.metric(
        format!("{tag}/last_second/mean_friction_residual"),
        residual,
    );
    let rest = rest_criterion(&case.scene, case.theta_deg);
    let verdict = case.run.rest_verdict;
    for (name, _, m) in verdict.map_or_else(Vec::new, |v| v.margins()) {
        out.metric(format!("{tag}/rest/{name}_at_end"), m.value);
        out.metric(format!("{tag}/rest/{name}_misses_by"), m.misses_by());
    }
    if let Some(v) = verdict {
        out.metric(format!("{tag}/rest/speeds_held_s"), v.speeds_held_s);
    }
    out.check(Check::less_than(
        format!("{tag}/at rest before the cap: time of rest (s)"),
        case.run.rest_from_s.unwrap_or(f64::INFINITY),
        case.scene.duration_s,
        format!(
            "validity of the measurement: granular codes' rest criterion (99th-percentile speed and the fastest particle two spacings deep below 0.05 sqrt(g s) for 0.5 s, the angle moving < 0.3 deg over 1 s; speeds only for theta = 0) before the {} s cap; at the end: {}",
            case.scene.duration_s,
            verdict.map_or_else(|| "no verdict".to_string(), |v| v.summary(&rest.settings))
        ),
    ));
    Ok(Some(base_of(&case.scene)?))
}

/// Over the run's last second: the fraction of substeps whose friction solve hit its cap,
/// the friction iterations per substep, and the mean residual of the frames' last friction
/// solves (whether the creep of a heap is the solver's, not the model's).
fn last_second_friction(frames: &[sph_sim::FrameRecord], end_t: f64) -> (f64, f64, f64) {
    let last: Vec<_> = frames.iter().filter(|f| f.time_s > end_t - 1.0).collect();
    let substeps = last.iter().map(|f| f.substeps).sum::<usize>().max(1) as f64;
    let capped = last
        .iter()
        .map(|f| f.unconverged_friction_substeps)
        .sum::<usize>() as f64;
    let iterations = last.iter().map(|f| f.friction_iterations).sum::<usize>() as f64;
    let residual =
        last.iter().map(|f| f.last_friction_residual).sum::<f64>() / last.len().max(1) as f64;
    (capped / substeps, iterations / substeps, residual)
}

/// The particles above the base, between its edges.
fn on_base(positions: &[Vec3<f64>], base: Base) -> Vec<Vec3<f64>> {
    positions
        .iter()
        .copied()
        .filter(|p| p.y > base.top_y && p.x > base.x0 && p.x < base.x1)
        .collect()
}

/// The heap's checks; returns its measurement.
fn check_heap(out: &mut Outcome, case: &Case, base: Base) -> Option<Measured> {
    let tag = &case.tag;
    let s = case.scene.particle_spacing;
    let on_base = on_base(&case.run.final_positions, base);
    let opts = ReposeOptions::planar(base.top_y, s)
        .with_spacing(s)
        .with_steepest_run(STEEPEST_RUN_M);
    let m = match angle_of_repose(&on_base, &opts) {
        Ok(m) => m,
        Err(e) => {
            out.check(Check::equals(
                format!("{tag}/heap measurable"),
                0.0,
                1.0,
                format!("the measurement failed: {e}"),
            ));
            return None;
        }
    };
    let predicted = case.cone.predicted_repose_angle_deg(case.theta_deg);
    let flank = |side: i8| {
        m.flanks
            .iter()
            .find(|f| f.side == side)
            .map_or(f64::NAN, |f| f.angle_deg)
    };
    let measured = Measured {
        angle_deg: m.angle_deg,
        steepest_deg: m.steepest_deg.unwrap_or(f64::NAN),
        flank_difference_deg: (flank(-1) - flank(1)).abs(),
        height_m: m.pile_height_m,
    };
    out.metric(format!("{tag}/predicted_deg"), predicted);
    out.metric(format!("{tag}/angle_deg"), measured.angle_deg);
    out.metric(format!("{tag}/steepest_deg"), measured.steepest_deg);
    out.metric(
        format!("{tag}/flank_difference_deg"),
        measured.flank_difference_deg,
    );
    out.metric(format!("{tag}/heap_height_m"), measured.height_m);
    out.metric(
        format!("{tag}/rest_from_s"),
        case.run.rest_from_s.unwrap_or(f64::NAN),
    );
    out.check(Check::less_than(
        format!("{tag}/heap formed by flow: apex below the block's top (m)"),
        m.profile
            .iter()
            .map(|p| p.y_m)
            .fold(f64::NEG_INFINITY, f64::max),
        base.block_top_y - s,
        "validity: an apex at the block's top is a block that did not fail, not a heap",
    ));
    let edge_gap = m
        .profile
        .first()
        .map_or(f64::INFINITY, |p| p.d_m - base.x0)
        .max(m.profile.last().map_or(f64::INFINITY, |p| base.x1 - p.d_m));
    out.check(Check::less_than(
        format!("{tag}/heap covers the base: largest gap to an edge (m)"),
        edge_gap,
        2.0 * s,
        "validity of the fixed-base method: the toes are pinned at the base's edges",
    ));
    out.check(Check::within(
        format!("{tag}/angle of repose (deg) against atan(alpha/sqrt 2) = {predicted:.1}"),
        measured.angle_deg,
        predicted - TOLERANCE_DEG,
        predicted + TOLERANCE_DEG,
        format!(
            "physics: a surface layer at rest in simple shear holds tan(beta) = alpha/sqrt(2) ({} match; crate docs); band ±{TOLERANCE_DEG}° = the measure's resolution on lattice heaps (<= 0.8°, tests/measure.rs) + the spread of repeated runs (repeat/ metrics)",
            case.cone.name()
        ),
    ));
    Some(measured)
}

/// θ = 0: drained off the base, flat in the troughs.
fn check_drained(out: &mut Outcome, case: &Case, base: Base) -> Result<()> {
    let tag = &case.tag;
    let s = case.scene.particle_spacing;
    let pos = &case.run.final_positions;
    let left_on_base = pos.iter().filter(|p| p.y > base.top_y).count() as f64 / pos.len() as f64;
    out.metric(format!("{tag}/fraction_left_on_base"), left_on_base);
    out.check(Check::less_than(
        format!("{tag}/drains off the base: fraction of particles left on it"),
        left_on_base,
        DRAINED_FRACTION,
        "physics: without friction there is no yield stress, the material flows off the base like a liquid (2 %: a film of one particle layer over the base)",
    ));
    let tank = case.scene.tank.expect("the repose scenes have a tank");
    let mut worst: f64 = 0.0;
    for (lo, hi) in [(tank.min.x, base.x0), (base.x1, tank.max.x)] {
        let trough: Vec<Vec3<f64>> = pos
            .iter()
            .copied()
            .filter(|p| p.x > lo && p.x < hi)
            .collect();
        let profile = surface_profile(&trough, PileShape::Planar, s)?;
        let y_hi = profile
            .iter()
            .map(|p| p.y_m)
            .fold(f64::NEG_INFINITY, f64::max);
        let y_lo = profile.iter().map(|p| p.y_m).fold(f64::INFINITY, f64::min);
        let layer = trough.len() as f64 * s.powi(3) / ((hi - lo) * (tank.max.z - tank.min.z));
        worst = worst.max((y_hi - y_lo) / layer);
    }
    out.metric(format!("{tag}/trough_relief_over_layer"), worst);
    out.check(Check::less_than(
        format!("{tag}/flat: surface relief / layer thickness in the troughs"),
        worst,
        FLAT_RELIEF_FRACTION,
        "a-priori bound of this project: a liquid at rest is flat (half the layer thickness)",
    ));
    Ok(())
}

/// The angle increases with θ under each match; the spread of the repeated run (metrics).
fn check_order_and_spread(
    out: &mut Outcome,
    measured: &[(ConeMatch, f64, Measured)],
    by_tag: &[(String, Measured)],
) {
    for cone in MATCHES {
        let angles: Vec<f64> = measured
            .iter()
            .filter(|(c, _, _)| *c == cone)
            .map(|(_, _, m)| m.angle_deg)
            .collect();
        if angles.len() == THETAS.len() {
            let increasing = angles.windows(2).all(|w| w[1] > w[0]);
            out.check(Check::equals(
                format!(
                    "{}/measured angle increases with theta (20 < 30 < 40)",
                    cone.name()
                ),
                f64::from(u8::from(increasing)),
                1.0,
                "physics: a larger friction angle holds a steeper slope",
            ));
        }
    }
    let find = |tag: &str| by_tag.iter().find(|(t, _)| t == tag).map(|(_, m)| *m);
    if let (Some(a), Some(b)) = (
        find("simple-shear/theta=30"),
        find("repeat/simple-shear/theta=30"),
    ) {
        out.metric(
            "repeat/angle_difference_deg",
            (a.angle_deg - b.angle_deg).abs(),
        );
        out.metric(
            "repeat/steepest_difference_deg",
            (a.steepest_deg - b.steepest_deg).abs(),
        );
    }
    if let (Some(a), Some(w)) = (
        find("simple-shear/theta=30"),
        find("wide/simple-shear/theta=30"),
    ) {
        out.metric("wide/angle_minus_narrow_deg", w.angle_deg - a.angle_deg);
    }
    let flanks = by_tag
        .iter()
        .map(|(_, m)| m.flank_difference_deg)
        .fold(0.0, f64::max);
    out.metric("largest_flank_difference_deg", flanks);
}

fn plot_angles(ctx: &mut Context, measured: &[(ConeMatch, f64, Measured)]) -> Result<()> {
    let curve = |cone: ConeMatch| {
        (0..=50)
            .map(|t| (f64::from(t), cone.predicted_repose_angle_deg(f64::from(t))))
            .collect::<Vec<_>>()
    };
    let mut series = vec![
        Series::styled(
            "simple-shear match: β = θ",
            curve(ConeMatch::SimpleShear),
            SeriesStyle::Dashed,
            0,
        ),
        Series::styled(
            "plane-strain match (eq. 14): β = atan(sin θ)",
            curve(ConeMatch::PlaneStrain),
            SeriesStyle::Dashed,
            1,
        ),
    ];
    for (i, cone) in MATCHES.iter().enumerate() {
        let pick = |f: fn(&Measured) -> f64| {
            measured
                .iter()
                .filter(|(c, _, _)| c == cone)
                .map(|(_, t, m)| (*t, f(m)))
                .collect::<Vec<_>>()
        };
        series.push(Series::markers(
            format!("{}: band fit 20–80 %", cone.name()),
            pick(|m| m.angle_deg),
            Marker::Circle,
            i,
        ));
        series.push(Series::markers(
            format!("{}: steepest {STEEPEST_RUN_M} m", cone.name()),
            pick(|m| m.steepest_deg),
            Marker::Ring,
            i,
        ));
    }
    let spec = PlotSpec {
        legend: Legend::UpperLeft,
        series,
        x_range: Some((0.0, 50.0)),
        y_range: Some((0.0, 50.0)),
        ..PlotSpec::new(
            "Angle of repose of fixed-base heaps against the yield cone's prediction",
            "friction angle θ (deg)",
            "angle of repose β (deg)",
        )
    };
    plot_xy(&ctx.path("repose.png"), &spec)?;
    ctx.add_plot(
        "repose.png",
        "measured angle of repose per matching against the friction angle, with each matching's prediction",
    );
    Ok(())
}

fn plot_profiles(ctx: &mut Context, profiles: &[(String, Vec<(f64, f64)>)]) -> Result<()> {
    if profiles.is_empty() {
        return Ok(());
    }
    let series = profiles
        .iter()
        .enumerate()
        .map(|(i, (tag, pts))| Series::line(tag.clone(), pts.clone(), i))
        .collect();
    let spec = PlotSpec {
        legend: Legend::UpperRight,
        series,
        ..PlotSpec::new(
            "Surface profiles at the end of each run (the base spans x = 0.8–1.6 m, top at 0.25 m)",
            "x (m)",
            "height of the highest particle (m)",
        )
    };
    plot_xy(&ctx.path("profiles.png"), &spec)?;
    ctx.add_plot(
        "profiles.png",
        "free-surface profile (highest particle per bin of one spacing) at the end of each run",
    );
    Ok(())
}

/// Whether a run is one of the sweep (not a repeat or a side-wall variant).
fn is_sweep(tag: &str) -> bool {
    !(tag.starts_with("repeat/") || tag.starts_with("wide/"))
}
