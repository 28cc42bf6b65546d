//! Single-thread memory bandwidth of this machine (copy and write of 256 MiB), the
//! denominator of the memory bound quoted in `neighbour-search`'s docs:
//! `cargo run --release -p benches --example bandwidth`.
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let n = 32 << 20; // 32 Mi u64 = 256 MiB
    let src: Vec<u64> = (0..n as u64).collect();
    let mut dst = vec![0u64; n];
    let mut best_copy = f64::MAX;
    let mut best_fill = f64::MAX;
    for round in 0..5u64 {
        let t = Instant::now();
        dst.copy_from_slice(black_box(&src));
        best_copy = best_copy.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        dst.fill(black_box(round));
        best_fill = best_fill.min(t.elapsed().as_secs_f64());
        black_box(&dst);
    }
    let bytes = (n * 8) as f64;
    println!(
        "copy: {:.1} GB/s read + {:.1} GB/s written",
        bytes / best_copy / 1e9,
        bytes / best_copy / 1e9
    );
    println!("fill: {:.1} GB/s written", bytes / best_fill / 1e9);
}
