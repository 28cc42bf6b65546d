//! The scenes shipped in `scenes/` parse, produce the particle counts stated in their
//! comments (within ±15 % of the paper's targets), and build their solids. They read the
//! workspace's `scenes/`, so this file stays out of the published package (`exclude` in
//! `Cargo.toml`).

use std::path::{Path, PathBuf};

use sph_core::{Sdf, Vec3};
use sph_scene::{BoundaryModel, FluidSpec, Precision, Scene, SolverSpec};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

fn counts(scene: &Scene) -> (usize, usize) {
    let full = scene.fluid_positions::<f32>().unwrap().len();
    let quick = scene.quick().fluid_positions::<f32>().unwrap().len();
    (full, quick)
}

fn check_inside(scene: &Scene) {
    let pts = scene.fluid_positions::<f64>().unwrap();
    let solids = scene.build_solids::<f64>().unwrap();
    assert!(!solids.is_empty());
    for p in &pts {
        for s in &solids {
            assert!(s.signed_distance(p) > 0.0, "{p:?}");
        }
    }
}

#[test]
fn dam_break_matches_table_1() {
    let s = Scene::load(&scene_path("dam_break.toml")).unwrap();
    assert_eq!(s.name, "dam_break");
    assert_eq!(s.precision, Precision::F32);
    assert_eq!(s.solver.kind_name(), "pbf");
    assert_eq!((s.solver.substeps(), s.solver.iterations()), (4, 3));
    let SolverSpec::Pbf(pbf) = &s.solver else {
        panic!("not PBF: {:?}", s.solver)
    };
    assert_eq!(pbf.vorticity_epsilon, Some(0.0));
    assert_eq!(
        s.boundary.model,
        BoundaryModel::Collision,
        "the paper's walls"
    );
    assert_eq!((s.frame_dt_s, s.duration_s), (0.016, 6.0));
    assert_eq!(s.frame_count(), 375);
    let (full, quick) = counts(&s);
    println!("dam_break: {full} particles, quick {quick}");
    assert_eq!(full, 98_304);
    assert_eq!(quick, 12_288);
    assert!((full as f64 - 100_000.0).abs() <= 15_000.0);
    assert!((8_000..=15_000).contains(&quick));
    let q = s.quick();
    assert_eq!((q.particle_spacing, q.duration_s), (0.025, 1.5));
    assert!(q.quick_overrides.is_none());
    check_inside(&s);
    check_inside(&q);
}

#[test]
fn bunny_drop_matches_fig_3() {
    let s = Scene::load(&scene_path("bunny_drop.toml")).unwrap();
    assert_eq!((s.solver.substeps(), s.solver.iterations()), (4, 10));
    assert!(matches!(s.fluids[1], FluidSpec::Mesh { .. }));
    let (full, quick) = counts(&s);
    println!("bunny_drop: {full} particles, quick {quick}");
    assert!((full as f64 - 80_000.0).abs() <= 0.15 * 80_000.0, "{full}");
    assert!(quick <= 10_000, "{quick}");
    check_inside(&s);
}

#[test]
fn armadillo_splash_matches_table_1() {
    let s = Scene::load(&scene_path("armadillo_splash.toml")).unwrap();
    assert_eq!((s.solver.substeps(), s.solver.iterations()), (2, 3));
    let (full, quick) = counts(&s);
    println!("armadillo_splash: {full} particles, quick {quick}");
    assert!(
        (full as f64 - 128_000.0).abs() <= 0.15 * 128_000.0,
        "{full}"
    );
    assert!(quick <= 10_000, "{quick}");
    check_inside(&s);
}

/// Every `.toml` in `scenes/` (including scenes written by others) parses.
#[test]
fn every_shipped_scene_parses() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let s = Scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
            let q = s.quick();
            println!(
                "{}: {} particles (quick {})",
                p.display(),
                s.fluid_positions::<f32>().unwrap().len(),
                q.fluid_positions::<f32>().unwrap().len()
            );
            n += 1;
        }
    }
    assert!(n >= 3);
}

