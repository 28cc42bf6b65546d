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
    /// The lists would hold more pairs than [`crate::SearchLimits::max_pairs`] allows (a
    /// radius in the wrong units, or many coincident particles); the search stopped as
    /// soon as it found more.
    #[error(
        "the neighbour lists need more than {limit} pairs ({limit_bytes} bytes of indices \
         allowed): at least {found} found (at least {found_bytes} bytes) when the search \
         stopped; is the radius in the units of the positions, or are many particles \
         coincident?"
    )]
    TooManyPairs {
        /// Pairs found when the search stopped (a lower bound on what the lists need).
        found: usize,
        /// Bytes of `u32` indices `found` pairs take.
        found_bytes: usize,
        /// The limit on pairs.
        limit: usize,
        /// Bytes of `u32` indices `limit` pairs take.
        limit_bytes: usize,
    },
    /// An allocation whose size the input sets failed.
    #[error("could not allocate {bytes} bytes for {what}: {reason}")]
    OutOfMemory {
        /// The buffer (e.g. "neighbour indices").
        what: &'static str,
        /// Bytes asked for.
        bytes: usize,
        /// The allocator's reason.
        reason: String,
    },
    /// The caller's interrupt flag ([`crate::SearchLimits::interrupt`]) was raised.
    #[error("the neighbour search was interrupted")]
    Interrupted,
}

impl SearchError {
    /// [`SearchError::OutOfMemory`] for `count` elements of `T` in `what`.
    pub(crate) fn out_of_memory<T>(
        what: &'static str,
        count: usize,
        e: std::collections::TryReserveError,
    ) -> Self {
        SearchError::OutOfMemory {
            what,
            bytes: count.saturating_mul(std::mem::size_of::<T>()),
            reason: e.to_string(),
        }
    }
}
