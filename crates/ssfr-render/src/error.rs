//! [`SsfrError`], the crate's one error type.

use std::path::PathBuf;

/// Errors of the renderer. Every variant names what is wrong and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SsfrError {
    /// The image has no pixel (width or height 0), or more than [`crate::MAX_PIXELS`].
    #[error("image size {width} x {height}: {reason}")]
    ImageSize {
        /// Width (pixels).
        width: usize,
        /// Height (pixels).
        height: usize,
        /// Why it is refused.
        reason: &'static str,
    },
    /// The image's buffers would take more memory than the process may allocate (checked
    /// before they are allocated: [`crate::check_frame_memory`]).
    #[error(
        "image size {width} x {height}: its buffers need {needed_bytes} bytes \
         ({bytes_per_pixel} per pixel) and {available_bytes} bytes of memory are available"
    )]
    OutOfMemory {
        /// Width (pixels).
        width: usize,
        /// Height (pixels).
        height: usize,
        /// Bytes the renderer's buffers need at this size.
        needed_bytes: u64,
        /// Bytes per pixel of those buffers ([`crate::BYTES_PER_PIXEL`]).
        bytes_per_pixel: usize,
        /// Bytes the process may still allocate.
        available_bytes: u64,
    },
    /// The render was cancelled through its flag ([`crate::Renderer::set_cancel`]) before
    /// it finished; the renderer's buffers hold no complete frame.
    #[error("cancelled before the frame was finished")]
    Cancelled,
    /// A parameter is out of range (NaN, negative radius, degenerate camera, ...).
    #[error("{field}: {reason}")]
    Invalid {
        /// The parameter, as a path (`camera.fov_deg`, `material.ior_liquid`).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A particle position or radius is not finite, or a radius is not positive.
    #[error("particle {index}: {what} is {value} (must be finite{positive})", positive = if *what == "radius" { " and > 0" } else { "" })]
    BadParticle {
        /// Index of the particle in the caller's arrays.
        index: usize,
        /// `"position"`, `"radius"` or `"ellipsoid"`.
        what: &'static str,
        /// The offending value (a NaN or the radius).
        value: f64,
    },
    /// The per-particle arrays differ in length.
    #[error("{what}: {found} entries for {expected} particles")]
    LengthMismatch {
        /// The array.
        what: &'static str,
        /// Its length.
        found: usize,
        /// The number of positions.
        expected: usize,
    },
    /// No particle lies in front of the camera inside the image: nothing to render (a
    /// camera looking away from the liquid, or an empty frame).
    #[error("the camera sees none of the {particles} particles (camera at {eye:?} looking at {target:?})")]
    NothingVisible {
        /// Number of particles given.
        particles: usize,
        /// Camera position (m).
        eye: [f32; 3],
        /// Camera target (m).
        target: [f32; 3],
    },
    /// A particle frame file is missing.
    #[error("{}: frame file missing: {reason}", path.display())]
    MissingFrame {
        /// The file.
        path: PathBuf,
        /// Operating-system reason.
        reason: String,
    },
    /// A particle frame file cannot be decoded (truncated, not particle data, ...).
    #[error("{}: corrupt particle frame: {reason}", path.display())]
    CorruptFrame {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The `[render]` table of a scene file is malformed.
    #[error("render.{field}: {reason}")]
    Config {
        /// Field path inside `[render]` (`camera.eye`, `smoothing.method`).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// Writing or reading an image failed.
    #[error("{}: {reason}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        reason: String,
    },
}

impl SsfrError {
    pub(crate) fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        SsfrError::Invalid {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

/// `Ok` when `x` is finite and `> 0`.
pub(crate) fn positive(field: &str, x: f32) -> Result<(), SsfrError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(SsfrError::invalid(
            field,
            format!("{x}: must be finite and > 0"),
        ))
    }
}

/// `Ok` when `x` is finite and `>= 0`.
pub(crate) fn non_negative(field: &str, x: f32) -> Result<(), SsfrError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(SsfrError::invalid(
            field,
            format!("{x}: must be finite and >= 0"),
        ))
    }
}

/// `Ok` when every component is finite.
pub(crate) fn finite3(field: &str, v: [f32; 3]) -> Result<(), SsfrError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(SsfrError::invalid(field, format!("{v:?}: must be finite")))
    }
}
