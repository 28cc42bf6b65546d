//! Moving walls of boundary particles: a floor that moves carries the grains on it (no-slip
//! along it, any model across it) and a free-slip floor sliding under them does not drag
//! them; the wall velocity is checked when set; a moving wall of the parameters
//! (`MovingWall`) stops by itself, resumes bit for bit, wraps across a periodic seam and is
//! checked.

use elastoplastic_granular::boundary_particles::sample_moving_wall;
use elastoplastic_granular::{
    boundary_block, cubic_lattice, Aabb, Elastoplastic, ElastoplasticParams, InitialStress,
    MovingWall, ParticleSet, PeriodicAxis, Solids, SolverError, Vec3, WallModel,
};

const S: f64 = 0.02;

/// An elastic slab `8s × 5s × 4s`, periodic along `x` and `z`, at rest under its geostatic
/// stress on a floor of three rows of boundary particles of model `wall` under `y = 0`
/// (no contact solid: the floor's particles alone hold the slab), the floor moving at
/// `velocity`. Cohesion 100 kPa keeps the slab inside its cone (elastic). Returns the
/// solver, the slab and the period along `x` and `z`.
fn slab(wall: WallModel, velocity: Vec3<f64>) -> (Elastoplastic<f64>, ParticleSet<f64>, Vec3<f64>) {
    let (p, state, hi) = slab_params();
    let solids: Solids<f64> = Vec::new();
    let mut solver = Elastoplastic::new(p, solids).unwrap();
    let rows = Aabb::new(Vec3::new(0.0, -3.0 * S, 0.0), Vec3::new(hi.x, 0.0, hi.z)).unwrap();
    let floor = boundary_block(&rows, S, Vec3::y(), wall, 10_000).unwrap();
    let count = floor.len();
    solver.scheme_mut().set_boundary_particles(floor).unwrap();
    solver
        .scheme_mut()
        .set_boundary_velocity(0..count, velocity)
        .unwrap();
    (solver, state, hi)
}

/// The parameters and particles of [`slab`], and the periods.
fn slab_params() -> (ElastoplasticParams<f64>, ParticleSet<f64>, Vec3<f64>) {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.cohesion = 1e5;
    p.common.dt = 0.02;
    let hi = Vec3::new(8.0 * S, 5.0 * S, 4.0 * S);
    for axis in [0, 2] {
        p.periodic.push(PeriodicAxis {
            axis,
            lo: 0.0,
            hi: hi[axis],
        });
    }
    p.initial_stress = InitialStress::Geostatic;
    let region = Aabb::new(Vec3::zeros(), hi).unwrap();
    let x = cubic_lattice(&region, S, 10_000).unwrap();
    let state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    (p, state, hi)
}

/// The slab of [`slab`] with its floor moving at `velocity` from the start: the slab's mean
/// displacement and the floor's after `t_s` seconds.
fn slab_on_moving_floor(wall: WallModel, velocity: Vec3<f64>, t_s: f64) -> (Vec3<f64>, Vec3<f64>) {
    let (mut solver, mut state, hi) = slab(wall, velocity);
    let floor_start = solver.scheme().boundary_particles()[0].position;
    let start = state.positions.clone();
    let frames = (t_s / 0.02).round() as usize;
    let mut travelled = vec![Vec3::zeros(); state.len()];
    let mut before = start;
    for _ in 0..frames {
        solver.step(&mut state).unwrap();
        if let Some(perm) = solver.last_permutation() {
            // The step reordered the particles first: follow them.
            before = perm.iter().map(|&o| before[o as usize]).collect();
            travelled = perm.iter().map(|&o| travelled[o as usize]).collect();
        }
        for (k, (x, b)) in state.positions.iter().zip(&before).enumerate() {
            let mut d = x - b;
            for a in [0, 2] {
                // Unwrapped: a periodic wrap moves a particle by one period.
                if d[a] > 0.5 * hi[a] {
                    d[a] -= hi[a];
                } else if d[a] < -0.5 * hi[a] {
                    d[a] += hi[a];
                }
            }
            travelled[k] += d;
        }
        before = state.positions.clone();
    }
    let mean = travelled.iter().sum::<Vec3<f64>>() / state.len() as f64;
    let mut floor_moved = solver.scheme().boundary_particles()[0].position - floor_start;
    for a in [0, 2] {
        floor_moved[a] = floor_moved[a].rem_euclid(hi[a]);
        if floor_moved[a] > 0.5 * hi[a] {
            floor_moved[a] -= hi[a];
        }
    }
    (mean, floor_moved)
}

