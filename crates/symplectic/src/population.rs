//! A population of test particles advanced in parallel against one shared planet ephemeris.

use std::collections::VecDeque;
use std::ops::Range;
use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::ephemeris::{BodyStates, Ephemeris, GridView};
use crate::kepler::Elements;
use crate::lanes::{self, norm, norm_squared, KickLanes, Mask, LANES, V, V3};
use crate::particles::ParticlePiece;
use crate::particles::{KickTerms, ParticleIntegrator, TestParticle};
use crate::run::ParticleStatus;
use crate::{SymplecticError, Variant, Vec3, WorkCounters};

/// When a particle of a [`Population`] is removed, checked at the end of each of its steps.
/// A rule left out (`None`) is not applied.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RemovalRules {
    /// Remove a particle inside `hill_factor` Hill radii of a planet: the Hill radius of
    /// planet `j` is `|Q_j| (m_j/3m₀)^{1/3}` with `Q_j` its heliocentric position at the
    /// particle's time. The method does not resolve planetary encounters; removal at Hill
    /// sphere entry is the standard treatment (Holman & Wisdom 1993, AJ 105, 1987). Checked
    /// at step ends: an encounter shorter than a step can be missed, as in any fixed-step
    /// integrator with this rule.
    pub hill_factor: Option<f64>,
    /// Remove a particle whose barycentric osculating perihelion is below this distance
    /// (outside the validity domain of `B₀, B₁`, condition 35 of Chegodaeva 2004).
    pub min_perihelion: Option<f64>,
    /// Remove an unbound particle (barycentric osculating energy `≥ 0`) beyond this distance
    /// from the barycentre.
    pub ejection_distance: Option<f64>,
}

impl RemovalRules {
    fn validate(&self) -> Result<(), SymplecticError> {
        for (name, value) in [
            ("hill_factor", self.hill_factor),
            ("min_perihelion", self.min_perihelion),
            ("ejection_distance", self.ejection_distance),
        ] {
            if let Some(v) = value {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(SymplecticError::InvalidParameter {
                        name,
                        value: v,
                        reason: "removal rule must be finite and >= 0",
                    });
                }
            }
        }
        Ok(())
    }
}

/// One particle of a [`Population`]: its identifier (kept through shards and merges), its
/// state and its status. A removed particle keeps its state at removal (the end of the step
/// that triggered the rule, or the start of a step that failed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PopulationMember {
    /// Identifier given by the caller (row of the particle file, say).
    pub id: u64,
    /// The particle.
    pub particle: TestParticle,
    /// Active or removed, with the reason.
    pub status: ParticleStatus,
    /// Barycentric position of the Sun at the particle's time (to turn the mixed variant's
    /// heliocentric position into a barycentric one without the ephemeris).
    pub sun_position: Vec3,
}

/// Where a [`Population`] stands after a synchronisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PopulationProgress {
    /// The synchronisation time reached: every active particle is at or after it.
    pub time: f64,
    /// Particle steps taken so far (all particles, all calls).
    pub particle_steps: u64,
    /// Particles still active.
    pub active: usize,
    /// Particles removed.
    pub removed: usize,
}

/// Default length of a synchronisation window, in planet steps.
pub const DEFAULT_WINDOW_STEPS: u32 = 256;

