//! Shared by the angle-of-repose experiments (`bui_2008::granular_repose`, poured heaps of the
//! elastic–plastic model, and `neder_2024::granular_repose_thesis`, fixed-base heaps of the
//! thesis model): a heap's run until at rest with its diagnostic line, the checks every run
//! has (no solver error, at rest before the cap), the planar measure of a heap and its
//! metrics, the flatness of a liquid's pool, the order of the angles, and the `repose.csv`,
//! `repose.png` and `profiles.png` outputs. Each experiment knows its model, its scenes and
//! its own checks.

use anyhow::Result;
use granular_measure::{
    angle_of_repose, surface_profile, PileShape, ReposeMeasurement, ReposeOptions, SurfacePoint,
};
use sph_core::Vec3;
use sph_scene::Scene;
use sph_solver::ConeMatch;

use super::{plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle};
use crate::scene_runs::{
    run_scene_until_rest, solver_error_check, RestCriterion, RestSettings, RunStore, SceneRun,
};
use crate::{Check, Context, Mode, Outcome};

/// The friction angles (degrees) of the sweeps, each with its shipped scenes.
pub const THETAS: [f64; 3] = [20.0, 30.0, 40.0];
/// The matches of the sweeps, in run order.
pub const MATCHES: [ConeMatch; 2] = [ConeMatch::SimpleShear, ConeMatch::PlaneStrain];
/// Horizontal run of the steepest-slope measure (m).
pub const STEEPEST_RUN_M: f64 = 0.2;
/// Band of the comparison with the prediction in quick mode (degrees): the measure's
/// resolution on 20 mm lattice heaps (≤ 0.8°, `granular-measure/tests/measure.rs`) plus the
/// flank-to-flank spread of heaps at rest at 20 mm (up to 1.2°,
/// `docs/elastoplastic-granular.md`). The thesis replay keeps it in full mode (the band it was
/// documented with).
pub const TOLERANCE_QUICK_DEG: f64 = 2.0;
/// θ = 0: largest relief of the surface where the liquid collects, as a fraction of its
/// layer's thickness (a-priori bound of this project: a liquid at rest is flat; half the
/// layer allows a particle's roughness on a layer of about ten particles).
pub const FLAT_RELIEF_FRACTION: f64 = 0.5;

/// One planned run of a repose case; `V` says how it departs from its shipped scene.
#[derive(Debug, Clone)]
pub struct Plan<V> {
    /// The case's tag.
    pub tag: String,
    /// The friction angle (degrees).
    pub theta_deg: f64,
    /// The cone's match.
    pub cone: ConeMatch,
    /// How it departs from the shipped scene.
    pub variant: V,
}

/// One run of a repose case: its tag, friction angle, scene and what it gave.
pub struct HeapRun {
    /// The case's tag, the prefix of its checks and metrics.
    pub tag: String,
    /// The friction angle (degrees).
    pub theta_deg: f64,
    /// The scene run.
    pub scene: Scene,
    /// What the run gave.
    pub run: SceneRun,
    /// Wall-clock time of the run (s).
    pub wall_s: f64,
}

/// The measured heap of a case.
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    /// The angle of repose: the mean of both flanks' band fits (degrees).
    pub angle_deg: f64,
    /// The steepest slope over [`STEEPEST_RUN_M`] (degrees).
    pub steepest_deg: f64,
    /// The difference of the two flanks' angles (degrees).
    pub flank_difference_deg: f64,
    /// The angle of the flank facing `−x` (the left one) and of the flank facing `+x`
    /// (degrees; NaN for a flank the measure did not find).
    pub flank_deg: [f64; 2],
    /// The heap's height (m).
    pub height_m: f64,
}

/// The rest settings of a run: granular codes' default, the angle's drift for θ > 0 only
/// (θ = 0 leaves no heap: the speeds only).
pub fn rest_settings(theta_deg: f64) -> RestSettings {
    RestSettings {
        angle_drift_deg: RestSettings::default()
            .angle_drift_deg
            .filter(|_| theta_deg > 0.0),
        ..RestSettings::default()
    }
}

