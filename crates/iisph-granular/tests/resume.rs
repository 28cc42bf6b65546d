//! Resumable runs: `k` frames, `save_state`, a fresh solver, `restore_state`, `k` more frames
//! give bit for bit the particles (and passive points) of `2 k` frames straight, with
//! reordering by cell inside both halves: IISPH water (warm-started pressures), granular
//! with upscaling (pressures, frictional stress, passive points and their velocities), with
//! collision and with volume-map walls.

mod common;

use iisph_granular::{FluidSolver, IisphParams, IisphScheme, KernelKind, SolverError, SolverState};
use sph_solver::testing::{assert_block_resumes, assert_resume_is_bit_identical};

const BLOCK: [usize; 3] = [6, 6, 4];
const TANK: [f64; 3] = [12.0, 10.0, 4.0];

fn water() -> IisphParams<f64> {
    let mut p = IisphParams::for_spacing(0.025);
    p.common.substeps = 4;
    p.common.reorder_every = 4; // reorders at frames 0, 4 (first half) and 8 (second half)
    p
}

fn granular() -> IisphParams<f64> {
    let mut p = IisphParams::granular(0.025, 30.0);
    p.common.substeps = 4;
    p.common.reorder_every = 4;
    p.upscaling_factor = Some(2);
    p
}

#[test]
fn iisph_water_resumes_bit_for_bit() {
    let saved = assert_block_resumes::<f64, IisphScheme<f64>>(&water(), None);
    assert_eq!(saved.solver, "IISPH");
    let names: Vec<_> = saved.arrays.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["pressure"]);
    assert!(
        saved.arrays[0].1.iter().any(|&p| p > 0.0),
        "warm start carried"
    );
}

#[test]
fn iisph_water_with_volume_maps_resumes_bit_for_bit() {
    assert_block_resumes::<f64, IisphScheme<f64>>(&water(), Some(KernelKind::CubicSpline));
}

#[test]
fn granular_with_upscaling_and_volume_maps_resumes_bit_for_bit() {
    let p = granular();
    let (_, state) = common::relaxed_block_solver(p.clone(), BLOCK, TANK);
    let make = || -> Box<dyn FluidSolver<f64>> {
        Box::new(common::block_solver(p.clone(), BLOCK, TANK).0)
    };
    let saved = assert_resume_is_bit_identical(&make, &state, 5);
    assert_eq!(saved.solver, "IISPH-granular");
    let names: Vec<_> = saved.arrays.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "pressure",
            "stress",
            "friction_acceleration",
            "passive_positions",
            "passive_velocities"
        ]
    );
    let n = state.len();
    assert_eq!(saved.array("stress").unwrap().len(), 6 * n);
    assert_eq!(saved.array("friction_acceleration").unwrap().len(), 3 * n);
    assert_eq!(saved.array("passive_positions").unwrap().len(), 3 * 2 * n);
}

/// States that do not fit are refused by name, and the solver is left as it was.
#[test]
fn iisph_refuses_states_that_do_not_fit() {
    let p = granular();
    let (mut solver, mut state) = common::block_solver(p.clone(), BLOCK, TANK);
    let n = state.len();
    solver.step(&mut state).unwrap();
    let saved = solver.save_state();
    let mut fresh = common::block_solver(p, BLOCK, TANK).0;
    let reason = |e: SolverError| match e {
        SolverError::InvalidSolverState { reason, .. } => reason,
        other => panic!("{other:?}"),
    };
    // Another solver.
    let water = SolverState::new("IISPH", 1, saved.arrays.clone());
    assert!(reason(fresh.restore_state(&water, n).unwrap_err()).contains("`IISPH`"));
    // Another particle count.
    let r = reason(fresh.restore_state(&saved, n + 1).unwrap_err());
    assert!(r.contains("`pressure` has"), "{r}");
    // Only one of the passive arrays.
    let mut half = saved.clone();
    half.arrays.retain(|(name, _)| name != "passive_velocities");
    let r = reason(fresh.restore_state(&half, n).unwrap_err());
    assert!(r.contains("passive_velocities"), "{r}");
    // A non-finite pressure.
    let mut nan = saved.clone();
    nan.arrays[0].1[3] = f64::NAN;
    let r = reason(fresh.restore_state(&nan, n).unwrap_err());
    assert!(r.contains("value 3 is not finite"), "{r}");
    assert_eq!(fresh.steps_done(), 0);
    assert!(fresh.passive_points().is_none());
    assert!(fresh.pressure().is_empty());
    fresh.restore_state(&saved, n).unwrap();
    assert_eq!(fresh.steps_done(), 1);
    assert_eq!(fresh.passive_points(), solver.passive_points());
}

/// A state without `friction_acceleration` (saved before the solver carried it) resumes:
/// the next step computes the friction of the restored stress afresh, and the state saved
/// after it carries the array again.
#[test]
fn granular_resumes_without_the_friction_acceleration() {
    let p = granular();
    let (mut solver, mut state) = common::block_solver(p.clone(), BLOCK, TANK);
    let n = state.len();
    solver.step(&mut state).unwrap();
    let mut saved = solver.save_state();
    saved
        .arrays
        .retain(|(name, _)| name != "friction_acceleration");
    let mut fresh = common::block_solver(p, BLOCK, TANK).0;
    fresh.restore_state(&saved, n).unwrap();
    assert!(fresh.save_state().array("friction_acceleration").is_none());
    let mut resumed = state.clone();
    fresh.step(&mut resumed).unwrap();
    solver.step(&mut state).unwrap();
    let a = fresh.save_state();
    let a = a.array("friction_acceleration").unwrap();
    assert_eq!(a.len(), 3 * n);
    assert!(a.iter().all(|v| v.is_finite()));
    // Only the friction the pressure solve saw differs (the last step's a^f against the
    // restored stress's at this step's positions): the runs stay close.
    let dx = resumed
        .positions
        .iter()
        .zip(&state.positions)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0f64, f64::max);
    assert!(dx < 1e-3 * 0.025, "max position difference {dx} m");
}

/// Iteration counts beyond what can finish are refused, and the error states the bound
/// (`min_iterations = 1e9` ran for ever before).
#[test]
fn counts_are_bounded() {
    use iisph_granular::{MAX_FRICTION_ITERATIONS, MAX_PRESSURE_ITERATIONS};
    let mut p = granular();
    p.min_iterations = 1_000_000_000;
    p.max_iterations = 1_000_000_000;
    let e = p.validate().unwrap_err().to_string();
    assert!(
        e.contains("min_iterations") && e.contains(&MAX_PRESSURE_ITERATIONS.to_string()),
        "{e}"
    );
    let mut p = granular();
    p.max_iterations = MAX_PRESSURE_ITERATIONS + 1;
    let e = p.validate().unwrap_err().to_string();
    assert!(
        e.contains("max_iterations") && e.contains(&MAX_PRESSURE_ITERATIONS.to_string()),
        "{e}"
    );
    let mut p = granular();
    p.granular.as_mut().unwrap().friction_max_iterations = MAX_FRICTION_ITERATIONS + 1;
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains(&MAX_FRICTION_ITERATIONS.to_string()), "{e}");
}
