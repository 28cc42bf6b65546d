//! Events recorded without ending a particle of a [`Population`](crate::Population): the
//! first time its perihelion falls below a value, its first crossing of `T_J = 3`, and each
//! close approach to a planet (the planet, the time and the distance of the closest
//! approach), as Jupiter-family-comet studies measure them.

use serde::{Deserialize, Serialize};

use crate::classes::JUPITER_SEMI_MAJOR_AXIS_AU;
use crate::{SymplecticError, Vec3};

/// Default of [`EventRules::max_per_particle`].
pub const DEFAULT_MAX_EVENTS_PER_PARTICLE: u32 = 1000;

/// Most values in [`EventRules::perihelion_below`] (one bit each in a particle's
/// [`EventLog`]).
pub const MAX_PERIHELION_THRESHOLDS: usize = 64;

/// What a [`Population`](crate::Population) records about its particles without removing
/// them (all off by default), checked where the removal rules are: at the end of each map
/// step, and at the end of each encounter-integrator step
/// ([`Encounters`](crate::Encounters)). A particle keeps at most
/// [`EventRules::max_per_particle`] events; later ones are counted in
/// [`EventLog::dropped`], never lost silently.
///
/// **Cost.** With any event (or any of the rules [`RemovalRules::sun_collision`],
/// [`RemovalRules::min_distance`], [`RemovalRules::max_distance`]) every step end goes
/// through the scalar checks instead of only the lanes the vector tests flag: measured
/// 0.224 µs per particle step against 0.104 µs without (2000 scattered-disk comets over
/// 5000 years, one thread, S6 planets at 730.5 days, 2026-12-05; the same 7.46·10⁶ steps,
/// the trajectories are unchanged).
///
/// [`RemovalRules::sun_collision`]: crate::RemovalRules::sun_collision
/// [`RemovalRules::min_distance`]: crate::RemovalRules::min_distance
/// [`RemovalRules::max_distance`]: crate::RemovalRules::max_distance
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EventRules {
    /// Perihelion distances (AU, finite, `> 0`, at most [`MAX_PERIHELION_THRESHOLDS`]):
    /// record the first check at which the barycentric osculating perihelion is below each
    /// ([`EventKind::PerihelionBelow`]). Not checked inside the encounter mode's switch
    /// radius, where the barycentric elements do not describe the orbit (as the perihelion
    /// removal rule).
    #[serde(default)]
    pub perihelion_below: Vec<f64>,
    /// Record the first crossing of `T_J = 3` ([`EventKind::TisserandCrossing`]): the
    /// Tisserand parameter with respect to Jupiter
    /// ([`tisserand_jupiter`](crate::tisserand_jupiter), `a_J` =
    /// [`JUPITER_SEMI_MAJOR_AXIS_AU`], inclination to Jupiter's osculating heliocentric orbit
    /// plane at the particle's time, barycentric elements) changes side of 3 between two
    /// checks of a bound orbit. Levison's (1996) boundary between the Jupiter-family comets
    /// and the Encke- and Chiron-type. Not checked inside the switch radius. Needs a planet
    /// named Jupiter.
    #[serde(default)]
    pub tisserand_crossing: bool,
    /// Record each passage inside this radius of a planet ([`EventKind::CloseApproach`]):
    /// the smallest distance sampled at the checks and its time. Map steps are long (a few
    /// percent of an orbit): a radius within the encounter mode's switch radius is sampled
    /// at the encounter integrator's steps.
    #[serde(default)]
    pub close_approach: Option<ApproachRadius>,
    /// Most events kept per particle (`>= 1`; default
    /// [`DEFAULT_MAX_EVENTS_PER_PARTICLE`]): bounds the memory of a population at
    /// `40 × max_per_particle` bytes per particle; events beyond it are counted
    /// ([`EventLog::dropped`]).
    #[serde(default = "default_max_events")]
    pub max_per_particle: u32,
}

fn default_max_events() -> u32 {
    DEFAULT_MAX_EVENTS_PER_PARTICLE
}

impl Default for EventRules {
    fn default() -> Self {
        Self {
            perihelion_below: Vec::new(),
            tisserand_crossing: false,
            close_approach: None,
            max_per_particle: DEFAULT_MAX_EVENTS_PER_PARTICLE,
        }
    }
}

