//! Every fast method returns exactly the oracle's neighbour sets (proptest), in f32 and f64.
//!
//! Negative controls: each of the following bugs was planted once (2026-11-23), one at a
//! time, and `cargo test --release -p neighbour-search --test oracle` run; the tests that
//! caught it are named at each test below.
//! 1. cell-start grid visits x-columns −1..0 instead of −1..=1 (off-by-one cell range,
//!    `grid.rs`, `CellStartGrid`'s `locate`);
//! 2. hashed grid visits z-cells 0..=1 instead of −1..=1 (`HashedGrid`'s `locate`);
//! 3. relation table writes only the z-offsets −1..0 of a particle's 27 entries
//!    (`relation_table.rs`);
//! 4. `<=` instead of `<` in the distance test (`scan.rs`: scalar, AVX2 and AVX-512 paths),
//!    i.e. a particle at exactly `h` counted as a neighbour.

use neighbour_search::point_sets::{self, to_real as to_r};
use neighbour_search::{
    BruteForce, CellStartGrid, HashedGrid, Method, NeighbourLists, NeighbourSearch, Real,
    RelationTable, SearchError, Vec3, CELL_MARGIN,
};
use proptest::prelude::*;
use sph_core::random::SplitMix64;

fn oracle<R: Real>(points: &[Vec3<R>], h: R) -> Result<Vec<Vec<u32>>, SearchError> {
    let mut out = NeighbourLists::new();
    BruteForce::new().search(points, h, &mut out)?;
    Ok(out.to_sorted_sets())
}

/// Runs every fast method (twice, reusing buffers, to catch stale state) and compares.
fn check_all<R: Real>(points: &[Vec3<R>], h: R) -> Result<(), TestCaseError> {
    let expected = oracle(points, h);
    let mut searches: Vec<Box<dyn NeighbourSearch<R>>> =
        Method::FAST.iter().map(|m| m.build::<R>()).collect();
    for s in searches.iter_mut() {
        for round in 0..2 {
            let mut out = NeighbourLists::new();
            match (s.search(points, h, &mut out), &expected) {
                (Ok(()), Ok(exp)) => {
                    prop_assert_eq!(out.particle_count(), points.len());
                    prop_assert_eq!(
                        out.offsets()[points.len()],
                        out.indices().len(),
                        "{} CSR inconsistent",
                        s.name()
                    );
                    let got = out.to_sorted_sets();
                    for (i, (g, e)) in got.iter().zip(exp).enumerate() {
                        prop_assert_eq!(
                            g,
                            e,
                            "{} round {}: particle {} differs",
                            s.name(),
                            round,
                            i
                        );
                    }
                }
                // The bounded grid may refuse a domain whose bounding grid is too large.
                (Err(SearchError::DomainTooLarge { .. }), Ok(_))
                    if s.name() == "cell-start-grid" => {}
                (Err(e), Err(x)) => {
                    prop_assert_eq!(&e, x, "{} error differs from oracle", s.name())
                }
                (got, exp) => prop_assert!(
                    false,
                    "{}: got {:?}, oracle {:?}",
                    s.name(),
                    got.err(),
                    exp.as_ref().err()
                ),
            }
        }
    }
    Ok(())
}

/// The fixed point sets of `point_sets` (lattice ties, far clusters, negative coordinates,
/// points on cell faces), small, in both precisions: every method agrees with the oracle.
#[test]
fn fixed_point_sets_match_the_oracle() {
    let n = 1000;
    let mut rng = SplitMix64::new(0x5eed);
    let sets = [
        point_sets::lattice_block(n, 0.025),
        point_sets::random_cloud(&mut rng, n),
        point_sets::two_clusters(&mut rng, n),
        point_sets::negative_coordinates(&mut rng, n),
        point_sets::cell_faces(&mut rng, n),
    ];
    for set in &sets {
        check_all::<f64>(&to_r(&set.points), set.radius)
            .unwrap_or_else(|e| panic!("{}: {e}", set.name));
        check_all::<f32>(&to_r(&set.points), set.radius as f32)
            .unwrap_or_else(|e| panic!("{}: {e}", set.name));
    }
}

fn cloud(max: usize, half: f64) -> impl Strategy<Value = Vec<[f64; 3]>> {
    proptest::collection::vec([-half..half, -half..half, -half..half], 0..max)
}

