//! The per-particle loops of one explicit step (see the crate docs for the equations). Each
//! writes one particle's values from the previous arrays, so results do not depend on the
//! thread count.

use nalgebra::Matrix3;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::Kernel;
use sph_solver::boundary::Boundary;
use sph_solver::csr::par_csr_blocks;
use sph_solver::step::MIN_LEN;
use sph_solver::NeighbourLists;

use crate::kernels::Consts;
use crate::params::WallModel;
use crate::scratch::Scratch;
use crate::stress::artificial_stress;
use crate::walls::{wall_part, WallSampler};

/// What the passes read besides the scratch arrays.
pub(crate) struct StepInputs<'a, R: Real, K> {
    pub c: Consts<R, K>,
    pub masses: &'a [R],
    pub nb: &'a NeighbourLists,
    pub boundary: &'a dyn Boundary<R>,
    pub walls: &'a WallSampler<R>,
    pub models: &'a [WallModel],
    pub gravity: Vec3<R>,
    pub dt: R,
    /// Mass of a boundary particle (kg): neighbours `j ≥ masses.len()` are boundary
    /// particles.
    pub boundary_mass: R,
}

impl<R: Real, K> StepInputs<'_, R, K> {
    #[inline]
    fn mass(&self, j: usize) -> R {
        self.masses.get(j).copied().unwrap_or(self.boundary_mass)
    }
}

/// The density re-initialisation
/// ([`ElastoplasticParams::density_reinit_interval_s`](crate::ElastoplasticParams)): each
/// grain's density becomes the kernel sum over itself, its grain neighbours and the boundary
/// particles, normalised by the full lattice's, floored at `ρ0` (free surface, separated
/// grains).
pub(crate) fn reinitialise_density<R: Real, K: Kernel<R>>(
    s: &mut Scratch<R>,
    inp: &StepInputs<'_, R, K>,
) {
    let c = inp.c;
    let n = inp.masses.len();
    let h2 = c.support2_above;
    let w0 = c.kernel.value(R::zero());
    let (x, images) = (&s.x[..], &s.images);
    s.rho[..n]
        .par_iter_mut()
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, rho)| {
            let xi = x[i];
            let mut sum = inp.masses[i] * w0;
            for &j in inp.nb.neighbours(i) {
                let (j, xj) = images.resolve(j as usize, x);
                let r2 = (xi - xj).norm_squared();
                if r2 <= h2 {
                    sum += inp.mass(j) * c.kernel.value(r2.sqrt());
                }
            }
            let summed = sum * c.summation_scale;
            *rho = if summed > c.rho0 { summed } else { c.rho0 };
        });
}

/// The kernel gradient `∇_i W_ij` of every grain's listed pair, in the lists' CSR order
/// (zero beyond the support): computed once per explicit step and read by both passes.
pub(crate) fn pair_gradients<R: Real, K: Kernel<R>>(
    s: &mut Scratch<R>,
    inp: &StepInputs<'_, R, K>,
) {
    let n = inp.masses.len();
    let offsets = &inp.nb.offsets()[..=n];
    let pairs = offsets[n];
    s.pair_grad.resize(pairs, Vec3::zeros());
    let (x, images, h2, kernel) = (&s.x[..], &s.images, inp.c.support2_above, inp.c.kernel);
    let mut grains = vec![(); n];
    par_csr_blocks(
        offsets,
        &mut grains[..],
        &mut s.pair_grad[..pairs],
        &|first, grains: &mut [()], out: &mut [Vec3<R>]| {
            let base = offsets[first];
            for i in first..first + grains.len() {
                let xi = x[i];
                let at = offsets[i] - base;
                for (k, &j) in inp.nb.neighbours(i).iter().enumerate() {
                    let (_, xj) = images.resolve(j as usize, x);
                    let xij = xi - xj;
                    out[at + k] = if xij.norm_squared() > h2 {
                        Vec3::zeros()
                    } else {
                        kernel.gradient(&xij)
                    };
                }
            }
            0.0
        },
    );
}

