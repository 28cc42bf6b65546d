//! Close encounters: a particle of a [`Population`](crate::Population) that comes near a
//! planet, or where the map's regularisation no longer dominates, is integrated by an
//! adaptive high-order integrator of its full equations of motion, then handed back to the
//! map.
//!
//! **When.** At the end of each map step (the population's removal checks), a particle
//! switches to the encounter mode when
//!
//! - it is within [`Encounters::hill_factor`] Hill radii of a planet (`R_H = |Q_j|
//!   (m_j/3m₀)^{1/3}`), 3 by default: the changeover distance of MERCURY's hybrid integrator
//!   (J. E. Chambers, "A hybrid symplectic integrator that permits close encounters between
//!   massive bodies", *MNRAS* 304, 793–799 (1999), doi:10.1046/j.1365-8711.1999.02379.x) and
//!   the default `r_crit_hill = 3` of REBOUND's MERCURIUS (H. Rein, D. M. Hernandez, D. Tamayo
//!   et al., "Hybrid symplectic integrators for planetary dynamics", *MNRAS* 485, 5490–5497
//!   (2019), doi:10.1093/mnras/stz769). Inside it the planet's pull exceeds about 1/9 of the
//!   Sun's tidal term only at the Hill radius itself, and is below 4 % of the Sun's at 3 R_H,
//!   so the map's splitting error there is what it is in the free orbit; closer in, a step
//!   of the map (its length set by the distance to the Sun, `Δt ∝ r/B₁`) no longer resolves
//!   the planetocentric orbit;
//! - or `F₁ = K₁/r` (Chegodaeva 2004, eq. 22) has fallen below half its regularising part
//!   `B₀ + B₁/r` — the paper's condition 35 read as a factor 2, the reading of
//!   [`MIXED_DOMAIN_MIN_RATIO`](crate::MIXED_DOMAIN_MIN_RATIO) — or a step of the map failed
//!   because `F₀` or `F₁` stopped being positive. Such a particle (a perihelion inside the
//!   range where `B₀, B₁` dominate: with the paper's `B₁ = 0.21·10⁻⁶` below about 14 AU) is
//!   no longer removed as `regularisation_lost`: the encounter integrator takes over until
//!   the condition holds again.
//!
//! **How.** The planets are one function of time in both modes: the ephemeris' interpolant
//! ([`Ephemeris`](crate::Ephemeris)), read by the map at its kicks and by the encounter
//! integrator at every substep. The particle alone is integrated, in barycentric coordinates,
//! by the Bulirsch–Stoer method (module `bulirsch_stoer`) with a relative tolerance per step
//! [`Encounters::tolerance`] and steps fitted to the encounter by the error control, together
//! with its `p₄` (`dp₄/dt = −∂H/∂t`, the term the map's kicks add), so that the change of
//! `H + p₄`, a constant of the exact motion, over the encounter is its integration error,
//! which the hand-back passes on to the map (*Hand-back*). Nothing jumps at the switch or
//! the hand-back: the particle's position and velocity are handed over as they are and the
//! planets are the same. The geometry of an
//! encounter is then set by the ephemeris' accuracy (measured against the Newtonian flow of
//! its grid states: [`Ephemeris`](crate::Ephemeris), 2.1·10⁻⁹ AU for Jupiter at the 91.3125 d
//! planet step of the shipped populations) and by the tolerance. (Until this version the
//! planets were integrated here from the last grid state, up to a grid step back, so that
//! they jumped by the interpolant's error at the switch and back at the hand-back, and `p₄`
//! was reset at the hand-back, which hid the jump.) The particle keeps its own clock;
//! nothing depends on the window or on the other particles, so the population stays
//! bit-identical across threads, shards, checkpoints and lanes: a step that needs the planets
//! beyond the ephemeris' newest grid time is abandoned with the state unchanged and redone,
//! with the same result, in the next window.
//!
//! **Hand-back.** After a step of the encounter integrator, the particle returns to the map
//! when it is outside [`Encounters::hand_back_hill_factor`] Hill radii of every planet (3.5
//! by default, beyond the switch's 3), `F₁ ≥ ¾ (B₀ + B₁/r)` (a margin above the switch's ½),
//! and at least one map step's time (`h/F₁` at the switch) has passed since the switch, and
//! if the map's `F₀` is then at least `½ (B₀ + B₁/r)`. It keeps its step `h` in the new
//! variable `s`. The two modes conserve different functions of the same state: the encounter
//! integrator, the exact motion's `K = H + p₄ = F₀ − F₁`; the map, whose pieces are the
//! flows of `ln F₀` and `−ln F₁` (the logarithmic Hamiltonian of S. Mikkola and K. Tanikawa,
//! "Explicit symplectic algorithms for time-transformed Hamiltonians", *Celest. Mech. Dyn.
//! Astron.* 74, 287–295 (1999), doi:10.1023/A:1008368322547), the ratio `F₀/F₁`. Carrying
//! `K` through an encounter would turn the map's small error `F₀/F₁ − 1` into
//! `(F₀/F₁ − 1) · F₁(switch)/F₁(hand-back)`: `F₁` holds the nearest planet's `G m/|q − Q|`,
//! larger at the switch (3 R_H) than at the hand-back (3.5 R_H), by 2.2 % on average in the
//! Centaur population, so that the error grew geometrically over a comet's encounters (after
//! some 270 of them to `|K/F₁| ≈ 1`, where `F₀` reaches zero and the map fails). So the
//! hand-back sets `p₄` such that `F₀/F₁` is the map's value at the switch plus the change of
//! `K` over the encounter (the encounter integrator's error, which the energy diagnostic then
//! sees): `K = F₁ (F₀/F₁|switch − 1) + ΔK`. (Where `F₀` or `F₁` was not positive at the
//! switch, the map's ratio is taken as 1: only `ΔK` is kept.)
//!
//! *Hysteresis.* Both margins keep a particle from going back and forth across one
//! boundary. A sharp switch in and out at the same radius does: a comet skimming 3 R_H
//! switches at every dip below it. MERCURY and MERCURIUS have no such boundary: their
//! changeover function `K(r)` (Chambers 1999, eq. 10: `10y³ − 15y⁴ + 6y⁵` with
//! `y = (r − 0.1 r_crit)/(0.9 r_crit)`) hands the planet's force over gradually across most of
//! `r_crit`. Here the switch stays sharp (below) and the hand-back radius is larger instead:
//! 3.5 R_H, a band of 1/6 of the switch radius. That covers what the distance of a slow
//! encounter does by itself over an orbit: a comet on Jupiter's orbit a fixed time behind
//! it is at a distance `∝ 1 + e_J cos ν` (`ν` Jupiter's true anomaly), while
//! `R_H ∝ |Q_J| ∝ 1/(1 + e_J cos ν)`, so its distance in Hill radii goes as
//! `(1 + e_J cos ν)²`, ±10 % for Jupiter's `e_J = 0.048`: trailing Jupiter at 3 R_H, it dips
//! below and rises above 3 R_H once per Jupiter orbit. Jupiter's pull against the Sun's
//! tidal acceleration `3Ω²r` is `(R_H/r)³`: 3.7 % at 3 R_H, 2.3 % at 3.5 R_H, so the map is
//! handed no particle it would not have kept. `hand_back_hill_factor = hill_factor` gives
//! the switch without hysteresis. [`PopulationMember::encounters_begun`](crate::PopulationMember)
//! counts the switches of each particle, [`EncounterTally`](crate::EncounterTally) its close
//! encounters with the planets (from a switch inside the switch radius until it is beyond
//! twice that radius) and the switches in each, and
//! [`Population::switches_per_encounter`](crate::Population::switches_per_encounter) their
//! mean and largest number over a population (the population table's
//! `planet_encounters`, `planet_encounter_switches` and `max_switches_per_encounter`).
//!
//! **Ends** during an encounter (checked after each step of the encounter integrator): a
//! collision (closer to a planet's centre than its radius,
//! [`Planets::radius`](crate::Planets::radius)); and, outside every planet's `hill_factor`
//! Hill radii (where barycentric elements mean something), the population's perihelion and
//! ejection rules ([`RemovalRules`](crate::RemovalRules)).
//!
//! **Deviations from the codes cited.** MERCURY and MERCURIUS change over smoothly between
//! the map and the close-encounter integrator; here the switch is sharp, as in SWIFT's RMVS
//! (H. F. Levison and M. J. Duncan, "The long-term dynamical behavior of short-period
//! comets", *Icarus* 108, 18–36 (1994), doi:10.1006/icar.1994.1039), which a test particle
//! allows: its switch changes no planet's orbit. The encounter is integrated in barycentric,
//! not planetocentric, coordinates; the error control works on the particle's position and
//! velocity vectors (and `p₄`), so its relative error per step is bounded by the tolerance
//! against its barycentric distance (about 5 AU near Jupiter: `5·10⁻¹²` AU per step at the
//! default tolerance, against a closest approach of 0.01 AU or more). MERCURY integrates the
//! planets along with the encounter; here they are massive bodies of the ephemeris, whose
//! states the comet does not change.

