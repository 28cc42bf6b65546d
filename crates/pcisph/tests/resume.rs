//! Resumable runs: `k` frames, `save_state`, a fresh solver, `restore_state`, `k` more frames
//! give bit for bit the particles of `2 k` frames straight (with reordering by cell inside
//! both halves), with collision and with volume-map walls.

use pcisph::{FluidSolver, KernelKind, Pcisph, PcisphParams};
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::testing::{assert_resume_is_bit_identical, block_in_tank};

const BLOCK: [usize; 3] = [6, 6, 4];
const TANK: [f64; 3] = [12.0, 10.0, 4.0];

fn params() -> PcisphParams<f64> {
    let mut p = PcisphParams::default();
    p.common.reorder_every = 4; // reorders at frames 0, 4 (first half) and 8 (second half)
    p
}

#[test]
fn pcisph_resumes_bit_for_bit() {
    let p = params();
    let (state, _, _) = block_in_tank(&p.common, BLOCK, TANK);
    let make = || -> Box<dyn FluidSolver<f64>> {
        let (_, solids, _) = block_in_tank(&p.common, BLOCK, TANK);
        Box::new(Pcisph::new(p.clone(), solids).unwrap())
    };
    let saved = assert_resume_is_bit_identical(&make, &state, 5);
    assert_eq!(saved.solver, "PCISPH");
    assert!(saved.arrays.is_empty(), "PCISPH starts each time step from p = 0");
}

#[test]
fn pcisph_with_volume_maps_resumes_bit_for_bit() {
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
        Box::new(Pcisph::with_boundary(p.clone(), Box::new(b)).unwrap())
    };
    assert_resume_is_bit_identical(&make, &state, 5);
}
