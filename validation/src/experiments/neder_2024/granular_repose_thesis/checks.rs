//! The checks of `granular-repose-thesis`'s fixed-base heaps: at rest, formed by flow and
//! covering the base, the angle against the prediction; θ = 0 drained off the base and flat
//! in the troughs; the angles' order; the repeat's and the deeper slab's differences.

use anyhow::Result;
use granular_measure::SurfacePoint;
use iisph_granular::ConeMatch;
use sph_core::Vec3;
use sph_scene::{FluidSpec, Scene, SolidSpec};

use super::plan::{PLAIN_30_TAG, REPEAT_TAG, WIDE_TAG};
use crate::helpers::repose::{
    check_completed, check_flatness, check_rest, heap_metrics, measure_heap, pool_relief,
    rest_settings, Ground, HeapRun, Measured, TOLERANCE_QUICK_DEG,
};
use crate::scene_runs::RestCriterion;
use crate::{Check, Outcome};

/// θ = 0 on the base: largest fraction of the particles left on it.
const DRAINED_FRACTION: f64 = 0.02;

/// The geometry of a fixed-base repose scene: the base the heap stands on (the first solid, a
/// box) and the block of grains.
#[derive(Debug, Clone, Copy)]
pub struct Base {
    /// The base's edges along `x` (m).
    pub x0: f64,
    /// See [`Base::x0`].
    pub x1: f64,
    /// The base's top (m): the floor the heap stands on.
    pub top_y: f64,
    /// The block's top (m).
    pub block_top_y: f64,
}