/// What the heaps of one experiment stand on, read from its scenes.
pub trait Ground: Copy {
    /// The ground of `scene`.
    fn of(scene: &Scene) -> Result<Self>;
    /// The heap's grains among `positions`.
    fn heap(self, positions: &[Vec3<f64>]) -> Vec<Vec3<f64>>;
    /// The height the heap stands on (m): the floor of its planar measure.
    fn level_y(self) -> f64;
}

/// Builds every planned case's scene with `scene_for` (refusing a bad one before any run),
/// then runs each until at rest by `rest` (or to its cap), its diagnostic line measured on
/// the ground `G` of its scene. The runs go in parallel on rayon's pool (a heap of a few
/// thousand grains keeps one core busy but not two: its own parallel loops gain little),
/// the longest first by [`steps_to_cap`] (each worker takes the next run when it is free, so
/// a long run does not start last and leave the other cores idle), and come back in plan
/// order; each run is the same bits as when run alone (the solver's loops split their work
/// in fixed chunks, whatever the threads).
pub fn run_plans<V: Send + Sync, G: Ground>(
    ctx: &mut Context,
    plans: Vec<Plan<V>>,
    scene_for: impl Fn(&Plan<V>, Mode) -> Result<Scene>,
    rest: impl Fn(&Scene, f64) -> RestCriterion + Sync,
) -> Result<Vec<(Plan<V>, HeapRun)>> {
    use rayon::iter::{ParallelBridge, ParallelIterator};
    let scenes = plans
        .iter()
        .map(|p| scene_for(p, ctx.mode))
        .collect::<Result<Vec<_>>>()?;
    ctx.progress
        .set_length(scenes.iter().map(|s| s.frame_count() as u64).sum());
    let order = longest_first(&scenes.iter().map(steps_to_cap).collect::<Vec<_>>());
    let mut scenes: Vec<Option<Scene>> = scenes.into_iter().map(Some).collect();
    // The runs in the order to start them: `par_bridge` hands the next to a worker when it
    // is free.
    let jobs: Vec<(usize, Scene)> = order
        .iter()
        .filter_map(|&k| scenes[k].take().map(|scene| (k, scene)))
        .collect();
    let ctx: &Context = ctx;
    let mut runs: Vec<(usize, Result<HeapRun>)> = jobs
        .into_iter()
        .par_bridge()
        .map(|(k, scene)| {
            let p = &plans[k];
            let criterion = rest(&scene, p.theta_deg);
            let ground = G::of(&scene).ok();
            let heap = |pos: &[_]| ground.map_or_else(Vec::new, |g| g.heap(pos));
            let level_y = ground.map(G::level_y);
            let run = run_heap(
                ctx,
                p.tag.clone(),
                p.theta_deg,
                scene,
                criterion,
                level_y,
                heap,
            );
            (k, run)
        })
        .collect();
    runs.sort_by_key(|(k, _)| *k);
    plans
        .into_iter()
        .zip(runs)
        .map(|(p, (_, run))| Ok((p, run?)))
        .collect()
}

/// The order in which to start runs of estimated costs `cost`: the most costly first (ties in
/// plan order), the longest-processing-time-first rule, within 4/3 of the best schedule
/// (Graham 1969, "Bounds on multiprocessing timing anomalies", SIAM J. Appl. Math. 17,
/// 416–429).
fn longest_first(cost: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..cost.len()).collect();
    order.sort_by(|&a, &b| cost[b].total_cmp(&cost[a]));
    order
}

/// The explicit steps `scene` takes to its cap (frames × substeps, times the explicit steps
/// per substep of the elastic–plastic solver): the run's cost before its heap comes to rest,
/// for the order of the runs (a stiffer or finer heap takes more steps per frame).
pub fn steps_to_cap(scene: &Scene) -> f64 {
    let frames = scene.frame_count() as f64 * scene.solver.substeps() as f64;
    match scene.solver_params::<f64>() {
        Ok(sph_scene::SolverParams::Elastoplastic(p)) => frames * p.explicit_steps().0 as f64,
        _ => frames,
    }
}

