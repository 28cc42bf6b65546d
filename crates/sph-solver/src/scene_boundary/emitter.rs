//! The pour's emitter: grains added during a run, as the funnel method forms a heap (a
//! funnel held just above the growing heap's top, e.g. ISO 4324:1977 and ASTM C1444-00), a
//! layer of grains at a time. [`FrameSolver`](crate::FrameSolver) steps it at the start of
//! each frame (as SPlisHSPlasH steps its emitters before the time step) and hands the new
//! particles to its scheme ([`SubstepScheme::init_emitted`](crate::SubstepScheme::init_emitted)),
//! which readies what it carries per particle for them.
//!
//! A [`Pour`] is a box, the funnel: each layer is one grain at each node of the particle
//! lattice over the box's horizontal face (`x`, `z` at half a spacing from its faces, as
//! `sph_core::sampling::cubic_lattice` fills a box), at rest, one spacing above the highest
//! grain under it that has landed (slower than `√(g s)`, the speed of a fall of half a
//! spacing), and at least half a spacing above the box's floor. A layer is placed no sooner
//! than [`FALL_OVER_LANDING_TIME`] × `√(s/g)` after the one before it: a grain released at
//! rest falls slower than `√(g s)` for its first `√(s/g)` seconds (36 ms at 12.5 mm), and a
//! layer placed sooner would take the one before it, still in the air, for the heap's top,
//! a spacing above it, and so on up to the funnel's top, from where every layer would drop
//! (a 12.5 mm pour at one layer per 31 ms did that). Layers fall due at the
//! pour's rate (bulk volume: grains × spacing³); one is placed at the start of a frame when
//! no grain is nearer than [`ROOM_OVER_SPACING`] spacings to any of its grains, otherwise
//! it waits for the next frame (the pour then runs late). Each layer is shifted across
//! gravity by [`Pour::layer_shift`] (alternate layers a quarter spacing either way along `x`,
//! or a seeded random shift of up to half a spacing along `x` and `z`; along `x` only for a
//! layer one node deep along a non-periodic `z`, a planar run's), so that a narrow pour
//! does not stack its grains in columns. Gravity must point along `−y` ([`Pour::validate`]).

use sph_core::{ParticleSet, Real, Vec3};

use super::{PeriodicAxis, Pour};
use crate::SolverError;

/// The room a new grain needs: no grain nearer than this many spacings.
pub const ROOM_OVER_SPACING: f64 = 0.9;

/// The shortest time between two layers over `√(s/g)`, the time a grain released at rest
/// takes to reach the landed speed `√(g s)`: a layer that has fallen this long is either
/// faster than the landed speed or has landed. The 10 % is a margin for the steps' rounding.
pub const FALL_OVER_LANDING_TIME: f64 = 1.1;

/// A pour under way, the emitter the frame shell steps: its layer's nodes, its schedule
/// and how far it has got.
#[derive(Debug, Clone)]
pub struct PourEmitter {
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
    /// The shortest time between two layers (s): [`FALL_OVER_LANDING_TIME`] `√(s/g)`.
    min_interval_s: f64,
    /// When the last layer was placed (s from the run's start), in the particles'
    /// precision as a checkpoint keeps it; `None` before the first.
    last_layer_s: Option<f64>,
    /// The periodic axes: (axis, period).
    periodic: Vec<(usize, f64)>,
    /// The layer is one node deep along a non-periodic `z` (a planar run's pour): its
    /// grains stay in that plane, unshifted along `z`.
    planar: bool,
    /// Layers placed so far.
    poured: usize,
    /// The pour (its layers' shifts).
    pour: Pour<f64>,
}

