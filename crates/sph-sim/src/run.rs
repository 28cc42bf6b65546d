//! The observers of a scene run (VTK frames, `stats.csv`, a progress bar; checkpoints and
//! rendered frames are in [`crate::checkpoint`] and [`crate::render`]) and [`run_scene`],
//! the run of `particles run SCENE` / `cargo xtask run SCENE` with the one frame loop
//! ([`crate::frame_loop::run_frames`]).

use std::fs::File;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use sph_core::Real;
use sph_scene::{Override, Scene};

use crate::checkpoint::CheckpointObserver;
use crate::error::SimError;
use crate::frame_loop::{run_frames, Ending, Flow, FrameObserver, RunOutcome, RunPlan};
use crate::observe::RestCriterion;
use crate::record::FrameRecord;
use crate::render::RenderObserver;
use crate::rest_log::RestLog;
use crate::run_dir::{RunDir, RunSource};
use crate::sim::SceneSim;
use crate::with_precision;

/// Writes `frame_NNNNN.vtk` (and `passive_NNNNN.vtk` when the solver advects passive
/// points) every `output.every_frames` frames, frame 0 included, and the last frame of a run
/// that completed or stopped.
#[derive(Debug)]
pub struct VtkObserver {
    run: RunDir,
    every: usize,
}

impl VtkObserver {
    /// Frames of `scene`'s output cadence into `run`.
    pub fn new(scene: &Scene, run: &RunDir) -> Self {
        Self {
            run: run.clone(),
            every: scene.output.every_frames.max(1),
        }
    }

    fn write<R: Real>(&self, sim: &SceneSim<R>) -> Result<(), SimError> {
        sim.write_vtk(&self.run.frame_vtk(sim.frame))?;
        sim.write_passive_vtk(&self.run.passive_vtk(sim.frame))?;
        Ok(())
    }

    /// Bytes of the frame files of frame `f` (particles and passive points), if written.
    fn frame_bytes(&self, f: usize) -> Option<u64> {
        let size = |p: PathBuf| std::fs::metadata(p).ok().map(|m| m.len());
        Some(size(self.run.frame_vtk(f))? + size(self.run.passive_vtk(f)).unwrap_or(0))
    }

    /// Refuses a run whose remaining frame files would not fit on the output's file system,
    /// estimated from the size of the last frame written (particle counts do not change).
    fn check_output_volume(&self, plan: &RunPlan) -> Result<(), SimError> {
        let last_written = self.run.frames()?.last().map(|(f, _)| *f);
        let Some(per_frame) = last_written.and_then(|f| self.frame_bytes(f)) else {
            return Ok(());
        };
        let frames = frames_written_after(plan, self.every);
        let bytes = per_frame.saturating_mul(frames);
        let free = sph_core::disk::available_bytes(self.run.path());
        match sph_core::disk::room_shortfall(self.run.path(), bytes, free) {
            None => Ok(()),
            Some(why) => Err(SimError::output(
                self.run.path(),
                format!(
                    "writing {frames} more frame files (output.every_frames = {}, about {} each) {why}: write fewer frames (a larger output.every_frames), run fewer frames, or choose another output directory",
                    self.every,
                    sph_core::disk::human(per_frame)
                ),
            )),
        }
    }
}

/// Frames after `plan.first_frame` up to `plan.last_frame` whose files a run writes every
/// `every` frames.
fn frames_written_after(plan: &RunPlan, every: usize) -> u64 {
    let every = every.max(1);
    (plan.last_frame / every).saturating_sub(plan.first_frame / every) as u64
}

