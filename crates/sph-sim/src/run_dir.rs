//! The output directory of a scene run: what it holds and under which names.
//!
//! ```text
//! OUT/scene_source.txt     the scene file (absolute path) and the mode, `quick` or `full`
//! OUT/stats.csv            one row per frame (written and flushed as each frame ends)
//! OUT/frame_NNNNN.vtk      particle frames (legacy VTK), every `output.every_frames`
//! OUT/passive_NNNNN.vtk    passive points of the same frames (granular upscaling)
//! OUT/checkpoint.sphck     the last checkpoint (`run --checkpoint-every N`, `--resume`)
//! OUT/render/frame_NNNNN.png  rendered frames (`run --render`, `render OUT`)
//! ```
//!
//! A fresh run removes what an earlier run left under these names (and nothing else), so
//! that a shorter rerun into the same directory never leaves stale frames beside new ones.

use std::path::{Path, PathBuf};

use crate::error::SimError;

/// The file naming the scene and mode of a run, so that `render OUT` and `repose OUT` find
/// the scene: two lines, the absolute scene path and `quick` or `full`.
pub const RUN_SOURCE_FILE: &str = "scene_source.txt";
/// The per-frame statistics.
pub const STATS_FILE: &str = "stats.csv";
/// The checkpoint of a run.
pub const CHECKPOINT_FILE: &str = "checkpoint.sphck";
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
                [self.stats_csv(), self.checkpoint()]
                    .into_iter()
                    .filter(|p| p.is_file()),
            );
        }
        for p in &stale {
            std::fs::remove_file(p).map_err(|e| SimError::output(p, e))?;
        }
        Ok(stale.len())
    }

    /// Records the scene and mode of the run ([`RUN_SOURCE_FILE`]).
    pub fn write_source(&self, scene: &Path, quick: bool) -> Result<(), SimError> {
        let abs = std::path::absolute(scene).unwrap_or_else(|_| scene.to_path_buf());
        let path = self.path.join(RUN_SOURCE_FILE);
        let mode = if quick { "quick" } else { "full" };
        std::fs::write(&path, format!("{}\n{mode}\n", abs.display()))
            .map_err(|e| SimError::output(&path, e))
    }

    /// The scene file and mode recorded by [`RunDir::write_source`].
    pub fn read_source(&self) -> Result<(PathBuf, bool), SimError> {
        let path = self.path.join(RUN_SOURCE_FILE);
        let text = sph_core::input::read_text_limited(&path, 64 * 1024, "run source file")
            .map_err(|e| {
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
        Ok((scene, quick))
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