/// Runs `scene` until at rest by `rest` (or to its cap) and prints the run's diagnostic line
/// on stderr, with the angle of `heap` (the heap's grains of the final positions) on a floor
/// at `floor_y`. In full mode the finished run is kept in `<out>/runs/` and a run this build
/// already finished on the same scene is taken from there ([`stored_runs`]).
pub fn run_heap(
    ctx: &Context,
    tag: String,
    theta_deg: f64,
    scene: Scene,
    rest: RestCriterion,
    floor_y: Option<f64>,
    heap: impl Fn(&[Vec3<f64>]) -> Vec<Vec3<f64>>,
) -> Result<HeapRun> {
    let store = stored_runs(ctx);
    let stored = store.as_ref().and_then(|s| s.load(&tag, &scene));
    let reused = stored.is_some();
    let (run, wall_s) = match stored {
        Some(kept) => {
            ctx.progress.inc(scene.frame_count() as u64);
            kept
        }
        None => {
            let t0 = std::time::Instant::now();
            let run = run_scene_until_rest(ctx, &scene, rest)?;
            let wall_s = t0.elapsed().as_secs_f64();
            if let Some(Err(e)) = store.map(|s| s.save(&tag, &scene, &run, wall_s)) {
                eprintln!("  {tag}: the finished run is not kept: {e:#}");
            }
            (run, wall_s)
        }
    };
    // On stderr, not through the progress bar (hidden when not a terminal): a diagnostic
    // line per run.
    let angle = floor_y
        .and_then(|y| {
            let opts = ReposeOptions::planar(y, scene.particle_spacing);
            angle_of_repose(&heap(&run.final_positions), &opts).ok()
        })
        .map_or(f64::NAN, |m| m.angle_deg);
    eprintln!(
        "  {tag}: angle {angle:.2} deg, {} particles, {} at {:.2} s, {wall_s:.0} s wall{}",
        run.particles,
        if run.rest_from_s.is_some() {
            "at rest"
        } else {
            "NOT at rest"
        },
        run.rest_from_s
            .unwrap_or(run.frames.last().map_or(0.0, |f| f.time_s)),
        if reused {
            " (the stored run of this build, reused)"
        } else {
            ""
        },
    );
    Ok(HeapRun {
        tag,
        theta_deg,
        scene,
        run,
        wall_s,
    })
}

/// Where full mode keeps its finished heap runs (`<out>/runs/`, [`RunStore`]): its ensembles
/// take hours, and an interrupted experiment resumes with the runs it finished. Quick mode's
/// runs take minutes and always run.
pub fn stored_runs(ctx: &Context) -> Option<RunStore> {
    (ctx.mode == Mode::Full)
        .then(|| RunStore::for_this_build(ctx.path("runs")))
        .flatten()
}

/// The first checks every run has: its size and wall time (metrics) and no solver error.
/// Returns the run's end time (s), or `None` when a blow-up ended it (nothing to measure).
pub fn check_completed(out: &mut Outcome, case: &HeapRun) -> Option<f64> {
    let tag = &case.tag;
    out.metric(format!("{tag}/particles"), case.run.particles as f64);
    out.metric(format!("{tag}/wall_s"), case.wall_s);
    if let Some(e) = &case.run.blow_up {
        out.check(solver_error_check(tag, e));
        return None;
    }
    let end_t = case.run.frames.last().map_or(f64::NAN, |f| f.time_s);
    out.metric(format!("{tag}/end_time_s"), end_t);
    Some(end_t)
}

/// At rest before the cap by `rest` (the criterion the run used): the verdict's margins
/// (metrics) and the check.
pub fn check_rest(out: &mut Outcome, case: &HeapRun, rest: &RestCriterion) {
    let tag = &case.tag;
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
}

