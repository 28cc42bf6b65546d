//! A population of test particles advanced in parallel against one shared planet ephemeris.

use std::ops::Range;
use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::ephemeris::{BodyStates, Ephemeris};
use crate::kepler::Elements;
use crate::particles::ParticleIntegrator;
use crate::run::ParticleStatus;
use crate::{Encounters, SymplecticError, Variant, Vec3, WorkCounters};

mod ends;
mod events;
mod members;
#[cfg(test)]
mod tests;
mod window;

pub use events::{
    ApproachRadius, CometEvent, EventKind, EventLog, EventRules, OpenApproach,
    DEFAULT_MAX_EVENTS_PER_PARTICLE, MAX_PERIHELION_THRESHOLDS,
};
pub use members::{
    DistanceFrame, DistanceLimit, EncounterTally, OpenEncounter, PopulationMember,
    PopulationProgress, RemovalRules, SwitchesPerEncounter, ENCOUNTER_SEPARATION_FACTOR,
};
use window::{run_window, total_gm, StepPath};

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
///   the third-order series guess: 1.00 iterations per solve on the scattered-disk comets) and the
///   `f, g` update, about 140 flops, one square root and 7 divisions, in one dependent chain.
/// - *The removal rules:* Hill spheres of 4 planets compared squared, energy and perihelion
///   without square roots beyond `|q|`, about 110 flops.
///
/// In all about 850 flops, 7 square roots and 17 divisions per particle step, but about
/// 2200 machine instructions on the scalar path (SSE2 scalar code, loads, stores, the checks;
/// counted with callgrind, 10² comets, 2026-11-25): at about 0.175 µs (≈ 610 cycles) per
/// step the processor retired nearly four instructions per cycle, so one particle at a time
/// is bound by the number of instructions, not by the latency of its chains (stepping whole
/// particles in turn, round-robin, gained nothing). A particle's 200 bytes stay in registers
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
/// for the stored accelerations; the four planets' Kepler drifts go through the lanes too,
/// bit for bit the scalar drifts) about 1 µs per planet step (the bare S6 map 0.72 µs,
/// criterion `planet-step/S6`, 2026-11-25, loaded machine), i.e. about `0.5/N` µs per
/// particle-year, comparable to the particles' own cost only for `N` near 10.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Population {
    ephemeris: Ephemeris,
    integrator: ParticleIntegrator,
    rules: RemovalRules,
    /// Integration through close encounters (`None`: none; Hill-sphere entry is then a
    /// removal rule, and lost regularisation removes).
    #[serde(default)]
    encounters: Option<Encounters>,
    /// What is recorded without removing (none in a population saved before events).
    #[serde(default)]
    events: EventRules,
    members: Vec<PopulationMember>,
    /// Synchronisation time reached.
    time: f64,
    /// Planet steps per window.
    window_steps: u32,
    /// Particle steps taken so far.
    particle_steps: u64,
}

impl Population {
    /// A population at the epoch `time` from initial positions and barycentric velocities
    /// (`states[i] = (position, velocity)` in the integrator's variant: barycentric position
    /// for [`Variant::Barycentric`], heliocentric for [`Variant::Mixed`]), each particle's
    /// first physical step `initial_dt` (see [`ParticleIntegrator::particle`]), identifiers
    /// `ids` (one per state, distinct). The ephemeris is extended to `time` if needed; the
    /// particles are built in parallel. Errors name the offending particle by its identifier.
    pub fn new(
        ephemeris: Ephemeris,
        integrator: ParticleIntegrator,
        rules: RemovalRules,
        time: f64,
        initial_dt: f64,
        states: &[(Vec3, Vec3)],
        ids: &[u64],
    ) -> Result<Self, SymplecticError> {
        Self::build(
            ephemeris,
            integrator,
            rules,
            time,
            |_| initial_dt,
            states,
            ids,
        )
    }

    /// [`Population::new`] with each particle's first physical step given (`initial_dts[i]`
    /// for `states[i]`): for populations spread over distances where one first step does not
    /// fit all (the step law is `Δt ∝ r` far from the planets, so a first step proportional to
    /// the initial distance gives every particle the same step in `s`).
    pub fn with_first_steps(
        ephemeris: Ephemeris,
        integrator: ParticleIntegrator,
        rules: RemovalRules,
        time: f64,
        initial_dts: &[f64],
        states: &[(Vec3, Vec3)],
        ids: &[u64],
    ) -> Result<Self, SymplecticError> {
        if initial_dts.len() != states.len() {
            return Err(SymplecticError::InvalidParameter {
                name: "initial_dts",
                value: initial_dts.len() as f64,
                reason: "need one first step per particle state",
            });
        }
        Self::build(
            ephemeris,
            integrator,
            rules,
            time,
            |i| initial_dts[i],
            states,
            ids,
        )
    }

