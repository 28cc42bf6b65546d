//! The friction-stress solve of the granular model: the Drucker–Prager-bounded stress that
//! keeps the material rigid (Neder 2024 eqs. 7–14 and 26; solved implicitly as Alduán &
//! Otaduy 2011 intend, see the crate documentation).
//!
//! The stress `s_i` (Pa, symmetric, deviatoric) is a state of the particle: it is kept from
//! one time step to the next (permuted with the particles) and corrected each step until the
//! velocity field it produces has no strain rate where the material is not yielding:
//!
//! 1. [`predict`]: `a^f_i` of the kept stress (the one the last step's solve ended with)
//!    enters the advection velocity, so the pressure solve sees the friction of the last
//!    step;
//! 2. [`solve`], after the pressure solve: `v^base_i = v^adv_i + Δt (a^p_i − a^f_i)` is the
//!    velocity without friction; then, per iteration, the strain rate `ε_i` of `v = v^base +
//!    Δt a^f(s)` (eqs. 7–8, walls no-slip), the update `s_i ← Y_i(dev(s_i − 2ω D⁻¹ ε_i))`
//!    (eqs. 10–14: `Y_i` the radial return to `‖s‖ ≤ α p_i`, `ω` the relaxation), and the new `a^f(s)` (eq. 26
//!    with eq. 31). It stops once the mean unyielded strain per step is below the tolerance.
//!
//! The factor 2 in the prototype `D` (eq. 9) makes `s ← s − D⁻¹ε` a Jacobi step relaxed by
//! ½ on the exact self-coupling `Δε_i = (D/2) Δs_i` (see [`crate::granular`]); the update
//! here is relaxed by `ω` ([`crate::GranularParams::friction_relaxation`], default 0.35),
//! the stability bound `ω < 2/λ_max = 0.355` of the prototype lattice's symbol (the crate
//! docs derive it; the test below recomputes it): at ½ mid-wavelength modes grow until
//! the yield cone clips them, and the residual stalls.

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_solver::step::{par_update_sum, MIN_LEN};

use crate::granular::{deviatoric, frobenius, strain_rate, sym_mul, yield_clamp, Sym3};
use crate::kernels::Consts;
use crate::passes::{grad, pressure_accel};
use crate::scratch::Scratch;

/// How a friction solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FrictionOutcome {
    /// Iterations done (≥ 1 for a non-empty set).
    pub iterations: usize,
    /// Mean unyielded strain per step `Σ_i ‖dev ε_i‖ Δt / N` of the last iteration.
    pub residual: f64,
    /// Whether `residual` met the tolerance.
    pub converged: bool,
}

/// The friction acceleration `F^f_i/m_i = −Σ_j m_j (s_i/ρ_i² + s_j/ρ_j²) ∇W_ij − ρ0
/// (s_i/ρ_i²) ∇Ψ_i` (Neder 2024 eqs. 26 and 31), evaluated as `−(s_i/ρ_i²) G_i − Σ_j
/// (m_j s_j/ρ_j²) ∇W_ij` from `q_j = m_j s_j/ρ_j²` and the step's `G_i = Σ_j m_j ∇W_ij +
/// ρ0 ∇Ψ_i` (the density pass's `grad_sum`): one symmetric product per pair.
#[inline]
#[allow(clippy::too_many_arguments)]
fn friction_accel<R: Real>(
    x: &[Vec3<R>],
    m: &[R],
    offsets: &[usize],
    indices: &[u32],
    gs: &[R],
    q: &[Sym3<R>],
    grad_sum: &[Vec3<R>],
    i: usize,
) -> Vec3<R> {
    let xi = x[i];
    let mut f = Vec3::zeros();
    for k in offsets[i]..offsets[i + 1] {
        let j = indices[k] as usize;
        f += sym_mul(&q[j], &grad(&xi, &x[j], gs[k]));
    }
    let inv_mi = R::one() / m[i];
    -(f + sym_mul(&q[i], &grad_sum[i]) * inv_mi)
}

/// The strain rate `ε_i` (eqs. 7–8) of the velocity field `v`: `∇u_i = Σ_j V_j (u_j − u_i)
/// ⊗ ∇W_ij − u_i ⊗ ∇Ψ_i` (`V_j = m_j/ρ_j`, given in `vol`; the static walls' share
/// `Σ_b V_b (0 − u_i) ⊗ ∇W_ib` makes them no-slip, as the friction force of eq. 31 treats
/// them).
#[inline]
#[allow(clippy::too_many_arguments)]
fn strain_rate_at<R: Real>(
    x: &[Vec3<R>],
    v: &[Vec3<R>],
    vol: &[R],
    offsets: &[usize],
    indices: &[u32],
    gs: &[R],
    bgrad: &[Vec3<R>],
    i: usize,
) -> Sym3<R> {
    let (xi, vi) = (x[i], v[i]);
    let mut g = [[R::zero(); 3]; 3];
    for k in offsets[i]..offsets[i + 1] {
        let j = indices[k] as usize;
        let gw = grad(&xi, &x[j], gs[k]);
        let du = (v[j] - vi) * vol[j];
        for a in 0..3 {
            for b in 0..3 {
                g[a][b] += du[a] * gw[b];
            }
        }
    }
    let bg = bgrad[i];
    for a in 0..3 {
        for b in 0..3 {
            g[a][b] -= vi[a] * bg[b];
        }
    }
    strain_rate(&g)
}

