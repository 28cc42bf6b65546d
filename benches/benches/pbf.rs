//! One PBF step and one PCISPH step on SPlisHSPlasH's `DamBreakModel` scene at particle
//! radius 0.0125 m (59,319 fluid particles, support 0.05 m, Δt = 0.002 s, one step per call),
//! from the rest state: `cargo bench -p benches --bench pbf`.
//!
//! Iterations: 5 per step, close to SPlisHSPlasH 2.19's mean for this scene with its PBF
//! solver iterating to 0.1 % mean density error (5.33 over the first 250 steps; 2.55 over
//! the first 51). The side-by-side figures (`examples/pbf_dambreak.rs` against
//! SPlisHSPlasH) are in the `pbf` crate documentation, section "Performance and
//! determinism".
use criterion::{criterion_group, criterion_main, Criterion};
use pbf::{FluidSolver, ParticleSet, Pbf, PbfParams, Solids};
use pcisph::{Pcisph, PcisphParams};
use sph_core::{BoxSdf, Inverted};

/// Pressure/constraint iterations per step (SPlisHSPlasH's average, see the module docs).
const ITERATIONS: usize = 5;

fn setup() -> (ParticleSet<f32>, Solids<f32>) {
    let (p, tank) = benches::dam_break_fluid::<f32>();
    let state = ParticleSet::from_positions(p, 1000.0 * 0.025f32.powi(3), 1000.0);
    let solids: Solids<f32> = vec![Box::new(Inverted(BoxSdf::new(tank).expect("tank")))];
    (state, solids)
}

fn solver_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("fluid-step-dambreak-59k");
    group.sample_size(10);
    let (state0, _) = setup();
    let mut pbf_params = PbfParams::<f32>::for_spacing(0.025);
    pbf_params.common.dt = 0.002;
    pbf_params.common.substeps = 1;
    pbf_params.solver_iterations = ITERATIONS;
    let mut pci_params = PcisphParams::<f32>::for_spacing(0.025);
    pci_params.common.dt = 0.002;
    pci_params.common.substeps = 1;
    pci_params.pressure_iterations = ITERATIONS;
    let solvers: Vec<Box<dyn FluidSolver<f32>>> = vec![
        Box::new(Pbf::new(pbf_params, setup().1).expect("params")),
        Box::new(Pcisph::new(pci_params, setup().1).expect("params")),
    ];
    for mut solver in solvers {
        let mut state = state0.clone();
        // Warm up: grow the buffers and sort the particles by cell once.
        solver.step(&mut state).expect("step");
        group.bench_function(solver.name(), |b| {
            b.iter(|| solver.step(&mut state).expect("step"))
        });
    }
    group.finish();
}

criterion_group!(benches, solver_step);
criterion_main!(benches);
