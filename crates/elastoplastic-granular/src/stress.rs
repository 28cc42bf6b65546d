//! The constitutive update of one particle: Bui et al. (2008)'s elastic–perfectly-plastic
//! Drucker–Prager stress rate with the Jaumann co-rotational term, and their return of a
//! stress that left the cone (tension cracking, then scaling of the deviator).
//!
//! Conventions: tension positive; `σ` the Cauchy stress (Pa); `L_ab = ∂v_a/∂x_b` the
//! velocity gradient (1/s), `ε̇ = (L + Lᵀ)/2`, `ω = (L − Lᵀ)/2`; `I1 = tr σ`,
//! `s = σ − (I1/3) I`, `J2 = s:s / 2`.
//!
//! ```text
//! f(σ)  = √J2 + α_φ I1 − k_c
//! σ̇     = σ ωᵀ + ω σ + 2G ė + K tr(ε̇) I − λ̇ [3 α_ψ K I + (G/√J2) s]
//! λ̇     = (3 α_φ K tr(ε̇) + (G/√J2) s:ε̇) / (9 α_φ α_ψ K + G)   if f(σ) = 0 and λ̇ > 0, else 0
//! ```
//!
//! with `ė = ε̇ − tr(ε̇)/3 I`, `K = E/(3(1 − 2ν))`, `G = E/(2(1 + ν))`, and `α_φ`, `k_c`,
//! `α_ψ` from the friction angle `φ`, the cohesion `c` and the dilatancy angle `ψ` by the
//! cone's match to Mohr–Coulomb ([`ConeMatch`]; Bui et al. 2008's plane-strain match of an
//! associated material, `α_φ = tan φ/√(9 + 12 tan² φ)`, `k_c = 3c/√(9 + 12 tan² φ)`, by
//! default).
//!
//! # The slope a heap comes to rest at
//!
//! A flank that has flowed and stopped is in steady shear parallel to its surface; with
//! zero dilatancy the plastic flow is deviatoric and coaxial with `s`, so the stress that
//! shears a layer without changing its thickness has `s` of pure shear on the slope planes
//! and equal normal stresses, `√J2 = |τ|`, `I1 = −3σ_n`; the cone then reads
//! `|τ| ≤ 3 α_φ σ_n + k_c` and a cohesionless infinite slope (`τ/σ_n = tan β`) stops at
//! **`tan β = 3 α_φ`** ([`ConeMatch::predicted_repose_angle_deg`]). A settled wedge that has
//! not flowed fails later, at the cone's Mohr–Coulomb angle in plane strain,
//! `sin φ_m = 3 α_φ` ([`ConeMatch::max_stable_slope_deg`]): Davis (1968)'s reduced
//! strength. The derivation, and the runs that confirm it, are in the workspace's
//! `docs/elastoplastic-granular.md`.

use nalgebra::{Matrix3, SymmetricEigen};
use sph_core::Real;

/// A stress is "on the cone" (the plastic rate applies) when `f ≥ −YIELD_TOLERANCE · scale`,
/// `scale = √J2 + α_φ |I1| + k_c`: the return leaves `f` at rounding level, and a stress
/// within this relative distance of the cone counts as on it.
pub const YIELD_TOLERANCE: f64 = 1e-5;

/// The elastic moduli and the Drucker–Prager cone of a material (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DruckerPrager<R: Real> {
    /// Shear modulus `G = E/(2(1 + ν))` (Pa).
    pub shear_modulus: R,
    /// Bulk modulus `K = E/(3(1 − 2ν))` (Pa).
    pub bulk_modulus: R,
    /// `α_φ` of the friction angle ([`ConeMatch::alpha_phi`], dimensionless).
    pub alpha_phi: R,
    /// `α_ψ` of the dilatancy angle ([`ConeMatch::alpha_phi`], dimensionless).
    pub alpha_psi: R,
    /// `k_c` of the cohesion ([`ConeMatch::k_c`], Pa).
    pub k_c: R,
}

/// How the cone is matched to Mohr–Coulomb: the vocabulary the granular solvers share
/// (`sph_solver::cone_match`, with the table of `α_φ`, `k_c` and the slope at rest of each
/// match); this solver uses `α_φ` and `k_c` as they are.
pub use sph_solver::cone_match::{plane_strain_alpha, ConeMatch};

