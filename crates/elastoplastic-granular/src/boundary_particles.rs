//! Walls of fixed boundary (dummy) particles whose stress and velocity are extrapolated from
//! the granular particles around them: Adami, Hu & Adams (2012), "A generalized wall
//! boundary condition for smoothed particle hydrodynamics", *J. Comput. Phys.*
//! 231:7057–7075, with the pressure generalised to the stress tensor as in Bui et al.
//! (2008, rows of fixed boundary particles) and Project Chrono's CRM (Hu, Rakhsha, Yang,
//! Negrut et al. 2021, *CMAME* 385:114022, boundary condition enforcing markers).
//!
//! For a boundary particle `b` with unit normal `n_b` (pointing into the granular side),
//! over the granular neighbours `f` (Shepard weights `W_bf`, `r_bf = x_b − x_f`):
//!
//! ```text
//! σ̄_b = (Σ_f σ_f W_bf − I Σ_f ρ_f (g·r_bf) W_bf) / Σ_f W_bf     (Adami eq. 27, stress)
//! ṽ_b = Σ_f v_f W_bf / Σ_f W_bf
//! free-slip:  σ_b = P σ̄_b P,  v_b = P ṽ_b,   P = I − 2 n_b n_bᵀ (the mirror image)
//! no-slip:    σ_b = σ̄_b,      v_b = −ṽ_b                       (wall at rest)
//! ```
//!
//! Their density is `ρ0` and their mass that of a particle; they enter every sum (velocity
//! gradient, continuity, momentum, artificial viscosity and stress) as neighbours. The
//! isotropic gravity term carries the hydrostatic gradient of the normal stress across the
//! wall (the part the wall must supply for a resting layer to carry its weight). A boundary
//! particle without granular neighbours carries no stress and no velocity.

use nalgebra::Matrix3;
use rayon::prelude::*;
use sph_core::sampling::cubic_lattice;
use sph_core::{Aabb, Real, Vec3};
use sph_kernels::Kernel;
use sph_solver::step::MIN_LEN;
use sph_solver::{NeighbourLists, SolverError};

use crate::kernels::Consts;
use crate::params::WallModel;
use crate::periodic::Images;
use crate::stress::artificial_stress;

/// One fixed boundary particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundaryParticle<R: Real> {
    /// Position (m).
    pub position: Vec3<R>,
    /// Unit normal of the wall it stands for, pointing into the granular side.
    pub normal: Vec3<R>,
    /// Free-slip (mirrored) or no-slip (opposite velocity).
    pub model: WallModel,
}

/// Boundary particles on the cubic lattice of spacing `spacing` filling `region` (half a
/// spacing from its faces, as the granular particles are placed), all with `normal` and
/// `model`. Errors: those of the lattice, or a normal that is not finite and non-zero.
pub fn boundary_block<R: Real>(
    region: &Aabb<R>,
    spacing: R,
    normal: Vec3<R>,
    model: WallModel,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    let len = normal.norm();
    if !(len.is_finite() && len > R::zero()) {
        return Err(SolverError::InvalidParameter {
            solver: crate::solver::NAME,
            name: "normal",
            value: len.as_f64(),
            reason: "a boundary block's normal must be finite and non-zero (value: its length)",
        });
    }
    let normal = normal / len;
    Ok(cubic_lattice(region, spacing, max_count)?
        .into_iter()
        .map(|position| BoundaryParticle {
            position,
            normal,
            model,
        })
        .collect())
}

/// What [`extrapolate`] reads.
pub(crate) struct Extrapolation<'a, R: Real> {
    pub c: Consts<R>,
    pub nb: &'a NeighbourLists,
    pub images: &'a Images<R>,
    /// Positions of the particles then the boundary particles.
    pub x: &'a [Vec3<R>],
    /// Densities of the particles (the boundary's are `ρ0`).
    pub rho: &'a [R],
    pub particles: &'a [BoundaryParticle<R>],
    pub gravity: Vec3<R>,
}

/// Writes the boundary particles' stress into `stress[n..]` from the particles' `stress[..n]`
/// (module docs), their artificial stress into `art[n..]` if given, and their velocity into
/// `v[n..]` if given (from `v[..n]`).
pub(crate) fn extrapolate<R: Real>(
    e: &Extrapolation<'_, R>,
    stress: &mut [Matrix3<R>],
    v: Option<&mut [Vec3<R>]>,
    art: Option<&mut [Matrix3<R>]>,
) {
    let n = e.x.len() - e.particles.len();
    let (s_head, s_tail) = stress.split_at_mut(n);
    let (v_head, v_tail) = match v {
        Some(v) => {
            let (h, t) = v.split_at_mut(n);
            (Some(&*h), Some(t))
        }
        None => (None, None),
    };
    let art_tail = art.map(|a| &mut a[n..]);
    let two = R::of_f64(2.0);
    let work =
        |k: usize, sig: &mut Matrix3<R>, vel: Option<&mut Vec3<R>>, a: Option<&mut Matrix3<R>>| {
            let b = n + k;
            let xb = e.x[b];
            let mut sum_s = Matrix3::zeros();
            let mut sum_g = R::zero();
            let mut sum_v = Vec3::zeros();
            let mut sum_w = R::zero();
            for &j in e.nb.neighbours(b) {
                let (j, xj) = e.images.resolve(j as usize, e.x);
                if j >= n {
                    continue;
                }
                let r = xb - xj;
                let w = e.c.kernel.value(r.norm());
                sum_s += s_head[j] * w;
                sum_g += e.rho[j] * e.gravity.dot(&r) * w;
                if let Some(vh) = v_head {
                    sum_v += vh[j] * w;
                }
                sum_w += w;
            }
            let p = &e.particles[k];
            let mirror = Matrix3::identity() - p.normal * p.normal.transpose() * two;
            let (s_bar, v_bar) = if sum_w > R::zero() {
                ((sum_s - Matrix3::identity() * sum_g) / sum_w, sum_v / sum_w)
            } else {
                (Matrix3::zeros(), Vec3::zeros())
            };
            let (s_b, v_b) = match p.model {
                WallModel::NoSlip => (s_bar, -v_bar),
                _ => (mirror * s_bar * mirror, mirror * v_bar),
            };
            *sig = s_b;
            if let Some(vel) = vel {
                *vel = v_b;
            }
            if let Some(a) = a {
                *a = artificial_stress(&s_b, e.c.rho0, e.c.eps_stress);
            }
        };
    match (v_tail, art_tail) {
        (Some(vt), None) => s_tail
            .par_iter_mut()
            .zip(vt.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(k, (sig, vel))| work(k, sig, Some(vel), None)),
        (None, Some(at)) => s_tail
            .par_iter_mut()
            .zip(at.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(k, (sig, a))| work(k, sig, None, Some(a))),
        _ => s_tail
            .par_iter_mut()
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(k, sig)| work(k, sig, None, None)),
    }
}
