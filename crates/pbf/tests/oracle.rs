//! The solver against a naive O(N²) oracle written independently here in f64 from the paper's
//! equations: brute-force neighbour loops, the Poly6 / Spiky formulas of Müller et al. (2003)
//! written out, and Algorithm 1 of Macklin & Müller (2013) step by step.
//!
//! Planted bugs these tests catch (each planted once in `src/passes.rs`, the tests run, the
//! code restored; 2026-11-23): the density without its self term `m_i W(0)`, a halved `λ_i`,
//! the denominator of eq. 11 without `|∇_{p_i} C_i|²`: each fails all six tests; the sign of
//! `λ_j` flipped in `Δp_i` (eq. 14): fails all but `unilateral_lambda`, which checks `λ` only;
//! `s_corr` with exponent `n − 1` instead of `n` (eq. 13): fails the four tests that use
//! `s_corr`; the collision projection skipped in the Jacobi loop (line 14): fails
//! `full_step`, the one test with a solid.

mod common;

use std::f64::consts::PI;

use common::formulas::{add, cross, dot, norm, poly6, scale, spiky_grad, sub, to_v, V};
use pbf::{Pbf, PbfParams, Sdf, Vec3};
use proptest::prelude::*;
use sph_core::Plane;

/// `Σ_k |∇_{p_k} C_i|²` for a particle inside a simple cubic lattice of spacing `s` with
/// volumes `s³` (the unit of `s_corr`, see the crate docs).
fn lattice_denominator(s: f64, h: f64) -> f64 {
    let reach = (h / s).ceil() as i64;
    let mut sum = 0.0;
    let mut gi = [0.0; 3];
    for a in -reach..=reach {
        for b in -reach..=reach {
            for c in -reach..=reach {
                if (a, b, c) == (0, 0, 0) {
                    continue;
                }
                let g = scale(
                    spiky_grad([a as f64 * s, b as f64 * s, c as f64 * s], h),
                    s.powi(3),
                );
                sum += dot(g, g);
                gi = add(gi, g);
            }
        }
    }
    sum + dot(gi, gi)
}

struct Oracle {
    h: f64,
    rho0: f64,
    eps: f64,
    k: f64,
    n: i32,
    dq: f64,
    scorr_unit: f64,
}

impl Oracle {
    fn new(p: &PbfParams<f64>) -> Self {
        Self {
            h: p.common.support_radius,
            rho0: p.common.rest_density,
            eps: p.cfm_epsilon,
            k: p.scorr_k,
            n: p.scorr_n as i32,
            dq: p.scorr_delta_q * p.common.support_radius,
            scorr_unit: 1.0
                / lattice_denominator(p.common.particle_spacing, p.common.support_radius),
        }
    }

    /// Brute-force neighbour sets: `j ≠ i` with `|x_i − x_j| < h`.
    fn neighbours(&self, x: &[V]) -> Vec<Vec<usize>> {
        (0..x.len())
            .map(|i| {
                (0..x.len())
                    .filter(|&j| j != i && norm(sub(x[i], x[j])) < self.h)
                    .collect()
            })
            .collect()
    }

    /// Eq. 13.
    fn scorr(&self, r: V) -> f64 {
        -self.k * (poly6(r, self.h) / poly6([self.dq, 0.0, 0.0], self.h)).powi(self.n)
    }

