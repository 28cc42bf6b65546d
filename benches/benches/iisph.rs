//! One IISPH water step and one granular step (friction θ = 30°, drag C_D = 1) on
//! SPlisHSPlasH's `DamBreakModel` scene at particle radius 0.0125 m (59,319 particles,
//! Δt = 0.002 s, volume maps), and one granular step of a 100k-particle pile (a
//! 46 × 46 × 48 block on the floor of a tank twice its width): `cargo bench -p benches
//! --bench iisph`. Each from a state after a few warm-up steps (buffers grown, particles
//! sorted, pressures warm-started). The side-by-side with SPlisHSPlasH is
//! `examples/iisph_dambreak.rs`.
use criterion::{criterion_group, criterion_main, Criterion};
use iisph_granular::{Iisph, IisphParams, ParticleSet, Vec3};
use sph_core::{sampling::cubic_lattice, Aabb, BoxSdf, Inverted};
use sph_kernels::KernelKind;
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::Solids;

fn solver(q: IisphParams<f32>, tank: Aabb<f32>) -> Iisph<f32> {
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
    Iisph::with_boundary(q, Box::new(b)).expect("params")
}

fn params(granular: bool) -> IisphParams<f32> {
    let mut q = if granular {
        let mut q = IisphParams::<f32>::granular(0.025, 30.0);
        q.granular.as_mut().expect("granular").drag_coefficient = 1.0;
        q
    } else {
        IisphParams::<f32>::for_spacing(0.025)
    };
    q.common.dt = 0.002;
    q.common.substeps = 1;
    q
}

fn dam_break(c: &mut Criterion) {
    let mut group = c.benchmark_group("iisph-step-dambreak-59k");
    group.sample_size(10);
    let (p, tank) = benches::dam_break_fluid::<f32>();
    let state0 = ParticleSet::from_positions(p, 1000.0 * 0.8 * 0.025f32.powi(3), 1000.0);
    for (name, granular) in [("water", false), ("granular", true)] {
        let mut s = solver(params(granular), tank);
        let mut state = state0.clone();
        for _ in 0..5 {
            s.step(&mut state).expect("step");
        }
        group.bench_function(name, |b| b.iter(|| s.step(&mut state).expect("step")));
    }
    group.finish();
}

fn pile_100k(c: &mut Criterion) {
    let mut group = c.benchmark_group("granular-step-pile-100k");
    group.sample_size(10);
    let s = 0.025f32;
    let block = Aabb::new(Vec3::repeat(0.5 * s), Vec3::new(46.5, 48.5, 46.5) * s).expect("block");
    let p = cubic_lattice(&block, s, usize::MAX).expect("lattice");
    let tank = Aabb::new(Vec3::zeros(), Vec3::new(92.0, 60.0, 47.0) * s).expect("tank");
    let mut state = ParticleSet::from_positions(p, 1000.0 * s * s * s, 1000.0);
    let mut g = solver(params(true), tank);
    for _ in 0..5 {
        g.step(&mut state).expect("step");
    }
    group.bench_function(format!("granular-{}", state.len()), |b| {
        b.iter(|| g.step(&mut state).expect("step"))
    });
    group.finish();
}

criterion_group!(benches, dam_break, pile_100k);
criterion_main!(benches);
