//! The Rust side of `benches/scripts/python_overhead.py`: the call `partisim.neighbour_lists`
//! makes (a fresh searcher and fresh lists each time, float64), timed on positions from a
//! file of little-endian float64 triples.
//!
//! `cargo run --release -p benches --example neighbour_lists_file -- FILE RADIUS [METHOD] [REPEATS]`
//! prints the median wall-clock seconds of REPEATS calls (default 5).
use neighbour_search::{Method, NeighbourLists, Vec3};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: neighbour_lists_file FILE RADIUS [METHOD] [REPEATS]";
    let bytes = std::fs::read(args.get(1).expect(usage)).expect("reading the positions");
    let radius: f64 = args.get(2).expect(usage).parse().expect("RADIUS");
    let method: Method = args
        .get(3)
        .map_or("cell-start-grid", String::as_str)
        .parse()
        .expect("METHOD");
    let repeats: usize = args.get(4).map_or(5, |r| r.parse().expect("REPEATS"));
    let values: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    let positions: Vec<Vec3<f64>> = values
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let mut times = Vec::with_capacity(repeats);
    let mut pairs = 0;
    for _ in 0..repeats {
        let start = Instant::now();
        let mut lists = NeighbourLists::new();
        method
            .build::<f64>()
            .search(&positions, radius, &mut lists)
            .expect("search");
        times.push(start.elapsed().as_secs_f64());
        pairs = lists.pair_count();
        drop(lists);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{} particles, {} pairs, median {:.6} s",
        positions.len(),
        pairs,
        times[repeats / 2]
    );
}
