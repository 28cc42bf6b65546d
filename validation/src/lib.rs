//! Validation experiments: each reproduces a published figure, table or claim, writes its
//! data (CSV) and plots (PNG), and states pass/fail checks against bounds whose origin is
//! recorded (paper, definition, or error analysis).
//!
//! Run them with `cargo xtask validate` (quick mode) or `cargo xtask validate --full`; see
//! [`runner`] for the output layout (`<out>/<id>/verdict.json`, `<out>/summary.json`,
//! `<out>/report.md`).
//!
//! Adding an experiment: implement [`Experiment`] in a new module
//! `src/experiments/<paper>/<id>.rs` (the folder of the paper whose crates it validates,
//! [`papers::Paper`]; a folder `<id>/` with a `mod.rs` for a large one), put its reference
//! data in `reference-data/<id>/` with a `SOURCE.md`, and list it in
//! [`experiments::registry`]. The paper → crates → experiments → scenes → reference-data
//! table of `docs/papers.md` is generated from the registry ([`papers::experiment_table`]) and
//! checked by `cargo test -p validation`, as is that layout.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use indicatif::ProgressBar;
use serde::{Deserialize, Serialize};

pub mod deviations;
pub mod experiments;
pub mod helpers;
pub mod papers;
pub mod report;
pub mod runner;
pub mod scene_runs;
pub mod verdict;

pub use experiments::registry;

/// Environment variable overriding the reference-data directory.
pub const REFERENCE_DATA_ENV: &str = "SPH_REFERENCE_DATA";

/// The workspace root (`validation/..`), fixed at compile time.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from(".."))
}

/// The reference-data directory: `$SPH_REFERENCE_DATA` if set, else the workspace's
/// `reference-data/`.
pub fn reference_data_dir() -> PathBuf {
    match std::env::var_os(REFERENCE_DATA_ENV) {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => workspace_root().join("reference-data"),
    }
}

/// How much work the experiments do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Small sizes; every experiment finishes in seconds (the default).
    Quick,
    /// The sizes of the papers' figures; minutes.
    Full,
}

impl Mode {
    /// `"quick"` or `"full"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Mode::Quick => "quick",
            Mode::Full => "full",
        }
    }

    /// `quick` in quick mode, `full` otherwise.
    pub fn pick<T>(self, quick: T, full: T) -> T {
        match self {
            Mode::Quick => quick,
            Mode::Full => full,
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A reproduced figure, table or claim.
pub trait Experiment: Sync {
    /// Stable identifier, used for `--only` and as the output sub-directory
    /// (`"kernels"`, `"neighbour-search"`).
    fn id(&self) -> &'static str;
    /// The paper and figure/table/claim this experiment reproduces.
    fn source(&self) -> &'static str;
    /// The workspace crates (package directory names under `crates/`) whose results the
    /// experiment checks.
    fn crates(&self) -> &'static [&'static str];
    /// The shipped scenes (`scenes/<name>.toml`) the experiment runs or edits, by name.
    fn scenes(&self) -> &'static [&'static str] {
        &[]
    }
    /// The Rust path of the experiment's type; its module path names the experiment's paper
    /// folder and file ([`papers::Paper::of_experiment`]). Not meant to be overridden.
    fn type_path(&self) -> &'static str {
        std::any::type_name::<Self>()
    }
    /// Runs the experiment, writing files under [`Context::out_dir`].
    fn run(&self, ctx: &mut Context) -> anyhow::Result<Outcome>;
}

/// A file an experiment produced, listed in the report.
#[derive(Debug, Clone, Serialize)]
pub struct Artifact {
    /// Path relative to the experiment's output directory.
    pub file: String,
    /// One-line description (the figure caption for plots).
    pub caption: String,
}