/// A floor lowered at 5 cm/s (a tenth of `√(g s)`): the slab descends with it, by the
/// floor's travel within 10 % (the slab starts at rest and catches up within its elastic
/// wave's crossing time, `5 s / √(E/ρ0)` ≈ 0.6 ms, plus the damping of its bounce), and
/// does not move sideways.
#[test]
fn a_lowered_floor_carries_the_slab_down() {
    let w = 0.05;
    let t = 0.3;
    let (slab, floor) = slab_on_moving_floor(WallModel::NoSlip, Vec3::new(0.0, -w, 0.0), t);
    eprintln!("slab {slab:?}, floor {floor:?}");
    // The floor's particles move exactly with the wall: w t (rounding only).
    assert!((floor.y + w * t).abs() < 1e-9, "floor moved {floor:?}");
    assert!(
        (slab.y + w * t).abs() < 0.1 * w * t,
        "slab moved {:?} against the floor's {}",
        slab,
        -w * t
    );
    assert!(slab.x.abs() < 0.1 * S && slab.z.abs() < 0.1 * S);
}

/// A no-slip floor sliding along `x` at 0.1 m/s drags the (elastic, cohesive) slab with
/// it: its mean travel is the floor's within 10 % (it lags by the shear wave's crossing
/// time and its damped oscillation); a free-slip floor sliding the same way leaves it in
/// place (under a tenth of a spacing): the mirrored relative velocity shears nothing.
#[test]
fn a_sliding_floor_drags_the_slab_only_if_no_slip() {
    let u = 0.1;
    let t = 0.3;
    let (dragged, floor) = slab_on_moving_floor(WallModel::NoSlip, Vec3::new(u, 0.0, 0.0), t);
    let (left, _) = slab_on_moving_floor(WallModel::FreeSlip, Vec3::new(u, 0.0, 0.0), t);
    eprintln!("no-slip: slab {dragged:?}, floor {floor:?}; free-slip: slab {left:?}");
    assert!((floor.x - u * t).abs() < 1e-9, "floor moved {floor:?}");
    assert!(
        (dragged.x - u * t).abs() < 0.1 * u * t,
        "no-slip floor: slab moved {dragged:?}"
    );
    assert!(
        left.x.abs() < 0.1 * S,
        "free-slip floor: slab moved {left:?}"
    );
}

/// The wall velocity is checked: a range past the boundary particles and a non-finite
/// velocity are refused, by name.
#[test]
fn a_wall_velocity_out_of_range_or_not_finite_is_refused() {
    let p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    let mut solver = Elastoplastic::new(p, Vec::new()).unwrap();
    let rows = Aabb::new(Vec3::new(0.0, -3.0 * S, 0.0), Vec3::new(0.1, 0.0, 0.1)).unwrap();
    let floor = boundary_block(&rows, S, Vec3::y(), WallModel::NoSlip, 10_000).unwrap();
    let n = floor.len();
    solver.scheme_mut().set_boundary_particles(floor).unwrap();
    let named = |e: SolverError| {
        matches!(
            e,
            SolverError::InvalidParameter {
                name: "boundary_velocity",
                ..
            }
        )
    };
    let past = solver
        .scheme_mut()
        .set_boundary_velocity(0..n + 1, Vec3::zeros())
        .unwrap_err();
    assert!(named(past));
    let nan = solver
        .scheme_mut()
        .set_boundary_velocity(0..n, Vec3::new(f64::NAN, 0.0, 0.0))
        .unwrap_err();
    assert!(named(nan));
    solver
        .scheme_mut()
        .set_boundary_velocity(0..n, Vec3::new(0.0, -1.0, 0.0))
        .unwrap();
}

