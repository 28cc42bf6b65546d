//! The `[solver]` table, read in two steps so that errors keep the field path and line.
//!
//! [`SolverSpec`] deserializes as an internally tagged enum, but serde buffers an internally
//! tagged table before handing it to the variant, and the buffer has neither the TOML spans
//! nor `serde_path_to_error`'s path: an unknown field would be reported on `solver`, at the
//! table's position. So `kind` is read first, with the rest of the document (`RawScene`; an
//! unknown kind names the allowed ones), then here the variant struct from the same table
//! without `kind` (its `deny_unknown_fields` refuses the fields of the other solvers).
//!
//! The settings shared by several solvers are `#[serde(flatten)]`ed into the variants
//! (`CommonSettings`, `iisph_granular::IisphSettings`: the parts listed in the solver's
//! registration line), and serde buffers flattened fields too: a wrong
//! value there, or an unknown field, comes without path or line. So the shared parts are
//! read on their own first (they accept unknown fields), which reports their errors at the
//! field, and an unknown field is named with its line from the document. The values are
//! range-checked later, by `Scene::check` (the parameters' own `validate`).

use serde::de::DeserializeOwned;
use toml::de::{DeValue, ValueDeserializer};

use super::SolverTable;
use crate::error::{serde_error, Ctx};
use crate::solver_spec::SettingsReader;
use crate::{SceneError, SolverKind, SolverSpec};

/// Reads the `[solver]` table `table` of the scene text `text`, whose `kind` has been read
/// already.
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
    if t.contains_key("periodic") {
        return Err(ctx.invalid(
            "solver.periodic",
            "the periodic axes are the scene's, not the solver's: write them under [boundary] (`[boundary] periodic = [...]`)",
        ));
    }
    // The flattened parts first, for their errors' paths and lines (see `SolverSpec::read`).
    SolverSpec::read(
        kind,
        &mut Reader {
            ctx,
            text,
            kind,
            table,
        },
    )
}

/// The `[solver]` table without `kind`, read by [`SolverSpec::read`].
struct Reader<'a, 'i> {
    ctx: &'a Ctx<'a>,
    text: &'a str,
    kind: SolverKind,
    table: SolverTable<'i>,
}

impl SettingsReader<SceneError> for Reader<'_, '_> {
    fn part<T: DeserializeOwned>(&mut self) -> Result<(), SceneError> {
        variant::<T>(self.ctx, self.text, self.kind, self.table.clone()).map(|_| ())
    }

    fn settings<T: DeserializeOwned>(&mut self) -> Result<T, SceneError> {
        variant::<T>(self.ctx, self.text, self.kind, self.table.clone())
    }
}

/// The variant struct of `kind` from the table without `kind`.
fn variant<T: DeserializeOwned>(
    ctx: &Ctx,
    text: &str,
    kind: SolverKind,
    table: SolverTable<'_>,
) -> Result<T, SceneError> {
    let note = format!("kind = \"{}\" has no such field", kind.name());
    serde_path_to_error::deserialize(ValueDeserializer::from(table)).map_err(|e| {
        let err = serde_error(ctx.file, text, "solver", &note, &e);
        // An error serde met in a flattened (buffered) part is placed at the table: give the
        // field's own line instead.
        match err {
            SceneError::Syntax { file, field, .. } if e.path().iter().next().is_none() => {
                let at = ctx.lines.and_then(|l| l.location(&field));
                let at = at.map(|at| format!(" ({at})")).unwrap_or_default();
                let message = e.inner().message().trim();
                // The note explains an unknown field only; a missing one is not the kind's.
                let reason = if message.starts_with("unknown field `") {
                    format!("{message}{at}; {note}")
                } else {
                    format!("{message}{at}")
                };
                SceneError::Syntax {
                    file,
                    field,
                    reason,
                }
            }
            other => other,
        }
    })
}
