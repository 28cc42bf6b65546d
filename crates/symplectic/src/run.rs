//! Several test particles and the planets advanced together, with atomic checkpoints.

use std::path::Path;

use serde::{de::DeserializeOwned, Deserialize, Serialize};

use crate::ephemeris::Ephemeris;
use crate::kepler::Elements;
use crate::particles::{ParticleIntegrator, ParticleScratch, ParticleStepInfo, TestParticle};
use crate::{SymplecticError, WorkCounters};

/// Why a particle stopped being integrated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum ParticleStatus {
    /// Still integrated.
    Active,
    /// Its barycentric osculating perihelion fell below [`Limits::min_perihelion`] (outside
    /// the validity domain of `B₀, B₁`).
    PerihelionBelowLimit {
        /// Time when detected.
        time: f64,
        /// The perihelion distance then.
        perihelion: f64,
    },
    /// Unbound (`e ≥ 1`) beyond [`Limits::ejection_distance`].
    Ejected {
        /// Time when detected.
        time: f64,
        /// Distance from the barycentre then.
        distance: f64,
    },
    /// Entered `hill_factor` Hill radii of a planet
    /// ([`RemovalRules::hill_factor`](crate::RemovalRules::hill_factor); a
    /// [`Population`](crate::Population) rule: the method does not resolve planetary
    /// encounters).
    HillSphereEntry {
        /// Time when detected (end of the step).
        time: f64,
        /// The planet (1-based, in the order of [`Planets`](crate::Planets)).
        planet: usize,
        /// Distance to the planet then.
        distance: f64,
        /// The planet's Hill radius then, `|Q_j| (m_j / 3m₀)^{1/3}`.
        hill_radius: f64,
    },
    /// Came closer to a planet's centre than its physical radius
    /// ([`Planets::radius`](crate::Planets::radius)) while integrated through an encounter
    /// ([`Encounters`](crate::Encounters)).
    Collision {
        /// Time when detected (end of the encounter integrator's step).
        time: f64,
        /// The planet (1-based; its name: [`Planets::name`](crate::Planets::name)).
        planet: usize,
        /// Distance to the planet's centre then.
        distance: f64,
        /// The planet's radius.
        radius: f64,
    },
    /// Collided with the Sun ([`RemovalRules::sun_collision`](crate::RemovalRules::sun_collision)):
    /// closer to its centre than its radius at a check, or past a perihelion below it since
    /// the previous check.
    SunCollision {
        /// Time when detected (the end of the step).
        time: f64,
        /// Distance to the Sun's centre then, or the perihelion passed below the radius.
        distance: f64,
    },
    /// Came closer to the Sun or the barycentre than
    /// [`RemovalRules::min_distance`](crate::RemovalRules::min_distance).
    InsideMinDistance {
        /// Time when detected (the end of the step).
        time: f64,
        /// The distance then (AU).
        distance: f64,
        /// From the Sun or the barycentre.
        frame: crate::DistanceFrame,
    },
    /// Went farther from the Sun or the barycentre than
    /// [`RemovalRules::max_distance`](crate::RemovalRules::max_distance), bound or not.
    BeyondMaxDistance {
        /// Time when detected (the end of the step).
        time: f64,
        /// The distance then (AU).
        distance: f64,
        /// From the Sun or the barycentre.
        frame: crate::DistanceFrame,
    },
    /// The step failed for another reason (non-finite state, Kepler solver); the particle is
    /// kept at its state before the step (a [`Population`](crate::Population) goes on with the
    /// others).
    IntegrationFailed {
        /// The particle's time before the failed step.
        time: f64,
        /// The error.
        reason: String,
    },
    /// `K₀/r` or `K₁/r` stopped being positive.
    RegularisationLost {
        /// Time.
        time: f64,
        /// `"K0/r"` or `"K1/r"`.
        quantity: String,
        /// Its value.
        value: f64,
    },
}

/// A particle with its status.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackedParticle {
    /// State.
    pub particle: TestParticle,
    /// Status.
    pub status: ParticleStatus,
}

