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
//! **How.** The planets at the particle's own times are not interpolated during an
//! encounter: the quintic Hermite interpolant's error, `≈ (ωτ)⁶/46080` of the orbit radius
//! ([`Ephemeris`](crate::Ephemeris)), is 1.6·10⁻⁴ AU for Jupiter on the default 730.5-day
//! grid, 0.5 % of an impact distance of 0.1 R_H (0.036 AU). As the paper does for its
//! particle times (eqs. 33–34), the planets are advanced from the last grid state at or
//! before the particle's time, here by the same integrator as the particle: the Sun, the
//! planets and the particle are integrated together in barycentric coordinates (the
//! particle massless) by the Bulirsch–Stoer method (module `bulirsch_stoer`) with a relative
//! tolerance per step [`Encounters::tolerance`], steps fitted to the encounter by the error
//! control. The particle keeps its own clock; nothing depends on the window or on the other
//! particles, so the population stays bit-identical across threads, shards, checkpoints and
//! lanes.
//!
//! **Hand-back.** After a step of the encounter integrator, the particle returns to the map
//! when it is outside [`Encounters::hand_back_hill_factor`] Hill radii of every planet (3.5
//! by default, beyond the switch's 3), `F₁ ≥ ¾ (B₀ + B₁/r)` with the planets from the
//! ephemeris (a margin above the switch's ½), and at least one map step's time (`h/F₁` at
//! the switch) has passed since the switch. It keeps its step `h` in the new variable `s`;
//! `p₄ = −H` is set anew with the ephemeris' planets.
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
//! counts the switches of each particle.
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
//! not planetocentric, coordinates; the error control works on each object's position and
//! velocity vectors, so the particle's relative error per step is bounded by the tolerance
//! against its barycentric distance (about 5 AU near Jupiter: `5·10⁻¹²` AU per step at the
//! default tolerance, against a closest approach of 0.01 AU or more).

pub(crate) mod bulirsch_stoer;

use serde::{Deserialize, Serialize};

use crate::ephemeris::{BodyStates, GridView};
use crate::particles::{ParticleIntegrator, TestParticle};
use crate::{SymplecticError, Vec3};
use bulirsch_stoer::{BulirschStoer, Scratch};

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

/// A particle in the encounter mode: the Sun, the planets and the particle integrated
/// together from the last planet grid state before the switch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Encounter {
    /// Time of `state`.
    pub time: f64,
    /// Barycentric positions of the Sun, the planets and the particle (3 values each), then
    /// their velocities.
    pub state: Vec<f64>,
    /// The next step the integrator proposes (days).
    pub next_step: f64,
    /// When the particle switched to this mode.
    pub since: f64,
    /// The earliest time it may be handed back (one map step after the switch).
    pub earliest_hand_back: f64,
    /// Steps of the encounter integrator so far.
    pub steps: u64,
}

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

impl Encounter {
    /// Switches `p` (barycentric, at its time) to the encounter mode: the planets at the grid
    /// state at or before `p.time` are advanced to `p.time` by the integrator, then joined by
    /// the particle.
    pub(crate) fn begin(
        p: &TestParticle,
        grid: &GridView<'_>,
        settings: &Encounters,
        map_dt: f64,
        scratch: &mut EncounterScratch,
    ) -> Result<Self, SymplecticError> {
        let t_grid = grid.grid_time_at_or_before(p.time)?;
        grid.interpolate(t_grid, &mut scratch.bodies, false)?;
        let n1 = scratch.bodies.gm.len();
        let planets = &mut scratch.planets;
        planets.clear();
        planets.extend(
            scratch
                .bodies
                .positions
                .iter()
                .flat_map(|x| x.iter().copied()),
        );
        planets.extend(
            scratch
                .bodies
                .velocities
                .iter()
                .flat_map(|x| x.iter().copied()),
        );
        let bs = settings.integrator();
        let mut t = t_grid;
        let mut h = grid.step() / 8.0;
        let mut forces = 0;
        while t < p.time {
            let remaining = p.time - t;
            let taken = bs.step(
                &scratch.bodies.gm,
                planets,
                &mut t,
                h,
                remaining,
                &mut scratch.bs,
                &mut forces,
            )?;
            // The last step is cut to land on the particle's time; `t` is set to it exactly.
            if taken.step >= remaining {
                t = p.time;
            }
            h = taken.next;
        }
        let mut state = Vec::with_capacity(6 * (n1 + 1));
        state.extend_from_slice(&planets[..3 * n1]);
        state.extend(p.position.iter().copied());
        state.extend_from_slice(&planets[3 * n1..]);
        state.extend(p.velocity.iter().copied());
        Ok(Self {
            time: p.time,
            state,
            next_step: h.min(map_dt.max(f64::MIN_POSITIVE)),
            since: p.time,
            earliest_hand_back: p.time + map_dt,
            steps: 0,
        })
    }

