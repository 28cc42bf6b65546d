//! The two passes of one Jacobi iteration (Algorithm 1 lines 9–13) and their per-pair cache.

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::Kernel;
use sph_solver::pair_lanes::Packed;
use sph_solver::step::MIN_LEN;
use sph_solver::{Boundary, ContactGuard};

use crate::kernels::Consts;
use crate::lanes::{self, LambdaSums, LaneConsts};

/// Per-pair values of one Jacobi iteration, in the CSR order of the neighbour lists:
/// computed by [`lambda_pass`] and reused by [`delta_pass`], which sees the same positions,
/// so that the second pass needs no square root, division or kernel evaluation (measured:
/// this is faster than recomputing `s_corr` from `r²` in the second pass, although it
/// streams a second per-pair array).
#[derive(Debug, Clone, Default)]
pub(crate) struct PairCache<R: Real> {
    /// Spiky gradient factor `f_ij` with `∇W(p_i − p_j) = (p_i − p_j) f_ij` (`dW/dr / r`;
    /// 0 at `r = 0` and at or beyond `h`).
    grad_factor: Vec<R>,
    /// `s_corr` of the pair (eq. 13; 0 when the artificial pressure is off, or with the
    /// lanes the neighbour's mass `m_j`, which the `Δp` lanes read).
    scorr: Vec<R>,
    /// The positions and masses of the pass, packed for the lanes (filled only when they
    /// run); after the `λ` pass `[x, y, z, λ]` for the `Δp` lanes.
    pub(crate) packed: Packed,
    /// The velocities packed `[v, 0]` for the final density and XSPH lanes (filled only
    /// when they run).
    pub(crate) packed_v: Packed,
}

impl<R: Real> PairCache<R> {
    /// Makes room for `pairs` pairs (reallocates only when the capacity is exceeded).
    fn resize(&mut self, pairs: usize) {
        self.grad_factor.resize(pairs, R::zero());
        self.scorr.resize(pairs, R::zero());
    }
}

/// The Spiky gradient factor `dW/dr / r` (see [`PairCache::grad_factor`]); the same
/// arithmetic as `Kernel::gradient`, so that `r * factor` equals `spiky.gradient(&r)`.
#[inline]
fn spiky_factor<R: Real>(c: &Consts<R>, r2: R) -> R {
    let len = r2.sqrt();
    if len > R::zero() && len < c.h {
        c.spiky.derivative(len) / len
    } else {
        R::zero()
    }
}

/// What the particle loops of one pass read.
#[derive(Clone, Copy)]
pub(crate) struct PassInput<'a, R: Real> {
    pub c: &'a Consts<R>,
    pub x: &'a [Vec3<R>],
    pub m: &'a [R],
    pub nb: &'a NeighbourLists,
    /// The boundary when it takes part in the density (volume maps), `None` otherwise, with
    /// the particles it can reach during this step's iterations (see [`near_boundary`]).
    pub volume: Option<(&'a dyn Boundary<R>, &'a [bool])>,
    /// The `f32` lane kernels' constants when they run ([`LaneConsts::new`]).
    pub lanes: Option<LaneConsts>,
}

/// Each particle's distance to the solids at the predicted positions `x` (`clearance`, the
/// bound [`ContactGuard`] carries through the iterations), and which particles a volume
/// boundary can reach during one step's Jacobi iterations: those closer than `1.5 h`.
/// Farther particles have `Ψ = 0` unless an iteration moves them by more than `h/2` (the
/// iterations' corrections are a small fraction of the spacing; a move of `h/2` is a
/// blow-up), so the solve skips their boundary samples (on SPlisHSPlasH's dam break, 85 % of
/// the particles).
pub(crate) fn near_boundary<R: Real>(
    boundary: &dyn Boundary<R>,
    x: &[Vec3<R>],
    h: R,
    clearance: &mut [R],
    near: &mut [bool],
) {
    let reach = h * R::of_f64(1.5);
    near.par_iter_mut()
        .zip(clearance.par_iter_mut())
        .zip(x.par_iter())
        .with_min_len(MIN_LEN)
        .for_each(|((n, c), xi)| {
            *c = boundary.distance(xi);
            *n = *c < reach;
        });
}

/// Per-particle outputs of [`lambda_pass`].
pub(crate) struct LambdaOut<'a, R: Real> {
    pub density: &'a mut [R],
    pub lambda: &'a mut [R],
    /// `∇Ψ_i` of the boundary at `x_i` (zero without a volume boundary).
    pub boundary_grad: &'a mut [Vec3<R>],
}

