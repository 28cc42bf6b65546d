//! The IISPH curve of `dam-break-front`: the Martin & Moyce (1952) column
//! (`scenes/martin_moyce.toml`) run with `kind = "iisph"` (the solver's defaults: relaxed
//! Jacobi with ω = 0.5, at least 2 iterations, average density error 0.1 %), the scene's steps,
//! and volume-map walls (the boundary model of the thesis, eqs. 29–31), measured with the same
//! front as PBF's.

use anyhow::Result;
use sph_scene::{Precision, Scene};
use toml::Value;

use super::scene_edit::SceneText;
use crate::experiments::pbf::dam_break_front::{interpolate, simulate};
use crate::Context;

/// The IISPH run of the surge front.
#[derive(Debug, Clone)]
pub struct IisphFront {
    /// `(T, Z)` per frame.
    pub series: Vec<(f64, f64)>,
    /// Particles simulated.
    pub particles: usize,
    /// The largest `(Z_sim − Z_exp)/Z_exp` (signed) over the measured `(T, Z)`.
    pub worst_relative_error: f64,
}

/// The Martin & Moyce scene with IISPH (see the module documentation).
pub fn iisph_scene(ctx: &Context) -> Result<Scene> {
    let mut text = SceneText::shipped("martin_moyce", ctx.mode)?;
    let substeps = text.number("solver.substeps")? as i64;
    text.set_solver("iisph", &[("substeps", Value::Integer(substeps))]);
    text.set("boundary.model", "volume-map")?;
    text.scene()
}

/// Runs the IISPH curve and compares it with the measured `(T, Z)`.
pub fn run(ctx: &Context, measured: &[(f64, f64)]) -> Result<IisphFront> {
    let scene = iisph_scene(ctx)?;
    let (series, particles) = match scene.precision {
        Precision::F32 => simulate::<f32>(ctx, &scene)?,
        Precision::F64 => simulate::<f64>(ctx, &scene)?,
    };
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
    })
}