/// `N` test particles, each on its own clock with Emel'yanenko's variable step
/// ([`ParticleIntegrator`], either [`Variant`] and either [`Scheme`](crate::Scheme)), advanced
/// in parallel (rayon) between synchronisation times against one shared, read-only planet
/// ephemeris.
///
/// Chegodaeva (2004) integrates the particles separately from the planets so that many can
/// share one planet integration; this is that sharing. [`Population::advance_to`] cuts the
/// span into windows of [`Population::window_steps`] planet steps: the ephemeris is extended
/// once per window (sequentially, one planet step per grid point) to cover the window and
/// one more, then every active particle steps while its own time is before the window's
/// end, reading the ephemeris through [`Ephemeris::interpolate`]. A step that would need
/// planets beyond the covered span is undone and redone in the next window. Nothing is
/// scanned per particle step: the cost of a particle step does not depend on `N`.
///
/// **Determinism.** A particle's trajectory depends only on its own initial state and on the
/// planet grid (the interpolant at a time depends on that time and the grid only, not on how
/// far the grid reaches), never on the windows, the other particles or the threads. So the
/// result is bit-identical on any number of threads, equal bit for bit to integrating the
/// particle alone with [`ParticleIntegrator::step`] and a mutable [`Ephemeris`], and a
/// population split into shards ([`Population::shard`]) run separately and merged
/// ([`Population::merge`]) equals the whole run.
///
/// **Memory:** [`Population::bytes_per_particle`] per particle (one [`PopulationMember`]), plus
/// the ephemeris window (`72 (n+1)` bytes per retained planet step: 360 bytes for the Sun and
/// four giants, at most about `3 ×` [`Population::window_steps`] steps).
///
/// **Threads.** The particles of a window are spread over rayon's threads; meanwhile one task
/// integrates the planets of the next window ([`Ephemeris`] states computed from a copy of the
/// planets and appended after the window: the same states in the same order as extending in
/// turn), so the planets' integration is not a serial stage between windows.
///
/// **What bounds a particle step** (barycentric variant, S2, the Sun and four giants; counted
/// from the code, one step = `E₁(h/2) E₀(h) E₁(h/2)`):
///
/// - *The planets at the particle's new time:* one quintic Hermite interpolation of positions
///   and velocities of 5 bodies, about 390 flops (60 for the weights, 330 for
///   `5 × 2 × 3` dot products of length 6), reading two grid states (720 bytes, from a
///   retained window of at most about 280 kB, in L2).
/// - *The kicks:* the closing `E₁` of a step and the opening one of the next are at the same
///   `(t, q)`, where `F₁` and its derivatives are the same numbers: they are evaluated once
///   ([`ParticleIntegrator`]'s kick cache, bit for bit the same result), 5 body terms of about
///   35 flops, one square root and one division each, then two updates of `v` and `p₄`.
/// - *The Kepler drift* ([`kepler::drift`](crate::kepler::drift)): `F₀` and `Δt = h/F₀`, the
///   universal-variable solve (Stumpff series of 12 multiply-adds, one Halley iteration from
///   the third-order series guess: 1.00 iterations per solve on the issue-21 comets) and the
///   `f, g` update, about 140 flops, one square root and 7 divisions, in one dependent chain.
/// - *The removal rules:* Hill spheres of 4 planets compared squared, energy and perihelion
///   without square roots beyond `|q|`, about 110 flops.
///
/// In all about 850 flops, 7 square roots and 17 divisions per particle step, but about
/// 2200 machine instructions on the scalar path (SSE2 scalar code, loads, stores, the checks;
/// counted with callgrind, 10² comets, 2026-11-25): at about 0.175 µs (≈ 610 cycles) per
/// step the processor retired nearly four instructions per cycle, so one particle at a time
/// is bound by the number of instructions, not by the latency of its chains (stepping whole
/// particles in turn, round-robin, gained nothing). A particle's 184 bytes stay in registers
/// and L1 through the window; the step is not bandwidth-bound.
///
/// **Lanes.** In the barycentric variant (either scheme) a window therefore steps its
/// particles four at a time: the states of four particles, each on its own clock, are held
/// in `[f64; 4]` values, compiled as AVX code (four `f64` per register) when the processor
/// has it (detected at run time) and as pairs of SSE2 instructions otherwise (`mulpd`,
/// `addpd`, `divpd`, `sqrtpd`; no `target-cpu` needed either way). Each lane interpolates the
/// planets at its own time (its own grid interval; the Hermite weights computed packed, the
/// grid data gathered lane by lane), kicks with its own bodies, drifts (the Halley iteration
/// runs until every lane has passed its own test, each lane keeping its own result and
/// iteration count; the Stumpff reductions are counted per lane) and tests the removal
/// rules, which name the rule with the scalar code only for a lane that meets one. Every lane
/// performs exactly the scalar path's operations in the same order (IEEE `+ − × ÷ √` round
/// alike in scalar, SSE2 and AVX form; Rust contracts nothing to FMA and FMA is not
/// enabled), so the result is bit for bit that of [`ParticleIntegrator::step`] (a property
/// test compares whole populations, removals and lost regularisation included, through the
/// AVX lanes, the portable lanes and the scalar path). What the lanes leave out — a
/// non-positive `F₀` or `F₁`, a drift longer than the orbital period, a Halley iteration that
/// fails or does not converge, a non-finite state, a time beyond the ephemeris — the scalar
/// step redoes from the particle's unchanged state. A lane whose particle is done with the
/// window (or removed) takes the next particle of its chunk (the whole population on one
/// thread, about a quarter of a thread's share on more); in a chunk of at most 64 particles
/// they take turns every 32 steps, so that the last few do not run with idle lanes. The mixed
/// variant goes one particle at a time. Measured (one thread, CPU time of paired runs on a
/// shared machine, 2026-11-25): 0.10 µs per step, 1.7× less than the scalar path at
/// `N` = 10³–10⁵ (SSE2-only lanes: 1.55×; about 1700 instructions per step instead of 2200);
/// 1.3× at `N` = 10, where the planets' own integration is about half of the time. Two SSE2
/// lanes gave 1.4× and eight 1.4× (`docs/performance.md`).
///
/// **The ephemeris:** one planet step per grid interval, shared by all `N` particles: with the
/// default S6 at 730.5 d (12 Kepler solves and 24 pair forces per step, plus 10 pair forces
/// for the stored accelerations) about 1.4 µs per planet step, i.e. `0.7/N` µs per
/// particle-year, comparable to the particles' own cost only for `N` below about 10.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Population {
    ephemeris: Ephemeris,
    integrator: ParticleIntegrator,
    rules: RemovalRules,
    members: Vec<PopulationMember>,
    /// Synchronisation time reached.
    time: f64,
    /// Planet steps per window.
    window_steps: u32,
    /// Particle steps taken so far.
    particle_steps: u64,
}

/// Per-thread scratch of [`Population::advance_to`].
struct Worker {
    bodies: BodyStates,
    /// Time `bodies` holds (`NaN` if none).
    bodies_time: f64,
    /// The last barycentric kick's terms.
    kick: KickTerms,
}

/// The read-only context of a window.
struct WindowContext<'a> {
    /// The planets, read through one view of the grid for the whole window.
    grid: GridView<'a>,
    integrator: ParticleIntegrator,
    rules: RemovalRules,
    /// `(m_j/3m₀)^{1/3}` per planet.
    hill_coefficients: Vec<f64>,
    total_gm: f64,
    end: f64,
    /// `G m_j` of the Sun and the planets, as the interpolation gives them.
    gm: Vec<f64>,
    /// `μ'` of the Kepler drift when the particles go through the lanes (barycentric variant,
    /// valid `μ'`); `None`: one particle at a time ([`WindowContext::advance_member`]).
    lanes_mu: Option<f64>,
    /// Whether the lanes run as AVX code (the same operations, four `f64` per register).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx: bool,
}

/// Chunks of at most this many members take turns in the lanes
/// ([`WindowContext::advance_lanes`]).
const ROTATION_MAX_MEMBERS: usize = 16 * LANES;

/// Lane steps per turn of a member in a small chunk.
const ROTATION_STEPS: u32 = 32;

/// How [`Population::advance_with`] steps the barycentric particles.
#[derive(Debug, Clone, Copy, PartialEq)]
enum StepPath {
    /// One at a time.
    Scalar,
    /// In lanes, compiled for AVX when the processor has it.
    Lanes,
    /// In lanes, portable code only (SSE2 on x86-64).
    #[cfg_attr(not(test), allow(dead_code))]
    PortableLanes,
}

/// Whether the processor runs AVX instructions.
fn avx_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// What one scalar step of a member did ([`WindowContext::step_member`]).
enum StepOutcome {
    /// The step was taken (the member may have been removed at its end).
    Stepped,
    /// The step failed; the member is removed with the reason.
    Failed,
    /// The step needs the planets at this time, beyond the ephemeris: redone next window.
    Beyond(f64),
}

/// One lane of [`WindowContext::advance_lanes`].
struct Slot {
    /// The member in the lane (index in the chunk).
    member: Option<usize>,
    /// Time of the lane's bodies in [`LaneState`] (`NaN`: none).
    bodies_time: f64,
    /// The scalar path's scratch.
    worker: Worker,
    /// Whether the lanes' kick terms hold this member's at its `(t, q)`.
    kick_valid: bool,
}

