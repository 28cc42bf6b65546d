//! [`SceneError`] and the crate's helpers for building it: the error context [`Ctx`] with
//! the value checks shared by the parser and the mesh placement, and the translation of
//! TOML/serde errors into a field path and a reason with line and column.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sph_core::Aabb;

use crate::geom::{v3, AXES};
use crate::override_span::is_override_span;

/// Errors of scene loading and building. Every variant names the scene file, the field path
/// and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{}: cannot read the scene file: {reason}", file.display())]
    Read {
        /// The scene file.
        file: PathBuf,
        /// Operating-system reason.
        reason: String,
    },
    /// TOML syntax error, wrong type, unknown or missing field.
    #[error("{}: {field}: {reason}", file.display())]
    Syntax {
        /// The scene file.
        file: PathBuf,
        /// Field path (`solver.substeps`), or `<document>` for a syntax error.
        field: String,
        /// What is wrong, with line and column.
        reason: String,
    },
    /// A value is out of range or inconsistent with others.
    #[error("{}: {field}: {reason}", file.display())]
    Invalid {
        /// The scene file.
        file: PathBuf,
        /// Field path, e.g. `fluid[1].min`.
        field: String,
        /// What is wrong, ending with the field's line in the scene file (`(line 7)`) when
        /// the error was found while parsing it.
        reason: String,
    },
    /// A mesh file is missing, unreadable, malformed or not closed.
    #[error("{}: {field}: mesh {}: {reason}", file.display(), mesh.display())]
    Mesh {
        /// The scene file.
        file: PathBuf,
        /// Field path of the mesh's `path`, e.g. `solid[0].path`.
        field: String,
        /// The mesh file, resolved against the scene file's directory.
        mesh: PathBuf,
        /// What is wrong, with the line of the mesh file (for an open mesh: the first
        /// offending edge and the face it belongs to).
        reason: String,
    },
}

impl SceneError {
    /// The field path the error refers to.
    pub fn field(&self) -> &str {
        match self {
            SceneError::Read { .. } => "<file>",
            SceneError::Syntax { field, .. }
            | SceneError::Invalid { field, .. }
            | SceneError::Mesh { field, .. } => field,
        }
    }
}

/// Where errors are reported: the scene file, a prefix for reasons, and (while parsing) the
/// line of each field.
pub(crate) struct Ctx<'a> {
    /// The scene file.
    pub file: &'a Path,
    /// Prefix for reasons (e.g. `"with the [quick] overrides: "`).
    pub note: &'a str,
    /// The line of each field path of the scene text, when parsing it.
    pub lines: Option<&'a FieldLines>,
}

impl<'a> Ctx<'a> {
    /// A context for `file` without a note or lines.
    pub fn new(file: &'a Path) -> Self {
        Ctx {
            file,
            note: "",
            lines: None,
        }
    }

    /// An [`SceneError::Invalid`] for `field`, its reason followed by the field's line when
    /// known (or the line of the closest enclosing table or array element).
    pub fn invalid(&self, field: impl Into<String>, reason: impl AsRef<str>) -> SceneError {
        let field = field.into();
        let mut reason = format!("{}{}", self.note, reason.as_ref());
        if let Some(at) = self.lines.and_then(|l| l.location(&field)) {
            let _ = write!(reason, " ({at})");
        }
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            field,
            reason,
        }
    }

    /// `v` is finite and > 0.
    pub fn positive(&self, field: &str, v: f64) -> Result<(), SceneError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.invalid(field, format!("must be finite and > 0, got {v}")))
        }
    }

    /// Every component of `v` is finite.
    pub fn finite3(&self, field: &str, v: &[f64; 3]) -> Result<(), SceneError> {
        match (0..3).find(|&a| !v[a].is_finite()) {
            Some(a) => Err(self.invalid(
                field,
                format!("component {} is not finite ({})", AXES[a], v[a]),
            )),
            None => Ok(()),
        }
    }

    /// A box with finite corners and `min < max` on every axis.
    pub fn check_box(
        &self,
        field: &str,
        min: &[f64; 3],
        max: &[f64; 3],
    ) -> Result<Aabb<f64>, SceneError> {
        self.finite3(&format!("{field}.min"), min)?;
        self.finite3(&format!("{field}.max"), max)?;
        if let Some(a) = (0..3).find(|&a| min[a] >= max[a]) {
            return Err(self.invalid(
                format!("{field}.min"),
                format!(
                    "min must be < max on every axis ({}: min {} >= max {})",
                    AXES[a], min[a], max[a]
                ),
            ));
        }
        Ok(Aabb {
            min: v3(*min),
            max: v3(*max),
        })
    }
}

/// The 1-based line of every field path of a TOML document (`simulation.frame_dt`,
/// `fluid[1]`, `fluid[1].min`, ...): the line of its key, or for an element of an array of
/// tables the line where the element starts; 0 for a key set by an override
/// ([`crate::Override`]), which has no line.
#[derive(Debug, Default)]
pub(crate) struct FieldLines(BTreeMap<String, usize>);

