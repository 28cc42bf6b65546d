//! Anisotropic particles (Yu & Turk 2013, §3–4): each particle becomes an ellipsoid
//! stretched along its neighbourhood's principal directions, so that thin sheets and
//! filaments render flat and smooth instead of as strings of beads. The PBF paper renders
//! with it.
//!
//! For particle `i` with neighbours `j` within `support_m` (`r`), weights
//! `w_ij = 1 − (|x_i − x_j|/r)³` (Yu & Turk eq. 11), the weighted mean
//! `x̄_i = Σ w_ij x_j / Σ w_ij` and covariance `C_i = Σ w_ij (x_j − x̄_i)(x_j − x̄_i)ᵀ / Σ w_ij`
//! (eqs. 10, 12), decomposed `C = R diag(σ₁ ≥ σ₂ ≥ σ₃) Rᵀ`. With more than `min_neighbours`
//! (`N_ε`) neighbours the singular values are clamped, `σ̃_k = max(σ_k, σ₁/k_r)` (eq. 15);
//! with fewer the particle stays a sphere (their `k_n I`). The centre is smoothed,
//! `x̃_i = (1 − λ) x_i + λ x̄_i` (eq. 6).
//!
//! *Deviation:* Yu & Turk scale `σ̃` by a constant `k_s` tuned so that a full neighbourhood
//! gives a kernel of the isotropic size; we instead keep the sphere's volume,
//! `M_i = r_p R diag(σ̃ / (σ̃₁σ̃₂σ̃₃)^{1/3}) Rᵀ` (`r_p` the particle radius), so that the
//! ellipsoid is a volume-preserving stretch of the particle's sphere and no constant needs
//! tuning. The neighbour search is a hashed uniform grid of cell `r` (this crate depends on
//! `sph-core` only); [`anisotropic_ellipsoids_naive`] is its all-pairs oracle.

// NaN-rejecting checks are written as `!(x > 0.0)` on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::{Matrix3, SymmetricEigen};
use rayon::prelude::*;
use sph_core::{Real, Vec3};

use crate::error::positive;
use crate::{SsfrError, V3};

/// Smoothed centres and ellipsoid matrices, one per particle.
pub type Ellipsoids = (Vec<Vec3<f32>>, Vec<Matrix3<f32>>);

/// Parameters of the anisotropy (Yu & Turk 2013's defaults where they give them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnisotropyParams {
    /// Neighbourhood radius `r` (m); Yu & Turk use twice the SPH support.
    pub support_m: f32,
    /// Radius of the isotropic particle sphere (m).
    pub particle_radius_m: f32,
    /// Centre smoothing `λ` in [0, 1] (0.9 in the paper).
    pub lambda: f32,
    /// Largest ratio of the principal radii, `k_r` (4 in the paper).
    pub max_stretch: f32,
    /// Fewest neighbours for an ellipsoid, `N_ε` (25 in the paper).
    pub min_neighbours: usize,
}

impl AnisotropyParams {
    /// Yu & Turk's defaults for particles of `particle_radius_m` and neighbourhood
    /// `support_m`.
    pub fn new(particle_radius_m: f32, support_m: f32) -> Self {
        Self {
            support_m,
            particle_radius_m,
            lambda: 0.9,
            max_stretch: 4.0,
            min_neighbours: 25,
        }
    }

    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), SsfrError> {
        positive("anisotropy.support_m", self.support_m)?;
        positive("anisotropy.particle_radius_m", self.particle_radius_m)?;
        if !(0.0..=1.0).contains(&self.lambda) {
            return Err(SsfrError::invalid("anisotropy.lambda", "must be in [0, 1]"));
        }
        if !(self.max_stretch >= 1.0) {
            return Err(SsfrError::invalid("anisotropy.max_stretch", "must be >= 1"));
        }
        Ok(())
    }
}