/// Eqs. 1, 2, 8 and 11: densities and `λ_i` at positions `x`, and the pair cache for
/// [`delta_pass`]. With a volume boundary, `ρ_i += ρ0 Ψ(x_i)` and `∇_{p_i} C_i += ∇Ψ(x_i)`
/// (the boundary is a fixed neighbour without a constraint of its own). Returns the sum of
/// the compressions `max(ρ_i/ρ0 − 1, 0)` (in f64, summed over a split tree that depends only
/// on the particle count, so the result does not depend on the number of threads).
pub(crate) fn lambda_pass<R: Real>(
    input: PassInput<'_, R>,
    out: LambdaOut<'_, R>,
    cache: &mut PairCache<R>,
) -> f64 {
    let pairs = input.nb.pair_count();
    cache.resize(pairs);
    if input.lanes.is_some() {
        cache.packed.fill(input.x, input.m);
    }
    let compression = lambda_block(
        input,
        0,
        LambdaOut {
            density: out.density,
            lambda: &mut *out.lambda,
            boundary_grad: out.boundary_grad,
        },
        &cache.packed,
        (&mut cache.grad_factor[..pairs], &mut cache.scorr[..pairs]),
    );
    if input.lanes.is_some() {
        lanes::pack_lambda(&mut cache.packed, out.lambda);
    }
    compression
}

/// [`lambda_pass`] over the particles `first..first + out.density.len()`, whose pairs are
/// `grad_factor` and `scorr`: split in halves (rayon `join`) down to `MIN_LEN` particles, so
/// that each task owns its particles' contiguous CSR range of the cache. Returns the block's
/// compression sum.
fn lambda_block<R: Real>(
    input: PassInput<'_, R>,
    first: usize,
    out: LambdaOut<'_, R>,
    packed: &Packed,
    (grad_factor, scorr): (&mut [R], &mut [R]),
) -> f64 {
    let n = out.density.len();
    let offsets = input.nb.offsets();
    if n > MIN_LEN {
        let mid = n / 2;
        let split = offsets[first + mid] - offsets[first];
        let (d0, d1) = out.density.split_at_mut(mid);
        let (l0, l1) = out.lambda.split_at_mut(mid);
        let (b0, b1) = out.boundary_grad.split_at_mut(mid);
        let (g0, g1) = grad_factor.split_at_mut(split);
        let (s0, s1) = scorr.split_at_mut(split);
        let (a, b) = rayon::join(
            || {
                let out = LambdaOut {
                    density: d0,
                    lambda: l0,
                    boundary_grad: b0,
                };
                lambda_block(input, first, out, packed, (g0, s0))
            },
            || {
                let out = LambdaOut {
                    density: d1,
                    lambda: l1,
                    boundary_grad: b1,
                };
                lambda_block(input, first + mid, out, packed, (g1, s1))
            },
        );
        return a + b;
    }
    let PassInput {
        c,
        x,
        m,
        nb,
        volume,
        lanes,
    } = input;
    let base = offsets[first];
    let mut compression = R::zero();
    for (k, ((rho, lam), bg)) in out
        .density
        .iter_mut()
        .zip(out.lambda.iter_mut())
        .zip(out.boundary_grad.iter_mut())
        .enumerate()
    {
        let i = first + k;
        let (a, b) = (offsets[i] - base, offsets[i + 1] - base);
        let xi = x[i];
        let (gf, sc) = (&mut grad_factor[a..b], &mut scorr[a..b]);
        let sums = match &lanes {
            Some(l) => lanes::lambda_sums(l, (x, m, packed), nb, i, gf, sc),
            None => lambda_sums(c, x, m, nb, i, gf, sc),
        };
        let mut sum_w = sums.density;
        let mut grad_i = sums.grad;
        let sum_g2 = sums.grad_sq;
        if let Some((bd, near)) = volume {
            if near[i] {
                // ρ_B = ρ0 Ψ; ∇_{p_i} (ρ0 Ψ / ρ0) = ∇Ψ.
                let s = bd.sample(&xi);
                sum_w += c.rho0 * s.volume;
                grad_i += s.volume_gradient;
                *bg = s.volume_gradient;
            } else {
                *bg = Vec3::zeros();
            }
        }
        *rho = sum_w;
        let mut constraint = sum_w * c.inv_rho0 - R::one();
        if constraint > R::zero() {
            compression += constraint;
        } else if c.unilateral {
            constraint = R::zero();
        }
        *lam = -constraint / (sum_g2 + grad_i.norm_squared() + c.eps);
    }
    compression.as_f64()
}