/// The radius of a close approach ([`EventRules::close_approach`]): `{ hill_radii = 1.0 }`
/// or `{ au = 0.1 }` in a population file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ApproachRadius {
    /// In Hill radii of the planet, `|Q_j − Q_☉| (m_j/3m₀)^{1/3}` at the particle's time.
    HillRadii(f64),
    /// In AU.
    Au(f64),
}

impl EventRules {
    /// Whether any event is recorded.
    pub fn any(&self) -> bool {
        !self.perihelion_below.is_empty()
            || self.tisserand_crossing
            || self.close_approach.is_some()
    }

    /// Checks the values; errors name the field.
    pub(crate) fn validate(&self) -> Result<(), SymplecticError> {
        if self.perihelion_below.len() > MAX_PERIHELION_THRESHOLDS {
            return Err(SymplecticError::InvalidParameter {
                name: "events.perihelion_below",
                value: self.perihelion_below.len() as f64,
                reason: "at most 64 perihelion values (MAX_PERIHELION_THRESHOLDS)",
            });
        }
        if let Some(&q) = self
            .perihelion_below
            .iter()
            .find(|q| !(q.is_finite() && **q > 0.0))
        {
            return Err(SymplecticError::InvalidParameter {
                name: "events.perihelion_below",
                value: q,
                reason: "a perihelion distance must be finite and > 0 (AU)",
            });
        }
        if let Some(radius) = self.close_approach {
            let (name, value) = match radius {
                ApproachRadius::HillRadii(f) => ("events.close_approach.hill_radii", f),
                ApproachRadius::Au(r) => ("events.close_approach.au", r),
            };
            if !(value.is_finite() && value > 0.0) {
                return Err(SymplecticError::InvalidParameter {
                    name,
                    value,
                    reason: "a close-approach radius must be finite and > 0",
                });
            }
        }
        if self.max_per_particle == 0 {
            return Err(SymplecticError::InvalidParameter {
                name: "events.max_per_particle",
                value: 0.0,
                reason: "must be >= 1",
            });
        }
        Ok(())
    }
}

/// One event of a particle ([`EventRules`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CometEvent {
    /// When (days): the check at which it was detected, or for a close approach the check
    /// of the smallest distance.
    pub time: f64,
    /// What.
    pub kind: EventKind,
}

/// What happened ([`CometEvent`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum EventKind {
    /// The barycentric osculating perihelion fell below `threshold` for the first time.
    PerihelionBelow {
        /// The value of [`EventRules::perihelion_below`] (AU).
        threshold: f64,
        /// The perihelion then (AU).
        perihelion: f64,
    },
    /// The Tisserand parameter with respect to Jupiter crossed 3 for the first time.
    TisserandCrossing {
        /// `T_J` at the previous check of a bound orbit.
        before: f64,
        /// `T_J` now.
        after: f64,
    },
    /// A passage inside [`EventRules::close_approach`] of a planet.
    CloseApproach {
        /// The planet (1-based, in the order of [`Planets`](crate::Planets)).
        planet: usize,
        /// The smallest distance to its centre sampled (AU), at the event's time.
        min_distance: f64,
        /// The radius (AU) at that time.
        radius: f64,
    },
}

/// A close approach under way: the planet and the smallest distance so far.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OpenApproach {
    /// The planet (1-based).
    pub planet: usize,
    /// Time of the smallest distance so far (days).
    pub time: f64,
    /// The smallest distance so far (AU).
    pub min_distance: f64,
    /// The radius then (AU).
    pub radius: f64,
}

impl OpenApproach {
    /// The approach as an event (ended, or cut by the end of the run or of the particle).
    pub fn event(&self) -> CometEvent {
        CometEvent {
            time: self.time,
            kind: EventKind::CloseApproach {
                planet: self.planet,
                min_distance: self.min_distance,
                radius: self.radius,
            },
        }
    }
}

/// The events of one particle and the state their detection carries from check to check
/// (saved in checkpoints: a resumed run records the same events).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EventLog {
    /// The events, in the order detected (at most [`EventRules::max_per_particle`]).
    pub events: Vec<CometEvent>,
    /// Events not kept because the log was full.
    pub dropped: u64,
    /// Bit `k`: the perihelion has been below [`EventRules::perihelion_below`]`[k]`.
    pub perihelion_reached: u64,
    /// `T_J` at the last check of a bound orbit (`None` before the first).
    pub last_tisserand: Option<f64>,
    /// Whether `T_J = 3` has been crossed.
    pub tisserand_crossed: bool,
    /// Close approaches under way (one per planet at most). A particle removed during one
    /// keeps it here; [`EventLog::all_events`] lists it.
    pub open_approaches: Vec<OpenApproach>,
}