pub(crate) mod bulirsch_stoer;

use serde::{Deserialize, Serialize};

use crate::ephemeris::{BodyStates, GridView};
use crate::particles::{ParticleIntegrator, TestParticle};
use crate::{SymplecticError, Vec3, WorkCounters};
use bulirsch_stoer::{Bodies, BulirschStoer, Field, Scratch};

/// Default switch distance, in Hill radii (MERCURY's and MERCURIUS' default).
pub const DEFAULT_ENCOUNTER_HILL_FACTOR: f64 = 3.0;

/// Default hand-back distance, in Hill radii: beyond the switch's
/// [`DEFAULT_ENCOUNTER_HILL_FACTOR`] by the ±10 % that Jupiter's eccentricity makes of a
/// slow encounter's distance in Hill radii over an orbit (module [`encounter`](self),
/// *Hysteresis*).
pub const DEFAULT_ENCOUNTER_HAND_BACK_HILL_FACTOR: f64 = 3.5;

/// Default relative tolerance per step of the encounter integrator.
pub const DEFAULT_ENCOUNTER_TOLERANCE: f64 = 1e-12;

/// Integration through close encounters in a [`Population`](crate::Population) (barycentric
/// variant): see the module [`encounter`](self).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Encounters {
    /// Switch distance in Hill radii ([`DEFAULT_ENCOUNTER_HILL_FACTOR`]).
    #[serde(default = "default_hill_factor")]
    pub hill_factor: f64,
    /// Hand-back distance in Hill radii, at least `hill_factor`
    /// ([`DEFAULT_ENCOUNTER_HAND_BACK_HILL_FACTOR`]): a particle in the encounter mode
    /// returns to the map only outside it (`hill_factor`: no hysteresis).
    #[serde(default = "default_hand_back_hill_factor")]
    pub hand_back_hill_factor: f64,
    /// Relative tolerance per step of the Bulirsch–Stoer integrator
    /// ([`DEFAULT_ENCOUNTER_TOLERANCE`]).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
}

