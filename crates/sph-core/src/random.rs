//! SplitMix64, the workspace's small seeded generator for reproducible point sets, jitter and
//! perturbations (no `rand` dependency; the same stream on every platform).
//!
//! G. L. Steele Jr., D. Lea and C. H. Flood, "Fast splittable pseudorandom number
//! generators", *Proc. OOPSLA 2014*, 453–472, doi:10.1145/2660193.2660195: the state advances
//! by the odd constant `γ = 0x9E3779B97F4A7C15`, and each output is the state through the
//! mixing function of Stafford's variant 13 (`z ^= z >> 30; z *= 0xBF58476D1CE4E5B9;
//! z ^= z >> 27; z *= 0x94D049BB133111EB; z ^= z >> 31`). Not for cryptography.
//!
//! `symplectic` carries its own copy of the same generator: that crate depends on none of
//! the particle crates, and its sample streams are reimplemented by peer scripts.

/// The SplitMix64 generator (see the module documentation).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from `seed` (the first output mixes `seed + γ`).
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`: the top 53 bits of [`SplitMix64::next_u64`] over `2^53`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`: `lo + (hi − lo) · unit()`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform integer in `[0, n)` (Lemire's multiply-shift, `⌊next_u64 · n / 2^64⌋`); 0 for
    /// `n = 0`.
    pub fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    /// The first outputs for seed 1234567, the published test vector of the Rosetta Code
    /// task "Pseudo-random numbers/Splitmix64" (from Vigna's reference `splitmix64.c`).
    #[test]
    fn matches_the_reference_stream() {
        let mut g = SplitMix64::new(1234567);
        let expected: [u64; 5] = [
            6457827717110365317,
            3203168211198807973,
            9817491932198370423,
            4593380528125082431,
            16408922859458223821,
        ];
        for e in expected {
            assert_eq!(g.next_u64(), e);
        }
    }

    #[test]
    fn unit_range_below_stay_in_bounds() {
        let mut g = SplitMix64::new(7);
        for _ in 0..10_000 {
            let u = g.unit();
            assert!((0.0..1.0).contains(&u));
            let r = g.range(-1.2, 0.3);
            assert!((-1.2..0.3).contains(&r));
            assert!(g.below(9) < 9);
        }
        assert_eq!(g.below(0), 0);
    }
}