/// Pass 1: the wall gradients at `x`, the velocity gradient `L_i` and the continuity rate
/// from `x`, `v`, `ρ`; the stress update (rate and return, [`crate::DruckerPrager::update`];
/// zero for a particle without granular neighbours inside the support), the density and
/// plastic strain after `Δt`, and the artificial stress of the new stress.
pub(crate) fn stress_pass<R: Real, K: Kernel<R>>(s: &mut Scratch<R>, inp: &StepInputs<'_, R, K>) {
    let c = inp.c;
    let slots = inp.models.len();
    let n = inp.masses.len();
    // `m_j / ρ_j` of every neighbour, once per particle rather than once per pair (the
    // boundary particles' stays `m_b / ρ0` from `Scratch::resize`).
    s.volume[..n]
        .par_iter_mut()
        .zip(inp.masses.par_iter().zip(s.rho[..n].par_iter()))
        .with_min_len(MIN_LEN)
        .for_each(|(vol, (&m, &r))| *vol = m / r);
    let (x, v, rho, volume) = (&s.x[..], &s.v[..], &s.rho[..], &s.volume[..]);
    let (stress, plastic, images) = (&s.stress[..], &s.plastic_strain[..], &s.images);
    let (grad, offsets) = (&s.pair_grad[..], inp.nb.offsets());
    s.stress_new[..n]
        .par_iter_mut()
        .zip(s.rho_new[..n].par_iter_mut())
        .zip(s.plastic_new.par_iter_mut())
        .zip(s.art[..n].par_iter_mut())
        .zip(s.wall_grad.par_chunks_mut(slots.max(1)))
        .zip(s.stress_over_rho2[..n].par_iter_mut())
        .zip(s.art_on[..n].par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(
            |(i, ((((((sig, r), kappa), art), grads), sig_rho2), art_on))| {
                let (xi, vi) = (x[i], v[i]);
                let mut grad_v = Matrix3::zeros();
                let mut drho = R::zero();
                let mut in_contact = false;
                let grad_i = &grad[offsets[i]..offsets[i + 1]];
                for (&j, &gw) in inp.nb.neighbours(i).iter().zip(grad_i) {
                    // Beyond the support (the lists' skin) the gradient is zero, whose terms
                    // would add zeros.
                    if gw == Vec3::zeros() {
                        continue;
                    }
                    let (j, _) = images.resolve(j as usize, x);
                    in_contact |= j < n && j != i;
                    let dv = v[j] - vi;
                    grad_v += dv * gw.transpose() * volume[j];
                    drho -= inp.mass(j) * dv.dot(&gw);
                }
                if slots > 0 {
                    inp.walls.sample(inp.boundary, &xi, grads);
                    for (g, &model) in grads.iter().zip(inp.models) {
                        if model != WallModel::ContactOnly && g.norm_squared() > R::zero() {
                            grad_v -= wall_part(model, g, &vi) * g.transpose();
                            drho += c.rho0 * vi.dot(g);
                        }
                    }
                }
                let mut up = c.material.update(&stress[i], &grad_v, inp.dt);
                if !in_contact {
                    // A grain without a granular neighbour is out of contact: it carries no
                    // stress (else it keeps the last one, its velocity gradient being zero).
                    up.stress = Matrix3::zeros();
                    up.plastic_strain = R::zero();
                }
                let rho_next = rho[i] + drho * inp.dt;
                *sig = up.stress;
                *r = rho_next;
                *kappa = plastic[i] + up.plastic_strain;
                *art = artificial_stress(&up.stress, rho_next, c.eps_stress);
                *sig_rho2 = up.stress / (rho_next * rho_next);
                *art_on = *art != Matrix3::zeros();
            },
        );
}

/// Pass 2: the acceleration from the new stresses (with the artificial viscosity and
/// stress and the walls' share), the velocity and position after `Δt` (symplectic Euler),
/// the position projected out of the solids and the velocity corrected by that projection.
pub(crate) fn momentum_pass<R: Real, K: Kernel<R>>(s: &mut Scratch<R>, inp: &StepInputs<'_, R, K>) {
    let c = inp.c;
    let slots = inp.models.len();
    let n = inp.masses.len();
    let (x, v) = (&s.x[..], &s.v[..]);
    let (sig, rho, art, grads) = (&s.stress_new[..], &s.rho_new[..], &s.art[..], &s.wall_grad);
    let (sig_rho2, art_on) = (&s.stress_over_rho2[..], &s.art_on[..]);
    let images = &s.images;
    let (grad, offsets) = (&s.pair_grad[..], inp.nb.offsets());
    let two = R::of_f64(2.0);
    let half = R::of_f64(0.5);
    let inv_dt = R::one() / inp.dt;
    s.v_new[..n]
        .par_iter_mut()
        .zip(s.x_new[..n].par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (vn, xn))| {
            let (xi, vi, ri) = (x[i], v[i], rho[i]);
            let si = sig_rho2[i];
            let art_i = art[i];
            let art_i_on = art_on[i];
            let mut a = inp.gravity;
            let grad_i = &grad[offsets[i]..offsets[i + 1]];
            for (&j, &gw) in inp.nb.neighbours(i).iter().zip(grad_i) {
                if gw == Vec3::zeros() {
                    continue;
                }
                let (j, xj) = images.resolve(j as usize, x);
                let xij = xi - xj;
                let rj = rho[j];
                let mut t = si + sig_rho2[j];
                // Monaghan's artificial viscosity, for approaching pairs (`Π_ij > 0`: only
                // the diagonal changes).
                let vij = vi - v[j];
                let vx = vij.dot(&xij);
                if vx < R::zero() {
                    let phi = c.h * vx / (xij.norm_squared() + c.eta2);
                    let pi = (-c.alpha * c.c0 * phi + c.beta * phi * phi) / ((ri + rj) * half);
                    for k in 0..3 {
                        t[(k, k)] -= pi;
                    }
                }
                // Gray, Monaghan & Swift's artificial stress.
                if art_i_on || art_on[j] {
                    let f = (c.kernel.value(xij.norm()) * c.inv_w_spacing).powf(c.exponent);
                    t += (art_i + art[j]) * f;
                }
                a += t * gw * inp.mass(j);
            }
            if slots > 0 {
                let gi = &grads[i * slots..(i + 1) * slots];
                for (g, &model) in gi.iter().zip(inp.models) {
                    if model != WallModel::ContactOnly && g.norm_squared() > R::zero() {
                        a += wall_part(model, g, &(sig[i] * g)) * (two * c.rho0 / (ri * ri));
                    }
                }
            }
            let v_star = vi + a * inp.dt;
            let y = xi + v_star * inp.dt;
            let p = inp.boundary.project(y);
            *xn = p;
            *vn = v_star + (p - y) * inv_dt;
        });
}

/// `σ_b/ρ_b²` and whether the artificial stress is non-zero, for the boundary particles
/// `n..` (after their stress and artificial stress are extrapolated), as the stress pass
/// writes them for the grains.
pub(crate) fn boundary_pair_terms<R: Real>(s: &mut Scratch<R>, n: usize) {
    let (sig, rho, art) = (&s.stress_new[n..], &s.rho_new[n..], &s.art[n..]);
    s.stress_over_rho2[n..]
        .par_iter_mut()
        .zip(s.art_on[n..].par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(k, (sr, on))| {
            *sr = sig[k] / (rho[k] * rho[k]);
            *on = art[k] != Matrix3::zeros();
        });
}

/// The largest distance (m) any particle has moved since the last neighbour search.
pub(crate) fn max_displacement<R: Real>(s: &Scratch<R>, n: usize) -> R {
    s.x[..n]
        .par_iter()
        .zip(s.anchor.par_iter())
        .with_min_len(MIN_LEN)
        .map(|(a, b)| (a - b).norm())
        .reduce(R::zero, |a, b| if b > a { b } else { a })
}
