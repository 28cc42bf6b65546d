//! Symplectic integrators for the planets and small bodies of the Solar System.
//!
//! Implements
//!
//! > Е. А. Чегодаева (E. A. Chegodaeva), «Метод симплектического интегрирования уравнений
//! > движения малых тел Солнечной системы» ("A method of symplectic integration of the
//! > equations of motion of small Solar System bodies"), 2004
//! > (in Russian; full citation in `docs/papers.md`),
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
//!   [`S6_D1`], [`S6_D2`]).
//!
//! # Performance
//!
//! `cargo bench -p benches --bench symplectic` times one S2 and one S6 step of the planets
//! and of a test particle; the figures, beside REBOUND's WHFast on the same system, are in
//! the workspace's `docs/performance.md`. The Kepler drift uses Halley's iteration from
//! a third-order series start, which converges in two Stumpff evaluations for these steps.
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
//!   coordinates, [`Variant::Mixed`]) and eqs. 36–38 (barycentric, [`Variant::Barycentric`],
//!   the paper's recommendation), with the second-order ([`Scheme::S2`], eq. 27) or
//!   pseudo-sixth-order ([`Scheme::S6`], eq. 7) composition of the pieces
//!   [`ParticleIntegrator::kepler_drift`] (`E₀`) and [`ParticleIntegrator::perturbation`] (`E₁`);
//! - [`CometRun`]: planets and particles advanced together, stop criteria ([`Limits`]), and
//!   atomic checkpoints ([`save_checkpoint`], [`load_checkpoint`]) that resume bit for bit.

pub mod ephemeris;
pub mod kepler;
mod maps;
mod particles;
mod planets;
mod run;

pub use ephemeris::{BodyStates, Ephemeris};
pub use maps::{Integrator, Piece, Stage, S2_STAGES, S6_C1, S6_C2, S6_D1, S6_D2, S6_STAGES};
pub use particles::{
    ParticleIntegrator, ParticlePiece, ParticleScratch, ParticleStage, ParticleStepInfo, Scheme,
    TestParticle, Variant, PARTICLE_S2_STAGES, PARTICLE_S6_STAGES,
};
pub use planets::Planets;
pub use run::{
    load_checkpoint, save_checkpoint, CometRun, Limits, ParticleStatus, TrackedParticle,
};

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
    /// A checkpoint could not be written or read.
    #[error("checkpoint {path}: {reason}")]
    Checkpoint {
        /// File.
        path: String,
        /// Why.
        reason: String,
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
