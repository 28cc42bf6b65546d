//! Symplectic integrators for the planets and small bodies of the Solar System.
//!
//! Implements the planetary part of
//!
//! > Е. А. Чегодаева (E. A. Chegodaeva), «Метод симплектического интегрирования уравнений
//! > движения малых тел Солнечной системы» ("A method of symplectic integration of the
//! > equations of motion of small Solar System bodies"), 2004
//! > (`../shared/papers/004_83a841cf9713bdd7.txt`; English summary in the papers' README),
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
//! Units are the caller's; the experiments use AU, days and solar masses with
//! `G = 2.95912208286e-4 AU³ M☉⁻¹ day⁻²`.
//!
//! Not yet implemented (issue #4 continues): the test particles with Emel'yanenko's variable
//! time step (eqs. 14–38).

pub mod kepler;
mod maps;
mod planets;

pub use maps::{Integrator, Piece, Stage, S2_STAGES, S6_C1, S6_C2, S6_D1, S6_D2, S6_STAGES};
pub use planets::Planets;

/// 3-vector of `f64` (nalgebra).
pub type Vec3 = nalgebra::Vector3<f64>;

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
    /// The integration blew up: a non-finite value appeared at this step.
    #[error("blow-up at step {step}: body {body} has a non-finite state")]
    BlowUp {
        /// Step index.
        step: u64,
        /// Index of the body (1-based planets).
        body: usize,
    },
}
