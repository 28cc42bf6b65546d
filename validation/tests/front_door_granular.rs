//! The `iisph-granular` example `granular_column` builds what the shipped scene
//! `scenes/granular_column_collapse.toml` builds in quick mode (through `sph-sim`'s
//! `SceneSetup`): the same particles, masses (calibrated against volume-map walls) and
//! boundary, so that a user copying the example gets the scene.

#[allow(dead_code)] // the example's `main` is not called here
#[path = "../../crates/iisph-granular/examples/granular_column.rs"]
mod example;

use std::path::Path;

use sph_scene::Scene;
use sph_sim::SceneSetup;

#[test]
fn the_example_builds_the_shipped_granular_scene() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/granular_column_collapse.toml");
    let scene = Scene::load(&path).unwrap().quick();
    let setup = SceneSetup::<f32>::new(&scene).unwrap();
    let (solver, state) = example::build().unwrap();

    assert_eq!(state.len(), setup.state.len());
    assert_eq!(solver.boundary().name(), setup.boundary.name());
    // The scene samples its lattice in f64 and rounds to f32; the example samples in f32:
    // positions agree to a few f32 ulps of 0.2 m, masses (calibrated from them) to 1e-5.
    for (k, (a, b)) in state
        .positions
        .iter()
        .zip(&setup.state.positions)
        .enumerate()
    {
        assert!((a - b).norm() < 1e-6, "particle {k}: {a:?} vs {b:?}");
    }
    let mut lowered = 0;
    for (k, (a, b)) in state.masses.iter().zip(&setup.state.masses).enumerate() {
        assert!((a / b - 1.0).abs() < 1e-5, "mass {k}: {a} vs {b}");
        lowered += usize::from(*b < setup.params.common().particle_mass());
    }
    assert!(
        lowered > 0,
        "the scene calibrates its masses; so must the example"
    );
    let (p, q) = (
        solver.params(),
        match &setup.params {
            sph_scene::SolverParams::Granular(p) => p.clone(),
            other => panic!("the scene is granular IISPH, got {other:?}"),
        },
    );
    assert_eq!(format!("{p:?}"), format!("{q:?}"), "solver parameters");
}