/// Mesh fluids: the particle volume `N s³` approximates the mesh volume (the lattice is
/// unbiased: a point counts when its centre is inside), and the velocities line up.
#[test]
fn mesh_fluid_volume_and_velocities() {
    let s = Scene::load(&scene_path("bunny_drop.toml")).unwrap();
    let FluidSpec::Mesh { mesh, .. } = &s.fluids[1] else {
        unreachable!()
    };
    // Divergence theorem volume of the placed closed mesh.
    let v = mesh.mesh.vertices();
    let vol: f64 = mesh
        .mesh
        .triangles()
        .iter()
        .map(|t| {
            let (a, b, c) = (v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum();
    let pts = s.fluid_positions::<f64>().unwrap();
    let pool = 64 * 16 * 64;
    let n = pts.len() - pool;
    let sp = s.particle_spacing;
    let rel = (n as f64 * sp * sp * sp - vol) / vol;
    println!(
        "bunny: mesh volume {vol:.5} m³, {n} particles, N s³ off by {:.2} %",
        rel * 100.0
    );
    assert!(rel.abs() < 0.03, "{rel}");
    let vel = s.fluid_velocities::<f32>().unwrap();
    assert_eq!(vel.len(), pts.len());
    assert!(vel.iter().all(|v| *v == Vec3::zeros()));
}

/// Building twice does not reload the meshes (they are shared through an `Arc`) and the
/// grid SDF of a scene mesh agrees with the exact distance (build time is a benchmark's
/// business, not a test's).
#[test]
fn meshes_are_cached_and_grids_match_exact_distance() {
    let s = Scene::load(&scene_path("armadillo_splash.toml")).unwrap();
    let FluidSpec::Mesh { mesh, .. } = &s.fluids[1] else {
        unreachable!()
    };
    let q = s.quick();
    let FluidSpec::Mesh { mesh: qm, .. } = &q.fluids[1] else {
        unreachable!()
    };
    assert!(std::sync::Arc::ptr_eq(&mesh.mesh, &qm.mesh));
    let tris = mesh.mesh.triangles().len();
    // The dragon as a solid GridSdf at ~100 cells along its length.
    let cell = mesh.mesh.bounds().extent().x / 100.0;
    let g = sph_core::GridSdf::new(&mesh.mesh, cell, 2.0 * cell).unwrap();
    println!("dragon: {tris} triangles, grid {:?}", g.dims());
    // Spot check against the exact distance.
    let b = g.grid_box();
    let mut worst: f64 = 0.0;
    for i in 0..50 {
        let f = (i as f64 + 0.5) / 50.0;
        let p = b.min
            + b.extent()
                .component_mul(&Vec3::new(f, (f * 7.0).fract(), (f * 13.0).fract()));
        let exact = mesh.mesh.signed_distance_exact(&p);
        let v = g.signed_distance(&p);
        worst = worst.max((v - exact).abs() / cell);
        if exact.abs() > cell {
            assert_eq!(v < 0.0, exact < 0.0, "{p:?}");
        }
    }
    println!("dragon grid: max |grid - exact| at 50 points = {worst:.3} cells");
    assert!(worst < 0.97);
}

/// The shipped IISPH dam break reads as an IISPH scene with volume-map walls.
#[test]
fn shipped_dam_break_iisph() {
    let path = scene_path("dam_break_iisph.toml");
    let s = Scene::load(&path).unwrap();
    assert_eq!(s.solver.kind(), sph_scene::SolverKind::Iisph);
    assert_eq!(s.boundary.model, BoundaryModel::VolumeMap);
    assert_eq!(s.solver.substeps(), 8);
}

/// The cylinder fluid of the axisymmetric collapse: the counts the scene's comment states
/// (a 16- and 8-spacing disc of 812 and 208 lattice points, 16 and 8 layers), every particle
/// inside the cylinder, the centroid on the axis, velocities zero.
#[test]
fn cylinder_fluid_of_the_axisymmetric_collapse() {
    let s = Scene::load(&scene_path("granular_column_collapse_axisymmetric.toml")).unwrap();
    let FluidSpec::Cylinder {
        base_center: c,
        radius,
        height,
        ..
    } = s.fluids[0]
    else {
        panic!("not a cylinder: {:?}", s.fluids[0]);
    };
    for (scene, expected) in [(s.clone(), 812 * 16), (s.quick(), 208 * 8)] {
        let p = scene.fluid_positions::<f64>().unwrap();
        assert_eq!(p.len(), expected);
        let n = p.len() as f64;
        let (mx, mz) = p
            .iter()
            .fold((0.0, 0.0), |(x, z), q| (x + q.x / n, z + q.z / n));
        assert!((mx - c[0]).abs() < 1e-9 && (mz - c[2]).abs() < 1e-9);
        for q in &p {
            assert!((q.x - c[0]).hypot(q.z - c[2]) < radius);
            assert!(q.y > c[1] && q.y < c[1] + height);
        }
        let v = scene.fluid_velocities::<f64>().unwrap();
        assert!(v.iter().all(|v| v.norm() == 0.0));
    }
}

/// The elastoplastic heap: the block of `granular_repose_thesis_30` in a slab periodic across `z`
/// (0.06 m: at least the support plus skin, 2.7 spacings, at the quick spacing), walls of
/// boundary particles (the tank free-slip, the base no-slip); its stated particle counts.
#[test]
fn granular_heap_elastoplastic_is_a_periodic_slab_with_particle_walls() {
    let s = Scene::load(&scene_path("granular_heap_elastoplastic.toml")).unwrap();
    assert_eq!(s.solver.kind(), sph_scene::SolverKind::Elastoplastic);
    assert_eq!(s.boundary.model, BoundaryModel::Particles);
    assert_eq!(s.periodic_axes(), vec![(2, 0.0, 0.06)]);
    assert_eq!(s.walls.tank, Some(sph_scene::WallModel::FreeSlip));
    assert_eq!(s.walls.solids, vec![Some(sph_scene::WallModel::NoSlip)]);
    assert_eq!(counts(&s), (80 * 30 * 6, 40 * 15 * 3));
    check_inside(&s);
    let sph_scene::SolverParams::Elastoplastic(p) = s.solver_params::<f64>().unwrap() else {
        panic!("not elastoplastic")
    };
    assert_eq!(
        p.wall_models,
        vec![sph_scene::WallModel::FreeSlip, sph_scene::WallModel::NoSlip]
    );
    assert_eq!(p.boundary_particle_region, s.tank);
    assert_eq!(p.friction_angle_deg, 30.0);
    // the friction angle is the angle of repose under this match
    assert_eq!(p.cone_match, elastoplastic_granular::ConeMatch::SimpleShear);
    assert_eq!(p.viscosity_alpha, 0.5);
}

/// The drained heaps (`scenes/granular_repose_{20,30,40}.toml`): a
/// bed 0.2 m high, periodic along `x` (the period per θ) and `z` (0.06 m), on a no-slip plate
/// with a slot 0.24 m wide centred on the seam, the sump's floor 0.6 m below the plate; the
/// particle counts their comments state.
#[test]
fn granular_repose_scenes_are_drained_beds() {
    for (theta, period) in [(20.0, 1.6), (30.0, 1.2), (40.0, 1.0)] {
        let s = Scene::load(&scene_path(&format!("granular_repose_{theta:.0}.toml"))).unwrap();
        assert_eq!(s.solver.kind(), sph_scene::SolverKind::Elastoplastic);
        assert_eq!(s.boundary.model, BoundaryModel::Particles);
        assert_eq!(s.periodic_axes(), vec![(0, 0.0, period), (2, 0.0, 0.06)]);
        let SolverSpec::Elastoplastic(e) = &s.solver else {
            panic!("not elastoplastic")
        };
        assert_eq!(e.friction_angle_deg, theta);
        assert_eq!(
            e.cone_match,
            Some(elastoplastic_granular::ConeMatch::SimpleShear)
        );
        let Some(sph_scene::SolidSpec::Box { min, max }) = s.solids.first() else {
            panic!("the plate is a box")
        };
        assert_eq!(min[0], 0.12, "slot 0.24 m wide");
        assert!((max[0] - (period - 0.12)).abs() < 1e-12, "slot 0.24 m wide");
        assert_eq!(max[1], 0.0, "the plate's top is the floor y = 0");
        assert_eq!(s.walls.solids, vec![Some(sph_scene::WallModel::NoSlip)]);
        let tank = s.tank.unwrap();
        assert!((min[1] - 0.6 - tank.min.y).abs() < 1e-12, "sump 0.6 m deep");
        let cells = |sp: f64| (period / sp).round() as usize;
        assert_eq!(
            counts(&s),
            (cells(0.01) * 20 * 6, cells(0.02) * 10 * 3),
            "θ = {theta}"
        );
    }
}

/// The trapdoor variants of the drained heaps (`scenes/granular_repose_trapdoor_*.toml`):
/// the open-slot scene's bed, period and plate, with a
/// channel 0.6 m deep under the slot (free-slip walls down to the tank's floor) closed by a
/// no-slip trapdoor filling the slot that is lowered at 5 cm/s for 12 s (0.6 m: it stops
/// above the channel's floor), the cap after it stops.
#[test]
fn granular_repose_trapdoor_scenes_lower_a_door_under_the_slot() {
    for theta in [20, 30, 40] {
        let open = Scene::load(&scene_path(&format!("granular_repose_{theta}.toml"))).unwrap();
        let s = Scene::load(&scene_path(&format!(
            "granular_repose_trapdoor_{theta}.toml"
        )))
        .unwrap();
        assert_eq!(s.periodic_axes(), open.periodic_axes());
        assert_eq!(counts(&s), counts(&open), "θ = {theta}: the same bed");
        use sph_scene::SolidSpec::Box;
        use sph_scene::WallModel::{FreeSlip, NoSlip};
        let (
            Some(Box { min, max }),
            Some(Box {
                min: plate,
                max: plate_top,
            }),
        ) = (s.solids.first(), open.solids.first())
        else {
            panic!("the plates are boxes")
        };
        assert_eq!((min, max), (plate, plate_top), "the open scene's plate");
        assert_eq!(
            s.walls.solids,
            vec![Some(NoSlip), Some(FreeSlip), Some(NoSlip)]
        );
        let tank = s.tank.unwrap();
        let Some(Box {
            min: wmin,
            max: wmax,
        }) = s.solids.get(1)
        else {
            panic!("the channel's walls are a box")
        };
        assert_eq!((wmin[0], wmax[0], wmax[1]), (min[0], max[0], 0.0));
        assert_eq!(wmin[1], tank.min.y, "the walls reach the channel's floor");
        assert!(
            (max[1] - 0.6 - tank.min.y - 0.1).abs() < 1e-12,
            "0.6 m under the plate"
        );
        let Some(Box {
            min: door,
            max: top,
        }) = s.solids.get(2)
        else {
            panic!("the trapdoor is a box")
        };
        assert_eq!(
            (door[0], top[0], top[1]),
            (-0.12, 0.12, 0.0),
            "fills the slot"
        );
        assert_eq!(s.motions[..2], [None, None]);
        let m = s.motions[2].expect("the trapdoor moves");
        assert_eq!(m.velocity, [0.0, -0.05, 0.0]);
        let travel = 0.05 * m.duration_s;
        assert!((travel - 0.6).abs() < 1e-12 && door[1] - travel > tank.min.y);
        assert!(
            s.quick().duration_s > m.duration_s,
            "the cap after the door stops"
        );
    }
}

/// `granular_repose_poured_{20,30,40}.toml`: no grains at the start, a funnel 0.1 m wide
/// at the period's middle pouring 0.16 m² of cross-section over the slab's 0.06 m at
/// 0.012 m² a second (30 grains a second at 20 mm); the period holds the heap the cone
/// predicts with room beyond its toes.
#[test]
fn granular_repose_poured_pours_a_heap_the_period_holds() {
    let slab = 0.06;
    for theta in [20.0_f64, 30.0, 40.0] {
        let full =
            Scene::load(&scene_path(&format!("granular_repose_poured_{theta}.toml"))).unwrap();
        let quick = full.quick();
        assert_eq!(counts(&quick).0, 0);
        assert_eq!((quick.poured_grains(), full.poured_grains()), (1200, 9600));
        let pour = quick.pour.unwrap();
        assert!((pour.volume_m3 - 0.16 * slab).abs() < 1e-12);
        assert!((pour.rate_m3_s - 0.012 * slab).abs() < 1e-12);
        assert!((pour.max[0] - pour.min[0] - 0.1).abs() < 1e-12);
        assert!((pour.max[2] - pour.min[2] - slab).abs() < 1e-12);
        let (axis, lo, period) = quick.periodic_axes()[0];
        assert_eq!((axis, lo), (0, 0.0));
        assert!((0.5 * (pour.min[0] + pour.max[0]) - 0.5 * period).abs() < 1e-12);
        let SolverSpec::Elastoplastic(e) = &quick.solver else {
            panic!("theta {theta}: not elastoplastic")
        };
        assert_eq!(e.friction_angle_deg, theta);
        // The triangle of the poured cross-section at the predicted slope θ, with a fifth of
        // the period to spare beyond its toes: base = 2 sqrt(area / tan θ).
        let area = pour.volume_m3 / 0.06;
        let base = 2.0 * (area / theta.to_radians().tan()).sqrt();
        assert!(
            base < 0.8 * period,
            "theta {theta}: base {base} m, period {period} m"
        );
    }
}
