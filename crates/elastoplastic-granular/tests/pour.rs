//! Pours (`Pour`): layers fall due at the pour's rate and land where the heap grows, new
//! grains start unstressed, a run resumes bit for bit in the middle of a pour, a buried
//! funnel and bad pours are refused with their reason.

mod common;
use common::heap::{poured_heap, PouredSetup};
use elastoplastic_granular::{
    boundary_block, cubic_lattice, Aabb, Elastoplastic, ElastoplasticParams, InitialStress,
    ParticleSet, PeriodicAxis, Pour, SolverError, Vec3, WallModel,
};
use nalgebra::Matrix3;

const S: f64 = 0.02;

/// A small poured heap: period 0.4 m, a funnel two spacings wide, `layers` layers of six
/// grains at 30 layers a second, frames of 16 ms.
fn small_pour(layers: f64, funnel_top_m: f64) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    poured(layers, funnel_top_m, None)
}

/// [`small_pour`] with its funnel's top 1 m up and the pour's seed.
fn seeded_pour(layers: f64, seed: Option<u64>) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    poured(layers, 1.0, seed)
}

fn poured(
    layers: f64,
    funnel_top_m: f64,
    seed: Option<u64>,
) -> (Elastoplastic<f64>, ParticleSet<f64>) {
    let mut params = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    params.youngs_modulus = 5.84e5;
    params.common.dt = 0.016;
    let slab = 3.0 * S;
    let layer_m3 = 2.0 * S * S * slab;
    let setup = PouredSetup {
        period_x_m: 0.4,
        slab_depth_m: slab,
        funnel_width_m: 2.0 * S,
        funnel_top_m,
        volume_m3: layers * layer_m3,
        rate_m3_s: 30.0 * layer_m3,
        seed,
    };
    poured_heap(params, setup).unwrap()
}

/// A seeded pour shifts each layer by its own draw, within half a spacing along `x` and `z`
/// of the funnel's nodes: two seeds give different heaps, one seed the same heap twice, and
/// a run resumed in the middle of a seeded pour repeats the uninterrupted one bit for bit
/// (the draw is a function of the seed and the layer's number).
#[test]
fn seeded_pours_are_an_ensemble() {
    let run = |seed: Option<u64>, frames: usize| {
        let (mut solver, mut state) = seeded_pour(12.0, seed);
        for _ in 0..frames {
            solver.step(&mut state).unwrap();
        }
        state
    };
    let a = run(Some(1), 30);
    let b = run(Some(2), 30);
    assert_eq!(a.positions, run(Some(1), 30).positions);
    assert_ne!(a.positions, b.positions);
    // Each layer's shift lies within half a spacing of the nodes, and differs from layer to
    // layer.
    let (solver, _) = seeded_pour(12.0, Some(1));
    let pour = solver.params().pour.unwrap();
    for k in 0..12 {
        let [dx, dz] = pour.layer_shift(k, S);
        assert!(
            dx.abs() <= 0.5 * S && dz.abs() <= 0.5 * S,
            "layer {k}: {dx}, {dz}"
        );
    }
    let distinct: std::collections::BTreeSet<u64> = (0..12)
        .map(|k| pour.layer_shift(k, S)[0].to_bits())
        .collect();
    assert_eq!(distinct.len(), 12, "each layer has its own shift");
    // Resumed from frame 15 of 30.
    let (mut first, mut state) = seeded_pour(12.0, Some(1));
    for _ in 0..15 {
        first.step(&mut state).unwrap();
    }
    let saved = first.save_state();
    let (mut second, _) = seeded_pour(12.0, Some(1));
    second.restore_state(&saved, state.len()).unwrap();
    for _ in 0..15 {
        second.step(&mut state).unwrap();
    }
    assert_eq!(state.positions, a.positions);
}

