//! Volume-map construction (Bender et al. 2019, `sph_solver::boundary::volume_map`): the cold
//! build of the walls of a 0.8 × 0.6 × 0.3 m tank (a fifth of SPlisHSPlasH's `DamBreakModel`
//! tank per axis: its 12 edges and 8 corners run the spherical quadrature) for the cubic
//! spline at `h = 0.05` m, default options (`h/4` cells), `f32`; and loading the same map from
//! a [`VolumeMapCache`] file: `cargo bench -p benches --bench volume_map`. The full tank
//! against SPlisHSPlasH's initialisation is `examples/volume_map_build.rs`.
use criterion::{criterion_group, criterion_main, Criterion};
use sph_core::{Aabb, BoxSdf, Inverted, Vec3};
use sph_kernels::KernelKind;
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapCache, VolumeMapOptions};
use sph_solver::Solids;

fn build(cache: Option<&VolumeMapCache>) -> VolumeMapBoundary<f32> {
    let tank = Aabb::new(Vec3::new(-0.4, 0.0, -0.15), Vec3::new(0.4, 0.6, 0.15)).expect("tank");
    let solids: Solids<f32> = vec![Box::new(Inverted(BoxSdf::new(tank).expect("tank")))];
    VolumeMapBoundary::with_cache(
        solids,
        KernelKind::CubicSpline,
        0.05,
        tank,
        0.00625,
        VolumeMapOptions::default(),
        cache,
    )
    .expect("volume map")
}

fn volume_map(c: &mut Criterion) {
    let mut g = c.benchmark_group("volume-map");
    g.sample_size(10);
    g.bench_function("cold-build-tank-0.8m", |b| b.iter(|| build(None)));
    let dir = std::env::temp_dir().join(format!("volume-map-bench-{}", std::process::id()));
    let cache = VolumeMapCache::new(&dir).expect("cache directory");
    build(Some(&cache));
    g.bench_function("cache-load-tank-0.8m", |b| b.iter(|| build(Some(&cache))));
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, volume_map);
criterion_main!(benches);
