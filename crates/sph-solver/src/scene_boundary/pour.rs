//! A pour as a scene states it (`[pour]`): grains added during the run, a layer at a time,
//! from a funnel's box. A solver that takes pours ([`BoundaryFeatures::pour`](super::BoundaryFeatures))
//! returns it from [`SubstepScheme::pour`](crate::SubstepScheme::pour), and the frame shell
//! places the layers ([`PourEmitter`](super::PourEmitter)).

use sph_core::{Aabb, Real, Vec3};

use crate::SolverError;

/// Most grains a pour may add (20 M, the scenes' particle bound).
pub const MAX_POURED_GRAINS: usize = 20_000_000;
/// The relative slack of "a whole number of spacings" in a pour's box: a box written as
/// `n` spacings wide is `n` spacings in `f32` too.
const NODE_SLACK: f64 = 1e-5;

/// Grains added during the run, a layer at a time: the funnel's box, and how much is poured
/// how fast. Each layer is one grain at each node of the particle lattice over the box's
/// horizontal face (`x`, `z`); gravity points along `−y`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pour<R: Real> {
    /// The funnel (m): the layers' grains lie over its horizontal face, between half a
    /// spacing above its floor and its top.
    pub region: Aabb<R>,
    /// The bulk volume poured (m³: grains × spacing³).
    pub volume_m3: R,
    /// The pour's rate (m³ of bulk volume per second).
    pub rate_m3_s: R,
    /// `Some(seed)`: each layer is shifted across gravity (along `x` and `z`) by a uniform
    /// random fraction of a spacing in `[−s/2, s/2)`, drawn from the seed and the layer's
    /// number (SplitMix64, no state: a resumed run repeats its layers), so that pours of
    /// different seeds form different heaps of the same material (an ensemble of pours, as
    /// an experimenter repeats one); `None`: alternate layers shifted a quarter spacing
    /// either way along `x`.
    pub seed: Option<u64>,
}

/// SplitMix64's output for `state` (Steele, Lea & Flood, "Fast splittable pseudorandom
/// number generators", OOPSLA 2014): a well-mixed 64-bit value of a counter.
fn splitmix64(state: u64) -> u64 {
    let mut z = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform value in `[0, 1)` from the 53 high bits of `bits`.
fn unit(bits: u64) -> f64 {
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

impl<R: Real> Pour<R> {
    /// The shift (m) of layer `k` (from 0) along `x` and `z` at spacing `s`: the seeded
    /// draw of [`Pour::seed`], or `∓s/4` along `x` for alternate layers without a seed.
    pub fn layer_shift(&self, k: usize, s: f64) -> [f64; 2] {
        match self.seed {
            None => [if k.is_multiple_of(2) { -0.25 } else { 0.25 } * s, 0.0],
            Some(seed) => {
                let base = splitmix64(seed ^ (k as u64).wrapping_mul(0xd1b5_4a32_d192_ed03));
                let x = unit(splitmix64(base));
                let z = unit(splitmix64(base ^ 0x2545_f491_4f6c_dd1d));
                [(x - 0.5) * s, (z - 0.5) * s]
            }
        }
    }

    /// The lattice nodes of a layer along `x` and `z` at spacing `s` (m): `⌊extent/s⌋` each,
    /// at least one when the extent is a spacing or more.
    pub fn layer_nodes(&self, s: f64) -> [usize; 2] {
        [0, 2].map(|a| {
            let extent = (self.region.max[a] - self.region.min[a]).as_f64();
            (extent / s + NODE_SLACK).floor().max(0.0) as usize
        })
    }

    /// Grains per layer at spacing `s`.
    pub fn grains_per_layer(&self, s: f64) -> usize {
        let [nx, nz] = self.layer_nodes(s);
        nx.saturating_mul(nz)
    }

    /// Layers poured in all at spacing `s`: the volume over a layer's, rounded, at least one.
    pub fn layers(&self, s: f64) -> usize {
        let layer = self.grains_per_layer(s) as f64 * s.powi(3);
        let k = (self.volume_m3.as_f64() / layer).round();
        if k.is_finite() && k >= 1.0 {
            k.min(MAX_POURED_GRAINS as f64) as usize
        } else {
            1
        }
    }

    /// Grains poured in all at spacing `s`.
    pub fn grains(&self, s: f64) -> usize {
        self.layers(s).saturating_mul(self.grains_per_layer(s))
    }

    /// The checks of a pour for `solver` (named in the error, parameter `pour`): a proper box
    /// at least a spacing `s` wide along `x` and `z` and a spacing high, a volume and a rate
    /// positive and finite, at most [`MAX_POURED_GRAINS`] grains, gravity along `−y`.
    pub fn validate(
        &self,
        solver: &'static str,
        s: f64,
        gravity: Vec3<R>,
    ) -> Result<(), SolverError> {
        let invalid = |value: f64, reason: &'static str| SolverError::InvalidParameter {
            solver,
            name: "pour",
            value,
            reason,
        };
        let (lo, hi) = (self.region.min, self.region.max);
        let finite = lo.iter().chain(hi.iter()).all(|v| v.is_finite());
        if !finite || (0..3).any(|a| (hi[a] - lo[a]).as_f64() < s * (1.0 - NODE_SLACK)) {
            return Err(invalid(
                s,
                "the pour's box needs finite corners at least a spacing (the value, m) apart on every axis",
            ));
        }
        let (v, r) = (self.volume_m3.as_f64(), self.rate_m3_s.as_f64());
        if !(v.is_finite() && v > 0.0) {
            return Err(invalid(
                v,
                "the pour's volume (m³) must be positive and finite",
            ));
        }
        if !(r.is_finite() && r > 0.0) {
            return Err(invalid(
                r,
                "the pour's rate (m³/s) must be positive and finite",
            ));
        }
        let grains = (v / s.powi(3)).round();
        if grains > MAX_POURED_GRAINS as f64 {
            return Err(invalid(
                grains,
                "a pour adds at most MAX_POURED_GRAINS = 2e7 grains (value: its volume over spacing³)",
            ));
        }
        let g = gravity.map(|c| c.as_f64());
        if !(g.y < 0.0 && g.x.abs() <= 1e-9 * g.y.abs() && g.z.abs() <= 1e-9 * g.y.abs()) {
            return Err(invalid(
                g.y,
                "a pour needs gravity along −y (value: its y component)",
            ));
        }
        Ok(())
    }
}
