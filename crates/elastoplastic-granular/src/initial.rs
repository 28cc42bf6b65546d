//! The initial stress of [`InitialStress::Geostatic`](crate::InitialStress::Geostatic): a
//! column of grains at rest under gravity has the vertical stress of its weight,
//! `σ_v = −ρ0 |g| d` at depth `d`, and the horizontal stress `K0 σ_v` with Jaky's coefficient
//! of earth pressure at rest of a normally consolidated granular soil, `K0 = 1 − sin φ`
//! (J. Jaky, "The coefficient of earth pressure at rest", *Journal of the Society of
//! Hungarian Architects and Engineers* 78(22), 355–358, 1944; e.g. Craig's *Soil
//! Mechanics*, §10.2), the choice of SPHinXsys's granular column collapse.
//!
//! Why not the elastic oedometer's `ν/(1 − ν)`: at ν = 0.3 it is 0.43, below Rankine's
//! active coefficient `(1 − sin φ)/(1 + sin φ)` for φ ≳ 23° and, for the cones the solver
//! matches, outside the cone already at smaller angles (Bui's plane-strain match at
//! φ = 19.8°: `√J2 + α_φ I1 = +0.10 |σ_v|`), so the first step's return would leave the whole
//! column plastic before it has moved. Jaky's `K0` lies between the active and the passive
//! coefficients for every φ (`1 − sin φ ≥ (1 − sin φ)/(1 + sin φ)`), but the matched cone
//! is not Mohr–Coulomb: for the plane-strain matches at large angles (40° and above) Jaky's
//! state lies just outside it. The start then takes the cone's own active coefficient, the
//! least `K` whose state `(−K, −1, −K) σ_v` is inside the cone (cohesion ignored: it only
//! widens the cone), `K_a = (1 − √3 α_φ)/(1 + 2√3 α_φ)` from `√J2 = (1 − K)|σ_v|/√3`,
//! `I1 = (1 + 2K) σ_v`: `K0 = max(1 − sin φ, K_a)`, on the cone in that case
//! (the unit test `the_geostatic_start_is_admissible`). A friction angle of zero (a granular liquid) gives `K0 = 1`: the hydrostatic
//! stress.

use std::collections::HashMap;

use nalgebra::Matrix3;
use sph_core::{Real, Vec3};
use sph_solver::SolverError;

use crate::params::ElastoplasticParams;

fn alloc_error(value: usize) -> SolverError {
    SolverError::InvalidParameter {
        solver: crate::name::NAME,
        name: "initial_stress",
        value: value as f64,
        reason: "could not allocate the initial stress (value: the particle count)",
    }
}

