//! The per-particle passes of one IISPH time step (Algorithm 1 of Ihmsen et al. 2014 with
//! the boundary terms of Neder 2024): densities and `a_ii`, advection, predicted density,
//! the relaxed Jacobi pressure solve, forces and integration.

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::Kernel;
use sph_solver::csr::par_csr_blocks;
use sph_solver::pair_lanes::{CubicLanes, Packed};
use sph_solver::step::{par_update_sum, MIN_LEN};
use sph_solver::Boundary;

use crate::granular::{drag_force, occlusion_of_cosine};
use crate::kernels::Consts;
use crate::lanes::PressureLanes;
use crate::params::IisphParams;
use crate::scratch::Scratch;

/// `∇W_ij` from the cached `W'(r)/r` of the pair.
#[inline(always)]
pub(crate) fn grad<R: Real>(xi: &Vec3<R>, xj: &Vec3<R>, f: R) -> Vec3<R> {
    (xi - xj) * f
}

/// The packed arrays of the pressure passes' lanes ([`PressureLanes`]) and the gradient
/// sums they need.
#[derive(Clone, Copy)]
pub(crate) struct Packs<'a, R: Real> {
    /// `[x, y, z, m π]` of the current pressure iterate.
    pub xp: &'a Packed,
    /// `G_i = Σ_j m_j ∇W_ij` (the density pass's, without the boundary's term).
    pub mass_grad: &'a [Vec3<R>],
}

/// What the pressure passes read of a step: the positions, masses and lists, the per-pair
/// `W'(r)/r` of [`density_pass`], and the pressure lanes with their packed arrays where
/// they run (the scalar loops otherwise).
#[derive(Clone, Copy)]
pub(crate) struct Step<'a, R: Real> {
    pub x: &'a [Vec3<R>],
    pub m: &'a [R],
    pub nb: &'a NeighbourLists,
    pub gs: &'a [R],
    pub lanes: Option<(PressureLanes, Packs<'a, R>)>,
}

impl<'a, R: Real> Step<'a, R> {
    /// The step's inputs, with the lanes where they run on `packs` (filled for these
    /// positions, or empty).
    pub(crate) fn new(
        x: &'a [Vec3<R>],
        m: &'a [R],
        nb: &'a NeighbourLists,
        gs: &'a [R],
        packs: Packs<'a, R>,
    ) -> Self {
        let lanes = PressureLanes::new::<R>(x.len(), nb, &[packs.xp])
            .filter(|_| packs.mass_grad.len() == x.len())
            .map(|l| (l, packs));
        Self {
            x,
            m,
            nb,
            gs,
            lanes,
        }
    }

    /// Particle `i`'s slice of the per-pair `W'(r)/r`.
    #[inline]
    fn gs_of(&self, i: usize) -> &'a [R] {
        let o = self.nb.offsets();
        &self.gs[o[i]..o[i + 1]]
    }

    /// [`pressure_accel`] of particle `i`.
    #[inline]
    pub(crate) fn pressure_accel(
        &self,
        c: &Consts<R>,
        pi: &[R],
        bgrad: &[Vec3<R>],
        i: usize,
    ) -> Vec3<R> {
        match self.lanes {
            Some((l, p)) => {
                let own = (pi[i], p.mass_grad[i]);
                l.pressure_sum(p.xp, self.nb, self.gs_of(i), own, i) - bgrad[i] * (c.rho0 * pi[i])
            }
            None => {
                let (o, k) = (self.nb.offsets(), self.nb.indices());
                pressure_accel(c, self.x, self.m, o, k, self.gs, pi, bgrad, i)
            }
        }
    }

    /// [`a_times_p`] of particle `i`; `am` holds the packed `[a, m]` where the lanes run
    /// ([`pack_vectors`]).
    #[inline]
    pub(crate) fn a_times_p(
        &self,
        c: &Consts<R>,
        (a, am): (&[Vec3<R>], &Packed),
        bgrad: &[Vec3<R>],
        i: usize,
    ) -> R {
        match self.lanes {
            Some((l, p)) => {
                let sum =
                    l.a_dot((p.xp, am), self.nb, self.gs_of(i), i) + c.rho0 * a[i].dot(&bgrad[i]);
                c.dt * c.dt * sum
            }
            None => {
                let (o, k) = (self.nb.offsets(), self.nb.indices());
                a_times_p(c, self.x, self.m, o, k, self.gs, a, bgrad, i)
            }
        }
    }
}

