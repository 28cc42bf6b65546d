//! The scene-facing settings of PCISPH (`[solver] kind = "pcisph"`): each key is the name
//! of the [`PcisphParams`] field it sets, defaults are [`PcisphParams::for_spacing`]'s, the
//! range checks are [`PcisphParams::validate`]'s.

use serde::Deserialize;
use sph_core::Real;
use sph_solver::settings::convert;
use sph_solver::{
    Boundary, CommonSettings, FluidSolver, KernelKind, SceneValues, SolverError, SolverSettings,
};

use crate::{Pcisph, PcisphParams, PCISPH_KERNEL};

/// PCISPH's `[solver]` settings (`kind = "pcisph"`); `None` = the default of
/// [`PcisphParams::for_spacing`]. Units and ranges as in [`PcisphParams`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PcisphSettings {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: CommonSettings,
    /// [`PcisphParams::pressure_iterations`] (required; formerly `iterations`).
    #[serde(alias = "iterations")]
    pub pressure_iterations: usize,
    /// [`PcisphParams::xsph_c`].
    pub xsph_c: Option<f64>,
    /// [`PcisphParams::clamp_negative_pressure`].
    pub clamp_negative_pressure: Option<bool>,
    /// [`PcisphParams::density_error_tolerance`].
    pub density_error_tolerance: Option<f64>,
}

/// The solver's name in errors.
use crate::params::NAME;

impl SolverSettings for PcisphSettings {
    type Params<R: Real> = PcisphParams<R>;

    const DENSITY_KERNEL: KernelKind = PCISPH_KERNEL;

    const RENAMED: &'static [(&'static str, &'static str)] =
        &[("iterations", "pressure_iterations")];

    fn with_common(common: CommonSettings, iterations: usize) -> Self {
        Self {
            common,
            pressure_iterations: iterations,
            xsph_c: None,
            clamp_negative_pressure: None,
            density_error_tolerance: None,
        }
    }

    fn common(&self) -> &CommonSettings {
        &self.common
    }

    fn common_mut(&mut self) -> &mut CommonSettings {
        &mut self.common
    }

    fn iterations(&self) -> usize {
        self.pressure_iterations
    }

    fn set_iterations(&mut self, n: usize) {
        self.pressure_iterations = n;
    }

    fn params(&self, scene: &SceneValues) -> PcisphParams<f64> {
        let mut p = PcisphParams::for_spacing(scene.particle_spacing);
        self.common.apply(scene, &mut p.common);
        p.pressure_iterations = self.pressure_iterations;
        if let Some(c) = self.xsph_c {
            p.xsph_c = c;
        }
        if let Some(c) = self.clamp_negative_pressure {
            p.clamp_negative_pressure = c;
        }
        if let Some(t) = self.density_error_tolerance {
            p.density_error_tolerance = Some(t);
        }
        p
    }

    fn build<R: Real>(
        params: PcisphParams<R>,
        boundary: Box<dyn Boundary<R>>,
    ) -> Result<Box<dyn FluidSolver<R>>, SolverError> {
        Ok(Box::new(Pcisph::with_boundary(params, boundary)?))
    }
}

impl<R: Real> PcisphParams<R> {
    /// These parameters in precision `S`, each value rounded to nearest (an error names the
    /// first finite value that does not fit).
    pub fn try_convert<S: Real>(&self) -> Result<PcisphParams<S>, SolverError> {
        Ok(PcisphParams {
            common: self.common.try_convert(NAME)?,
            pressure_iterations: self.pressure_iterations,
            density_error_tolerance: self
                .density_error_tolerance
                .map(|t| convert(NAME, "density_error_tolerance", t))
                .transpose()?,
            clamp_negative_pressure: self.clamp_negative_pressure,
            xsph_c: convert(NAME, "xsph_c", self.xsph_c)?,
        })
    }
}
