#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Symplectic integrators for the planets and small bodies of the Solar System.
//!
//! Implements
//!
//! > Е. А. Чегодаева (E. A. Chegodaeva), «Метод симплектического интегрирования уравнений
//! > движения малых тел Солнечной системы» ("A method of symplectic integration of the
//! > equations of motion of small Solar System bodies"), 2004, in Russian,
//!
//! after J. Wisdom and M. Holman, "Symplectic maps for the N-body problem", *The Astronomical
//! Journal* 102, 1528–1538, 1991 (doi:10.1086/115978); M. J. Duncan, H. F. Levison and
//! M. H. Lee, "A multiple time step symplectic algorithm for integrating close encounters",
//! *The Astronomical Journal* 116, 2067–2077, 1998 (doi:10.1086/300541); J. Laskar and
//! P. Robutel, "High order symplectic integrators for perturbed Hamiltonian systems",
//! *Celestial Mechanics and Dynamical Astronomy* 80, 39–62, 2001
//! (doi:10.1023/A:1012098603882),
//!
//! in `f64` throughout:
//!
//! - [`kepler::drift`]: the exact two-body drift in universal variables (Stumpff functions,
//!   Gauss `f` and `g`), for elliptic, parabolic and hyperbolic orbits;
//! - [`Planets`]: the Sun and `n` planets in **mixed (democratic heliocentric)** variables
//!   (eq. 9: heliocentric positions `Q_i`, barycentric momenta `P_i`), with the Hamiltonian
//!   split `H = H_Kepl + H_Sun + H_Inter` of eqs. 10–12 and its three exact flows as named
//!   pieces: [`Planets::kepler_drift`] (A), [`Planets::interaction_kick`] (B),
//!   [`Planets::sun_drift`] (C);
//! - [`Integrator`]: the maps assembled from those pieces with named coefficients:
//!   [`Integrator::S2`] `= C/2 B/2 A B/2 C/2` (eq. 13) and the pseudo-sixth-order
//!   [`Integrator::S6`] of Laskar & Robutel (eq. 7, coefficients [`S6_C1`], [`S6_C2`],
//!   [`S6_D1`], [`S6_D2`]);
//! - [`outer_solar_system`]: the system of the paper's experiments (the Sun carrying the inner
//!   planets' masses, Jupiter, Saturn, Uranus, Neptune; Hairer, Lubich & Wanner's Table 2.1),
//!   with `G` ([`G_AU3_PER_MSUN_DAY2`]) and the rotation to the ecliptic ([`Frame`]).
//!
//! Units are the caller's; the experiments use AU, days and solar masses with
//! `G = 2.95912208286e-4 AU³ M☉⁻¹ day⁻²`.
//!
//! Test particles (massless comets) are integrated separately from the planets, each on its
//! own clock, with Emel'yanenko's variable time step in the extended phase space:
//!
//! - [`Ephemeris`]: the planets on their fixed-step grid, interpolated (quintic Hermite) to
//!   any particle time, with velocities that are the exact derivative of positions;
//! - [`ParticleIntegrator`]: the logarithmic-Hamiltonian maps of eqs. 21–32 (mixed
//!   coordinates, [`Variant::Mixed`], with its validity domain checked up front) and
//!   eqs. 36–38 (barycentric, [`Variant::Barycentric`], the paper's recommendation), with the
//!   second-order ([`Scheme::S2`], eq. 27) or pseudo-sixth-order ([`Scheme::S6`], eq. 7)
//!   composition of the pieces [`ParticleIntegrator::kepler_drift`] (`E₀`) and
//!   [`ParticleIntegrator::perturbation`] (`E₁`);
//! - [`CometRun`]: planets and particles advanced together, stop criteria ([`Limits`]), and
//!   atomic checkpoints ([`save_checkpoint`], [`load_checkpoint`]: temporary file, `fsync`,
//!   rename) that resume bit for bit.
//!
//! Populations of test particles (10 to 10⁶ comets sharing one planet integration, the
//! reason the paper integrates particles separately from the planets):
//!
//! - [`Population`]: every particle on its own clock with the same maps, advanced in parallel
//!   (rayon) through synchronisation windows against one shared, read-only ephemeris window
//!   ([`Ephemeris::interpolate`]), extended once per window; removal per particle with its
//!   reason, time and state ([`RemovalRules`]: Hill-sphere entry, perihelion below a limit,
//!   unbound beyond a distance, heliocentric or barycentric `r < R` and `r > R` bound or not,
//!   collision with the Sun; regularisation lost; [`ParticleStatus`]); events recorded
//!   without ending a particle ([`EventRules`]: the first perihelion below a value, the first
//!   crossing of `T_J = 3`, each close approach to a planet, kept per member in its
//!   [`EventLog`]); shards ([`Population::shard`],
//!   [`Population::merge`]) and versioned atomic checkpoints ([`Population::save`]). The
//!   result is a deterministic function of the input: bit-identical on any number of
//!   threads, across shards, after a resume, and equal bit for bit to each particle
//!   integrated alone with [`ParticleIntegrator::step`];
//! - [`encounter`]: close encounters integrated through ([`Population::set_encounters`],
//!   [`Encounters`]): inside 3 Hill radii of a planet (MERCURY's and MERCURIUS' changeover),
//!   or where `B₀, B₁` no longer dominate (the paper's condition 35, read as a factor 2), a
//!   particle is integrated by Bulirsch–Stoer among the planets of the same ephemeris the
//!   map reads (one trajectory of the planets in both modes: nothing jumps at the switch or
//!   the hand-back, and `H + p₄` is carried through), and handed back to the
//!   map outside 3.5 Hill radii (a hysteresis band: a comet skimming 3 Hill radii switches
//!   once, not at every dip; [`PopulationMember::encounters_begun`] counts the switches,
//!   [`Population::switches_per_encounter`] the switches per close encounter with a planet,
//!   [`EncounterTally`]); ends by collision with a planet's radius
//!   ([`ParticleStatus::Collision`]), and never for lost regularisation. Checked against
//!   REBOUND's IAS15 on single encounters with Jupiter and Neptune down to 0.02 Hill radii
//!   and, comet by comet, along the population's own path (the map, the switch, the
//!   encounter, the hand-back: eleven comets passing the four giants at 0.05 to 2.9 Hill
//!   radii, `tests/population_path.rs`), each within a fixed bound from IAS15's own
//!   convergence, and against a fine fixed-step RK4 (property test); as a population,
//!   300 Centaurs over 1 Myr against REBOUND's MERCURIUS with the same initial conditions and
//!   end rules (survival, lifetimes, fractions ejected, collided and reaching q < 2.5 AU;
//!   the validation experiment `centaur-population`);
//! - [`classes`]: Levison's (1996) comet classes by the Tisserand parameter with respect to
//!   Jupiter (Jupiter-family, Encke-type, Chiron-type, Halley-type, long-period) and, apart,
//!   the region of an orbit by perihelion and semi-major axis (trans-Neptunian, Centaur,
//!   perihelion inside Jupiter's orbit), both in the population tables;
//! - [`samples`]: seeded sample populations (SplitMix64) shared with the peer scripts;
//! - with the feature `io`: `io` (the population TOML, the particle CSV with line/column
//!   errors); with the feature `parquet` (which brings `io`) also its Parquet tables
//!   readable by pandas and polars and `study` (a whole study with snapshots, final table and
//!   checkpoints, resumed byte for byte).
//!
//! Every integration counts its work ([`WorkCounters`]: Kepler solves, their iterations,
//! pairwise force evaluations, ephemeris interpolations): a cost measure that does not
//! depend on the machine.
//!
//! # Example
//!
//! The paper's first comet (a = 60.91 AU, q = 30.01 AU, i = 16°, 91 AU from the Sun) among the
//! four giant planets, second-order maps, for 1000 years:
//!
//! ```
//! use symplectic::{
//!     outer_solar_system, CometRun, Ephemeris, Frame, Integrator, Limits, ParticleIntegrator,
//!     ParticleScratch, ParticleStatus, Scheme, Variant, Vec3,
//! };
//!
//! // Planets in the ecliptic of J2000, advanced by S2 with the paper's 365-day step.
//! let planets = outer_solar_system(Frame::EclipticJ2000);
//! let (sun_position, sun_velocity) = planets.sun_barycentric_state();
//! let mut ephemeris = Ephemeris::new(planets, Integrator::S2 { step: 365.0 })?;
//!
//! // The particle (heliocentric ecliptic state, AU and AU/day, from the paper's elements with
//! // Ω = ω = 0 on the outbound branch), moved to the barycentre for the barycentric variant.
//! let position = Vec3::new(-90.2133300970874, 11.477121391583594, 3.291011600830304);
//! let velocity = Vec3::new(-3.3558225919028486e-4, -1.1900915840439576e-3, -3.4125327035499536e-4);
//! // The paper's regularisation B0 = 0, B1 = 0.21e-6 AU³/day² (`PAPER_B0`, `PAPER_B1`).
//! let integrator = ParticleIntegrator::paper(Variant::Barycentric, Scheme::S2);
//! let mut scratch = ParticleScratch::default();
//! let comet = integrator.particle(
//!     position + sun_position,
//!     velocity + sun_velocity,
//!     0.0,   // time (days)
//!     298.0, // first step (days), as in the paper
//!     &mut ephemeris,
//!     &mut scratch,
//! )?;
//!
//! let limits = Limits { min_perihelion: 26.0, ejection_distance: 1000.0 };
//! let mut run = CometRun::new(ephemeris, integrator, vec![comet], limits);
//! let mut worst = 0.0f64;
//! run.advance_to(1000.0 * 365.25, |_, _, info| worst = worst.max(info.relative_error.abs()))?;
//!
//! assert_eq!(run.particles[0].status, ParticleStatus::Active);
//! assert!(worst < 1e-5, "extended-Hamiltonian error {worst:e}");
//! let a = run.elements(0)?.semi_major_axis;
//! assert!((50.0..70.0).contains(&a), "a = {a} AU");
//! println!("{} Kepler solves", run.work().kepler_solves);
//! # Ok::<(), symplectic::SymplecticError>(())
//! ```
//!
//! # Performance
//!
//! `cargo bench -p benches --bench symplectic` times one planet step of S2 and S6 (four giant
//! planets, τ = 365 d, state synchronised after every step) and one particle step
//! (barycentric, planets interpolated); the figures and the same-script comparison with
//! REBOUND's WHFast are in the workspace's `docs/performance.md`. The Kepler drift uses Halley's
//! iteration from a third-order series start, which converges in two Stumpff evaluations for
//! these steps.
//!
//! ## What bounds a population's step
//!
//! One particle step of [`Population`] (barycentric variant, S2, Sun and four giants) is one
//! ephemeris interpolation at the particle's new time (the one at its old time is reused from
//! the previous step: 5 bodies × positions and velocities, ≈ 450 flops with the Hermite
//! weights), two perturbation kicks `E₁(h/2)` (5 body terms each: ≈ 150 flops, 5 square
//! roots and 10 divisions), one universal-variable Kepler drift (≈ 150 flops, two Stumpff
//! evaluations) and the removal checks (Hill spheres: 8 square roots; perihelion and
//! ejection from energy and angular momentum: ≈ 40 flops, 1 square root): about 1000 flops
//! and 30 square roots or divisions, all on data in L1. S6 has 3 drifts, 4 kicks and 3
//! interpolations. Each particle is one [`PopulationMember`] of
//! [`Population::bytes_per_particle`] bytes (232 on x86-64; 208 before the encounter tally, 200 before the event log, 192 before the count of encounters begun, 184 before the encounter state), stepped many times per window
//! while it sits in L1, so memory traffic is 2 × 232 bytes per particle per window, not per
//! step. The ephemeris window (360 bytes per planet step for five bodies, ≈ 2 ×
//! [`DEFAULT_WINDOW_STEPS`] steps, ≈ 180 KB) is shared read-only by all threads and stays in
//! L2; extending it costs one planet step per grid point, once for the whole population
//! (it matters only for N ≲ 10). Nothing in a window is O(N) per particle step, so the cost
//! per particle step does not depend on N; `cargo run --release -p benches --example
//! comet_throughput -- N YEARS [s2|s6]` measures it, and `docs/performance.md` compares it
//! with REBOUND's WHFast from one script.

