/// Errors of the neighbour search; each names the offending particle or value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SearchError {
    /// The search radius is zero, negative, NaN or infinite.
    #[error("search radius h = {value} must be finite and > 0")]
    InvalidRadius {
        /// The rejected radius, widened to f64.
        value: f64,
    },
    /// A particle position has a NaN or infinite component.
    #[error("particle {index}: position component {axis} is not finite ({value})")]
    NonFinitePosition {
        /// Index of the particle (in the caller's order).
        index: usize,
        /// `'x'`, `'y'` or `'z'`.
        axis: char,
        /// The offending value.
        value: f64,
    },
    /// A cell coordinate `floor(x / h)` does not fit in an `i32` (with room for the ±1
    /// neighbour offsets): the radius is too small for the coordinates.
    #[error(
        "particle {index}: cell coordinate {axis} = floor({position} / {radius}) = {cell:e} \
         overflows i32; use a larger radius or smaller coordinates"
    )]
    CellCoordinateOverflow {
        /// Index of the particle.
        index: usize,
        /// `'x'`, `'y'` or `'z'`.
        axis: char,
        /// Its coordinate on that axis.
        position: f64,
        /// The search radius.
        radius: f64,
        /// The cell coordinate that overflowed.
        cell: f64,
    },
    /// A bounded grid method (cell start/end table) would need more cells than allowed.
    #[error(
        "the cell-start grid over the particles' bounding box needs {cells:e} cells \
         (limit {limit}); use an unbounded method (relation table or hashed grid)"
    )]
    DomainTooLarge {
        /// Cells the bounding grid would need.
        cells: f64,
        /// The configured limit.
        limit: usize,
    },
    /// More particles than 32-bit neighbour indices can address.
    #[error("{count} particles exceed the limit of {limit} for this method")]
    TooManyParticles {
        /// Number of particles given.
        count: usize,
        /// The method's limit.
        limit: usize,
    },
}