/// What an experiment gets to work with.
#[derive(Debug)]
pub struct Context {
    /// Quick or full.
    pub mode: Mode,
    /// `<out>/<id>/`, created before [`Experiment::run`].
    pub out_dir: PathBuf,
    /// Root of the reference data (see [`reference_data_dir`]).
    pub reference_dir: PathBuf,
    /// Progress bar of this experiment: set its length and advance it.
    pub progress: ProgressBar,
    plots: Vec<Artifact>,
    files: Vec<Artifact>,
}

impl Context {
    /// A context writing to `out_dir` (which must exist).
    pub fn new(
        mode: Mode,
        out_dir: PathBuf,
        reference_dir: PathBuf,
        progress: ProgressBar,
    ) -> Self {
        Self {
            mode,
            out_dir,
            reference_dir,
            progress,
            plots: Vec::new(),
            files: Vec::new(),
        }
    }

    /// `out_dir/file`.
    pub fn path(&self, file: &str) -> PathBuf {
        self.out_dir.join(file)
    }

    /// Records a plot (PNG in `out_dir`) for the report.
    pub fn add_plot(&mut self, file: &str, caption: impl Into<String>) {
        self.plots.push(Artifact {
            file: file.to_string(),
            caption: caption.into(),
        });
    }

    /// Records a data file (CSV in `out_dir`) for the report.
    pub fn add_file(&mut self, file: &str, caption: impl Into<String>) {
        self.files.push(Artifact {
            file: file.to_string(),
            caption: caption.into(),
        });
    }

    /// Plots recorded so far.
    pub fn plots(&self) -> &[Artifact] {
        &self.plots
    }

    /// Data files recorded so far.
    pub fn files(&self) -> &[Artifact] {
        &self.files
    }

    /// Prints a line above the progress bar (for diagnostics while running).
    pub fn println(&self, line: impl AsRef<str>) {
        self.progress.println(line);
    }
}

/// A pass/fail comparison of a measured value against a bound.
#[derive(Debug, Clone, Serialize)]
pub struct Check {
    /// `"<what>/<case>"`, e.g. `"normalisation/poly6/f64"`.
    pub name: String,
    /// The measured value (a NaN value always fails).
    pub value: f64,
    /// The bound as text, e.g. `"< 1e-4"`, `"== 0"`, `"in [0.9, 1.1]"`.
    pub bound: String,
    /// Whether `value` satisfies the bound.
    pub pass: bool,
    /// Where the bound comes from (paper, definition, error analysis).
    pub origin: String,
}

impl Check {
    fn make(
        name: impl Into<String>,
        value: f64,
        bound: String,
        pass: bool,
        origin: impl Into<String>,
    ) -> Self {
        Self {
            name: name.into(),
            value,
            bound,
            pass: pass && !value.is_nan(),
            origin: origin.into(),
        }
    }

    /// Passes when `value < bound`.
    pub fn less_than(
        name: impl Into<String>,
        value: f64,
        bound: f64,
        origin: impl Into<String>,
    ) -> Self {
        Self::make(
            name,
            value,
            format!("< {}", fmt_num(bound)),
            value < bound,
            origin,
        )
    }

    /// Passes when `value <= bound`.
    pub fn at_most(
        name: impl Into<String>,
        value: f64,
        bound: f64,
        origin: impl Into<String>,
    ) -> Self {
        Self::make(
            name,
            value,
            format!("<= {}", fmt_num(bound)),
            value <= bound,
            origin,
        )
    }

    /// Passes when `value > bound`.
    pub fn greater_than(
        name: impl Into<String>,
        value: f64,
        bound: f64,
        origin: impl Into<String>,
    ) -> Self {
        Self::make(
            name,
            value,
            format!("> {}", fmt_num(bound)),
            value > bound,
            origin,
        )
    }

    /// Passes when `lo <= value <= hi`.
    pub fn within(
        name: impl Into<String>,
        value: f64,
        lo: f64,
        hi: f64,
        origin: impl Into<String>,
    ) -> Self {
        Self::make(
            name,
            value,
            format!("in [{}, {}]", fmt_num(lo), fmt_num(hi)),
            lo <= value && value <= hi,
            origin,
        )
    }

