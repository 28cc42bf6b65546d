//! The solver on small blocks: a settled layer against hydrostatics, determinism across
//! thread counts, resuming from a checkpoint, parameter checks.

use elastoplastic_granular::{
    boundary_block, Aabb, BoxSdf, Elastoplastic, ElastoplasticParams, ElastoplasticScheme,
    InitialStress, Inverted, ParticleSet, PeriodicAxis, Plane, Solids, SolverError, Vec3,
    WallModel,
};
use nalgebra::Matrix3;
use sph_core::sampling::cubic_lattice;

const S: f64 = 0.01;

/// A block `[0, w] × [0, d] × [0, 0.03]` (m) in a box `[0, box_w] × [0, 0.5] × [0, 0.03]`
/// whose faces are all one free-slip solid; `E` = 5.84e5 Pa.
fn block(w: f64, d: f64, box_w: f64) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = 5.84e5;
    p.wall_models = vec![WallModel::FreeSlip];
    let tank = Aabb::new(Vec3::zeros(), Vec3::new(box_w, 0.5, 0.03)).unwrap();
    let solids: Solids<f64> = vec![Box::new(Inverted(BoxSdf::new(tank).unwrap()))];
    let walls = Elastoplastic::volume_map_walls(solids, &p, tank, None).unwrap();
    let region = Aabb::new(Vec3::zeros(), Vec3::new(w, d, 0.03)).unwrap();
    let x = cubic_lattice(&region, S, 100_000).unwrap();
    let state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    (ElastoplasticScheme::solver(p, walls).unwrap(), state)
}

/// A layer `[0, 0.08] × [0, d] × [0, 0.03]` (m), periodic along `x` and `z`, on a floor of
/// three rows of free-slip boundary particles (the floor plane only keeps particles out);
/// `E` = 5.84e5 Pa, c = 0, φ = 30°. `geostatic`: it starts from `σ_yy = −ρ0 g (d − y)`,
/// `σ_xx = σ_zz = K0 σ_yy`, `K0 = ν/(1 − ν)` ([`InitialStress::Geostatic`]: the depth below
/// each column's top grain plus half a spacing is `d − y` on this lattice).
fn periodic_layer(d: f64, geostatic: bool) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = 5.84e5;
    p.wall_models = vec![WallModel::ContactOnly];
    let hi = Vec3::new(0.08, d, 0.03);
    for axis in [0, 2] {
        p.periodic.push(PeriodicAxis {
            axis,
            lo: 0.0,
            hi: hi[axis],
        });
    }
    let solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())];
    let domain = Aabb::new(
        Vec3::new(-0.05, 0.0, -0.05),
        hi + Vec3::new(0.05, 0.3, 0.05),
    )
    .unwrap();
    let walls = Elastoplastic::volume_map_walls(solids, &p, domain, None).unwrap();
    let x = cubic_lattice(&Aabb::new(Vec3::zeros(), hi).unwrap(), S, 100_000).unwrap();
    let state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    if geostatic {
        p.initial_stress = InitialStress::Geostatic;
    }
    let mut solver = ElastoplasticScheme::solver(p, walls).unwrap();
    let rows = Aabb::new(Vec3::new(0.0, -3.0 * S, 0.0), Vec3::new(hi.x, 0.0, hi.z)).unwrap();
    let floor = boundary_block(&rows, S, Vec3::y(), WallModel::FreeSlip, 10_000).unwrap();
    solver.scheme_mut().set_boundary_particles(floor).unwrap();
    (solver, state)
}

#[test]
fn a_geostatic_layer_on_a_particle_floor_rests_and_carries_its_weight() {
    // 20 layers (d = 0.2 m), periodic sideways, for 1 s. Checks: the bottom layer's mean
    // σ_yy within 3 % of −ρ0 g (d − s/2) (its centres lie d − s/2 below the surface; a flat
    // bed's vertical stress within 3 % of ρ g d), and at rest by the criterion of granular
    // codes over the last 0.5 s: the 99th-percentile speed below 0.05 √(g s).
    // (With volume-map walls the same layer does not rest: docs/elastoplastic-granular.md.)
    let d = 0.2;
    let (mut solver, mut state) = periodic_layer(d, true);
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
    let rho0 = solver.params().common.rest_density;
    let expected = -rho0 * 9.81 * (d - S / 2.0);
    let bottom: Vec<f64> = state
        .positions
        .iter()
        .zip(solver.stress())
        .filter(|(x, _)| x.y < S)
        .map(|(_, s)| s[(1, 1)])
        .collect();
    assert_eq!(bottom.len(), 8 * 3);
    let mean = bottom.iter().sum::<f64>() / bottom.len() as f64;
    assert!(
        (mean / expected - 1.0).abs() < 0.03,
        "bottom σ_yy {mean} Pa against {expected} Pa"
    );
}

