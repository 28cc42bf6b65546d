//! The IISPH pressure system (Ihmsen et al. 2014; Neder 2024 eqs. 17–24) against
//! independent evaluations: a literal dense f64 evaluation of eqs. 3, 19 and 20–24 (density,
//! predicted density, `a_ii`, `a_ii p_i + ψ_i`) on random particle sets, and the relaxed
//! Jacobi pressures against a direct sparse LU solve (faer) of the same linear system.

mod common;

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use iisph_granular::{Iisph, IisphParams, ParticleSet, Vec3};
use proptest::prelude::*;
use sph_kernels::{CubicSpline, Kernel};
use sph_solver::Boundary;

/// The oracle: eqs. 3, 19, 20–24 written out with all-pairs neighbours, in f64.
struct Oracle {
    rho: Vec<f64>,
    /// `ρ0 − ρ^adv`.
    source: Vec<f64>,
    aii: Vec<f64>,
    /// `a_ii p_i + ψ_i` for the given `p`.
    ap: Vec<f64>,
}

fn oracle(
    params: &IisphParams<f64>,
    boundary: &dyn Boundary<f64>,
    state: &ParticleSet<f64>,
    p: &[f64],
) -> Oracle {
    let h = params.common.support_radius;
    let rho0 = params.common.rest_density;
    let dt = params.substep_dt();
    let g = params.common.gravity;
    let k = CubicSpline::new(h).unwrap();
    let (x, v, m) = (&state.positions, &state.velocities, &state.masses);
    let n = x.len();
    let nbrs: Vec<Vec<usize>> = (0..n)
        .map(|i| {
            (0..n)
                .filter(|&j| j != i && (x[i] - x[j]).norm() < h)
                .collect()
        })
        .collect();
    let gw = |i: usize, j: usize| k.gradient(&(x[i] - x[j]));
    let vol = |i: usize| boundary.sample(&x[i]);
    // Eq. 3 + eq. 29.
    let rho: Vec<f64> = (0..n)
        .map(|i| {
            m[i] * k.value(0.0)
                + nbrs[i]
                    .iter()
                    .map(|&j| m[j] * k.value((x[i] - x[j]).norm()))
                    .sum::<f64>()
                + rho0 * vol(i).volume
        })
        .collect();
    // Eq. 18 (gravity only), eq. 19 with the boundary term.
    let vadv: Vec<Vec3<f64>> = (0..n).map(|i| v[i] + g * dt).collect();
    let source: Vec<f64> = (0..n)
        .map(|i| {
            let mut r = rho[i];
            for &j in &nbrs[i] {
                r += dt * m[j] * (vadv[i] - vadv[j]).dot(&gw(i, j));
            }
            r += dt * rho0 * vadv[i].dot(&vol(i).volume_gradient);
            rho0 - r
        })
        .collect();
    // d_ii (with the boundary), d_ij.
    let dii: Vec<Vec3<f64>> = (0..n)
        .map(|i| {
            let mut d = Vec3::zeros();
            for &j in &nbrs[i] {
                d -= gw(i, j) * (dt * dt * m[j] / (rho[i] * rho[i]));
            }
            d - vol(i).volume_gradient * (dt * dt * rho0 / (rho[i] * rho[i]))
        })
        .collect();
    let dij = |i: usize, j: usize| -gw(i, j) * (dt * dt * m[j] / (rho[j] * rho[j]));
    let sum_dij_pj: Vec<Vec3<f64>> = (0..n)
        .map(|i| nbrs[i].iter().map(|&j| dij(i, j) * p[j]).sum())
        .collect();
    // Eq. 24 with the boundary term.
    let aii: Vec<f64> = (0..n)
        .map(|i| {
            let mut a = 0.0;
            for &j in &nbrs[i] {
                let dji = -gw(j, i) * (dt * dt * m[i] / (rho[i] * rho[i]));
                a += m[j] * (dii[i] - dji).dot(&gw(i, j));
            }
            a + rho0 * dii[i].dot(&vol(i).volume_gradient)
        })
        .collect();
    // Eqs. 21–22: ψ_i = Σ_j m_j (Σ_j d_ij p_j − d_jj p_j − Σ_{k≠i} d_jk p_k)·∇W_ij, plus the
    // boundary's ρ0 (Σ_j d_ij p_j)·∇Ψ_i.
    let ap: Vec<f64> = (0..n)
        .map(|i| {
            let mut psi = 0.0;
            for &j in &nbrs[i] {
                let djk: Vec3<f64> = nbrs[j]
                    .iter()
                    .filter(|&&kk| kk != i)
                    .map(|&kk| dij(j, kk) * p[kk])
                    .sum();
                psi += m[j] * (sum_dij_pj[i] - dii[j] * p[j] - djk).dot(&gw(i, j));
            }
            psi += rho0 * sum_dij_pj[i].dot(&vol(i).volume_gradient);
            aii[i] * p[i] + psi
        })
        .collect();
    Oracle {
        rho,
        source,
        aii,
        ap,
    }
}

fn close(a: f64, b: f64, scale: f64, what: &str, i: usize) {
    assert!(
        (a - b).abs() <= 1e-9 * scale,
        "{what}[{i}]: solver {a} vs oracle {b} (scale {scale})"
    );
}