impl<R: Real> FrameObserver<R> for VtkObserver {
    fn start(&mut self, sim: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        if !plan.resumed {
            self.write(sim)?;
        } else if !plan.first_frame.is_multiple_of(self.every) {
            // The last frame of the run resumed from, off the cadence: an uninterrupted run
            // has no such file.
            for p in [
                self.run.frame_vtk(sim.frame),
                self.run.passive_vtk(sim.frame),
            ] {
                if p.is_file() {
                    std::fs::remove_file(&p).map_err(|e| SimError::output(&p, e))?;
                }
            }
        }
        self.check_output_volume(plan)
    }
    fn frame(&mut self, sim: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        if sim.frame.is_multiple_of(self.every) {
            self.write(sim)?;
        }
        Ok(Flow::Continue)
    }
    /// A run that completed or was stopped (at rest) between two frames of the cadence ends
    /// with its last frame written, so that `repose` and `render` see the state it ended in.
    fn finish(&mut self, sim: &SceneSim<R>, outcome: Option<&RunOutcome>) -> Result<(), SimError> {
        let ended =
            outcome.is_some_and(|o| matches!(o.ending, Ending::Completed | Ending::Stopped { .. }));
        if ended && !sim.frame.is_multiple_of(self.every) {
            self.write(sim)?;
        }
        Ok(())
    }
}

/// Writes `stats.csv`, one row per frame, flushed as each frame ends (so a killed run keeps
/// the rows of the frames it finished). Resumed at frame `k`, it keeps the header and the
/// rows of frames `1..=k` and appends after them.
#[derive(Debug)]
pub struct StatsObserver {
    path: PathBuf,
    writer: Option<csv::Writer<File>>,
}

impl StatsObserver {
    /// The statistics file of `run`.
    pub fn new(run: &RunDir) -> Self {
        Self {
            path: run.stats_csv(),
            writer: None,
        }
    }

    fn err(&self, e: impl ToString) -> SimError {
        SimError::output(&self.path, e)
    }
}

/// The lines of an earlier `stats.csv` to keep when resuming at `frame`: the header and the
/// complete rows of frames `1..=frame` (a partial last line, left by a kill, is dropped).
fn kept_stats_lines(text: &str, frame: usize) -> String {
    let mut kept = String::new();
    for (k, line) in text.split_inclusive('\n').enumerate() {
        let complete = line.ends_with('\n');
        let row_frame = line.split(',').next().and_then(|f| f.parse::<usize>().ok());
        let keep = complete && (k == 0 || row_frame.is_some_and(|f| f <= frame));
        if keep {
            kept.push_str(line);
        }
    }
    kept
}

impl<R: Real> FrameObserver<R> for StatsObserver {
    fn start(&mut self, sim: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        let header = FrameRecord::csv_header(sim.solver().phase_names());
        let kept = if plan.resumed && self.path.is_file() {
            let text = sph_core::input::read_text_limited(&self.path, 1 << 30, "statistics file")?;
            let kept = kept_stats_lines(&text, sim.frame);
            let expected = header.join(",");
            if kept.lines().next() != Some(expected.as_str()) {
                return Err(SimError::input(
                    &self.path,
                    "its header is not this solver's: the run directory holds another run's statistics",
                ));
            }
            Some(kept)
        } else {
            None
        };
        let mut file = File::create(&self.path).map_err(|e| self.err(e))?;
        let mut writer = match kept {
            Some(kept) => {
                file.write_all(kept.as_bytes()).map_err(|e| self.err(e))?;
                csv::Writer::from_writer(file)
            }
            None => {
                let mut w = csv::Writer::from_writer(file);
                w.write_record(&header).map_err(|e| self.err(e))?;
                w
            }
        };
        writer.flush().map_err(|e| self.err(e))?;
        self.writer = Some(writer);
        Ok(())
    }

