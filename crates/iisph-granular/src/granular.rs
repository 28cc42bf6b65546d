//! The per-particle formulas of the granular model (Neder 2024 §§5.6–5.7), as small pure
//! functions: the solver's loops call them, and the tests check them against independent
//! formulas.

use sph_core::{Real, Vec3};
use sph_kernels::Kernel;

/// A symmetric 3×3 tensor stored as `[xx, yy, zz, xy, xz, yz]` (a stress `s` in Pa, or a
/// strain rate `ε` in 1/s).
pub type Sym3<R> = [R; 6];

/// The symmetric part `ε = (G + Gᵀ)/2` of a velocity gradient `G` (`G[a][b] = ∂u_a/∂x_b`,
/// 1/s): Neder 2024 eq. 8.
#[inline]
pub fn strain_rate<R: Real>(g: &[[R; 3]; 3]) -> Sym3<R> {
    let half = R::of_f64(0.5);
    [
        g[0][0],
        g[1][1],
        g[2][2],
        (g[0][1] + g[1][0]) * half,
        (g[0][2] + g[2][0]) * half,
        (g[1][2] + g[2][1]) * half,
    ]
}

/// The deviatoric part `s − (Tr s / 3) I` (Neder 2024 eqs. 11–12 in their 3D form: the
/// thesis writes `Tr s / 2`, which is the 2D mean stress; in 3D the mean of the three
/// normal stresses is `Tr s / 3`, and only that makes the result traceless).
#[inline]
pub fn deviatoric<R: Real>(s: &Sym3<R>) -> Sym3<R> {
    let mean = (s[0] + s[1] + s[2]) / R::of_f64(3.0);
    [s[0] - mean, s[1] - mean, s[2] - mean, s[3], s[4], s[5]]
}

/// Frobenius norm `‖s‖ = (Σ_ab s_ab²)^½` of a symmetric tensor (off-diagonals count twice).
#[inline]
pub fn frobenius<R: Real>(s: &Sym3<R>) -> R {
    let two = R::of_f64(2.0);
    (s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + two * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]))
        .sqrt()
}

/// The Drucker–Prager yield criterion `‖s‖ ≤ α p` (Neder 2024 eqs. 13–14) as a radial
/// return: `s` scaled by `α p / ‖s‖` where it exceeds the bound (Alduán & Otaduy 2011 §4.2;
/// the thesis mentions a per-component piecewise-linear approximation, we use the exact
/// norm). A non-positive `p` (no confinement) leaves no friction.
#[inline]
pub fn yield_clamp<R: Real>(s: &Sym3<R>, alpha: R, p: R) -> Sym3<R> {
    let bound = alpha * p;
    if bound <= R::zero() {
        return [R::zero(); 6];
    }
    let norm = frobenius(s);
    if norm <= bound {
        *s
    } else {
        let k = bound / norm;
        s.map(|c| c * k)
    }
}

/// `S · v` for a symmetric tensor `S` and a vector `v`.
#[inline]
pub fn sym_mul<R: Real>(s: &Sym3<R>, v: &Vec3<R>) -> Vec3<R> {
    Vec3::new(
        s[0] * v.x + s[3] * v.y + s[4] * v.z,
        s[3] * v.x + s[1] * v.y + s[5] * v.z,
        s[4] * v.x + s[5] * v.y + s[2] * v.z,
    )
}