/// A jittered lattice of `n³` particles with random velocities, in a tank with volume maps.
fn random_scene(
    n: usize,
    jitter: &[f64],
    vel: &[f64],
) -> (Iisph<f64>, ParticleSet<f64>, IisphParams<f64>) {
    let p = IisphParams::<f64>::for_spacing(0.025);
    let (solver, mut state) = common::block_solver(p.clone(), [n, n, n], [n as f64 + 2.0; 3]);
    let s = p.common.particle_spacing;
    for (i, x) in state.positions.iter_mut().enumerate() {
        for a in 0..3 {
            x[a] += 0.3 * s * jitter[(3 * i + a) % jitter.len()];
            state.velocities[i][a] = vel[(3 * i + a + 1) % vel.len()];
        }
    }
    (solver, state, p)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Density, source, a_ii and a_ii p + ψ (the matrix-free A·p through pressure
    /// accelerations) against the literal eqs. 3, 19, 20–24.
    #[test]
    fn system_matches_literal_equations(
        jitter in prop::collection::vec(-1.0f64..1.0, 30..60),
        vel in prop::collection::vec(-1.0f64..1.0, 30..60),
        pres in prop::collection::vec(0.0f64..2000.0, 30..60),
    ) {
        let (mut solver, state, params) = random_scene(4, &jitter, &vel);
        let n = state.len();
        let p: Vec<f64> = (0..n).map(|i| pres[i % pres.len()]).collect();
        solver.assemble_system(&state).unwrap();
        let o = oracle(&params, solver.boundary(), &state, &p);
        let mut ap = vec![0.0; n];
        solver.apply_system(&state, &p, &mut ap).unwrap();
        let rho0 = params.common.rest_density;
        let a_scale = o.aii.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        let p_scale = 2000.0 * a_scale;
        for (i, &api) in ap.iter().enumerate() {
            close(solver.system_density()[i], o.rho[i], rho0, "rho", i);
            close(solver.system_source()[i], o.source[i], rho0, "source", i);
            close(solver.system_diagonal()[i], o.aii[i], a_scale, "a_ii", i);
            close(api, o.ap[i], p_scale, "A p", i);
        }
    }
}

/// A block of 6 × 6 × 6 particles squeezed to 0.9 spacing and falling onto the floor at
/// 1 m/s in a tank with volume maps, so most particles are compressed.
fn compressed_scene() -> (Iisph<f64>, ParticleSet<f64>) {
    let mut p = IisphParams::<f64>::for_spacing(0.025);
    p.density_error_tolerance = 1e-9;
    p.max_iterations = 20_000;
    let (solver, mut state) = common::block_solver(p, [6, 6, 6], [8.0, 8.0, 8.0]);
    let c = state.positions[0];
    for (x, v) in state.positions.iter_mut().zip(&mut state.velocities) {
        *x = c + (*x - c) * 0.9;
        *v = Vec3::new(0.0, -1.0, 0.0);
    }
    (solver, state)
}

/// The relaxed-Jacobi pressures of one step against a direct sparse LU solve (faer) of the
/// same linear system `A p = ρ0 − ρ^adv` restricted to the particles the unilateral solve
/// leaves under pressure (the others have `p = 0`): the pressures agree to 1e-4 of the
/// largest, and each solution leaves the other's set without compression.
#[test]
fn jacobi_matches_direct_sparse_solve() {
    let (mut solver, state) = compressed_scene();
    solver.assemble_system(&state).unwrap();
    let (iters, err, converged) = solver.solve_system(&state);
    assert!(
        converged,
        "Jacobi did not reach 1e-9 in {iters} iterations (error {err})"
    );
    let p_jacobi = solver.pressure().to_vec();
    let n = state.len();
    let source = solver.system_source().to_vec();
    let active: Vec<usize> = (0..n).filter(|&i| p_jacobi[i] > 0.0).collect();
    assert!(
        active.len() > n / 3,
        "only {} of {n} particles under pressure",
        active.len()
    );
    // Assemble A column by column (A e_k) on the active set.
    let mut pos = vec![usize::MAX; n];
    for (a, &i) in active.iter().enumerate() {
        pos[i] = a;
    }
    let mut triplets = Vec::new();
    let mut e = vec![0.0; n];
    let mut col = vec![0.0; n];
    for (ca, &k) in active.iter().enumerate() {
        e.iter_mut().for_each(|x| *x = 0.0);
        e[k] = 1.0;
        solver.apply_system(&state, &e, &mut col).unwrap();
        for (i, &v) in col.iter().enumerate() {
            if v != 0.0 && pos[i] != usize::MAX {
                triplets.push(Triplet::new(pos[i], ca, v));
            }
        }
    }
    let m = active.len();
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &triplets).unwrap();
    let lu = a.sp_lu().unwrap();
    let rhs = faer::Mat::<f64>::from_fn(m, 1, |r, _| source[active[r]]);
    let x = lu.solve(&rhs);
    let mut p_direct = vec![0.0; n];
    for (r, &i) in active.iter().enumerate() {
        p_direct[i] = x[(r, 0)];
    }
    let p_max = p_jacobi.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut worst = 0.0f64;
    for i in 0..n {
        worst = worst.max((p_jacobi[i] - p_direct[i]).abs());
    }
    assert!(
        worst <= 1e-4 * p_max,
        "max |p_jacobi - p_direct| = {worst} Pa, max p = {p_max} Pa"
    );
    // The direct solution is a valid unilateral one: p >= 0 on the set, no compression
    // (A p − source <= 0, to the solver's tolerance) off it.
    let rho0 = 1000.0;
    let mut ap = vec![0.0; n];
    solver.apply_system(&state, &p_direct, &mut ap).unwrap();
    for i in 0..n {
        if pos[i] == usize::MAX {
            assert!(
                ap[i] - source[i] <= 1e-6 * rho0,
                "particle {i} off the set is compressed by the direct pressures"
            );
        } else {
            assert!(
                p_direct[i] >= -1e-6 * p_max,
                "p_direct[{i}] = {}",
                p_direct[i]
            );
        }
    }
}
