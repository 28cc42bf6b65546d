//! Scene-facing settings: what a `[solver]` table of a scene file says, and how a solver's
//! crate turns it into its parameters.
//!
//! Each solver crate owns one settings struct (serde, `deny_unknown_fields`, the keys named
//! as the parameters they set, `#[serde(alias = …)]` for keys renamed since, listed in
//! [`SolverSettings::RENAMED`]) with the settings every solver has, [`CommonSettings`],
//! flattened into it, and implements [`SolverSettings`] for it: the defaults stay those of
//! the parameters' own constructor (`for_spacing`), the one range check is the parameters'
//! own `validate`, and the parameters are built once, in `f64`, then converted to the
//! precision the solver runs in ([`SolverParameters::convert`], failing on a value that
//! does not fit, [`convert`]). The settings also declare the scene boundary features the
//! solver takes ([`SolverSettings::BOUNDARY_FEATURES`], [`crate::scene_boundary`]) and take
//! the scene's boundary into the parameters ([`SolverSettings::take_scene_boundary`]). A
//! scene reader (`sph-scene`) registers each settings struct with one line; the solver
//! kinds, the scene's solver enum, the factory and the density kernel follow from this
//! trait.

use serde::Deserialize;
use sph_core::{Real, Vec3};
use sph_kernels::KernelKind;

use crate::scene_boundary::{BoundaryFeatures, SceneBoundary};
use crate::{Boundary, CommonParams, FluidSolver, SolverError, SolverParameters};

/// The settings every solver has, flattened into each solver's settings (`[solver]` keys
/// `substeps`, `rest_density`, `support_over_spacing`, `reorder_every`). `None` = the
/// solver's default ([`CommonParams::for_spacing`] and the solver's own `for_spacing`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct CommonSettings {
    /// Solver steps per frame ([`CommonParams::substeps`], required).
    pub substeps: usize,
    /// Rest density `ρ0` (kg/m³, [`CommonParams::rest_density`]).
    pub rest_density: Option<f64>,
    /// Support radius over particle spacing, `h / s` (the one setting stated relative to
    /// the scene: [`CommonParams::support_radius`] is `h = (h/s) s`; a refusal of
    /// `support_radius` is reported at this key, as `h / s`).
    pub support_over_spacing: Option<f64>,
    /// Reorder particles every this many frames, 0 = never
    /// ([`CommonParams::reorder_every`]).
    pub reorder_every: Option<usize>,
}

impl CommonSettings {
    /// `substeps` steps per frame, every other setting the solver's default.
    pub fn new(substeps: usize) -> Self {
        Self {
            substeps,
            rest_density: None,
            support_over_spacing: None,
            reorder_every: None,
        }
    }

    /// Sets the parameters `c` (a solver's defaults for the scene's spacing) from the
    /// scene's frame and gravity and these settings.
    pub fn apply(&self, scene: &SceneValues, c: &mut CommonParams<f64>) {
        if let Some(ratio) = self.support_over_spacing {
            c.support_radius = scene.particle_spacing * ratio;
        }
        if let Some(rho0) = self.rest_density {
            c.rest_density = rho0;
        }
        if let Some(k) = self.reorder_every {
            c.reorder_every = k;
        }
        c.dt = scene.frame_dt;
        c.gravity = Vec3::from(scene.gravity);
        c.substeps = self.substeps;
    }

    /// The key of a refused common parameter `name` with value `value` when that parameter
    /// is not itself a `[solver]` key: `support_radius` is set as `support_over_spacing`
    /// (the value then given as `h / s`).
    pub fn key_of(name: &str, value: f64, particle_spacing: f64) -> Option<(&'static str, f64)> {
        (name == "support_radius").then(|| ("support_over_spacing", value / particle_spacing))
    }
}

/// What a scene gives every solver besides its `[solver]` settings: the particle spacing
/// (m), the frame length (s) and gravity (m/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneValues {
    /// Particle spacing `s` (m).
    pub particle_spacing: f64,
    /// Frame length: the `dt` of one `step` call (s).
    pub frame_dt: f64,
    /// Gravity (m/s²).
    pub gravity: [f64; 3],
    /// Two or three dimensions ([`crate::Dimensions`]).
    pub dimensions: crate::Dimensions,
}

/// A solver's scene-facing settings (the `[solver]` table of its kind), implemented by each
/// solver crate for its settings struct: everything a scene reader needs to make and run
/// the solver (see the module documentation).
pub trait SolverSettings: Sized + Clone + std::fmt::Debug + PartialEq {
    /// The solver's parameters in precision `R` (their name, common part, range check and
    /// conversion: [`SolverParameters`]).
    type Params<R: Real>: SolverParameters<R>;

    /// The solver's name in reports: the name its solver gives itself for these settings
    /// ([`FluidSolver::name`]); by default its parameters'
    /// [`SolverParameters::NAME`].
    const LABEL: &'static str = <Self::Params<f64> as SolverParameters<f64>>::NAME;

    /// The scene boundary features the solver takes ([`crate::scene_boundary`]): by
    /// default solids as collision boundaries or volume maps only.
    const BOUNDARY_FEATURES: BoundaryFeatures = BoundaryFeatures::SOLIDS_ONLY;

    /// Whether the solver runs in the plane ([`crate::Dimensions::Two`]); by default only
    /// in three dimensions.
    const PLANAR: bool = false;

