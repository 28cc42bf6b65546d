//! Resumable runs: `k` frames, `save_state`, a fresh solver, `restore_state`, `k` more frames
//! give bit for bit the particles of `2 k` frames straight (with reordering by cell inside
//! both halves), with collision and with volume-map walls.

use pbf::{KernelKind, Pbf, PbfParams, PbfScheme, SolverError, SolverState};
use sph_solver::testing::{assert_block_resumes, block_in_tank};

fn params() -> PbfParams<f64> {
    let mut p = PbfParams::default();
    p.common.reorder_every = 4; // reorders at frames 0, 4 (first half) and 8 (second half)
    p
}

#[test]
fn pbf_resumes_bit_for_bit() {
    let saved = assert_block_resumes::<f64, PbfScheme<f64>>(&params(), None);
    assert_eq!(saved.solver, "PBF");
    assert!(
        saved.arrays.is_empty(),
        "PBF carries nothing but the frame count"
    );
}

#[test]
fn pbf_with_volume_maps_resumes_bit_for_bit() {
    assert_block_resumes::<f64, PbfScheme<f64>>(&params(), Some(KernelKind::Poly6));
}

/// A state of another solver, or carrying an array PBF does not have, is refused by name
/// and leaves the solver as it was.
#[test]
fn pbf_refuses_foreign_states() {
    let p = params();
    let (_, solids, _) = block_in_tank(&p.common, [2, 2, 2], [4.0, 4.0, 4.0]);
    let mut solver = Pbf::new(p, solids).unwrap();
    let foreign = SolverState::<f64>::new("PCISPH", 3, vec![]);
    let e = solver.restore_state(&foreign, 10).unwrap_err();
    assert!(
        matches!(&e, SolverError::InvalidSolverState { reason, .. } if reason.contains("PCISPH")),
        "{e}"
    );
    let extra = SolverState::new("PBF", 3, vec![("pressure".to_string(), vec![0.0; 10])]);
    let e = solver.restore_state(&extra, 10).unwrap_err();
    assert!(e.to_string().contains("`pressure` is not carried"), "{e}");
    assert_eq!(solver.steps_done(), 0);
    solver
        .restore_state(&SolverState::new("PBF", 7, vec![]), 10)
        .unwrap();
    assert_eq!(solver.steps_done(), 7);
}

/// Iteration and substep counts beyond what can finish are refused, and the error states
/// the bound.
#[test]
fn counts_are_bounded() {
    let mut p = params();
    p.solver_iterations = pbf::MAX_SOLVER_ITERATIONS + 1;
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains(&pbf::MAX_SOLVER_ITERATIONS.to_string()), "{e}");
    p.solver_iterations = 1_000_000_000;
    assert!(p.validate().is_err());
    let mut p = params();
    p.common.substeps = 100_000;
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains(&sph_solver::MAX_SUBSTEPS.to_string()), "{e}");
}
