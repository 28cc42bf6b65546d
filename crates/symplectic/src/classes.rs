//! Dynamical classes of comets from their osculating elements: trans-Neptunian, Centaur,
//! Jupiter-family, after
//!
//! > H. F. Levison, "Comet taxonomy", in T. W. Rettig and J. M. Hahn (eds.), *Completing the
//! > Inventory of the Solar System*, Astronomical Society of the Pacific Conference Series
//! > 107, 173–191 (1996),
//!
//! which sorts comets by the Tisserand parameter with respect to Jupiter,
//!
//! `T_J = a_J/a + 2 cos i √((a/a_J)(1 − e²))`,
//!
//! into ecliptic comets (`T_J > 2`) — Jupiter-family for `2 < T_J < 3` — and nearly isotropic
//! ones (`T_J < 2`). The classes here ([`classify`]):
//!
//! - [`DynamicalClass::TransNeptunian`]: bound, `a ≥ a_N`;
//! - [`DynamicalClass::Centaur`]: `q ≥ a_J` and `a < a_N` (perihelion beyond Jupiter, orbit
//!   inside Neptune's: the usual boundaries of the region between the giants);
//! - [`DynamicalClass::JupiterFamily`]: `q < a_J` and `2 < T_J < 3` (Levison's Jupiter-family
//!   comets that reach inside Jupiter's orbit);
//! - [`DynamicalClass::Other`]: anything else (`q < a_J` with `T_J ≤ 2` or `T_J ≥ 3`, or
//!   unbound).
//!
//! `a_J`, `a_N`: the J2000 mean semi-major axes of Jupiter and Neptune (E. M. Standish,
//! "Keplerian elements for approximate positions of the major planets", JPL Solar System
//! Dynamics, Table 1, valid 1800–2050). **Deviation:** `i` is the inclination to the
//! ecliptic of J2000 (the frame of the population), not to Jupiter's orbital plane (1.3° apart),
//! and the elements are barycentric.

use serde::{Deserialize, Serialize};

use crate::kepler::Elements;

/// Jupiter's semi-major axis, AU (Standish, J2000 mean elements).
pub const JUPITER_SEMI_MAJOR_AXIS_AU: f64 = 5.202_887_00;

/// Neptune's semi-major axis, AU (Standish, J2000 mean elements).
pub const NEPTUNE_SEMI_MAJOR_AXIS_AU: f64 = 30.069_922_76;

/// A comet's dynamical class ([`classify`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DynamicalClass {
    /// Bound, `a ≥ a_N`.
    TransNeptunian,
    /// `q ≥ a_J`, `a < a_N`.
    Centaur,
    /// `q < a_J`, `2 < T_J < 3`.
    JupiterFamily,
    /// Anything else.
    Other,
}

impl DynamicalClass {
    /// The label in tables: `trans_neptunian`, `centaur`, `jupiter_family`, `other`.
    pub fn label(self) -> &'static str {
        match self {
            Self::TransNeptunian => "trans_neptunian",
            Self::Centaur => "centaur",
            Self::JupiterFamily => "jupiter_family",
            Self::Other => "other",
        }
    }
}

/// Tisserand parameter with respect to Jupiter, `a_J/a + 2 cos i √((a/a_J)(1 − e²))`; `NaN`
/// for an unbound orbit (`1 − e² < 0` with `a < 0`: the root's argument is still positive,
/// but the parameter is not used for unbound orbits).
pub fn tisserand_jupiter(el: &Elements) -> f64 {
    let a = el.semi_major_axis;
    if a.is_nan() || a <= 0.0 {
        return f64::NAN;
    }
    let a_j = JUPITER_SEMI_MAJOR_AXIS_AU;
    let e2 = el.eccentricity * el.eccentricity;
    a_j / a + 2.0 * el.inclination.cos() * ((a / a_j) * (1.0 - e2).max(0.0)).sqrt()
}

/// The dynamical class of an orbit (module docs).
pub fn classify(el: &Elements) -> DynamicalClass {
    let a = el.semi_major_axis;
    if !(a > 0.0 && el.eccentricity < 1.0) {
        return DynamicalClass::Other;
    }
    if a >= NEPTUNE_SEMI_MAJOR_AXIS_AU {
        return DynamicalClass::TransNeptunian;
    }
    if el.perihelion >= JUPITER_SEMI_MAJOR_AXIS_AU {
        return DynamicalClass::Centaur;
    }
    let t = tisserand_jupiter(el);
    if t > 2.0 && t < 3.0 {
        DynamicalClass::JupiterFamily
    } else {
        DynamicalClass::Other
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn el(a: f64, e: f64, i_deg: f64) -> Elements {
        Elements {
            semi_major_axis: a,
            eccentricity: e,
            inclination: i_deg.to_radians(),
            perihelion: a * (1.0 - e),
        }
    }

    /// Known objects (JPL Small-Body Database osculating elements, rounded): 2060 Chiron
    /// (a 13.7, e 0.38, i 6.9°: q 8.5 AU) is a Centaur; 67P/Churyumov–Gerasimenko (a 3.46,
    /// e 0.64, i 7.0°: T_J 2.75) Jupiter-family; 2P/Encke (a 2.22, e 0.85, i 11.8°: T_J 3.03)
    /// not; 1P/Halley (a 17.8, e 0.967, i 162°: T_J −0.6) not; 136199 Eris (a 67.9) and
    /// Pluto (a 39.5) trans-Neptunian; a hyperbolic orbit other.
    #[test]
    fn known_objects_fall_in_their_classes() {
        assert_eq!(classify(&el(13.7, 0.38, 6.9)), DynamicalClass::Centaur);
        let churyumov = el(3.46, 0.64, 7.0);
        assert!((tisserand_jupiter(&churyumov) - 2.75).abs() < 0.02);
        assert_eq!(classify(&churyumov), DynamicalClass::JupiterFamily);
        let encke = el(2.22, 0.85, 11.8);
        assert!((tisserand_jupiter(&encke) - 3.03).abs() < 0.02);
        assert_eq!(classify(&encke), DynamicalClass::Other);
        assert_eq!(classify(&el(17.8, 0.967, 162.0)), DynamicalClass::Other);
        assert_eq!(
            classify(&el(67.9, 0.44, 44.0)),
            DynamicalClass::TransNeptunian
        );
        assert_eq!(
            classify(&el(39.5, 0.25, 17.1)),
            DynamicalClass::TransNeptunian
        );
        assert_eq!(classify(&el(-5.0, 1.5, 10.0)), DynamicalClass::Other);
    }
}