/// The frictional coefficient `d` of the prototype particle (Neder 2024 eq. 9, s·m/kg):
/// `D = (2 m² Δt / ρ0²) Σ_j (1/ρ0) ∇W_0j ∇W_0jᵀ` over a full simple cubic lattice of
/// spacing `s` with masses `m = ρ0 s³` and `ρ_i = ρ_j = ρ0`. On the cubic lattice `D` is
/// exactly isotropic, `D = d I` with `d = Tr D / 3`, so `D⁻¹ ε = ε / d`. `None` if the
/// result is not finite and positive.
pub fn prototype_friction_coefficient<R: Real, K: Kernel<R>>(
    kernel: &K,
    spacing: R,
    rest_density: R,
    dt: R,
) -> Option<R> {
    let h = kernel.support_radius();
    let reach = (h / spacing).as_f64().ceil();
    if !(reach.is_finite() && reach <= 64.0) {
        return None;
    }
    let reach = reach as i64;
    let mut sum_sq = R::zero();
    for a in -reach..=reach {
        for b in -reach..=reach {
            for c in -reach..=reach {
                let r = Vec3::new(
                    R::of_f64(a as f64),
                    R::of_f64(b as f64),
                    R::of_f64(c as f64),
                ) * spacing;
                sum_sq += kernel.gradient(&r).norm_squared();
            }
        }
    }
    let m = rest_density * spacing * spacing * spacing;
    let two = R::of_f64(2.0);
    let d =
        two * m * m * dt / (rest_density * rest_density * rest_density) * sum_sq / R::of_f64(3.0);
    (d.is_finite_value() && d > R::zero()).then_some(d)
}

/// The drag force of Neder 2024 eqs. 5–6 (N): `F = ½ ρ_a |v_a − v_i|² C_D ω A (v_a − v_i) /
/// |v_a − v_i|`, with the occlusion weight `ω = 1 − o` computed by [`occlusion`]. Zero when
/// the relative velocity vanishes.
#[inline]
pub fn drag_force<R: Real>(
    relative_velocity: Vec3<R>,
    air_density: R,
    drag_coefficient: R,
    area: R,
    omega: R,
) -> Vec3<R> {
    let speed = relative_velocity.norm();
    if !speed.is_finite_value() || speed <= R::zero() {
        return Vec3::zeros();
    }
    // ½ ρ_a |v_rel|² C_D ω A along v_rel/|v_rel|.
    relative_velocity * (R::of_f64(0.5) * air_density * speed * drag_coefficient * omega * area)
}

/// Occlusion `o ∈ [0, 1]` of one neighbour at offset `d = x_j − x_i` for air arriving from
/// direction `upstream` (unit vector): 0 outside the cone of half-angle `acos(cos_cone)`
/// around `upstream`, rising linearly in the cosine of the angle `φ` between `d` and
/// `upstream` to 1 on the axis: `o = (cos φ − cos_cone) / (1 − cos_cone)`. The particle's
/// occlusion is the largest over its neighbours (the neighbour at the smallest angle,
/// Neder 2024 §5.6), and its drag weight `ω = 1 − o`.
#[inline]
pub fn occlusion<R: Real>(upstream: &Vec3<R>, d: &Vec3<R>, cos_cone: R) -> R {
    let len = d.norm();
    if !len.is_finite_value() || len <= R::zero() {
        return R::zero();
    }
    occlusion_of_cosine(upstream.dot(d) / len, cos_cone)
}

