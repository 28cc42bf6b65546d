//! Summary statistics of the experiments' figures and timings, said once.
//!
//! **Median**: of the finite values sorted ascending, `x₍ₖ₊₁₎` for an odd count `n = 2k + 1`
//! and the mean of the two middle values `(x₍ₖ₎ + x₍ₖ₊₁₎)/2` for an even count `n = 2k`; NaN
//! when there is no finite value. Non-finite values (a particle no longer integrated, an
//! overflowed error) are left out, not sorted to an end. Wall-clock samples are summarised
//! by their median because preemption on a shared machine only adds time (one-sided noise).
//!
//! **Ensembles** (results that scatter from run to run, e.g. poured heaps of different seeds):
//! the mean `x̄ = Σxᵢ/n`, the sample standard deviation `s = √(Σ(xᵢ − x̄)²/(n − 1))`, and, for
//! groups assumed to share one variance (pours of different cases of one model, at one
//! spacing), the pooled deviation `s_p = √(Σ_g Σ_i (x_gi − x̄_g)² / Σ_g (n_g − 1))` with
//! `Σ_g (n_g − 1)` degrees of freedom. A mean's standard error is `s/√n`; the two-sided
//! 95 % band of a mean or of a difference of two means is `t_{0.975, ν} × SE`
//! ([`t_quantile`], Student's t with `ν` degrees of freedom, from `statrs`). A check that a
//! mean lies within `b` of a value catches a true offset `Δ` with probability
//! `Φ((|Δ| − b)/SE)`: 80 % at `|Δ| = b + 0.84 SE` ([`shift_caught_80`]), its power.

/// The median of the finite values of `values` (definition in the module documentation).
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_unstable_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The spread `max − min` of the finite values of `values`; NaN when there is none.
pub fn spread(values: &[f64]) -> f64 {
    let finite = values.iter().copied().filter(|x| x.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    if lo <= hi {
        hi - lo
    } else {
        f64::NAN
    }
}

/// The mean of the finite values of `values`; NaN when there is none.
pub fn mean(values: &[f64]) -> f64 {
    let finite: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if finite.is_empty() {
        return f64::NAN;
    }
    finite.iter().sum::<f64>() / finite.len() as f64
}

/// The sum of squared deviations from their mean of the finite values of `values`, and
/// their count.
fn squared_deviations(values: &[f64]) -> (f64, usize) {
    let m = mean(values);
    let finite = values.iter().copied().filter(|x| x.is_finite());
    finite.fold((0.0, 0), |(ss, n), x| (ss + (x - m) * (x - m), n + 1))
}

/// The sample standard deviation of the finite values of `values` (`n − 1` in the
/// denominator); NaN for fewer than two.
pub fn sample_sd(values: &[f64]) -> f64 {
    match squared_deviations(values) {
        (_, n) if n < 2 => f64::NAN,
        (ss, n) => (ss / (n - 1) as f64).sqrt(),
    }
}

/// The pooled standard deviation of `groups` (each group's deviations from its own mean)
/// and its degrees of freedom `Σ (n_g − 1)`; NaN and 0 when no group has two values.
pub fn pooled_sd<'a>(groups: impl IntoIterator<Item = &'a [f64]>) -> (f64, usize) {
    let (ss, dof) = groups
        .into_iter()
        .map(squared_deviations)
        .filter(|&(_, n)| n >= 2)
        .fold((0.0, 0), |(ss, dof), (s, n)| (ss + s, dof + n - 1));
    if dof == 0 {
        (f64::NAN, 0)
    } else {
        ((ss / dof as f64).sqrt(), dof)
    }
}

/// The `p` quantile of Student's t distribution with `dof` degrees of freedom; NaN for no
/// degree of freedom or `p` outside (0, 1).
pub fn t_quantile(p: f64, dof: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    match StudentsT::new(0.0, 1.0, dof as f64) {
        Ok(t) if dof > 0 && p > 0.0 && p < 1.0 => t.inverse_cdf(p),
        _ => f64::NAN,
    }
}

/// The standard normal quantile of 0.8 (`Φ⁻¹(0.8)`).
pub const Z_80: f64 = 0.841_621_233_572_914_3;

/// The true offset a check of a mean within `band` catches with probability 80 %, its
/// power: `band + Φ⁻¹(0.8) × se` (module documentation).
pub fn shift_caught_80(band: f64, se: f64) -> f64 {
    band + Z_80 * se
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_odd_is_the_middle_value() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[5.0]), 5.0);
    }

    #[test]
    fn median_even_is_the_mean_of_the_two_middle_values() {
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&[1.0, 2.0]), 1.5);
    }

    #[test]
    fn median_leaves_out_non_finite_values() {
        assert_eq!(median(&[f64::NAN, 1.0, f64::INFINITY, 3.0, 2.0]), 2.0);
        assert!(median(&[]).is_nan());
        assert!(median(&[f64::NAN, f64::NEG_INFINITY]).is_nan());
    }

    #[test]
    fn spread_is_max_minus_min() {
        assert_eq!(spread(&[2.0, -1.0, 5.0, f64::NAN]), 6.0);
        assert_eq!(spread(&[7.0]), 0.0);
        assert!(spread(&[]).is_nan());
    }

    #[test]
    fn mean_and_sample_sd_by_hand() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, squared deviations 32, s = sqrt(32/7).
        let x = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        assert_eq!(mean(&x), 5.0);
        assert!((sample_sd(&x) - (32.0f64 / 7.0).sqrt()).abs() < 1e-15);
        assert!(sample_sd(&[3.0]).is_nan());
        assert!(mean(&[]).is_nan());
    }

    #[test]
    fn pooled_sd_uses_each_groups_own_mean() {
        // Groups {1, 3} (ss 2) and {10, 14, 12} (ss 8): s_p = sqrt(10/3), 3 degrees of freedom.
        let a = [1.0, 3.0];
        let b = [10.0, 14.0, 12.0];
        let (sd, dof) = pooled_sd([&a[..], &b[..], &[5.0][..]]);
        assert_eq!(dof, 3);
        assert!((sd - (10.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!(pooled_sd([&[1.0][..]]).0.is_nan());
    }

    #[test]
    fn t_quantiles_match_the_tables() {
        // Student's t table (two-sided 95 %): 12.706 (1), 2.776 (4), 2.228 (10), 2.042 (30).
        for (dof, t) in [(1, 12.706), (4, 2.776), (10, 2.228), (30, 2.042)] {
            assert!((t_quantile(0.975, dof) - t).abs() < 5e-4, "dof {dof}");
        }
        assert!(t_quantile(0.975, 0).is_nan());
        assert!((shift_caught_80(1.0, 1.0) - 1.8416).abs() < 1e-4);
    }
}
