//! The adaptive iteration count of `PbfParams::mean_compression_tolerance` (SPlisHSPlasH's
//! stopping rule), checked against an oracle written independently of the crate: the mean
//! compression of every iteration is recomputed here in f64 with the Poly6 formula of
//! `formulas` and brute-force neighbour sets (all pairs within `h` at the predicted
//! positions, Algorithm 1 lines 5–7 of Macklin & Müller 2013), from positions obtained with a
//! fixed iteration count; the iteration at which the solver stopped must be the first one
//! (from the minimum on) within the tolerance, or the maximum.
//!
//! Planted bugs this catches (each planted once, the tests run, the code restored;
//! 2026-11-23): the density without its self term `m_i W(0)` (three of the four tests fail:
//! the reported compression and the decisions differ from the oracle's), and the minimum
//! iteration count ignored by the stopping rule (`loose_tolerance_runs_the_minimum` and the
//! property test fail). A halved `λ` or a wrong constraint gradient passes here by design:
//! the positions come from the solver's own fixed-count steps, and `tests/oracle.rs` checks
//! them.

mod common;

use common::formulas::{norm, poly6, sub, to_v, V};
use pbf::{ParticleSet, Pbf, PbfParams, Vec3};
use proptest::prelude::*;

/// Brute-force neighbour sets: `j ≠ i` with `|x_i − x_j| < h`.
fn brute_force_neighbours(x: &[V], h: f64) -> Vec<Vec<usize>> {
    (0..x.len())
        .map(|i| {
            (0..x.len())
                .filter(|&j| j != i && norm(sub(x[i], x[j])) < h)
                .collect()
        })
        .collect()
}

/// Mean compression `(1/N) Σ max(ρ_i/ρ0 − 1, 0)` at positions `x`, with the neighbour sets
/// `nb` fixed for the step, `ρ_i = m_i W(0) + Σ_j m_j W(|x_i − x_j|)` (eq. 2), in f64.
fn mean_compression(p: &PbfParams<f64>, x: &[Vec3<f64>], m: &[f64], nb: &[Vec<usize>]) -> f64 {
    let h = p.common.support_radius;
    let x: Vec<V> = x.iter().map(to_v).collect();
    let mut sum = 0.0;
    for i in 0..x.len() {
        let mut rho = m[i] * poly6([0.0; 3], h);
        for &j in &nb[i] {
            rho += m[j] * poly6(sub(x[i], x[j]), h);
        }
        sum += (rho / p.common.rest_density - 1.0).max(0.0);
    }
    sum / x.len() as f64
}

/// One frame (one substep) from `before` with a fixed count of `k` iterations.
fn fixed_step(
    p: &PbfParams<f64>,
    solids_of: &dyn Fn() -> pbf::Solids<f64>,
    before: &ParticleSet<f64>,
    k: usize,
) -> (ParticleSet<f64>, Pbf<f64>) {
    let q = PbfParams {
        mean_compression_tolerance: None,
        solver_iterations: k,
        ..p.clone()
    };
    let mut solver = Pbf::new(q, solids_of()).unwrap();
    let mut state = before.clone();
    solver.step(&mut state).unwrap();
    (state, solver)
}