#[test]
fn periodic_layers_on_particle_floors_are_deterministic_and_resumable() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let (mut solver, mut state) = periodic_layer(0.05, false);
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
    let (mut solver, mut state) = periodic_layer(0.05, false);
    solver.step(&mut state).unwrap();
    let (saved_particles, saved) = (state.clone(), solver.save_state());
    for _ in 0..2 {
        solver.step(&mut state).unwrap();
    }
    let (mut resumed, _) = periodic_layer(0.05, false);
    let mut particles = saved_particles;
    resumed.restore_state(&saved, particles.len()).unwrap();
    for _ in 0..2 {
        resumed.step(&mut particles).unwrap();
    }
    assert_eq!(particles.positions, state.positions);
    assert_eq!(resumed.stress(), solver.stress());
    assert_eq!(state.positions, a.positions);
}

#[test]
fn a_grain_out_of_contact_carries_no_stress() {
    // One particle, no neighbours, no walls, no gravity, started under a compressive
    // stress: a grain in the air has nothing to push against, so its stress is zero after
    // one step (its velocity gradient is zero, so without the rule it would keep it).
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = 5.84e5;
    p.common.gravity = Vec3::zeros();
    let mut solver = Elastoplastic::new(p, Vec::new()).unwrap();
    let mut state = ParticleSet::from_positions(vec![Vec3::new(0.1, 0.1, 0.1)], 2.04e-3, 2040.0);
    let sigma = Matrix3::from_diagonal(&Vec3::new(-500.0, -1000.0, -500.0));
    solver.scheme_mut().set_stress(&[sigma]).unwrap();
    solver.step(&mut state).unwrap();
    assert_eq!(solver.stress()[0], Matrix3::zeros());
    assert_eq!(state.velocities[0], Vec3::zeros());
}

fn run(threads: usize, frames: usize) -> (ParticleSet<f64>, Vec<f64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let (mut solver, mut state) = block(0.1, 0.1, 0.3);
        for _ in 0..frames {
            solver.step(&mut state).unwrap();
        }
        let stress = solver
            .stress()
            .iter()
            .flat_map(|m| m.iter().copied())
            .collect();
        (state, stress)
    })
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    let (a, sa) = run(1, 4);
    let (b, sb) = run(2, 4);
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.velocities, b.velocities);
    assert_eq!(a.densities, b.densities);
    assert_eq!(sa, sb);
}

#[test]
fn a_resumed_run_repeats_the_uninterrupted_one() {
    let (mut solver, mut state) = block(0.1, 0.1, 0.3);
    for _ in 0..2 {
        solver.step(&mut state).unwrap();
    }
    let (saved_particles, saved) = (state.clone(), solver.save_state());
    assert!(solver.plastic_strain().iter().any(|&k| k > 0.0));
    for _ in 0..2 {
        solver.step(&mut state).unwrap();
    }
    let (mut resumed, _) = block(0.1, 0.1, 0.3);
    let mut particles = saved_particles;
    resumed.restore_state(&saved, particles.len()).unwrap();
    for _ in 0..2 {
        resumed.step(&mut particles).unwrap();
    }
    assert_eq!(particles.positions, state.positions);
    assert_eq!(resumed.stress(), solver.stress());
    assert_eq!(resumed.plastic_strain(), solver.plastic_strain());
}

#[test]
fn invalid_parameters_are_named() {
    let base = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    type Change = fn(&mut ElastoplasticParams<f64>);
    let cases: [(&str, Change); 7] = [
        ("periodic", |p| {
            p.periodic.push(PeriodicAxis {
                axis: 2,
                lo: 0.0,
                hi: 0.02,
            })
        }),
        ("periodic", |p| {
            p.periodic.push(PeriodicAxis {
                axis: 3,
                lo: 0.0,
                hi: 1.0,
            })
        }),
        ("poisson_ratio", |p| p.poisson_ratio = 0.5),
        ("youngs_modulus", |p| p.youngs_modulus = -1.0),
        ("dilatancy_angle_deg", |p| p.dilatancy_angle_deg = 40.0),
        ("cfl_number", |p| p.cfl_number = 1e-9),
        ("skin", |p| p.skin = f64::NAN),
    ];
    assert!(base.validate().is_ok());
    for (name, change) in cases {
        let mut p = base.clone();
        change(&mut p);
        match p.validate() {
            Err(SolverError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
}

/// A block `[0, 0.04]² × [0, 0.03]` (m) over a floor, moving as a whole along `x` at
/// `fraction` of the sound speed `√(E/ρ0)` (no relative velocity: no viscosity, no stress).
fn sliding_block(fraction: f64) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = 5.84e5;
    let c = p.sound_speed();
    let solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())];
    let region = Aabb::new(Vec3::zeros(), Vec3::new(0.04, 0.04, 0.03)).unwrap();
    let x = cubic_lattice(&region, S, 1000).unwrap();
    let mut state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    state
        .velocities
        .iter_mut()
        .for_each(|v| *v = Vec3::new(fraction * c, 0.0, 0.0));
    (Elastoplastic::new(p, solids).unwrap(), state)
}

