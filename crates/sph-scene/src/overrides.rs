//! Overrides of a scene file's keys: `solver.friction_angle_deg = 33` given by a program (or
//! `--set` on the command line) instead of an edited file.
//!
//! Each override names a key by its dotted path in the file (`simulation.duration`,
//! `solver.friction_angle_deg`, `fluid[0].min`) and gives its value. The overrides are
//! applied to the parsed TOML document before serde reads it, so that a value of the wrong
//! type, an unknown key (reported with the keys its table has) and an out-of-range value are
//! refused exactly as in a file, at the same field path. A value given as an override has no
//! line in the file: its messages say "given as an override" where a file's value would say
//! its line.

use std::borrow::Cow;
use std::path::Path;

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::error::Ctx;
use crate::override_span::override_span;
use crate::SceneError;

/// One override: a key of the scene file, by its dotted path, and the value it takes.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The key's dotted path in the file: table names and keys joined by `.`, an element of
    /// an array of tables as `fluid[0]` (e.g. `solver.friction_angle_deg`, `fluid[1].max`).
    pub path: String,
    /// The value, as the file would write it.
    pub value: toml::Value,
}

impl Override {
    /// The override of the key at `path` with `value`.
    pub fn new(path: impl Into<String>, value: toml::Value) -> Self {
        Self {
            path: path.into(),
            value,
        }
    }

    /// Reads `KEY=VALUE` (the command line's `--set`): `VALUE` is TOML (`33.0`, `"pbf"`,
    /// `[0.0, 1.0, 0.0]`, `true`); a bare word that is not TOML is taken as a string
    /// (`boundary.model=collision`).
    pub fn parse(arg: &str) -> Result<Self, String> {
        let (path, value) = arg
            .split_once('=')
            .ok_or_else(|| format!("`{arg}`: expected KEY=VALUE (e.g. solver.substeps=8)"))?;
        let (path, value) = (path.trim(), value.trim());
        if path.is_empty() {
            return Err(format!("`{arg}`: no key before `=`"));
        }
        let doc = format!("v = {value}");
        let value = match doc.parse::<toml::Table>() {
            Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(value.into())),
            Err(_) => toml::Value::String(value.into()),
        };
        Ok(Self::new(path, value))
    }

    /// The override as `KEY=VALUE` (the value in TOML), which [`Override::parse`] reads back.
    pub fn to_arg(&self) -> String {
        format!("{}={}", self.path, self.value)
    }
}

/// One step of a dotted path: a key, or a key and an index into its array of tables.
#[derive(Debug, PartialEq)]
struct Step<'p> {
    key: &'p str,
    index: Option<usize>,
}

/// The steps of `path` (`fluid[0].min` → `fluid`[0], `min`).
fn steps(path: &str) -> Result<Vec<Step<'_>>, String> {
    path.split('.')
        .map(|part| {
            let (key, index) = match part.split_once('[') {
                None => (part, None),
                Some((key, rest)) => {
                    let digits = rest
                        .strip_suffix(']')
                        .ok_or_else(|| format!("`{part}`: an index is written `name[0]`"))?;
                    let i = digits
                        .parse::<usize>()
                        .map_err(|_| format!("`{part}`: the index must be a whole number"))?;
                    (key, Some(i))
                }
            };
            let bare = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
            if key.is_empty() || !key.chars().all(bare) {
                return Err(format!(
                    "`{part}`: not a key (keys are letters, digits, `_` and `-`, joined by `.`)"
                ));
            }
            Ok(Step { key, index })
        })
        .collect()
}

/// The TOML document `v = VALUE` of each override's value, which [`apply`] parses: made
/// before the scene's document, whose values then borrow from both.
pub(crate) fn value_documents(
    file: &Path,
    overrides: &[Override],
) -> Result<Vec<String>, SceneError> {
    let ctx = Ctx::new(file);
    overrides
        .iter()
        .map(|o| {
            let mut table = toml::Table::new();
            table.insert("v".into(), o.value.clone());
            toml::to_string(&table)
                .map_err(|e| ctx.invalid(&o.path, format!("not a TOML value: {e}")))
        })
        .collect()
}

/// The value of the document `v = VALUE` whose every span marks it as an override.
fn document_value(text: &str) -> Result<Spanned<DeValue<'_>>, String> {
    let doc = DeTable::parse(text).map_err(|e| format!("not a TOML value: {e}"))?;
    let v = doc
        .into_inner()
        .remove("v")
        .ok_or_else(|| "not a TOML value".to_string())?;
    Ok(respan(v.into_inner()))
}

