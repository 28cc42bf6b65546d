//! `particles run --until-rest`: the rest criterion of [`crate::observe::RestObserver`]
//! watched during a scene run, its samples written as they are taken and its verdict at
//! the end, so that a run stopped and resumed stops where one whole run would.
//!
//! ```text
//! OUT/rest_samples.csv  one row per sample (time_s, percentile_speed_m_s,
//!                       deep_max_speed_m_s, deep_particles, angle_deg), flushed per frame
//! OUT/rest.json         the verdict at the run's end: the criterion's settings, the
//!                       verdict with its margins, rest_from_s and the one-line summary
//! ```

use std::fs::File;
use std::io::Write as _;
use std::path::PathBuf;

use sph_core::Real;

use crate::error::SimError;
use crate::frame_loop::{Flow, FrameObserver, RunOutcome, RunPlan};
use crate::observe::{RestCriterion, RestObserver, RestSample};
use crate::record::FrameRecord;
use crate::run_dir::RunDir;
use crate::sim::SceneSim;

pub use crate::run_dir::{REST_SAMPLES_FILE, REST_VERDICT_FILE};
const HEADER: &str = "time_s,percentile_speed_m_s,deep_max_speed_m_s,deep_particles,angle_deg";

/// A [`RestObserver`] whose samples go to `OUT/rest_samples.csv` as they are taken and
/// whose verdict goes to `OUT/rest.json` when the run ends.
#[derive(Debug)]
pub struct RestLog {
    /// The observer (its samples and verdict).
    pub observer: RestObserver,
    samples_path: PathBuf,
    verdict_path: PathBuf,
    file: Option<File>,
    written: usize,
}

impl RestLog {
    /// Watches `criterion` in `run`. Resumed at `time_s`, it goes on from the samples the
    /// directory holds up to that time (the rows after it, written before a kill, are
    /// dropped), so that the verdicts are those of one whole run.
    pub fn new(
        criterion: RestCriterion,
        run: &RunDir,
        resumed_at_s: Option<f64>,
    ) -> Result<Self, SimError> {
        let samples_path = run.path().join(REST_SAMPLES_FILE);
        let carried = match resumed_at_s {
            Some(t) if samples_path.is_file() => read_samples(&samples_path, t)?,
            _ => Vec::new(),
        };
        Ok(Self {
            observer: RestObserver::resumed(criterion, carried),
            verdict_path: run.path().join(REST_VERDICT_FILE),
            samples_path,
            file: None,
            written: 0,
        })
    }

    fn err(&self, e: impl ToString) -> SimError {
        SimError::output(&self.samples_path, e)
    }

    /// Rewrites the file with the samples carried over, then appends as samples come.
    fn open(&mut self) -> Result<(), SimError> {
        let mut text = format!("{HEADER}\n");
        for s in &self.observer.samples {
            text.push_str(&row(s));
        }
        let mut f = File::create(&self.samples_path).map_err(|e| self.err(e))?;
        f.write_all(text.as_bytes()).map_err(|e| self.err(e))?;
        self.written = self.observer.samples.len();
        self.file = Some(f);
        Ok(())
    }

    /// Appends the samples taken since the last call.
    fn append(&mut self) -> Result<(), SimError> {
        // The observer clears its samples while a pour goes on: nothing is written then.
        self.written = self.written.min(self.observer.samples.len());
        let text: String = self.observer.samples[self.written..]
            .iter()
            .map(row)
            .collect();
        self.written = self.observer.samples.len();
        let Some(f) = self.file.as_mut() else {
            return Err(self.err("rest samples written before the run started"));
        };
        f.write_all(text.as_bytes())
            .and_then(|()| f.flush())
            .map_err(|e| SimError::output(&self.samples_path, e))
    }

    /// The verdict's one line (what misses and by how much), or why there is none.
    pub fn summary(&self) -> String {
        match self.observer.verdict {
            Some(v) => v.summary(&self.observer.criterion.settings),
            None => "not judged (no sample after the pour's last layer)".into(),
        }
    }