    fn build(
        mut ephemeris: Ephemeris,
        integrator: ParticleIntegrator,
        rules: RemovalRules,
        time: f64,
        initial_dt: impl Fn(usize) -> f64 + Sync,
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
            .enumerate()
            .map(|(i, (&(position, velocity), &id))| {
                let particle = integrator
                    .particle_from_bodies(
                        position,
                        velocity,
                        time,
                        initial_dt(i),
                        &bodies,
                        &planets,
                    )
                    .map_err(|e| SymplecticError::InvalidState {
                        what: "population particle",
                        reason: format!("particle {id}: {e}"),
                    })?;
                Ok(PopulationMember {
                    id,
                    particle,
                    status: ParticleStatus::Active,
                    sun_position: bodies.positions[0],
                    encounter: None,
                    encounters_begun: 0,
                    tally: EncounterTally::default(),
                    events: None,
                })
            })
            .collect::<Result<Vec<_>, SymplecticError>>()?;
        let mut population = Self {
            ephemeris,
            integrator,
            rules,
            encounters: None,
            events: EventRules::default(),
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

    /// Integrates the particles through close encounters with `encounters`
    /// ([`Encounters`], the module [`encounter`](crate::encounter)) instead of removing them;
    /// `None` turns it off. Barycentric variant only, and not with the removal rule
    /// [`RemovalRules::hill_factor`] (one removes at Hill-sphere entry, the other integrates
    /// through it).
    pub fn set_encounters(
        &mut self,
        encounters: Option<Encounters>,
    ) -> Result<(), SymplecticError> {
        if let Some(e) = &encounters {
            e.validate()?;
            if self.integrator.variant != Variant::Barycentric {
                return Err(SymplecticError::InvalidParameter {
                    name: "encounters",
                    value: e.hill_factor,
                    reason: "close encounters are integrated for the barycentric variant only",
                });
            }
            if let Some(f) = self.rules.hill_factor {
                return Err(SymplecticError::InvalidParameter {
                    name: "hill_factor",
                    value: f,
                    reason: "removes at Hill-sphere entry, while `encounters` integrates through it: set one of them",
                });
            }
        }
        self.encounters = encounters;
        Ok(())
    }

    /// Records `events` from now on ([`EventRules`]; the default records none). Errors name
    /// the field of a bad value; the Tisserand crossing needs a planet named Jupiter.
    pub fn set_events(&mut self, events: EventRules) -> Result<(), SymplecticError> {
        events.validate()?;
        if events.tisserand_crossing && self.jupiter_index().is_none() {
            return Err(SymplecticError::InvalidParameter {
                name: "events.tisserand_crossing",
                value: 1.0,
                reason: "needs a planet named Jupiter (Planets::with_names_and_radii)",
            });
        }
        self.events = events;
        Ok(())
    }

    /// What is recorded without removing.
    pub fn events(&self) -> &EventRules {
        &self.events
    }

    /// Jupiter's index among the bodies (the Sun is 0), if a planet is so named.
    fn jupiter_index(&self) -> Option<usize> {
        let planets = self.ephemeris.planets();
        (1..=planets.len()).find(|&j| planets.name(j) == "Jupiter")
    }

    /// The close-encounter settings, if any.
    pub fn encounters(&self) -> Option<Encounters> {
        self.encounters
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
        let (active, encounters_begun) = self
            .members
            .par_iter()
            .with_min_len(4096)
            .map(|m| {
                (
                    usize::from(m.status == ParticleStatus::Active),
                    u64::from(m.encounters_begun),
                )
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        PopulationProgress {
            time: self.time,
            particle_steps: self.particle_steps,
            active,
            removed: self.members.len() - active,
            encounters_begun,
        }
    }

    /// Switches to the encounter mode per close encounter with a planet, over every
    /// particle, active or removed ([`EncounterTally`] defines an encounter): the count of
    /// encounters and of their switches, the mean and the most in one.
    pub fn switches_per_encounter(&self) -> SwitchesPerEncounter {
        self.members
            .par_iter()
            .with_min_len(4096)
            .fold(SwitchesPerEncounter::default, |s, m| s.add(&m.tally))
            .reduce(SwitchesPerEncounter::default, SwitchesPerEncounter::join)
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
        let jupiter = self.jupiter_index();
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
            let (integrator, rules) = (self.integrator, (self.rules, self.encounters));
            let events = (&self.events, jupiter);
            let (extension, (steps, beyond)) = rayon::join(
                || ephemeris.extension(ahead),
                || run_window(ephemeris, integrator, rules, events, members, end, path),
            );
            self.particle_steps += steps;
            self.ephemeris.append(extension?)?;
            // Ctrl-C: the members stopped where they were, each on its own clock.
            crate::guard::check_stop("advancing the population")?;
            needed = beyond;
            self.time = self.time.max(end);
            on_sync(&self.progress());
        }
        self.time = self.time.max(t_end);
        Ok(self.progress())
    }

    fn oldest_active_time(&self) -> Option<f64> {
        // In parallel: once per window over every member (the minimum of finite times does
        // not depend on the order).
        self.members
            .par_iter()
            .with_min_len(4096)
            .filter(|m| m.status == ParticleStatus::Active)
            .map(|m| m.particle.time)
            .reduce_with(f64::min)
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
            encounters: self.encounters,
            events: self.events.clone(),
            members: Vec::new(),
            time: self.time,
            window_steps: self.window_steps,
            particle_steps: self.particle_steps,
        }
    }

    /// Joins shards of one population advanced to the same time ([`Population::shard`]): the
    /// members in identifier order, the ephemeris covering all of them. Errors if the shards
    /// differ in integrator, rules, event rules, planets' step or time, or share an identifier.
    pub fn merge(shards: Vec<Self>) -> Result<Self, SymplecticError> {
        let Some(first) = shards.first() else {
            return Err(SymplecticError::InvalidParameter {
                name: "shards",
                value: 0.0,
                reason: "nothing to merge",
            });
        };
        for (k, s) in shards.iter().enumerate().skip(1) {
            let differ = |reason: String| SymplecticError::InvalidState {
                what: "merging shards",
                reason: format!("shard {k} and shard 0 {reason}"),
            };
            if s.time.to_bits() != first.time.to_bits() {
                return Err(differ(format!(
                    "are at different times, t = {} and {} days ({} and {} years): advance every shard to the same time first",
                    s.time,
                    first.time,
                    s.time / 365.25,
                    first.time / 365.25
                )));
            }
            let same = s.integrator == first.integrator
                && s.rules == first.rules
                && s.encounters == first.encounters
                && s.events == first.events
                && s.ephemeris.integrator() == first.ephemeris.integrator()
                && s.ephemeris.grid_time(0).to_bits() == first.ephemeris.grid_time(0).to_bits();
            if !same {
                return Err(differ(
                    "differ in integrator, removal rules, encounters, event rules or planets: not shards of one population"
                        .into(),
                ));
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
            &SavedEnvelope {
                format: POPULATION_FORMAT,
                version: POPULATION_VERSION,
                population: self,
            },
        )
    }

    /// Reads a population written by [`Population::save`]; refuses a foreign, truncated or
    /// other-version file by name. A resumed population continues bit for bit. A version 1
    /// file (before the hand-back radius) goes on as it was integrated: its encounter
    /// settings, which have no [`Encounters::hand_back_hill_factor`], hand back at
    /// `hill_factor`.
    pub fn load(path: &Path) -> Result<Self, SymplecticError> {
        let e: Envelope = crate::load_checkpoint(path)?;
        if e.format != POPULATION_FORMAT || !(1..=POPULATION_VERSION).contains(&e.version) {
            return Err(SymplecticError::Checkpoint {
                path: path.display().to_string(),
                reason: format!(
                    "format {:?} version {}, expected {POPULATION_FORMAT:?} version 1 to {POPULATION_VERSION}",
                    e.format, e.version
                ),
            });
        }
        let mut population = e.population;
        if e.version == 1 {
            population.keep_version_1_hand_back();
        }
        Ok(population)
    }

    /// A population of a version 1 checkpoint, whose encounter settings had no hand-back
    /// radius (read as the default, 3.5 Hill radii): handed back at its switch radius, as
    /// it was integrated up to the checkpoint, so that it goes on the same way.
    pub(crate) fn keep_version_1_hand_back(&mut self) {
        if let Some(e) = &mut self.encounters {
            e.hand_back_hill_factor = e.hill_factor;
        }
    }
}

const POPULATION_FORMAT: &str = "symplectic-population";
/// 2: [`Encounters::hand_back_hill_factor`] and [`PopulationMember::encounters_begun`];
/// 3: the removal rules `sun_collision`, `min_distance`, `max_distance`, the event rules and
/// the members' event logs (a version 1 or 2 file reads them as off and empty), and
/// [`Encounter::state`](crate::Encounter) holds the particle only (and its `p₄`); an
/// encounter state of an older file (the Sun, the planets and the particle) is converted
/// when the member next steps.
const POPULATION_VERSION: u32 = 3;

/// [`Envelope`] as written, borrowing the population (no copy of it).
#[derive(Serialize)]
struct SavedEnvelope<'a> {
    format: &'a str,
    version: u32,
    population: &'a Population,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Envelope {
    format: String,
    version: u32,
    population: Population,
}