/// When to stop integrating a particle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Smallest barycentric osculating perihelion distance allowed.
    pub min_perihelion: f64,
    /// Distance from the barycentre beyond which an unbound particle counts as ejected.
    pub ejection_distance: f64,
}

/// Planets plus test particles, each particle on its own clock (Chegodaeva 2004: the
/// particles are integrated separately from the planets, which saves time).
///
/// [`CometRun::advance_to`] always steps the active particle that is furthest behind, so the
/// ephemeris window stays short; the run is a deterministic function of its state, which is
/// what [`save_checkpoint`] stores: a run resumed from a checkpoint continues bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CometRun {
    /// The planets.
    pub ephemeris: Ephemeris,
    /// The particle map.
    pub integrator: ParticleIntegrator,
    /// The particles.
    pub particles: Vec<TrackedParticle>,
    /// Stop criteria.
    pub limits: Limits,
    #[serde(skip)]
    scratch: ParticleScratch,
}

impl CometRun {
    /// A run of `particles` (built with [`ParticleIntegrator::particle`]).
    pub fn new(
        ephemeris: Ephemeris,
        integrator: ParticleIntegrator,
        particles: Vec<TestParticle>,
        limits: Limits,
    ) -> Self {
        Self {
            ephemeris,
            integrator,
            particles: particles
                .into_iter()
                .map(|particle| TrackedParticle {
                    particle,
                    status: ParticleStatus::Active,
                })
                .collect(),
            limits,
            scratch: ParticleScratch::default(),
        }
    }

    /// Barycentric osculating elements of particle `i` (`μ = G M`, positions relative to the
    /// barycentre; for the mixed variant the heliocentric position is shifted).
    /// Errors if the particle's time precedes the ephemeris' retained window (a stopped
    /// particle left behind).
    pub fn elements(&mut self, i: usize) -> Result<Elements, SymplecticError> {
        let Some(tracked) = self.particles.get(i) else {
            return Err(SymplecticError::InvalidParameter {
                name: "particle index",
                value: i as f64,
                reason: "no such particle in the run",
            });
        };
        let mut bodies = crate::ephemeris::BodyStates::default();
        self.ephemeris
            .bodies_at(tracked.particle.time, &mut bodies)?;
        particle_elements(&self.integrator, &self.particles[i].particle, &bodies)
    }

