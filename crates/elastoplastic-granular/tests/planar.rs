//! The planar (2D, plane-strain) path: a layer on a floor of boundary particles in the plane
//! `z = 0` rests and carries its weight, runs the same on one and two threads, and a grain
//! off the plane or a volume-map wall is refused.

use elastoplastic_granular::{
    boundary_block, Aabb, Elastoplastic, ElastoplasticParams, InitialStress, ParticleSet,
    PeriodicAxis, Plane, Solids, SolverError, Vec3, WallModel,
};
use sph_core::sampling::cubic_lattice;
use sph_solver::{CollisionBoundary, Dimensions};

const S: f64 = 0.01;

/// A layer `[0, 0.08] × [0, d]` (m) in the plane `z = 0`, periodic along `x`, on a floor of
/// three rows of free-slip boundary particles (the floor plane only keeps particles out);
/// `E` = 5.84e5 Pa, c = 0, φ = 30°, from the geostatic stress.
fn planar_layer(d: f64) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = 5.84e5;
    p.dimensions = Dimensions::Two;
    p.initial_stress = InitialStress::Geostatic;
    p.periodic.push(PeriodicAxis {
        axis: 0,
        lo: 0.0,
        hi: 0.08,
    });
    let solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())];
    let boundary = CollisionBoundary::new(solids, 0.0).unwrap();
    let plane = |lo: Vec3<f64>, hi: Vec3<f64>| {
        Aabb::new(lo - Vec3::z() * (S / 2.0), hi + Vec3::z() * (S / 2.0)).unwrap()
    };
    let x = cubic_lattice(&plane(Vec3::zeros(), Vec3::new(0.08, d, 0.0)), S, 100_000).unwrap();
    let state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    let mut solver = Elastoplastic::with_boundary(p, Box::new(boundary)).unwrap();
    let rows = plane(Vec3::new(0.0, -3.0 * S, 0.0), Vec3::new(0.08, 0.0, 0.0));
    let floor = boundary_block(&rows, S, Vec3::y(), WallModel::FreeSlip, 10_000).unwrap();
    assert!(floor.iter().all(|b| b.position.z == 0.0));
    solver.scheme_mut().set_boundary_particles(floor).unwrap();
    (solver, state)
}

#[test]
fn a_planar_layer_rests_and_carries_its_weight() {
    // 20 layers (d = 0.2 m) for 1 s. Checks, as for the 3D layer (tests/solver.rs): the
    // bottom layer's mean σ_yy within 3 % of −ρ0 g (d − s/2) (a flat bed's vertical stress
    // is its weight above: physics), at rest over the last 0.5 s (99th-percentile speed
    // below 0.05 √(g s), the rest criterion of granular codes), every grain still in the
    // plane, and the density within 1 % of ρ0 (an elastic strain ρ g d / E = 0.7 %).
    let d = 0.2;
    let (mut solver, mut state) = planar_layer(d);
    assert_eq!(state.len(), 8 * 20);
    let bound = 0.05 * (9.81 * S).sqrt();
    let frames = 60;
    for frame in 1..=frames {
        solver.step(&mut state).unwrap();
        if frame > frames / 2 {
            let mut speeds: Vec<f64> = state.velocities.iter().map(|v| v.norm()).collect();
            let k = (speeds.len() as f64 * 0.99) as usize;
            let (_, p99, _) = speeds.select_nth_unstable_by(k, f64::total_cmp);
            assert!(*p99 < bound, "frame {frame}: p99 speed {p99} m/s");
        }
    }
    assert!(state.positions.iter().all(|x| x.z == 0.0));
    let rho0 = solver.params().common.rest_density;
    for r in &state.densities {
        assert!((r / rho0 - 1.0).abs() < 0.01, "density {r} against {rho0}");
    }
    let expected = -rho0 * 9.81 * (d - S / 2.0);
    let bottom: Vec<f64> = state
        .positions
        .iter()
        .zip(solver.stress())
        .filter(|(x, _)| x.y < S)
        .map(|(_, s)| s[(1, 1)])
        .collect();
    assert_eq!(bottom.len(), 8);
    let mean = bottom.iter().sum::<f64>() / bottom.len() as f64;
    assert!(
        (mean / expected - 1.0).abs() < 0.03,
        "bottom σ_yy {mean} Pa against {expected} Pa"
    );
    // Plane strain: no shear across the plane.
    for s in solver.stress() {
        assert_eq!((s[(0, 2)], s[(1, 2)]), (0.0, 0.0));
    }
}