/// Packs 3-vectors `a` (`v^adv` for the predicted density, the pressure accelerations for
/// `A p`) with the masses for the lanes (`[a, m]`), where they run.
pub(crate) fn pack_vectors<R: Real>(m: &[R], nb: &NeighbourLists, a: &[Vec3<R>], am: &mut Packed) {
    if PressureLanes::available::<R>(m.len(), nb) {
        am.fill_with(a, |i| m[i]);
    } else {
        am.clear();
    }
}

/// Packs `m_i π_i` of the current `π = p/ρ²` for the pressure lanes, in place of the masses
/// of the step's `[x, y, z, m]` (filled by [`density_pass`], which the pressure passes no
/// longer read): `[x, y, z, m π]`, where the lanes run.
pub(crate) fn pack_pressure<R: Real>(m: &[R], nb: &NeighbourLists, s: &mut Scratch<R>) {
    if PressureLanes::available::<R>(m.len(), nb) && s.packed.len() == m.len() {
        let pi = &s.p_over_rho2[..];
        s.packed.set_fourth(|i| m[i] * pi[i]);
    } else {
        s.packed.clear();
    }
}

/// A block's outputs of [`density_pass`]: `(ρ, ∇Ψ, G)` and `(a_ii, occlusion)`.
type DensityOutputs<'a, R> = (
    (&'a mut [R], &'a mut [Vec3<R>], &'a mut [Vec3<R>]),
    (&'a mut [R], &'a mut [R], &'a mut [Vec3<R>]),
);

/// Eq. 3 + eq. 29: `ρ_i`, `∇Ψ_i`, `W'(r)/r` of every pair, and the diagonal `a_ii` of
/// eq. 24 (it needs only `x`, `m` and the particle's own density) with its gradient sum
/// `G_i = Σ_j m_j ∇W_ij + ρ0 ∇Ψ_i` (kept for the friction acceleration):
/// `a_ii = Σ_j m_j (d_ii − d_ji)·∇W_ij + ρ0 d_ii·∇Ψ_i
///       = −Δt²/ρ_i² (|Σ_j m_j ∇W_ij + ρ0 ∇Ψ_i|² + m_i Σ_j m_j |∇W_ij|²)`.
/// With drag, the same loop also takes the occlusion `max_j o_ij` of eq. 6 (it needs the
/// pair's offset and distance, which the density computes anyway) into `s.occlusion`, as
/// the occlusion of the largest `cos φ` ([`occlusion_of_cosine`]: one division per pair).
#[allow(clippy::needless_range_loop)] // k addresses the CSR pair arrays (indices, scales)
pub(crate) fn density_pass<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    v: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    volume: Option<&dyn Boundary<R>>,
    s: &mut Scratch<R>,
) {
    let offsets = nb.offsets();
    let indices = nb.indices();
    s.grad_scale.resize(indices.len(), R::zero());
    let dt2 = c.dt * c.dt;
    // The f32 lanes where they run (the packed positions also for the pressure passes'
    // lanes, `Step::lanes`); drag needs the occlusion, which only the scalar loop takes.
    let lanes = CubicLanes::new(&c.kernel, x.len(), nb);
    if lanes.is_some() {
        s.packed.fill(x, m);
    } else {
        s.packed.clear();
    }
    let lanes = lanes.filter(|_| !c.drag);
    let (packed, cached) = (&s.packed, &s.end_samples);
    let outputs = (
        (&mut s.density[..], &mut s.bgrad[..], &mut s.grad_sum[..]),
        (&mut s.aii[..], &mut s.occlusion[..], &mut s.mass_grad[..]),
    );
    par_csr_blocks(
        offsets,
        outputs,
        &mut s.grad_scale[..],
        &|first,
          ((rho_b, bg_b, gsum_b), (aii_b, occ_b, mg_b)): DensityOutputs<'_, R>,
          gs: &mut [R]| {
            let base = offsets[first];
            let block = rho_b
                .iter_mut()
                .zip(bg_b.iter_mut().zip(gsum_b.iter_mut()))
                .zip(aii_b.iter_mut().zip(occ_b.iter_mut()).zip(mg_b.iter_mut()));
            for (l, ((rho, (bg, gsum)), ((aii, occ_out), mass_grad))) in block.enumerate() {
                let i = first + l;
                let (xi, mi) = (x[i], m[i]);
                let upstream = if c.drag {
                    upstream(c, &v[i])
                } else {
                    Vec3::zeros()
                };
                let mut max_cos = c.cos_cone;
                let (mut sum, sum_grad, sum_grad_sq) = match &lanes {
                    Some(l) => {
                        let (a, b) = (offsets[i] - base, offsets[i + 1] - base);
                        let s = l.density_gradient(packed, nb, i, &mut gs[a..b]);
                        (s.density, s.grad, s.grad_sq)
                    }
                    None => {
                        let mut sum = mi * c.w0;
                        let mut sum_grad = Vec3::zeros();
                        let mut sum_grad_sq = R::zero();
                        for k in offsets[i]..offsets[i + 1] {
                            let j = indices[k] as usize;
                            let d = xi - x[j];
                            let r = d.norm();
                            sum += m[j] * c.kernel.value(r);
                            let f = if r > R::zero() {
                                c.kernel.derivative(r) / r
                            } else {
                                R::zero()
                            };
                            gs[k - base] = f;
                            let gw = d * f;
                            sum_grad += gw * m[j];
                            sum_grad_sq += m[j] * gw.norm_squared();
                            if c.drag && r > R::zero() {
                                // cos φ of x_j − x_i against the upstream direction (the
                                // distance is the density's).
                                max_cos = max_cos.max(upstream.dot(&(-d)) / r);
                            }
                        }
                        (sum, sum_grad, sum_grad_sq)
                    }
                };
                *occ_out = occlusion_of_cosine(max_cos, c.cos_cone);
                if let Some(b) = volume {
                    let smp = cached.get(i, &xi).unwrap_or_else(|| b.sample(&xi));
                    sum += c.rho0 * smp.volume;
                    *bg = smp.volume_gradient;
                } else {
                    *bg = Vec3::zeros();
                }
                *rho = sum;
                *mass_grad = sum_grad;
                let gi = sum_grad + *bg * c.rho0;
                *gsum = gi;
                *aii = -dt2 / (sum * sum) * (gi.norm_squared() + mi * sum_grad_sq);
            }
            0.0
        },
    );
}

