#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Measurements of granular heaps and deposits on particle output, usable on any scene's
//! positions (a VTK frame read back, a simulation state, an experiment's run): the **angle of
//! repose** of a settled pile ([`repose`]), that of a conical heap on a circular base per
//! azimuthal sector ([`cone`]: the funnel method's fixed base), and the **runout** of a collapsed column, planar
//! ([`runout()`]) or axisymmetric ([`radial_runout`]) ([`mod@runout`]), and whether a heap is
//! **at rest** ([`rest`]: robust speeds and the angle's drift over time, with the margins),
//! and the **stress of a heap's flanks** in the slope's axes ([`flank`], from a solver that
//! carries a stress per particle). They depend on the particle positions (velocities, stress)
//! only, not on the solver that made them.
//!
//! Conventions: SI units (m, degrees for angles); gravity along −y, so "up" is +y and the
//! floor is the plane `y = floor_y`. Heights and distances are those of particle **centres**
//! (the free surface lies one particle radius above them; that offset does not change a
//! slope, and [`RunoutOptions::particle_radius_m`] adds it to the front). Positions are
//! `f32` or `f64` ([`Real`]); every figure is computed in `f64`. Nothing panics on input: an
//! empty set, a non-finite position (with its index), an option out of range or a pile that
//! cannot be measured is a [`MeasureError`].
//!
//! References: G. Lube, H. E. Huppert, R. S. J. Sparks & M. A. Hallworth, "Axisymmetric
//! collapses of granular columns", *J. Fluid Mech.* 508, 175–199 (2004),
//! doi:10.1017/S0022112004009036. G. Lube, H. E. Huppert, R. S. J. Sparks & A. Freundt,
//! "Collapses of two-dimensional granular columns", *Physical Review E* 72, 041301 (2005),
//! doi:10.1103/PhysRevE.72.041301.

pub mod cone;
mod error;
pub mod flank;
pub mod repose;
pub mod rest;
pub mod runout;

pub use cone::{cone_angle_by_sector, ConeBase, ConeMeasurement, ConeOptions, SectorFit};
pub use error::MeasureError;
pub use flank::{flank_layer_stress, FlankLayers, LayerStress};
pub use repose::{
    angle_of_repose, surface_profile, FlankFit, PileShape, ReposeMeasurement, ReposeOptions,
    SurfacePoint,
};
pub use rest::{judge_rest, rest_sample, RestMargin, RestSample, RestSettings, RestVerdict};
pub use runout::{
    normalised_runout, radial_runout, runout, FrontMethod, RadialRunout, RadialRunoutOptions,
    RunoutOptions,
};
pub use sph_core::{Real, Vec3};

/// Fails on an empty set or a non-finite position (the first, with its index).
pub(crate) fn check_finite<R: Real>(
    what: &'static str,
    positions: &[Vec3<R>],
) -> Result<(), MeasureError> {
    if positions.is_empty() {
        return Err(MeasureError::Empty { what });
    }
    for (index, p) in positions.iter().enumerate() {
        if !(p.x.is_finite_value() && p.y.is_finite_value() && p.z.is_finite_value()) {
            return Err(MeasureError::NonFinite {
                what,
                index,
                x: p.x.as_f64(),
                y: p.y.as_f64(),
                z: p.z.as_f64(),
            });
        }
    }
    Ok(())
}