/// The sums of particle `i`'s pairs in the `λ` pass (eqs. 2 and 8, with the density's self
/// term `m_i W(0)` first, without the boundary), writing its pairs' Spiky factors and `s_corr` (its CSR range of the
/// cache): the scalar loop, in list order.
pub(crate) fn lambda_sums<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    i: usize,
    grad_factor: &mut [R],
    scorr: &mut [R],
) -> LambdaSums<R> {
    let xi = x[i];
    let mut sums = LambdaSums {
        density: m[i] * c.w0,
        grad: Vec3::zeros(),
        grad_sq: R::zero(),
    };
    for ((&j, gf), sc) in nb.neighbours(i).iter().zip(grad_factor).zip(scorr) {
        let j = j as usize;
        let r = xi - x[j];
        let r2 = r.norm_squared();
        let w = c.poly6.value_r2(r2);
        sums.density += m[j] * w;
        *sc = if c.scorr_on {
            c.scorr.from_kernel_value(w)
        } else {
            R::zero()
        };
        let f = spiky_factor(c, r2);
        *gf = f;
        // ∇_{p_j} C_i = −(m_j/ρ0) ∇W(p_i − p_j); ∇_{p_i} C_i = Σ_j (m_j/ρ0) ∇W.
        let g = (r * f) * (m[j] * c.inv_rho0);
        sums.grad += g;
        sums.grad_sq += g.norm_squared();
    }
    sums
}

/// The `Δp` pass's pair sum of particle `i`,
/// `Σ_j (λ_i m_j + λ_j m_i + s_corr (m_i + m_j) unit/2) ∇W_ij` (before `1/ρ0`), from the
/// pair cache (`W'(r)/r`, `s_corr`) of its CSR range: the scalar loop, in list order.
#[allow(clippy::too_many_arguments)] // the pass's inputs, one particle
pub(crate) fn delta_sum<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    lambda: &[R],
    nb: &NeighbourLists,
    i: usize,
    (grad_factor, scorr): (&[R], &[R]),
    half_unit: R,
) -> Vec3<R> {
    let (xi, li, mi) = (x[i], lambda[i], m[i]);
    let mut acc = Vec3::zeros();
    for ((&j, &f), &sc) in nb.neighbours(i).iter().zip(grad_factor).zip(scorr) {
        let j = j as usize;
        let r = xi - x[j];
        let mj = m[j];
        // λ_i ∇_{p_i} C_i + λ_j ∇_{p_i} C_j, with ∇_{p_i} C_j = (m_i/ρ0) ∇W(p_i − p_j).
        let mut coeff = li * mj + lambda[j] * mi;
        if c.scorr_on {
            coeff += sc * (mi + mj) * half_unit;
        }
        acc += (r * f) * coeff;
    }
    acc
}

/// Eqs. 13 and 14, then the boundary's contact response: `delta_p` receives `Δp_i` (with
/// the boundary term `λ_i ∇Ψ_i` of a volume boundary), `next` the corrected position
/// `x_i + Δp_i` after [`Boundary::project`]. Reads the pair cache written by
/// [`lambda_pass`] at the same positions. With a guard in `contact`, whose slice holds the
/// particles' distance bounds at `x`, the response is called only where the bound does not
/// prove it a no-op (the same positions; the bounds carried to `next`); without one the
/// slice (one entry per particle) is not read.
#[allow(clippy::too_many_arguments)] // the pass's inputs and outputs
pub(crate) fn delta_pass<R: Real>(
    input: PassInput<'_, R>,
    lambda: &[R],
    boundary_grad: &[Vec3<R>],
    cache: &PairCache<R>,
    boundary: &dyn Boundary<R>,
    contact: (Option<ContactGuard<R>>, &mut [R]),
    delta_p: &mut [Vec3<R>],
    next: &mut [Vec3<R>],
) {
    let PassInput {
        c,
        x,
        m,
        nb,
        volume,
        lanes,
    } = input;
    let half_unit = R::of_f64(0.5) * c.scorr_unit;
    let offsets = nb.offsets();
    let with_volume = volume.is_some();
    let (guard, clearance) = contact;
    assert_eq!(clearance.len(), x.len(), "one distance bound per particle");
    delta_p
        .par_iter_mut()
        .zip(next.par_iter_mut())
        .zip(clearance.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, ((dp, xn), cl))| {
            let (a, b) = (offsets[i], offsets[i + 1]);
            let pair_cache = (&cache.grad_factor[a..b], &cache.scorr[a..b]);
            let acc = match &lanes {
                Some(l) => {
                    lanes::delta_sum(l, (m, &cache.packed), lambda, nb, i, pair_cache, half_unit)
                }
                None => delta_sum(c, x, m, lambda, nb, i, pair_cache, half_unit),
            };
            let mut d = acc * c.inv_rho0;
            if with_volume {
                d += boundary_grad[i] * lambda[i];
            }
            *dp = d;
            *xn = match &guard {
                Some(g) => g.project(boundary, cl, &x[i], x[i] + d),
                None => boundary.project(x[i] + d),
            };
        });
}