/// `out_i = m_i s_i / ρ_i²` for the densities of the step.
fn weight_stress<R: Real>(stress: &[Sym3<R>], m: &[R], rho: &[R], out: &mut [Sym3<R>]) {
    out.par_iter_mut()
        .zip(stress.par_iter())
        .zip(m.par_iter().zip(rho.par_iter()))
        .with_min_len(MIN_LEN)
        .for_each(|((o, s), (&mi, &r))| {
            let w = mi / (r * r);
            *o = s.map(|e| e * w);
        });
}

/// `friction_accel = a^f(s)` of the current stress (`mass_stress_over_rho2`).
fn accelerations<R: Real>(x: &[Vec3<R>], m: &[R], nb: &NeighbourLists, s: &mut Scratch<R>) {
    let (offsets, indices) = (nb.offsets(), nb.indices());
    let (gs, q, gsum) = (
        &s.grad_scale[..],
        &s.mass_stress_over_rho2[..],
        &s.grad_sum[..],
    );
    s.friction_accel
        .par_iter_mut()
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, a)| *a = friction_accel(x, m, offsets, indices, gs, q, gsum, i));
}

/// `friction_accel = a^f(s)` of the current stress and, in the same pass, the trial
/// velocities `v_trial = v^base + Δt a^f(s)`.
fn accelerations_and_velocities<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) {
    let (offsets, indices) = (nb.offsets(), nb.indices());
    let (gs, q, gsum, vb) = (
        &s.grad_scale[..],
        &s.mass_stress_over_rho2[..],
        &s.grad_sum[..],
        &s.v_base[..],
    );
    let dt = c.dt;
    s.friction_accel
        .par_iter_mut()
        .zip(s.v_trial.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (a, vt))| {
            *a = friction_accel(x, m, offsets, indices, gs, q, gsum, i);
            *vt = vb[i] + *a * dt;
        });
}

/// Step 1: `a^f` of the kept stress, added to the advection velocity `v^adv`. Expects the
/// densities of the step. `a^f` is the one the last step's solve ended with (carried with
/// the stress, at the last step's positions and densities), unless `s.friction_accel_current`
/// is false (a restored state without it), when it is computed afresh at this step's
/// positions. The approximation moves only the friction the pressure solve sees: [`solve`]
/// subtracts the same `a^f` again for `v^base` and recomputes the friction of its stress.
pub(crate) fn predict<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) {
    if !s.friction_accel_current {
        weight_stress(&s.stress, m, &s.density, &mut s.mass_stress_over_rho2);
        accelerations(x, m, nb, s);
        s.friction_accel_current = true;
    }
    let dt = c.dt;
    s.v_adv
        .par_iter_mut()
        .zip(s.friction_accel.par_iter())
        .with_min_len(MIN_LEN)
        .for_each(|(v, a)| *v += a * dt);
}

/// Step 2, after the pressure solve (`p/ρ²` final): iterates the stress to the tolerance
/// and leaves the final velocity `v^base + Δt a^f(s)` in `v_trial`.
pub(crate) fn solve<R: Real>(
    c: &Consts<R>,
    max_iterations: usize,
    tolerance: f64,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) -> FrictionOutcome {
    let n = x.len();
    let (offsets, indices) = (nb.offsets(), nb.indices());
    let dt = c.dt;
    // v^base = v^adv + Δt (a^p − a^f_prev); the trial velocity of the kept stress is
    // v^adv + Δt a^p; the volumes V_i = m_i/ρ_i of the strain rate.
    {
        let (gs, pi, bgrad, va, af, rho) = (
            &s.grad_scale[..],
            &s.p_over_rho2[..],
            &s.bgrad[..],
            &s.v_adv[..],
            &s.friction_accel[..],
            &s.density[..],
        );
        s.v_base
            .par_iter_mut()
            .zip(s.v_trial.par_iter_mut())
            .zip(s.volume.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, ((vb, vt), vol))| {
                let ap = pressure_accel(c, x, m, offsets, indices, gs, pi, bgrad, i);
                *vt = va[i] + ap * dt;
                *vb = *vt - af[i] * dt;
                *vol = m[i] / rho[i];
            });
    }
    let mut outcome = FrictionOutcome {
        iterations: 0,
        residual: 0.0,
        converged: true,
    };
    if n == 0 {
        return outcome;
    }
    let inv_d = c.stress_step;
    for k in 0..max_iterations {
        // The strain rate of the trial velocities and the stress update.
        {
            let (gs, bgrad, rho, pr, vt, vol) = (
                &s.grad_scale[..],
                &s.bgrad[..],
                &s.density[..],
                &s.pressure[..],
                &s.v_trial[..],
                &s.volume[..],
            );
            let update = |i: usize, st: &mut Sym3<R>, so: &mut Sym3<R>| -> f64 {
                let eps = deviatoric(&strain_rate_at(x, vt, vol, offsets, indices, gs, bgrad, i));
                let trial: Sym3<R> = std::array::from_fn(|e| st[e] - eps[e] * inv_d);
                let bound = c.alpha * pr[i];
                *st = yield_clamp(&trial, c.alpha, pr[i]);
                let w = m[i] / (rho[i] * rho[i]);
                *so = st.map(|e| e * w);
                // Strain counts as residual where the material should be rigid: inside the
                // yield surface (a yielding particle flows).
                if bound > R::zero() && frobenius(&trial) <= bound {
                    (frobenius(&eps) * dt).as_f64()
                } else {
                    0.0
                }
            };
            let total = par_update_sum(
                &mut s.stress,
                &mut s.mass_stress_over_rho2,
                &mut s.error_partials,
                update,
            );
            outcome.residual = total / n as f64;
        }
        outcome.iterations = k + 1;
        // a^f of the new stress and the velocities it gives.
        accelerations_and_velocities(c, x, m, nb, s);
        if outcome.residual <= tolerance {
            return outcome;
        }
    }
    outcome.converged = false;
    outcome
}