    /// Eqs. 2 and 11 (densities, λ) and eq. 14 (Δp), written for general masses:
    /// `∇_{p_j} C_i = −(m_j/ρ0) ∇W_ij`, `∇_{p_i} C_i = Σ_j (m_j/ρ0) ∇W_ij`,
    /// `Δp_i = Σ_j (λ_i m_j + λ_j m_i)/ρ0 ∇W_ij + s_corr` terms.
    fn lambda_delta(&self, x: &[V], m: &[f64], nb: &[Vec<usize>]) -> (Vec<f64>, Vec<f64>, Vec<V>) {
        let n = x.len();
        let mut rho = vec![0.0; n];
        let mut lambda = vec![0.0; n];
        for i in 0..n {
            rho[i] = m[i] * poly6([0.0; 3], self.h);
            for &j in &nb[i] {
                rho[i] += m[j] * poly6(sub(x[i], x[j]), self.h);
            }
            let c = rho[i] / self.rho0 - 1.0;
            // k = i and k = j cases of eq. 8.
            let mut grad_self = [0.0; 3];
            let mut sum = 0.0;
            for &j in &nb[i] {
                let g = spiky_grad(sub(x[i], x[j]), self.h);
                grad_self = add(grad_self, scale(g, m[j] / self.rho0));
                let gj = scale(g, -m[j] / self.rho0);
                sum += dot(gj, gj);
            }
            sum += dot(grad_self, grad_self);
            lambda[i] = -c / (sum + self.eps);
        }
        let mut dp = vec![[0.0; 3]; n];
        for i in 0..n {
            for &j in &nb[i] {
                let r = sub(x[i], x[j]);
                let coeff = lambda[i] * m[j]
                    + lambda[j] * m[i]
                    + self.scorr(r) * self.scorr_unit * 0.5 * (m[i] + m[j]);
                dp[i] = add(dp[i], scale(spiky_grad(r, self.h), coeff / self.rho0));
            }
        }
        (rho, lambda, dp)
    }

    /// The paper's eq. 14 exactly, for equal masses `m` (its "drop the mass" form times `m`).
    fn delta_equal_mass(&self, x: &[V], m: f64, lambda: &[f64], nb: &[Vec<usize>]) -> Vec<V> {
        (0..x.len())
            .map(|i| {
                let mut d = [0.0; 3];
                for &j in &nb[i] {
                    let r = sub(x[i], x[j]);
                    let w = lambda[i] + lambda[j] + self.scorr(r) * self.scorr_unit;
                    d = add(d, scale(spiky_grad(r, self.h), w));
                }
                scale(d, m / self.rho0)
            })
            .collect()
    }
}

#[derive(Debug, Clone)]
struct Case {
    h: f64,
    ratio: f64,
    eps_rel: f64,
    k: f64,
    n: u32,
    dq: f64,
    points: Vec<V>,
    mass_factors: Vec<f64>,
}

fn case() -> impl Strategy<Value = Case> {
    (
        0.02..0.2f64,
        1.5..3.0f64,
        0.1..2.0f64,
        0.0..0.3f64,
        1u32..7,
        0.1..0.3f64,
        2usize..48,
        1.5..4.0f64,
    )
        .prop_flat_map(|(h, ratio, eps_rel, k, n, dq, count, side)| {
            let l = side * h;
            (
                proptest::collection::vec([0.0..l, 0.0..l, 0.0..l], count),
                proptest::collection::vec(0.5..2.0f64, count),
            )
                .prop_map(move |(points, mass_factors)| Case {
                    h,
                    ratio,
                    eps_rel,
                    k,
                    n,
                    dq,
                    points,
                    mass_factors,
                })
        })
}

