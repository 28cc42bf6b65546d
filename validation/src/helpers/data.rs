//! CSV output and reference-data input.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context as _, Result};

use crate::{Context, REFERENCE_DATA_ENV};

/// Writes named `f64` columns (all the same length) as CSV with a header row.
pub fn write_csv_columns(path: &Path, columns: &[(&str, &[f64])]) -> Result<()> {
    let n = columns.first().map_or(0, |c| c.1.len());
    if let Some((name, col)) = columns.iter().find(|c| c.1.len() != n) {
        bail!(
            "{}: column {name:?} has {} rows, the first column has {n}",
            path.display(),
            col.len()
        );
    }
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("creating {}", path.display()))?;
    w.write_record(columns.iter().map(|c| c.0))?;
    for i in 0..n {
        w.write_record(columns.iter().map(|c| format_value(c.1[i])))?;
    }
    w.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Writes rows of text fields under `headers` as CSV.
pub fn write_csv_rows<I, S>(path: &Path, headers: &[&str], rows: I) -> Result<()>
where
    I: IntoIterator<Item = Vec<S>>,
    S: AsRef<str>,
{
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("creating {}", path.display()))?;
    w.write_record(headers)?;
    for (k, row) in rows.into_iter().enumerate() {
        if row.len() != headers.len() {
            bail!(
                "{}: row {k} has {} fields, expected {} ({headers:?})",
                path.display(),
                row.len(),
                headers.len()
            );
        }
        w.write_record(row.iter().map(|s| s.as_ref()))?;
    }
    w.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Shortest representation that round-trips (`{}` of f64 does), `NaN` kept as text.
fn format_value(x: f64) -> String {
    format!("{x}")
}

/// One data row of a reference CSV file with its line number in the file.
#[derive(Debug, Clone)]
pub struct ReferenceRow {
    /// 1-based line number in the file.
    pub line: u64,
    /// The fields, trimmed.
    pub fields: Vec<String>,
}

/// A reference CSV file: header + rows. Lines starting with `#` are comments.
#[derive(Debug, Clone)]
pub struct ReferenceTable {
    /// Path as given (relative to the reference-data directory), for messages.
    pub name: String,
    /// Absolute path of the file.
    pub path: PathBuf,
    /// Column names.
    pub headers: Vec<String>,
    /// Data rows.
    pub rows: Vec<ReferenceRow>,
}

impl ReferenceTable {
    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// `true` without data rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    fn column(&self, col: &str) -> Result<usize> {
        self.headers.iter().position(|h| h == col).ok_or_else(|| {
            anyhow!(
                "reference file {}: no column {col:?} (columns: {})",
                self.path.display(),
                self.headers.join(", ")
            )
        })
    }

    /// The text of column `col` in row `row`.
    pub fn text(&self, row: usize, col: &str) -> Result<&str> {
        let c = self.column(col)?;
        Ok(self.rows[row].fields[c].as_str())
    }

    /// Column `col` of row `row` parsed as a number; the error names file, line and column.
    pub fn number(&self, row: usize, col: &str) -> Result<f64> {
        let text = self.text(row, col)?;
        text.parse::<f64>().map_err(|_| {
            anyhow!(
                "reference file {}, line {}: column {col:?} = {text:?} is not a number",
                self.path.display(),
                self.rows[row].line
            )
        })
    }

    /// Index of the rows whose columns equal the given values.
    pub fn find_all(&self, key: &[(&str, &str)]) -> Result<Vec<usize>> {
        let cols: Vec<(usize, &str)> = key
            .iter()
            .map(|(c, v)| Ok((self.column(c)?, *v)))
            .collect::<Result<_>>()?;
        Ok((0..self.rows.len())
            .filter(|&i| cols.iter().all(|(c, v)| self.rows[i].fields[*c] == *v))
            .collect())
    }

    /// The single row whose columns equal the given values (error if none or several).
    pub fn find(&self, key: &[(&str, &str)]) -> Result<usize> {
        let rows = self.find_all(key)?;
        match rows.as_slice() {
            [i] => Ok(*i),
            [] => bail!(
                "reference file {}: no row with {key:?}",
                self.path.display()
            ),
            _ => bail!(
                "reference file {}: several rows with {key:?} (lines {:?})",
                self.path.display(),
                rows.iter().map(|&i| self.rows[i].line).collect::<Vec<_>>()
            ),
        }
    }
}

/// Loads `<reference dir>/<relative>` and checks that the `required` columns exist.
/// Errors name the file (and line for malformed rows) and say how to point
/// `SPH_REFERENCE_DATA` elsewhere.
pub fn load_reference_csv(
    ctx: &Context,
    relative: &str,
    required: &[&str],
) -> Result<ReferenceTable> {
    load_reference_csv_from(&ctx.reference_dir, relative, required)
}

pub(crate) fn load_reference_csv_from(
    dir: &Path,
    relative: &str,
    required: &[&str],
) -> Result<ReferenceTable> {
    let path = dir.join(relative);
    if !path.is_file() {
        bail!(
            "reference file {} not found (reference-data directory {}; set {REFERENCE_DATA_ENV} \
             to use another one; see reference-data/README.md)",
            path.display(),
            dir.display()
        );
    }
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(false)
        .from_path(&path)
        .with_context(|| format!("opening reference file {}", path.display()))?;
    let headers: Vec<String> = reader
        .headers()
        .map_err(|e| malformed(&path, &e))?
        .iter()
        .map(str::to_string)
        .collect();
    let missing: Vec<&str> = required
        .iter()
        .copied()
        .filter(|r| !headers.iter().any(|h| h == r))
        .collect();
    if !missing.is_empty() {
        bail!(
            "reference file {}: missing required column(s) {} (header: {})",
            path.display(),
            missing.join(", "),
            headers.join(", ")
        );
    }
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| malformed(&path, &e))?;
        rows.push(ReferenceRow {
            line: record.position().map_or(0, |p| p.line()),
            fields: record.iter().map(str::to_string).collect(),
        });
    }
    Ok(ReferenceTable {
        name: relative.to_string(),
        path,
        headers,
        rows,
    })
}

fn malformed(path: &Path, e: &csv::Error) -> anyhow::Error {
    match e.position() {
        Some(p) => anyhow!(
            "reference file {}, line {}: malformed CSV: {e}",
            path.display(),
            p.line()
        ),
        None => anyhow!("reference file {}: malformed CSV: {e}", path.display()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("validation-test-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn reads_and_reports_errors() {
        let d = temp_dir("ref");
        std::fs::write(d.join("ok.csv"), "# comment\na, b\nx, 1.5\ny, oops\n").unwrap();
        let t = load_reference_csv_from(&d, "ok.csv", &["a", "b"]).unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(t.number(t.find(&[("a", "x")]).unwrap(), "b").unwrap(), 1.5);
        let err = t.number(1, "b").unwrap_err().to_string();
        assert!(err.contains("line 4"), "{err}");

        let err = load_reference_csv_from(&d, "ok.csv", &["a", "c"])
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing required column(s) c"), "{err}");
        let err = load_reference_csv_from(&d, "absent.csv", &[])
            .unwrap_err()
            .to_string();
        assert!(err.contains("absent.csv not found"), "{err}");

        std::fs::write(d.join("bad.csv"), "a,b\n1,2\n3\n").unwrap();
        let err = load_reference_csv_from(&d, "bad.csv", &[])
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 3"), "{err}");
        std::fs::remove_dir_all(&d).ok();
    }
}
