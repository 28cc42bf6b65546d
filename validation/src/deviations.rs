//! Documented deviations: checks whose miss is a reviewed finding, not a bug.
//!
//! The list lives in one file, `reference-data/deviations.toml`, one `[[deviation]]` table per
//! check:
//!
//! ```toml
//! [[deviation]]
//! experiment = "pbf-stability"          # experiment id
//! check = "pcisph_unstable/substeps=5"  # the check's name, exactly
//! modes = ["quick", "full"]             # where the miss is documented
//! seen_quick = "stable at 5 substeps"   # the figures seen (free text)
//! seen_full = "..."
//! explanation = """First line: the one-line summary shown on the console.
//! More lines: why."""
//! evidence = "where the figures come from (command, output files)"
//! ```
//!
//! The runner turns each check into a [`CheckVerdict`]: a failed check listed here (for the
//! mode being run) is a `deviation`; a listed check that now **passes** is an
//! `unexpected-pass` and fails the run (as pytest's strict xfail), so the list stays true; a
//! listed check the experiment no longer produces is reported as a stale entry and fails the
//! run too.

use std::path::Path;

use anyhow::{bail, Context as _, Result};
use serde::{Deserialize, Serialize};

use crate::{Check, Mode};

/// File name of the deviations list inside the reference-data directory.
pub const DEVIATIONS_FILE: &str = "deviations.toml";

/// One documented deviation.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Deviation {
    /// Experiment id.
    pub experiment: String,
    /// Check name, exactly as the experiment reports it.
    pub check: String,
    /// Modes in which the miss is documented (`"quick"`, `"full"`).
    pub modes: Vec<Mode>,
    /// Figures seen in quick mode.
    #[serde(default)]
    pub seen_quick: Option<String>,
    /// Figures seen in full mode.
    #[serde(default)]
    pub seen_full: Option<String>,
    /// Why the result differs from the paper; the first line is the summary.
    pub explanation: String,
    /// Where the figures and the explanation come from.
    pub evidence: String,
}

impl Deviation {
    /// The explanation's first line.
    pub fn summary(&self) -> &str {
        self.explanation.lines().next().unwrap_or("").trim()
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DeviationFile {
    #[serde(default, rename = "deviation")]
    deviations: Vec<Deviation>,
}

/// The documented deviations, read from `reference-data/deviations.toml`.
#[derive(Debug, Clone, Default)]
pub struct Deviations {
    list: Vec<Deviation>,
}

impl Deviations {
    /// No documented deviations.
    pub fn none() -> Self {
        Self::default()
    }

    /// Parses the TOML text of a deviations file; `origin` names it in errors. Refuses
    /// duplicate entries and entries without an explanation or evidence.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let file: DeviationFile =
            toml::from_str(text).with_context(|| format!("parsing {origin}"))?;
        let list = file.deviations;
        for (i, d) in list.iter().enumerate() {
            if d.explanation.trim().is_empty() || d.evidence.trim().is_empty() {
                bail!(
                    "{origin}: deviation {}/{} needs an explanation and evidence",
                    d.experiment,
                    d.check
                );
            }
            if d.modes.is_empty() {
                bail!(
                    "{origin}: deviation {}/{} lists no mode",
                    d.experiment,
                    d.check
                );
            }
            if list[..i]
                .iter()
                .any(|e| e.experiment == d.experiment && e.check == d.check)
            {
                bail!(
                    "{origin}: deviation {}/{} is listed twice",
                    d.experiment,
                    d.check
                );
            }
        }
        Ok(Self { list })
    }

    /// Reads `dir/deviations.toml` (no file: no deviations).
    pub fn load(dir: &Path) -> Result<Self> {
        let path = dir.join(DEVIATIONS_FILE);
        if !path.exists() {
            return Ok(Self::none());
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Every entry.
    pub fn all(&self) -> &[Deviation] {
        &self.list
    }

    /// Entries of `experiment` documented for `mode`.
    pub fn for_experiment<'a>(
        &'a self,
        experiment: &'a str,
        mode: Mode,
    ) -> impl Iterator<Item = &'a Deviation> + 'a {
        self.list
            .iter()
            .filter(move |d| d.experiment == experiment && d.modes.contains(&mode))
    }

    /// The entry for `experiment`/`check` in `mode`, if documented.
    pub fn find(&self, experiment: &str, check: &str, mode: Mode) -> Option<&Deviation> {
        self.list
            .iter()
            .find(|d| d.experiment == experiment && d.check == check && d.modes.contains(&mode))
    }
}

/// Marker lines around the README's list of deviations.
pub const README_START: &str =
    "<!-- deviations: generated from reference-data/deviations.toml; checked by cargo test -p validation -->";
/// End marker of the README's list.
pub const README_END: &str = "<!-- /deviations -->";

/// The README's list of documented deviations: one line per entry, with its modes and its
/// summary.
pub fn readme_list(deviations: &Deviations) -> String {
    let mut s = String::new();
    for d in deviations.all() {
        let modes: Vec<&str> = d.modes.iter().map(|m| m.as_str()).collect();
        s.push_str(&format!(
            "- `{}`, check \"{}\" ({}): {}\n",
            d.experiment,
            d.check,
            modes.join(", "),
            d.summary()
        ));
    }
    s
}

/// How one check came out, against the deviations list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CheckVerdict {
    /// Passed, not listed.
    Pass,
    /// Failed, and the miss is documented.
    Deviation,
    /// Failed, not documented.
    Fail,
    /// Documented as a deviation but passed: the list is out of date (fails the run).
    UnexpectedPass,
    /// Listed in the deviations file for this mode, but the experiment produced no check of
    /// that name (fails the run).
    StaleEntry,
}

impl CheckVerdict {
    /// Verdict of `check` of `experiment` in `mode`.
    pub fn of(check: &Check, documented: bool) -> Self {
        match (check.pass, documented) {
            (true, false) => CheckVerdict::Pass,
            (false, true) => CheckVerdict::Deviation,
            (false, false) => CheckVerdict::Fail,
            (true, true) => CheckVerdict::UnexpectedPass,
        }
    }

