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