/// The ellipsoid of one particle from its neighbours' positions (`x_i` included); `nb`
/// yields them (twice: mean, then covariance; no allocation).
fn ellipsoid<I: Iterator<Item = V3>>(
    xi: &V3,
    nb: impl Fn() -> I,
    p: &AnisotropyParams,
) -> (V3, Matrix3<f32>) {
    let r = p.support_m;
    let weight = |xj: &V3| {
        let d = (xj - xi).norm();
        (d < r).then(|| 1.0 - (d / r).powi(3))
    };
    let (mut wsum, mut mean, mut count) = (0.0f32, V3::zeros(), 0usize);
    for xj in nb() {
        if let Some(w) = weight(&xj) {
            wsum += w;
            mean += xj * w;
            count += 1;
        }
    }
    let sphere = Matrix3::identity() * p.particle_radius_m;
    if wsum <= 0.0 {
        return (*xi, sphere);
    }
    mean /= wsum;
    let centre = xi * (1.0 - p.lambda) + mean * p.lambda;
    // `count` includes the particle itself.
    if count <= p.min_neighbours {
        return (centre, sphere);
    }
    let mut c = Matrix3::zeros();
    for xj in nb() {
        if let Some(w) = weight(&xj) {
            let d = xj - mean;
            c += d * d.transpose() * w;
        }
    }
    c /= wsum;
    let eig = SymmetricEigen::new(c);
    let s_max = eig.eigenvalues.max().max(0.0).sqrt();
    if !(s_max > 0.0) {
        return (centre, sphere);
    }
    // Principal radii ∝ standard deviations, clamped to s_max / k_r.
    let s = eig
        .eigenvalues
        .map(|e| e.max(0.0).sqrt().max(s_max / p.max_stretch));
    let scale = p.particle_radius_m / (s.x * s.y * s.z).cbrt();
    let m = eig.eigenvectors * Matrix3::from_diagonal(&(s * scale)) * eig.eigenvectors.transpose();
    (centre, m)
}

fn cell_of(x: &V3, r: f32) -> (i32, i32, i32) {
    (
        (x.x / r).floor() as i32,
        (x.y / r).floor() as i32,
        (x.z / r).floor() as i32,
    )
}

/// The smoothed centres and ellipsoids (`{x̃_i + M_i w : |w| ≤ 1}`) of `positions`, for
/// [`crate::ParticleView::ellipsoids`] (draw the ellipsoids at the returned centres).
pub fn anisotropic_ellipsoids<R: Real>(
    positions: &[Vec3<R>],
    params: &AnisotropyParams,
) -> Result<Ellipsoids, SsfrError> {
    anisotropic_ellipsoids_cancellable(positions, params, None)
}

/// [`anisotropic_ellipsoids`] that stops with [`SsfrError::Cancelled`] once `cancel` is set
/// (checked per particle).
pub fn anisotropic_ellipsoids_cancellable<R: Real>(
    positions: &[Vec3<R>],
    params: &AnisotropyParams,
    cancel: Option<&AtomicBool>,
) -> Result<Ellipsoids, SsfrError> {
    let cancelled = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
    params.validate()?;
    let x: Vec<V3> = positions
        .iter()
        .map(|p| p.map(|c| c.as_f64() as f32))
        .collect();
    if let Some((index, p)) = x
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
    {
        return Err(SsfrError::BadParticle {
            index,
            what: "position",
            value: p
                .iter()
                .find(|c| !c.is_finite())
                .copied()
                .unwrap_or(f32::NAN) as f64,
        });
    }
    let r = params.support_m;
    let mut grid: HashMap<(i32, i32, i32), Vec<u32>> = HashMap::new();
    for (k, p) in x.iter().enumerate() {
        grid.entry(cell_of(p, r)).or_default().push(k as u32);
    }
    let out: Vec<(V3, Matrix3<f32>)> = x
        .par_iter()
        .map(|xi| {
            if cancelled() {
                return Err(SsfrError::Cancelled);
            }
            let (ci, cj, ck) = cell_of(xi, r);
            let (grid, x) = (&grid, &x);
            let neighbours = move || {
                (-1..=1).flat_map(move |a| {
                    (-1..=1).flat_map(move |b| {
                        (-1..=1).flat_map(move |c| {
                            grid.get(&(ci + a, cj + b, ck + c))
                                .into_iter()
                                .flatten()
                                .map(move |&j| x[j as usize])
                        })
                    })
                })
            };
            Ok(ellipsoid(xi, neighbours, params))
        })
        .collect::<Result<_, _>>()?;
    Ok(out.into_iter().unzip())
}

/// The all-pairs oracle of [`anisotropic_ellipsoids`] (tests only).
pub fn anisotropic_ellipsoids_naive(
    positions: &[V3],
    params: &AnisotropyParams,
) -> (Vec<V3>, Vec<Matrix3<f32>>) {
    positions
        .iter()
        .map(|xi| ellipsoid(xi, || positions.iter().copied(), params))
        .unzip()
}