/// Measures the planar heap `heap` on a floor at `floor_y` (band fit 20–80 %, steepest over
/// [`STEEPEST_RUN_M`]); a failing check `<tag>/heap measurable` when it cannot be measured.
pub fn measure_heap(
    out: &mut Outcome,
    case: &HeapRun,
    heap: &[Vec3<f64>],
    floor_y: f64,
) -> Option<(ReposeMeasurement, Measured)> {
    let s = case.scene.particle_spacing;
    let opts = ReposeOptions::planar(floor_y, s)
        .with_spacing(s)
        .with_steepest_run(STEEPEST_RUN_M);
    let m = match angle_of_repose(heap, &opts) {
        Ok(m) => m,
        Err(e) => {
            out.check(Check::equals(
                format!("{}/heap measurable", case.tag),
                0.0,
                1.0,
                format!("the measurement failed: {e}"),
            ));
            return None;
        }
    };
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
        flank_deg: [flank(-1), flank(1)],
        height_m: m.pile_height_m,
    };
    Some((m, measured))
}

/// The heap's metrics: the prediction, the measure and the time of rest.
pub fn heap_metrics(out: &mut Outcome, case: &HeapRun, predicted_deg: f64, m: &Measured) {
    let tag = &case.tag;
    out.metric(format!("{tag}/predicted_deg"), predicted_deg);
    out.metric(format!("{tag}/angle_deg"), m.angle_deg);
    out.metric(format!("{tag}/steepest_deg"), m.steepest_deg);
    out.metric(
        format!("{tag}/flank_difference_deg"),
        m.flank_difference_deg,
    );
    out.metric(format!("{tag}/heap_height_m"), m.height_m);
    out.metric(
        format!("{tag}/rest_from_s"),
        case.run.rest_from_s.unwrap_or(f64::NAN),
    );
}

/// The surface profile of the grains of `positions` between `lo` and `hi` along `x`, and its
/// relief (highest minus lowest point) over the thickness of their layer on a floor
/// `(hi − lo) × depth_m`.
pub fn pool_relief(
    positions: &[Vec3<f64>],
    (lo, hi): (f64, f64),
    s: f64,
    depth_m: f64,
) -> Result<(Vec<SurfacePoint>, f64)> {
    let pool: Vec<Vec3<f64>> = positions
        .iter()
        .copied()
        .filter(|p| p.x > lo && p.x < hi)
        .collect();
    let profile = surface_profile(&pool, PileShape::Planar, s)?;
    let y_hi = profile
        .iter()
        .map(|p| p.y_m)
        .fold(f64::NEG_INFINITY, f64::max);
    let y_lo = profile.iter().map(|p| p.y_m).fold(f64::INFINITY, f64::min);
    let layer = pool.len() as f64 * s.powi(3) / ((hi - lo) * depth_m);
    Ok((profile, (y_hi - y_lo) / layer))
}

/// θ = 0: the largest relief over the layer's thickness where the liquid collects (`place`)
/// below [`FLAT_RELIEF_FRACTION`].
pub fn check_flatness(out: &mut Outcome, tag: &str, worst: f64, place: &str) {
    out.metric(format!("{tag}/trough_relief_over_layer"), worst);
    out.check(Check::less_than(
        format!("{tag}/flat: surface relief / layer thickness {place}"),
        worst,
        FLAT_RELIEF_FRACTION,
        "a-priori bound of this project: a liquid at rest is flat (half the layer thickness)",
    ));
}

/// The angle increases with θ under one match (`name`, e.g. `"simple-shear"` or
/// `"thesis/plane-strain"`), when it ran at all three angles (`angles` in θ's order).
fn check_increasing(out: &mut Outcome, name: &str, angles: &[f64]) {
    if angles.len() == THETAS.len() {
        let increasing = angles.windows(2).all(|w| w[1] > w[0]);
        out.check(Check::equals(
            format!("{name}/measured angle increases with theta (20 < 30 < 40)"),
            f64::from(u8::from(increasing)),
            1.0,
            "physics: a larger friction angle holds a steeper slope",
        ));
    }
}