impl Ground for Base {
    /// The base and block of `scene`.
    fn of(scene: &Scene) -> Result<Base> {
        let (Some(SolidSpec::Box { min, max }), Some(FluidSpec::Block { max: bmax, .. })) =
            (scene.solids.first(), scene.fluids.first())
        else {
            anyhow::bail!(
                "{}: a fixed-base repose scene needs a box solid (the base) and a fluid block",
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

    /// The heap's grains: those above the base, between its edges.
    fn heap(self, positions: &[Vec3<f64>]) -> Vec<Vec3<f64>> {
        positions
            .iter()
            .copied()
            .filter(|p| p.y > self.top_y && p.x > self.x0 && p.x < self.x1)
            .collect()
    }

    fn level_y(self) -> f64 {
        self.top_y
    }
}

/// The rest criterion of a run: the heap's grains (above the base, between its edges) for
/// θ > 0; all grains and the speeds only for θ = 0 (which must come to rest everywhere and
/// leaves no heap).
pub fn rest_criterion(scene: &Scene, theta_deg: f64) -> RestCriterion {
    let base = Base::of(scene).ok();
    let region = base.filter(|_| theta_deg > 0.0).map(|b| sph_core::Aabb {
        min: Vec3::new(b.x0, b.top_y, f64::NEG_INFINITY),
        max: Vec3::new(b.x1, f64::INFINITY, f64::INFINITY),
    });
    RestCriterion {
        settings: rest_settings(theta_deg),
        region,
        floor_y: base.map(|b| b.top_y),
        ..RestCriterion::default()
    }
}

/// The checks every run has: no solver error, at rest before the cap; the friction solve
/// over the last second (metrics). Returns the base when the run can be measured.
pub fn check_run(out: &mut Outcome, case: &HeapRun) -> Result<Option<Base>> {
    let Some(end_t) = check_completed(out, case) else {
        return Ok(None);
    };
    let tag = &case.tag;
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
    check_rest(out, case, &rest_criterion(&case.scene, case.theta_deg));
    Ok(Some(Base::of(&case.scene)?))
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

/// The heap's checks: formed by flow and covering the base, the angle against the prediction
/// of `cone` within [`TOLERANCE_QUICK_DEG`] (the band the replay was documented with, in
/// either mode); returns its measurement.
pub fn check_heap(
    out: &mut Outcome,
    case: &HeapRun,
    cone: ConeMatch,
    base: Base,
) -> Option<Measured> {
    let tolerance_deg = TOLERANCE_QUICK_DEG;
    let heap = base.heap(&case.run.final_positions);
    let (m, measured) = measure_heap(out, case, &heap, base.top_y)?;
    let predicted = cone.predicted_repose_angle_deg(case.theta_deg);
    heap_metrics(out, case, predicted, &measured);
    check_on_base(out, case, base, heap.len(), &m.profile);
    out.check(Check::within(
        format!(
            "{}/angle of repose (deg) against atan(alpha/sqrt 2) = {predicted:.1}",
            case.tag
        ),
        measured.angle_deg,
        predicted - tolerance_deg,
        predicted + tolerance_deg,
        format!(
            "physics: a surface layer at rest in simple shear holds tan(beta) = alpha/sqrt(2) ({} match; crate iisph-granular docs); band ±{tolerance_deg}° = the measure's resolution on lattice heaps (<= 0.8°, tests/measure.rs) + the spread of repeated runs (thesis/repeat/ metrics)",
            cone.name()
        ),
    ));
    Some(measured)
}

/// The fixed-base heap: formed by flow (the apex below the block's top) and covering its
/// base (the toes pinned at the base's edges).
fn check_on_base(
    out: &mut Outcome,
    case: &HeapRun,
    base: Base,
    on_base: usize,
    profile: &[SurfacePoint],
) {
    let tag = &case.tag;
    let s = case.scene.particle_spacing;
    out.metric(
        format!("{tag}/fraction_on_base"),
        on_base as f64 / case.run.particles.max(1) as f64,
    );
    let apex = profile
        .iter()
        .map(|p| p.y_m)
        .fold(f64::NEG_INFINITY, f64::max);
    out.check(Check::less_than(
        format!("{tag}/heap formed by flow: apex below the block's top (m)"),
        apex,
        base.block_top_y - s,
        "validity: an apex at the block's top is a block that did not fail, not a heap",
    ));
    let edge_gap = profile
        .first()
        .map_or(f64::INFINITY, |p| p.d_m - base.x0)
        .max(profile.last().map_or(f64::INFINITY, |p| base.x1 - p.d_m));
    out.check(Check::less_than(
        format!("{tag}/heap covers the base: largest gap to an edge (m)"),
        edge_gap,
        2.0 * s,
        "validity of the fixed-base method: the toes are pinned at the edges of the base",
    ));
}

/// θ = 0: drained off the base and flat in the troughs beside it.
pub fn check_flat(out: &mut Outcome, case: &HeapRun, base: Base) -> Result<()> {
    let tag = &case.tag;
    let s = case.scene.particle_spacing;
    let pos = &case.run.final_positions;
    let Some(tank) = case.scene.tank else {
        anyhow::bail!(
            "{}: a repose scene needs a tank",
            case.scene.source.display()
        );
    };
    let left_on_base = pos.iter().filter(|p| p.y > base.top_y).count() as f64 / pos.len() as f64;
    out.metric(format!("{tag}/fraction_left_on_base"), left_on_base);
    out.check(Check::less_than(
        format!("{tag}/drains off the base: fraction of particles left on it"),
        left_on_base,
        DRAINED_FRACTION,
        "physics: without friction there is no yield stress, the material flows off like a liquid (2 %: a film of one particle layer)",
    ));
    let depth = tank.max.z - tank.min.z;
    let mut worst: f64 = 0.0;
    for pool in [(tank.min.x, base.x0), (base.x1, tank.max.x)] {
        worst = worst.max(pool_relief(pos, pool, s, depth)?.1);
    }
    check_flatness(out, tag, worst, "in the troughs");
    Ok(())
}

/// The repeat's and the deeper slab's differences from the 30° simple-shear heap (metrics).
pub fn pair_metrics(out: &mut Outcome, by_tag: &[(String, Measured)]) {
    let find = |tag: &str| by_tag.iter().find(|(t, _)| t == tag).map(|(_, m)| *m);
    if let (Some(a), Some(b)) = (find(PLAIN_30_TAG), find(REPEAT_TAG)) {
        out.metric(
            "thesis/repeat/angle_difference_deg",
            (a.angle_deg - b.angle_deg).abs(),
        );
        out.metric(
            "thesis/repeat/steepest_difference_deg",
            (a.steepest_deg - b.steepest_deg).abs(),
        );
    }
    if let (Some(a), Some(w)) = (find(PLAIN_30_TAG), find(WIDE_TAG)) {
        out.metric(
            "thesis/wide/angle_minus_narrow_deg",
            w.angle_deg - a.angle_deg,
        );
    }
}
