//! The members of a [`Population`](crate::Population)(super::Population), their removal rules and the population's
//! progress: the types shared by the population and its window engine.

use serde::{Deserialize, Serialize};

use crate::encounter::Encounter;
use crate::particles::TestParticle;
use crate::run::ParticleStatus;
use crate::{SymplecticError, Vec3};

/// When a particle of a [`Population`](crate::Population) is removed, checked at the end of each of its steps.
/// A rule left out (`None`) is not applied.
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
}

impl RemovalRules {
    pub(super) fn validate(&self) -> Result<(), SymplecticError> {
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