/// [`occlusion`] from `cos φ`: 0 for `cos φ ≤ cos_cone`, else `min(1, (cos φ − cos_cone) /
/// (1 − cos_cone))`. Non-decreasing in `cos φ` (also in floating point), so the largest
/// occlusion over the neighbours is that of the largest cosine.
#[inline]
pub fn occlusion_of_cosine<R: Real>(cos_phi: R, cos_cone: R) -> R {
    if cos_phi <= cos_cone {
        R::zero()
    } else {
        ((cos_phi - cos_cone) / (R::one() - cos_cone)).min(R::one())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use sph_kernels::CubicSpline;

    fn full(s: &Sym3<f64>) -> [[f64; 3]; 3] {
        [[s[0], s[3], s[4]], [s[3], s[1], s[5]], [s[4], s[5], s[2]]]
    }

    proptest! {
        /// The deviatoric part is traceless and differs from `s` by a multiple of I; the
        /// yield clamp never exceeds `α p` and leaves stresses inside the cone unchanged.
        #[test]
        fn deviatoric_and_yield(c in prop::array::uniform6(-1e3f64..1e3), alpha in 0.0f64..1.4, p in -10.0f64..1e3) {
            let d = deviatoric(&c);
            prop_assert!((d[0] + d[1] + d[2]).abs() < 1e-9);
            let shift = c[0] - d[0];
            prop_assert!((c[1] - d[1] - shift).abs() < 1e-9 && (c[2] - d[2] - shift).abs() < 1e-9);
            let y = yield_clamp(&d, alpha, p);
            let norm: f64 = full(&y).iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
            prop_assert!((norm - frobenius(&y)).abs() < 1e-9 * (1.0 + norm));
            prop_assert!(norm <= (alpha * p).max(0.0) * (1.0 + 1e-12) + 1e-12);
            if frobenius(&d) <= alpha * p {
                prop_assert_eq!(y, d);
            }
        }

        /// `S v` equals the full matrix product.
        #[test]
        fn sym_mul_is_matrix_product(c in prop::array::uniform6(-10.0f64..10.0), v in prop::array::uniform3(-10.0f64..10.0)) {
            let m = full(&c);
            let r = sym_mul(&c, &Vec3::new(v[0], v[1], v[2]));
            for a in 0..3 {
                let e: f64 = (0..3).map(|b| m[a][b] * v[b]).sum();
                prop_assert!((r[a] - e).abs() < 1e-9);
            }
        }
    }

    /// The prototype `D` against an explicit lattice sum of the full 3×3 tensor: isotropic
    /// (off-diagonals 0, equal diagonal) and equal to `d`.
    #[test]
    fn prototype_d_is_isotropic() {
        let (s, rho0, dt) = (0.025, 1000.0, 0.002);
        let k = CubicSpline::new(2.0 * s).unwrap();
        let d = prototype_friction_coefficient(&k, s, rho0, dt).unwrap();
        let mut t = [[0.0f64; 3]; 3];
        for a in -2i32..=2 {
            for b in -2i32..=2 {
                for c in -2i32..=2 {
                    let r = Vec3::new(a as f64, b as f64, c as f64) * s;
                    let g = k.gradient(&r);
                    for i in 0..3 {
                        for j in 0..3 {
                            t[i][j] += g[i] * g[j];
                        }
                    }
                }
            }
        }
        let m = rho0 * s * s * s;
        let f = 2.0 * m * m * dt / (rho0 * rho0) / rho0;
        for i in 0..3 {
            assert!((f * t[i][i] - d).abs() < 1e-12 * d);
            for j in 0..3 {
                if i != j {
                    assert!(t[i][j].abs() < 1e-9 * t[0][0]);
                }
            }
        }
    }

    /// Occlusion: 1 straight upstream, 0 outside the cone, in between inside; drag along
    /// the relative velocity with magnitude ½ ρ_a |v|² C_D ω A.
    #[test]
    fn occlusion_and_drag() {
        let up = Vec3::new(1.0, 0.0, 0.0);
        let cos30 = 30f64.to_radians().cos();
        assert_eq!(occlusion(&up, &Vec3::new(0.02, 0.0, 0.0), cos30), 1.0);
        assert_eq!(occlusion(&up, &Vec3::new(0.0, 0.02, 0.0), cos30), 0.0);
        assert_eq!(occlusion(&up, &Vec3::new(-0.02, 0.0, 0.0), cos30), 0.0);
        let o = occlusion(&up, &Vec3::new(1.0, 0.2, 0.0), cos30);
        assert!(o > 0.0 && o < 1.0);
        let f: Vec3<f64> = drag_force(Vec3::new(0.0, 3.0, 4.0), 1.2, 0.5, 0.01, 0.5);
        let expect = 0.5 * 1.2 * 25.0 * 0.5 * 0.5 * 0.01;
        assert!((f.norm() - expect).abs() < 1e-12);
        assert!((f.normalize() - Vec3::new(0.0, 0.6, 0.8)).norm() < 1e-12);
        assert_eq!(
            drag_force(Vec3::<f64>::zeros(), 1.2, 0.5, 0.01, 1.0),
            Vec3::zeros()
        );
    }

    /// The strain rate of a linear field u = G x is the symmetric part of G.
    #[test]
    fn strain_rate_is_symmetric_part() {
        let g = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]];
        assert_eq!(strain_rate(&g), [1.0, 5.0, 9.0, 3.0, 5.0, 7.0]);
    }
}
