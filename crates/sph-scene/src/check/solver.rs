//! The `[solver]` settings as written: each in its range, and consistent with the others
//! (in file-documentation order). The solver's own checks of the parameters made from them
//! run after, in `params.rs`.

// NaN-rejecting checks are written as `!(x > 0.0)` on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::error::Ctx;
use crate::{
    GranularSpec, IisphSettings, PbfSpec, PcisphSpec, SceneError, SolverCommon, SolverSpec,
    DEFAULT_IISPH_MIN_ITERATIONS,
};

/// Checks the settings of `spec`.
pub(super) fn check(ctx: &Ctx, spec: &SolverSpec) -> Result<(), SceneError> {
    check_common(ctx, spec.common())?;
    match spec {
        SolverSpec::Pbf(s) => check_pbf(ctx, s),
        SolverSpec::Pcisph(s) => check_pcisph(ctx, s),
        SolverSpec::Iisph(s) => check_iisph(ctx, &s.iisph),
        SolverSpec::Granular(s) => {
            check_iisph(ctx, &s.iisph)?;
            check_granular(ctx, s)
        }
    }
}

/// The settings every solver has.
fn check_common(ctx: &Ctx, c: &SolverCommon) -> Result<(), SceneError> {
    at_least_one(ctx, "substeps", Some(c.substeps))?;
    positive(ctx, "rest_density", c.rest_density)?;
    if let Some(v) = c.support_over_spacing {
        if !(v.is_finite() && v > 1.0) {
            return Err(ctx.invalid(
                "solver.support_over_spacing",
                format!("must be finite and > 1, got {v}"),
            ));
        }
    }
    Ok(())
}

/// XSPH `c` in [0, 1] (PBF and PCISPH).
fn xsph(ctx: &Ctx, xsph_c: Option<f64>) -> Result<(), SceneError> {
    match xsph_c {
        Some(v) if !(v.is_finite() && (0.0..=1.0).contains(&v)) => {
            Err(ctx.invalid("solver.xsph_c", format!("must be in [0, 1], got {v}")))
        }
        _ => Ok(()),
    }
}

/// PBF settings.
fn check_pbf(ctx: &Ctx, s: &PbfSpec) -> Result<(), SceneError> {
    at_least_one(ctx, "iterations", Some(s.iterations))?;
    xsph(ctx, s.xsph_c)?;
    positive(ctx, "relative_cfm", s.relative_cfm)?;
    non_negative(ctx, "scorr_k", s.scorr_k)?;
    at_least_one(ctx, "scorr_n", s.scorr_n.map(|n| n as usize))?;
    if let Some(v) = s.scorr_delta_q {
        if !(v.is_finite() && v > 0.0 && v < 1.0) {
            return Err(ctx.invalid(
                "solver.scorr_delta_q",
                format!("must be in (0, 1), got {v}"),
            ));
        }
    }
    non_negative(ctx, "vorticity_epsilon", s.vorticity_epsilon)?;
    positive(
        ctx,
        "mean_compression_tolerance",
        s.mean_compression_tolerance,
    )?;
    if let Some(k) = s.min_iterations {
        if s.mean_compression_tolerance.is_none() {
            return Err(ctx.invalid(
                "solver.min_iterations",
                "only applies with solver.mean_compression_tolerance",
            ));
        }
        if k == 0 || k > s.iterations {
            return Err(ctx.invalid(
                "solver.min_iterations",
                format!(
                    "must be >= 1 and <= solver.iterations = {}, got {k}",
                    s.iterations
                ),
            ));
        }
    }
    Ok(())
}

/// PCISPH settings.
fn check_pcisph(ctx: &Ctx, s: &PcisphSpec) -> Result<(), SceneError> {
    at_least_one(ctx, "iterations", Some(s.iterations))?;
    xsph(ctx, s.xsph_c)?;
    positive(ctx, "density_error_tolerance", s.density_error_tolerance)
}

/// The settings of both IISPH kinds.
fn check_iisph(ctx: &Ctx, s: &IisphSettings) -> Result<(), SceneError> {
    let min = s.min_iterations.unwrap_or(DEFAULT_IISPH_MIN_ITERATIONS);
    at_least_one(ctx, "min_iterations", s.min_iterations)?;
    if let Some(max) = s.max_iterations {
        if max < min {
            return Err(ctx.invalid(
                "solver.max_iterations",
                format!("must be >= min_iterations = {min}, got {max}"),
            ));
        }
    }
    positive(ctx, "density_error_tolerance", s.density_error_tolerance)?;
    if let Some(w) = s.relaxation {
        if !(w.is_finite() && w > 0.0 && w <= 1.0) {
            return Err(ctx.invalid("solver.relaxation", format!("must be in (0, 1], got {w}")));
        }
    }
    if let Some(v) = s.viscosity {
        if !(v.is_finite() && v >= 0.0) {
            return Err(ctx.invalid(
                "solver.viscosity",
                format!("must be finite and >= 0 (m^2/s), got {v}"),
            ));
        }
    }
    Ok(())
}

/// The granular settings (`kind = "granular"`).
fn check_granular(ctx: &Ctx, s: &GranularSpec) -> Result<(), SceneError> {
    let th = s.friction_angle_deg;
    if !(th.is_finite() && (0.0..90.0).contains(&th)) {
        return Err(ctx.invalid(
            "solver.friction_angle_deg",
            format!("must be in [0, 90) degrees, got {th}"),
        ));
    }
    non_negative(ctx, "drag_coefficient", s.drag_coefficient)?;
    if let Some(v) = s.air_velocity {
        ctx.finite3("solver.air_velocity", &v)?;
    }
    match s.upscaling_factor {
        Some(0) => Err(ctx.invalid(
            "solver.upscaling_factor",
            "must be >= 1 passive point per particle (omit it for no upscaling), got 0",
        )),
        Some(k) if k > 4096 => Err(ctx.invalid(
            "solver.upscaling_factor",
            format!("must be at most 4096 passive points per particle, got {k}"),
        )),
        _ => Ok(()),
    }
}

/// `solver.<name>`, if given, is ≥ 1.
fn at_least_one(ctx: &Ctx, name: &str, v: Option<usize>) -> Result<(), SceneError> {
    if v == Some(0) {
        return Err(ctx.invalid(format!("solver.{name}"), "must be >= 1, got 0"));
    }
    Ok(())
}

/// `solver.<name>`, if given, is finite and > 0.
fn positive(ctx: &Ctx, name: &str, v: Option<f64>) -> Result<(), SceneError> {
    match v {
        Some(v) => ctx.positive(&format!("solver.{name}"), v),
        None => Ok(()),
    }
}

/// `solver.<name>`, if given, is finite and ≥ 0.
fn non_negative(ctx: &Ctx, name: &str, v: Option<f64>) -> Result<(), SceneError> {
    match v {
        Some(v) if !(v.is_finite() && v >= 0.0) => Err(ctx.invalid(
            format!("solver.{name}"),
            format!("must be finite and >= 0, got {v}"),
        )),
        _ => Ok(()),
    }
}