/// The layers fall due at the rate (30 a second: one by 33 ms), but each waits until the
/// one before it has fallen `FALL_OVER_LANDING_TIME √(s/g)` = 49.7 ms (a layer released at
/// rest is slower than the landed speed `√(g s)` before `√(s/g)`), so with frames of 16 ms
/// they come in every fourth frame: none earlier than due, none within 49.7 ms of the one
/// before it, all twelve in by 0.77 s (six grains each, 72 grains), above the floor.
#[test]
fn a_pour_adds_its_layers_on_schedule_paced_by_the_falls() {
    let (mut solver, mut state) = small_pour(12.0, 1.0);
    assert_eq!(solver.poured_layers(), Some((0, 12)));
    assert_eq!(state.len(), 0);
    let min_interval_s = elastoplastic_granular::FALL_OVER_LANDING_TIME * (S / 9.81).sqrt();
    let mut last_layer_s: Option<f64> = None;
    let mut before = 0;
    for frame in 0..48 {
        let frame_start_s = frame as f64 * 0.016;
        solver.step(&mut state).unwrap();
        let (done, _) = solver.poured_layers().unwrap();
        // Due at the frame's start: floor(30 t).
        let due = (30.0 * frame_start_s + 1e-9).floor() as usize;
        assert!(done <= due.min(12), "{done} layers by {frame_start_s} s");
        assert!(
            done <= before + 1,
            "two layers in the frame at {frame_start_s} s"
        );
        if done > before {
            if let Some(t) = last_layer_s {
                assert!(
                    frame_start_s - t >= min_interval_s,
                    "a layer at {frame_start_s} s, {} s after the last",
                    frame_start_s - t
                );
            }
            last_layer_s = Some(frame_start_s);
        }
        before = done;
        assert_eq!(state.len(), 6 * done);
    }
    assert_eq!(solver.poured_layers(), Some((12, 12)));
    assert_eq!(state.len(), 72);
    assert!(state.positions.iter().all(|p| p.y > 0.0 && p.y < 0.3));
}

/// A grain poured where no grain reaches it starts unstressed, whatever the stress of the
/// grains and walls already in the run: a stressed block stands on a floor whose boundary
/// particles under it come first (the solver keeps the boundary's stresses after the
/// grains', so a new grain not cleared would take one of theirs), and the funnel's floor is
/// 0.3 m up: the first layer is still falling freely at the end of the frame that poured it.
#[test]
fn poured_grains_start_unstressed() {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = 5.84e5;
    p.common.dt = 0.016;
    p.initial_stress = InitialStress::Geostatic;
    let (l, slab) = (0.4, 3.0 * S);
    p.periodic = [(0, l), (2, slab)]
        .into_iter()
        .map(|(axis, hi)| PeriodicAxis { axis, lo: 0.0, hi })
        .collect();
    let layer_m3 = 2.0 * S * S * slab;
    p.pour = Some(Pour {
        region: Aabb::new(Vec3::new(0.18, 0.3, 0.0), Vec3::new(0.22, 1.0, slab)).unwrap(),
        volume_m3: 10.0 * layer_m3,
        rate_m3_s: 30.0 * layer_m3,
        seed: None,
    });
    let block = Aabb::new(Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.3, 0.06, slab)).unwrap();
    let x = cubic_lattice(&block, S, 10_000).unwrap();
    let mut state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    let mut solver = Elastoplastic::new(p, Vec::new()).unwrap();
    let floor = |lo: f64, hi: f64| {
        let rows = Aabb::new(Vec3::new(lo, -3.0 * S, 0.0), Vec3::new(hi, 0.0, slab)).unwrap();
        boundary_block(&rows, S, Vec3::y(), WallModel::NoSlip, 10_000).unwrap()
    };
    let mut rows = floor(0.1, 0.3);
    rows.extend(floor(0.0, 0.1));
    rows.extend(floor(0.3, l));
    solver.scheme_mut().set_boundary_particles(rows).unwrap();
    let before = state.len();
    while solver.poured_layers() == Some((0, 10)) {
        solver.step(&mut state).unwrap();
    }
    assert_eq!(state.len(), before + 6);
    let stressed = solver.scheme().stress()[..before]
        .iter()
        .filter(|m| m[(1, 1)] < -100.0)
        .count();
    assert!(
        2 * stressed > before,
        "{stressed} of {before} grains carry their weight"
    );
    for (x, m) in state.positions[before..]
        .iter()
        .zip(&solver.scheme().stress()[before..])
    {
        assert!(x.y > 0.25, "the new grain at {x:?} is falling freely");
        assert_eq!(*m, Matrix3::zeros(), "the new grain at {x:?}");
    }
}