fn params(c: &Case) -> PbfParams<f64> {
    let mut p = PbfParams::<f64>::for_spacing(c.h / c.ratio);
    p.common.support_radius = c.h;
    p.cfm_epsilon = c.eps_rel * p.reference_denominator().unwrap();
    p.scorr_k = c.k;
    p.scorr_n = c.n;
    p.scorr_delta_q = c.dq;
    p
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// ρ, λ (eq. 11) and Δp (eq. 14) of one Jacobi iteration, equal masses: against the
    /// oracle's general-mass form and the paper's literal equal-mass eq. 14.
    #[test]
    fn lambda_and_delta_p_equal_masses(c in case()) {
        let p = params(&c);
        let m = p.particle_mass();
        let oracle = Oracle::new(&p);
        let x: Vec<V> = c.points.clone();
        let masses = vec![m; x.len()];
        let nb = oracle.neighbours(&x);
        let (rho, lambda, dp) = oracle.lambda_delta(&x, &masses, &nb);
        let dp_paper = oracle.delta_equal_mass(&x, m, &lambda, &nb);
        let pts: Vec<Vec3<f64>> = x.iter().map(|a| Vec3::new(a[0], a[1], a[2])).collect();
        let mut solver = Pbf::new(p.clone(), vec![]).unwrap();
        let ev = solver.evaluate_constraints(&pts, &masses).unwrap();
        let lam_scale = lambda.iter().fold(0.0f64, |a, &l| a.max(l.abs()));
        let dp_scale = dp.iter().fold(0.0f64, |a, d| a.max(norm(*d)));
        for i in 0..x.len() {
            prop_assert!(close(ev.density[i], rho[i], 1e-12 * p.common.rest_density),
                "rho {i}: {} vs {}", ev.density[i], rho[i]);
            prop_assert!(close(ev.lambda[i], lambda[i], 1e-10 * lam_scale + 1e-300),
                "lambda {i}: {} vs {}", ev.lambda[i], lambda[i]);
            let got = to_v(&ev.delta_p[i]);
            prop_assert!(norm(sub(got, dp[i])) <= 1e-10 * dp_scale + 1e-300,
                "dp {i}: {got:?} vs {:?}", dp[i]);
            prop_assert!(norm(sub(dp_paper[i], dp[i])) <= 1e-12 * dp_scale + 1e-300,
                "paper form {i}");
        }
    }

    /// The same with unequal masses (the mass-weighted generalisation documented in the crate).
    #[test]
    fn lambda_and_delta_p_unequal_masses(c in case()) {
        let p = params(&c);
        let oracle = Oracle::new(&p);
        let x: Vec<V> = c.points.clone();
        let masses: Vec<f64> = c.mass_factors.iter().map(|f| f * p.particle_mass()).collect();
        let nb = oracle.neighbours(&x);
        let (rho, lambda, dp) = oracle.lambda_delta(&x, &masses, &nb);
        let pts: Vec<Vec3<f64>> = x.iter().map(|a| Vec3::new(a[0], a[1], a[2])).collect();
        let mut solver = Pbf::new(p.clone(), vec![]).unwrap();
        let ev = solver.evaluate_constraints(&pts, &masses).unwrap();
        let lam_scale = lambda.iter().fold(0.0f64, |a, &l| a.max(l.abs()));
        let dp_scale = dp.iter().fold(0.0f64, |a, d| a.max(norm(*d)));
        for i in 0..x.len() {
            prop_assert!(close(ev.density[i], rho[i], 1e-12 * p.common.rest_density));
            prop_assert!(close(ev.lambda[i], lambda[i], 1e-10 * lam_scale + 1e-300));
            prop_assert!(norm(sub(to_v(&ev.delta_p[i]), dp[i])) <= 1e-10 * dp_scale + 1e-300);
        }
    }

    /// `clamp_negative_constraint` (SPlisHSPlasH's unilateral `max(C_i, 0)`): the oracle's
    /// λ where the particle is compressed, exactly 0 where it is not.
    #[test]
    fn unilateral_lambda(c in case()) {
        let mut p = params(&c);
        p.clamp_negative_constraint = true;
        let oracle = Oracle::new(&p);
        let x: Vec<V> = c.points.clone();
        let masses: Vec<f64> = c.mass_factors.iter().map(|f| f * p.particle_mass()).collect();
        let nb = oracle.neighbours(&x);
        let (rho, lambda, _) = oracle.lambda_delta(&x, &masses, &nb);
        let pts: Vec<Vec3<f64>> = x.iter().map(|a| Vec3::new(a[0], a[1], a[2])).collect();
        let mut solver = Pbf::new(p.clone(), vec![]).unwrap();
        let ev = solver.evaluate_constraints(&pts, &masses).unwrap();
        let lam_scale = lambda.iter().fold(0.0f64, |a, &l| a.max(l.abs()));
        for i in 0..x.len() {
            if (rho[i] / p.common.rest_density - 1.0).abs() < 1e-12 {
                continue; // the sign is not decided at round-off
            }
            let expected = if rho[i] > p.common.rest_density { lambda[i] } else { 0.0 };
            prop_assert!(close(ev.lambda[i], expected, 1e-10 * lam_scale + 1e-300),
                "lambda {i}: {} vs {expected} (rho {})", ev.lambda[i], rho[i]);
        }
    }

    /// One full step of Algorithm 1 (gravity, prediction, neighbours once, Jacobi iterations
    /// with collisions against a floor, velocity update, vorticity confinement, XSPH)
    /// against the oracle.
    #[test]
    fn full_step(c in case(), iters in 1usize..4, vort in 0.0..0.5f64, xsph in 0.0..0.2f64,
                 vel in proptest::collection::vec([-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], 48)) {
        let mut p = params(&c);
        p.common.substeps = 1;
        p.common.dt = 0.004;
        p.solver_iterations = iters;
        p.vorticity_epsilon = vorticity_scale(vort);
        p.xsph_c = xsph;
        p.common.reorder_every = 0;
        let n = c.points.len();
        let masses: Vec<f64> = c.mass_factors.iter().map(|f| f * p.particle_mass()).collect();
        let v0: Vec<V> = vel[..n].to_vec();
        let r = p.particle_radius();
        // Floor y = 0 (solid below); the cloud starts in y ∈ [0, side·h], some particles
        // within the particle radius of it.
        let floor: Box<dyn Sdf<f64>> =
            Box::new(Plane::new(Vec3::zeros(), Vec3::new(0.0, 1.0, 0.0)).unwrap());
        let mut state = pbf::ParticleSet::new();
        for i in 0..n {
            let (x, v) = (c.points[i], v0[i]);
            state.push(Vec3::new(x[0], x[1], x[2]), Vec3::new(v[0], v[1], v[2]), masses[i], 0.0);
        }
        let mut solver = Pbf::new(p.clone(), vec![floor]).unwrap();
        let result = solver.step(&mut state);

        // Oracle: Algorithm 1.
        let o = Oracle::new(&p);
        let dt = p.common.dt;
        let g = to_v(&p.common.gravity);
        let x0 = c.points.clone();
        let mut xs: Vec<V> = (0..n).map(|i| add(x0[i], scale(add(v0[i], scale(g, dt)), dt))).collect();
        let nb = o.neighbours(&xs);
        for _ in 0..iters {
            let (_, _, dp) = o.lambda_delta(&xs, &masses, &nb);
            xs = (0..n)
                .map(|i| {
                    let mut y = add(xs[i], dp[i]);
                    if y[1] < r {
                        y[1] = r;
                    }
                    y
                })
                .collect();
        }
        let v: Vec<V> = (0..n).map(|i| scale(sub(xs[i], x0[i]), 1.0 / dt)).collect();
        let vol: Vec<f64> = masses.iter().map(|m| m / p.common.rest_density).collect();
        let mut omega = vec![[0.0; 3]; n];
        let mut rho = vec![0.0; n];
        for i in 0..n {
            rho[i] = masses[i] * poly6([0.0; 3], o.h);
            for &j in &nb[i] {
                let rij = sub(xs[i], xs[j]);
                rho[i] += masses[j] * poly6(rij, o.h);
                // Eq. 15: ω_i = Σ_j V_j v_ij × ∇_{p_j} W(p_i − p_j), ∇_{p_j} W = −∇W(r_ij).
                let vij = sub(v[j], v[i]);
                let grad_j = scale(spiky_grad(rij, o.h), -1.0);
                omega[i] = add(omega[i], scale(cross(vij, grad_j), vol[j]));
            }
        }
        let mut v_new = v.clone();
        for i in 0..n {
            let mut eta = [0.0; 3];
            let mut xs_sum = [0.0; 3];
            for &j in &nb[i] {
                let rij = sub(xs[i], xs[j]);
                let dw = norm(omega[j]) - norm(omega[i]);
                eta = add(eta, scale(spiky_grad(rij, o.h), vol[j] * dw));
                xs_sum = add(xs_sum, scale(sub(v[j], v[i]), vol[j] * poly6(rij, o.h)));
            }
            v_new[i] = add(v_new[i], scale(xs_sum, p.xsph_c));
            let le = norm(eta);
            if p.vorticity_epsilon > 0.0 && le > 0.0 {
                // Eq. 16, applied as an acceleration over Δt.
                let n_hat = scale(eta, 1.0 / le);
                v_new[i] = add(v_new[i], scale(cross(n_hat, omega[i]), p.vorticity_epsilon * dt));
            }
        }

        prop_assert!(result.is_ok(), "{:?}", result);
        let x_scale = 10.0 * o.h;
        let v_scale = v.iter().chain(&v_new).fold(1.0f64, |a, w| a.max(norm(*w)));
        for i in 0..n {
            prop_assert!(norm(sub(to_v(&state.positions[i]), xs[i])) <= 1e-9 * x_scale,
                "x {i}: {:?} vs {:?}", state.positions[i], xs[i]);
            prop_assert!(norm(sub(to_v(&state.velocities[i]), v_new[i])) <= 1e-8 * v_scale,
                "v {i}: {:?} vs {:?}", state.velocities[i], v_new[i]);
            prop_assert!(close(state.densities[i], rho[i], 1e-10 * p.common.rest_density));
        }
    }
}

