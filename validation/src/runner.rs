//! Runs the selected experiments and records their verdicts ([`crate::verdict`]);
//! [`crate::report`] writes them out (`verdict.json`, `summary.json`, `report.md`, the terminal table).
//!
//! Output layout (`<out>` defaults to `target/validation` under the workspace root):
//!
//! - `<out>/<id>/` — each experiment's CSV data and PNG plots, and `verdict.json`
//!   (id, source, status, wall_s, metrics, checks, notes, error);
//! - `<out>/summary.json` — `{"mode", "experiments": [{"id", "source", "status", "wall_s",
//!   "metrics", "checks": [{"name", "value", "bound", "pass", "origin"}], ...}]}`;
//! - `<out>/report.md` — every check in one table, then each experiment's notes and plots.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{bail, Context as _, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::deviations::{CheckVerdict, Deviations};
use crate::report;
use crate::verdict::{judge, status_of, Verdict};
use crate::{reference_data_dir, Context, Experiment, Mode, Outcome};

/// What to run and where to write.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Quick or full.
    pub mode: Mode,
    /// Experiment ids to run (empty: all).
    pub only: Vec<String>,
    /// Output directory.
    pub out: PathBuf,
}

/// Selects experiments by id, in registry order; unknown ids are an error naming the
/// known ones.
pub fn select<'a>(
    all: &'a [Box<dyn Experiment>],
    only: &[String],
) -> Result<Vec<&'a dyn Experiment>> {
    let known: Vec<&str> = all.iter().map(|e| e.id()).collect();
    let unknown: Vec<&String> = only
        .iter()
        .filter(|o| !known.contains(&o.as_str()))
        .collect();
    if !unknown.is_empty() {
        bail!(
            "unknown experiment id(s) {} (known: {})",
            unknown
                .iter()
                .map(|s| format!("{s:?}"))
                .collect::<Vec<_>>()
                .join(", "),
            known.join(", ")
        );
    }
    Ok(all
        .iter()
        .filter(|e| only.is_empty() || only.iter().any(|o| o == e.id()))
        .map(|e| e.as_ref())
        .collect())
}

static PANIC_MESSAGE: Mutex<Option<String>> = Mutex::new(None);

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-string payload".to_string()
    }
}

/// Runs one experiment with its progress bar, catching errors and panics.
pub fn run_one(
    exp: &dyn Experiment,
    mode: Mode,
    out: &Path,
    reference_dir: &Path,
    deviations: &Deviations,
) -> Result<Verdict> {
    let dir = out.join(exp.id());
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix:>18.bold} [{elapsed_precise}] {wide_bar} {pos}/{len} eta {eta} {msg}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_prefix(exp.id());
    let mut ctx = Context::new(mode, dir.clone(), reference_dir.to_path_buf(), bar.clone());

    *PANIC_MESSAGE.lock().unwrap_or_else(|e| e.into_inner()) = None;
    let previous_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|info| {
        let mut slot = PANIC_MESSAGE.lock().unwrap_or_else(|e| e.into_inner());
        if slot.is_none() {
            *slot = Some(info.to_string());
        }
    }));
    let start = Instant::now();
    let result = catch_unwind(AssertUnwindSafe(|| exp.run(&mut ctx)));
    let wall_s = start.elapsed().as_secs_f64();
    std::panic::set_hook(previous_hook);
    bar.finish_and_clear();

    let (outcome, error) = match result {
        Ok(Ok(outcome)) => (outcome, None),
        Ok(Err(e)) => (Outcome::new(), Some(format!("{e:#}"))),
        Err(payload) => {
            let hooked = PANIC_MESSAGE
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take();
            let text = hooked.unwrap_or_else(|| panic_text(payload.as_ref()));
            (Outcome::new(), Some(format!("panic: {text}")))
        }
    };
    let checks = judge(exp.id(), mode, outcome.checks, deviations, error.is_none());
    let status = status_of(error.is_some(), &checks);
    let verdict = Verdict {
        id: exp.id().to_string(),
        source: exp.source().to_string(),
        status,
        wall_s,
        metrics: outcome.metrics,
        checks,
        notes: outcome.notes,
        error,
        plots: ctx.plots().to_vec(),
        files: ctx.files().to_vec(),
    };
    report::write_json(&dir.join("verdict.json"), &verdict)?;
    Ok(verdict)
}

/// The deviations list of `reference_dir`, refusing entries that name no registered
/// experiment.
pub fn load_deviations(all: &[Box<dyn Experiment>], reference_dir: &Path) -> Result<Deviations> {
    let deviations = Deviations::load(reference_dir)?;
    for d in deviations.all() {
        if !all.iter().any(|e| e.id() == d.experiment) {
            bail!(
                "{}: deviation {}/{} names no registered experiment",
                reference_dir
                    .join(crate::deviations::DEVIATIONS_FILE)
                    .display(),
                d.experiment,
                d.check
            );
        }
    }
    Ok(deviations)
}

/// Runs the selected experiments, writes `summary.json` and `report.md`, prints the final
/// table. Returns the verdicts.
pub fn run(all: &[Box<dyn Experiment>], opts: &RunOptions) -> Result<Vec<Verdict>> {
    let deviations = load_deviations(all, &reference_data_dir())?;
    run_with(all, opts, &deviations)
}