    /// Whether this verdict fails the run.
    pub fn fails_run(self) -> bool {
        matches!(
            self,
            CheckVerdict::Fail | CheckVerdict::UnexpectedPass | CheckVerdict::StaleEntry
        )
    }

    /// Console and report label.
    pub fn label(self) -> &'static str {
        match self {
            CheckVerdict::Pass => "pass",
            CheckVerdict::Deviation => "deviation",
            CheckVerdict::Fail => "FAIL",
            CheckVerdict::UnexpectedPass => "UNEXPECTED PASS",
            CheckVerdict::StaleEntry => "STALE DEVIATION",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: &str = r#"
[[deviation]]
experiment = "e"
check = "c"
modes = ["quick"]
explanation = "Summary line.\nDetails."
evidence = "a run"
"#;

    #[test]
    fn parse_find_and_summary() {
        let d = Deviations::parse(ONE, "test").unwrap();
        assert_eq!(d.all().len(), 1);
        assert!(d.find("e", "c", Mode::Quick).is_some());
        assert!(d.find("e", "c", Mode::Full).is_none());
        assert!(d.find("e", "other", Mode::Quick).is_none());
        assert_eq!(d.all()[0].summary(), "Summary line.");
    }

    #[test]
    fn refuses_duplicates_unknown_fields_and_empty_evidence() {
        let twice = format!("{ONE}{ONE}");
        let e = Deviations::parse(&twice, "test").unwrap_err().to_string();
        assert!(e.contains("listed twice"), "{e}");
        let unknown = ONE.replace("evidence", "evidense");
        assert!(Deviations::parse(&unknown, "test").is_err());
        let empty = ONE.replace("\"a run\"", "\" \"");
        let e = Deviations::parse(&empty, "test").unwrap_err().to_string();
        assert!(e.contains("evidence"), "{e}");
    }

    #[test]
    fn readme_lists_the_deviations() {
        let root = crate::workspace_root();
        let d = Deviations::load(&root.join("reference-data")).unwrap();
        let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
        let expected = readme_list(&d);
        let block = readme
            .split_once(README_START)
            .and_then(|(_, rest)| rest.split_once(README_END))
            .map(|(block, _)| block.trim_start_matches('\n').to_string());
        assert_eq!(
            block.as_deref(),
            Some(expected.as_str()),
            "README.md's list between the deviation markers must be:\n{README_START}\n{expected}{README_END}"
        );
    }

    #[test]
    fn verdicts() {
        let pass = Check::less_than("c", 0.0, 1.0, "t");
        let fail = Check::less_than("c", 2.0, 1.0, "t");
        assert_eq!(CheckVerdict::of(&pass, false), CheckVerdict::Pass);
        assert_eq!(CheckVerdict::of(&fail, true), CheckVerdict::Deviation);
        assert_eq!(CheckVerdict::of(&fail, false), CheckVerdict::Fail);
        assert_eq!(CheckVerdict::of(&pass, true), CheckVerdict::UnexpectedPass);
        assert!(!CheckVerdict::Deviation.fails_run());
        assert!(CheckVerdict::UnexpectedPass.fails_run());
        assert!(CheckVerdict::StaleEntry.fails_run());
    }
}