    /// Number of bodies (Sun and planets).
    fn bodies(&self) -> usize {
        self.state.len() / 6 - 1
    }

    fn position(&self, object: usize) -> Vec3 {
        Vec3::from_column_slice(&self.state[3 * object..3 * object + 3])
    }

    fn velocity(&self, object: usize) -> Vec3 {
        let o = 3 * (self.bodies() + 1) + 3 * object;
        Vec3::from_column_slice(&self.state[o..o + 3])
    }

    /// The particle's barycentric position and velocity.
    pub(crate) fn particle(&self) -> (Vec3, Vec3) {
        let k = self.bodies();
        (self.position(k), self.velocity(k))
    }

    /// One step of the integrator (never cut: its length depends on the state only).
    pub(crate) fn step(
        &mut self,
        gm: &[f64],
        settings: &Encounters,
        scratch: &mut EncounterScratch,
        forces: &mut u64,
    ) -> Result<(), SymplecticError> {
        let taken = settings.integrator().step(
            gm,
            &mut self.state,
            &mut self.time,
            self.next_step,
            f64::INFINITY,
            &mut scratch.bs,
            forces,
        )?;
        self.next_step = taken.next;
        self.steps += 1;
        Ok(())
    }

    /// The particle against the planets: the nearest in Hill radii and a collision, if any.
    /// `hill_coefficients[j]` is `(m_j/3m₀)^{1/3}`, `radii[j]` the radius of planet `j + 1`.
    pub(crate) fn geometry(&self, hill_coefficients: &[f64], radii: &[Option<f64>]) -> Geometry {
        let (q, _) = self.particle();
        let sun = self.position(0);
        let mut g = Geometry {
            nearest: 1,
            nearest_ratio: f64::INFINITY,
            collision: None,
        };
        for (j, c) in hill_coefficients.iter().enumerate() {
            let planet = self.position(j + 1);
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

    /// The particle as a map particle at its time, with the ephemeris' `bodies` at that
    /// time: `p₄ = −H`, the map step `step` kept.
    pub(crate) fn hand_back(
        &self,
        integrator: &ParticleIntegrator,
        previous: &TestParticle,
        bodies: &BodyStates,
    ) -> TestParticle {
        let (position, velocity) = self.particle();
        let mut p = TestParticle {
            position,
            velocity,
            time: self.time,
            p4: 0.0,
            step: previous.step,
            steps: previous.steps,
            work: previous.work,
        };
        p.p4 = -integrator.hamiltonian(&p, bodies);
        p
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
/// with the encounter integrator of a [`Population`](crate::Population) (the same steps,
/// except the last, cut to land on `t_end`): a single encounter, for comparison with other
/// codes.
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
    let (mut t, mut h, mut steps, mut forces) = (bodies.time, 1.0, 0, 0);
    let mut scratch = Scratch::default();
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
        let taken = bs.step(
            &bodies.gm,
            &mut state,
            &mut t,
            h,
            remaining,
            &mut scratch,
            &mut forces,
        )?;
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
    planets: Vec<f64>,
}