/// The final profile of a sweep's run for `profiles.png`, `(x, height)`.
pub fn final_profile(case: &HeapRun) -> Option<Vec<(f64, f64)>> {
    surface_profile(
        &case.run.final_positions,
        PileShape::Planar,
        case.scene.particle_spacing,
    )
    .ok()
    .map(|p| p.iter().map(|p| (p.d_m, p.y_m)).collect())
}

/// A row of `repose.csv`.
pub fn csv_row(case: &HeapRun, cone_match: &str, predicted_deg: f64, m: &Measured) -> Vec<String> {
    vec![
        case.tag.clone(),
        format!("{}", case.theta_deg),
        cone_match.to_string(),
        format!("{predicted_deg:.3}"),
        format!("{:.3}", m.angle_deg),
        format!("{:.3}", m.steepest_deg),
        format!("{:.3}", m.flank_difference_deg),
        format!("{:.4}", m.height_m),
        format!("{:.3}", case.run.rest_from_s.unwrap_or(f64::NAN)),
        case.run.particles.to_string(),
        format!("{:.1}", case.wall_s),
    ]
}

/// Writes `repose.csv` (rows of [`csv_row`]) and records it.
pub fn write_repose_csv(ctx: &mut Context, rows: Vec<Vec<String>>) -> Result<()> {
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
            "wall_s",
        ],
        rows,
    )?;
    ctx.add_file(
        "repose.csv",
        "measured angle of repose (band fit and steepest 0.2 m) per case, with the prediction, the time of rest and the wall time",
    );
    Ok(())
}

/// How one model's heaps are drawn in `repose.png` and `profiles.png`.
pub struct ReposeFigures<'a> {
    /// The model in the legend, e.g. `"elastic-plastic"`.
    pub model: &'a str,
    /// The model's marker.
    pub marker: Marker,
    /// The heaps in the title of `repose.png`, e.g. `"poured heaps"`.
    pub heaps: &'a str,
    /// The title of `profiles.png`.
    pub profiles_title: &'a str,
}

/// `repose.png` (each match's prediction dashed, and the measured angles `measured` of the
/// sweeps, the i-th match in the i-th colour) and `profiles.png` (the final profiles).
pub fn plot_repose(
    ctx: &mut Context,
    figures: &ReposeFigures<'_>,
    measured: &[(ConeMatch, f64, Measured)],
    profiles: &[(String, Vec<(f64, f64)>)],
) -> Result<()> {
    let predictions: [(&str, ConeMatch); 2] = [
        ("simple-shear match: β = θ", ConeMatch::SimpleShear),
        (
            "plane-strain match: β = atan(sin θ)",
            ConeMatch::PlaneStrain,
        ),
    ];
    let mut series: Vec<Series> = predictions
        .iter()
        .enumerate()
        .map(|(i, (label, cone))| {
            let curve = (0..=50)
                .map(|t| (f64::from(t), cone.predicted_repose_angle_deg(f64::from(t))))
                .collect();
            Series::styled(*label, curve, SeriesStyle::Dashed, i)
        })
        .collect();
    for (i, cone) in MATCHES.iter().enumerate() {
        let points: Vec<(f64, f64)> = measured
            .iter()
            .filter(|(c, _, _)| c == cone)
            .map(|(_, t, m)| (*t, m.angle_deg))
            .collect();
        if !points.is_empty() {
            let label = format!("{}, {}: band fit 20–80 %", figures.model, cone.name());
            series.push(Series::markers(label, points, figures.marker, i % 2));
        }
    }
    let title = format!(
        "Angle of repose of {} against the yield cone's prediction",
        figures.heaps
    );
    let spec = PlotSpec {
        legend: Legend::UpperLeft,
        series,
        x_range: Some((0.0, 50.0)),
        y_range: Some((0.0, 50.0)),
        ..PlotSpec::new(&title, "friction angle θ (deg)", "angle of repose β (deg)")
    };
    plot_xy(&ctx.path("repose.png"), &spec)?;
    ctx.add_plot(
        "repose.png",
        "measured angle of repose per model and match against the friction angle, with each match's prediction",
    );
    plot_profiles(ctx, figures.profiles_title, profiles)
}

