//! Resumable runs: `k` frames, `save_state`, a fresh solver, `restore_state`, `k` more frames
//! give bit for bit the particles of `2 k` frames straight (with reordering by cell inside
//! both halves), with collision and with volume-map walls.

use pbf::{FluidSolver, KernelKind, Pbf, PbfParams, SolverError, SolverState};
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::testing::{assert_resume_is_bit_identical, block_in_tank};

const BLOCK: [usize; 3] = [6, 6, 4];
const TANK: [f64; 3] = [12.0, 10.0, 4.0];

fn params() -> PbfParams<f64> {
    let mut p = PbfParams::default();
    p.common.reorder_every = 4; // reorders at frames 0, 4 (first half) and 8 (second half)
    p
}

#[test]
fn pbf_resumes_bit_for_bit() {
    let p = params();
    let (state, _, _) = block_in_tank(&p.common, BLOCK, TANK);
    let make = || -> Box<dyn FluidSolver<f64>> {
        let (_, solids, _) = block_in_tank(&p.common, BLOCK, TANK);
        Box::new(Pbf::new(p.clone(), solids).unwrap())
    };
    let saved = assert_resume_is_bit_identical(&make, &state, 5);
    assert_eq!(saved.solver, "PBF");
    assert!(saved.arrays.is_empty(), "PBF carries nothing but the frame count");
}

#[test]
fn pbf_with_volume_maps_resumes_bit_for_bit() {
    let p = params();
    let (state, _, _) = block_in_tank(&p.common, BLOCK, TANK);
    let make = || -> Box<dyn FluidSolver<f64>> {
        let (_, solids, tank) = block_in_tank(&p.common, BLOCK, TANK);
        let b = VolumeMapBoundary::new(
            solids,
            KernelKind::Poly6,
            p.common.support_radius,
            tank,
            p.common.particle_radius() * 0.5,
            VolumeMapOptions::default(),
        )
        .unwrap();
        Box::new(Pbf::with_boundary(p.clone(), Box::new(b)).unwrap())
    };
    assert_resume_is_bit_identical(&make, &state, 5);
}

/// A state of another solver, or carrying an array PBF does not have, is refused by name
/// and leaves the solver as it was.
#[test]
fn pbf_refuses_foreign_states() {
    let p = params();
    let (_, solids, _) = block_in_tank(&p.common, BLOCK, TANK);
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