pub mod classes;
pub mod encounter;
pub mod ephemeris;
pub mod guard;
#[cfg(feature = "io")]
pub mod io;
pub mod kepler;
mod lanes;
mod maps;
mod particles;
mod planets;
mod population;
mod run;
pub mod samples;
pub mod solar_system;
#[cfg(feature = "parquet")]
pub mod study;
mod work;

pub use classes::{levison_class, orbital_region, tisserand_jupiter, LevisonClass, OrbitalRegion};
pub use encounter::{
    integrate_through, Encounter, EncounterOutcome, Encounters,
    DEFAULT_ENCOUNTER_HAND_BACK_HILL_FACTOR, DEFAULT_ENCOUNTER_HILL_FACTOR,
    DEFAULT_ENCOUNTER_TOLERANCE,
};
pub use ephemeris::{BodyStates, Ephemeris};
pub use maps::{Integrator, Piece, Stage, S2_STAGES, S6_C1, S6_C2, S6_D1, S6_D2, S6_STAGES};
pub use particles::{
    MixedDomain, ParticleIntegrator, ParticlePiece, ParticleScratch, ParticleStage,
    ParticleStepInfo, Scheme, TestParticle, Variant, MIXED_DOMAIN_MIN_RATIO, PAPER_B0, PAPER_B1,
    PARTICLE_S2_STAGES, PARTICLE_S6_STAGES,
};
pub use planets::Planets;
pub use population::{
    ApproachRadius, CometEvent, DistanceFrame, DistanceLimit, EncounterTally, EventKind, EventLog,
    EventRules, OpenApproach, OpenEncounter, Population, PopulationMember, PopulationProgress,
    RemovalRules, SwitchesPerEncounter, DEFAULT_MAX_EVENTS_PER_PARTICLE, DEFAULT_WINDOW_STEPS,
    ENCOUNTER_SEPARATION_FACTOR, MAX_PERIHELION_THRESHOLDS,
};
pub use run::{
    load_checkpoint, save_checkpoint, CometRun, Limits, ParticleStatus, TrackedParticle,
};
pub use solar_system::{outer_solar_system, Frame, G_AU3_PER_MSUN_DAY2};
pub use work::WorkCounters;

