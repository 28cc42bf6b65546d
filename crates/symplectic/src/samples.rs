//! Seeded sample populations, shared by the throughput example, the `comet-population`
//! experiment and the tests, so that every code compared runs the same orbits.

use crate::kepler::ConicElements;

/// Ranges (AU, radians) of a sample population; every element is drawn uniformly in its
/// range, the angles `Ω`, `ω`, `M` uniformly in `[0, 2π)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleRanges {
    /// Perihelion distance range, or `None` to draw it from the semi-major axis and
    /// eccentricity.
    pub perihelion: Option<(f64, f64)>,
    /// Semi-major axis range.
    pub semi_major_axis: (f64, f64),
    /// Eccentricity range (used when `perihelion` is `None`).
    pub eccentricity: (f64, f64),
    /// Inclination range.
    pub inclination: (f64, f64),
}

/// The population of the throughput test: perihelia 32–40 AU, semi-major axes
/// 40–100 AU, inclinations 0–30°, random angles (scattered-disk-like comets that stay in the
/// validity domain of `B₁ = 0.21·10⁻⁶`).
pub const SCATTERED_DISK: SampleRanges = SampleRanges {
    perihelion: Some((32.0, 40.0)),
    semi_major_axis: (40.0, 100.0),
    eccentricity: (0.0, 0.0),
    inclination: (0.0, 30.0 * std::f64::consts::PI / 180.0),
};

/// Near-circular orbits between and beyond the giant planets, as in Holman & Wisdom (1993,
/// AJ 105, 1987) and Gladman & Duncan (1990, AJ 100, 1680): `a` 20–50 AU, `e < 0.01`,
/// `i < 1°`.
pub const NEAR_CIRCULAR: SampleRanges = SampleRanges {
    perihelion: None,
    semi_major_axis: (20.0, 50.0),
    eccentricity: (0.0, 0.01),
    inclination: (0.0, std::f64::consts::PI / 180.0),
};

/// Centaurs among the giant planets: `a` 5.5–30 AU, `e` 0–0.2, `i` 0–10°, random angles
/// (the population of the Centaur throughput and validation runs).
pub const CENTAURS: SampleRanges = SampleRanges {
    perihelion: None,
    semi_major_axis: (5.5, 30.0),
    eccentricity: (0.0, 0.2),
    inclination: (0.0, 10.0 * std::f64::consts::PI / 180.0),
};

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, fully specified generator, so that the
/// samples are the same on every platform and in the Python driver of the peer code.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` (53 bits).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    fn in_range(&mut self, (lo, hi): (f64, f64)) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
}

/// `n` orbits drawn from `ranges` with `seed` (draw order per particle: `a`, then `q` or `e`,
/// `i`, `Ω`, `ω`, `M`). With a perihelion range, `q` is drawn in `[q_min, min(q_max, a))`.
pub fn sample_elements(ranges: &SampleRanges, n: usize, seed: u64) -> Vec<ConicElements> {
    let mut rng = SplitMix64::new(seed);
    let tau = std::f64::consts::TAU;
    (0..n)
        .map(|_| {
            let a = rng.in_range(ranges.semi_major_axis);
            let (q, e) = match ranges.perihelion {
                Some((lo, hi)) => {
                    let q = rng.in_range((lo, hi.min(a)));
                    (q, 1.0 - q / a)
                }
                None => {
                    let e = rng.in_range(ranges.eccentricity);
                    (a * (1.0 - e), e)
                }
            };
            ConicElements {
                perihelion: q,
                eccentricity: e,
                inclination: rng.in_range(ranges.inclination),
                node: rng.in_range((0.0, tau)),
                argument_of_perihelion: rng.in_range((0.0, tau)),
                mean_anomaly: rng.in_range((0.0, tau)),
            }
        })
        .collect()
}
