//! Gauss–Legendre quadrature, the rule the workspace integrates kernels with (their
//! normalisation, the volume maps' radial integrals, the kernels' property tests).
//!
//! The `n`-point rule on `[−1, 1]` has as nodes `x_i` the roots of the Legendre polynomial
//! `P_n` and as weights `w_i = 2 / ((1 − x_i²) P_n'(x_i)²)`; it integrates every polynomial
//! of degree `≤ 2n − 1` exactly (Abramowitz & Stegun, *Handbook of Mathematical Functions*,
//! 1964, §25.4.29; Golub & Welsch, "Calculation of Gauss quadrature rules", *Math. Comp.* 23,
//! 221–230, 1969, for the theory). The roots are found by Newton's method from the
//! asymptotic guesses `cos(π (i + 3/4) / (n + 1/2))` (Abramowitz & Stegun §22.16.6), `P_n`
//! and `P_n'` by the three-term recurrence `k P_k = (2k − 1) x P_{k−1} − (k − 1) P_{k−2}`
//! and `P_n' = n (x P_n − P_{n−1}) / (x² − 1)`, to machine precision. Each root of the
//! positive half is computed once and mirrored, so the rule is exactly symmetric.

use std::f64::consts::PI;

/// The `n`-point Gauss–Legendre rule on `[−1, 1]`: `(node, weight)` pairs in ascending order
/// of the node, exact for polynomials of degree `≤ 2n − 1` (method in the module
/// documentation). `n = 0` is taken as 1. Costs `O(n²)` operations per Newton step; meant for
/// rules of up to a few hundred points, built once and reused.
///
/// ```
/// // ∫_{−1}^{1} x⁴ dx = 2/5, exact with 3 points (degree ≤ 5).
/// let rule = sph_kernels::quadrature::gauss_legendre(3);
/// let integral: f64 = rule.iter().map(|&(x, w)| w * x.powi(4)).sum();
/// assert!((integral - 0.4).abs() < 1e-15);
/// ```
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let n = n.max(1);
    // (P_n(x), P_n'(x)).
    let legendre = |x: f64| {
        let (mut p0, mut p1) = (1.0, x);
        for k in 2..=n {
            let kf = k as f64;
            let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
            p0 = p1;
            p1 = p2;
        }
        if n == 1 {
            (x, 1.0)
        } else {
            (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
        }
    };
    let mut out = vec![(0.0, 0.0); n];
    for i in 0..n.div_ceil(2) {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, dp) = legendre(x);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let (_, dp) = legendre(x);
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out[i] = (-x, w);
        out[n - 1 - i] = (x, w);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::gauss_legendre;

    /// Exact for every monomial of degree < 2n (`∫ x^k = 2/(k+1)` for even `k`, 0 for odd),
    /// and not for degree 2n (the rule's order is exactly 2n − 1).
    #[test]
    fn integrates_monomials_up_to_degree_2n_minus_1() {
        for n in 1..=20 {
            let rule = gauss_legendre(n);
            assert_eq!(rule.len(), n);
            assert!(
                rule.windows(2).all(|w| w[0].0 < w[1].0),
                "n {n}: not ascending"
            );
            let q = |deg: i32| rule.iter().map(|&(x, w)| w * x.powi(deg)).sum::<f64>();
            let exact = |deg: i32| {
                if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                }
            };
            for deg in 0..2 * n as i32 {
                // Rounding only: the rule is exact for degree < 2n; 1e-13 covers the
                // accumulated f64 error of up to 20 terms of size ≤ 2.
                assert!(
                    (q(deg) - exact(deg)).abs() < 1e-13,
                    "n {n} deg {deg}: {} vs {}",
                    q(deg),
                    exact(deg)
                );
            }
            // Degree 2n: the error is 2^(2n+1) (n!)^4 / ((2n+1) ((2n)!)^3) · (2n)! > 0
            // (Abramowitz & Stegun 25.4.29 with f^(2n) = (2n)!), far above rounding for n ≤ 8.
            if n <= 8 {
                let d = 2 * n as i32;
                assert!((q(d) - exact(d)).abs() > 1e-8, "n {n}: exact at degree {d}");
            }
        }
    }

    #[test]
    fn zero_points_is_the_one_point_rule() {
        assert_eq!(gauss_legendre(0), vec![(0.0, 2.0)]);
    }
}
