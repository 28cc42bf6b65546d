//! The `[solver]` table, read in two steps so that errors keep the field path and line.
//!
//! [`SolverSpec`] deserializes as an internally tagged enum, but serde buffers an internally
//! tagged table before handing it to the variant, and the buffer has neither the TOML spans
//! nor `serde_path_to_error`'s path: an unknown field would be reported on `solver`, at the
//! table's position. So `kind` is read first, with the rest of the document (`RawScene`; an
//! unknown kind names the allowed ones), then here the variant struct from the same table
//! without `kind` (its `deny_unknown_fields` refuses the fields of the other solvers, at
//! their line). Then the values are range-checked.

use serde::de::DeserializeOwned;
use toml::de::{DeValue, ValueDeserializer};

use super::SolverTable;
use crate::error::{line_col, serde_error, Ctx};
use crate::{
    GranularSpec, IisphSpec, PbfSpec, PcisphSpec, SceneError, SolverKind, SolverSpec,
    DEFAULT_IISPH_MIN_ITERATIONS,
};

/// Reads and checks the `[solver]` table `table` of the scene text `text`, whose `kind` has
/// been read already.
pub(super) fn parse(
    ctx: &Ctx,
    text: &str,
    kind: SolverKind,
    mut table: SolverTable<'_>,
) -> Result<SolverSpec, SceneError> {
    // (serde also reads a struct from an array, so `solver = ["pbf", 1, 1]` got this far.)
    let DeValue::Table(t) = table.get_mut() else {
        let found = table.get_ref().type_str();
        return Err(ctx.invalid("solver", format!("must be a table, not {found}")));
    };
    t.remove("kind");
    // The line of each field, for the range errors.
    let lines = Lines(
        t.iter()
            .map(|(k, v)| (k.get_ref().to_string(), line_col(text, v.span().start).0))
            .collect(),
    );
    let spec = match kind {
        SolverKind::Pbf => SolverSpec::Pbf(variant(ctx, text, kind, table)?),
        SolverKind::Pcisph => SolverSpec::Pcisph(variant(ctx, text, kind, table)?),
        SolverKind::Iisph => SolverSpec::Iisph(variant(ctx, text, kind, table)?),
        SolverKind::Granular => SolverSpec::Granular(variant(ctx, text, kind, table)?),
    };
    match &spec {
        SolverSpec::Pbf(s) => check_pbf(ctx, s)?,
        SolverSpec::Pcisph(s) => check_pcisph(ctx, s)?,
        SolverSpec::Iisph(s) => check_iisph(ctx, &lines, &IisphShared::of_iisph(s))?,
        SolverSpec::Granular(s) => check_granular(ctx, &lines, s)?,
    }
    Ok(spec)
}

/// The variant struct of `kind` from the table without `kind`.
fn variant<T: DeserializeOwned>(
    ctx: &Ctx,
    text: &str,
    kind: SolverKind,
    table: SolverTable<'_>,
) -> Result<T, SceneError> {
    let note = format!("kind = \"{}\" has no such field", kind.name());
    serde_path_to_error::deserialize(ValueDeserializer::from(table))
        .map_err(|e| serde_error(ctx.file, text, "solver", &note, &e))
}

/// The settings every solver has: step counts, rest density, support ratio, XSPH `c`.
fn check_shared(
    ctx: &Ctx,
    substeps: usize,
    iterations: usize,
    rest_density: Option<f64>,
    support_over_spacing: Option<f64>,
    xsph_c: Option<f64>,
) -> Result<(), SceneError> {
    at_least_one(ctx, "substeps", Some(substeps))?;
    at_least_one(ctx, "iterations", Some(iterations))?;
    positive(ctx, "rest_density", rest_density)?;
    if let Some(v) = support_over_spacing {
        if !(v.is_finite() && v > 1.0) {
            return Err(ctx.invalid(
                "solver.support_over_spacing",
                format!("must be finite and > 1, got {v}"),
            ));
        }
    }
    if let Some(v) = xsph_c {
        if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
            return Err(ctx.invalid("solver.xsph_c", format!("must be in [0, 1], got {v}")));
        }
    }
    Ok(())
}

