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
use crate::error::{serde_error, Ctx};
use crate::{PbfSpec, PcisphSpec, SceneError, SolverKind, SolverSpec};

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
    let spec = match kind {
        SolverKind::Pbf => SolverSpec::Pbf(variant(ctx, text, kind, table)?),
        SolverKind::Pcisph => SolverSpec::Pcisph(variant(ctx, text, kind, table)?),
    };
    match &spec {
        SolverSpec::Pbf(s) => check_pbf(ctx, s)?,
        SolverSpec::Pcisph(s) => check_pcisph(ctx, s)?,
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