/// The lanes of [`WindowContext::advance_lanes`]: the particles' slots and the bodies and kick
/// terms per lane.
struct LaneState {
    slots: [Slot; LANES],
    /// Barycentric positions and velocities of each body, lane `l` at the time of its member.
    positions: Vec<V3>,
    velocities: Vec<V3>,
    kick: KickLanes,
    /// One lane's body positions, for [`WindowContext::removal`].
    column: Vec<Vec3>,
}

impl Population {
    /// A population at the epoch `time` from initial positions and barycentric velocities
    /// (`states[i] = (position, velocity)` in the integrator's variant: barycentric position
    /// for [`Variant::Barycentric`], heliocentric for [`Variant::Mixed`]), each particle's
    /// first physical step `initial_dt` (see [`ParticleIntegrator::particle`]), identifiers
    /// `ids` (one per state, distinct). The ephemeris is extended to `time` if needed; the
    /// particles are built in parallel. Errors name the offending particle by its identifier.
    pub fn new(
        mut ephemeris: Ephemeris,
        integrator: ParticleIntegrator,
        rules: RemovalRules,
        time: f64,
        initial_dt: f64,
        states: &[(Vec3, Vec3)],
        ids: &[u64],
    ) -> Result<Self, SymplecticError> {
        rules.validate()?;
        if ids.len() != states.len() {
            return Err(SymplecticError::InvalidParameter {
                name: "ids",
                value: ids.len() as f64,
                reason: "need one identifier per particle state",
            });
        }
        let mut bodies = BodyStates::default();
        ephemeris.bodies_at(time, &mut bodies)?;
        let planets = ephemeris.planets().clone();
        let members = states
            .par_iter()
            .zip(ids)
            .map(|(&(position, velocity), &id)| {
                let particle = integrator
                    .particle_from_bodies(position, velocity, time, initial_dt, &bodies, &planets)
                    .map_err(|e| SymplecticError::InvalidState {
                        what: "population particle",
                        reason: format!("particle {id}: {e}"),
                    })?;
                Ok(PopulationMember {
                    id,
                    particle,
                    status: ParticleStatus::Active,
                    sun_position: bodies.positions[0],
                })
            })
            .collect::<Result<Vec<_>, SymplecticError>>()?;
        let mut population = Self {
            ephemeris,
            integrator,
            rules,
            members,
            time,
            window_steps: DEFAULT_WINDOW_STEPS,
            particle_steps: 0,
        };
        population.check_ids()?;
        Ok(population)
    }