fn default_hill_factor() -> f64 {
    DEFAULT_ENCOUNTER_HILL_FACTOR
}

fn default_hand_back_hill_factor() -> f64 {
    DEFAULT_ENCOUNTER_HAND_BACK_HILL_FACTOR
}

fn default_tolerance() -> f64 {
    DEFAULT_ENCOUNTER_TOLERANCE
}

impl Default for Encounters {
    fn default() -> Self {
        Self {
            hill_factor: DEFAULT_ENCOUNTER_HILL_FACTOR,
            hand_back_hill_factor: DEFAULT_ENCOUNTER_HAND_BACK_HILL_FACTOR,
            tolerance: DEFAULT_ENCOUNTER_TOLERANCE,
        }
    }
}

impl Encounters {
    pub(crate) fn validate(&self) -> Result<(), SymplecticError> {
        if !(self.hill_factor.is_finite() && self.hill_factor > 0.0) {
            return Err(SymplecticError::InvalidParameter {
                name: "encounters.hill_factor",
                value: self.hill_factor,
                reason: "must be finite and > 0",
            });
        }
        let hand_back = self.hand_back_hill_factor;
        if !(hand_back.is_finite() && hand_back > 0.0) {
            return Err(SymplecticError::InvalidParameter {
                name: "encounters.hand_back_hill_factor",
                value: hand_back,
                reason: "must be finite and > 0",
            });
        }
        if hand_back < self.hill_factor {
            return Err(SymplecticError::InvalidParameter {
                name: "encounters.hand_back_hill_factor",
                value: hand_back,
                reason: "must be >= encounters.hill_factor, the switch-in distance (the default \
                         hand-back is 3.5 Hill radii: with hill_factor above it, give \
                         hand_back_hill_factor too)",
            });
        }
        if !(self.tolerance.is_finite() && self.tolerance > 1e-15 && self.tolerance < 1e-3) {
            return Err(SymplecticError::InvalidParameter {
                name: "encounters.tolerance",
                value: self.tolerance,
                reason: "must lie between 1e-15 and 1e-3",
            });
        }
        Ok(())
    }

