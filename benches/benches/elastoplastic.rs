//! One frame of the elastic–plastic granular solver (Bui et al. 2008,
//! `elastoplastic-granular`: 2 ms, its explicit steps sub-cycled inside) on the 59,319 grains
//! of SPlisHSPlasH's dam break held at rest in a box of boundary particles
//! (`benches::settled_block_elastoplastic`), beside one IISPH water step (2 ms, volume maps)
//! on the same particles: `cargo bench -p benches --bench elastoplastic`. The throughput is
//! particles × explicit steps per second (granular) and particles × steps per second
//! (water), so the two per-particle figures read side by side; the ratio, in one run, is
//! `examples/elastoplastic_step.rs`.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use iisph_granular::{Iisph, IisphParams, ParticleSet};
use sph_core::{BoxSdf, Inverted};
use sph_kernels::KernelKind;
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::Solids;

fn dam_break(c: &mut Criterion) {
    let mut group = c.benchmark_group("elastoplastic-dambreak-59k");
    group.sample_size(10);
    let (p, tank) = benches::dam_break_fluid::<f32>();
    let n = p.len();
    let mut state = ParticleSet::from_positions(p, 1000.0 * 0.8 * 0.025f32.powi(3), 1000.0);
    let mut q = IisphParams::<f32>::for_spacing(0.025);
    q.common.dt = 0.002;
    q.common.substeps = 1;
    let solids: Solids<f32> = vec![Box::new(Inverted(BoxSdf::new(tank).expect("tank")))];
    let b = VolumeMapBoundary::new(
        solids,
        KernelKind::CubicSpline,
        q.common.support_radius,
        tank,
        q.common.particle_radius() * 0.5,
        VolumeMapOptions::default(),
    )
    .expect("volume map");
    let mut water = Iisph::with_boundary(q, Box::new(b)).expect("params");
    for _ in 0..5 {
        water.step(&mut state).expect("step");
    }
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function("water-step", |b| {
        b.iter(|| water.step(&mut state).expect("step"))
    });
    let (mut solver, mut grains) = benches::settled_block_elastoplastic::<f32>(
        0.002,
        elastoplastic_granular::DEFAULT_YOUNGS_MODULUS_PA,
    )
    .expect("granular scene");
    let (steps, _) = solver.params().explicit_steps();
    solver.step(&mut grains).expect("warm-up frame");
    group.throughput(Throughput::Elements((n * steps) as u64));
    group.bench_function(format!("elastoplastic-frame-{steps}-explicit-steps"), |b| {
        b.iter(|| solver.step(&mut grains).expect("frame"))
    });
    group.finish();
}

criterion_group!(benches, dam_break);
criterion_main!(benches);
