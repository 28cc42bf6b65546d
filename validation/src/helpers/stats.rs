//! Summary statistics of the experiments' figures and timings, said once.
//!
//! **Median**: of the finite values sorted ascending, `x₍ₖ₊₁₎` for an odd count `n = 2k + 1`
//! and the mean of the two middle values `(x₍ₖ₎ + x₍ₖ₊₁₎)/2` for an even count `n = 2k`; NaN
//! when there is no finite value. Non-finite values (a particle no longer integrated, an
//! overflowed error) are left out, not sorted to an end. Wall-clock samples are summarised
//! by their median because preemption on a shared machine only adds time (one-sided noise).

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
}