    /// Passes when `value == expected` exactly (counts, exact algorithms).
    pub fn equals(
        name: impl Into<String>,
        value: f64,
        expected: f64,
        origin: impl Into<String>,
    ) -> Self {
        Self::make(
            name,
            value,
            format!("== {}", fmt_num(expected)),
            value == expected,
            origin,
        )
    }

    /// Passes when `|value − expected| <= tol · |expected|`.
    pub fn rel_close(
        name: impl Into<String>,
        value: f64,
        expected: f64,
        tol: f64,
        origin: impl Into<String>,
    ) -> Self {
        let ok = (value - expected).abs() <= tol * expected.abs();
        Self::make(
            name,
            value,
            format!("{} ± {} rel.", fmt_num(expected), fmt_num(tol)),
            ok,
            origin,
        )
    }
}

/// The result of one experiment.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Outcome {
    /// Named measurements (reported, not judged).
    pub metrics: BTreeMap<String, f64>,
    /// Pass/fail checks.
    pub checks: Vec<Check>,
    /// Free text lines for the report (conventions, caveats, findings).
    pub notes: Vec<String>,
}

impl Outcome {
    /// An empty outcome.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records a metric (replacing one of the same name).
    pub fn metric(&mut self, name: impl Into<String>, value: f64) {
        self.metrics.insert(name.into(), value);
    }

    /// Records a check.
    pub fn check(&mut self, check: Check) {
        self.checks.push(check);
    }

    /// Records a note.
    pub fn note(&mut self, line: impl Into<String>) {
        self.notes.push(line.into());
    }

    /// `true` when every check passes.
    pub fn all_pass(&self) -> bool {
        self.checks.iter().all(|c| c.pass)
    }
}

/// Compact number formatting for bounds, tables and terminal output: integers as
/// integers, moderate magnitudes with up to 4 significant digits, the rest in `e` notation.
pub fn fmt_num(x: f64) -> String {
    if x.is_nan() {
        return "NaN".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if x == x.trunc() && x.abs() < 1e9 {
        return format!("{}", x as i64);
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let s = format!("{:.4}", x);
        let s = s.trim_end_matches('0').trim_end_matches('.');
        // keep 4 significant digits for values < 1
        if a < 1.0 {
            let digits = (-a.log10()).floor() as usize + 4;
            let s = format!("{:.*}", digits, x);
            return s.trim_end_matches('0').trim_end_matches('.').to_string();
        }
        s.to_string()
    } else {
        let s = format!("{:.3e}", x);
        // 1.000e-4 -> 1e-4, 2.500e-7 -> 2.5e-7
        match s.split_once('e') {
            Some((m, e)) => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            None => s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_fails_every_check() {
        assert!(!Check::less_than("a", f64::NAN, 1.0, "").pass);
        assert!(!Check::greater_than("a", f64::NAN, 1.0, "").pass);
        assert!(!Check::within("a", f64::NAN, 0.0, 1.0, "").pass);
        assert!(!Check::equals("a", f64::NAN, f64::NAN, "").pass);
        assert!(!Check::at_most("a", f64::NAN, f64::INFINITY, "").pass);
    }

    #[test]
    fn bounds_format() {
        assert_eq!(Check::less_than("a", 0.5, 1e-4, "").bound, "< 1e-4");
        assert_eq!(Check::equals("a", 0.0, 0.0, "").bound, "== 0");
        assert_eq!(Check::within("a", 1.0, 0.9, 1.1, "").bound, "in [0.9, 1.1]");
        assert!(Check::within("a", 1.0, 0.9, 1.1, "").pass);
        assert_eq!(fmt_num(2.5e-7), "2.5e-7");
        assert_eq!(fmt_num(0.0123456), "0.01235");
        assert_eq!(fmt_num(12.5), "12.5");
    }
}