macro_rules! for_both_precisions {
    ($name:ident, $body:expr) => {
        mod $name {
            use super::*;
            proptest! {
                #![proptest_config(ProptestConfig::with_cases(64))]
                #[test]
                fn f64_(case in $body) { check_all::<f64>(&to_r(&case.0), case.1)?; }
                #[test]
                fn f32_(case in $body) { check_all::<f32>(&to_r(&case.0), case.1 as f32)?; }
            }
        }
    };
}

// Random clouds with random radius: from sparse to ~100 neighbours each.
// Caught planted bugs 1, 2, 3 (not 4: an exact distance h has probability zero here).
for_both_precisions!(random_clouds, (cloud(400, 3.0), 0.05..2.0f64));

// Negative and offset coordinates. Caught planted bugs 1, 2, 3.
for_both_precisions!(
    negative_coordinates,
    (cloud(300, 1.0), 0.1..1.0f64, -1e3..-1.0f64).prop_map(|(c, h, off)| (
        c.into_iter()
            .map(|p| p.map(|x| x + off))
            .collect::<Vec<_>>(),
        h
    ))
);

// Two clusters 1e6 apart (the cell-start grid may refuse: its bounding grid is huge).
// Caught planted bugs 1, 2, 3.
for_both_precisions!(
    far_clusters,
    (
        cloud(150, 0.5),
        cloud(150, 0.5),
        0.05..0.5f64,
        any::<bool>()
    )
        .prop_map(|(a, b, h, neg)| {
            let d = if neg { -1e6 } else { 1e6 };
            let mut v = a;
            v.extend(b.into_iter().map(|p| [p[0] + d, p[1] - d, p[2] + 0.5 * d]));
            (v, h)
        })
);

// Points on a lattice of spacing h (distance exactly h between lattice neighbours, and on the
// faces of cells of edge h) and on a lattice of the actual cell edge h(1 + CELL_MARGIN),
// with duplicates. Caught planted bugs 1, 2, 3 and 4 (the only proptest that sees 4).
for_both_precisions!(
    lattice_faces_and_duplicates,
    (1usize..6, 0.01..3.0f64, any::<bool>(), 0usize..20, -5i32..5).prop_map(
        |(n, h, on_cells, dups, shift)| {
            let step = if on_cells { h * (1.0 + CELL_MARGIN) } else { h };
            let mut v = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        v.push([
                            (i as i32 + shift) as f64 * step,
                            j as f64 * step,
                            -(k as f64) * step,
                        ]);
                    }
                }
            }
            let m = v.len();
            for d in 0..dups.min(m) {
                v.push(v[(d * 7) % m]);
            }
            (v, h)
        }
    )
);

// Dense near-duplicates: many particles within a fraction of h. Caught planted bugs 1, 2, 3.
for_both_precisions!(dense_blob, (cloud(300, 0.05), 0.01..0.2f64));

#[test]
fn empty_and_single() {
    for s in Method::FAST.iter().chain([Method::BruteForce].iter()) {
        let mut search = s.build::<f64>();
        let mut out = NeighbourLists::new();
        search.search(&[], 1.0, &mut out).unwrap();
        assert_eq!(out.particle_count(), 0);
        search
            .search(&[Vec3::new(1.0, -2.0, 3.0)], 1.0, &mut out)
            .unwrap();
        assert_eq!(out.particle_count(), 1);
        assert!(out.neighbours(0).is_empty());
    }
}

/// Caught planted bug 4 (`<=` in the distance test); blind to 1–3 (three points in one cell).
#[test]
fn distance_exactly_h_is_excluded_and_just_below_is_included() {
    let h = 0.1f64;
    let pts = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(h, 0.0, 0.0),
        Vec3::new(0.0, h * (1.0 - 1e-15), 0.0),
    ];
    for m in Method::FAST.iter().chain([Method::BruteForce].iter()) {
        let mut out = NeighbourLists::new();
        m.build::<f64>().search(&pts, h, &mut out).unwrap();
        let sets = out.to_sorted_sets();
        assert_eq!(sets[0], vec![2], "{}", m.name());
        assert!(
            sets[1].is_empty(),
            "{}: distance h*sqrt(2) and exactly h",
            m.name()
        );
    }
}