    fn check_ids(&mut self) -> Result<(), SymplecticError> {
        let mut ids: Vec<u64> = self.members.iter().map(|m| m.id).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(SymplecticError::InvalidParameter {
                name: "particle id",
                value: w[0] as f64,
                reason: "appears twice in the population",
            });
        }
        Ok(())
    }

    /// Bytes of one particle in memory (one [`PopulationMember`], without the heap text of a
    /// failure message).
    pub const fn bytes_per_particle() -> usize {
        std::mem::size_of::<PopulationMember>()
    }

    /// Sets the synchronisation window, in planet steps (`>= 1`). Changes when the
    /// population synchronises, never the particles' trajectories.
    pub fn set_window_steps(&mut self, steps: u32) -> Result<(), SymplecticError> {
        if steps == 0 {
            return Err(SymplecticError::InvalidParameter {
                name: "window_steps",
                value: 0.0,
                reason: "must be >= 1",
            });
        }
        self.window_steps = steps;
        Ok(())
    }

    /// Planet steps per synchronisation window.
    pub fn window_steps(&self) -> u32 {
        self.window_steps
    }

    /// The particles, in identifier order after a merge, in the caller's order otherwise.
    pub fn members(&self) -> &[PopulationMember] {
        &self.members
    }

    /// The particle map.
    pub fn integrator(&self) -> ParticleIntegrator {
        self.integrator
    }

    /// The removal rules.
    pub fn rules(&self) -> RemovalRules {
        self.rules
    }

    /// The planets' ephemeris.
    pub fn ephemeris(&self) -> &Ephemeris {
        &self.ephemeris
    }

    /// The synchronisation time reached.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Where the population stands.
    pub fn progress(&self) -> PopulationProgress {
        let active = self
            .members
            .iter()
            .filter(|m| m.status == ParticleStatus::Active)
            .count();
        PopulationProgress {
            time: self.time,
            particle_steps: self.particle_steps,
            active,
            removed: self.members.len() - active,
        }
    }

    /// Work of the planets, the ephemeris and every particle (a particle of a population
    /// counts its own ephemeris interpolations).
    pub fn work(&self) -> WorkCounters {
        self.ephemeris.work() + self.members.iter().map(|m| m.particle.work).sum()
    }

    /// `G M`, the sum of `G m_j` over the Sun and the planets (the `μ` of barycentric
    /// elements), summed as [`BodyStates::total_gm`] does.
    pub fn total_gm(&self) -> f64 {
        total_gm(self.ephemeris.planets())
    }

    /// Barycentric position of member `i` at its own time.
    pub fn barycentric_position(&self, i: usize) -> Vec3 {
        let m = &self.members[i];
        match self.integrator.variant {
            Variant::Barycentric => m.particle.position,
            Variant::Mixed => m.particle.position + m.sun_position,
        }
    }

    /// Barycentric osculating elements of member `i` at its own time (`μ = G M`).
    pub fn elements(&self, i: usize) -> Result<Elements, SymplecticError> {
        let Some(m) = self.members.get(i) else {
            return Err(SymplecticError::InvalidParameter {
                name: "particle index",
                value: i as f64,
                reason: "no such particle in the population",
            });
        };
        crate::kepler::elements(
            &self.barycentric_position(i),
            &m.particle.velocity,
            self.total_gm(),
        )
    }

    /// The extended-Hamiltonian error `(H + p₄)/|H|` of member `i` at its own time, or
    /// `None` if the ephemeris no longer holds that time (a particle removed long ago).
    pub fn relative_error(&self, i: usize) -> Option<f64> {
        let m = self.members.get(i)?;
        let mut bodies = BodyStates::default();
        self.ephemeris
            .interpolate(m.particle.time, &mut bodies, true)
            .ok()?;
        let h = self.integrator.hamiltonian(&m.particle, &bodies);
        Some((h + m.particle.p4) / h.abs())
    }

    /// Advances every active particle until its own time reaches `t_end` (its last step
    /// overshoots: the steps are variable), in windows; `on_sync` sees the population's
    /// progress after each window. Removed particles stop; they never stop the others. Errors
    /// only for a bad `t_end` or a planet integration that fails.
    pub fn advance_to(
        &mut self,
        t_end: f64,
        on_sync: impl FnMut(&PopulationProgress),
    ) -> Result<PopulationProgress, SymplecticError> {
        self.advance_with(t_end, StepPath::Lanes, on_sync)
    }

    /// [`Population::advance_to`] along `path` (the others are the oracles of the lanes'
    /// tests).
    fn advance_with(
        &mut self,
        t_end: f64,
        path: StepPath,
        mut on_sync: impl FnMut(&PopulationProgress),
    ) -> Result<PopulationProgress, SymplecticError> {
        if !t_end.is_finite() {
            return Err(SymplecticError::InvalidParameter {
                name: "end time",
                value: t_end,
                reason: "must be finite",
            });
        }
        let window = f64::from(self.window_steps) * self.ephemeris.grid_step();
        let mut needed = f64::NEG_INFINITY;
        while let Some(oldest) = self.oldest_active_time() {
            if oldest >= t_end {
                break;
            }
            let end = (self.time.max(oldest) + window).min(t_end);
            self.ephemeris.discard_before(oldest);
            // Covered already by the previous window's extension, except at the start.
            self.ephemeris.extend_to((end + window).max(needed))?;
            // The planets of the next window are integrated while the particles step through
            // this one (the same states, in the same order, as extending in turn).
            let ahead = (end + window).min(t_end) + window;
            let ephemeris = &self.ephemeris;
            let members = &mut self.members;
            let (integrator, rules) = (self.integrator, self.rules);
            let (extension, (steps, beyond)) = rayon::join(
                || ephemeris.extension(ahead),
                || run_window(ephemeris, integrator, rules, members, end, path),
            );
            self.ephemeris.append(extension?)?;
            self.particle_steps += steps;
            needed = beyond;
            self.time = self.time.max(end);
            on_sync(&self.progress());
        }
        self.time = self.time.max(t_end);
        Ok(self.progress())
    }

    fn oldest_active_time(&self) -> Option<f64> {
        self.members
            .iter()
            .filter(|m| m.status == ParticleStatus::Active)
            .map(|m| m.particle.time)
            .reduce(f64::min)
    }

    /// The members in `range` as a population of their own, with a copy of the ephemeris:
    /// run it anywhere and [`Population::merge`] the results.
    pub fn shard(&self, range: Range<usize>) -> Result<Self, SymplecticError> {
        let Some(members) = self.members.get(range.clone()) else {
            return Err(SymplecticError::InvalidParameter {
                name: "shard end",
                value: range.end as f64,
                reason: "beyond the population's particles",
            });
        };
        Ok(Self {
            members: members.to_vec(),
            particle_steps: 0,
            ..self.clone_without_members()
        })
    }

    fn clone_without_members(&self) -> Self {
        Self {
            ephemeris: self.ephemeris.clone(),
            integrator: self.integrator,
            rules: self.rules,
            members: Vec::new(),
            time: self.time,
            window_steps: self.window_steps,
            particle_steps: self.particle_steps,
        }
    }

    /// Joins shards of one population advanced to the same time ([`Population::shard`]): the
    /// members in identifier order, the ephemeris covering all of them. Errors if the shards
    /// differ in integrator, rules, planets' step or time, or share an identifier.
    pub fn merge(shards: Vec<Self>) -> Result<Self, SymplecticError> {
        let Some(first) = shards.first() else {
            return Err(SymplecticError::InvalidParameter {
                name: "shards",
                value: 0.0,
                reason: "nothing to merge",
            });
        };
        for s in &shards[1..] {
            let same = s.integrator == first.integrator
                && s.rules == first.rules
                && s.time.to_bits() == first.time.to_bits()
                && s.ephemeris.integrator() == first.ephemeris.integrator()
                && s.ephemeris.grid_time(0).to_bits() == first.ephemeris.grid_time(0).to_bits();
            if !same {
                return Err(SymplecticError::InvalidParameter {
                    name: "shards",
                    value: s.time,
                    reason:
                        "differ in integrator, rules, planets or time: not shards of one population",
                });
            }
        }
        // The ephemeris retaining the oldest state, extended to the newest of all.
        let newest = shards
            .iter()
            .map(|s| s.ephemeris.newest_time())
            .fold(f64::NEG_INFINITY, f64::max);
        let oldest = shards
            .iter()
            .enumerate()
            .min_by(|a, b| {
                a.1.ephemeris
                    .oldest_time()
                    .total_cmp(&b.1.ephemeris.oldest_time())
            })
            .map_or(0, |(i, _)| i);
        let mut merged = shards[oldest].clone_without_members();
        merged.ephemeris.extend_to(newest)?;
        merged.particle_steps = shards.iter().map(|s| s.particle_steps).sum();
        merged.members = shards.into_iter().flat_map(|s| s.members).collect();
        merged.members.sort_by_key(|m| m.id);
        merged.check_ids()?;
        Ok(merged)
    }

    /// Writes the whole population atomically to `path` (temporary file, `fsync`, rename;
    /// see [`save_checkpoint`](crate::save_checkpoint)), in a versioned envelope.
    pub fn save(&self, path: &Path) -> Result<(), SymplecticError> {
        crate::save_checkpoint(
            path,
            &Envelope {
                format: POPULATION_FORMAT.into(),
                version: POPULATION_VERSION,
                population: self.clone(),
            },
        )
    }

    /// Reads a population written by [`Population::save`]; refuses a foreign, truncated or
    /// other-version file by name. A resumed population continues bit for bit.
    pub fn load(path: &Path) -> Result<Self, SymplecticError> {
        let e: Envelope = crate::load_checkpoint(path)?;
        if e.format != POPULATION_FORMAT || e.version != POPULATION_VERSION {
            return Err(SymplecticError::Checkpoint {
                path: path.display().to_string(),
                reason: format!(
                    "format {:?} version {}, expected {POPULATION_FORMAT:?} version {POPULATION_VERSION}",
                    e.format, e.version
                ),
            });
        }
        Ok(e.population)
    }
}