/// [`run`] with a given deviations list.
pub fn run_with(
    all: &[Box<dyn Experiment>],
    opts: &RunOptions,
    deviations: &Deviations,
) -> Result<Vec<Verdict>> {
    let selected = select(all, &opts.only)?;
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("creating {}", opts.out.display()))?;
    let reference_dir = reference_data_dir();
    eprintln!(
        "validation ({} mode): {} experiment(s) -> {}  [reference data: {}, {} documented \
         deviation(s), rayon threads: {}]",
        opts.mode,
        selected.len(),
        opts.out.display(),
        reference_dir.display(),
        deviations.all().len(),
        rayon::current_num_threads()
    );
    let mut verdicts = Vec::new();
    for exp in selected {
        let v = run_one(exp, opts.mode, &opts.out, &reference_dir, deviations)?;
        let count = |k: CheckVerdict| v.checks.iter().filter(|c| c.verdict == k).count();
        eprintln!(
            "{:>18}: {} in {:.2} s ({} checks: {} pass, {} deviation, {} fail)",
            v.id,
            v.status.label(),
            v.wall_s,
            v.checks.len(),
            count(CheckVerdict::Pass),
            count(CheckVerdict::Deviation),
            v.checks.iter().filter(|c| c.verdict.fails_run()).count(),
        );
        verdicts.push(v);
    }
    let (summary_path, report_path) =
        report::write_summary_and_report(&opts.out, opts.mode, &verdicts)?;
    print!("{}", report::terminal_table(&verdicts));
    println!("summary: {}", summary_path.display());
    println!("report:  {}", report_path.display());
    Ok(verdicts)
}

/// `true` when no experiment failed or errored (documented deviations allowed): the exit
/// code of `cargo xtask validate`.
pub fn succeeded(verdicts: &[Verdict]) -> bool {
    verdicts.iter().all(|v| !v.status.fails_run())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::terminal_table;
    use crate::verdict::Status;
    use crate::Check;

    /// An experiment of the tests: its id and what its run does.
    struct Stub(&'static str, fn() -> Result<Outcome>);
    impl Experiment for Stub {
        fn id(&self) -> &'static str {
            self.0
        }
        fn source(&self) -> &'static str {
            "test"
        }
        fn crates(&self) -> &'static [&'static str] {
            &[]
        }
        fn run(&self, _ctx: &mut Context) -> Result<Outcome> {
            (self.1)()
        }
    }

    fn fails() -> Result<Outcome> {
        let mut o = Outcome::new();
        o.metric("m", 1.0);
        o.check(Check::less_than("c", 2.0, 1.0, "test"));
        Ok(o)
    }

    fn documented() -> Result<Outcome> {
        let mut o = Outcome::new();
        o.check(Check::less_than("misses", 2.0, 1.0, "test"));
        o.check(Check::less_than("passes", 0.0, 1.0, "test"));
        Ok(o)
    }

    const DEVIATIONS: &str = r#"
[[deviation]]
experiment = "documented"
check = "misses"
modes = ["quick"]
explanation = "A documented miss.\nWith details."
evidence = "test"
"#;

    #[test]
    fn statuses_and_files() {
        let all: Vec<Box<dyn Experiment>> = vec![
            Box::new(Stub("fails", fails)),
            Box::new(Stub("panics", || panic!("boom"))),
            Box::new(Stub("errs", || bail!("no data"))),
            Box::new(Stub("documented", documented)),
        ];
        let out = std::env::temp_dir().join(format!("validation-runner-{}", std::process::id()));
        let opts = RunOptions {
            mode: Mode::Quick,
            only: vec![],
            out: out.clone(),
        };
        let deviations = Deviations::parse(DEVIATIONS, "test").unwrap();
        let v = run_with(&all, &opts, &deviations).unwrap();
        assert_eq!(v[0].status, Status::Fail);
        assert_eq!(v[1].status, Status::Error);
        assert!(v[1].error.as_deref().unwrap().contains("boom"));
        assert_eq!(v[2].status, Status::Error);
        assert_eq!(v[3].status, Status::Deviation);
        assert_eq!(v[3].checks[0].verdict, CheckVerdict::Deviation);
        assert_eq!(
            v[3].checks[0].deviation.as_deref(),
            Some("A documented miss.")
        );
        assert!(!succeeded(&v));
        assert!(succeeded(&v[3..]));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["mode"], "quick");
        assert_eq!(summary["experiments"][0]["checks"][0]["pass"], false);
        assert_eq!(summary["experiments"][0]["checks"][0]["verdict"], "fail");
        assert_eq!(summary["experiments"][3]["status"], "deviation");
        assert_eq!(
            summary["experiments"][3]["checks"][0]["verdict"],
            "deviation"
        );
        assert_eq!(summary["experiments"][0]["metrics"]["m"], 1.0);
        assert!(out.join("fails/verdict.json").is_file());
        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(report.contains("## Documented deviations"), "{report}");
        assert!(report.contains("A documented miss."), "{report}");
        let table = terminal_table(&v);
        assert!(table.contains("documented: A documented miss."), "{table}");
        let err = select(&all, &["nope".to_string()])
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("known: fails, panics, errs"), "{err}");
        std::fs::remove_dir_all(&out).ok();
    }

    #[test]
    fn shipped_deviations_name_registered_experiments() {
        let all = crate::registry();
        let d = load_deviations(&all, &reference_data_dir()).unwrap();
        for dev in d.all() {
            assert!(
                !dev.summary().is_empty(),
                "{}/{}",
                dev.experiment,
                dev.check
            );
        }
    }
}