/// The stress increment of one explicit step and what it did plastically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StressUpdate<R: Real> {
    /// The stress after the step and the return to the cone (Pa).
    pub stress: Matrix3<R>,
    /// Increment of the equivalent plastic shear strain `Σ √(2 Δe^p : Δe^p)` (Δe^p the
    /// deviatoric plastic strain increment; equal to the engineering shear strain in simple
    /// shear), from the flow rule and the return together.
    pub plastic_strain: R,
}

/// `I1`, the deviator `s` and `√J2` of `σ`.
#[inline]
pub fn invariants<R: Real>(sigma: &Matrix3<R>) -> (R, Matrix3<R>, R) {
    let i1 = sigma.trace();
    let s = sigma - Matrix3::identity() * (i1 / R::of_f64(3.0));
    let j2 = s.component_mul(&s).sum() * R::of_f64(0.5);
    (i1, s, j2.max(R::zero()).sqrt())
}

impl<R: Real> DruckerPrager<R> {
    /// The material of Young's modulus `E` (Pa), Poisson's ratio `ν`, friction angle `φ`,
    /// dilatancy angle `ψ` (degrees) and cohesion `c` (Pa), the cone matched as Bui et al.
    /// (2008) match it ([`ConeMatch::PlaneStrainAssociated`]).
    pub fn new(
        youngs_modulus: f64,
        poisson_ratio: f64,
        friction_angle_deg: f64,
        dilatancy_angle_deg: f64,
        cohesion: f64,
    ) -> Self {
        Self::matched(
            youngs_modulus,
            poisson_ratio,
            friction_angle_deg,
            dilatancy_angle_deg,
            cohesion,
            ConeMatch::PlaneStrainAssociated,
        )
    }

    /// [`Self::new`] with the cone matched by `cone_match`.
    pub fn matched(
        youngs_modulus: f64,
        poisson_ratio: f64,
        friction_angle_deg: f64,
        dilatancy_angle_deg: f64,
        cohesion: f64,
        cone_match: ConeMatch,
    ) -> Self {
        Self {
            shear_modulus: R::of_f64(youngs_modulus / (2.0 * (1.0 + poisson_ratio))),
            bulk_modulus: R::of_f64(youngs_modulus / (3.0 * (1.0 - 2.0 * poisson_ratio))),
            alpha_phi: R::of_f64(cone_match.alpha_phi(friction_angle_deg)),
            alpha_psi: R::of_f64(cone_match.alpha_phi(dilatancy_angle_deg)),
            k_c: R::of_f64(cone_match.k_c(cohesion, friction_angle_deg)),
        }
    }

    /// `f(σ) = √J2 + α_φ I1 − k_c` (Pa): negative inside the cone.
    pub fn yield_function(&self, sigma: &Matrix3<R>) -> R {
        let (i1, _, sqrt_j2) = invariants(sigma);
        sqrt_j2 + self.alpha_phi * i1 - self.k_c
    }

    /// Whether `σ` lies on (or outside) the cone within [`YIELD_TOLERANCE`].
    pub fn on_cone(&self, sigma: &Matrix3<R>) -> bool {
        let (i1, _, sqrt_j2) = invariants(sigma);
        let f = sqrt_j2 + self.alpha_phi * i1 - self.k_c;
        let scale = sqrt_j2 + self.alpha_phi * i1.abs() + self.k_c;
        sqrt_j2 > R::zero() && f >= -scale * R::of_f64(YIELD_TOLERANCE)
    }

    /// The stress rate `σ̇` (Pa/s) at stress `σ` under velocity gradient `L`, and the plastic
    /// multiplier `λ̇` (1/s) it used (module docs).
    pub fn stress_rate(&self, sigma: &Matrix3<R>, grad_v: &Matrix3<R>) -> (Matrix3<R>, R) {
        let half = R::of_f64(0.5);
        let three = R::of_f64(3.0);
        let strain_rate = (grad_v + grad_v.transpose()) * half;
        let spin = (grad_v - grad_v.transpose()) * half;
        let tr = strain_rate.trace();
        let dev_rate = strain_rate - Matrix3::identity() * (tr / three);
        let (g, k) = (self.shear_modulus, self.bulk_modulus);
        let mut rate = sigma * spin.transpose()
            + spin * sigma
            + dev_rate * (g + g)
            + Matrix3::identity() * (k * tr);
        let mut lambda_dot = R::zero();
        if self.on_cone(sigma) {
            let (_, s, sqrt_j2) = invariants(sigma);
            let g_over = g / sqrt_j2;
            let numerator =
                three * self.alpha_phi * k * tr + g_over * s.component_mul(&strain_rate).sum();
            let denominator = R::of_f64(9.0) * self.alpha_phi * self.alpha_psi * k + g;
            let l = numerator / denominator;
            if l > R::zero() {
                lambda_dot = l;
                rate -= (Matrix3::identity() * (three * self.alpha_psi * k) + s * g_over) * l;
            }
        }
        (rate, lambda_dot)
    }