/// The direction the air comes from at a particle of velocity `v` (`−(v_a − v)/|v_a − v|`,
/// 0 in still air relative to the particle).
#[inline]
fn upstream<R: Real>(c: &Consts<R>, v: &Vec3<R>) -> Vec3<R> {
    let rel = c.air_velocity - v;
    let len = rel.norm();
    if len > R::zero() {
        -rel / len
    } else {
        Vec3::zeros()
    }
}

/// Eqs. 5–6 and 17–18: drag (with the occlusion of [`density_pass`]), viscosity, `v^adv`;
/// the warm start `p⁰ = p(t − Δt) / 2` and its `p/ρ²`.
pub(crate) fn advection_pass<R: Real>(
    c: &Consts<R>,
    g: Vec3<R>,
    x: &[Vec3<R>],
    v: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) {
    let offsets = nb.offsets();
    let indices = nb.indices();
    let (rho, gs, occlusion) = (&s.density[..], &s.grad_scale[..], &s.occlusion[..]);
    let half = R::of_f64(0.5);
    let eps_h2 = R::of_f64(0.01) * c.h * c.h;
    // The body for particle i: writes v^adv, the warm start and p/ρ².
    let body = |i: usize, va: &mut Vec3<R>, pr: &mut R, pi: &mut R| {
        let (xi, vi, mi, rhoi) = (x[i], v[i], m[i], rho[i]);
        *pr *= half;
        *pi = *pr / (rhoi * rhoi);
        let mut acc = g;
        if c.visc > R::zero() {
            let mut visc = Vec3::zeros();
            for k in offsets[i]..offsets[i + 1] {
                let j = indices[k] as usize;
                let xj = x[j];
                let gw = grad(&xi, &xj, gs[k]);
                let vol_j = m[j] / rho[j];
                let xij = xi - xj;
                visc += gw * (vol_j * (vi - v[j]).dot(&xij) / (xij.norm_squared() + eps_h2));
            }
            acc += visc * c.visc;
        }
        if c.drag {
            let f = drag_force(
                c.air_velocity - vi,
                c.air_density,
                c.drag_coefficient,
                c.area,
                R::one() - occlusion[i],
            );
            acc += f / mi;
        }
        *va = vi + acc * c.dt;
    };
    s.v_adv
        .par_iter_mut()
        .zip(s.pressure.par_iter_mut())
        .zip(s.p_over_rho2.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, ((va, pr), pi))| body(i, va, pr, pi));
}

