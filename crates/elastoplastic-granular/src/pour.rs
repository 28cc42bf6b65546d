//! Grains poured during a run: a heap formed as the funnel method forms it (a funnel held
//! just above the growing heap's top, e.g. ISO 4324:1977 and ASTM C1444-00), a layer of
//! grains at a time.
//!
//! A [`Pour`] is a box, the funnel: each layer is one grain at each node of the particle
//! lattice over the box's horizontal face (`x`, `z` at half a spacing from its faces, as
//! [`crate::cubic_lattice`] fills a box), at rest and unstressed, one spacing above the
//! highest grain under it that has landed (slower than `√(g s)`, the speed of a fall of
//! half a spacing), and at least half a spacing above the box's floor. Layers fall due at
//! the pour's rate (bulk volume: grains × spacing³); one is placed at the start of a frame
//! when no grain is nearer than [`ROOM_OVER_SPACING`] spacings to any of its grains,
//! otherwise it waits for the next frame (the pour then runs late). Alternate layers are
//! shifted a quarter spacing either way along `x`, so that a narrow pour does not stack
//! its grains in columns. Gravity must point along `−y`.
//!
//! Why a pour: a heap formed by pouring grows by surface avalanches that stop at its toe
//! (in compression), where a drained heap's flanks form while they flow out (in extension);
//! with a Drucker–Prager cone the two stand at different angles
//! (`docs/elastoplastic-granular.md`, run 40).

use sph_core::{Aabb, ParticleSet, Real, Vec3};
use sph_solver::SolverError;

use crate::periodic::PeriodicAxis;
use crate::solver::NAME;

/// The room a new grain needs: no grain nearer than this many spacings.
pub const ROOM_OVER_SPACING: f64 = 0.9;
/// Most grains a pour may add (20 M, the scenes' particle bound).
pub const MAX_POURED_GRAINS: usize = 20_000_000;
/// The relative slack of "a whole number of spacings" in a pour's box: a box written as
/// `n` spacings wide is `n` spacings in `f32` too.
const NODE_SLACK: f64 = 1e-5;

/// Grains added during the run, a layer at a time (see the module documentation): the
/// funnel's box, and how much is poured how fast.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pour<R: Real> {
    /// The funnel (m): the layers' grains lie over its horizontal face, between half a
    /// spacing above its floor and its top.
    pub region: Aabb<R>,
    /// The bulk volume poured (m³: grains × spacing³).
    pub volume_m3: R,
    /// The pour's rate (m³ of bulk volume per second).
    pub rate_m3_s: R,
}

impl<R: Real> Pour<R> {
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