impl FieldLines {
    /// The lines of the fields of the parsed document `doc` of `text`.
    pub fn new(text: &str, doc: &toml::de::DeTable<'_>) -> Self {
        let mut map = BTreeMap::new();
        collect_lines(text, doc, "", &mut map);
        FieldLines(map)
    }

    /// The field paths written in the file directly under `table` (e.g. `solver`).
    pub fn fields_under<'s>(&'s self, table: &'s str) -> impl Iterator<Item = &'s str> + 's {
        self.0.keys().filter_map(move |k| {
            k.strip_prefix(table)
                .and_then(|rest| rest.strip_prefix('.'))
                .filter(|name| !name.contains(['.', '[']))
        })
    }

    /// Where `field` (else its closest parent path that is known) was given, for a message:
    /// `line 7`, or `given as an override`.
    pub fn location(&self, field: &str) -> Option<String> {
        let mut f = field;
        loop {
            match self.0.get(f) {
                Some(0) => return Some(OVERRIDE_LOCATION.into()),
                Some(&l) => return Some(format!("line {l}")),
                None => {}
            }
            let cut = f.rfind(['.', '['])?;
            f = &f[..cut];
        }
    }
}

fn collect_lines(
    text: &str,
    table: &toml::de::DeTable<'_>,
    prefix: &str,
    out: &mut BTreeMap<String, usize>,
) {
    use toml::de::DeValue;
    for (key, value) in table {
        let path = if prefix.is_empty() {
            key.get_ref().to_string()
        } else {
            format!("{prefix}.{}", key.get_ref())
        };
        out.insert(path.clone(), line_of_span(text, key.span().start));
        match value.get_ref() {
            DeValue::Table(t) => collect_lines(text, t, &path, out),
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    if let DeValue::Table(t) = item.get_ref() {
                        let p = format!("{path}[{i}]");
                        out.insert(p.clone(), line_of_span(text, item.span().start));
                        collect_lines(text, t, &p, out);
                    }
                }
            }
            _ => {}
        }
    }
}

/// What messages say of a value given as an override instead of its line.
pub(crate) const OVERRIDE_LOCATION: &str = "given as an override";

/// The 1-based line of a span starting at `start`, 0 for an override's.
fn line_of_span(text: &str, start: usize) -> usize {
    if is_override_span(start) {
        0
    } else {
        line_col(text, start).0
    }
}

/// Line and column (1-based) of a byte offset.
pub(crate) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let mut line = 1;
    let mut col = 1;
    for (i, ch) in text.char_indices() {
        if i >= offset {
            break;
        }
        if ch == '\n' {
            line += 1;
            col = 1;
        } else {
            col += 1;
        }
    }
    (line, col)
}

/// The message of a TOML error with its line and column in `text`.
pub(crate) fn toml_reason(text: &str, e: &toml::de::Error) -> String {
    let mut s = e.message().trim().to_string();
    match e.span() {
        Some(span) if is_override_span(span.start) => {
            let _ = write!(s, " ({OVERRIDE_LOCATION})");
        }
        Some(span) => {
            let (l, c) = line_col(text, span.start);
            let _ = write!(s, " (line {l}, column {c})");
        }
        None => {}
    }
    s
}

/// A [`SceneError::Syntax`] for a TOML syntax error (no field).
pub(crate) fn document_error(file: &Path, text: &str, e: &toml::de::Error) -> SceneError {
    SceneError::Syntax {
        file: file.to_path_buf(),
        field: "<document>".into(),
        reason: toml_reason(text, e),
    }
}

/// A [`SceneError::Syntax`] for a serde error met while deserializing the value at field
/// path `prefix` (`""` for the document): the field path is `prefix` + the path serde
/// reports, with the field itself for unknown and missing fields; `note` (if not empty) is
/// added to the reason of an unknown field.
pub(crate) fn serde_error(
    file: &Path,
    text: &str,
    prefix: &str,
    note: &str,
    e: &serde_path_to_error::Error<toml::de::Error>,
) -> SceneError {
    let mut field = e.path().to_string();
    if field == "." {
        field.clear();
    }
    let mut field = match (prefix.is_empty(), field.is_empty()) {
        (true, _) => field,
        (false, true) => prefix.to_string(),
        (false, false) => format!("{prefix}.{field}"),
    };
    let mut reason = toml_reason(text, e.inner());
    // Unknown and missing fields: name the field itself.
    for prefix in ["unknown field `", "missing field `"] {
        if let Some(rest) = reason.strip_prefix(prefix) {
            if let Some(end) = rest.find('`') {
                let name = &rest[..end];
                let already = field == name || field.ends_with(&format!(".{name}"));
                if !already {
                    field = if field.is_empty() {
                        name.to_string()
                    } else {
                        format!("{field}.{name}")
                    };
                }
            }
        }
    }
    if !note.is_empty() && reason.starts_with("unknown field `") {
        reason = format!("{reason}; {note}");
    }
    if field.is_empty() {
        field = "<document>".into();
    }
    SceneError::Syntax {
        file: file.to_path_buf(),
        field,
        reason,
    }
}