#[test]
fn a_particle_faster_than_sound_is_a_blow_up_without_a_solid_to_catch_it() {
    // The explicit step Δt ≤ C h / c holds the scheme within its Courant condition only
    // while the particles are slower than c; nothing encloses this block, so only the
    // speed can tell. At half the sound speed the frame runs.
    let (mut solver, mut state) = sliding_block(0.5);
    solver.step(&mut state).unwrap();
    let (mut solver, mut state) = sliding_block(2.0);
    match solver.step(&mut state) {
        Err(SolverError::BlowUp {
            particle, reason, ..
        }) => {
            assert!(particle < state.len());
            assert!(reason.contains("above the sound speed"), "{reason}");
        }
        other => panic!("expected a blow-up, got {other:?}"),
    }
}

#[test]
fn a_prepared_solver_shows_the_initial_stress_at_frame_0_and_steps_as_an_unprepared_one() {
    // `FluidSolver::prepare` applies the geostatic stress before the first frame (so that
    // frame 0 is written with it); the first frame's reordering then permutes it. The
    // geostatic stress is a function of each particle's position and the set of columns, so
    // the prepared and the unprepared solver must agree bit for bit after two frames.
    use sph_solver::FluidSolver;
    let (mut plain, mut plain_state) = periodic_layer(0.1, true);
    let (mut prepared, mut prepared_state) = periodic_layer(0.1, true);
    assert!(FluidSolver::particle_fields(&plain)[0].1.is_empty());
    FluidSolver::prepare(&mut prepared, &prepared_state).unwrap();
    let fields = FluidSolver::particle_fields(&prepared);
    let (name, stress) = &fields[0];
    assert_eq!(
        (name.as_str(), stress.len()),
        ("stress", 6 * prepared_state.len())
    );
    // The top of the layer is lighter than its bottom: the initial stress is there.
    let syy = |i: usize| stress[6 * i + 1];
    let (top, bottom) = (0..prepared_state.len()).fold((0, 0), |(t, b), i| {
        let y = |k: usize| prepared_state.positions[k].y;
        (
            if y(i) > y(t) { i } else { t },
            if y(i) < y(b) { i } else { b },
        )
    });
    assert!(
        syy(bottom) < syy(top) && syy(top) < 0.0,
        "{} {}",
        syy(bottom),
        syy(top)
    );
    for _ in 0..2 {
        plain.step(&mut plain_state).unwrap();
        prepared.step(&mut prepared_state).unwrap();
    }
    assert_eq!(plain_state.positions, prepared_state.positions);
    assert_eq!(plain_state.velocities, prepared_state.velocities);
    assert_eq!(
        FluidSolver::particle_fields(&plain),
        FluidSolver::particle_fields(&prepared)
    );
}

#[test]
fn the_explicit_step_holds_the_courant_bound_of_the_p_wave() {
    // The P-wave speed from the material's own moduli (stress.rs, `DruckerPrager::matched`),
    // an independent path to `√((K + 4G/3)/ρ0)` (Landau & Lifshitz, Theory of Elasticity,
    // §22); at ν = 0.3 it is `√(0.7/(1.3 × 0.4)) = 1.1602` times `√(E/ρ0)`.
    for (e, nu) in [(5.84e6, 0.3), (5.84e5, 0.3), (1e7, 0.0), (1e7, 0.49)] {
        let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
        p.youngs_modulus = e;
        p.poisson_ratio = nu;
        let m = p.material();
        let c_p = ((m.bulk_modulus + 4.0 / 3.0 * m.shear_modulus) / p.common.rest_density).sqrt();
        // Rounding of the two formulas: a few ulps of the square root's argument.
        assert!(
            (p.p_wave_speed() - c_p).abs() <= 1e-12 * c_p,
            "E {e}, ν {nu}"
        );
        let (n, dt) = p.explicit_steps();
        let limit = p.cfl_number * p.smoothing_length() / c_p;
        let sub = p.common.substep_dt();
        // The step is within the bound, and one step fewer would break it (n is the least).
        assert!(dt <= limit * (1.0 + 1e-12), "E {e}, ν {nu}: {dt} > {limit}");
        assert!(
            n == 1 || sub / (n - 1) as f64 > limit,
            "E {e}, ν {nu}: n = {n} not the least"
        );
    }
    let p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    let ratio = p.p_wave_speed() / p.sound_speed();
    assert!((ratio - (0.7f64 / 0.52).sqrt()).abs() < 1e-12, "{ratio}");
}