/// Eq. 19 (with the boundary term): the source `ρ0 − ρ_i^adv`; fused with the pressure
/// accelerations of the warm start `p⁰` (the first half of the first Jacobi iteration,
/// which reads the same neighbour data).
pub(crate) fn predicted_density_pass<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) {
    pack_pressure(m, nb, s);
    pack_vectors(m, nb, &s.v_adv, &mut s.packed_vectors);
    let offsets = nb.offsets();
    let indices = nb.indices();
    let (rho, gs, bgrad, va, pi) = (
        &s.density[..],
        &s.grad_scale[..],
        &s.bgrad[..],
        &s.v_adv[..],
        &s.p_over_rho2[..],
    );
    let packs = Packs {
        xp: &s.packed,
        mass_grad: &s.mass_grad,
    };
    let step = Step::new(x, m, nb, gs, packs);
    let vm = &s.packed_vectors;
    let lanes = step.lanes.filter(|_| vm.len() == x.len());
    s.source
        .par_iter_mut()
        .zip(s.accel.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (src, acc))| {
            let (xi, vai, p_i) = (x[i], va[i], pi[i]);
            let (mut div, a) = match lanes {
                Some((l, p)) => {
                    let own = (p_i, p.mass_grad[i]);
                    l.divergence_pressure_sum((p.xp, vm), nb, step.gs_of(i), own, i)
                }
                None => {
                    let mut div = R::zero();
                    let mut a = Vec3::zeros();
                    for k in offsets[i]..offsets[i + 1] {
                        let j = indices[k] as usize;
                        let gw = grad(&xi, &x[j], gs[k]);
                        div += m[j] * (vai - va[j]).dot(&gw);
                        a -= gw * (m[j] * (p_i + pi[j]));
                    }
                    (div, a)
                }
            };
            div += c.rho0 * vai.dot(&bgrad[i]);
            let rho_adv = rho[i] + c.dt * div;
            *src = c.rho0 - rho_adv;
            *acc = a - bgrad[i] * (c.rho0 * p_i);
        });
}

/// The pressure acceleration `F^p_i/m_i = −Σ_j m_j (p_i/ρ_i² + p_j/ρ_j²) ∇W_ij − ρ0 (p_i/ρ_i²)
/// ∇Ψ_i` (eqs. 25 and 31) from `p/ρ²`.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn pressure_accel<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    offsets: &[usize],
    indices: &[u32],
    gs: &[R],
    pi: &[R],
    bgrad: &[Vec3<R>],
    i: usize,
) -> Vec3<R> {
    let (xi, p_i) = (x[i], pi[i]);
    let mut a = Vec3::zeros();
    for k in offsets[i]..offsets[i + 1] {
        let j = indices[k] as usize;
        a -= grad(&xi, &x[j], gs[k]) * (m[j] * (p_i + pi[j]));
    }
    a - bgrad[i] * (c.rho0 * p_i)
}