/// A run saved in the middle of its pour resumes bit for bit: a fresh solver restored from
/// the saved state pours the same layers at the same frames.
#[test]
fn a_pour_resumes_bit_for_bit() {
    let (mut first, mut state) = small_pour(30.0, 1.0);
    for _ in 0..20 {
        first.step(&mut state).unwrap();
    }
    let saved = first.save_state();
    assert!(saved.arrays.iter().any(|(name, _)| name == "pour"));
    let n_saved = state.len();
    let mut resumed_state = state.clone();
    for _ in 0..25 {
        first.step(&mut state).unwrap();
    }
    let (mut second, _) = small_pour(30.0, 1.0);
    second.restore_state(&saved, resumed_state.len()).unwrap();
    for _ in 0..25 {
        second.step(&mut resumed_state).unwrap();
    }
    assert_eq!(first.poured_layers(), second.poured_layers());
    assert_eq!(state.positions, resumed_state.positions);
    assert_eq!(state.velocities, resumed_state.velocities);
    assert_eq!(first.scheme().stress(), second.scheme().stress());
    // The pour's progress is found wherever the state lists it, not only last.
    let mut reordered = saved.clone();
    reordered.arrays.rotate_right(1);
    assert_eq!(reordered.arrays[0].0, "pour");
    let (mut third, _) = small_pour(30.0, 1.0);
    let (mut fourth, _) = small_pour(30.0, 1.0);
    third.restore_state(&saved, n_saved).unwrap();
    fourth.restore_state(&reordered, n_saved).unwrap();
    assert_eq!(third.poured_layers(), fourth.poured_layers());
    assert_eq!(third.save_state(), fourth.save_state());
}

/// A saved pour's progress that does not fit is refused: more layers than the pour has, or
/// a progress given to a solver without a pour.
#[test]
fn a_pour_state_that_does_not_fit_is_refused() {
    let (mut first, mut state) = small_pour(12.0, 1.0);
    for _ in 0..10 {
        first.step(&mut state).unwrap();
    }
    let mut saved = first.save_state();
    for (name, v) in saved.arrays.iter_mut() {
        if name == "pour" {
            v[0] = 13.0;
        }
    }
    let (mut second, _) = small_pour(12.0, 1.0);
    let err = second.restore_state(&saved, state.len()).unwrap_err();
    assert!(err.to_string().contains("layers placed"), "{err}");
    let p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    let mut plain = Elastoplastic::new(p, Vec::new()).unwrap();
    let err = plain
        .restore_state(&first.save_state(), state.len())
        .unwrap_err();
    assert!(err.to_string().contains("no pour"), "{err}");
}

/// A heap that reaches the funnel's top stops the run with the reason.
#[test]
fn a_buried_funnel_is_an_error() {
    let (mut solver, mut state) = small_pour(200.0, 3.0 * S);
    let err = (0..200)
        .find_map(|_| solver.step(&mut state).err())
        .expect("the heap reaches the funnel's top");
    assert!(err.to_string().contains("reached the pour's top"), "{err}");
}

/// Bad pours are refused by `validate`, each with its reason.
#[test]
fn bad_pours_are_refused() {
    let good = Pour {
        region: Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.1, 1.0, 0.06)).unwrap(),
        volume_m3: 0.001,
        rate_m3_s: 0.001,
        seed: None,
    };
    type Spoil = Box<dyn Fn(&mut ElastoplasticParams<f64>)>;
    let cases: [(&str, Spoil); 5] = [
        (
            "at least a spacing",
            Box::new(|p| p.pour.as_mut().unwrap().region.max.x = 0.01),
        ),
        (
            "volume",
            Box::new(|p| p.pour.as_mut().unwrap().volume_m3 = f64::NAN),
        ),
        (
            "rate",
            Box::new(|p| p.pour.as_mut().unwrap().rate_m3_s = 0.0),
        ),
        (
            "MAX_POURED_GRAINS",
            Box::new(|p| p.pour.as_mut().unwrap().volume_m3 = 1e6),
        ),
        (
            "gravity along −y",
            Box::new(|p| p.common.gravity = Vec3::new(-9.81, 0.0, 0.0)),
        ),
    ];
    let mut ok = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    ok.pour = Some(good);
    ok.validate().unwrap();
    for (reason, spoil) in cases {
        let mut p = ok.clone();
        spoil(&mut p);
        match p.validate() {
            Err(SolverError::InvalidParameter {
                name, reason: r, ..
            }) => {
                assert_eq!(name, "pour");
                assert!(r.contains(reason), "{r} (expected {reason})");
            }
            other => panic!("{reason}: {other:?}"),
        }
    }
}