/// A particle at a check, with the bodies at its time (barycentric, the Sun first).
pub(crate) struct CheckPoint<'a> {
    pub time: f64,
    pub position: Vec3,
    pub velocity: Vec3,
    pub body_positions: &'a [Vec3],
    pub body_velocities: &'a [Vec3],
}

/// What the checks need beyond the particle: `G M`, the Hill coefficients
/// `(m_j/3m₀)^{1/3}`, the index of Jupiter among the bodies.
pub(crate) struct EventContext<'a> {
    pub rules: &'a EventRules,
    pub total_gm: f64,
    pub hill_coefficients: &'a [f64],
    pub jupiter: Option<usize>,
}

impl EventLog {
    fn push(&mut self, event: CometEvent, cap: u32) {
        if self.events.len() < cap as usize {
            self.events.push(event);
        } else {
            self.dropped += 1;
        }
    }

    /// The events and the close approaches still open, in that order.
    pub fn all_events(&self) -> impl Iterator<Item = (CometEvent, bool)> + '_ {
        self.events
            .iter()
            .map(|e| (*e, false))
            .chain(self.open_approaches.iter().map(|o| (o.event(), true)))
    }

    /// Records what `c` shows; `elements_apply`: whether the barycentric elements describe
    /// the orbit (the map, or the encounter mode beyond its switch radius).
    pub(crate) fn check(
        &mut self,
        ctx: &EventContext<'_>,
        c: &CheckPoint<'_>,
        elements_apply: bool,
    ) {
        let rules = ctx.rules;
        let cap = rules.max_per_particle;
        if let Some(radius) = rules.close_approach {
            self.approaches(ctx, c, radius);
        }
        if !elements_apply {
            return;
        }
        let mu = ctx.total_gm;
        let (q, v) = (c.position, c.velocity);
        let r = q.norm();
        let h = q.cross(&v);
        let h2 = h.norm_squared();
        if !rules.perihelion_below.is_empty() {
            let all = if rules.perihelion_below.len() == 64 {
                u64::MAX
            } else {
                (1u64 << rules.perihelion_below.len()) - 1
            };
            if self.perihelion_reached != all {
                // e² = 1 + 2E h²/μ² with 2E = v² − 2μ/r; q = h²/(μ (1 + e)).
                let e2 = 1.0 + (v.norm_squared() - 2.0 * mu / r) * h2 / (mu * mu);
                let perihelion = h2 / (mu * (1.0 + e2.max(0.0).sqrt()));
                for (k, &threshold) in rules.perihelion_below.iter().enumerate() {
                    if self.perihelion_reached & (1 << k) == 0 && perihelion < threshold {
                        self.perihelion_reached |= 1 << k;
                        let kind = EventKind::PerihelionBelow {
                            threshold,
                            perihelion,
                        };
                        self.push(CometEvent { time: c.time, kind }, cap);
                    }
                }
            }
        }
        if rules.tisserand_crossing && !self.tisserand_crossed {
            if let Some(t_j) = ctx
                .jupiter
                .and_then(|j| tisserand_at(q, v, h, mu, c.body_positions, c.body_velocities, j))
            {
                if let Some(before) = self.last_tisserand {
                    if (before < 3.0) != (t_j < 3.0) {
                        self.tisserand_crossed = true;
                        let kind = EventKind::TisserandCrossing { before, after: t_j };
                        self.push(CometEvent { time: c.time, kind }, cap);
                    }
                }
                self.last_tisserand = Some(t_j);
            }
        }
    }

    /// Opens, updates and closes the close approaches.
    fn approaches(&mut self, ctx: &EventContext<'_>, c: &CheckPoint<'_>, radius: ApproachRadius) {
        let sun = c.body_positions[0];
        for (j, planet) in c.body_positions.iter().enumerate().skip(1) {
            let limit = match radius {
                ApproachRadius::Au(r) => r,
                ApproachRadius::HillRadii(f) => {
                    f * (planet - sun).norm() * ctx.hill_coefficients[j - 1]
                }
            };
            let distance = (c.position - planet).norm();
            let open = self.open_approaches.iter().position(|o| o.planet == j);
            match (distance < limit, open) {
                (true, Some(k)) => {
                    let o = &mut self.open_approaches[k];
                    if distance < o.min_distance {
                        (o.time, o.min_distance, o.radius) = (c.time, distance, limit);
                    }
                }
                (true, None) => self.open_approaches.push(OpenApproach {
                    planet: j,
                    time: c.time,
                    min_distance: distance,
                    radius: limit,
                }),
                (false, Some(k)) => {
                    let o = self.open_approaches.remove(k);
                    self.push(o.event(), ctx.rules.max_per_particle);
                }
                (false, None) => {}
            }
        }
    }
}

