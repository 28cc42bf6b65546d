//! The output directory of a scene run: what it holds and under which names.
//!
//! ```text
//! OUT/scene_source.txt     the scene file (absolute path), the mode (`quick` or `full`)
//!                          and a line `set KEY=VALUE` per override (`run --set`)
//! OUT/stats.csv            one row per frame (written and flushed as each frame ends)
//! OUT/frame_NNNNN.vtk      particle frames (legacy VTK), every `output.every_frames`
//! OUT/passive_NNNNN.vtk    passive points of the same frames (granular upscaling)
//! OUT/checkpoint.sphck     the last checkpoint (`run --checkpoint-every N`, `--resume`)
//! OUT/render/frame_NNNNN.png  rendered frames (`run --render`, `render OUT`)
//! OUT/rest_samples.csv     the rest criterion's samples (`run --until-rest`)
//! OUT/rest.json            its verdict at the run's end
//! ```
//!
//! A fresh run removes what an earlier run left under these names (and nothing else), so
//! that a shorter rerun into the same directory never leaves stale frames beside new ones.

use std::path::{Path, PathBuf};

use sph_scene::{Override, Scene};

use crate::error::SimError;
use crate::source::SceneSource;

/// The file naming the scene, mode and overrides of a run, so that `render OUT`,
/// `repose OUT` and `run --resume` find the scene: the absolute scene path, `quick` or
/// `full`, then a line `set KEY=VALUE` per override.
pub const RUN_SOURCE_FILE: &str = "scene_source.txt";
/// The per-frame statistics.
pub const STATS_FILE: &str = "stats.csv";
/// The checkpoint of a run.
pub const CHECKPOINT_FILE: &str = "checkpoint.sphck";
/// The rest criterion's samples (`run --until-rest`, [`crate::rest_log`]).
pub const REST_SAMPLES_FILE: &str = "rest_samples.csv";
/// The rest criterion's verdict at the run's end.
pub const REST_VERDICT_FILE: &str = "rest.json";
/// The rendered frames' subdirectory.
pub const RENDER_DIR: &str = "render";

/// A run's output directory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunDir {
    path: PathBuf,
}

impl RunDir {
    /// The directory `path` (not created).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self { path: path.into() }
    }

    /// Creates the directory (and its parents) or names why it cannot be an output directory.
    pub fn create(&self) -> Result<(), SimError> {
        let dir = &self.path;
        if dir.exists() && !dir.is_dir() {
            return Err(SimError::output(
                dir,
                "exists and is not a directory (give a directory for the output)",
            ));
        }
        std::fs::create_dir_all(dir)
            .map_err(|e| SimError::output(dir, format!("cannot create the output directory: {e}")))
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `frame_NNNNN.vtk` of frame `f`.
    pub fn frame_vtk(&self, f: usize) -> PathBuf {
        self.path.join(format!("frame_{f:05}.vtk"))
    }

    /// `passive_NNNNN.vtk` of frame `f`.
    pub fn passive_vtk(&self, f: usize) -> PathBuf {
        self.path.join(format!("passive_{f:05}.vtk"))
    }

    /// The name of frame `f`'s rendered image, `frame_NNNNN.png`.
    pub fn frame_png_name(f: usize) -> String {
        format!("frame_{f:05}.png")
    }

    /// The statistics file.
    pub fn stats_csv(&self) -> PathBuf {
        self.path.join(STATS_FILE)
    }

    /// The checkpoint file.
    pub fn checkpoint(&self) -> PathBuf {
        self.path.join(CHECKPOINT_FILE)
    }

    /// The rendered frames' directory.
    pub fn render_dir(&self) -> PathBuf {
        self.path.join(RENDER_DIR)
    }

    /// The particle frames `frame_NNNNN.vtk` of the directory with their frame numbers,
    /// sorted by frame.
    pub fn frames(&self) -> Result<Vec<(usize, PathBuf)>, SimError> {
        numbered_files(&self.path, "frame_", ".vtk")
    }

    /// Removes what a run writes under this directory's names (frames, passive points,
    /// rendered frames, statistics, checkpoint) for frames after `after` (all of them with
    /// `None`, which also removes the statistics and the checkpoint). Returns the number of
    /// files removed.
    pub fn remove_outputs(&self, after: Option<usize>) -> Result<usize, SimError> {
        let keep = |f: usize| after.is_some_and(|a| f <= a);
        let mut stale = Vec::new();
        for (prefix, ext, dir) in [
            ("frame_", ".vtk", self.path.clone()),
            ("passive_", ".vtk", self.path.clone()),
            ("frame_", ".png", self.render_dir()),
        ] {
            if dir.is_dir() {
                stale.extend(
                    numbered_files(&dir, prefix, ext)?
                        .into_iter()
                        .filter(|(f, _)| !keep(*f))
                        .map(|(_, p)| p),
                );
            }
        }
        if after.is_none() {
            stale.extend(
                [
                    self.stats_csv(),
                    self.checkpoint(),
                    self.path.join(REST_SAMPLES_FILE),
                    self.path.join(REST_VERDICT_FILE),
                ]
                .into_iter()
                .filter(|p| p.is_file()),
            );
        }
        for p in &stale {
            std::fs::remove_file(p).map_err(|e| SimError::output(p, e))?;
        }
        Ok(stale.len())
    }

    /// Records the scene, the mode and the overrides of the run ([`RUN_SOURCE_FILE`]).
    pub fn write_source(&self, source: &RunSource) -> Result<(), SimError> {
        let abs = std::path::absolute(&source.scene).unwrap_or_else(|_| source.scene.clone());
        let path = self.path.join(RUN_SOURCE_FILE);
        let mode = if source.quick { "quick" } else { "full" };
        let mut text = format!("{}\n{mode}\n", abs.display());
        for o in &source.overrides {
            text.push_str(&format!("set {}\n", o.to_arg()));
        }
        std::fs::write(&path, text).map_err(|e| SimError::output(&path, e))
    }

    /// The scene file, mode and overrides recorded by [`RunDir::write_source`].
    pub fn read_source(&self) -> Result<RunSource, SimError> {
        let path = self.path.join(RUN_SOURCE_FILE);
        let text =
            sph_core::input::read_text_limited(&path, 1 << 20, "run source file").map_err(|e| {
                SimError::Invalid(format!(
                    "{e} (no scene recorded for this run directory: give --scene SCENE)"
                ))
            })?;
        let mut lines = text.lines();
        let scene = PathBuf::from(lines.next().unwrap_or_default());
        let quick = match lines.next() {
            Some("quick") => true,
            Some("full") => false,
            other => {
                return Err(SimError::input(
                    &path,
                    format!("line 2 is {other:?}, not \"quick\" or \"full\""),
                ))
            }
        };
        let mut overrides = Vec::new();
        for (k, line) in lines.enumerate() {
            let arg = line.strip_prefix("set ").ok_or_else(|| {
                SimError::input(&path, format!("line {} is not `set KEY=VALUE`", k + 3))
            })?;
            let o = Override::parse(arg)
                .map_err(|e| SimError::input(&path, format!("line {}: {e}", k + 3)))?;
            overrides.push(o);
        }
        Ok(RunSource {
            scene,
            quick,
            overrides,
        })
    }
}

