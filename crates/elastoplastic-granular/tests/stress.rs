//! The constitutive update against hand-derived values and a naive index-notation oracle.

use elastoplastic_granular::stress::{invariants, plane_strain_alpha, YIELD_TOLERANCE};
use elastoplastic_granular::DruckerPrager;
use nalgebra::Matrix3;
use proptest::prelude::*;

const E: f64 = 1e6;
const NU: f64 = 0.25;

fn sand() -> DruckerPrager<f64> {
    DruckerPrager::new(E, NU, 30.0, 0.0, 0.0)
}

fn close(a: &Matrix3<f64>, b: &Matrix3<f64>, tol: f64) -> bool {
    (a - b).abs().max() <= tol * (1.0 + b.abs().max())
}

/// The rate of the crate docs written out component by component, as an oracle.
fn naive_rate(m: &DruckerPrager<f64>, sig: &Matrix3<f64>, l: &Matrix3<f64>) -> Matrix3<f64> {
    let (g, k) = (m.shear_modulus, m.bulk_modulus);
    let mut eps = [[0.0; 3]; 3];
    let mut om = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            eps[a][b] = 0.5 * (l[(a, b)] + l[(b, a)]);
            om[a][b] = 0.5 * (l[(a, b)] - l[(b, a)]);
        }
    }
    let tr = eps[0][0] + eps[1][1] + eps[2][2];
    let i1 = sig[(0, 0)] + sig[(1, 1)] + sig[(2, 2)];
    let mut s = [[0.0; 3]; 3];
    let mut j2 = 0.0;
    for a in 0..3 {
        for b in 0..3 {
            s[a][b] = sig[(a, b)] - if a == b { i1 / 3.0 } else { 0.0 };
            j2 += 0.5 * s[a][b] * s[a][b];
        }
    }
    let sq = j2.sqrt();
    let f = sq + m.alpha_phi * i1 - m.k_c;
    let mut lambda = 0.0;
    if sq > 0.0 && f >= -YIELD_TOLERANCE * (sq + m.alpha_phi * i1.abs() + m.k_c) {
        let mut se = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                se += s[a][b] * eps[a][b];
            }
        }
        let l =
            (3.0 * m.alpha_phi * k * tr + g / sq * se) / (9.0 * m.alpha_phi * m.alpha_psi * k + g);
        lambda = l.max(0.0);
    }
    let mut out = Matrix3::zeros();
    for a in 0..3 {
        for b in 0..3 {
            let d = if a == b { 1.0 } else { 0.0 };
            let mut jaumann = 0.0;
            for c in 0..3 {
                jaumann += sig[(a, c)] * om[b][c] + om[a][c] * sig[(c, b)];
            }
            let elastic = 2.0 * g * (eps[a][b] - d * tr / 3.0) + k * tr * d;
            let plastic = if lambda > 0.0 {
                lambda * (3.0 * m.alpha_psi * k * d + g / sq * s[a][b])
            } else {
                0.0
            };
            out[(a, b)] = jaumann + elastic - plastic;
        }
    }
    out
}

#[test]
fn uniaxial_strain_rate_gives_the_constrained_and_lame_moduli() {
    // σ̇_xx = E(1−ν)/((1+ν)(1−2ν)) ε̇ = 1.2e6 ε̇, σ̇_yy = σ̇_zz = Eν/((1+ν)(1−2ν)) ε̇ = 4e5 ε̇.
    let l = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-3, 0.0, 0.0));
    let (rate, lambda) = sand().stress_rate(&Matrix3::zeros(), &l);
    let expected = Matrix3::from_diagonal(&nalgebra::Vector3::new(1200.0, 400.0, 400.0));
    assert!(close(&rate, &expected, 1e-12), "{rate}");
    assert_eq!(lambda, 0.0);
}

#[test]
fn rigid_spin_rotates_the_stress() {
    // v = w ẑ × x: L = [[0, −w, 0], [w, 0, 0], 0]; σ̇_xy = w (σ_xx − σ_yy), nothing else,
    // for a stress inside the cone (√J2 = 500 Pa < α_φ |I1| = 1201 Pa).
    let w = 0.3;
    let sig = Matrix3::from_diagonal(&nalgebra::Vector3::new(-2e3, -3e3, -2.5e3));
    let l = Matrix3::new(0.0, -w, 0.0, w, 0.0, 0.0, 0.0, 0.0, 0.0);
    let (rate, _) = sand().stress_rate(&sig, &l);
    let mut expected = Matrix3::zeros();
    expected[(0, 1)] = w * 1e3;
    expected[(1, 0)] = w * 1e3;
    assert!(close(&rate, &expected, 1e-12), "{rate}");
}

