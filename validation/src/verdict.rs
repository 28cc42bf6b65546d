//! The verdict of a validation run: how each check came out against the documented
//! deviations ([`CheckRecord`], [`judge`]), the status of an experiment ([`Status`],
//! [`status_of`]) and everything recorded about its run ([`Verdict`], the content of
//! `verdict.json`). [`crate::runner`] produces them and [`crate::report`] writes them out;
//! both import them from here.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::deviations::{CheckVerdict, Deviations};
use crate::{Artifact, Check, Mode};

/// Final state of an experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Ran, every check passed.
    Pass,
    /// Ran, every miss is a documented deviation (see [`crate::deviations`]).
    Deviation,
    /// Ran, and some check failed undocumented, or a documented deviation passed or was not
    /// produced (the deviations list is out of date).
    Fail,
    /// Returned an error or panicked.
    Error,
    /// Ran without error and produced no check: the experiment runs no case in this mode
    /// (a full-mode-only study run in quick mode). Not a pass: nothing was judged.
    NoChecks,
}

impl Status {
    /// `"pass"`, `"deviation"`, `"fail"` or `"error"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Pass => "pass",
            Status::Deviation => "deviation",
            Status::Fail => "fail",
            Status::Error => "error",
            Status::NoChecks => "no-checks",
        }
    }

    /// Console label (misses in capitals).
    pub fn label(self) -> &'static str {
        match self {
            Status::Pass => "pass",
            Status::Deviation => "deviation",
            Status::Fail => "FAIL",
            Status::Error => "ERROR",
            Status::NoChecks => "no checks",
        }
    }

    /// Whether this status fails the run (exit code 1).
    pub fn fails_run(self) -> bool {
        matches!(self, Status::Fail | Status::Error)
    }
}

/// A check with its verdict against the deviations list.
#[derive(Debug, Clone, Serialize)]
pub struct CheckRecord {
    /// The check as the experiment reported it.
    #[serde(flatten)]
    pub check: Check,
    /// pass / deviation / fail / unexpected-pass / stale-entry.
    pub verdict: CheckVerdict,
    /// The documented deviation's one-line summary, when listed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deviation: Option<String>,
}

/// The checks of one run against the deviations documented for `id` in `mode`, with a
/// stale-entry record for each documented check that was not produced (only when the
/// experiment ran to the end: an error says nothing about its checks).
pub fn judge(
    id: &str,
    mode: Mode,
    checks: Vec<Check>,
    deviations: &Deviations,
    ran: bool,
) -> Vec<CheckRecord> {
    let mut records: Vec<CheckRecord> = checks
        .into_iter()
        .map(|check| {
            let dev = deviations.find(id, &check.name, mode);
            CheckRecord {
                verdict: CheckVerdict::of(&check, dev.is_some()),
                deviation: dev.map(|d| d.summary().to_string()),
                check,
            }
        })
        .collect();
    if ran {
        for d in deviations.for_experiment(id, mode) {
            if !records.iter().any(|r| r.check.name == d.check) {
                records.push(CheckRecord {
                    check: Check {
                        name: d.check.clone(),
                        value: f64::NAN,
                        bound: "(not produced)".into(),
                        pass: false,
                        origin: format!("{} lists it", crate::deviations::DEVIATIONS_FILE),
                    },
                    verdict: CheckVerdict::StaleEntry,
                    deviation: Some(d.summary().to_string()),
                });
            }
        }
    }
    records
}

/// The status of an experiment from its error and its judged checks.
pub fn status_of(error: bool, checks: &[CheckRecord]) -> Status {
    if error {
        Status::Error
    } else if checks.is_empty() {
        Status::NoChecks
    } else if checks.iter().any(|c| c.verdict.fails_run()) {
        Status::Fail
    } else if checks.iter().any(|c| c.verdict == CheckVerdict::Deviation) {
        Status::Deviation
    } else {
        Status::Pass
    }
}

/// Everything recorded about one experiment run (the content of `verdict.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// Experiment id.
    pub id: String,
    /// What it reproduces.
    pub source: String,
    /// pass / deviation / fail / error / no-checks.
    pub status: Status,
    /// Wall-clock time of `run`, seconds.
    pub wall_s: f64,
    /// Metrics.
    pub metrics: BTreeMap<String, f64>,
    /// Checks, with their verdicts.
    pub checks: Vec<CheckRecord>,
    /// Notes.
    pub notes: Vec<String>,
    /// Error or panic message when `status` is error.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Plots (relative to the experiment's directory).
    pub plots: Vec<Artifact>,
    /// Data files (relative to the experiment's directory).
    pub files: Vec<Artifact>,
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEVIATIONS: &str = r#"
[[deviation]]
experiment = "documented"
check = "misses"
modes = ["quick"]
explanation = "A documented miss.\nWith details."
evidence = "test"
"#;

    #[test]
    fn strict_deviations() {
        // A documented deviation that passes, and one that is not produced, fail the run.
        let stale = format!(
            "{DEVIATIONS}\n[[deviation]]\nexperiment = \"documented\"\ncheck = \"gone\"\n\
             modes = [\"quick\"]\nexplanation = \"x\"\nevidence = \"y\"\n\
             [[deviation]]\nexperiment = \"documented\"\ncheck = \"passes\"\n\
             modes = [\"quick\"]\nexplanation = \"x\"\nevidence = \"y\"\n"
        );
        let deviations = Deviations::parse(&stale, "test").unwrap();
        let checks = vec![
            Check::less_than("misses", 2.0, 1.0, "test"),
            Check::less_than("passes", 0.0, 1.0, "test"),
        ];
        let judged = judge("documented", Mode::Quick, checks.clone(), &deviations, true);
        let verdicts: Vec<CheckVerdict> = judged.iter().map(|c| c.verdict).collect();
        assert_eq!(
            verdicts,
            [
                CheckVerdict::Deviation,
                CheckVerdict::UnexpectedPass,
                CheckVerdict::StaleEntry
            ]
        );
        assert_eq!(status_of(false, &judged), Status::Fail);
        // Full mode lists nothing: the miss is an undocumented failure there.
        let full = judge("documented", Mode::Full, checks.clone(), &deviations, true);
        assert_eq!(full[0].verdict, CheckVerdict::Fail);
        // An experiment that errored is not judged stale.
        let errored = judge("documented", Mode::Quick, vec![], &deviations, false);
        assert!(errored.is_empty());
        assert_eq!(status_of(true, &errored), Status::Error);
        // A run without error and without checks judged nothing: not a pass.
        assert_eq!(status_of(false, &[]), Status::NoChecks);
        assert!(!Status::NoChecks.fails_run());
    }
}