    pub(crate) fn integrator(&self) -> BulirschStoer {
        BulirschStoer {
            tolerance: self.tolerance,
        }
    }
}

/// A particle in the encounter mode: its barycentric position and velocity and its `p₄`,
/// integrated among the planets of the ephemeris (the same function of time the map reads).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Encounter {
    /// Time of `state`.
    pub time: f64,
    /// The particle's barycentric position (3 values), velocity (3 values) and `p₄` (1 value,
    /// `dp₄/dt = −∂H/∂t`: `H + p₄` is a constant of the encounter's exact motion, as of the
    /// map's).
    pub state: Vec<f64>,
    /// The next step the integrator proposes (days).
    pub next_step: f64,
    /// When the particle switched to this mode.
    pub since: f64,
    /// The earliest time it may be handed back (one map step after the switch).
    pub earliest_hand_back: f64,
    /// Steps of the encounter integrator so far.
    pub steps: u64,
    /// `H + p₄` at the switch (AU²/day²): the encounter's own error is the change of
    /// `H + p₄` from this value at the hand-back.
    #[serde(default)]
    pub switch_energy: f64,
    /// `F₀/F₁` of the map at the switch (1 if either was not positive): the quantity the
    /// map conserves (module [`encounter`](self), *Hand-back*), continued at the hand-back.
    #[serde(default = "unit_ratio")]
    pub switch_ratio: f64,
}

fn unit_ratio() -> f64 {
    1.0
}

/// Length of [`Encounter::state`]: position, velocity, `p₄`.
pub(crate) const ENCOUNTER_STATE_LEN: usize = 7;

/// Where a particle in the encounter mode stands against the planets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Geometry {
    /// The planet (1-based) closest in units of its Hill radius, that ratio, its distance
    /// and its Hill radius.
    pub nearest: usize,
    pub nearest_ratio: f64,
    /// A planet (1-based) whose radius the particle is inside, with the distance and radius.
    pub collision: Option<(usize, f64, f64)>,
}

/// The encounter mode's right-hand side: a massless particle among the bodies of the
/// ephemeris at each substep's time, with `dp₄/dt = Σ_j G m_j (q − Q_j)·V_j/|q − Q_j|³`
/// (`−∂H/∂t` of the barycentric `H`, the term the map's kicks add to `p₄`).
struct AmongBodies<'a, 'b> {
    grid: &'a GridView<'b>,
    bodies: &'a mut BodyStates,
    /// The interpolations and pair terms counted so far.
    work: &'a mut WorkCounters,
}

