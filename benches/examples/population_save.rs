//! Time of writing a population: `Population::save` (the checkpoint, JSON) and the snapshot
//! table (`io::population_table` + `io::write_parquet`, what `particles comets` writes at
//! every snapshot), for the scattered-disk population of `comet_throughput`:
//!
//! `cargo run --release -p benches --example population_save -- N [DIR]`
//!
//! writes into `DIR` (default: the system's temporary directory) and prints the best of
//! three of each, the bytes written, as its last line
//!
//! `particles=N save_s=X save_bytes=B parquet_s=Y parquet_bytes=P`.
use std::time::Instant;

use symplectic::io::{population_table, write_parquet};
use symplectic::{Integrator, Scheme};

fn main() {
    if let Err(e) = run() {
        eprintln!("population_save: {e}");
        std::process::exit(2);
    }
}

fn best_of_three(mut f: impl FnMut() -> Result<(), String>) -> Result<f64, String> {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        f()?;
        best = best.min(start.elapsed().as_secs_f64());
    }
    Ok(best)
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: population_save N [DIR]";
    let n: usize = args.first().and_then(|s| s.parse().ok()).ok_or(usage)?;
    let dir = args
        .get(1)
        .map_or_else(std::env::temp_dir, std::path::PathBuf::from);
    let (population, _) =
        benches::scattered_disk_population(n, Scheme::S2, 547.875, Integrator::S6 { step: 730.5 })?;
    let save_path = dir.join(format!("population-save-{}.json", std::process::id()));
    let table_path = dir.join(format!("population-save-{}.parquet", std::process::id()));
    let save_s = best_of_three(|| population.save(&save_path).map_err(|e| e.to_string()))?;
    let parquet_s = best_of_three(|| {
        population_table(&population)
            .and_then(|t| write_parquet(&table_path, &t))
            .map_err(|e| e.to_string())
    })?;
    let size = |p: &std::path::Path| std::fs::metadata(p).map_or(0, |m| m.len());
    println!(
        "particles={n} save_s={save_s:.4} save_bytes={} parquet_s={parquet_s:.4} parquet_bytes={}",
        size(&save_path),
        size(&table_path)
    );
    std::fs::remove_file(&save_path).ok();
    std::fs::remove_file(&table_path).ok();
    Ok(())
}