    /// The checks of [`crate::ElastoplasticParams::validate`]: a proper box at least a
    /// spacing wide along `x` and `z` and a spacing high, a volume and a rate positive and
    /// finite, at most [`MAX_POURED_GRAINS`] grains, gravity along `−y`.
    pub(crate) fn validate(&self, s: f64, gravity: Vec3<R>) -> Result<(), SolverError> {
        let invalid = |value: f64, reason: &'static str| SolverError::InvalidParameter {
            solver: NAME,
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

/// A pour under way: its layer's nodes, its schedule and how far it has got.
#[derive(Debug, Clone)]
pub(crate) struct Pouring {
    /// The layer's nodes (`x`, `z`), unshifted.
    nodes: Vec<[f64; 2]>,
    /// The layer's centre and half extents along `x` and `z` (m).
    centre: [f64; 2],
    half: [f64; 2],
    floor_y: f64,
    top_y: f64,
    spacing: f64,
    layers: usize,
    layers_per_s: f64,
    landed_speed: f64,
    /// The periodic axes: (axis, period).
    periodic: Vec<(usize, f64)>,
    /// Layers placed so far.
    pub(crate) poured: usize,
}

impl Pouring {
    /// The pour `p` at spacing `s` under gravity `g` (m/s², its magnitude), with the
    /// solver's periodic axes.
    pub(crate) fn new<R: Real>(p: &Pour<R>, s: f64, g: f64, periodic: &[PeriodicAxis<R>]) -> Self {
        let [nx, nz] = p.layer_nodes(s);
        let (lo, hi) = (
            p.region.min.map(|c| c.as_f64()),
            p.region.max.map(|c| c.as_f64()),
        );
        let nodes = (0..nz)
            .flat_map(|k| (0..nx).map(move |i| [i, k]))
            .map(|[i, k]| [lo.x + (i as f64 + 0.5) * s, lo.z + (k as f64 + 0.5) * s])
            .collect();
        let layer = (nx * nz) as f64 * s.powi(3);
        Self {
            nodes,
            centre: [0.5 * (lo.x + hi.x), 0.5 * (lo.z + hi.z)],
            half: [0.5 * nx as f64 * s, 0.5 * nz as f64 * s],
            floor_y: lo.y + 0.5 * s,
            top_y: hi.y,
            spacing: s,
            layers: p.layers(s),
            layers_per_s: p.rate_m3_s.as_f64() / layer,
            landed_speed: (g * s).sqrt(),
            periodic: periodic
                .iter()
                .map(|a| (a.axis, a.period().as_f64()))
                .collect(),
            poured: 0,
        }
    }

    /// Layers in all.
    pub(crate) fn layers(&self) -> usize {
        self.layers
    }

    /// Grains per layer.
    pub(crate) fn grains_per_layer(&self) -> usize {
        self.nodes.len()
    }

    /// `d` with each periodic component wrapped into `[−period/2, period/2]`.
    fn min_image(&self, mut d: [f64; 3]) -> [f64; 3] {
        for &(a, period) in &self.periodic {
            d[a] -= period * (d[a] / period).round();
        }
        d
    }

    /// The offset of `p` from the layer's centre (height from 0), periodic axes wrapped.
    fn offset_from_centre<R: Real>(&self, p: &Vec3<R>) -> [f64; 3] {
        self.min_image([
            p.x.as_f64() - self.centre[0],
            p.y.as_f64(),
            p.z.as_f64() - self.centre[1],
        ])
    }

    /// The next layer's grains (positions), or `None` while a grain is in its way. Errors:
    /// the heap has reached the funnel's top.
    pub(crate) fn next_layer<R: Real>(
        &self,
        x: &[Vec3<R>],
        v: &[Vec3<R>],
    ) -> Result<Option<Vec<[f64; 3]>>, SolverError> {
        let s = self.spacing;
        let under = |d: &[f64; 3]| {
            d[0].abs() <= self.half[0] + 1.5 * s && d[2].abs() <= self.half[1] + 1.5 * s
        };
        let landed = (self.landed_speed * self.landed_speed).max(0.0);
        let top = x
            .iter()
            .zip(v)
            .filter(|(_, u)| u.norm_squared().as_f64() < landed)
            .map(|(p, _)| self.offset_from_centre(p))
            .filter(under)
            .map(|d| d[1])
            .fold(f64::NEG_INFINITY, f64::max);
        let y = (top + s).max(self.floor_y);
        if y > self.top_y {
            return Err(SolverError::InvalidSolverState {
                solver: NAME.to_owned(),
                reason: format!(
                    "the poured heap reached the pour's top (y = {} m) after {} of {} layers: raise the pour's box or pour less",
                    self.top_y, self.poured, self.layers
                ),
            });
        }
        let shift = if self.poured.is_multiple_of(2) {
            -0.25
        } else {
            0.25
        } * s;
        let layer: Vec<[f64; 3]> = self
            .nodes
            .iter()
            .map(|[nx, nz]| [nx + shift, y, *nz])
            .collect();
        Ok(self.has_room(&layer, x).then_some(layer))
    }

    /// Whether no grain of `x` is nearer than [`ROOM_OVER_SPACING`] spacings to a grain of
    /// `layer`: the grains within a spacing of the layer's box first, then their distances.
    pub(crate) fn has_room<R: Real>(&self, layer: &[[f64; 3]], x: &[Vec3<R>]) -> bool {
        let s = self.spacing;
        let room2 = (ROOM_OVER_SPACING * s).powi(2);
        let y = layer.first().map_or(0.0, |p| p[1]);
        x.iter().all(|p| {
            let d = self.offset_from_centre(p);
            let near = d[0].abs() <= self.half[0] + 1.5 * s
                && d[2].abs() <= self.half[1] + 1.5 * s
                && (d[1] - y).abs() <= s;
            !near
                || layer.iter().all(|q| {
                    let e = self.min_image([
                        p.x.as_f64() - q[0],
                        p.y.as_f64() - q[1],
                        p.z.as_f64() - q[2],
                    ]);
                    e[0] * e[0] + e[1] * e[1] + e[2] * e[2] >= room2
                })
        })
    }

    /// Places the layers due by `time_s` (s from the run's start) that have room, each grain
    /// at rest with `mass` and `density`; returns how many grains were added. Errors: the
    /// heap reached the funnel's top, or memory for a layer could not be had.
    pub(crate) fn pour<R: Real>(
        &mut self,
        time_s: f64,
        state: &mut ParticleSet<R>,
        mass: R,
        density: R,
    ) -> Result<usize, SolverError> {
        let due = ((self.layers_per_s * time_s + 1e-9).floor().max(0.0) as usize).min(self.layers);
        let mut added = 0;
        while self.poured < due {
            let Some(layer) = self.next_layer(&state.positions, &state.velocities)? else {
                break;
            };
            state
                .try_reserve(layer.len())
                .map_err(|e| SolverError::InvalidSolverState {
                    solver: NAME.to_owned(),
                    reason: format!(
                        "no memory for a poured layer of {} grains: {e}",
                        layer.len()
                    ),
                })?;
            for p in &layer {
                let x = Vec3::new(R::of_f64(p[0]), R::of_f64(p[1]), R::of_f64(p[2]));
                state.push(x, Vec3::zeros(), mass, density);
            }
            added += layer.len();
            self.poured += 1;
        }
        Ok(added)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pouring(periodic_z: bool) -> Pouring {
        let pour = Pour {
            region: Aabb {
                min: Vec3::new(0.5, 0.0, 0.0),
                max: Vec3::new(0.6, 1.0, 0.06),
            },
            volume_m3: 0.001,
            rate_m3_s: 0.0001,
        };
        let axes = [PeriodicAxis {
            axis: 2,
            lo: 0.0,
            hi: 0.06,
        }];
        Pouring::new(&pour, 0.02, 9.81, if periodic_z { &axes[..] } else { &[] })
    }

    proptest! {
        /// The room test against the naive one: every grain against every new grain.
        #[test]
        fn room_matches_all_pairs(
            grains in prop::collection::vec((0.3f64..0.8, 0.0f64..0.2, -0.1f64..0.16), 0..60),
            y in 0.01f64..0.2,
            periodic in any::<bool>(),
        ) {
            let p = pouring(periodic);
            let x: Vec<Vec3<f64>> = grains.iter().map(|&(a, b, c)| Vec3::new(a, b, c)).collect();
            let layer: Vec<[f64; 3]> = p.nodes.iter().map(|[a, c]| [*a, y, *c]).collect();
            let naive = x.iter().all(|g| layer.iter().all(|q| {
                let e = p.min_image([g.x - q[0], g.y - q[1], g.z - q[2]]);
                (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() >= ROOM_OVER_SPACING * 0.02
            }));
            prop_assert_eq!(p.has_room(&layer, &x), naive);
        }
    }
}