/// Vorticity strengths of up to a few m/s, so that confinement changes velocities visibly.
fn vorticity_scale(x: f64) -> f64 {
    10.0 * x
}

/// A hand-made configuration: two particles at `0.5 h` with no `s_corr` give the textbook
/// two-body λ (symmetric pair, `∇_{p_i} C_i = −∇_{p_j} C_i`).
#[test]
fn two_particles_by_hand() {
    let mut p = PbfParams::<f64>::for_spacing(0.025);
    p.scorr_k = 0.0;
    let h = p.common.support_radius;
    let m = p.particle_mass();
    let pts = vec![Vec3::zeros(), Vec3::new(0.5 * h, 0.0, 0.0)];
    let mut solver = Pbf::new(p.clone(), vec![]).unwrap();
    let ev = solver.evaluate_constraints(&pts, &[m, m]).unwrap();
    // ρ = m (W(0) + W(h/2)), W = 315/(64π h³)(1 − q²)³.
    let w = |q: f64| 315.0 / (64.0 * PI * h.powi(3)) * (1.0 - q * q).powi(3);
    let rho = m * (w(0.0) + w(0.5));
    assert!((ev.density[0] - rho).abs() < 1e-12 * rho);
    // |∇W(h/2)| = 45/(π h⁶)(h/2)², both gradient terms have that length times m/ρ0.
    let g = m / p.common.rest_density * 45.0 / (PI * h.powi(6)) * (0.5 * h).powi(2);
    let lambda = -(rho / p.common.rest_density - 1.0) / (2.0 * g * g + p.cfm_epsilon);
    assert!((ev.lambda[0] - lambda).abs() < 1e-12 * lambda.abs());
    // Δp_0 = (m/ρ0)(λ0 + λ1) ∇W(x0 − x1); ∇W(x0 − x1) points from x0 to x1 (+x), so an
    // under-dense pair (λ > 0) attracts.
    let dp0 = 2.0 * lambda * g;
    assert!((ev.delta_p[0].x - dp0).abs() < 1e-12 * dp0.abs());
    assert!(ev.delta_p[0].y == 0.0 && ev.delta_p[0].z == 0.0);
    assert!(lambda > 0.0, "an under-dense pair attracts");
    assert!(
        (ev.delta_p[0] + ev.delta_p[1]).norm() < 1e-18,
        "momentum-conserving pair"
    );
}

