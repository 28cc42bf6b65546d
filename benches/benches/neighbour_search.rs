//! Build + query time of every neighbour-search method, side by side with kiddo's k-d tree.
//!
//! `cargo bench -p benches --bench neighbour_search` (or `cargo xtask bench`). Scenes
//! (`neighbour_search::point_sets`): a jittered uniform block at rest spacing 0.025 with h = 0.05 (~30 neighbours each) and a
//! splash-like sparse cloud, at 10k, 100k and 1M particles (f32, in generation order), on
//! the default rayon pool; and SPlisHSPlasH's dam-break anchor scene (59k fluid + 129k
//! boundary particles) sorted by cell (as a solver keeps them) on one thread and on two,
//! and unsorted on one thread. kiddo builds its tree from the same points each iteration.

use benches::{dam_break_anchor, kiddo_search};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use neighbour_search::point_sets;
use neighbour_search::{CellOrder, CellSorter, Method, NeighbourLists, Vec3};
use std::hint::black_box;
use std::time::Duration;

const SPACING: f64 = 0.025;
const H: f32 = 0.05;

fn run_methods(c: &mut Criterion, group_name: &str, points: &[Vec3<f32>], threads: Option<usize>) {
    let mut group = c.benchmark_group(group_name);
    group.throughput(Throughput::Elements(points.len() as u64));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(if points.len() > 500_000 {
        8
    } else {
        3
    }));
    let threads = threads.unwrap_or_else(rayon::current_num_threads);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    for m in Method::FAST {
        let mut search = m.build::<f32>();
        let mut out = NeighbourLists::new();
        group.bench_with_input(
            BenchmarkId::new(m.name(), points.len()),
            points,
            |b, pts| {
                b.iter(|| {
                    pool.install(|| search.search(black_box(pts), H, &mut out).unwrap());
                    black_box(out.pair_count())
                })
            },
        );
    }
    group.bench_with_input(BenchmarkId::new("kiddo", points.len()), points, |b, pts| {
        b.iter(|| black_box(pool.install(|| kiddo_search(black_box(pts), H))))
    });
    group.finish();
}

fn uniform(c: &mut Criterion) {
    for n in [10_000, 100_000, 1_000_000] {
        let points = point_sets::jittered_lattice::<f32>(n, SPACING).expect("a valid lattice");
        run_methods(c, "uniform-block", &points, None);
    }
}

fn splash(c: &mut Criterion) {
    for n in [10_000, 100_000, 1_000_000] {
        let points = point_sets::splash::<f32>(n, SPACING).expect("a valid lattice");
        run_methods(c, "splash", &points, None);
    }
}

fn anchor(c: &mut Criterion) {
    let (points, _) = dam_break_anchor::<f32>();
    // As generated (lattice order), and sorted by cell as a solver keeps its particles.
    let perm = CellSorter::new()
        .permutation(&points, H, CellOrder::Lexicographic)
        .unwrap()
        .to_vec();
    let sorted: Vec<Vec3<f32>> = perm.iter().map(|&i| points[i as usize]).collect();
    run_methods(c, "dam-break-anchor-sorted-1-thread", &sorted, Some(1));
    run_methods(c, "dam-break-anchor-sorted-2-threads", &sorted, Some(2));
    run_methods(c, "dam-break-anchor-unsorted-1-thread", &points, Some(1));
}

criterion_group!(benches, anchor, uniform, splash);
criterion_main!(benches);