#[test]
fn bad_input_is_named() {
    let mut pts = vec![Vec3::new(0.0f32, 0.0, 0.0); 5];
    pts[3].y = f32::NAN;
    for m in Method::FAST.iter().chain([Method::BruteForce].iter()) {
        let mut out = NeighbourLists::new();
        let mut s = m.build::<f32>();
        match s.search(&pts, 1.0, &mut out) {
            Err(SearchError::NonFinitePosition {
                index: 3,
                axis: 'y',
                ..
            }) => {}
            other => panic!("{}: {other:?}", m.name()),
        }
        let ok = vec![Vec3::new(0.0f32, 0.0, 0.0); 2];
        for h in [0.0f32, -1.0, f32::NAN, f32::INFINITY, 1e-30] {
            let e = s.search(&ok, h, &mut out).unwrap_err();
            assert!(
                matches!(e, SearchError::InvalidRadius { .. }),
                "{}: h = {h}: {e}",
                m.name()
            );
            assert!(e.to_string().contains("radius"));
        }
        let far = vec![Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(0.0, 0.0, 3e9)];
        let e = s.search(&far, 1.0, &mut out).unwrap_err();
        assert!(
            matches!(
                e,
                SearchError::CellCoordinateOverflow {
                    index: 1,
                    axis: 'z',
                    ..
                }
            ),
            "{}: {e}",
            m.name()
        );
    }
}

#[test]
fn cell_start_grid_refuses_huge_domains_with_a_clear_error() {
    let pts = vec![Vec3::new(0.0f64, 0.0, 0.0), Vec3::new(1e6, 1e6, 1e6)];
    let mut out = NeighbourLists::new();
    let e = CellStartGrid::<f64>::new()
        .search(&pts, 0.1, &mut out)
        .unwrap_err();
    assert!(matches!(e, SearchError::DomainTooLarge { .. }), "{e}");
    assert!(e.to_string().contains("unbounded method"), "{e}");
    RelationTable::<f64>::new()
        .search(&pts, 0.1, &mut out)
        .unwrap();
    HashedGrid::<f64>::new()
        .search(&pts, 0.1, &mut out)
        .unwrap();
}

#[test]
fn output_is_identical_for_any_thread_count() {
    let pts: Vec<Vec3<f64>> = (0..20_000)
        .map(|i| {
            let t = i as f64;
            Vec3::new(
                (t * 0.61803).fract() * 3.0,
                (t * 0.41421).fract() * 3.0,
                (t * 0.7320).fract() * 3.0,
            )
        })
        .collect();
    for m in Method::FAST {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut out = NeighbourLists::new();
                m.build::<f64>().search(&pts, 0.12, &mut out).unwrap();
                out
            })
        };
        assert_eq!(run(1), run(3), "{}", m.name());
    }
}

/// Clouds already sorted by cell (as a solver keeps them): the searches skip their sort and
/// take the contiguous assembly path, on one thread and on several.
mod cell_sorted {
    use super::*;
    use neighbour_search::{CellOrder, CellSorter};

    fn sorted(case: &(Vec<[f64; 3]>, f64), sort_radius: f64) -> Vec<Vec3<f64>> {
        let pts: Vec<Vec3<f64>> = to_r(&case.0);
        let perm = CellSorter::new()
            .permutation(&pts, sort_radius, CellOrder::Lexicographic)
            .unwrap()
            .to_vec();
        perm.iter().map(|&i| pts[i as usize]).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Caught planted bugs 1, 2, 3 (not 4, as for the random clouds).
        #[test]
        fn sorted_clouds_match_the_oracle(case in (cloud(3000, 2.0), 0.05..0.6f64), sparse in any::<bool>(), threads in 1usize..4) {
            // Sparse: stretch the cloud so that many relation-table runs hold no particle
            // and whole tasks come out empty.
            let mut case = case;
            if sparse {
                for p in case.0.iter_mut() {
                    *p = p.map(|x| x * 20.0);
                }
            }
            let pts = sorted(&case, case.1);
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| check_all::<f64>(&pts, case.1))?;
        }
    }
}

/// `search_active`: the points `active..` passive, listing only the active points. Every
/// fast method against the oracle's lists with the passive–passive pairs taken out here
/// (as sets), and against its own full search with those entries taken out (entry for
/// entry: the order a solver's sums add in is the full search's), on unsorted and
/// cell-sorted clouds, on one thread and several, `active` from 0 to beyond the count.
mod active_points {
    use super::*;
    use neighbour_search::{CellOrder, CellSorter};