/// What a run directory records of its scene ([`RUN_SOURCE_FILE`]): the scene file, whether
/// its `[quick]` overrides apply, and the overrides of its keys (`particles run --set`), so
/// that `render`, `repose` and `--resume` see the scene the run ran.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSource {
    /// The scene file.
    pub scene: PathBuf,
    /// Whether the scene's `[quick]` overrides apply.
    pub quick: bool,
    /// The overrides of the file's keys, in order.
    pub overrides: Vec<Override>,
}

impl RunSource {
    /// The checked scene: the file read with the overrides applied, then quick mode
    /// ([`SceneSource::load`]).
    pub fn load(&self) -> Result<Scene, SimError> {
        SceneSource::load(&self.scene, self.overrides.clone(), self.quick).map(|(_, s)| s)
    }
}

/// Files `PREFIXNNNNN EXT` of `dir` with their numbers, sorted by number.
fn numbered_files(dir: &Path, prefix: &str, ext: &str) -> Result<Vec<(usize, PathBuf)>, SimError> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| SimError::input(dir, format!("not a readable run directory: {e}")))?;
    let mut v: Vec<(usize, PathBuf)> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let k = name.strip_prefix(prefix)?.strip_suffix(ext)?.parse().ok()?;
            Some((k, p))
        })
        .collect();
    v.sort();
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresh_start_removes_only_run_outputs_and_resume_keeps_earlier_frames() {
        let dir = std::env::temp_dir().join(format!("run-dir-test-{}", std::process::id()));
        let run = RunDir::new(&dir);
        run.create().unwrap();
        std::fs::create_dir_all(run.render_dir()).unwrap();
        for f in [0, 5, 10] {
            std::fs::write(run.frame_vtk(f), "x").unwrap();
            std::fs::write(run.passive_vtk(f), "x").unwrap();
            std::fs::write(run.render_dir().join(RunDir::frame_png_name(f)), "x").unwrap();
        }
        std::fs::write(run.stats_csv(), "x").unwrap();
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        assert_eq!(run.remove_outputs(Some(5)).unwrap(), 3);
        let left: Vec<usize> = run.frames().unwrap().into_iter().map(|(f, _)| f).collect();
        assert_eq!(left, [0, 5]);
        assert!(run.stats_csv().is_file());
        assert_eq!(run.remove_outputs(None).unwrap(), 7);
        assert!(run.frames().unwrap().is_empty());
        assert!(!run.stats_csv().exists());
        assert!(dir.join("notes.txt").is_file(), "files of other names stay");
        std::fs::remove_dir_all(&dir).ok();
    }
}
