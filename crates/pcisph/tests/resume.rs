//! Resumable runs: `k` frames, `save_state`, a fresh solver, `restore_state`, `k` more frames
//! give bit for bit the particles of `2 k` frames straight (with reordering by cell inside
//! both halves), with collision and with volume-map walls.

use pcisph::{KernelKind, PcisphParams, PcisphScheme};
use sph_solver::testing::assert_block_resumes;

fn params() -> PcisphParams<f64> {
    let mut p = PcisphParams::default();
    p.common.reorder_every = 4; // reorders at frames 0, 4 (first half) and 8 (second half)
    p
}

#[test]
fn pcisph_resumes_bit_for_bit() {
    let saved = assert_block_resumes::<f64, PcisphScheme<f64>>(&params(), None);
    assert_eq!(saved.solver, "PCISPH");
    assert!(
        saved.arrays.is_empty(),
        "PCISPH starts each time step from p = 0"
    );
}

#[test]
fn pcisph_with_volume_maps_resumes_bit_for_bit() {
    assert_block_resumes::<f64, PcisphScheme<f64>>(&params(), Some(KernelKind::Poly6));
}

/// Iteration counts beyond what can finish are refused, and the error states the bound.
#[test]
fn counts_are_bounded() {
    let mut p = params();
    p.pressure_iterations = pcisph::MAX_PRESSURE_ITERATIONS + 1;
    let e = p.validate().unwrap_err().to_string();
    assert!(
        e.contains(&pcisph::MAX_PRESSURE_ITERATIONS.to_string()),
        "{e}"
    );
    p.pressure_iterations = pcisph::MAX_PRESSURE_ITERATIONS;
    p.common.substeps = 1000;
    let e = p.validate().unwrap_err().to_string();
    assert!(
        e.contains(&sph_solver::MAX_ITERATIONS_PER_FRAME.to_string()),
        "{e}"
    );
}
