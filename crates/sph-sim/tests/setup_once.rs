//! A scene is built once: `SceneSim::from_setup` takes the set-up's particles and boundary
//! as they are, without sampling the fluid or building the solids again (the scene's fluids
//! and solids are cleared here before it is called: a second build would find none).

use std::path::Path;

use sph_scene::Scene;
use sph_sim::{SceneSetup, SceneSim};

fn dam_break() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dam_break.toml");
    Scene::load(&path).unwrap().quick()
}

#[test]
fn the_solver_is_built_from_the_setup_alone() {
    let scene = dam_break();
    let mut setup = SceneSetup::<f32>::new(&scene).unwrap();
    let n = setup.state.len();
    assert_eq!(n, scene.fluid_positions::<f32>().unwrap().len());
    let positions = setup.state.positions.clone();
    let boundary = setup.boundary.name();
    setup.scene.fluids.clear();
    setup.scene.solids.clear();
    setup.scene.tank = None;
    let mut sim = SceneSim::from_setup(setup).unwrap();
    assert_eq!(sim.state.len(), n);
    assert_eq!(sim.state.positions, positions);
    assert_eq!(sim.solver().boundary().name(), boundary);
    sim.advance().unwrap();
}

#[test]
fn new_is_setup_then_from_setup() {
    let scene = dam_break();
    let mut a = SceneSim::<f32>::new(&scene).unwrap();
    let mut b = SceneSim::from_setup(SceneSetup::<f32>::new(&scene).unwrap()).unwrap();
    for _ in 0..2 {
        a.advance().unwrap();
        b.advance().unwrap();
    }
    assert_eq!(a.state.positions, b.state.positions);
}

/// The fluid sample that the load-time checks took is reused by the set-up only for the
/// scene it was taken from: after a typed edit of a fluid the set-up samples the edited
/// block (as many particles as the lattice of the edited block, sampled here directly).
#[test]
fn an_edited_scene_is_sampled_again() {
    let mut scene = dam_break();
    let before = SceneSetup::<f32>::new(&scene).unwrap().state.len();
    let sph_scene::FluidSpec::Block { min, max, .. } = &mut scene.fluids[0] else {
        panic!("the dam-break fluid is a block")
    };
    max[1] = min[1] + 0.5 * (max[1] - min[1]);
    let block = sph_core::Aabb {
        min: sph_core::Vec3::from(*min),
        max: sph_core::Vec3::from(*max),
    };
    scene.check().unwrap();
    let edited = SceneSetup::<f32>::new(&scene).unwrap().state.len();
    let lattice =
        sph_core::sampling::cubic_lattice(&block, scene.particle_spacing, usize::MAX).unwrap();
    assert_eq!(scene.fluids.len(), 1);
    assert_eq!(edited, lattice.len());
    assert!(edited < before, "{edited} vs {before}");
}

/// `to_original_order` undoes the solver's reordering: the result indexed by id equals the
/// solver-order values looked up through `ids` (checked after frames that reorder), and at
/// the start (no reordering yet) it is the solver's order itself.
#[test]
fn values_come_back_in_the_scenes_order() {
    let scene = dam_break();
    let mut sim = SceneSim::<f32>::new(&scene).unwrap();
    let initial = sim.state.positions.clone();
    assert_eq!(
        sim.to_original_order(&sim.state.positions).unwrap(),
        initial
    );
    let mut reordered = false;
    for _ in 0..3 {
        reordered |= sim.advance().unwrap().reordered;
    }
    assert!(reordered, "the dam break's solver reorders its particles");
    let ordered = sim.to_original_order(&sim.state.positions).unwrap();
    for (k, &id) in sim.ids.iter().enumerate() {
        assert_eq!(ordered[id as usize], sim.state.positions[k]);
    }
    let err = sim.to_original_order(&[0u8; 3]).unwrap_err();
    assert!(
        err.to_string().contains("need one value per particle"),
        "{err}"
    );
}