#[test]
fn return_scales_the_deviator_back_to_the_cone() {
    // σ = diag(−1, −3, −2) kPa: I1 = −6 kPa, √J2 = 1 kPa > α_φ · 6 kPa = 960.6 Pa.
    let alpha = (30f64.to_radians().tan()) / 13f64.sqrt();
    let sig = Matrix3::from_diagonal(&nalgebra::Vector3::new(-1e3, -3e3, -2e3));
    let (out, dgamma) = sand().return_to_cone(&sig);
    let tau = alpha * 6e3;
    let expected = Matrix3::from_diagonal(&nalgebra::Vector3::new(-2e3 + tau, -2e3 - tau, -2e3));
    assert!(close(&out, &expected, 1e-12), "{out}");
    let g = E / (2.0 * (1.0 + NU));
    assert!((dgamma - (1e3 - tau) / g).abs() < 1e-15);
    assert!((plane_strain_alpha(30.0) - alpha).abs() < 1e-15);
}

#[test]
fn tension_cracks_back_to_the_apex() {
    let sig = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e3, 2e3, 3e3));
    let (out, _) = sand().return_to_cone(&sig);
    assert!(out.abs().max() < 1e-9, "{out}");
}

#[test]
fn shear_on_the_cone_flows_without_changing_the_stress() {
    // On the cone with ψ = 0 and ε̇ = diag(e, −e, 0): s:ε̇ = 2τe, λ̇ = 2e, and the plastic
    // rate cancels the elastic one exactly (perfect plasticity).
    let alpha = plane_strain_alpha(30.0);
    let tau = alpha * 6e3;
    let sig = Matrix3::from_diagonal(&nalgebra::Vector3::new(-2e3 + tau, -2e3 - tau, -2e3));
    let e = 1e-2;
    let l = Matrix3::from_diagonal(&nalgebra::Vector3::new(e, -e, 0.0));
    let (rate, lambda) = sand().stress_rate(&sig, &l);
    assert!((lambda - 2.0 * e).abs() < 1e-12, "λ̇ = {lambda}");
    assert!(rate.abs().max() < 1e-6, "{rate}");
}

fn symmetric(v: [f64; 6]) -> Matrix3<f64> {
    Matrix3::new(v[0], v[3], v[5], v[3], v[1], v[4], v[5], v[4], v[2])
}

proptest! {
    #[test]
    fn rate_matches_the_naive_oracle(
        sv in prop::array::uniform6(-5e3f64..5e3),
        lv in prop::array::uniform9(-1.0f64..1.0),
        onto_cone in any::<bool>(),
        psi in 0.0f64..30.0,
    ) {
        let m = DruckerPrager::new(E, NU, 30.0, psi, 0.0);
        let mut sig = symmetric(sv);
        if onto_cone {
            sig = m.return_to_cone(&sig).0;
        }
        let l = Matrix3::from_iterator(lv);
        let (rate, _) = m.stress_rate(&sig, &l);
        let oracle = naive_rate(&m, &sig, &l);
        prop_assert!(close(&rate, &oracle, 1e-10), "{} vs {}", rate, oracle);
    }

    #[test]
    fn the_return_lands_inside_the_cone(
        sv in prop::array::uniform6(-1e4f64..1e4),
        phi in 5.0f64..45.0,
        c in 0.0f64..1e3,
    ) {
        let m = DruckerPrager::new(E, NU, phi, 0.0, c);
        let (out, dgamma) = m.return_to_cone(&symmetric(sv));
        let (i1, _, sq) = invariants(&out);
        let scale = sq + m.alpha_phi * i1.abs() + m.k_c;
        prop_assert!(m.yield_function(&out) <= 1e-12 * scale.max(1.0));
        prop_assert!(dgamma >= 0.0);
    }

    #[test]
    fn elastic_loading_below_yield_is_reversible(
        lv in prop::array::uniform6(-2e-4f64..2e-4),
        p in 2e3f64..1e4,
    ) {
        // A symmetric velocity gradient (no spin) applied for 1 s and then reversed,
        // from an isotropic compression p, with both states inside the cone.
        let m = sand();
        let sig = Matrix3::identity() * -p;
        let l = symmetric(lv);
        let up = m.update(&sig, &l, 1.0);
        prop_assume!(m.yield_function(&up.stress) < 0.0);
        prop_assert_eq!(up.plastic_strain, 0.0);
        let back = m.update(&up.stress, &(-l), 1.0);
        prop_assert!(close(&back.stress, &sig, 1e-12), "{} vs {}", back.stress, sig);
    }
}