/// `T_J` of the barycentric orbit `(q, v)` (angular momentum `h`) with Jupiter body `j`:
/// `a_J/a + 2 cos i √(a(1 − e²)/a_J)` written without elements, `1/a = 2/r − v²/μ`,
/// `a(1 − e²) = h²/μ`, `cos i = h·n̂_J/|h|`, so `T_J = a_J (2/r − v²/μ) + 2 h·n̂_J/√(μ a_J)`
/// with `n̂_J` the normal of Jupiter's heliocentric osculating orbit. `None` for an unbound
/// orbit (as [`tisserand_jupiter`](crate::tisserand_jupiter)).
pub(crate) fn tisserand_at(
    q: Vec3,
    v: Vec3,
    h: Vec3,
    mu: f64,
    positions: &[Vec3],
    velocities: &[Vec3],
    j: usize,
) -> Option<f64> {
    let inverse_a = 2.0 / q.norm() - v.norm_squared() / mu;
    if inverse_a.is_nan() || inverse_a <= 0.0 {
        return None;
    }
    let normal = (positions[j] - positions[0]).cross(&(velocities[j] - velocities[0]));
    let a_j = JUPITER_SEMI_MAJOR_AXIS_AU;
    Some(a_j * inverse_a + 2.0 * h.dot(&normal) / (normal.norm() * (mu * a_j).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classes::{inclination_to_plane, tisserand_jupiter};

    /// The element-free `T_J` equals [`tisserand_jupiter`] from the elements, for an orbit
    /// inclined to a Jupiter whose plane is itself tilted (relative difference 10⁻¹³: a few
    /// dozen roundings of `O(1)` terms).
    #[test]
    fn tisserand_without_elements_equals_the_classes_formula() {
        let mu = 2.959_122_082_86e-4;
        let sun = (
            Vec3::new(0.003, -0.001, 0.0002),
            Vec3::new(1e-6, 2e-6, -1e-7),
        );
        let jupiter = (
            sun.0 + Vec3::new(4.9, 1.2, 0.1),
            sun.1 + Vec3::new(-0.0018, 0.0072, 0.0002),
        );
        let (q, v) = (Vec3::new(3.0, -5.0, 1.0), Vec3::new(0.006, 0.004, -0.001));
        let h = q.cross(&v);
        let t_j = tisserand_at(q, v, h, mu, &[sun.0, jupiter.0], &[sun.1, jupiter.1], 1)
            .expect("a bound orbit");
        let el = crate::kepler::elements(&q, &v, mu).unwrap();
        let normal = (jupiter.0 - sun.0).cross(&(jupiter.1 - sun.1)).normalize();
        let i = inclination_to_plane(&q, &v, &normal);
        let expected = tisserand_jupiter(el.semi_major_axis, el.eccentricity, i);
        assert!((t_j / expected - 1.0).abs() < 1e-13, "{t_j} vs {expected}");
        // Unbound: no T_J.
        assert!(tisserand_at(
            q,
            v * 3.0,
            h * 3.0,
            mu,
            &[sun.0, jupiter.0],
            &[sun.1, jupiter.1],
            1
        )
        .is_none());
    }

    /// A full log counts what it does not keep.
    #[test]
    fn a_full_log_counts_the_events_it_drops() {
        let mut log = EventLog::default();
        let event = CometEvent {
            time: 1.0,
            kind: EventKind::TisserandCrossing {
                before: 3.1,
                after: 2.9,
            },
        };
        for _ in 0..5 {
            log.push(event, 3);
        }
        assert_eq!((log.events.len(), log.dropped), (3, 2));
    }
}