    /// `lists` with the entries `j >= active` of the particles `i >= active` removed.
    fn without_passive_pairs(lists: &NeighbourLists, active: usize) -> Vec<Vec<u32>> {
        lists
            .iter()
            .map(|(i, l)| {
                l.iter()
                    .copied()
                    .filter(|&j| i < active || (j as usize) < active)
                    .collect()
            })
            .collect()
    }

    fn check<R: Real>(points: &[Vec3<R>], h: R, active: usize) -> Result<(), TestCaseError> {
        let mut full = NeighbourLists::new();
        let oracle = match BruteForce::new().search(points, h, &mut full) {
            Ok(()) => without_passive_pairs(&full, active),
            Err(_) => return Ok(()), // input errors: `check_all` covers them
        };
        let expected: Vec<Vec<u32>> = oracle
            .into_iter()
            .map(|mut l| {
                l.sort_unstable();
                l
            })
            .collect();
        for m in Method::FAST {
            let mut s = m.build::<R>();
            let mut whole = NeighbourLists::new();
            match s.search(points, h, &mut whole) {
                Ok(()) => {}
                Err(SearchError::DomainTooLarge { .. }) => continue,
                Err(e) => prop_assert!(false, "{}: {e}", m.name()),
            }
            for round in 0..2 {
                let mut out = NeighbourLists::new();
                s.search_active(points, active, h, &mut out)
                    .map_err(|e| TestCaseError::fail(format!("{}: {e}", m.name())))?;
                prop_assert_eq!(out.particle_count(), points.len());
                prop_assert_eq!(out.offsets()[points.len()], out.indices().len());
                let got: Vec<Vec<u32>> = out.iter().map(|(_, l)| l.to_vec()).collect();
                prop_assert_eq!(
                    &got,
                    &without_passive_pairs(&whole, active),
                    "{} round {}: not the full search's lists without the passive pairs",
                    m.name(),
                    round
                );
                prop_assert_eq!(
                    &out.to_sorted_sets(),
                    &expected,
                    "{} round {}: not the oracle's sets",
                    m.name(),
                    round
                );
            }
        }
        Ok(())
    }

    fn cell_sorted(pts: Vec<Vec3<f64>>, h: f64) -> Vec<Vec3<f64>> {
        let perm = CellSorter::new()
            .permutation(&pts, h, CellOrder::Lexicographic)
            .unwrap()
            .to_vec();
        perm.iter().map(|&i| pts[i as usize]).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn passive_points_list_only_active_ones(
            case in (cloud(600, 1.0), 0.05..0.6f64),
            active_frac in 0.0..1.2f64,
            sorted in any::<bool>(),
            threads in 1usize..4,
        ) {
            let (pts, h) = case;
            let active = (active_frac * pts.len() as f64) as usize;
            let pts: Vec<Vec3<f64>> = to_r(&pts);
            let pts = if sorted { cell_sorted(pts, h) } else { pts };
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| check::<f64>(&pts, h, active))?;
            let p32: Vec<Vec3<f32>> = pts.iter().map(|p| p.map(|x| x as f32)).collect();
            pool.install(|| check::<f32>(&p32, h as f32, active))?;
        }

        /// A wall of passive points on a lattice (ties at exactly `h`) under a cloud of
        /// active ones, as a solver's boundary rows under its particles.
        #[test]
        fn a_passive_lattice_under_active_points(
            side in 1usize..12,
            cloud_pts in cloud(200, 0.5),
            on_cells in any::<bool>(),
        ) {
            let h = 0.1;
            let step = if on_cells { h * (1.0 + CELL_MARGIN) } else { h };
            let mut pts: Vec<Vec3<f64>> = to_r(&cloud_pts);
            let active = pts.len();
            for i in 0..side {
                for k in 0..side {
                    for j in 0..3 {
                        pts.push(Vec3::new(
                            i as f64 * step - 0.5,
                            -0.5 - j as f64 * step,
                            k as f64 * step - 0.5,
                        ));
                    }
                }
            }
            check::<f64>(&pts, h, active)?;
        }
    }
}
