//! The one loader of shipped scenes, and scene variants built from them: the scene is loaded
//! (and checked) once, its typed fields are edited (a solver setting, the fluid block, the
//! tank), and the variant is checked again with [`Scene::check`], the checks [`Scene::load`]
//! runs (fluid inside the tank, solver fields in range, time step, particles), exactly as a
//! file a user writes would be.

use anyhow::Result;
use sph_scene::{CommonSettings, FluidSpec, IisphSettings, Scene, SolverSpec, WaterSettings};

use crate::{workspace_root, Mode};

/// The shipped scene `scenes/<name>.toml` in `mode`: its `[quick]` overrides applied in
/// quick mode, and dropped in either mode (so that edits are not overridden later).
pub fn shipped_scene(name: &str, mode: Mode) -> Result<Scene> {
    let mut scene = Scene::load(&workspace_root().join("scenes").join(format!("{name}.toml")))?;
    if mode == Mode::Quick {
        scene = scene.quick();
    }
    scene.quick_overrides = None;
    Ok(scene)
}

/// Replaces the fluids by one block `[min, max]` at rest, and the tank by `[tank_min,
/// tank_max]` (m). Check the scene after ([`Scene::check`]).
pub fn set_block_and_tank(
    scene: &mut Scene,
    min: [f64; 3],
    max: [f64; 3],
    tank_min: [f64; 3],
    tank_max: [f64; 3],
) {
    scene.fluids = vec![FluidSpec::Block {
        min,
        max,
        velocity: [0.0; 3],
    }];
    scene.tank = Some(sph_core::Aabb {
        min: tank_min.into(),
        max: tank_max.into(),
    });
}

/// IISPH (water) with `substeps` and the IISPH settings `iisph`, every other setting the
/// solver's default.
pub fn iisph_solver(substeps: usize, iisph: IisphSettings) -> SolverSpec {
    SolverSpec::Iisph(WaterSettings {
        common: CommonSettings::new(substeps),
        iisph,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quick_overrides_apply_and_edits_stay() {
        let mut s = shipped_scene("dam_break", Mode::Quick).unwrap();
        assert_eq!(s.particle_spacing, 0.025);
        s.solver.common_mut().substeps = 7;
        s.check().unwrap();
        assert_eq!(s.quick().solver.substeps(), 7);
        assert!(s.quick_overrides.is_none());
        let full = shipped_scene("dam_break", Mode::Full).unwrap();
        assert_eq!(full.particle_spacing, 0.0125);
        assert!(full.quick_overrides.is_none());
    }

    #[test]
    fn edited_block_is_checked_like_a_file() {
        let mut s = shipped_scene("dam_break", Mode::Quick).unwrap();
        set_block_and_tank(&mut s, [0.0; 3], [0.2, 0.4, 0.1], [0.0; 3], [1.0, 0.5, 0.1]);
        s.check().unwrap();
        assert_eq!(s.fluid_positions::<f64>().unwrap().len(), 8 * 16 * 4);
        // a block sticking out of the tank is refused
        set_block_and_tank(&mut s, [0.0; 3], [0.2, 0.6, 0.1], [0.0; 3], [1.0, 0.5, 0.1]);
        let err = s.check().unwrap_err().to_string();
        assert!(err.contains("fluid[0]"), "{err}");
        // a solver setting out of range is refused
        set_block_and_tank(&mut s, [0.0; 3], [0.2, 0.4, 0.1], [0.0; 3], [1.0, 0.5, 0.1]);
        s.solver = iisph_solver(
            1,
            IisphSettings {
                relaxation: Some(2.0),
                ..IisphSettings::default()
            },
        );
        let err = s.check().unwrap_err().to_string();
        assert!(err.contains("solver.relaxation"), "{err}");
    }
}