/// Two clusters 50 m apart with h = 0.05 m: the cell-start grid would need 10⁹ cells and
/// refuses; the solver falls back to the hashed grid and still matches the oracle.
#[test]
fn huge_domain_falls_back_to_hashed_grid() {
    let p = PbfParams::<f64>::for_spacing(0.025);
    let m = p.particle_mass();
    let oracle = Oracle::new(&p);
    let mut x: Vec<V> = Vec::new();
    for (k, base) in [[0.0; 3], [50.0, 50.0, 50.0]].into_iter().enumerate() {
        for i in 0..20 {
            let t = i as f64 * 0.77 + k as f64;
            x.push(add(
                base,
                [
                    0.03 * t.sin(),
                    0.03 * (1.3 * t).cos(),
                    0.02 * (0.7 * t).sin(),
                ],
            ));
        }
    }
    let masses = vec![m; x.len()];
    let nb = oracle.neighbours(&x);
    assert!(nb.iter().all(|l| !l.is_empty()));
    let (_, lambda, dp) = oracle.lambda_delta(&x, &masses, &nb);
    let pts: Vec<Vec3<f64>> = x.iter().map(|a| Vec3::new(a[0], a[1], a[2])).collect();
    let mut solver = Pbf::new(p, vec![]).unwrap();
    let ev = solver.evaluate_constraints(&pts, &masses).unwrap();
    let dp_scale = dp.iter().fold(0.0f64, |a, d| a.max(norm(*d)));
    for i in 0..x.len() {
        assert!((ev.lambda[i] - lambda[i]).abs() <= 1e-10 * lambda[i].abs().max(1e-12));
        assert!(norm(sub(to_v(&ev.delta_p[i]), dp[i])) <= 1e-10 * dp_scale);
    }
}
