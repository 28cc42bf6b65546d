//! The surge front of a collapsing water column, measured frame by frame: shared by the
//! PBF and IISPH curves of `dam-break-front` (Martin & Moyce 1952).

use anyhow::Result;
use sph_core::Real;
use sph_scene::Scene;

use sph_sim::observe::OnFrame;
use sph_sim::{Flow, FrameRecord, SceneSim};

use crate::scene_runs::{advance_frames, scene_sim};
use crate::Context;

/// Column width `a` of the scene (m).
pub(crate) const COLUMN_WIDTH_M: f64 = 0.2;
/// Fraction of the particles allowed ahead of the measured front (droplets).
pub(crate) const FRONT_QUANTILE: f64 = 1e-3;
/// Least-squares slope and rms residual of `(x, y)` points with `x` in `span`.
pub fn fitted_slope(points: &[(f64, f64)], span: (f64, f64)) -> (f64, f64) {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0 >= span.0 && p.0 <= span.1 && p.1.is_finite())
        .collect();
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return (f64::NAN, f64::NAN);
    }
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let slope = sxy / sxx;
    let rms = (pts
        .iter()
        .map(|p| (p.1 - (my + slope * (p.0 - mx))).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    (slope, rms)
}

/// `x` of the leading free surface: the `k`-th largest particle `x` (k = `FRONT_QUANTILE`
/// of the particles, at least 1) plus `radius`.
pub fn front_x<R: Real>(positions: &[sph_core::Vec3<R>], radius: f64) -> f64 {
    let mut xs: Vec<f64> = positions.iter().map(|p| p.x.as_f64()).collect();
    if xs.is_empty() {
        return f64::NAN;
    }
    let k = ((xs.len() as f64 * FRONT_QUANTILE) as usize).max(1);
    let idx = xs.len() - k;
    let (_, x, _) = xs.select_nth_unstable_by(idx, f64::total_cmp);
    *x + radius
}

/// Linear interpolation of `y(x)` in points sorted by `x`; `None` outside their span.
pub(crate) fn interpolate(points: &[(f64, f64)], x: f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        (x0 <= x && x <= x1 && x1 > x0).then(|| y0 + (y1 - y0) * (x - x0) / (x1 - x0))
    })
}

/// One run of the surge front: `(T, Z)` per frame, the particle count, and what the mass
/// calibration did (`[boundary] initial_masses = "calibrated"`).
pub(crate) struct FrontRun {
    pub series: Vec<(f64, f64)>,
    pub particles: usize,
    pub calibration: Option<sph_solver::initial::MassCalibration>,
}

pub(crate) fn simulate<R: Real>(ctx: &Context, scene: &Scene) -> Result<FrontRun> {
    let mut sim = scene_sim::<R>(scene)?;
    let frames = scene.frame_count();
    let radius = 0.5 * scene.particle_spacing;
    let g = (scene.gravity[0].powi(2) + scene.gravity[1].powi(2) + scene.gravity[2].powi(2)).sqrt();
    let t_scale = (2.0 * g / COLUMN_WIDTH_M).sqrt();
    let x_wall = scene.tank.map_or(0.0, |t| t.min.x);
    let mut series = vec![(
        0.0,
        (front_x(&sim.state.positions, radius) - x_wall) / COLUMN_WIDTH_M,
    )];
    let mut front = OnFrame(|sim: &SceneSim<R>, _: &FrameRecord| {
        let z = (front_x(&sim.state.positions, radius) - x_wall) / COLUMN_WIDTH_M;
        series.push((sim.time_s * t_scale, z));
        Flow::Continue
    });
    advance_frames(ctx, &mut sim, frames, &mut [&mut front])?;
    Ok(FrontRun {
        series,
        particles: sim.state.len(),
        calibration: sim.calibration,
    })
}