impl Field for AmongBodies<'_, '_> {
    fn derivative(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SymplecticError> {
        self.grid.interpolate(t, self.bodies, false)?;
        let q = [y[0], y[1], y[2]];
        let (mut a, mut dp4) = ([0.0; 3], 0.0);
        for ((gm, qj), vj) in self
            .bodies
            .gm
            .iter()
            .zip(&self.bodies.positions)
            .zip(&self.bodies.velocities)
        {
            let d = [q[0] - qj[0], q[1] - qj[1], q[2] - qj[2]];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let gm_r3 = gm / (r2 * r2.sqrt());
            for c in 0..3 {
                a[c] -= gm_r3 * d[c];
            }
            dp4 += gm_r3 * (d[0] * vj[0] + d[1] * vj[1] + d[2] * vj[2]);
        }
        self.work.interpolations += 1;
        self.work.force_evaluations += self.bodies.gm.len() as u64;
        dy[..3].copy_from_slice(&y[3..6]);
        dy[3..6].copy_from_slice(&a);
        dy[6] = dp4;
        Ok(())
    }
}

impl Encounter {
    /// Switches `p` (barycentric, at its time) to the encounter mode: its position, velocity
    /// and `p₄` as they are (the planets are the ephemeris' in both modes, so nothing jumps);
    /// the first step proposed is one map step's time `map_dt` (a grid step's eighth if that
    /// is not positive). `switch` holds the map's `H + p₄` and `F₁` there (`None` if the
    /// planets could not be read).
    pub(crate) fn begin(
        p: &TestParticle,
        grid: &GridView<'_>,
        map_dt: f64,
        switch: Option<(f64, f64)>,
    ) -> Self {
        let mut state = Vec::with_capacity(ENCOUNTER_STATE_LEN);
        state.extend(p.position.iter().copied());
        state.extend(p.velocity.iter().copied());
        state.push(p.p4);
        let first = if map_dt.is_finite() && map_dt > 0.0 {
            map_dt
        } else {
            grid.step() / 8.0
        };
        let (switch_energy, switch_ratio) = match switch {
            Some((energy, f1)) if f1 > 0.0 && f1 + energy > 0.0 => (energy, (f1 + energy) / f1),
            Some((energy, _)) => (energy, 1.0),
            None => (0.0, 1.0),
        };
        Self {
            time: p.time,
            state,
            next_step: first,
            since: p.time,
            earliest_hand_back: p.time + map_dt.max(0.0),
            steps: 0,
            switch_energy,
            switch_ratio,
        }
    }

    /// Converts the state of a checkpoint written before version 3 (positions of the Sun, the
    /// planets and the particle, then their velocities) to this version's (the particle and
    /// its `p₄`): the particle's position and velocity kept, `p₄ = −H` among `bodies` (the
    /// ephemeris' at the encounter's time), as that version's hand-back set it. A state of
    /// this version is left alone; one of neither layout is refused by name.
    pub(crate) fn upgrade(
        &mut self,
        integrator: &ParticleIntegrator,
        previous: &TestParticle,
        bodies: &BodyStates,
    ) -> Result<(), SymplecticError> {
        let len = self.state.len();
        if len == ENCOUNTER_STATE_LEN {
            return Ok(());
        }
        let objects = len / 6;
        if len != 6 * objects || objects != bodies.gm.len() + 1 {
            return Err(SymplecticError::InvalidState {
                what: "encounter state",
                reason: format!(
                    "{len} values: expected {ENCOUNTER_STATE_LEN} (position, velocity, p4), or \
                     {} as written before checkpoint version 3",
                    6 * (bodies.gm.len() + 1)
                ),
            });
        }
        let k = 3 * (objects - 1);
        let mut p = previous.clone();
        p.position = Vec3::from_column_slice(&self.state[k..k + 3]);
        p.velocity = Vec3::from_column_slice(&self.state[3 * objects + k..3 * objects + k + 3]);
        p.time = self.time;
        p.p4 = -integrator.hamiltonian(&p, bodies);
        (self.switch_energy, self.switch_ratio) = (0.0, 1.0);
        self.state.clear();
        self.state
            .extend(p.position.iter().chain(p.velocity.iter()).copied());
        self.state.push(p.p4);
        Ok(())
    }

    /// The particle's barycentric position and velocity.
    pub(crate) fn particle(&self) -> (Vec3, Vec3) {
        (
            Vec3::from_column_slice(&self.state[0..3]),
            Vec3::from_column_slice(&self.state[3..6]),
        )
    }