/// 3-vector of `f64` (nalgebra).
pub type Vec3 = nalgebra::Vector3<f64>;

/// Obliquity of the ecliptic at J2000, ε = 84381.448″ (IAU 1976 value), in radians.
pub const OBLIQUITY_J2000_RAD: f64 = 84_381.448 / 3600.0 * std::f64::consts::PI / 180.0;

/// Rotates a vector from the equatorial to the ecliptic frame of J2000 (about `x` by
/// [`OBLIQUITY_J2000_RAD`]).
pub fn equatorial_to_ecliptic(v: &Vec3) -> Vec3 {
    let (s, c) = OBLIQUITY_J2000_RAD.sin_cos();
    Vec3::new(v.x, c * v.y + s * v.z, -s * v.y + c * v.z)
}

/// Errors of `symplectic`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SymplecticError {
    /// A parameter is out of range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// Why.
        reason: &'static str,
    },
    /// A state that cannot be integrated (non-finite, collision, impossible orbit).
    #[error("{what}: {reason}")]
    InvalidState {
        /// Where it was detected.
        what: &'static str,
        /// Details, naming the body and values.
        reason: String,
    },
    /// A test particle's `K₀/r` or `K₁/r` (Chegodaeva 2004, eq. 22) is not positive: `B₀, B₁`
    /// no longer dominate the perturbation (condition 35) and the logarithm is undefined.
    #[error(
        "{quantity} = {value} <= 0 at t = {time}: B0, B1 too small for this orbit (condition 35)"
    )]
    RegularisationLost {
        /// `"K0/r"` or `"K1/r"`.
        quantity: &'static str,
        /// Its value.
        value: f64,
        /// The particle's time.
        time: f64,
    },
    /// A test particle of the mixed variant ([`Variant::Mixed`]) outside the domain where its
    /// `B₀, B₁` dominate the Sun term `H_Sun = −V·ΣP_i/m₀` (Chegodaeva 2004, condition 35):
    /// `K₁/r` would turn negative on the trajectory. See [`ParticleIntegrator::mixed_domain`].
    #[error(
        "mixed variant outside its domain: (B0 + B1/r)/(|V| |sum P_i|/m0) = {ratio:.3} < {required} \
         on this orbit (smallest at r = {at_distance:.2}) with B0 = {b0:e}, B1 = {b1:e}: \
         H_Sun is not dominated (condition 35); use B1 >= {b1_needed:.3e} or Variant::Barycentric"
    )]
    OutsideMixedDomain {
        /// Smallest ratio over the orbit.
        ratio: f64,
        /// Required ratio ([`MIXED_DOMAIN_MIN_RATIO`]).
        required: f64,
        /// Heliocentric distance where the ratio is smallest.
        at_distance: f64,
        /// `B₀` given.
        b0: f64,
        /// `B₁` given.
        b1: f64,
        /// Smallest `B₁` (with this `B₀`) that meets the requirement.
        b1_needed: f64,
    },
    /// A checkpoint could not be written or read.
    #[error("checkpoint {path}: {reason}")]
    Checkpoint {
        /// File.
        path: String,
        /// Why.
        reason: String,
    },
    /// A read-only ephemeris ([`Ephemeris::interpolate`]) was asked for a time after its
    /// newest grid state.
    #[error("time {time} is after the newest planet state ({newest}) of a read-only ephemeris")]
    BeyondEphemeris {
        /// Requested time.
        time: f64,
        /// Newest grid time.
        newest: f64,
    },
    /// A population specification (TOML) is malformed or out of range.
    #[error("{path}: field `{field}`: {reason}")]
    Spec {
        /// File.
        path: String,
        /// Field path (`span.years`), empty for the document.
        field: String,
        /// Why, with the line and column for syntax errors.
        reason: String,
    },
    /// A particle file (CSV) has a bad row; nothing was built.
    #[error("{path}: line {line}, column `{column}`: {reason}")]
    ParticleFile {
        /// File.
        path: String,
        /// Line (1-based; the header is line 1).
        line: u64,
        /// Column name (empty if the whole row).
        column: String,
        /// Why.
        reason: String,
    },
    /// A population would not fit in memory; refused before allocating.
    #[error(
        "{particles} particles need about {needed_bytes} bytes, more than the {available_bytes} bytes available"
    )]
    OutOfMemory {
        /// Particles requested.
        particles: usize,
        /// Bytes needed.
        needed_bytes: u128,
        /// Bytes available.
        available_bytes: u64,
    },
    /// An output table could not be written.
    #[error("output {path}: {reason}")]
    Output {
        /// File.
        path: String,
        /// Why.
        reason: String,
    },
    /// A stop was requested ([`guard::request_stop`], Ctrl-C); the state is consistent and
    /// goes on from where it stopped.
    #[error("interrupted (Ctrl-C) while {what}")]
    Interrupted {
        /// What was running.
        what: &'static str,
    },
    /// An allocation sized by the input was refused: more than the memory available, or the
    /// allocator could not give it.
    #[error(
        "{what}: {requested_bytes} bytes asked for, {}",
        available_bytes.map_or("refused by the allocator".to_string(), |a| format!("{a} bytes available"))
    )]
    AllocationFailed {
        /// What the memory was for.
        what: &'static str,
        /// Bytes asked for.
        requested_bytes: u128,
        /// Bytes available (`MemAvailable`), where known.
        available_bytes: Option<u64>,
    },
    /// The integration blew up: a non-finite value appeared at this step.
    #[error("blow-up at step {step}: body {body} has a non-finite state")]
    BlowUp {
        /// Step index.
        step: u64,
        /// Index of the body (1-based planets).
        body: usize,
    },
}