/// `(A p)_i = Δt² (Σ_j m_j (a_i − a_j)·∇W_ij + ρ0 a_i·∇Ψ_i)` from the pressure accelerations
/// `a` of `p`: the predicted density change due to pressure, `ρ_i^{l} − ρ_i^adv`, i.e. the
/// left side of Ihmsen et al.'s eq. 12 / Neder 2024 eqs. 20–23 (`a_ii p_i + ψ_i`).
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn a_times_p<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    offsets: &[usize],
    indices: &[u32],
    gs: &[R],
    a: &[Vec3<R>],
    bgrad: &[Vec3<R>],
    i: usize,
) -> R {
    let (xi, ai) = (x[i], a[i]);
    let mut sum = R::zero();
    for k in offsets[i]..offsets[i + 1] {
        let j = indices[k] as usize;
        sum += m[j] * (ai - a[j]).dot(&grad(&xi, &x[j], gs[k]));
    }
    sum += c.rho0 * ai.dot(&bgrad[i]);
    c.dt * c.dt * sum
}

/// Relaxed Jacobi (Ihmsen et al. 2014 eq. 14, Neder 2024 eq. 20) with the unilateral
/// projection `p ≥ 0` (eq. 4): at least `min_iterations`, then until the average predicted
/// compression is below `η`, at most `max_iterations`. Expects `accel` to hold the pressure
/// accelerations of the starting pressures. Returns `(iterations, last average error,
/// converged)`.
pub(crate) fn pressure_solve<R: Real>(
    c: &Consts<R>,
    p: &IisphParams<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) -> (usize, f64, bool) {
    let n = x.len();
    if n == 0 {
        return (0, 0.0, true);
    }
    let omega = p.relaxation;
    let eta = p.density_error_tolerance.as_f64();
    let inv_rho0 = 1.0 / c.rho0.as_f64();
    let mut error = 0.0;
    pack_pressure(m, nb, s);
    for l in 0..p.max_iterations {
        // Pressure accelerations of the iterate p^l (for l = 0 computed by
        // `predicted_density_pass`).
        let packs = Packs {
            xp: &s.packed,
            mass_grad: &s.mass_grad,
        };
        let step = Step::new(x, m, nb, &s.grad_scale, packs);
        if l > 0 {
            let (pi, bgrad) = (&s.p_over_rho2[..], &s.bgrad[..]);
            s.accel
                .par_iter_mut()
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, a)| *a = step.pressure_accel(c, pi, bgrad, i));
        }
        pack_vectors(m, nb, &s.accel, &mut s.packed_vectors);
        // A p^l, the density error of p^l, and the update p^{l+1}.
        {
            let (acc, am, bgrad, src, aii, rho) = (
                &s.accel[..],
                &s.packed_vectors,
                &s.bgrad[..],
                &s.source[..],
                &s.aii[..],
                &s.density[..],
            );
            let update = |i: usize, pr: &mut R, pi: &mut R| -> f64 {
                let ap = step.a_times_p(c, (acc, am), bgrad, i);
                let a = aii[i];
                let next = if a < R::zero() {
                    let q = *pr + omega * (src[i] - ap) / a;
                    if q > R::zero() {
                        q
                    } else {
                        R::zero()
                    }
                } else {
                    R::zero()
                };
                *pr = next;
                *pi = next / (rho[i] * rho[i]);
                // ρ_i^l − ρ0 = (A p)_i − (ρ0 − ρ_i^adv), counted where positive.
                (ap - src[i]).as_f64().max(0.0)
            };
            let total = par_update_sum(
                &mut s.pressure,
                &mut s.p_over_rho2,
                &mut s.error_partials,
                update,
            );
            error = total / n as f64 * inv_rho0;
        }
        pack_pressure(m, nb, s);
        if l + 1 >= p.min_iterations && error <= eta {
            return (l + 1, error, true);
        }
    }
    (p.max_iterations, error, false)
}