    /// The particle's `p₄`.
    pub(crate) fn p4(&self) -> f64 {
        self.state[6]
    }

    /// One step of the integrator (never cut: its length depends on the state only), the
    /// planets read from `grid`; its interpolations and pair terms are added to `work`. A
    /// step that needs the planets beyond the grid returns
    /// [`SymplecticError::BeyondEphemeris`] and leaves the encounter as it was.
    pub(crate) fn step(
        &mut self,
        grid: &GridView<'_>,
        settings: &Encounters,
        scratch: &mut EncounterScratch,
        work: &mut WorkCounters,
    ) -> Result<(), SymplecticError> {
        let mut field = AmongBodies {
            grid,
            bodies: &mut scratch.bodies,
            work,
        };
        let result = settings.integrator().step(
            &mut field,
            &mut self.state,
            &mut self.time,
            self.next_step,
            f64::INFINITY,
            &mut scratch.bs,
        );
        let taken = result?;
        self.next_step = taken.next;
        self.steps += 1;
        Ok(())
    }

    /// The particle against the planets of `bodies` (at the particle's time): the nearest in
    /// Hill radii and a collision, if any. `hill_coefficients[j]` is `(m_j/3m₀)^{1/3}`,
    /// `radii[j]` the radius of planet `j + 1`.
    pub(crate) fn geometry(
        &self,
        bodies: &BodyStates,
        hill_coefficients: &[f64],
        radii: &[Option<f64>],
    ) -> Geometry {
        let (q, _) = self.particle();
        let sun = bodies.positions[0];
        let mut g = Geometry {
            nearest: 1,
            nearest_ratio: f64::INFINITY,
            collision: None,
        };
        for (j, c) in hill_coefficients.iter().enumerate() {
            let planet = bodies.positions[j + 1];
            let distance = (q - planet).norm();
            let hill = (planet - sun).norm() * c;
            if distance / hill < g.nearest_ratio {
                g.nearest_ratio = distance / hill;
                g.nearest = j + 1;
            }
            if let Some(r) = radii.get(j).copied().flatten() {
                if distance < r && g.collision.is_none() {
                    g.collision = Some((j + 1, distance, r));
                }
            }
        }
        g
    }

    /// The map's `H + p₄` at the hand-back, where `H` (`hamiltonian`) and `F₁` (`f1`) are
    /// the particle's now: `F₁ (F₀/F₁ at the switch − 1)`, the map's conserved ratio
    /// continued, plus the change of `H + p₄` over the encounter (its integration error).
    /// `F₀ = F₁ + (H + p₄)` is then `F₁ · F₀/F₁ at the switch` plus that error.
    pub(crate) fn hand_back_energy(&self, hamiltonian: f64, f1: f64) -> f64 {
        f1 * (self.switch_ratio - 1.0) + (hamiltonian + self.p4() - self.switch_energy)
    }

