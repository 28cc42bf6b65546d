//! The crate's one error type.

/// What went wrong in a measurement: the input named, nothing panics.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeasureError {
    /// No particles were given.
    #[error("{what}: no particles given")]
    Empty {
        /// The measurement.
        what: &'static str,
    },
    /// A particle position is NaN or infinite.
    #[error("{what}: particle {index} has a non-finite position ({x}, {y}, {z})")]
    NonFinite {
        /// The measurement.
        what: &'static str,
        /// Index of the particle in the input.
        index: usize,
        /// Its coordinates.
        x: f64,
        /// Its coordinates.
        y: f64,
        /// Its coordinates.
        z: f64,
    },
    /// A particle velocity is NaN or infinite.
    #[error("{what}: particle {index} has a non-finite velocity ({x}, {y}, {z})")]
    NonFiniteVelocity {
        /// The measurement.
        what: &'static str,
        /// Index of the particle in the input.
        index: usize,
        /// Its components.
        x: f64,
        /// Its components.
        y: f64,
        /// Its components.
        z: f64,
    },
    /// Positions and velocities of different lengths.
    #[error("{what}: {positions} positions but {velocities} velocities")]
    LengthMismatch {
        /// The measurement.
        what: &'static str,
        /// How many positions.
        positions: usize,
        /// How many velocities.
        velocities: usize,
    },
    /// An option is out of range.
    #[error("{what}: option {option} = {value}: {reason}")]
    InvalidOption {
        /// The measurement.
        what: &'static str,
        /// The option's name.
        option: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range.
        reason: &'static str,
    },
    /// The particles do not form a pile that can be measured (flat layer, too few surface
    /// points in the fit band, nothing above the floor).
    #[error("{what}: degenerate pile: {reason}")]
    Degenerate {
        /// The measurement.
        what: &'static str,
        /// Why, with the figures.
        reason: String,
    },
}
