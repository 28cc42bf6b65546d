//! Quick single-run timing of the neighbour searches on the dam-break anchor scene:
//! `cargo run --release -p benches --example ns_profile [threads] [method]`. For figures to quote,
//! use the criterion benchmark (`cargo bench -p benches --bench neighbour_search`).
use benches::dam_break_anchor;
use neighbour_search::{CellOrder, CellSorter, Method, NeighbourLists};
use std::time::Instant;

fn main() {
    if std::env::var_os("F64").is_some() {
        run::<f64>()
    } else {
        run::<f32>()
    }
}

fn run<R: neighbour_search::Real>() {
    let threads: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let (mut pts, fluid) = dam_break_anchor::<R>();
    if std::env::var_os("UNSORTED").is_none() {
        // As a solver keeps them: sorted by cell of the search radius.
        let perm = CellSorter::new()
            .permutation(&pts, R::of_f64(0.05), CellOrder::Lexicographic)
            .unwrap()
            .to_vec();
        pts = perm.iter().map(|&i| pts[i as usize]).collect();
    }
    println!(
        "{} particles ({} fluid), {} thread(s), {}",
        pts.len(),
        fluid,
        threads,
        R::NAME
    );
    let only: Option<String> = std::env::args().nth(2);
    for m in Method::FAST {
        if only.as_deref().is_some_and(|o| o != m.name()) {
            continue;
        }
        let mut s = m.build::<R>();
        let mut out = NeighbourLists::new();
        let mut times = Vec::new();
        for _ in 0..40 {
            let t = Instant::now();
            pool.install(|| s.search(&pts, R::of_f64(0.05), &mut out).unwrap());
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let med = times[times.len() / 2];
        let min = times[0];
        let t = s.stats();
        println!(
            "{:16} median {:7.2} ms min {:7.2} ms {:.3} us/particle  pairs/particle {:.1} tests/particle {:.1}  last: cells {:.1} sort {:.1} table {:.1} query {:.1} assemble {:.1} ms",
            m.name(),
            med * 1e3,
            min * 1e3,
            med * 1e6 / pts.len() as f64,
            out.pair_count() as f64 / pts.len() as f64,
            t.candidate_tests as f64 / pts.len() as f64,
            t.cells_s * 1e3, t.sort_s * 1e3, t.table_s * 1e3, t.query_s * 1e3, t.assemble_s * 1e3
        );
    }
}