    /// The particle as a map particle at its time: position, velocity and `p₄` as integrated,
    /// the map step `step` kept. The population's hand-back then sets `p₄` to
    /// [`Encounter::hand_back_energy`] `− H`.
    pub(crate) fn hand_back(&self, previous: &TestParticle) -> TestParticle {
        let (position, velocity) = self.particle();
        TestParticle {
            position,
            velocity,
            time: self.time,
            p4: self.p4(),
            step: previous.step,
            steps: previous.steps,
            work: previous.work,
        }
    }
}

/// The result of [`integrate_through`].
#[derive(Debug, Clone, PartialEq)]
pub struct EncounterOutcome {
    /// The particle's barycentric position and velocity at the end.
    pub position: Vec3,
    /// The particle's barycentric velocity at the end.
    pub velocity: Vec3,
    /// The bodies' barycentric positions and velocities at the end (Sun first).
    pub bodies: Vec<(Vec3, Vec3)>,
    /// Steps of the integrator.
    pub steps: u64,
    /// Smallest distance to each planet over the step ends (not between them).
    pub closest: Vec<f64>,
}

/// Integrates the Sun and the planets (`bodies`: `G m` and barycentric states at
/// `bodies.time`) and a massless particle (barycentric `position`, `velocity`) to `t_end`
/// with the Bulirsch–Stoer integrator of a [`Population`](crate::Population)'s encounter
/// mode and its tolerance (the last step cut to land on `t_end`), the bodies integrated along
/// with the particle from exact states rather than read from an ephemeris: a single
/// encounter, for comparison with other codes.
pub fn integrate_through(
    bodies: &BodyStates,
    position: Vec3,
    velocity: Vec3,
    t_end: f64,
    settings: &Encounters,
) -> Result<EncounterOutcome, SymplecticError> {
    settings.validate()?;
    let n1 = bodies.gm.len();
    if n1 == 0 || bodies.positions.len() != n1 || bodies.velocities.len() != n1 {
        return Err(SymplecticError::InvalidState {
            what: "encounter bodies",
            reason: format!(
                "{} G m, {} positions, {} velocities: need one of each per body",
                n1,
                bodies.positions.len(),
                bodies.velocities.len()
            ),
        });
    }
    if !(t_end.is_finite() && t_end >= bodies.time) {
        return Err(SymplecticError::InvalidParameter {
            name: "end time",
            value: t_end,
            reason: "must be finite and not before the bodies' time",
        });
    }
    let mut state: Vec<f64> = Vec::with_capacity(6 * (n1 + 1));
    state.extend(bodies.positions.iter().flat_map(|x| x.iter().copied()));
    state.extend(position.iter().copied());
    state.extend(bodies.velocities.iter().flat_map(|x| x.iter().copied()));
    state.extend(velocity.iter().copied());
    let bs = settings.integrator();
    let (mut t, mut h, mut steps) = (bodies.time, 1.0, 0);
    let mut scratch = Scratch::default();
    let mut field = Bodies {
        gm: &bodies.gm,
        forces: 0,
    };
    let mut closest = vec![f64::INFINITY; n1 - 1];
    let distance = |state: &[f64], j: usize| {
        let k = 3 * n1;
        ((state[k] - state[3 * j]).powi(2)
            + (state[k + 1] - state[3 * j + 1]).powi(2)
            + (state[k + 2] - state[3 * j + 2]).powi(2))
        .sqrt()
    };
    while t < t_end {
        let remaining = t_end - t;
        let taken = bs.step(&mut field, &mut state, &mut t, h, remaining, &mut scratch)?;
        if taken.step >= remaining {
            t = t_end;
        }
        h = taken.next;
        steps += 1;
        for (j, c) in closest.iter_mut().enumerate() {
            *c = c.min(distance(&state, j + 1));
        }
    }
    let vec = |o: usize| Vec3::from_column_slice(&state[o..o + 3]);
    let v0 = 3 * (n1 + 1);
    Ok(EncounterOutcome {
        position: vec(3 * n1),
        velocity: vec(v0 + 3 * n1),
        bodies: (0..n1).map(|j| (vec(3 * j), vec(v0 + 3 * j))).collect(),
        steps,
        closest,
    })
}

/// `F₁ = K₁/r` of the barycentric map at `q` among `bodies` and its regularising part
/// `B₀ + B₁/r` (Chegodaeva 2004, eq. 22): the quantities of the switch and hand-back tests.
pub(crate) fn regularisation(
    integrator: &ParticleIntegrator,
    q: &Vec3,
    bodies: &BodyStates,
) -> (f64, f64) {
    let inv_r = 1.0 / q.norm();
    let part = integrator.b0 + integrator.b1 * inv_r;
    let mut f1 = part;
    for (gm, qj) in bodies.gm.iter().zip(&bodies.positions) {
        f1 += gm * (1.0 / (q - qj).norm() - inv_r);
    }
    (f1, part)
}

/// Per-thread buffers of the encounter mode.
#[derive(Debug, Clone, Default)]
pub(crate) struct EncounterScratch {
    bs: Scratch,
    bodies: BodyStates,
}