/// The angle increases with θ under each match run at all three angles (`measured`: the
/// sweeps' heaps, in θ's order); each check named `{prefix}{match}`.
pub fn check_order(out: &mut Outcome, prefix: &str, measured: &[(ConeMatch, f64, Measured)]) {
    for cone in MATCHES {
        let angles: Vec<f64> = measured
            .iter()
            .filter(|(c, _, _)| *c == cone)
            .map(|(_, _, m)| m.angle_deg)
            .collect();
        check_increasing(out, &format!("{prefix}{}", cone.name()), &angles);
    }
}

/// `profiles.png`: the final surface profile of each sweep run.
fn plot_profiles(
    ctx: &mut Context,
    title: &str,
    profiles: &[(String, Vec<(f64, f64)>)],
) -> Result<()> {
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
        ..PlotSpec::new(title, "x (m)", "height of the highest particle (m)")
    };
    plot_xy(&ctx.path("profiles.png"), &spec)?;
    ctx.add_plot(
        "profiles.png",
        "free-surface profile (highest particle per bin of one spacing) at the end of each run",
    );
    Ok(())
}

/// Whether a run is one of a sweep (not a repeat, side-wall, spacing or modulus variant).
pub fn is_sweep(tag: &str) -> bool {
    let t = tag.strip_prefix("thesis/").unwrap_or(tag);
    !["repeat/", "wide/", "coarse/", "stiff/"]
        .iter()
        .any(|p| t.starts_with(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Longest first, ties in plan order.
    #[test]
    fn runs_start_longest_first() {
        assert_eq!(longest_first(&[1.0, 3.0, 2.0, 3.0]), vec![1, 3, 2, 0]);
        assert!(longest_first(&[]).is_empty());
    }

    /// Full mode keeps a finished run and takes it back, bit for bit, when the same build
    /// runs the same scene again; another scene runs.
    #[test]
    fn full_mode_resumes_with_the_runs_it_finished() {
        let dir = std::env::temp_dir().join(format!("repose-store-{}", std::process::id()));
        std::fs::remove_dir_all(&dir).ok();
        std::fs::create_dir_all(&dir).unwrap();
        let ctx = Context::new(
            Mode::Full,
            dir.clone(),
            crate::reference_data_dir(),
            indicatif::ProgressBar::hidden(),
        );
        let short = |duration_s: f64| {
            let mut scene =
                crate::scene_runs::shipped_scene("granular_repose_poured_30_planar", Mode::Quick)
                    .unwrap();
            scene.duration_s = duration_s;
            scene
        };
        let run = |scene: Scene| {
            let rest = RestCriterion::default();
            run_heap(&ctx, "t/pour=1".into(), 30.0, scene, rest, None, |_| {
                Vec::new()
            })
            .unwrap()
        };
        let first = run(short(0.48));
        assert!(
            first.run.particles > 0,
            "the pour has placed grains to compare"
        );
        let kept = dir.join("runs/t_pour=1.json");
        let written = std::fs::metadata(&kept).unwrap().modified().unwrap();
        let again = run(short(0.48));
        assert_eq!(again.run.final_positions, first.run.final_positions);
        assert_eq!(again.wall_s, first.wall_s, "the kept run's wall time");
        assert_eq!(
            std::fs::metadata(&kept).unwrap().modified().unwrap(),
            written
        );
        let longer = run(short(0.64));
        assert!(
            longer.run.frames.len() > first.run.frames.len(),
            "another scene runs"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
