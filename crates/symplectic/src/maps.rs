//! Integrators assembled from the named pieces of [`Planets`].

use crate::{Planets, SymplecticError};

/// One exact flow of the splitting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Piece {
    /// A: [`Planets::kepler_drift`].
    Kepler,
    /// B: [`Planets::interaction_kick`].
    Interaction,
    /// C: [`Planets::sun_drift`].
    Sun,
    /// The whole perturbation `H_Sun + H_Inter` as `C(d/2) B(d) C(d/2)`: the "B" of the
    /// two-part schemes (eq. 7) when the perturbation has two parts (see [`Integrator::S6`]).
    Perturbation,
}

/// A piece applied for `coefficient × τ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stage {
    /// The flow.
    pub piece: Piece,
    /// Fraction of the step.
    pub coefficient: f64,
}

const fn stage(piece: Piece, coefficient: f64) -> Stage {
    Stage { piece, coefficient }
}

/// Eq. 13: `S2(τ) = e^{τC/2} e^{τB/2} e^{τA} e^{τB/2} e^{τC/2}` (Duncan, Levison & Lee 1998).
pub const S2_STAGES: [Stage; 5] = [
    stage(Piece::Sun, 0.5),
    stage(Piece::Interaction, 0.5),
    stage(Piece::Kepler, 1.0),
    stage(Piece::Interaction, 0.5),
    stage(Piece::Sun, 0.5),
];

/// `c₁ = 1/√5` of eq. 7 (Laskar & Robutel 2001, SBAB₃).
pub const S6_C1: f64 = 0.447_213_595_499_957_9;
/// `c₂ = (1 − 1/√5)/2` of eq. 7.
pub const S6_C2: f64 = 0.276_393_202_250_021;
/// `d₁ = 1/12` of eq. 7.
pub const S6_D1: f64 = 1.0 / 12.0;
/// `d₂ = 5/12` of eq. 7.
pub const S6_D2: f64 = 5.0 / 12.0;

/// Eq. 7: `S6(τ) = e^{d₁τB} e^{c₂τA} e^{d₂τB} e^{c₁τA} e^{d₂τB} e^{c₂τA} e^{d₁τB}`.
pub const S6_STAGES: [Stage; 7] = [
    stage(Piece::Perturbation, S6_D1),
    stage(Piece::Kepler, S6_C2),
    stage(Piece::Perturbation, S6_D2),
    stage(Piece::Kepler, S6_C1),
    stage(Piece::Perturbation, S6_D2),
    stage(Piece::Kepler, S6_C2),
    stage(Piece::Perturbation, S6_D1),
];

/// A fixed-step map for the planets, with its step `τ` (time units of the system).
///
/// - `S2`: eq. 13, second order, error `O(ε τ²)`.
/// - `S6`: eq. 7, the pseudo-sixth-order scheme of Laskar & Robutel (2001) as used by
///   Chambers & Murison (2000), error `ε² τ² (13 − 5√5)/288 {{A,B},B} + O(ε τ⁶)`.
///   **Deviation (documented choice):** eq. 7 is written for a two-part Hamiltonian
///   `A + εB`; in mixed variables the perturbation has two parts (`H_Sun`, `H_Inter`) that do
///   not commute, so each `e^{dτB}` is applied as `e^{dτC/2} e^{dτB} e^{dτC/2}`
///   ([`Piece::Perturbation`]). Its own error is `O(ε² τ³)`, below the scheme's `ε² τ²` term.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Integrator {
    /// Eq. 13 with step `τ`.
    S2 {
        /// Step τ.
        step: f64,
    },
    /// Eq. 7 with step `τ`.
    S6 {
        /// Step τ.
        step: f64,
    },
}

impl Integrator {
    /// The step `τ`.
    pub fn step_size(&self) -> f64 {
        match *self {
            Integrator::S2 { step } | Integrator::S6 { step } => step,
        }
    }

    /// The stages of the map.
    pub fn stages(&self) -> &'static [Stage] {
        match self {
            Integrator::S2 { .. } => &S2_STAGES,
            Integrator::S6 { .. } => &S6_STAGES,
        }
    }

    /// Short name ("S2", "S6").
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::S2 { .. } => "S2",
            Integrator::S6 { .. } => "S6",
        }
    }

    /// Advances the planets by one step `τ`.
    pub fn step(&self, planets: &mut Planets) -> Result<(), SymplecticError> {
        let tau = self.step_size();
        if !(tau.is_finite() && tau != 0.0) {
            return Err(SymplecticError::InvalidParameter {
                name: "step",
                value: tau,
                reason: "must be finite and non-zero",
            });
        }
        for s in self.stages() {
            let d = s.coefficient * tau;
            match s.piece {
                Piece::Kepler => planets.kepler_drift(d)?,
                Piece::Interaction => planets.interaction_kick(d),
                Piece::Sun => planets.sun_drift(d),
                Piece::Perturbation => {
                    planets.sun_drift(0.5 * d);
                    planets.interaction_kick(d);
                    planets.sun_drift(0.5 * d);
                }
            }
        }
        Ok(())
    }

    /// Advances `steps` steps; a non-finite state stops the run with the step and planet.
    pub fn run(&self, planets: &mut Planets, steps: u64) -> Result<(), SymplecticError> {
        for k in 0..steps {
            self.step(planets)?;
            if let Some(body) = planets.first_non_finite() {
                return Err(SymplecticError::BlowUp { step: k, body });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coefficients_are_those_of_eq_7() {
        let c1 = 1.0 / 5f64.sqrt();
        assert!((S6_C1 - c1).abs() <= f64::EPSILON * c1);
        assert!((S6_C2 - 0.5 * (1.0 - c1)).abs() <= 2.0 * f64::EPSILON);
        // Consistency: the drifts and the kicks each sum to one step.
        let sum = |p: Piece| {
            S6_STAGES
                .iter()
                .filter(|s| s.piece == p)
                .map(|s| s.coefficient)
                .sum::<f64>()
        };
        assert!((sum(Piece::Kepler) - 1.0).abs() < 1e-15);
        assert!((sum(Piece::Perturbation) - 1.0).abs() < 1e-15);
        let sum2 = |p: Piece| {
            S2_STAGES
                .iter()
                .filter(|s| s.piece == p)
                .map(|s| s.coefficient)
                .sum::<f64>()
        };
        assert_eq!(
            [
                sum2(Piece::Kepler),
                sum2(Piece::Interaction),
                sum2(Piece::Sun)
            ],
            [1.0; 3]
        );
    }
}
