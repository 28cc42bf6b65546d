//! The IISPH curve of `dam-break-front`: the Martin & Moyce (1952) column
//! (`scenes/martin_moyce.toml`) run with `kind = "iisph"` (the solver's defaults: relaxed
//! Jacobi with ω = 0.5, at least 2 iterations, average density error 0.1 %), the scene's steps,
//! and volume-map walls (the boundary model of the thesis, eqs. 29–31), measured with the same
//! front as PBF's. Quick mode runs it at the coarser spacing [`QUICK_SPACING_M`] with the
//! scene's CFL number; full mode at the scene's spacing.
//!
//! The masses are calibrated (`[boundary] initial_masses = "calibrated"`,
//! `sph_solver::initial`): with the lattice's `ρ0 s³` the column starts compressed at the
//! volume-map walls (`ρ/ρ0` 1.038 at a wall, 1.075 in a corner: the lattice plus the walls'
//! share `ρ0 Ψ`), which IISPH's first unilateral pressure solve releases as a jet (largest
//! speed 1.4 m/s after the first 16 ms frame in quick mode, against `g t` = 0.16 m/s; 0.28 m/s
//! calibrated), and the front then led the measurements by up to 33 %.

use anyhow::Result;
use sph_scene::{BoundaryModel, IisphSettings, InitialMasses, Scene};

use super::front::{interpolate, simulate, FrontRun};
use crate::scene_runs::{iisph_solver, shipped_scene};
use crate::{Context, Mode};

/// Spacing of the IISPH curve in quick mode (m): `a/16`, 16 × 32 × 8 = 4,096 particles (the
/// scene's quick spacing, `a/32`, costs 32,768 particles, beyond the quick suite's budget).
pub const QUICK_SPACING_M: f64 = 0.0125;

/// The IISPH run of the surge front.
#[derive(Debug, Clone)]
pub struct IisphFront {
    /// `(T, Z)` per frame.
    pub series: Vec<(f64, f64)>,
    /// Particles simulated.
    pub particles: usize,
    /// The largest `(Z_sim − Z_exp)/Z_exp` (signed) over the measured `(T, Z)`.
    pub worst_relative_error: f64,
    /// What the mass calibration did.
    pub calibration: Option<sph_solver::initial::MassCalibration>,
}

/// The Martin & Moyce scene with IISPH (see the module documentation).
pub fn iisph_scene(ctx: &Context) -> Result<Scene> {
    let mut scene = shipped_scene("martin_moyce", ctx.mode)?;
    let mut substeps = scene.solver.substeps() as f64;
    if ctx.mode == Mode::Quick {
        // same CFL number as the scene's steps at the coarser spacing
        substeps = (substeps * scene.particle_spacing / QUICK_SPACING_M).ceil();
        scene.particle_spacing = QUICK_SPACING_M;
    }
    scene.solver = iisph_solver(substeps as usize, IisphSettings::default());
    scene.boundary.model = BoundaryModel::VolumeMap;
    scene.boundary.initial_masses = InitialMasses::Calibrated;
    scene.check()?;
    Ok(scene)
}

/// Runs the IISPH curve and compares it with the measured `(T, Z)`.
pub fn run(ctx: &Context, measured: &[(f64, f64)]) -> Result<IisphFront> {
    let scene = iisph_scene(ctx)?;
    let FrontRun {
        series,
        particles,
        calibration,
    } = sph_sim::with_precision!(scene.precision, R => simulate::<R>(ctx, &scene)?);
    let worst_relative_error = measured
        .iter()
        .map(|&(t, z)| (interpolate(&series, t).unwrap_or(f64::NAN) - z) / z)
        .fold(0.0f64, |w, r| {
            if r.is_nan() || r.abs() > w.abs() {
                r
            } else {
                w
            }
        });
    Ok(IisphFront {
        series,
        particles,
        worst_relative_error,
        calibration,
    })
}