/// `v` with its span and those of everything inside it set to [`override_span`].
fn respan(v: DeValue<'_>) -> Spanned<DeValue<'_>> {
    let v = match v {
        DeValue::Table(t) => {
            let mut out = DeTable::new();
            for (k, item) in t {
                out.insert(
                    Spanned::new(override_span(), k.into_inner()),
                    respan(item.into_inner()),
                );
            }
            DeValue::Table(out)
        }
        DeValue::Array(mut items) => {
            for item in items.iter_mut() {
                let inner = std::mem::replace(item.get_mut(), DeValue::Boolean(false));
                *item = respan(inner);
            }
            DeValue::Array(items)
        }
        other => other,
    };
    Spanned::new(override_span(), v)
}

/// The keys a table has, for a message (`a`, `b`, `c`).
fn keys_of(t: &DeTable<'_>) -> String {
    let keys: Vec<String> = t.keys().map(|k| format!("`{}`", k.get_ref())).collect();
    if keys.is_empty() {
        "none".into()
    } else {
        keys.join(", ")
    }
}

/// Applies `o` to the document `doc`: the tables on its path are created when missing; an
/// element of an array of tables must exist. The key itself may be one the file does not
/// write (serde then checks it as it checks the file's keys).
fn apply_one<'i>(
    ctx: &Ctx,
    doc: &mut DeTable<'i>,
    o: &Override,
    value_doc: &'i str,
) -> Result<(), SceneError> {
    let steps = steps(&o.path).map_err(|reason| ctx.invalid(&o.path, reason))?;
    let value = document_value(value_doc).map_err(|reason| ctx.invalid(&o.path, reason))?;
    let mut table = doc;
    let mut at = String::new();
    for (n, step) in steps.iter().enumerate() {
        let last = n + 1 == steps.len();
        let parent = if at.is_empty() {
            "the document".to_string()
        } else {
            format!("`{at}`")
        };
        if !at.is_empty() {
            at.push('.');
        }
        at.push_str(step.key);
        if last && step.index.is_none() {
            // Replace the key as well: the value is no longer the file's (its line).
            table.remove(step.key);
            table.insert(
                Spanned::new(override_span(), Cow::Owned(step.key.into())),
                value,
            );
            return Ok(());
        }
        if !table.contains_key(step.key) {
            if step.index.is_some() {
                return Err(ctx.invalid(
                    &at,
                    format!(
                        "the scene has no `{at}` (the keys of {parent}: {})",
                        keys_of(table)
                    ),
                ));
            }
            table.insert(
                Spanned::new(override_span(), Cow::Owned(step.key.into())),
                Spanned::new(override_span(), DeValue::Table(DeTable::new())),
            );
        }
        let Some(entry) = table.get_mut(step.key) else {
            return Err(ctx.invalid(&at, "missing"));
        };
        let entry = match (step.index, entry.get_mut()) {
            (None, e) => e,
            (Some(i), DeValue::Array(items)) => {
                let count = items.len();
                let Some(item) = items.get_mut(i) else {
                    return Err(ctx.invalid(
                        format!("{at}[{i}]"),
                        format!(
                            "the scene has {count} elements of `{at}` (indices 0 to {})",
                            count.max(1) - 1
                        ),
                    ));
                };
                at.push_str(&format!("[{i}]"));
                if last {
                    *item = value;
                    return Ok(());
                }
                item.get_mut()
            }
            (Some(_), other) => {
                let kind = other.type_str();
                return Err(ctx.invalid(&at, format!("is {kind}, not an array: it has no index")));
            }
        };
        match entry {
            DeValue::Table(t) => table = t,
            other => {
                let kind = other.type_str();
                return Err(ctx.invalid(
                    &at,
                    format!(
                        "is {kind}, not a table: `{}` cannot be set inside it",
                        o.path
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Applies `overrides` in order to the document of the scene file `file`; `value_docs` are
/// their [`value_documents`].
pub(crate) fn apply<'i>(
    file: &Path,
    doc: &mut DeTable<'i>,
    overrides: &[Override],
    value_docs: &'i [String],
) -> Result<(), SceneError> {
    let ctx = Ctx::new(file);
    overrides
        .iter()
        .zip(value_docs)
        .try_for_each(|(o, v)| apply_one(&ctx, doc, o, v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_split_into_keys_and_indices() {
        let s = steps("fluid[1].min").unwrap();
        assert_eq!(
            s,
            [
                Step {
                    key: "fluid",
                    index: Some(1)
                },
                Step {
                    key: "min",
                    index: None
                }
            ]
        );
        assert!(steps("solver..kind").is_err());
        assert!(steps("fluid[x].min").is_err());
        assert!(steps("fluid[1.min").is_err());
    }

    #[test]
    fn command_line_values_are_toml_or_else_strings() {
        let o = Override::parse("solver.friction_angle_deg = 33.5").unwrap();
        assert_eq!(o.path, "solver.friction_angle_deg");
        assert_eq!(o.value, toml::Value::Float(33.5));
        let o = Override::parse("boundary.model=collision").unwrap();
        assert_eq!(o.value, toml::Value::String("collision".into()));
        let o = Override::parse("simulation.gravity=[0, -1.5, 0]").unwrap();
        assert_eq!(o.value.as_array().map(Vec::len), Some(3));
        assert!(Override::parse("no-equals-sign").is_err());
        for o in [
            Override::new("a.b", toml::Value::Float(0.1)),
            Override::new("a.b", toml::Value::Float(f64::INFINITY)),
            Override::new("a.b", toml::Value::String("x = \"y\"".into())),
            Override::new("a", toml::Value::Array(vec![1.into(), 2.5.into()])),
        ] {
            assert_eq!(
                Override::parse(&o.to_arg()).as_ref(),
                Ok(&o),
                "{}",
                o.to_arg()
            );
        }
    }
}
