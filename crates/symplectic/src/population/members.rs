//! The members of a [`Population`](crate::Population)(super::Population), their removal rules and the population's
//! progress: the types shared by the population and its window engine.

use serde::{Deserialize, Serialize};

use super::events::EventLog;
use crate::encounter::Encounter;
use crate::particles::TestParticle;
use crate::run::ParticleStatus;
use crate::{SymplecticError, Vec3};

/// When a particle of a [`Population`](crate::Population) is removed, checked at the end of
/// each of its steps (in the encounter mode, at the end of each of the encounter
/// integrator's steps). A rule left out (`None`, `false`) is not applied; the first rule met
/// ends the particle, in the order of the fields, and names itself in its
/// [`ParticleStatus`]. A file written before the rules `min_distance`, `max_distance` and
/// `sun_collision` existed reads them as off.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RemovalRules {
    /// Remove a particle inside `hill_factor` Hill radii of a planet: the Hill radius of
    /// planet `j` is `|Q_j| (m_j/3m₀)^{1/3}` with `Q_j` its heliocentric position at the
    /// particle's time. The map alone does not resolve planetary encounters; removal at Hill
    /// sphere entry is the standard treatment (Holman & Wisdom 1993, AJ 105, 1987), and
    /// [`Population::set_encounters`](crate::Population::set_encounters) the alternative
    /// that integrates through them (not together with this rule). Checked
    /// at step ends: an encounter shorter than a step can be missed, as in any fixed-step
    /// integrator with this rule.
    pub hill_factor: Option<f64>,
    /// Remove a particle whose barycentric osculating perihelion is below this distance
    /// (outside the validity domain of `B₀, B₁`, condition 35 of Chegodaeva 2004).
    pub min_perihelion: Option<f64>,
    /// Remove an unbound particle (barycentric osculating energy `≥ 0`) beyond this distance
    /// from the barycentre.
    pub ejection_distance: Option<f64>,
    /// Remove a particle that has collided with the Sun: closer to its centre than
    /// [`SUN_RADIUS_AU`](crate::solar_system::SUN_RADIUS_AU) (the IAU nominal solar
    /// radius) at a step end, or past a heliocentric perihelion below that radius during the
    /// step that just ended (its heliocentric two-body orbit about `G m₀` at the step end, as
    /// Mercury's central-body collision check does: Chambers 1999, MNRAS 304, 793), so that a
    /// grazing passage between two step ends is not missed. Status
    /// [`ParticleStatus::SunCollision`]. Applied in the encounter mode too.
    #[serde(default)]
    pub sun_collision: bool,
    /// Remove a particle closer than a distance to the Sun or the barycentre (Swift's
    /// `rmin`), at step ends. Status [`ParticleStatus::InsideMinDistance`]. Applied in the
    /// encounter mode too.
    #[serde(default)]
    pub min_distance: Option<DistanceLimit>,
    /// Remove a particle farther than a distance from the Sun or the barycentre, bound or
    /// not (Swift's `rmax`; [`RemovalRules::ejection_distance`] removes only unbound
    /// particles), at step ends. Status [`ParticleStatus::BeyondMaxDistance`]. Applied in
    /// the encounter mode too.
    #[serde(default)]
    pub max_distance: Option<DistanceLimit>,
}

/// Where a distance of a removal rule ([`RemovalRules::min_distance`],
/// [`RemovalRules::max_distance`]) is measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DistanceFrame {
    /// From the Sun's centre.
    #[default]
    Heliocentric,
    /// From the barycentre of the Sun and the planets.
    Barycentric,
}

/// A distance and where it is measured from (`{ distance = 0.1, frame = "heliocentric" }`
/// in a population file; the frame defaults to heliocentric).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DistanceLimit {
    /// The distance (AU), finite and `> 0`.
    pub distance: f64,
    /// Measured from the Sun or the barycentre.
    #[serde(default)]
    pub frame: DistanceFrame,
}

impl RemovalRules {
    pub(crate) fn validate(&self) -> Result<(), SymplecticError> {
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
        for (name, limit) in [
            ("min_distance.distance", self.min_distance),
            ("max_distance.distance", self.max_distance),
        ] {
            if let Some(l) = limit {
                if !(l.distance.is_finite() && l.distance > 0.0) {
                    return Err(SymplecticError::InvalidParameter {
                        name,
                        value: l.distance,
                        reason: "removal distance must be finite and > 0 (AU)",
                    });
                }
            }
        }
        if let (Some(near), Some(far)) = (self.min_distance, self.max_distance) {
            if near.frame == far.frame && near.distance >= far.distance {
                return Err(SymplecticError::InvalidParameter {
                    name: "min_distance.distance",
                    value: near.distance,
                    reason: "must be below max_distance.distance in the same frame (every particle would be removed)",
                });
            }
        }
        Ok(())
    }
}

