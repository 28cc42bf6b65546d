//! The space a scene and its solver live in: three dimensions, or the plane `z = 0` (two
//! dimensions: a plane-strain section, as the 2D experiments of granular mechanics are).

use serde::{Deserialize, Serialize};

/// The number of space dimensions of a run (in scene files `[simulation] dimensions = 2` or
/// `3`, the default).
///
/// In two dimensions the particles lie in the plane `z = 0` and interact through kernels
/// normalised in 2D; each stands for a slab of one particle spacing `s` across the plane, so
/// that masses stay `ρ0 s³` and densities `kg/m³` (a plane-strain section of unit depth per
/// spacing). Solvers that take it say so ([`crate::SolverSettings::PLANAR`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(try_from = "u8", into = "u8")]
#[non_exhaustive]
pub enum Dimensions {
    /// Three dimensions (the default).
    #[default]
    Three,
    /// The plane `z = 0`.
    Two,
}

impl Dimensions {
    /// 2 or 3.
    pub fn count(self) -> usize {
        match self {
            Dimensions::Three => 3,
            Dimensions::Two => 2,
        }
    }

    /// Whether this is the plane (two dimensions).
    pub fn is_planar(self) -> bool {
        self == Dimensions::Two
    }
}

impl TryFrom<u8> for Dimensions {
    type Error = String;
    fn try_from(n: u8) -> Result<Self, String> {
        match n {
            3 => Ok(Dimensions::Three),
            2 => Ok(Dimensions::Two),
            _ => Err(format!("dimensions must be 2 or 3, got {n}")),
        }
    }
}

impl From<Dimensions> for u8 {
    fn from(d: Dimensions) -> u8 {
        d.count() as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dimensions_are_their_count() {
        assert_eq!(Dimensions::try_from(2), Ok(Dimensions::Two));
        assert_eq!(Dimensions::try_from(3), Ok(Dimensions::Three));
        assert_eq!(u8::from(Dimensions::Two), 2);
        let e = Dimensions::try_from(1).unwrap_err();
        assert_eq!(e, "dimensions must be 2 or 3, got 1");
    }
}