/// PBF settings (in file-documentation order).
fn check_pbf(ctx: &Ctx, s: &PbfSpec) -> Result<(), SceneError> {
    check_shared(
        ctx,
        s.substeps,
        s.iterations,
        s.rest_density,
        s.support_over_spacing,
        s.xsph_c,
    )?;
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

/// PCISPH settings (in file-documentation order).
fn check_pcisph(ctx: &Ctx, s: &PcisphSpec) -> Result<(), SceneError> {
    check_shared(
        ctx,
        s.substeps,
        s.iterations,
        s.rest_density,
        s.support_over_spacing,
        s.xsph_c,
    )?;
    positive(ctx, "density_error_tolerance", s.density_error_tolerance)
}

/// The line of each field of the `[solver]` table.
struct Lines(Vec<(String, usize)>);

impl Lines {
    /// A [`SceneError::Invalid`] for `solver.<name>` with the field's line.
    fn invalid(&self, ctx: &Ctx, name: &str, reason: String) -> SceneError {
        match self.0.iter().find(|(k, _)| k == name) {
            Some((_, l)) => ctx.invalid(format!("solver.{name}"), format!("{reason} (line {l})")),
            None => ctx.invalid(format!("solver.{name}"), reason),
        }
    }
}

/// The settings both IISPH kinds have.
struct IisphShared {
    substeps: usize,
    max_iterations: Option<usize>,
    min_iterations: Option<usize>,
    density_error_tolerance: Option<f64>,
    relaxation: Option<f64>,
    rest_density: Option<f64>,
    support_over_spacing: Option<f64>,
    viscosity: Option<f64>,
}

impl IisphShared {
    fn of_iisph(s: &IisphSpec) -> Self {
        Self {
            substeps: s.substeps,
            max_iterations: s.max_iterations,
            min_iterations: s.min_iterations,
            density_error_tolerance: s.density_error_tolerance,
            relaxation: s.relaxation,
            rest_density: s.rest_density,
            support_over_spacing: s.support_over_spacing,
            viscosity: s.viscosity,
        }
    }

    fn of_granular(s: &GranularSpec) -> Self {
        Self {
            substeps: s.substeps,
            max_iterations: s.max_iterations,
            min_iterations: s.min_iterations,
            density_error_tolerance: s.density_error_tolerance,
            relaxation: s.relaxation,
            rest_density: s.rest_density,
            support_over_spacing: s.support_over_spacing,
            viscosity: s.viscosity,
        }
    }
}

/// IISPH settings (`kind = "iisph"`, and the shared part of `"granular"`).
fn check_iisph(ctx: &Ctx, lines: &Lines, s: &IisphShared) -> Result<(), SceneError> {
    let finite_positive = |name: &str, v: Option<f64>| match v {
        Some(v) if !(v.is_finite() && v > 0.0) => {
            Err(lines.invalid(ctx, name, format!("must be finite and > 0, got {v}")))
        }
        _ => Ok(()),
    };
    if s.substeps == 0 {
        return Err(lines.invalid(ctx, "substeps", "must be >= 1, got 0".into()));
    }
    let min = s.min_iterations.unwrap_or(DEFAULT_IISPH_MIN_ITERATIONS);
    if s.min_iterations == Some(0) {
        return Err(lines.invalid(ctx, "min_iterations", "must be >= 1, got 0".into()));
    }
    if let Some(max) = s.max_iterations {
        if max < min {
            return Err(lines.invalid(
                ctx,
                "max_iterations",
                format!("must be >= min_iterations = {min}, got {max}"),
            ));
        }
    }
    finite_positive("density_error_tolerance", s.density_error_tolerance)?;
    if let Some(w) = s.relaxation {
        if !(w.is_finite() && w > 0.0 && w <= 1.0) {
            return Err(lines.invalid(ctx, "relaxation", format!("must be in (0, 1], got {w}")));
        }
    }
    finite_positive("rest_density", s.rest_density)?;
    if let Some(v) = s.support_over_spacing {
        if !(v.is_finite() && v > 1.0) {
            return Err(lines.invalid(
                ctx,
                "support_over_spacing",
                format!("must be finite and > 1, got {v}"),
            ));
        }
    }
    if let Some(v) = s.viscosity {
        if !(v.is_finite() && v >= 0.0) {
            return Err(lines.invalid(
                ctx,
                "viscosity",
                format!("must be finite and >= 0 (m^2/s), got {v}"),
            ));
        }
    }
    Ok(())
}

/// Granular settings (`kind = "granular"`).
fn check_granular(ctx: &Ctx, lines: &Lines, s: &GranularSpec) -> Result<(), SceneError> {
    check_iisph(ctx, lines, &IisphShared::of_granular(s))?;
    let th = s.friction_angle_deg;
    if !(th.is_finite() && (0.0..90.0).contains(&th)) {
        return Err(lines.invalid(
            ctx,
            "friction_angle_deg",
            format!("must be in [0, 90) degrees, got {th}"),
        ));
    }
    if let Some(c) = s.drag_coefficient {
        if !(c.is_finite() && c >= 0.0) {
            return Err(lines.invalid(
                ctx,
                "drag_coefficient",
                format!("must be finite and >= 0, got {c}"),
            ));
        }
    }
    if let Some(v) = s.air_velocity {
        if let Some(a) = (0..3).find(|&a| !v[a].is_finite()) {
            return Err(lines.invalid(
                ctx,
                "air_velocity",
                format!("component {a} is not finite ({})", v[a]),
            ));
        }
    }
    match s.upscaling_factor {
        Some(0) => Err(lines.invalid(
            ctx,
            "upscaling_factor",
            "must be >= 1 passive point per particle (omit it for no upscaling), got 0".into(),
        )),
        Some(k) if k > 4096 => Err(lines.invalid(
            ctx,
            "upscaling_factor",
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