/// One window: every active member steps while its time is before `end`, reading `ephemeris`.
/// Returns the steps taken and the latest time a step needed beyond the ephemeris.
fn run_window(
    ephemeris: &Ephemeris,
    integrator: ParticleIntegrator,
    rules: RemovalRules,
    members: &mut [PopulationMember],
    end: f64,
    path: StepPath,
) -> (u64, f64) {
    let planets = ephemeris.planets();
    let m0 = planets.sun_mass();
    // The bodies' `G m` exactly as the interpolation fills them (any retained time will do).
    let mut bodies = BodyStates::default();
    let lanes_mu = match ephemeris.interpolate(ephemeris.newest_time(), &mut bodies, false) {
        Ok(()) if path != StepPath::Scalar && integrator.variant == Variant::Barycentric => {
            let mu = integrator.kepler_mu(&bodies);
            (mu.is_finite() && mu > 0.0).then_some(mu)
        }
        _ => None,
    };
    let ctx = WindowContext {
        grid: ephemeris.view(),
        integrator,
        rules,
        hill_coefficients: planets
            .masses()
            .iter()
            .map(|m| (m / (3.0 * m0)).cbrt())
            .collect(),
        total_gm: total_gm(planets),
        end,
        gm: bodies.gm,
        lanes_mu,
        avx: path == StepPath::Lanes && avx_available(),
    };
    // Chunks of particles, each stepped `LANES` at a time (a lane whose particle is done
    // takes the chunk's next one): one chunk on one thread; on more, about four chunks per
    // thread, so that a thread that finishes the next window's planets (see
    // `Population::advance_to`) can take over chunks that the others have not reached.
    let threads = rayon::current_num_threads();
    let chunk = if threads <= 1 {
        members.len().max(1)
    } else {
        members.len().div_ceil(4 * threads).max(LANES)
    };
    members
        .par_chunks_mut(chunk)
        .with_max_len(1)
        .map(|chunk| ctx.advance_chunk(chunk))
        .reduce(|| (0, f64::NEG_INFINITY), sum_steps)
}

/// Adds two `(steps, beyond)` pairs.
fn sum_steps(a: (u64, f64), b: (u64, f64)) -> (u64, f64) {
    (a.0 + b.0, a.1.max(b.1))
}

impl Worker {
    fn new() -> Self {
        Self {
            bodies: BodyStates::default(),
            bodies_time: f64::NAN,
            kick: KickTerms::default(),
        }
    }
}

fn total_gm(planets: &crate::Planets) -> f64 {
    let g = planets.g();
    std::iter::once(g * planets.sun_mass())
        .chain(planets.masses().iter().map(|m| g * m))
        .sum()
}

const POPULATION_FORMAT: &str = "symplectic-population";
const POPULATION_VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Envelope {
    format: String,
    version: u32,
    population: Population,
}

