//! The checks of each of `granular-repose`'s pours: every layer poured, at rest, the toes
//! clear of the period's ends, its measure; θ = 0 spread and flat. The angles are judged on
//! the ensembles ([`super::ensemble`]).

use anyhow::Result;
use elastoplastic_granular::ConeMatch;
use granular_measure::SurfacePoint;
use sph_core::Vec3;
use sph_scene::Scene;

use crate::helpers::repose::{
    check_completed, check_flatness, check_rest, heap_metrics, measure_heap, pool_relief,
    rest_settings, Ground, HeapRun, Measured,
};
use crate::scene_runs::RestCriterion;
use crate::{Check, Outcome};

/// The highest grain within two spacings of the period's ends, as a fraction of the heap's
/// height. The band fit starts at 20 % of the height: a foot higher than that at the period's
/// ends is a heap that met its periodic image, not a lone heap.
const TOE_CLEARANCE_FRACTION: f64 = 0.2;

/// What a poured heap stands on: the tank's floor at `y`, periodic along `x` from `x0` to
/// `x1`.
#[derive(Debug, Clone, Copy)]
pub struct Floor {
    /// Height of the floor (m).
    pub y: f64,
    /// The period's ends along `x` (m).
    pub x0: f64,
    /// See [`Floor::x0`].
    pub x1: f64,
}

impl Ground for Floor {
    /// The floor of a poured scene: its tank's.
    fn of(scene: &Scene) -> Result<Floor> {
        let Some(tank) = scene.tank else {
            anyhow::bail!(
                "{}: a poured heap needs a tank (its floor)",
                scene.source.display()
            );
        };
        Ok(Floor {
            y: tank.min.y,
            x0: tank.min.x,
            x1: tank.max.x,
        })
    }

    /// The heap's grains: those above the floor.
    fn heap(self, positions: &[Vec3<f64>]) -> Vec<Vec3<f64>> {
        positions.iter().copied().filter(|p| p.y > self.y).collect()
    }

    fn level_y(self) -> f64 {
        self.y
    }
}

/// The rest criterion of a run: every grain, the angle's drift for θ > 0 only.
pub fn rest_criterion(scene: &Scene, theta_deg: f64) -> RestCriterion {
    RestCriterion {
        settings: rest_settings(theta_deg),
        region: None,
        floor_y: Floor::of(scene).ok().map(|f| f.y),
        ..RestCriterion::default()
    }
}

/// The checks every run has: no solver error, every layer poured, at rest before the cap.
/// Returns the floor when the run can be measured.
pub fn check_run(out: &mut Outcome, case: &HeapRun) -> Result<Option<Floor>> {
    if check_completed(out, case).is_none() {
        return Ok(None);
    }
    if case.scene.pour.is_some() {
        out.check(Check::equals(
            format!("{}/every layer poured before the cap", case.tag),
            f64::from(u8::from(case.run.pour_finished)),
            1.0,
            format!(
                "definition of the heap: the whole pour ({} grains at this spacing) in {} s",
                case.scene.poured_grains(),
                case.scene.duration_s
            ),
        ));
    }
    check_rest(out, case, &rest_criterion(&case.scene, case.theta_deg));
    Ok(Some(Floor::of(&case.scene)?))
}

/// One pour's measure and metrics (the prediction of `cone`, both flanks) and the check that
/// its toes are clear of the period's ends; the angle is judged on the case's ensemble
/// ([`super::ensemble`]). Returns its measurement.
pub fn measure_pour(
    out: &mut Outcome,
    case: &HeapRun,
    cone: ConeMatch,
    floor: Floor,
) -> Option<Measured> {
    let heap = floor.heap(&case.run.final_positions);
    let (m, measured) = measure_heap(out, case, &heap, floor.y)?;
    let predicted = cone.predicted_repose_angle_deg(case.theta_deg);
    heap_metrics(out, case, predicted, &measured);
    out.metric(
        format!("{}/left_flank_deg", case.tag),
        measured.flank_deg[0],
    );
    out.metric(
        format!("{}/right_flank_deg", case.tag),
        measured.flank_deg[1],
    );
    check_toes(
        out,
        &case.tag,
        &m.profile,
        floor,
        case.scene.particle_spacing,
    );
    Some(measured)
}

/// A poured heap is a lone heap: its foot at the period's ends stands below
/// [`TOE_CLEARANCE_FRACTION`] of its height.
fn check_toes(out: &mut Outcome, tag: &str, profile: &[SurfacePoint], floor: Floor, s: f64) {
    let Floor { y, x0, x1 } = floor;
    let height = profile.iter().map(|p| p.y_m - y).fold(0.0, f64::max);
    let at_ends = profile
        .iter()
        .filter(|p| p.d_m < x0 + 2.0 * s || p.d_m > x1 - 2.0 * s)
        .map(|p| p.y_m - y)
        .fold(0.0, f64::max);
    out.metric(format!("{tag}/height_at_period_ends_m"), at_ends);
    out.check(Check::less_than(
        format!("{tag}/toes clear of the period's ends: height there / heap height"),
        at_ends / height,
        TOE_CLEARANCE_FRACTION,
        "validity of a lone heap: the band fit starts at 20 % of the height; a foot higher than that within two spacings of the period's ends is a heap that met its periodic image",
    ));
}

/// θ = 0: spread over the whole floor (the period) and flat there.
pub fn check_flat(out: &mut Outcome, case: &HeapRun, floor: Floor) -> Result<()> {
    let Some(tank) = case.scene.tank else {
        anyhow::bail!(
            "{}: a repose scene needs a tank",
            case.scene.source.display()
        );
    };
    let s = case.scene.particle_spacing;
    let depth = tank.max.z - tank.min.z;
    let pool = (floor.x0, floor.x1);
    let (profile, relief) = pool_relief(&case.run.final_positions, pool, s, depth)?;
    check_spread(out, &case.tag, &profile, pool, s);
    check_flatness(out, &case.tag, relief.max(0.0), "over the floor");
    Ok(())
}

/// θ = 0 poured: the liquid covers the periodic floor from `x0` to `x1`: no bare stretch
/// (between the highest grains of neighbouring surface bins, across the period's seam
/// included) of three spacings or more.
fn check_spread(
    out: &mut Outcome,
    tag: &str,
    profile: &[SurfacePoint],
    (x0, x1): (f64, f64),
    s: f64,
) {
    let xs: Vec<f64> = profile.iter().map(|p| p.d_m).collect();
    let across_seam = match (xs.first(), xs.last()) {
        (Some(first), Some(last)) => (first - x0) + (x1 - last),
        _ => x1 - x0,
    };
    let bare = xs
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(across_seam, f64::max);
    out.metric(format!("{tag}/largest_bare_stretch_m"), bare);
    out.check(Check::less_than(
        format!("{tag}/spread over the floor: largest bare stretch (m)"),
        bare,
        3.0 * s,
        "physics: without friction there is no yield stress, the poured material spreads over the whole floor like a liquid; on a covered floor the highest grains of neighbouring bins (one spacing wide) are less than two spacings apart, three allows one bin the profile drops as a pit",
    ));
}