    /// Writes `rest.json`: the settings, the verdict and when the criterion held.
    fn write_verdict(&self) -> Result<(), SimError> {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            at_rest: bool,
            rest_from_s: Option<f64>,
            summary: String,
            settings: &'a granular_measure::RestSettings,
            verdict: Option<&'a granular_measure::RestVerdict>,
            samples: usize,
        }
        let o = &self.observer;
        let out = Out {
            at_rest: o.rest_from_s.is_some(),
            rest_from_s: o.rest_from_s,
            summary: self.summary(),
            settings: &o.criterion.settings,
            verdict: o.verdict.as_ref(),
            samples: o.samples.len(),
        };
        let json = serde_json::to_string_pretty(&out)
            .map_err(|e| SimError::output(&self.verdict_path, e))?;
        crate::checkpoint::write_atomically(&self.verdict_path, json.as_bytes())
    }
}

/// One CSV row of `s` (floats in Rust's shortest form that reads back to the same bits).
fn row(s: &RestSample) -> String {
    let angle = s.angle_deg.map_or(String::new(), |a| a.to_string());
    format!(
        "{},{},{},{},{angle}\n",
        s.time_s, s.percentile_speed_m_s, s.deep_max_speed_m_s, s.deep_particles
    )
}

/// The samples of `path` up to `until_s` (complete rows only).
fn read_samples(path: &std::path::Path, until_s: f64) -> Result<Vec<RestSample>, SimError> {
    let text = sph_core::input::read_text_limited(path, 1 << 30, "rest samples file")?;
    let mut lines = text.split_inclusive('\n');
    if lines.next().map(str::trim_end) != Some(HEADER) {
        return Err(SimError::input(
            path,
            format!("its header is not `{HEADER}`: the run directory holds another file"),
        ));
    }
    let mut out = Vec::new();
    for (k, line) in lines.enumerate().filter(|(_, l)| l.ends_with('\n')) {
        let bad = |what: &str| SimError::input(path, format!("line {}: {what}", k + 2));
        let f: Vec<&str> = line.trim_end().split(',').collect();
        let [t, p, d, n, a] = f[..] else {
            return Err(bad("expected 5 columns"));
        };
        let num = |s: &str| s.parse::<f64>().map_err(|_| bad("not a number"));
        let sample = RestSample {
            time_s: num(t)?,
            percentile_speed_m_s: num(p)?,
            deep_max_speed_m_s: num(d)?,
            deep_particles: n.parse().map_err(|_| bad("not a particle count"))?,
            angle_deg: if a.is_empty() { None } else { Some(num(a)?) },
        };
        if sample.time_s <= until_s + 1e-9 {
            out.push(sample);
        }
    }
    Ok(out)
}

impl<R: Real> FrameObserver<R> for RestLog {
    fn start(&mut self, sim: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        self.open()?;
        self.observer.start(sim, plan)?;
        self.append()
    }
    fn frame(&mut self, sim: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError> {
        let flow = self.observer.frame(sim, record)?;
        self.append()?;
        Ok(flow)
    }
    fn finish(&mut self, _: &SceneSim<R>, _: Option<&RunOutcome>) -> Result<(), SimError> {
        self.write_verdict()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_read_back_bit_for_bit_up_to_the_resume_time() {
        let dir = std::env::temp_dir().join(format!("rest-log-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(REST_SAMPLES_FILE);
        let samples = [
            RestSample {
                time_s: 0.1,
                percentile_speed_m_s: 1.0 / 3.0,
                deep_max_speed_m_s: f64::NAN,
                deep_particles: 7,
                angle_deg: None,
            },
            RestSample {
                time_s: 0.2,
                percentile_speed_m_s: 2e-7,
                deep_max_speed_m_s: 0.012345678901234567,
                deep_particles: 0,
                angle_deg: Some(29.999999999999996),
            },
        ];
        let text: String = std::iter::once(format!("{HEADER}\n"))
            .chain(samples.iter().map(row))
            .chain(["0.3,1,1,1,".into()]) // a partial row, left by a kill
            .collect();
        std::fs::write(&path, text).unwrap();
        let back = read_samples(&path, 0.2).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!(back[1], samples[1]);
        assert_eq!(
            back[0].percentile_speed_m_s.to_bits(),
            (1.0f64 / 3.0).to_bits()
        );
        assert!(back[0].deep_max_speed_m_s.is_nan());
        assert_eq!(read_samples(&path, 0.15).unwrap().len(), 1);
        std::fs::remove_dir_all(&dir).ok();
    }
}
