//! [`SearchLimits`]: the pair limit is exact (a search needing `limit` pairs succeeds, one
//! needing more fails with `TooManyPairs`), an interrupt stops every method, and a searcher
//! stopped either way gives correct lists on its next search.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use neighbour_search::{Method, NeighbourLists, SearchError, SearchLimits, Vec3};

/// `n` coincident particles (every pair a neighbour: n·(n − 1) pairs) and a few others.
fn clump(n: usize) -> Vec<Vec3<f64>> {
    let mut p = vec![Vec3::new(0.5, 0.25, -0.75); n];
    p.extend((0..50).map(|i| Vec3::new(3.0 + 0.1 * i as f64, 0.0, 0.0)));
    p
}

const ALL: [Method; 4] = [
    Method::RelationTable,
    Method::CellStartGrid,
    Method::HashedGrid,
    Method::BruteForce,
];

fn run(
    m: Method,
    p: &[Vec3<f64>],
    limits: SearchLimits,
    threads: usize,
) -> (Result<(), SearchError>, NeighbourLists) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut out = NeighbourLists::with_limits(limits);
        let r = m.build::<f64>().search(p, 0.15, &mut out);
        (r, out)
    })
}

#[test]
fn the_pair_limit_is_exact() {
    let p = clump(2000);
    let mut reference = NeighbourLists::new();
    Method::BruteForce
        .build::<f64>()
        .search(&p, 0.15, &mut reference)
        .unwrap();
    // Independent count: 2000 coincident particles, 2000 · 1999 ordered pairs; the 50
    // others, 0.1 apart on a line within h = 0.15, have 2 neighbours each but the ends 1.
    let pairs = 2000 * 1999 + 48 * 2 + 2;
    assert_eq!(reference.pair_count(), pairs);
    for m in ALL {
        for threads in [1, 3] {
            let at = SearchLimits {
                max_pairs: Some(pairs),
                interrupt: None,
            };
            let (r, out) = run(m, &p, at, threads);
            r.unwrap_or_else(|e| panic!("{} ({threads} threads): {e}", m.name()));
            assert_eq!(
                out.to_sorted_sets(),
                reference.to_sorted_sets(),
                "{}",
                m.name()
            );

            let below = SearchLimits {
                max_pairs: Some(pairs - 1),
                interrupt: None,
            };
            match run(m, &p, below, threads).0 {
                Err(e @ SearchError::TooManyPairs { found, limit, .. }) => {
                    assert_eq!(limit, pairs - 1, "{}", m.name());
                    assert!(found > limit, "{}: {e}", m.name());
                    let text = e.to_string();
                    assert!(text.contains(&format!("more than {limit} pairs")), "{text}");
                    assert!(text.contains("radius"), "{text}");
                }
                other => panic!("{} ({threads} threads): {other:?}", m.name()),
            }
        }
    }
}

#[test]
fn a_tight_limit_stops_the_search_early() {
    // 20,000 coincident particles: 4·10⁸ pairs (1.6 GB of indices) if not stopped. A limit
    // of 10⁶ must stop each method after a few million, not after computing them all: the
    // lists it leaves hold little.
    let p = clump(20_000);
    for m in [
        Method::RelationTable,
        Method::CellStartGrid,
        Method::HashedGrid,
    ] {
        let limits = SearchLimits {
            max_pairs: Some(1_000_000),
            interrupt: None,
        };
        match run(m, &p, limits, 2).0 {
            Err(SearchError::TooManyPairs { found, .. }) => {
                // One report per 2^14 pairs per task and one particle's list (20,049) beyond:
                // well under 10 million.
                assert!(found < 10_000_000, "{}: {found}", m.name());
            }
            other => panic!("{}: {other:?}", m.name()),
        }
    }
}

#[test]
fn an_interrupt_stops_every_method_and_the_searcher_recovers() {
    let p = clump(300);
    for m in ALL {
        let flag = Arc::new(AtomicBool::new(true));
        let mut s = m.build::<f64>();
        let mut out = NeighbourLists::with_limits(SearchLimits {
            max_pairs: None,
            interrupt: Some(flag.clone()),
        });
        match s.search(&p, 0.15, &mut out) {
            Err(SearchError::Interrupted) => {}
            other => panic!("{}: {other:?}", m.name()),
        }
        // Lowered again, and after a pair-limit failure, the same searcher and lists give
        // the right answer.
        flag.store(false, std::sync::atomic::Ordering::Relaxed);
        out.set_limits(SearchLimits {
            max_pairs: Some(10),
            interrupt: Some(flag),
        });
        assert!(matches!(
            s.search(&p, 0.15, &mut out),
            Err(SearchError::TooManyPairs { .. })
        ));
        out.set_limits(SearchLimits::default());
        s.search(&p, 0.15, &mut out).unwrap();
        let mut reference = NeighbourLists::new();
        Method::BruteForce
            .build::<f64>()
            .search(&p, 0.15, &mut reference)
            .unwrap();
        assert_eq!(
            out.to_sorted_sets(),
            reference.to_sorted_sets(),
            "{}",
            m.name()
        );
    }
}
