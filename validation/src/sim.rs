//! The shipped scenes in the validation's modes; scene running itself is the `sph-sim`
//! crate.

use anyhow::Result;
use sph_scene::Scene;

pub use sph_sim::SceneSim;

use crate::{workspace_root, Mode};

/// The shipped scene `scenes/<name>.toml`, with its `[quick]` overrides in quick mode.
pub fn shipped_scene(name: &str, mode: Mode) -> Result<Scene> {
    let scene = Scene::load(&workspace_root().join("scenes").join(format!("{name}.toml")))?;
    Ok(mode.pick(scene.quick(), scene))
}
