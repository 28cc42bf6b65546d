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

/// The volume-map cache of the experiments, `target/cache/volume-maps` under the workspace
/// root (shared with `particles run`'s default when run from the root): a map built by one
/// experiment (or an earlier validation) is loaded by the next that needs it.
pub fn volume_map_cache() -> Result<sph_solver::boundary::VolumeMapCache> {
    let dir = workspace_root()
        .join("target")
        .join("cache")
        .join("volume-maps");
    Ok(sph_solver::boundary::VolumeMapCache::new(dir)?)
}

/// The simulation of `scene` in precision `R`, its volume maps from the experiments' cache
/// ([`volume_map_cache`]).
pub fn scene_sim<R: sph_core::Real>(scene: &Scene) -> Result<SceneSim<R>> {
    Ok(SceneSim::with_cache(scene, Some(&volume_map_cache()?))?)
}