/// The geostatic stress of each particle at `positions` (Pa, tension positive): along the
/// unit gravity `ĝ`, `σ = σ_v (K0 I + (1 − K0) ĝ ĝᵀ)`, `σ_v = −ρ0 |g| d`, the depth `d`
/// measured from the top particle of the particle's column (columns one spacing wide in
/// the plane across gravity) plus half a spacing, where the lattice's surface lies. Zero
/// without gravity.
pub fn geostatic<R: Real>(
    params: &ElastoplasticParams<R>,
    positions: &[Vec3<R>],
) -> Result<Vec<Matrix3<R>>, SolverError> {
    let n = positions.len();
    let mut out: Vec<Matrix3<R>> = Vec::new();
    out.try_reserve_exact(n).map_err(|_| alloc_error(n))?;
    let g = params.common.gravity;
    let g_norm = g.norm();
    if g_norm <= R::zero() {
        out.resize(n, Matrix3::zeros());
        return Ok(out);
    }
    let down = g / g_norm;
    // Two unit vectors across gravity.
    let pick = if down.x.abs() < R::of_f64(0.9) {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let e1 = down.cross(&pick).normalize();
    let e2 = down.cross(&e1);
    let s = params.common.particle_spacing;
    let column = |x: &Vec3<R>| {
        let u = (e1.dot(x) / s).floor().as_f64();
        let v = (e2.dot(x) / s).floor().as_f64();
        (u as i64, v as i64)
    };
    let mut top: HashMap<(i64, i64), R> = HashMap::new();
    top.try_reserve(n.min(1 << 20))
        .map_err(|_| alloc_error(n))?;
    for x in positions {
        let h = -down.dot(x);
        top.entry(column(x))
            .and_modify(|t| {
                if h > *t {
                    *t = h
                }
            })
            .or_insert(h);
    }
    let k0 = geostatic_k0(params);
    let shape = Matrix3::identity() * k0 + down * down.transpose() * (R::one() - k0);
    let rho_g = params.common.rest_density * g_norm;
    let half = R::of_f64(0.5);
    for x in positions {
        let t = top.get(&column(x)).copied().unwrap_or(-down.dot(x));
        let depth = t - (-down.dot(x)) + s * half;
        out.push(shape * (-rho_g * depth));
    }
    Ok(out)
}

/// The coefficient of the geostatic start: Jaky's `1 − sin φ`, or the matched cone's active
/// coefficient where that is larger (module docs).
pub fn geostatic_k0<R: Real>(params: &ElastoplasticParams<R>) -> R {
    let jaky = jaky_k0(params.friction_angle_deg);
    let a = 3f64.sqrt()
        * params
            .cone_match
            .alpha_phi(params.friction_angle_deg.as_f64());
    let active = R::of_f64((1.0 - a) / (1.0 + 2.0 * a));
    if active > jaky {
        active
    } else {
        jaky
    }
}

/// Jaky's coefficient of earth pressure at rest, `K0 = 1 − sin φ` (φ in degrees).
pub fn jaky_k0<R: Real>(friction_angle_deg: R) -> R {
    R::one() - R::of_f64(friction_angle_deg.as_f64().to_radians().sin())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ConeMatch;
    use crate::DruckerPrager;

    /// The geostatic start is admissible for every match and φ from 15° to 45° (inside the
    /// cone, or on it where Jaky's state is not: `f` at rounding level), between Rankine's
    /// active and passive coefficients; Jaky's `K0` itself is strictly inside every match's
    /// cone up to 35° and the simple-shear cone up to 45° (a column at rest starts elastic);
    /// the elastic oedometer's `ν/(1 − ν)` at ν = 0.3 is not (outside Bui's plane-strain cone
    /// at the bars' 19.8°, the reason for the change: see the module docs).
    #[test]
    fn the_geostatic_start_is_admissible() {
        let f = |k0: f64, phi: f64, cone: ConeMatch| {
            let m = DruckerPrager::<f64>::matched(5.84e6, 0.3, phi, 0.0, 0.0, cone);
            m.yield_function(&Matrix3::from_diagonal(&Vec3::new(-k0, -1.0, -k0)))
        };
        for phi in [15.0f64, 19.8, 21.9, 25.0, 30.0, 35.0, 40.0, 45.0] {
            let s = f64::sin(phi.to_radians());
            for cone in [
                ConeMatch::PlaneStrainAssociated,
                ConeMatch::PlaneStrain,
                ConeMatch::SimpleShear,
            ] {
                let mut p = ElastoplasticParams::<f64>::for_spacing(0.01, phi);
                p.cone_match = cone;
                let k0 = geostatic_k0(&p);
                assert!(k0 >= (1.0 - s) / (1.0 + s) && k0 <= (1.0 + s) / (1.0 - s));
                assert!(
                    f(k0, phi, cone) <= 1e-12,
                    "phi = {phi}, {cone:?}: K0 = {k0}"
                );
                if phi <= 35.0 || cone == ConeMatch::SimpleShear {
                    assert_eq!(k0, jaky_k0(phi), "phi = {phi}, {cone:?}");
                    assert!(f(k0, phi, cone) < 0.0, "phi = {phi}, {cone:?}");
                }
            }
        }
        let elastic = 0.3 / 0.7;
        assert!(f(elastic, 19.8, ConeMatch::PlaneStrainAssociated) > 0.05);
    }

    /// A column of four particles under `g = −9.81 ŷ` at φ = 30°: `σ_yy = −ρ0 g d` at depths
    /// `s/2, 3s/2, …`, `σ_xx = σ_zz = K0 σ_yy` with `K0 = 1 − sin 30° = 0.5`, no shear (the
    /// formula above, by hand).
    #[test]
    fn a_column_carries_its_weight() {
        let s = 0.1;
        let p = ElastoplasticParams::<f64>::for_spacing(s, 30.0);
        let x: Vec<Vec3<f64>> = (0..4)
            .map(|k| Vec3::new(0.05, 0.05 + s * k as f64, 0.05))
            .collect();
        let st = geostatic(&p, &x).unwrap();
        let k0 = 1.0 - 30f64.to_radians().sin();
        for (k, m) in st.iter().enumerate() {
            let d = (3 - k) as f64 * s + 0.5 * s;
            let sv = -2040.0 * 9.81 * d;
            assert!((m[(1, 1)] - sv).abs() < 1e-9 * sv.abs());
            assert!((m[(0, 0)] - k0 * sv).abs() < 1e-9 * sv.abs());
            assert!((m[(2, 2)] - k0 * sv).abs() < 1e-9 * sv.abs());
            assert!(m[(0, 1)].abs() < 1e-9 * sv.abs());
        }
    }
}