#[test]
fn a_planar_run_is_the_same_on_one_and_two_threads() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let (mut solver, mut state) = planar_layer(0.1);
                for _ in 0..3 {
                    solver.step(&mut state).unwrap();
                }
                (state, solver.stress().to_vec())
            })
    };
    let (a, sa) = run(1);
    let (b, sb) = run(2);
    assert_eq!(a.positions, b.positions);
    assert_eq!(sa, sb);
}

#[test]
fn a_grain_off_the_plane_is_refused_by_index() {
    let (mut solver, mut state) = planar_layer(0.05);
    state.positions[7].z = 1e-3;
    let e = solver.step(&mut state).unwrap_err().to_string();
    assert!(e.contains("particle 7 is at z = 0.001"), "{e}");
}

#[test]
fn a_planar_run_refuses_volume_maps_and_gravity_across_the_plane() {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.dimensions = Dimensions::Two;
    let solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())];
    let domain = Aabb::new(Vec3::new(-0.1, 0.0, -0.1), Vec3::new(0.1, 0.2, 0.1)).unwrap();
    let walls = Elastoplastic::volume_map_walls(solids, &p, domain, None).unwrap();
    let e = elastoplastic_granular::ElastoplasticScheme::solver(p.clone(), walls).unwrap_err();
    assert!(
        matches!(
            e,
            SolverError::InvalidParameter {
                name: "dimensions",
                ..
            }
        ),
        "{e}"
    );
    p.common.gravity = Vec3::new(0.0, -9.81, -1.0);
    let e = p.validate().unwrap_err();
    assert!(
        matches!(
            e,
            SolverError::InvalidParameter {
                name: "gravity",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_seeded_planar_pour_stays_in_the_plane() {
    // A pour one node deep along z (the layer |z| ≤ s/2) with a seed: the seeded shifts move
    // its layers along x only, so every grain is poured into, and stays in, the plane (the
    // solver refuses a grain off it).
    let (mut solver, _) = planar_layer(0.02);
    let mut state = ParticleSet::from_positions(Vec::new(), 0.0, 0.0);
    let mut p = solver.params().clone();
    p.pour = Some(elastoplastic_granular::Pour {
        region: Aabb::new(
            Vec3::new(0.02, 0.0, -S / 2.0),
            Vec3::new(0.06, 0.3, S / 2.0),
        )
        .unwrap(),
        volume_m3: 0.04 * 0.05 * S,
        rate_m3_s: 0.04 * 0.5 * S,
        seed: Some(11),
    });
    let mut poured = Elastoplastic::with_boundary(
        p,
        Box::new(
            CollisionBoundary::new(
                vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())],
                0.0,
            )
            .unwrap(),
        ),
    )
    .unwrap();
    let floor = solver.scheme_mut().boundary_particles().to_vec();
    poured.scheme_mut().set_boundary_particles(floor).unwrap();
    for _ in 0..15 {
        poured.step(&mut state).unwrap();
    }
    assert_eq!(state.len(), 4 * 5);
    assert!(state.positions.iter().all(|x| x.z == 0.0));
    let xs: std::collections::BTreeSet<u64> =
        state.positions.iter().map(|x| x.x.to_bits()).collect();
    assert!(xs.len() > 4, "the seeded layers are shifted along x");
}