    fn frame(&mut self, _: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError> {
        let Some(w) = self.writer.as_mut() else {
            return Err(self.err("statistics written before the run started"));
        };
        let r = w
            .write_record(record.csv_row())
            .and_then(|()| Ok(w.flush()?));
        r.map_err(|e| self.err(e)).map(|()| Flow::Continue)
    }
}

/// A progress bar on stderr: frames done, ETA, the last frame's largest density ratio and
/// time per frame.
#[derive(Debug)]
pub struct ProgressObserver {
    bar: ProgressBar,
}

impl ProgressObserver {
    /// A visible bar (`visible = false`: hidden, for tests and scripts).
    pub fn new(visible: bool) -> Self {
        let bar = if visible {
            ProgressBar::new(0)
        } else {
            ProgressBar::hidden()
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} frames ETA {eta} {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Self { bar }
    }
}

impl<R: Real> FrameObserver<R> for ProgressObserver {
    fn start(&mut self, _: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        self.bar.set_length(plan.last_frame as u64);
        self.bar.set_position(plan.first_frame as u64);
        self.bar.reset_eta();
        Ok(())
    }
    fn frame(&mut self, _: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError> {
        self.bar.set_message(format!(
            "rho_max/rho0 {:.4}, {:.1} ms/frame",
            record.max_density_ratio,
            record.total_s * 1e3
        ));
        self.bar.inc(1);
        Ok(Flow::Continue)
    }
    fn finish(&mut self, _: &SceneSim<R>, _: Option<&RunOutcome>) -> Result<(), SimError> {
        self.bar.finish();
        Ok(())
    }
}

/// Options of [`run_scene`].
#[derive(Debug, Clone)]
pub struct SceneRunOptions {
    /// Apply the scene's `[quick]` overrides.
    pub quick: bool,
    /// Output directory (frames, statistics, checkpoint); created if missing.
    pub out_dir: PathBuf,
    /// Stop at this frame (default: the scene's duration); must be ≥ 1.
    pub max_frames: Option<usize>,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Write a checkpoint every this many frames (and at the end); `None`: none.
    pub checkpoint_every: Option<usize>,
    /// Continue from the run directory's checkpoint instead of starting afresh.
    pub resume: bool,
    /// Render the frames (PNG in `OUT/render`) in process as the run writes them.
    pub render: bool,
    /// A directory of volume maps to load from and add to (`None`: build them, keep none).
    pub volume_map_cache: Option<PathBuf>,
    /// Overrides of the scene file's keys (`particles run --set KEY=VALUE`), applied as the
    /// file is read and checked with it; recorded in the run directory (a resumed run with
    /// none takes the recorded ones).
    pub overrides: Vec<Override>,
    /// Stop once the material is at rest by this criterion (`particles run --until-rest`;
    /// the scene's duration is then a cap): its samples and verdict are written to the run
    /// directory ([`crate::rest_log`]).
    pub until_rest: Option<RestCriterion>,
    /// A cancellation flag (set by a Ctrl-C handler): checked per row of nodes while the
    /// volume maps are built (the run then fails with
    /// [`sph_solver::SolverError::Cancelled`]) and after each frame (the run ends
    /// [`crate::frame_loop::Ending::Interrupted`], its final checkpoint written).
    pub cancel: Option<Arc<AtomicBool>>,
}

/// The frame a run of `scene` stops at with `max_frames`.
pub fn last_frame(scene: &Scene, max_frames: Option<usize>) -> Result<usize, SimError> {
    match max_frames {
        Some(0) => Err(SimError::Invalid(
            "--frames 0: nothing to run (give at least 1 frame)".into(),
        )),
        Some(m) => Ok(m.min(scene.frame_count())),
        None => Ok(scene.frame_count()),
    }
}

/// Loads the scene at `path` (with `opts.overrides`) and runs it into `opts.out_dir`
/// ([`crate::run_dir`]): a progress bar, VTK frames, `stats.csv`, checkpoints, with
/// `opts.render` the frames rendered in process ([`crate::render::RenderObserver`]) and with
/// `opts.until_rest` a stop at rest ([`crate::rest_log`]). A fresh run first removes what an
/// earlier run left in the directory; `opts.resume` continues from its checkpoint (refused
/// by name if it is another scene's, another version's, or damaged) with the overrides the
/// directory records. Returns how the run ended: a blow-up is
/// [`crate::frame_loop::Ending::Diverged`], naming the frame, step and particle (the files up
/// to it are kept).
pub fn run_scene(path: &Path, opts: &SceneRunOptions) -> Result<RunOutcome, SimError> {
    let run = RunDir::new(&opts.out_dir);
    let source = run_source(path, opts, &run)?;
    let scene = source.load()?;
    let last = last_frame(&scene, opts.max_frames)?;
    run.create()?;
    // Checked before any work, so that a bad [render] table costs nothing.
    let render = match opts.render {
        true => Some(RenderObserver::new(&scene, &run)?),
        false => None,
    };
    with_precision!(scene.precision, R => run_scene_in::<R>(&source, &scene, &run, last, opts, render))
}

/// The scene a run reads: the one asked for, and on `--resume` the overrides recorded in
/// the directory (those asked for, if any, must be the same).
fn run_source(path: &Path, opts: &SceneRunOptions, run: &RunDir) -> Result<RunSource, SimError> {
    let asked = RunSource {
        scene: path.to_path_buf(),
        quick: opts.quick,
        overrides: opts.overrides.clone(),
    };
    let recorded = run.path().join(crate::run_dir::RUN_SOURCE_FILE);
    if !opts.resume || !recorded.is_file() {
        return Ok(asked);
    }
    let recorded = run.read_source()?;
    let args = |o: &[Override]| match o {
        [] => "none".to_string(),
        o => o
            .iter()
            .map(|o| format!("--set {}", o.to_arg()))
            .collect::<Vec<_>>()
            .join(" "),
    };
    if !asked.overrides.is_empty() && asked.overrides != recorded.overrides {
        return Err(SimError::Invalid(format!(
            "--resume: the run in {} was made with overrides {}, not {}: give the same --set or none",
            run.path().display(),
            args(&recorded.overrides),
            args(&asked.overrides)
        )));
    }
    Ok(RunSource {
        overrides: recorded.overrides,
        ..asked
    })
}

fn run_scene_in<R: Real>(
    source: &RunSource,
    scene: &Scene,
    run: &RunDir,
    last: usize,
    opts: &SceneRunOptions,
    mut render: Option<RenderObserver>,
) -> Result<RunOutcome, SimError> {
    let t0 = Instant::now();
    let cache = match (&opts.volume_map_cache, scene.boundary.model) {
        (Some(dir), sph_scene::BoundaryModel::VolumeMap) => Some(
            sph_solver::boundary::VolumeMapCache::new(dir).map_err(|e| SimError::output(dir, e))?,
        ),
        _ => None,
    };
    let how = sph_solver::boundary::VolumeMapBuild {
        cache: cache.as_ref(),
        cancel: opts.cancel.as_deref(),
    };
    let mut sim = SceneSim::<R>::with_maps(scene, how)?;
    let resumed = opts.resume;
    if resumed {
        sim.resume_from(&run.checkpoint())?;
        run.remove_outputs(Some(sim.frame))?;
    } else {
        run.remove_outputs(None)?;
        run.write_source(source)?;
    }
    let plan = RunPlan {
        first_frame: sim.frame,
        last_frame: last.max(sim.frame),
        resumed,
    };
    announce(&sim, scene, &plan, run, t0);
    let mut vtk = VtkObserver::new(scene, run);
    let mut stats = StatsObserver::new(run);
    let mut bar = ProgressObserver::new(opts.progress);
    let mut checkpoints = CheckpointObserver::new(run, opts.checkpoint_every);
    let cancel = opts.cancel.clone();
    let mut ctrl_c = crate::observe::OnFrame(move |_: &SceneSim<R>, _: &FrameRecord| {
        if cancel.as_deref().is_some_and(|c| c.load(Ordering::Relaxed)) {
            Flow::Interrupt
        } else {
            Flow::Continue
        }
    });
    let mut rest = match opts.until_rest {
        Some(c) => Some(RestLog::new(c, run, resumed.then_some(sim.time_s))?),
        None => None,
    };
    let mut observers: Vec<&mut dyn FrameObserver<R>> = vec![&mut stats, &mut vtk];
    if let Some(r) = render.as_mut() {
        observers.push(r);
    }
    if let Some(r) = rest.as_mut() {
        observers.push(r);
    }
    observers.push(&mut ctrl_c);
    observers.push(&mut checkpoints);
    observers.push(&mut bar);
    let result = run_frames(&mut sim, &plan, &mut observers);
    let ending = match &result {
        Ok(o) => o.ending.name(),
        Err(_) => "failed",
    };
    eprintln!(
        "{}: {ending} at frame {} after {:.1} s{}; statistics in {}",
        scene.name,
        sim.frame,
        t0.elapsed().as_secs_f64(),
        render.map_or(String::new(), |r| format!(
            ", {} frames rendered to {}",
            r.rendered,
            run.render_dir().display()
        )),
        run.stats_csv().display()
    );
    if let Some(r) = &rest {
        eprintln!(
            "rest: {}; verdict in {}",
            r.summary(),
            run.path()
                .join(crate::rest_log::REST_VERDICT_FILE)
                .display()
        );
    }
    result
}

/// Prints what the run will do, and its cost in substeps, before it starts.
fn announce<R: Real>(sim: &SceneSim<R>, scene: &Scene, plan: &RunPlan, run: &RunDir, t0: Instant) {
    let substeps = sim.solver().common().substeps;
    eprintln!(
        "{}: {} particles, solver {}, boundary {}, frames {}..{} of {} s ({} substeps each, {} particle-substeps), set-up {:.2} s{} -> {}",
        scene.name,
        sim.state.len(),
        sim.solver().name(),
        match scene.boundary.model {
            // The solver's boundary is then the collision net under the particles' walls.
            sph_scene::BoundaryModel::Particles => "particles",
            _ => sim.solver().boundary().name(),
        },
        plan.first_frame,
        plan.last_frame,
        scene.frame_dt_s,
        substeps,
        plan.frames() as u128 * substeps as u128 * sim.state.len() as u128,
        t0.elapsed().as_secs_f64(),
        if plan.resumed { ", resumed from the checkpoint" } else { "" },
        run.path().display()
    );
    if let Some(c) = &sim.calibration {
        eprintln!(
            "initial masses calibrated: max rho/rho0 {:.4} -> {:.6} in {} iterations, {} particles lowered (smallest mass x{:.3}), total mass x{:.4}",
            c.max_density_ratio_before,
            c.max_density_ratio_after,
            c.iterations,
            c.lowered,
            c.min_mass_ratio,
            c.total_mass_ratio
        );
    }
}

#[cfg(test)]
mod tests {
    use super::{frames_written_after, kept_stats_lines};
    use crate::frame_loop::RunPlan;

    #[test]
    fn frames_written_after_the_first_follow_the_cadence() {
        let plan = |first_frame, last_frame| RunPlan {
            first_frame,
            last_frame,
            resumed: first_frame > 0,
        };
        // Naive count: the frames f in (first, last] with f a multiple of `every`.
        for (first, last, every) in [
            (0, 94, 1),
            (0, 94, 5),
            (12, 94, 5),
            (13, 14, 5),
            (0, 0, 3),
            (7, 7, 1),
        ] {
            let naive = (first + 1..=last).filter(|f| f % every == 0).count() as u64;
            assert_eq!(
                frames_written_after(&plan(first, last), every),
                naive,
                "{first} {last} {every}"
            );
        }
    }

    #[test]
    fn resumed_statistics_keep_the_header_and_the_finished_rows() {
        let text = "frame,x\n1,a\n2,b\n3,c\n4,d";
        assert_eq!(kept_stats_lines(text, 2), "frame,x\n1,a\n2,b\n");
        assert_eq!(kept_stats_lines(text, 9), "frame,x\n1,a\n2,b\n3,c\n");
        assert_eq!(kept_stats_lines("frame,x\n", 0), "frame,x\n");
    }
}