/// A run with a moving floor resumes bit for bit from a saved state: the floor's positions
/// and velocity travel in the state (`boundary_motion`), and a state from before the floor
/// moved carries none.
#[test]
fn a_moving_floor_resumes_bit_for_bit() {
    let down = Vec3::new(0.0, -0.05, 0.0);
    let (mut first, mut state, _) = slab(WallModel::NoSlip, down);
    for _ in 0..3 {
        first.step(&mut state).unwrap();
    }
    let saved = first.save_state();
    assert!(saved
        .arrays
        .iter()
        .any(|(name, _)| name == "boundary_motion"));
    // A fresh solver, its floor where the set-up puts it and at rest until restored.
    let (second, _, _) = slab(WallModel::NoSlip, Vec3::zeros());
    assert!(!second
        .save_state()
        .arrays
        .iter()
        .any(|(name, _)| name == "boundary_motion"));
    assert_resumes_bit_for_bit(first, state, second, 4);
}

/// Saves `first`'s state, steps it `frames` more frames from `state`, restores the saved
/// state into the fresh solver `second`, steps it as many from the same particles, and
/// asserts the two runs' particles and boundary particles equal bit for bit.
fn assert_resumes_bit_for_bit(
    mut first: Elastoplastic<f64>,
    mut state: ParticleSet<f64>,
    mut second: Elastoplastic<f64>,
    frames: usize,
) {
    let saved = first.save_state();
    let mut resumed_state = state.clone();
    for _ in 0..frames {
        first.step(&mut state).unwrap();
    }
    second.restore_state(&saved, resumed_state.len()).unwrap();
    for _ in 0..frames {
        second.step(&mut resumed_state).unwrap();
    }
    assert_eq!(state.positions, resumed_state.positions);
    assert_eq!(state.velocities, resumed_state.velocities);
    assert_eq!(
        first.scheme().boundary_particles(),
        second.scheme().boundary_particles()
    );
}

/// The slab of [`slab`] on a floor that is a moving wall of the parameters
/// ([`MovingWall`]: three rows under `y = 0` across the periods, lowered at 5 cm/s for
/// `duration_s`), sampled by the solver on the slab's lattice.
fn slab_on_scheduled_floor(duration_s: f64) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    let (mut p, state, hi) = slab_params();
    p.boundary_particle_region = Some(Aabb::new(Vec3::zeros(), hi).unwrap());
    p.moving_walls = vec![MovingWall {
        region: Aabb::new(Vec3::new(-1.0, -3.0 * S, -1.0), Vec3::new(1.0, 0.0, 1.0)).unwrap(),
        model: WallModel::NoSlip,
        velocity: Vec3::new(0.0, -0.05, 0.0),
        duration_s,
    }];
    (Elastoplastic::new(p, Vec::new()).unwrap(), state)
}

/// A moving wall of the parameters moves from the start and stops by itself at the
/// explicit step nearest its duration: after 0.2 s of motion and 0.2 s at rest, each of
/// its particles has travelled `0.05 × 0.2 = 10 mm` to within half an explicit step's
/// travel (the stop's rounding), stands still, and the slab it carried followed it down
/// (within 10 %, as for the lowered floor above).
#[test]
fn a_moving_wall_of_the_parameters_stops_after_its_duration() {
    let (mut solver, mut state) = slab_on_scheduled_floor(0.2);
    let start = solver.scheme().boundary_particles().to_vec();
    assert_eq!(start.len(), 8 * 3 * 4, "three rows across the periods");
    assert!(start
        .iter()
        .all(|b| b.velocity == Vec3::new(0.0, -0.05, 0.0)));
    let y0 = state.positions.iter().map(|x| x.y).sum::<f64>() / state.len() as f64;
    for _ in 0..20 {
        solver.step(&mut state).unwrap();
    }
    let (_, dt) = slab_params().0.explicit_steps();
    for (b, a) in solver.scheme().boundary_particles().iter().zip(&start) {
        let moved = b.position.y - a.position.y;
        assert!(
            (moved + 0.01).abs() <= 0.5 * 0.05 * dt + 1e-12,
            "moved {moved}"
        );
        assert_eq!(b.velocity, Vec3::zeros());
    }
    let y1 = state.positions.iter().map(|x| x.y).sum::<f64>() / state.len() as f64;
    assert!((y1 - y0 + 0.01).abs() < 0.001, "slab moved {}", y1 - y0);
}

