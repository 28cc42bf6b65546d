//! Eq. 13 (artificial pressure) at hand-computed points, and its unit in eq. 14.
//!
//! Planted bug these catch (planted once in `src/scorr.rs`, the tests run, the code
//! restored; 2026-11-23): the exponent `n − 1` instead of `n` fails both tests.

use std::f64::consts::PI;

use pbf::{ArtificialPressure, Pbf, PbfParams, Vec3};

/// At `r = h/2` with `|Δq| = 0.2 h`: `W(r)/W(Δq) = ((1 − 1/4)/(1 − 1/25))³ = (25/32)³
/// = 15625/32768` exactly, so `s_corr = −0.1 · (15625/32768)⁴ = −0.0051698788284564225`
/// (k = 0.1, n = 4), independent of `h`.
#[test]
fn scorr_value_at_half_h() {
    // The exact rational −0.1 · 15625⁴/32768⁴, to 17 digits.
    let expected = -0.0051698788284564225;
    assert!((-0.1 * (15625.0f64 / 32768.0).powi(4) - expected).abs() < 1e-18);
    for h in [1.0, 0.05, 3.7] {
        let a = ArtificialPressure::<f64>::new(h, 0.1, 4, 0.2).unwrap();
        let got = a.value_r2(0.25 * h * h);
        assert!(
            (got - expected).abs() <= 1e-14 * expected.abs(),
            "h = {h}: {got}"
        );
        // At |Δq| itself s_corr = −k; at and beyond h it vanishes.
        assert!((a.value_r2(0.04 * h * h) + 0.1).abs() < 1e-14);
        assert_eq!(a.value_r2(h * h), 0.0);
        assert_eq!(a.value_r2(4.0 * h * h), 0.0);
        // n = 1: linear in the kernel ratio.
        let a1 = ArtificialPressure::<f64>::new(h, 0.2, 1, 0.2).unwrap();
        assert!((a1.value_r2(0.25 * h * h) + 0.2 * 15625.0 / 32768.0).abs() < 1e-14);
    }
    let a32 = ArtificialPressure::<f32>::new(0.05, 0.1, 4, 0.2).unwrap();
    let got = a32.value_r2(0.25 * 0.05 * 0.05) as f64;
    assert!((got - expected).abs() < 1e-6 * expected.abs(), "f32: {got}");
}

/// In eq. 14 the dimensionless `s_corr` is added to `λ_i + λ_j` in units of `1/D_ref`
/// (m², see the crate docs), with `D_ref = 0.3733944911767979 / s²` at `h = 2 s`. For two
/// particles at `h/2`, switching `k` from 0 to 0.1 changes `Δp_0` by
/// `(m/ρ0) s_corr / D_ref ∇W(x0 − x1)`: a repulsion (along −x, away from x1).
#[test]
fn scorr_in_position_update() {
    let s = 0.025;
    let mut p = PbfParams::<f64>::for_spacing(s);
    let h = p.common.support_radius;
    assert!((p.reference_denominator().unwrap() * s * s - 0.3733944911767979).abs() < 1e-12);
    let m = p.particle_mass();
    let pts = vec![Vec3::zeros(), Vec3::new(0.5 * h, 0.0, 0.0)];
    let mut dp = [0.0; 2];
    for (slot, k) in [0.0, 0.1].into_iter().enumerate() {
        p.scorr_k = k;
        let mut solver = Pbf::new(p.clone(), vec![]).unwrap();
        dp[slot] = solver.evaluate_constraints(&pts, &[m, m]).unwrap().delta_p[0].x;
    }
    let grad = 45.0 / (PI * h.powi(6)) * (0.5 * h).powi(2); // |∇W(h/2)|, pointing to +x
    let scorr = -0.0051698788284564225;
    let expected = m / p.common.rest_density * scorr * (s * s / 0.3733944911767979) * grad;
    assert!(expected < 0.0);
    assert!(
        ((dp[1] - dp[0]) - expected).abs() < 1e-9 * expected.abs(),
        "{} vs {expected}",
        dp[1] - dp[0]
    );
}
