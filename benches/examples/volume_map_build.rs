//! Cold build (and cache load) of the volume map of SPlisHSPlasH's `DamBreakModel` tank:
//! the walls of the 4 × 3 × 1.5 m tank (`Inverted<BoxSdf>`) for the cubic spline at
//! `h = 0.05` m (particle radius 0.0125 m, support `4 r` as SPlisHSPlasH), default options
//! (`h/4` cells), `f32` solids as the IISPH side-by-side (`iisph_dambreak`):
//!
//! ```text
//! RAYON_NUM_THREADS=1 cargo run --release -p benches --example volume_map_build -- [cache DIR] [f64]
//! ```
//!
//! Prints the build statistics and the wall time; with `cache DIR` a second construction
//! loads the map from `DIR` and the program checks that it samples bit-identically.
use std::time::Instant;

use sph_core::{BoxSdf, Inverted, Real, Vec3};
use sph_kernels::KernelKind;
use sph_solver::boundary::{Boundary, VolumeMapBoundary, VolumeMapCache, VolumeMapOptions};
use sph_solver::Solids;

fn build<R: Real>(cache: Option<&VolumeMapCache>) -> VolumeMapBoundary<R> {
    let (_, tank) = benches::dam_break_fluid::<R>();
    let solids: Solids<R> = vec![Box::new(Inverted(BoxSdf::new(tank).expect("tank")))];
    let t = Instant::now();
    let b = VolumeMapBoundary::with_cache(
        solids,
        KernelKind::CubicSpline,
        R::of_f64(0.05),
        tank,
        R::of_f64(0.00625),
        VolumeMapOptions::default(),
        cache,
    )
    .expect("volume map");
    let s = b.maps()[0].stats();
    println!(
        "{:?}: {:.3} s wall ({} rayon threads, {}): {} nodes {:?}, {} band, {} by quadrature, {} stored",
        s.cache,
        t.elapsed().as_secs_f64(),
        rayon::current_num_threads(),
        R::NAME,
        s.nodes,
        s.dims,
        s.band_nodes,
        s.quadrature_nodes,
        s.stored_nodes
    );
    for w in b.cache_warnings() {
        println!("cache warning: {w}");
    }
    b
}

fn run<R: Real>(cache: Option<&VolumeMapCache>) {
    let cold = build::<R>(cache);
    if let Some(c) = cache {
        let hit = build::<R>(Some(c));
        // Sample both on a lattice through the tank's edges and corners.
        let mut same = true;
        for i in 0..=80 {
            for j in 0..=60 {
                for k in 0..=30 {
                    let x = Vec3::new(
                        R::of_f64(-2.02 + 0.0505 * i as f64),
                        R::of_f64(-0.02 + 0.0505 * j as f64),
                        R::of_f64(-0.77 + 0.0513 * k as f64),
                    );
                    let (a, b) = (cold.sample(&x), hit.sample(&x));
                    same &= a.volume.as_f64().to_bits() == b.volume.as_f64().to_bits()
                        && a.volume_gradient == b.volume_gradient;
                }
            }
        }
        println!("cache hit samples bit-identically to the cold build: {same}");
        assert!(same, "cache hit differs from the cold build");
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cache = args
        .iter()
        .position(|a| a == "cache")
        .and_then(|i| args.get(i + 1))
        .map(|d| VolumeMapCache::new(d).expect("cache directory"));
    if args.iter().any(|a| a == "f64") {
        run::<f64>(cache.as_ref());
    } else {
        run::<f32>(cache.as_ref());
    }
}