/// A run resumed from a state saved while the wall moved stops it at the same step and
/// repeats the uninterrupted run bit for bit (the clock is the frame count the state
/// carries).
#[test]
fn a_scheduled_wall_resumes_bit_for_bit_across_its_stop() {
    let (mut first, mut state) = slab_on_scheduled_floor(0.2);
    for _ in 0..8 {
        first.step(&mut state).unwrap();
    }
    let (second, _) = slab_on_scheduled_floor(0.2);
    assert_resumes_bit_for_bit(first, state, second, 6);
}

/// A moving wall's box across a periodic axis's ends gives particles on both sides of the
/// seam: a box `|x| < 2 s` on the period `8 s` holds the lattice columns `x = s/2, 3s/2`
/// and `8s − s/2, 8s − 3s/2`, each three rows and four layers deep.
#[test]
fn a_moving_wall_across_the_seam_wraps() {
    let (mut p, _, hi) = slab_params();
    p.boundary_particle_region = Some(Aabb::new(Vec3::zeros(), hi).unwrap());
    let wall = MovingWall {
        region: Aabb::new(
            Vec3::new(-2.0 * S, -3.0 * S, -1.0),
            Vec3::new(2.0 * S, 0.0, 1.0),
        )
        .unwrap(),
        model: WallModel::NoSlip,
        velocity: Vec3::zeros(),
        duration_s: 1.0,
    };
    let b = sample_moving_wall(&wall, &p, 10_000).unwrap();
    assert_eq!(b.len(), 4 * 3 * 4);
    let mut columns: Vec<i64> = b
        .iter()
        .map(|b| (b.position.x / S * 2.0).round() as i64)
        .collect();
    columns.sort_unstable();
    columns.dedup();
    assert_eq!(columns, vec![1, 3, 13, 15], "x in half spacings");
    assert!(b.iter().all(|b| (b.normal.norm() - 1.0).abs() < 1e-12));
}

/// A moving wall is checked with the parameters: one without a lattice to sample it on
/// (`boundary_particle_region`), with the model contact-only, a non-finite velocity or a
/// negative duration is refused, by name.
#[test]
fn a_moving_wall_without_a_lattice_or_with_bad_values_is_refused() {
    let (mut p, _, hi) = slab_params();
    let good = MovingWall {
        region: Aabb::new(Vec3::new(0.0, -3.0 * S, 0.0), hi).unwrap(),
        model: WallModel::NoSlip,
        velocity: Vec3::new(0.0, -0.05, 0.0),
        duration_s: 1.0,
    };
    p.moving_walls = vec![good];
    let refused = |p: &ElastoplasticParams<f64>| {
        matches!(
            p.validate(),
            Err(SolverError::InvalidParameter {
                name: "moving_walls",
                ..
            })
        )
    };
    assert!(refused(&p), "no boundary_particle_region");
    p.boundary_particle_region = Some(Aabb::new(Vec3::zeros(), hi).unwrap());
    p.validate().unwrap();
    for bad in [
        MovingWall {
            model: WallModel::ContactOnly,
            ..good
        },
        MovingWall {
            velocity: Vec3::new(f64::NAN, 0.0, 0.0),
            ..good
        },
        MovingWall {
            duration_s: -1.0,
            ..good
        },
    ] {
        p.moving_walls = vec![bad];
        assert!(refused(&p), "{bad:?}");
    }
}