    /// Bui et al. (2008)'s return of `σ` to the admissible set: tension cracking (if
    /// `−α_φ I1 + k_c < 0`, the mean stress is moved back to the apex `I1 = k_c/α_φ`), then
    /// the deviator scaled by `r = (−α_φ I1 + k_c)/√J2` when `r < 1`. Returns the stress and
    /// the equivalent plastic shear strain of the scaling, `(1 − r)√J2/G`.
    ///
    /// A material without friction or cohesion (`α_φ = k_c = 0`: a granular liquid, the
    /// θ = 0 limit) has its apex at `I1 = 0`: it carries no tension and no deviator.
    pub fn return_to_cone(&self, sigma: &Matrix3<R>) -> (Matrix3<R>, R) {
        let three = R::of_f64(3.0);
        let mut out = *sigma;
        let (mut i1, _, _) = invariants(&out);
        let apex = if self.alpha_phi > R::zero() {
            Some(self.k_c / self.alpha_phi)
        } else if self.k_c == R::zero() {
            Some(R::zero())
        } else {
            None
        };
        if let Some(apex) = apex.filter(|&apex| i1 > apex) {
            out -= Matrix3::identity() * ((i1 - apex) / three);
            i1 = apex;
        }
        let (_, s, sqrt_j2) = invariants(&out);
        let capacity = -self.alpha_phi * i1 + self.k_c;
        if sqrt_j2 > capacity && sqrt_j2 > R::zero() {
            let r = (capacity / sqrt_j2).max(R::zero());
            out = s * r + Matrix3::identity() * (i1 / three);
            let dgamma = (R::one() - r) * sqrt_j2 / self.shear_modulus;
            return (out, dgamma);
        }
        (out, R::zero())
    }

    /// One explicit step of length `dt` (s): `σ + Δt σ̇(σ, L)`, then [`Self::return_to_cone`].
    pub fn update(&self, sigma: &Matrix3<R>, grad_v: &Matrix3<R>, dt: R) -> StressUpdate<R> {
        let (rate, lambda_dot) = self.stress_rate(sigma, grad_v);
        let (stress, dgamma) = self.return_to_cone(&(sigma + rate * dt));
        StressUpdate {
            stress,
            plastic_strain: lambda_dot * dt + dgamma,
        }
    }
}

/// Gray, Monaghan & Swift (2001)'s artificial stress of a particle, `R = Σ_a R^a e_a e_aᵀ`
/// with `R^a = −ε σ^a/ρ²` for each tensile principal stress `σ^a > 0` (0 otherwise), in
/// the units of `σ/ρ²` (m⁵/(kg s²)). Zero without
/// any tensile principal stress (checked first by Gershgorin's bound, so compressed
/// particles skip the eigen-decomposition).
pub fn artificial_stress<R: Real>(sigma: &Matrix3<R>, density: R, epsilon: R) -> Matrix3<R> {
    let mut bound = R::of_f64(f64::NEG_INFINITY);
    for a in 0..3 {
        let mut row = sigma[(a, a)];
        for b in 0..3 {
            if b != a {
                row += sigma[(a, b)].abs();
            }
        }
        bound = bound.max(row);
    }
    if bound <= R::zero() || epsilon == R::zero() {
        return Matrix3::zeros();
    }
    let eig = SymmetricEigen::new(*sigma);
    let scale = -epsilon / (density * density);
    let mut out = Matrix3::zeros();
    for a in 0..3 {
        let value = eig.eigenvalues[a];
        if value > R::zero() {
            let e = eig.eigenvectors.column(a);
            out += e * e.transpose() * (scale * value);
        }
    }
    out
}