#[cfg(test)]
mod tests {
    use crate::params::DEFAULT_FRICTION_RELAXATION;
    use sph_core::Vec3;
    use sph_kernels::{CubicSpline, Kernel};

    /// The lattice offsets `r` within the support and their `∇W(r)` (cubic spline,
    /// `h = 2 s`, `s = 1`).
    fn lattice() -> Vec<(Vec3<f64>, Vec3<f64>)> {
        let k = CubicSpline::new(2.0).unwrap();
        let mut out = Vec::new();
        for a in -2i32..=2 {
            for b in -2i32..=2 {
                for c in -2i32..=2 {
                    let r = Vec3::new(a as f64, b as f64, c as f64);
                    let g = k.gradient(&r);
                    if g.norm() > 0.0 {
                        out.push((r, g));
                    }
                }
            }
        }
        out
    }

    /// `|g(k)|²` with `g(k) = Σ_r sin(k·r) ∇W(r)`.
    fn g2(l: &[(Vec3<f64>, Vec3<f64>)], k: Vec3<f64>) -> f64 {
        let g: Vec3<f64> = l.iter().map(|(r, gw)| gw * k.dot(r).sin()).sum();
        g.norm_squared()
    }

    /// The stability bound of `DEFAULT_FRICTION_RELAXATION`. On a full lattice with uniform
    /// density the map from a stress wave `S e^{ik·x}` to the strain rate it causes is
    /// `c sym(S g gᵀ)` (`c = V Δt m/ρ0²`): eigenvalues `(2/3) c |g|²` (the deviatoric mode
    /// along `g`), `c |g|²/2` (two shear modes), 0 (two). The diagonal is `c Σ_r |∇W(r)|²/3`;
    /// the mean of the five eigenvalues over the Brillouin zone must equal it (Parseval: a
    /// check of the symbol), and `2/λ_max` of the symbol relative to the diagonal bounds a
    /// stable Jacobi relaxation. The default must lie inside the bound and within 2 % of it
    /// (the optimal Jacobi `ω = 2/(λ_min + λ_max)` with `λ_min → 0` for smooth modes).
    #[test]
    fn friction_symbol_bound() {
        let l = lattice();
        let diag: f64 = l.iter().map(|(_, g)| g.norm_squared()).sum::<f64>() / 3.0;
        // Parseval on an 8³ grid of the zone (exact for offsets of at most 2 spacings).
        let n = 8;
        let mut mean = 0.0;
        for a in 0..n {
            for b in 0..n {
                for c in 0..n {
                    let step = 2.0 * std::f64::consts::PI / n as f64;
                    let k = Vec3::new(a as f64, b as f64, c as f64) * step;
                    mean += (2.0 / 3.0 + 0.5 + 0.5) * g2(&l, k) / 5.0;
                }
            }
        }
        mean /= (n * n * n) as f64;
        assert!((mean / diag - 1.0).abs() < 1e-12, "{mean} vs {diag}");
        // The maximum over a fine grid of the zone (the symbol is even in each axis).
        let m = 60;
        let mut max = 0.0f64;
        for a in 0..=m {
            for b in 0..=a {
                for c in 0..=b {
                    let k =
                        Vec3::new(a as f64, b as f64, c as f64) * (std::f64::consts::PI / m as f64);
                    max = max.max(2.0 / 3.0 * g2(&l, k) / diag);
                }
            }
        }
        let bound = 2.0 / max;
        assert!((max - 5.64).abs() < 0.01, "lambda_max {max}");
        assert!(
            DEFAULT_FRICTION_RELAXATION < bound && DEFAULT_FRICTION_RELAXATION > 0.98 * bound,
            "{DEFAULT_FRICTION_RELAXATION} against the bound {bound}"
        );
    }
}
