//! The initial stress of [`InitialStress::Geostatic`](crate::InitialStress::Geostatic): a
//! column of grains at rest under gravity in an elastic oedometer (no lateral strain) has
//! the vertical stress of its weight, `σ_v = −ρ0 |g| d` at depth `d`, and the horizontal
//! stress `K0 σ_v`, `K0 = ν/(1 − ν)` (the elastic earth pressure at rest, e.g. Craig's
//! *Soil Mechanics*, §10.2). Bui et al. (2008) start their column collapse from the same
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
    let nu = params.poisson_ratio;
    let k0 = nu / (R::one() - nu);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A column of four particles under `g = −9.81 ŷ`: `σ_yy = −ρ0 g d` at depths
    /// `s/2, 3s/2, …`, `σ_xx = σ_zz = K0 σ_yy`, no shear (the formula above, by hand).
    #[test]
    fn a_column_carries_its_weight() {
        let s = 0.1;
        let p = ElastoplasticParams::<f64>::for_spacing(s, 30.0);
        let x: Vec<Vec3<f64>> = (0..4)
            .map(|k| Vec3::new(0.05, 0.05 + s * k as f64, 0.05))
            .collect();
        let st = geostatic(&p, &x).unwrap();
        let k0 = 0.3 / 0.7;
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