/// Mohr–Coulomb stress states on the failure line, built from the mechanics (not from the
/// crate's coefficients), lie on the cone of the match made for them.
mod cone_match {
    use super::*;
    use elastoplastic_granular::ConeMatch;

    const P: f64 = 1.0e4; // mean compressive stress (Pa)

    fn matched(phi: f64, c: f64, m: ConeMatch) -> DruckerPrager<f64> {
        DruckerPrager::matched(E, NU, phi, 0.0, c, m)
    }

    /// Simple shear on the x–y planes with equal normal stresses `σ_n = P` and
    /// `τ = c + P tan φ`: Coulomb's law at failure on the slip planes.
    #[test]
    fn simple_shear_at_coulomb_failure_is_on_the_simple_shear_cone() {
        for (phi, c) in [(20.0, 0.0), (30.0, 0.0), (40.0, 0.0), (30.0, 500.0)] {
            let tau = c + P * f64::to_radians(phi).tan();
            let sig = Matrix3::new(-P, tau, 0.0, tau, -P, 0.0, 0.0, 0.0, -P);
            let f = matched(phi, c, ConeMatch::SimpleShear).yield_function(&sig);
            assert!(f.abs() < 1e-9 * P, "phi {phi}, c {c}: f = {f}");
        }
    }

    /// Plane strain at zero dilatancy: `σ_zz` the mean of the in-plane principal stresses,
    /// the Mohr circle of centre `P` tangent to `τ = c + σ tan φ` (radius `P sin φ + c cos φ`).
    #[test]
    fn a_mohr_circle_tangent_to_the_coulomb_line_is_on_the_plane_strain_cone() {
        for (phi, c) in [(20.0, 0.0), (30.0, 0.0), (40.0, 0.0), (30.0, 500.0)] {
            let a = f64::to_radians(phi);
            let r = P * a.sin() + c * a.cos();
            let sig = Matrix3::new(-P + r, 0.0, 0.0, 0.0, -P - r, 0.0, 0.0, 0.0, -P);
            let f = matched(phi, c, ConeMatch::PlaneStrain).yield_function(&sig);
            assert!(f.abs() < 1e-9 * P, "phi {phi}, c {c}: f = {f}");
        }
    }

    /// The repose angles of the match table, from `tan β = 3 α_φ` written out per match
    /// (Bui et al. 2008's `α_φ`, `sin φ / 3`, `tan φ / 3`).
    #[test]
    fn predicted_repose_angles_are_the_tables() {
        let cases = [
            (ConeMatch::PlaneStrainAssociated, [18.5, 25.7, 31.1]),
            (ConeMatch::PlaneStrain, [18.9, 26.6, 32.7]),
            (ConeMatch::SimpleShear, [20.0, 30.0, 40.0]),
        ];
        for (m, expected) in cases {
            for (phi, want) in [20.0, 30.0, 40.0].into_iter().zip(expected) {
                let got = m.predicted_repose_angle_deg(phi);
                // the table is rounded to 0.1°
                assert!((got - want).abs() < 0.05, "{m:?} {phi}: {got}");
            }
        }
        assert_eq!(
            ConeMatch::PlaneStrainAssociated.alpha_phi(30.0),
            plane_strain_alpha(30.0)
        );
        // a settled wedge of the default match holds to asin(3 α_φ) = 28.71° at φ = 30°
        // (docs/elastoplastic-granular.md, the wedge runs)
        let m = ConeMatch::PlaneStrainAssociated.max_stable_slope_deg(30.0);
        assert!((m - 28.71).abs() < 0.01, "{m}");
    }

    /// θ = 0 without cohesion: a granular liquid; tension and deviator are removed.
    #[test]
    fn a_frictionless_cohesionless_material_carries_no_tension_and_no_shear() {
        let m = matched(0.0, 0.0, ConeMatch::SimpleShear);
        let sig = Matrix3::new(200.0, 50.0, 0.0, 50.0, -100.0, 0.0, 0.0, 0.0, 10.0);
        let (out, _) = m.return_to_cone(&sig);
        assert!(out.abs().max() < 1e-12, "{out}");
        let compressed = Matrix3::new(-300.0, 50.0, 0.0, 50.0, -100.0, 0.0, 0.0, 0.0, -200.0);
        let (out, _) = m.return_to_cone(&compressed);
        let want = Matrix3::identity() * -200.0;
        assert!(close(&out, &want, 1e-12), "{out}");
    }
}
