/// Errors of `sph-core`: invalid geometry or particle data supplied by the user.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CoreError {
    /// A particle position has a NaN or infinite component.
    #[error("particle {index}: position component {axis} is not finite ({value})")]
    NonFinitePosition {
        /// Index of the offending particle.
        index: usize,
        /// `'x'`, `'y'` or `'z'`.
        axis: char,
        /// The offending value, widened to `f64`.
        value: f64,
    },
    /// A particle velocity has a NaN or infinite component.
    #[error("particle {index}: velocity component {axis} is not finite ({value})")]
    NonFiniteVelocity {
        /// Index of the offending particle.
        index: usize,
        /// `'x'`, `'y'` or `'z'`.
        axis: char,
        /// The offending value, widened to `f64`.
        value: f64,
    },
    /// A scalar parameter is out of its valid range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Name of the parameter, e.g. `"sphere radius"`.
        name: &'static str,
        /// The offending value, widened to `f64`.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// Per-particle arrays (or a permutation) do not have matching lengths.
    #[error("length mismatch: {what} has {found} entries, expected {expected}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        found: usize,
        /// The length it should have.
        expected: usize,
    },
    /// A permutation contains an index twice or out of range.
    #[error("invalid permutation: entry {position} = {value} is out of range or repeated")]
    InvalidPermutation {
        /// Position in the permutation array.
        position: usize,
        /// The offending entry.
        value: u32,
    },
    /// An input file was refused (missing, not a regular file, too large, not text).
    #[error("{path}: {reason}")]
    Input {
        /// The file.
        path: std::path::PathBuf,
        /// Why it was refused.
        reason: String,
    },
    /// A [`SampledGrid`](crate::SampledGrid) would have more nodes than allowed (counts
    /// that do not fit a `usize` are reported as `usize::MAX`).
    #[error("sampled grid of {nx} x {ny} x {nz} nodes exceeds the maximum of {max} nodes (cell size too small for the box)")]
    GridTooLarge {
        /// Nodes along x.
        nx: usize,
        /// Nodes along y.
        ny: usize,
        /// Nodes along z.
        nz: usize,
        /// [`SampledGrid::MAX_NODES`](crate::SampledGrid::MAX_NODES).
        max: usize,
    },
}