    /// The density kernel of the solver (the kernel its volume maps are integrated with and
    /// its masses calibrated with).
    const DENSITY_KERNEL: KernelKind;

    /// Keys renamed to the name of the parameter they set: `(old key, key)`, each old key
    /// accepted by serde (`alias`) so that older scene files still load, and named in errors
    /// as the file writes it.
    const RENAMED: &'static [(&'static str, &'static str)] = &[];

    /// The settings with `common`, every other setting the solver's default; `iterations`
    /// sets the iteration count of a solver whose table requires one (and is ignored by
    /// the others).
    fn with_common(common: CommonSettings, iterations: usize) -> Self;

    /// The settings every solver has.
    fn common(&self) -> &CommonSettings;

    /// The settings every solver has, to edit.
    fn common_mut(&mut self) -> &mut CommonSettings;

    /// The iterations per step the settings give (the maximum, for a solver that stops at
    /// a tolerance).
    fn iterations(&self) -> usize;

    /// Sets the iterations per step (the `[quick]` override `iterations`).
    fn set_iterations(&mut self, n: usize);

    /// The fewest iterations per step the settings give, if the solver has such a bound.
    fn min_iterations(&self) -> Option<usize> {
        None
    }

    /// The parameters, in `f64`: the solver's defaults for the scene's spacing, then the
    /// scene's values, then each setting given. Not validated.
    fn params(&self, scene: &SceneValues) -> Self::Params<f64>;

    /// The checks that only make sense on the settings as written (e.g. a setting that only
    /// applies with another one); the parameters' ranges are their `validate`'s. An error
    /// is `(parameter name, reason)`; `key` gives the `[solver]` key of a parameter as the
    /// file writes it (e.g. `solver.iterations`), for the reason to name.
    fn check_written(
        &self,
        key: &dyn Fn(&'static str) -> String,
    ) -> Result<(), (&'static str, String)> {
        let _ = key;
        Ok(())
    }

    /// The key of a refused parameter `name` (value `value`) that is not itself a key (a
    /// setting stated relative to something else), with the value as that key states it.
    fn key_of(params: &Self::Params<f64>, name: &str, value: f64) -> Option<(&'static str, f64)> {
        let _ = (params, name, value);
        None
    }

    /// Takes the scene's boundary (walls, moving walls, boundary particles, periodic axes,
    /// pour) into `params`. By default takes nothing and refuses a boundary that uses a
    /// feature beyond [`BoundaryFeatures::SOLIDS_ONLY`]'s
    /// ([`SolverError::UnsupportedFeature`]); a solver that declares more
    /// [`SolverSettings::BOUNDARY_FEATURES`] takes them here.
    fn take_scene_boundary(
        params: &mut Self::Params<f64>,
        boundary: SceneBoundary<f64>,
    ) -> Result<(), SolverError> {
        let _ = params;
        boundary.check_supported(
            <Self::Params<f64> as SolverParameters<f64>>::NAME,
            &BoundaryFeatures::SOLIDS_ONLY,
        )
    }

    /// The solver with these parameters and `boundary` (its constructor validates them).
    fn build<R: Real>(
        params: Self::Params<R>,
        boundary: Box<dyn Boundary<R>>,
    ) -> Result<Box<dyn FluidSolver<R>>, SolverError>;
}

/// `x` (parameter `name` of `solver`) in precision `S`, rounded to nearest; an error when a
/// finite value does not fit (it would overflow to ±∞), as splashsurf's `try_convert`. A
/// value that rounds to zero is kept: the parameters' `validate` in `S` says whether zero is
/// allowed there.
pub fn convert<R: Real, S: Real>(
    solver: &'static str,
    name: &'static str,
    x: R,
) -> Result<S, SolverError> {
    let y = S::of_f64(x.as_f64());
    if x.is_finite_value() && !y.is_finite_value() {
        return Err(SolverError::InvalidParameter {
            solver,
            name,
            value: x.as_f64(),
            reason: "does not fit in the precision the solver runs in",
        });
    }
    Ok(y)
}

/// [`convert`] of each component of `v`.
pub fn convert3<R: Real, S: Real>(
    solver: &'static str,
    name: &'static str,
    v: &Vec3<R>,
) -> Result<Vec3<S>, SolverError> {
    Ok(Vec3::new(
        convert(solver, name, v.x)?,
        convert(solver, name, v.y)?,
        convert(solver, name, v.z)?,
    ))
}

#[cfg(test)]
mod tests {
    use super::convert;

    /// A finite value that overflows the target precision is refused; one that rounds (to
    /// zero, too) is kept, and ±∞ and NaN pass through for `validate` to name.
    #[test]
    fn convert_refuses_only_overflow() {
        assert!(convert::<f64, f32>("t", "x", 1e300).is_err());
        assert!(convert::<f64, f32>("t", "x", -1e300).is_err());
        assert_eq!(convert::<f64, f32>("t", "x", 1e-300).unwrap(), 0.0);
        assert_eq!(convert::<f64, f32>("t", "x", 0.1).unwrap(), 0.1f32);
        assert!(convert::<f64, f32>("t", "x", f64::NAN).unwrap().is_nan());
        assert_eq!(
            convert::<f64, f32>("t", "x", f64::INFINITY).unwrap(),
            f32::INFINITY
        );
        assert_eq!(
            convert::<f32, f64>("t", "x", 0.1f32).unwrap(),
            0.1f32 as f64
        );
    }
}