    /// Advances every active particle until its time reaches `t_end` (the last step
    /// overshoots: the steps are variable) and the planets to `t_end`; `on_step(i, particle,
    /// info)` sees every particle step. Particles leaving the limits are marked and stopped.
    pub fn advance_to(
        &mut self,
        t_end: f64,
        mut on_step: impl FnMut(usize, &TestParticle, &ParticleStepInfo),
    ) -> Result<(), SymplecticError> {
        if !t_end.is_finite() {
            return Err(SymplecticError::InvalidParameter {
                name: "end time",
                value: t_end,
                reason: "must be finite",
            });
        }
        for (name, value) in [
            ("min_perihelion", self.limits.min_perihelion),
            ("ejection_distance", self.limits.ejection_distance),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(SymplecticError::InvalidParameter {
                    name,
                    value,
                    reason: "limit must be finite and >= 0",
                });
            }
        }
        for iteration in 0u64.. {
            if iteration.is_multiple_of(1024) {
                crate::guard::check_stop("advancing the comet run")?;
            }
            let next = self
                .particles
                .iter()
                .enumerate()
                .filter(|(_, p)| p.status == ParticleStatus::Active && p.particle.time < t_end)
                .min_by(|a, b| a.1.particle.time.total_cmp(&b.1.particle.time))
                .map(|(i, _)| i);
            let Some(i) = next else { break };
            let mut particle = self.particles[i].particle.clone();
            match self
                .integrator
                .step(&mut particle, &mut self.ephemeris, &mut self.scratch)
            {
                Ok(info) => {
                    self.particles[i].particle = particle;
                    on_step(i, &self.particles[i].particle, &info);
                    let p = &self.particles[i].particle;
                    // The scratch holds the bodies at the particle's new time.
                    let el = particle_elements(&self.integrator, p, self.scratch.bodies())?;
                    if el.eccentricity >= 1.0 && p.position.norm() > self.limits.ejection_distance {
                        self.particles[i].status = ParticleStatus::Ejected {
                            time: p.time,
                            distance: p.position.norm(),
                        };
                    } else if el.perihelion < self.limits.min_perihelion {
                        self.particles[i].status = ParticleStatus::PerihelionBelowLimit {
                            time: p.time,
                            perihelion: el.perihelion,
                        };
                    }
                }
                Err(SymplecticError::RegularisationLost {
                    quantity,
                    value,
                    time,
                }) => {
                    self.particles[i].status = ParticleStatus::RegularisationLost {
                        time,
                        quantity: quantity.to_string(),
                        value,
                    };
                }
                Err(e) => return Err(e),
            }
            if let Some(oldest) = self.oldest_active_time() {
                self.ephemeris.discard_before(oldest);
            }
        }
        self.ephemeris.extend_to(t_end)?;
        let newest = self.ephemeris.grid_time(self.ephemeris.planet_steps());
        let oldest = self.oldest_active_time().map_or(newest, |t| t.min(newest));
        self.ephemeris.discard_before(oldest);
        Ok(())
    }

    /// Work done so far by the planets, the ephemeris and every particle ([`WorkCounters`]).
    pub fn work(&self) -> WorkCounters {
        self.ephemeris.work() + self.particles.iter().map(|p| p.particle.work).sum()
    }

    /// Time of the active particle furthest behind, if any particle is active.
    fn oldest_active_time(&self) -> Option<f64> {
        self.particles
            .iter()
            .filter(|p| p.status == ParticleStatus::Active)
            .map(|p| p.particle.time)
            .reduce(f64::min)
    }
}

fn particle_elements(
    integrator: &ParticleIntegrator,
    p: &TestParticle,
    bodies: &crate::ephemeris::BodyStates,
) -> Result<Elements, SymplecticError> {
    let position = match integrator.variant {
        crate::Variant::Barycentric => p.position,
        crate::Variant::Mixed => p.position + bodies.positions[0],
    };
    crate::kepler::elements(&position, &p.velocity, bodies.total_gm())
}

/// Writes `value` as JSON to `path` atomically: a temporary file in the same directory is
/// written, flushed to disk and renamed over `path` (then the directory is synced), so a
/// crash leaves either the old or the new checkpoint, never a torn one. `f64` values
/// round-trip exactly (`serde_json`'s `float_roundtrip`).
pub fn save_checkpoint<T: Serialize>(path: &Path, value: &T) -> Result<(), SymplecticError> {
    let io = |e: std::io::Error| SymplecticError::Checkpoint {
        path: path.display().to_string(),
        reason: e.to_string(),
    };
    let f = atomic_write_file::AtomicWriteFile::open(path).map_err(io)?;
    // Buffered: serde_json writes a number or a punctuation mark at a time, a system call
    // each without the buffer.
    let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
    serde_json::to_writer(&mut w, value).map_err(|e| io(e.into()))?;
    let f = w.into_inner().map_err(|e| io(e.into_error()))?;
    f.commit().map_err(io)
}

/// Reads a checkpoint written by [`save_checkpoint`]: only a regular file (a named pipe or a
/// device such as `/dev/zero` is refused before it is opened) whose text fits in the memory
/// available (the size of its text is checked from its metadata, before it is read).
pub fn load_checkpoint<T: DeserializeOwned>(path: &Path) -> Result<T, SymplecticError> {
    let limit = crate::guard::available_memory().unwrap_or(u64::MAX);
    let text =
        crate::guard::read_text_limited(path, limit, "the memory available").map_err(|reason| {
            SymplecticError::Checkpoint {
                path: path.display().to_string(),
                reason,
            }
        })?;
    serde_json::from_str(&text).map_err(|e| SymplecticError::Checkpoint {
        path: path.display().to_string(),
        reason: format!("malformed checkpoint: {e}"),
    })
}