/// Line 14 (pressure and friction forces, eqs. 25–26 and 30–31) and line 15 (symplectic
/// Euler, eqs. 27–28), with the boundary's contact response on the new positions. A
/// granular step takes the velocity the friction solve left in `v_trial` (which holds both
/// forces); water adds the pressure acceleration to `v^adv`.
pub(crate) fn forces_pass<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    boundary: &dyn Boundary<R>,
    s: &mut Scratch<R>,
) {
    let packs = Packs {
        xp: &s.packed,
        mass_grad: &s.mass_grad,
    };
    let step = Step::new(x, m, nb, &s.grad_scale, packs);
    let (pi, bgrad, va, vt) = (
        &s.p_over_rho2[..],
        &s.bgrad[..],
        &s.v_adv[..],
        &s.v_trial[..],
    );
    let inv_dt = R::one() / c.dt;
    let guard = boundary.contact_guard();
    let cache = &s.end_samples;
    s.x_new
        .par_iter_mut()
        .zip(s.v_new.par_iter_mut())
        .zip(s.clearance.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, ((xn, vn), cl))| {
            let v_new = if c.granular {
                vt[i]
            } else {
                va[i] + step.pressure_accel(c, pi, bgrad, i) * c.dt
            };
            let y = x[i] + v_new * c.dt;
            let projected = match &guard {
                // From the distance at `x_i` (the last step's, or evaluated here): the
                // solids are evaluated at `y` only where the move may reach them.
                Some(g) => {
                    *cl = cache
                        .distance(i, &x[i])
                        .unwrap_or_else(|| boundary.distance(&x[i]));
                    g.project(boundary, cl, &x[i], y)
                }
                None => boundary.project(y),
            };
            let push = projected - y;
            let mut v_out = v_new + push * inv_dt;
            if c.granular {
                v_out = coulomb_contact(v_out, push * inv_dt, c.wall_friction);
            }
            *vn = v_out;
            *xn = projected;
        });
}

/// Coulomb friction of the contact response (granular only): a particle the boundary pushed
/// out with the velocity change `dv_n` (along the wall normal) loses up to `μ |dv_n|` of
/// its tangential velocity, `μ = tan θ`. It acts only where the contact safety net acts
/// (particles the volume map's pressure did not hold off the wall, which have no
/// confining pressure and so no Drucker–Prager friction).
#[inline]
fn coulomb_contact<R: Real>(v: Vec3<R>, dv_n: Vec3<R>, mu: R) -> Vec3<R> {
    let push = dv_n.norm();
    if push <= R::zero() || mu <= R::zero() {
        return v;
    }
    let n = dv_n / push;
    let vn = n * v.dot(&n);
    let vt = v - vn;
    let speed_t = vt.norm();
    let loss = mu * push;
    if speed_t <= loss {
        vn
    } else {
        vn + vt * ((speed_t - loss) / speed_t)
    }
}

#[cfg(test)]
mod tests {
    use super::coulomb_contact;
    use sph_core::Vec3;

    /// Coulomb's law at a contact: the tangential speed drops by `μ |Δv_n|` (to zero at
    /// most), the normal velocity is kept, and without a push nothing changes.
    #[test]
    fn coulomb_contact_follows_coulombs_law() {
        let v = Vec3::new(2.0, 0.5, 0.0);
        let push = Vec3::new(0.0, 1.0, 0.0);
        let out = coulomb_contact(v, push, 0.5);
        assert!((out - Vec3::new(1.5, 0.5, 0.0)).norm() < 1e-12, "{out}");
        let stopped = coulomb_contact(v, push * 10.0, 0.5);
        assert!(
            (stopped - Vec3::new(0.0, 0.5, 0.0)).norm() < 1e-12,
            "{stopped}"
        );
        assert_eq!(coulomb_contact(v, Vec3::zeros(), 0.5), v);
        assert_eq!(coulomb_contact(v, push, 0.0), v);
    }
}