impl PourEmitter {
    /// The pour `p` at spacing `s` (m) under gravity `g` (m/s², its magnitude), with the
    /// solver's periodic axes.
    pub fn new<R: Real>(p: &Pour<R>, s: f64, g: f64, periodic: &[PeriodicAxis<R>]) -> Self {
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
            min_interval_s: FALL_OVER_LANDING_TIME * (s / g).sqrt(),
            last_layer_s: None,
            periodic: periodic
                .iter()
                .map(|a| (a.axis, a.period().as_f64()))
                .collect(),
            planar: nz == 1 && !periodic.iter().any(|a| a.axis == 2),
            poured: 0,
            pour: Pour {
                region: sph_core::Aabb { min: lo, max: hi },
                volume_m3: p.volume_m3.as_f64(),
                rate_m3_s: p.rate_m3_s.as_f64(),
                seed: p.seed,
            },
        }
    }

    /// Layers in all.
    pub fn layers(&self) -> usize {
        self.layers
    }

    /// Layers placed so far.
    pub fn poured(&self) -> usize {
        self.poured
    }

    /// The layers placed by a checkpoint's `poured` (its value as saved) for a state of
    /// `particles` particles: a whole number in `[0, layers]` whose grains the particles
    /// hold, otherwise [`SolverError::InvalidSolverState`] naming `solver`.
    pub fn check_poured(
        &self,
        solver: &'static str,
        poured: f64,
        particles: usize,
    ) -> Result<usize, SolverError> {
        let layers = self.layers;
        if !(poured >= 0.0 && poured <= layers as f64 && poured.fract() == 0.0)
            || poured as usize * self.grains_per_layer() > particles
        {
            return Err(SolverError::InvalidSolverState {
                solver: solver.to_owned(),
                reason: format!(
                    "the pour's layers placed ({poured}) must be a whole number in [0, {layers}] whose grains the {particles} particles hold"
                ),
            });
        }
        Ok(poured as usize)
    }

    /// Sets the layers placed so far (a value [`PourEmitter::check_poured`] returned).
    pub fn set_poured(&mut self, poured: usize) {
        self.poured = poured.min(self.layers);
    }

    /// When the last layer was placed (s from the run's start; `None` before the first):
    /// what a checkpoint keeps besides [`PourEmitter::poured`].
    pub fn last_layer_s(&self) -> Option<f64> {
        self.last_layer_s
    }

    /// Sets when the last layer was placed (a checkpoint's value; `None`: no layer yet, or
    /// a checkpoint that did not keep it, which lets the next layer fall due at once).
    pub fn set_last_layer_s(&mut self, t: Option<f64>) {
        self.last_layer_s = t.filter(|t| t.is_finite());
    }

    /// Grains per layer.
    pub fn grains_per_layer(&self) -> usize {
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

    /// The next layer's grains (positions), or `None` while a grain is in its way. Errors
    /// (naming `solver`): the heap has reached the funnel's top.
    pub fn next_layer<R: Real>(
        &self,
        solver: &'static str,
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
                solver: solver.to_owned(),
                reason: format!(
                    "the poured heap reached the pour's top (y = {} m) after {} of {} layers: raise the pour's box or pour less",
                    self.top_y, self.poured, self.layers
                ),
            });
        }
        let [dx, dz] = self.pour.layer_shift(self.poured, s);
        let dz = if self.planar { 0.0 } else { dz };
        let layer: Vec<[f64; 3]> = self
            .nodes
            .iter()
            .map(|[nx, nz]| [nx + dx, y, nz + dz])
            .collect();
        Ok(self.has_room(&layer, x).then_some(layer))
    }

    /// Whether no grain of `x` is nearer than [`ROOM_OVER_SPACING`] spacings to a grain of
    /// `layer`: the grains within a spacing of the layer's box first, then their distances.
    pub fn has_room<R: Real>(&self, layer: &[[f64; 3]], x: &[Vec3<R>]) -> bool {
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
    /// at rest with `mass` and `density`, after the particles of `state`; returns how many
    /// grains were added. Errors (naming `solver`): the heap reached the funnel's top, or
    /// memory for a layer could not be had.
    pub fn emit<R: Real>(
        &mut self,
        solver: &'static str,
        time_s: f64,
        state: &mut ParticleSet<R>,
        mass: R,
        density: R,
    ) -> Result<usize, SolverError> {
        let due = ((self.layers_per_s * time_s + 1e-9).floor().max(0.0) as usize).min(self.layers);
        let mut added = 0;
        while self.poured < due
            && self
                .last_layer_s
                .is_none_or(|t| time_s >= t + self.min_interval_s)
        {
            let Some(layer) = self.next_layer(solver, &state.positions, &state.velocities)? else {
                break;
            };
            state
                .try_reserve(layer.len())
                .map_err(|e| SolverError::InvalidSolverState {
                    solver: solver.to_owned(),
                    reason: format!(
                        "no memory for a poured layer of {} grains: {e}",
                        layer.len()
                    ),
                })?;
            for p in &layer {
                let x = Vec3::new(R::of_f64(p[0]), R::of_f64(p[1]), R::of_f64(p[2]));
                state.push(x, Vec3::zeros(), mass, density);
            }
            self.last_layer_s = Some(R::of_f64(time_s).as_f64());
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
    use sph_core::Aabb;

    fn pouring(periodic_z: bool) -> PourEmitter {
        let pour = Pour {
            region: Aabb {
                min: Vec3::new(0.5, 0.0, 0.0),
                max: Vec3::new(0.6, 1.0, 0.06),
            },
            volume_m3: 0.001,
            rate_m3_s: 0.0001,
            seed: None,
        };
        let axes = [PeriodicAxis {
            axis: 2,
            lo: 0.0,
            hi: 0.06,
        }];
        PourEmitter::new(&pour, 0.02, 9.81, if periodic_z { &axes[..] } else { &[] })
    }

    /// A pour whose layers fall due faster than a released layer reaches the landed speed
    /// (one each 10 ms against `√(s/g)` = 45 ms at 2 cm) places each layer one spacing above the grains that
    /// have landed, never above a layer still in the air. The grains here fall freely onto a
    /// flat bed (a grain lands, and stops, a spacing above the highest landed grain, or on
    /// the pour's floor): the ground truth of "landed" is the model's, not the emitter's.
    #[test]
    fn a_fast_pour_stacks_no_layer_in_the_air() {
        let s = 0.02;
        let g = 9.81;
        let pour = Pour {
            region: Aabb {
                min: Vec3::new(0.5, 0.0, 0.0),
                max: Vec3::new(0.6, 1.0, 0.06),
            },
            volume_m3: 20.0 * 15.0 * s * s * s,
            rate_m3_s: 15.0 * s * s * s / 0.01,
            seed: None,
        };
        let mut e = PourEmitter::new(&pour, s, g, &[]);
        let mut state = ParticleSet::<f64>::new();
        let mut landed: Vec<bool> = Vec::new();
        let (frame_s, dt) = (0.016, 1e-4);
        for frame in 0..200 {
            let bed = |state: &ParticleSet<f64>, landed: &[bool]| {
                state
                    .positions
                    .iter()
                    .zip(landed)
                    .filter(|(_, &l)| l)
                    .map(|(p, _)| p.y)
                    .fold(f64::NEG_INFINITY, f64::max)
            };
            let top = bed(&state, &landed);
            let first = state.len();
            e.emit("test", frame as f64 * frame_s, &mut state, 1.0, 1.0)
                .unwrap();
            landed.resize(state.len(), false);
            for p in &state.positions[first..] {
                let highest = (top + s).max(0.5 * s);
                assert!(
                    p.y <= highest + 1e-12,
                    "frame {frame}: a layer at {} m, above the landed grains' {top} m + s",
                    p.y
                );
            }
            for _ in 0..(frame_s / dt).round() as usize {
                let stop_at = (bed(&state, &landed) + s).max(0.5 * s);
                for ((x, v), l) in state
                    .positions
                    .iter_mut()
                    .zip(state.velocities.iter_mut())
                    .zip(landed.iter_mut())
                    .filter(|(_, l)| !**l)
                {
                    v.y -= g * dt;
                    x.y += v.y * dt;
                    if x.y <= stop_at {
                        (x.y, *v, *l) = (stop_at, Vec3::zeros(), true);
                    }
                }
            }
        }
        assert_eq!(
            e.poured(),
            e.layers(),
            "the pour ends (late, paced by the falls)"
        );
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