impl WindowContext<'_> {
    /// Steps the members of a chunk through the window: through the lanes when they apply,
    /// one at a time otherwise. Returns the steps and the latest time needed beyond the
    /// ephemeris.
    fn advance_chunk(&self, members: &mut [PopulationMember]) -> (u64, f64) {
        match self.lanes_mu {
            #[cfg(target_arch = "x86_64")]
            Some(mu) if self.avx => {
                // SAFETY: `avx` is set only when the processor runs AVX (`avx_available`).
                #[allow(unsafe_code)]
                unsafe {
                    self.advance_lanes_avx(members, mu)
                }
            }
            Some(mu) => self.advance_lanes(members, mu),
            None => {
                let mut w = Worker::new();
                members
                    .iter_mut()
                    .map(|m| self.advance_member(m, &mut w))
                    .fold((0, f64::NEG_INFINITY), sum_steps)
            }
        }
    }

    /// [`WindowContext::advance_lanes`] compiled for AVX: the same operations (IEEE `+ − × ÷ √`
    /// round alike in SSE2 and AVX; no FMA is enabled), four lanes per register instead of
    /// two.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn advance_lanes_avx(&self, members: &mut [PopulationMember], mu: f64) -> (u64, f64) {
        self.advance_lanes(members, mu)
    }

    /// [`LANES`] members at a time ([`crate::lanes`]), each on its own clock: a lane whose
    /// member is done with the window (or removed) takes the next one, until none is left.
    #[inline(always)]
    fn advance_lanes(&self, members: &mut [PopulationMember], mu: f64) -> (u64, f64) {
        let zero = [V::splat(0.0); 3];
        let mut lanes = LaneState {
            slots: std::array::from_fn(|_| Slot {
                member: None,
                bodies_time: f64::NAN,
                worker: Worker::new(),
                kick_valid: false,
            }),
            positions: vec![zero; self.gm.len()],
            velocities: vec![zero; self.gm.len()],
            kick: KickLanes::zero(),
            column: Vec::with_capacity(self.gm.len()),
        };
        let mut queue: VecDeque<usize> = (0..members.len())
            .filter(|&i| {
                let m = &members[i];
                m.status == ParticleStatus::Active && m.particle.time < self.end
            })
            .collect();
        // A small chunk takes turns: a member leaves its lane after ROTATION_STEPS steps for
        // one that waits, so that the chunk's members finish the window together instead of
        // the last few running with idle lanes (a turn costs one kick evaluation and one
        // interpolation more, nothing else: the trajectory is the same).
        let rotate = members.len() <= ROTATION_MAX_MEMBERS;
        let mut stint = [0u32; LANES];
        let mut total = (0, f64::NEG_INFINITY);
        loop {
            for (slot, stint) in lanes.slots.iter_mut().zip(&mut stint) {
                if slot.member.is_none() {
                    slot.member = queue.pop_front();
                    slot.bodies_time = f64::NAN;
                    slot.kick_valid = false;
                    *stint = 0;
                }
            }
            if lanes.slots.iter().all(|s| s.member.is_none()) {
                return total;
            }
            total = sum_steps(total, self.lane_step(members, &mut lanes, mu));
            if rotate && !queue.is_empty() {
                for (slot, stint) in lanes.slots.iter_mut().zip(&mut stint) {
                    *stint += 1;
                    if let Some(i) = slot.member.filter(|_| *stint >= ROTATION_STEPS) {
                        queue.push_back(i);
                        slot.member = None;
                    }
                }
            }
        }
    }

    /// One step of every member in a lane: [`ParticleIntegrator::advance`] and the removal
    /// rules, lane by lane bit for bit; a lane the lanes cannot finish is redone by
    /// [`WindowContext::step_member`] from its unchanged state.
    #[inline(always)]
    fn lane_step(
        &self,
        members: &mut [PopulationMember],
        lanes: &mut LaneState,
        mu: f64,
    ) -> (u64, f64) {
        let live: Mask = std::array::from_fn(|l| lanes.slots[l].member.is_some());
        // Empty lanes repeat a live one; their results are dropped.
        let fill = lanes.slots.iter().find_map(|s| s.member).unwrap_or(0);
        let index: [usize; LANES] = std::array::from_fn(|l| lanes.slots[l].member.unwrap_or(fill));
        let zero = V::splat(0.0);
        let (mut q, mut v): (V3, V3) = ([zero; 3], [zero; 3]);
        let (mut t, mut p4, mut step) = (zero, zero, zero);
        for (l, &i) in index.iter().enumerate() {
            let p = &members[i].particle;
            for c in 0..3 {
                q[c].0[l] = p.position[c];
                v[c].0[l] = p.velocity[c];
            }
            (t.0[l], p4.0[l], step.0[l]) = (p.time, p.p4, p.step);
        }
        let (b0, b1) = (self.integrator.b0, self.integrator.b1);
        let mut redo: Mask = [false; LANES];
        let mut iterations = [0u32; LANES];
        let (mut drifts, mut kicks) = (0u64, 0u64);
        for (k, stage) in self.integrator.stages().iter().enumerate() {
            self.fetch_lanes(lanes, &t, live, &mut redo);
            let h = stage.coefficient * step;
            match stage.piece {
                ParticlePiece::KeplerDrift => {
                    // ParticleIntegrator::kepler_drift: F₀, Δt = h/F₀, the drift.
                    let r = norm(&q);
                    let f0 = 0.5 * norm_squared(&v) - mu / r + p4 + b0;
                    for (l, flag) in redo.iter_mut().enumerate() {
                        *flag |= !(f0.0[l] > 0.0 && f0.0[l].is_finite());
                    }
                    let dt = h / f0;
                    let it = lanes::drift(&mut q, &mut v, r, mu, dt, live, &mut redo);
                    for (total, it) in iterations.iter_mut().zip(it) {
                        *total += it;
                    }
                    t = t + dt;
                    drifts += 1;
                    for slot in &mut lanes.slots {
                        slot.kick_valid = false;
                    }
                }
                ParticlePiece::Perturbation => {
                    // ParticleIntegrator::perturbation_cached, barycentric: the terms kept
                    // from the last kick at the same (t, q) (the closing kick of the previous
                    // step), computed otherwise.
                    let need: Mask = std::array::from_fn(|l| {
                        live[l] && !redo[l] && !(k == 0 && lanes.slots[l].kick_valid)
                    });
                    if need.iter().any(|&n| n) {
                        let fresh = KickLanes::at(
                            b0,
                            b1,
                            &q,
                            &self.gm,
                            &lanes.positions,
                            &lanes.velocities,
                        );
                        lanes.kick = KickLanes::select(need, &fresh, &lanes.kick);
                    }
                    let f1 = lanes.kick.f1;
                    for (l, flag) in redo.iter_mut().enumerate() {
                        *flag |= !(f1.0[l] > 0.0 && f1.0[l].is_finite());
                    }
                    let sigma = h / f1;
                    for (vi, gi) in v.iter_mut().zip(&lanes.kick.gradient) {
                        *vi = *vi + *gi * sigma;
                    }
                    p4 = p4 + lanes.kick.dt_part * sigma;
                    kicks += 1;
                    for slot in &mut lanes.slots {
                        slot.kick_valid = true;
                    }
                }
            }
        }
        self.fetch_lanes(lanes, &t, live, &mut redo);
        let finite: [Mask; 7] = [q[0], q[1], q[2], v[0], v[1], v[2], p4].map(lanes::finite);
        let removal = self.removal_lanes(&q, &v, &lanes.positions);
        let (mut steps, mut beyond) = (0, f64::NEG_INFINITY);
        let forces = kicks * self.gm.len() as u64;
        for (l, slot) in lanes.slots.iter_mut().enumerate() {
            let Some(i) = slot.member else { continue };
            let m = &mut members[i];
            if redo[l] || !finite.iter().all(|f| f[l]) {
                slot.kick_valid = false;
                // The scalar path fetches its own bodies; the lane's are not updated.
                slot.worker.bodies_time = f64::NAN;
                let outcome = self.step_member(m, &mut slot.worker);
                slot.bodies_time = f64::NAN;
                match outcome {
                    StepOutcome::Stepped => steps += 1,
                    StepOutcome::Failed => {}
                    StepOutcome::Beyond(time) => {
                        beyond = beyond.max(time);
                        slot.member = None;
                        continue;
                    }
                }
            } else {
                let p = &mut m.particle;
                p.position = lanes::lane(&q, l);
                p.velocity = lanes::lane(&v, l);
                p.time = t.0[l];
                p.p4 = p4.0[l];
                p.steps += 1;
                p.work.kepler_solves += drifts;
                p.work.kepler_iterations += u64::from(iterations[l]);
                p.work.force_evaluations += forces;
                steps += 1;
                m.sun_position = lanes::lane(&lanes.positions[0], l);
                if removal[l] {
                    lanes.column.clear();
                    lanes
                        .column
                        .extend(lanes.positions.iter().map(|x| lanes::lane(x, l)));
                    if let Some(status) = self.removal(&m.particle, &lanes.column) {
                        m.status = status;
                    }
                }
            }
            if !(m.status == ParticleStatus::Active && m.particle.time < self.end) {
                slot.member = None;
            }
        }
        (steps, beyond)
    }

    /// The bodies at each live lane's time `t` where its lane holds another time (as
    /// [`ParticleIntegrator::advance`] fetches them); a lane whose time the ephemeris does not
    /// hold is marked for the scalar path.
    #[inline(always)]
    fn fetch_lanes(&self, lanes: &mut LaneState, t: &V, live: Mask, redo: &mut Mask) {
        let need: Mask =
            std::array::from_fn(|l| live[l] && !redo[l] && lanes.slots[l].bodies_time != t.0[l]);
        if !need.iter().any(|&n| n) {
            return;
        }
        let bad =
            self.grid
                .interpolate_lanes(*t, need, &mut lanes.positions, &mut lanes.velocities);
        for (l, slot) in lanes.slots.iter_mut().enumerate() {
            if need[l] {
                redo[l] |= bad[l];
                slot.bodies_time = if bad[l] { f64::NAN } else { t.0[l] };
            }
        }
    }

    /// Steps one member through the window with the scalar path; returns its steps and the
    /// time it needed beyond the ephemeris (`-∞` if none).
    fn advance_member(&self, m: &mut PopulationMember, w: &mut Worker) -> (u64, f64) {
        let mut steps = 0;
        while m.status == ParticleStatus::Active && m.particle.time < self.end {
            match self.step_member(m, w) {
                StepOutcome::Stepped => steps += 1,
                StepOutcome::Failed => {}
                StepOutcome::Beyond(time) => return (steps, time),
            }
        }
        (steps, f64::NEG_INFINITY)
    }

    /// One step of one member with the scalar path ([`ParticleIntegrator::advance`]), with the
    /// removal rules; a step that fails leaves the member's state as it was.
    #[inline(never)]
    fn step_member(&self, m: &mut PopulationMember, w: &mut Worker) -> StepOutcome {
        let accelerations = self.integrator.variant == Variant::Mixed;
        let saved = m.particle.clone();
        let bodies_time = w.bodies_time;
        w.bodies_time = f64::NAN;
        let result = self.integrator.advance(
            &mut m.particle,
            &mut w.bodies,
            bodies_time,
            &mut w.kick,
            &mut |t: f64, out: &mut BodyStates| self.grid.interpolate(t, out, accelerations),
        );
        match result {
            Ok(t) => {
                w.bodies_time = t;
                m.sun_position = w.bodies.positions[0];
                if let Some(status) = self.removal(&m.particle, &w.bodies.positions) {
                    m.status = status;
                }
                StepOutcome::Stepped
            }
            Err(SymplecticError::BeyondEphemeris { time, .. }) => {
                m.particle = saved;
                StepOutcome::Beyond(time)
            }
            Err(SymplecticError::RegularisationLost {
                quantity,
                value,
                time,
            }) => {
                m.particle = saved;
                m.status = ParticleStatus::RegularisationLost {
                    time,
                    quantity: quantity.to_string(),
                    value,
                };
                StepOutcome::Failed
            }
            Err(e) => {
                m.particle = saved;
                m.status = ParticleStatus::IntegrationFailed {
                    time: m.particle.time,
                    reason: e.to_string(),
                };
                StepOutcome::Failed
            }
        }
    }

    /// Per lane, whether [`WindowContext::removal`] removes the barycentric particle at `q`,
    /// `v` among the bodies at `positions`: the same tests with the same operations, so that
    /// only the lanes it flags need the scalar form (which names the rule).
    #[inline(always)]
    fn removal_lanes(&self, q: &V3, v: &V3, positions: &[V3]) -> Mask {
        let rules = &self.rules;
        let mut hit = [false; LANES];
        let mut flag = |test: Mask| {
            for (h, t) in hit.iter_mut().zip(test) {
                *h |= t;
            }
        };
        let sub = |a: &V3, b: &V3| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        if let Some(factor) = rules.hill_factor {
            let sun = &positions[0];
            for (c, planet) in self.hill_coefficients.iter().zip(&positions[1..]) {
                let distance2 = norm_squared(&sub(q, planet));
                let hill2 = norm_squared(&sub(planet, sun)) * (c * c);
                let limit = factor * factor * hill2;
                flag(std::array::from_fn(|l| distance2.0[l] < limit.0[l]));
            }
        }
        if rules.min_perihelion.is_none() && rules.ejection_distance.is_none() {
            return hit;
        }
        let mu = self.total_gm;
        let r = norm(q);
        let v2r = norm_squared(v) * r;
        if let Some(limit) = rules.ejection_distance {
            flag(std::array::from_fn(|l| {
                v2r.0[l] >= 2.0 * mu && r.0[l] > limit
            }));
        }
        if let Some(limit) = rules.min_perihelion {
            let h = [
                q[1] * v[2] - q[2] * v[1],
                q[2] * v[0] - q[0] * v[2],
                q[0] * v[1] - q[1] * v[0],
            ];
            let h2 = norm_squared(&h);
            let r_mu2_e2 = (r * mu * mu + (v2r - 2.0 * mu) * h2).max(0.0);
            let (u, w) = (h2 - limit * mu, limit * mu);
            let left = u * u * (r * mu * mu);
            let right = w * w * r_mu2_e2;
            flag(std::array::from_fn(|l| {
                u.0[l] < 0.0 || left.0[l] < right.0[l]
            }));
        }
        hit
    }

    /// The first removal rule the particle meets, with the bodies at its time.
    fn removal(&self, p: &TestParticle, positions: &[Vec3]) -> Option<ParticleStatus> {
        let q = match self.integrator.variant {
            Variant::Barycentric => p.position,
            Variant::Mixed => p.position + positions[0],
        };
        let rules = &self.rules;
        if let Some(factor) = rules.hill_factor {
            // Compared squared (no square root per planet and step); the distances are taken
            // only for the report.
            let sun = positions[0];
            for (j, c) in self.hill_coefficients.iter().enumerate() {
                let planet = positions[j + 1];
                let distance2 = (q - planet).norm_squared();
                let hill2 = (planet - sun).norm_squared() * (c * c);
                if distance2 < factor * factor * hill2 {
                    return Some(ParticleStatus::HillSphereEntry {
                        time: p.time,
                        planet: j + 1,
                        distance: distance2.sqrt(),
                        hill_radius: (planet - sun).norm() * c,
                    });
                }
            }
        }
        if rules.min_perihelion.is_none() && rules.ejection_distance.is_none() {
            return None;
        }
        // Barycentric osculating energy and perihelion from the energy and angular momentum
        // (no angles): e² = 1 + 2E h²/μ², q = h²/(μ (1 + e)). Multiplied through by r (and
        // μ²) so that no division is needed per step: 2E r = v² r − 2μ.
        let mu = self.total_gm;
        let r = q.norm();
        let v2r = p.velocity.norm_squared() * r;
        if let Some(limit) = rules.ejection_distance {
            if v2r >= 2.0 * mu && r > limit {
                return Some(ParticleStatus::Ejected {
                    time: p.time,
                    distance: r,
                });
            }
        }
        if let Some(limit) = rules.min_perihelion {
            let h2 = q.cross(&p.velocity).norm_squared();
            // r μ² e² = r μ² + (v² r − 2μ) h².
            let r_mu2_e2 = (r * mu * mu + (v2r - 2.0 * mu) * h2).max(0.0);
            // q < L ⟺ h² − Lμ < Lμ e: true when the left side is negative, otherwise compared
            // squared; q itself only for the report.
            let (u, w) = (h2 - limit * mu, limit * mu);
            if u < 0.0 || u * u * (r * mu * mu) < w * w * r_mu2_e2 {
                let e = (r_mu2_e2 / r).sqrt() / mu;
                let perihelion = h2 / (mu * (1.0 + e));
                return Some(ParticleStatus::PerihelionBelowLimit {
                    time: p.time,
                    perihelion,
                });
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;
    use crate::kepler::state_from_elements;
    use crate::samples::{sample_elements, SampleRanges};
    use crate::{outer_solar_system, Frame, Integrator, Scheme};

    /// Comets from Saturn's distance to the scattered disk: some enter a Hill sphere, some
    /// fall below the perihelion limit, some lose the regularisation (a `B₁` far below the
    /// paper's, or perihelia below the ≈ 26 AU of its condition 35) and are redone by the
    /// scalar path.
    fn population(n: usize, seed: u64, scheme: Scheme, b1: f64, rules: RemovalRules) -> Population {
        let planets = outer_solar_system(Frame::EclipticJ2000);
        let mu = planets.g() * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
        let ranges = SampleRanges {
            perihelion: None,
            semi_major_axis: (12.0, 70.0),
            eccentricity: (0.0, 0.5),
            inclination: (0.0, 0.4),
        };
        let ephemeris = Ephemeris::new(planets, Integrator::S6 { step: 730.5 }).unwrap();
        let integ = ParticleIntegrator::new(Variant::Barycentric, scheme, 0.0, b1).unwrap();
        // Orbits where K₀/r or K₁/r is not positive at the start cannot be built: left out.
        let (mut eph, mut scratch) = (ephemeris.clone(), crate::ParticleScratch::default());
        let states: Vec<(Vec3, Vec3)> = sample_elements(&ranges, n, seed)
            .iter()
            .map(|el| state_from_elements(el, mu).unwrap())
            .filter(|&(q, v)| {
                integ
                    .particle(q, v, 0.0, 400.0, &mut eph, &mut scratch)
                    .is_ok()
            })
            .collect();
        let ids: Vec<u64> = (0..states.len() as u64).collect();
        Population::new(ephemeris, integ, rules, 0.0, 400.0, &states, &ids).unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

        /// The lanes give the population of the scalar path bit for bit: every member's
        /// state, status (rule, time, figures), step and work counts, on one or two threads.
        #[test]
        fn lanes_equal_the_scalar_path(
            seed in 0u64..10_000,
            n in 1usize..23,
            s6 in any::<bool>(),
            window in 1u32..40,
            two_threads in any::<bool>(),
            small_b1 in any::<bool>(),
            hill in prop::option::of(0.5f64..3.0),
            min_perihelion in prop::option::of(5.0f64..30.0),
            ejection in prop::option::of(60.0f64..200.0),
        ) {
            let scheme = if s6 { Scheme::S6 } else { Scheme::S2 };
            let rules = RemovalRules {
                hill_factor: hill,
                min_perihelion,
                ejection_distance: ejection,
            };
            let b1 = if small_b1 { 3e-8 } else { crate::PAPER_B1 };
            let mut start = population(n, seed, scheme, b1, rules);
            start.set_window_steps(window).unwrap();
            let t_end = 400.0 * 365.25;
            let threads = if two_threads { 2 } else { 1 };
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let run = |path: StepPath| {
                let mut p = start.clone();
                pool.install(|| p.advance_with(t_end, path, |_| {})).unwrap();
                p
            };
            let (lanes, scalar) = (run(StepPath::Lanes), run(StepPath::Scalar));
            let portable = run(StepPath::PortableLanes);
            prop_assert_eq!(lanes.members(), portable.members());
            prop_assert!(lanes.members().iter().all(|m| m.particle.steps > 0 || m.status != ParticleStatus::Active));
            prop_assert_eq!(lanes.members(), scalar.members());
            prop_assert_eq!(lanes.progress(), scalar.progress());
            prop_assert_eq!(lanes.work(), scalar.work());
        }
    }

    /// The test population exercises what the lanes hand to the scalar path: removals by
    /// each rule and the loss of the regularisation.
    #[test]
    fn lanes_test_population_meets_every_outcome() {
        let rules = RemovalRules {
            hill_factor: Some(1.0),
            min_perihelion: Some(8.0),
            ejection_distance: Some(100.0),
        };
        let mut p = population(200, 3, Scheme::S2, 3e-8, rules);
        p.advance_to(400.0 * 365.25, |_| {}).unwrap();
        let count =
            |f: fn(&ParticleStatus) -> bool| p.members().iter().filter(|m| f(&m.status)).count();
        let hill = count(|s| matches!(s, ParticleStatus::HillSphereEntry { .. }));
        let perihelion = count(|s| matches!(s, ParticleStatus::PerihelionBelowLimit { .. }));
        let lost = count(|s| matches!(s, ParticleStatus::RegularisationLost { .. }));
        let active = count(|s| matches!(s, ParticleStatus::Active));
        assert!(
            hill > 0 && perihelion > 0 && lost > 0 && active > 0,
            "{hill} {perihelion} {lost} {active}"
        );
    }
}