/// One particle of a [`Population`](crate::Population): its identifier (kept through shards and merges), its
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
    /// The encounter mode's state while the particle is in it
    /// ([`Encounters`](crate::Encounters)); `particle`
    /// then holds its position, velocity, time and `p₄`. `None` once the particle is
    /// removed, in the encounter mode or not.
    #[serde(default)]
    pub encounter: Option<Box<Encounter>>,
    /// Switches to the encounter mode so far (encounters begun): one per encounter with
    /// the hand-back radius beyond the switch's
    /// ([`Encounters::hand_back_hill_factor`](crate::Encounters::hand_back_hill_factor)),
    /// more for a particle that goes back and forth. Counted from 0 in a population saved
    /// before the counter existed.
    #[serde(default)]
    pub encounters_begun: u32,
    /// Its close encounters with the planets and the switches in each
    /// ([`EncounterTally`]). Zero in a population saved before the tally existed.
    #[serde(default)]
    pub tally: EncounterTally,
    /// The events recorded so far and what their detection needs to remember
    /// ([`EventRules`](crate::EventRules)); `None` until the first step checked with event
    /// rules set, and in a population saved before events existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub events: Option<Box<EventLog>>,
}

/// How many separation radii ([`EncounterTally`]) per switch radius
/// ([`Encounters::hill_factor`](crate::Encounters::hill_factor)): twice it, 6 Hill radii by
/// default, where the planet's pull against the Sun's tidal acceleration, `(R_H/d)³`, is
/// 0.5 %, an eighth of its value at the switch radius.
pub const ENCOUNTER_SEPARATION_FACTOR: f64 = 2.0;

/// A particle's close encounters with the planets, and the switches to the encounter mode
/// in each.
///
/// **An encounter** is one close approach to one planet, as a planetary dynamicist counts
/// it: it begins at a switch to the encounter mode inside the switch radius of the planet
/// ([`Encounters::hill_factor`](crate::Encounters::hill_factor) Hill radii) and lasts until
/// the particle, back in the map, is at a map step's end beyond the separation radius:
/// [`ENCOUNTER_SEPARATION_FACTOR`] times the switch radius, or the hand-back radius if that
/// is larger (6 Hill radii with the defaults), or until it switches inside the switch radius
/// of another planet. A switch to the same planet before that belongs to the same encounter:
/// a comet skimming the switch radius (a slow, trailing or quasi-satellite passage, whose
/// distance in Hill radii swings by ±10 % over Jupiter's orbit) makes one encounter however
/// often it switches. With the hand-back radius beyond the switch's (hysteresis) an encounter
/// takes one switch unless the particle goes out beyond the hand-back radius and comes back
/// without passing the separation radius; without hysteresis it takes one per dip. Switches
/// where the map's regularisation was lost away from every planet (the Sun's vicinity) are
/// no planetary encounter and are counted only in
/// [`PopulationMember::encounters_begun`].
///
/// A particle with an encounter under way is followed by the scalar checks at every map step
/// (the lanes flag it, [`crate::Population`]); its trajectory is unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct EncounterTally {
    /// Encounters begun.
    pub encounters: u32,
    /// Switches in those encounters.
    pub switches: u32,
    /// Most switches in one of them (under way or ended).
    pub max_switches: u32,
    /// The encounter under way, if any: the planet (1-based) and its switches so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open: Option<OpenEncounter>,
}

/// An encounter under way ([`EncounterTally::open`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct OpenEncounter {
    /// The planet (1-based).
    pub planet: u32,
    /// Its switches so far.
    pub switches: u32,
}

impl EncounterTally {
    /// A switch to the encounter mode inside the switch radius of `planet` (1-based).
    pub(crate) fn switch(&mut self, planet: u32) {
        let open = match &mut self.open {
            Some(o) if o.planet == planet => {
                o.switches = o.switches.saturating_add(1);
                *o
            }
            _ => {
                self.encounters = self.encounters.saturating_add(1);
                *self.open.insert(OpenEncounter {
                    planet,
                    switches: 1,
                })
            }
        };
        self.switches = self.switches.saturating_add(1);
        self.max_switches = self.max_switches.max(open.switches);
    }
}

/// Switches to the encounter mode per close encounter with a planet, over a population
/// ([`Population::switches_per_encounter`](crate::Population::switches_per_encounter);
/// [`EncounterTally`] defines an encounter).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SwitchesPerEncounter {
    /// Encounters, all particles.
    pub encounters: u64,
    /// Switches in them.
    pub switches: u64,
    /// Most switches in one encounter.
    pub max: u32,
}

impl SwitchesPerEncounter {
    /// The mean number of switches per encounter (`NaN` without an encounter).
    pub fn mean(&self) -> f64 {
        if self.encounters == 0 {
            f64::NAN
        } else {
            self.switches as f64 / self.encounters as f64
        }
    }

    /// Adds a particle's tally.
    pub(crate) fn add(mut self, t: &EncounterTally) -> Self {
        self.encounters += u64::from(t.encounters);
        self.switches += u64::from(t.switches);
        self.max = self.max.max(t.max_switches);
        self
    }

    /// Joins two partial sums.
    pub(crate) fn join(self, other: Self) -> Self {
        Self {
            encounters: self.encounters + other.encounters,
            switches: self.switches + other.switches,
            max: self.max.max(other.max),
        }
    }
}

/// Where a [`Population`](crate::Population) stands after a synchronisation.
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
    /// Switches to the encounter mode so far, all particles
    /// ([`PopulationMember::encounters_begun`]).
    pub encounters_begun: u64,
}