/// Runs `frames` adaptive frames and checks each stopping decision against the oracle;
/// returns the iteration counts.
fn check_run(tol: f64, min: usize, max: usize, frames: usize) -> Vec<usize> {
    let (mut p, mut state, _) = common::dam_break::<f64>();
    let solids_of = || common::dam_break::<f64>().2;
    p.common.substeps = 1;
    p.common.reorder_every = 0;
    p.mean_compression_tolerance = Some(tol);
    p.min_solver_iterations = min;
    p.solver_iterations = max;
    let mut adaptive = Pbf::new(p.clone(), solids_of()).unwrap();
    let mut counts = Vec::new();
    for frame in 0..frames {
        let before = state.clone();
        let stats = adaptive.step(&mut state).unwrap();
        let k = stats.iterations;
        assert!((min..=max).contains(&k), "frame {frame}: {k} iterations");
        counts.push(k);

        // The adaptive step is the fixed-count step with the same number of iterations.
        let (fixed, _) = fixed_step(&p, &solids_of, &before, k);
        assert_eq!(common::bits(&fixed), common::bits(&state), "frame {frame}");

        // Compression at the start of iteration j: at the predicted positions for j = 1,
        // after j − 1 fixed iterations otherwise (a step's final positions are x*).
        let g = p.common.gravity;
        let dt = p.substep_dt();
        let predicted: Vec<Vec3<f64>> = before
            .positions
            .iter()
            .zip(&before.velocities)
            .map(|(x, v)| x + (v + g * dt) * dt)
            .collect();
        let predicted_v: Vec<V> = predicted.iter().map(to_v).collect();
        let nb = brute_force_neighbours(&predicted_v, p.common.support_radius);
        for j in 1..=k {
            let x = if j == 1 {
                predicted.clone()
            } else {
                fixed_step(&p, &solids_of, &before, j - 1).0.positions
            };
            let c = mean_compression(&p, &x, &before.masses, &nb);
            // Decisions closer to the tolerance than the f64 summation-order difference are
            // not judged.
            if (c - tol).abs() < 1e-12 {
                continue;
            }
            if j < k && j >= min {
                assert!(
                    c > tol,
                    "frame {frame}: iteration {j} of {k} already met {c} <= {tol}"
                );
            }
            if j == k {
                assert!(
                    (stats.last_solve_error - c).abs() <= 1e-12 * c.max(1e-3),
                    "frame {frame}: reported {} vs oracle {c}",
                    stats.last_solve_error
                );
                assert_eq!(
                    stats.unconverged_substeps,
                    usize::from(c > tol),
                    "frame {frame}: stopped at {k} of {max} with {c} vs {tol}"
                );
                if k < max {
                    assert!(
                        c <= tol,
                        "frame {frame}: stopped at {k} < {max} with {c} > {tol}"
                    );
                }
            }
        }
    }
    counts
}

#[test]
fn stops_at_the_first_iteration_within_the_tolerance() {
    // 0.1 % mean compression (SPlisHSPlasH's DamBreakModel setting) on the small dam break.
    let counts = check_run(1e-3, 2, 12, 10);
    assert!(
        counts.iter().any(|&k| k > 2),
        "the tolerance never required more than the minimum: {counts:?}"
    );
}

#[test]
fn unreachable_tolerance_runs_the_maximum_and_counts_it() {
    let (mut p, mut state, solids) = common::dam_break::<f32>();
    p.mean_compression_tolerance = Some(1e-30);
    p.min_solver_iterations = 1;
    p.solver_iterations = 3;
    let mut solver = Pbf::new(p.clone(), solids).unwrap();
    for _ in 0..3 {
        let s = solver.step(&mut state).unwrap();
        assert_eq!(s.iterations, p.common.substeps * 3);
        assert_eq!(s.unconverged_substeps, p.common.substeps);
        assert!(s.last_solve_error > 0.0);
    }
}

#[test]
fn loose_tolerance_runs_the_minimum() {
    let (mut p, mut state, solids) = common::dam_break::<f32>();
    p.mean_compression_tolerance = Some(1.0);
    p.min_solver_iterations = 2;
    p.solver_iterations = 50;
    let mut solver = Pbf::new(p.clone(), solids).unwrap();
    let s = solver.step(&mut state).unwrap();
    assert_eq!(s.iterations, p.common.substeps * 2);
    assert_eq!(s.unconverged_substeps, 0);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]
    #[test]
    fn stopping_rule_matches_the_oracle(tol in 2e-4..2e-2f64, min in 1usize..4, extra in 0usize..8) {
        check_run(tol, min, min + extra, 4);
    }
}
