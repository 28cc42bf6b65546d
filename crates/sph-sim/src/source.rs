//! Where a simulation's scene comes from ([`SceneSource`]): the scene file's text and what
//! was applied to it, shared by saved simulations ([`crate::saved`]) and run directories
//! ([`crate::run_dir`]).

use std::path::{Path, PathBuf};

use sph_scene::{Override, Scene};

use crate::error::SimError;

/// Where a simulation's scene comes from: the scene file's path and text, and what was
/// applied to it (overrides, quick mode).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneSource {
    /// The scene file (messages name it; mesh paths are relative to its directory).
    pub path: PathBuf,
    /// The scene file's text as read.
    pub text: String,
    /// The overrides applied to the file's keys, in order ([`Override`]).
    pub overrides: Vec<Override>,
    /// Whether the scene's `[quick]` overrides apply ([`Scene::quick`]).
    pub quick: bool,
}

impl SceneSource {
    /// Reads the scene file at `path` ([`Scene::read_text`]) and returns its source with the
    /// checked scene ([`SceneSource::scene`]).
    pub fn load(
        path: &Path,
        overrides: Vec<Override>,
        quick: bool,
    ) -> Result<(Self, Scene), SimError> {
        let source = Self {
            path: path.to_path_buf(),
            text: Scene::read_text(path)?,
            overrides,
            quick,
        };
        let scene = source.scene()?;
        Ok((source, scene))
    }

    /// The checked scene: the text with the overrides applied ([`Scene::parse_str_with`]),
    /// then the `[quick]` overrides if asked.
    pub fn scene(&self) -> Result<Scene, SimError> {
        let scene = Scene::parse_str_with(&self.text, &self.path, &self.overrides)?;
        Ok(if self.quick { scene.quick() } else { scene })
    }
}
