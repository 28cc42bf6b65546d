//! The scene-facing settings of the two IISPH kinds (`[solver] kind = "iisph"`, water, and
//! `kind = "granular"`): each key is the name of the [`IisphParams`] or [`GranularParams`]
//! field it sets, defaults are [`IisphParams::for_spacing`]'s and
//! [`GranularParams::with_friction_angle`]'s, the range checks are
//! [`IisphParams::validate`]'s.

use serde::Deserialize;
use sph_core::Real;
use sph_solver::settings::{convert, convert3};
use sph_solver::{
    Boundary, CommonSettings, FluidSolver, KernelKind, SceneValues, SolverError, SolverSettings,
};

use crate::params::NAME;
use crate::{
    ConeMatch, GranularParams, Iisph, IisphParams, DEFAULT_MAX_ITERATIONS, DEFAULT_MIN_ITERATIONS,
    IISPH_KERNEL,
};

/// The pressure-solve settings both IISPH kinds have (flattened into their tables); `None`
/// = the default of [`IisphParams::for_spacing`]. Units and ranges as in [`IisphParams`].
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct IisphSettings {
    /// [`IisphParams::max_iterations`] (default [`DEFAULT_MAX_ITERATIONS`]).
    pub max_iterations: Option<usize>,
    /// [`IisphParams::min_iterations`] (default [`DEFAULT_MIN_ITERATIONS`]).
    pub min_iterations: Option<usize>,
    /// [`IisphParams::density_error_tolerance`].
    pub density_error_tolerance: Option<f64>,
    /// [`IisphParams::relaxation`].
    pub relaxation: Option<f64>,
    /// [`IisphParams::viscosity`].
    pub viscosity: Option<f64>,
}

impl IisphSettings {
    /// [`IisphParams::for_spacing`] at the scene's spacing, with the scene's values,
    /// `common` and these settings.
    fn params(&self, common: &CommonSettings, scene: &SceneValues) -> IisphParams<f64> {
        let mut p = IisphParams::for_spacing(scene.particle_spacing);
        common.apply(scene, &mut p.common);
        if let Some(k) = self.max_iterations {
            p.max_iterations = k;
        }
        if let Some(k) = self.min_iterations {
            p.min_iterations = k;
        }
        if let Some(t) = self.density_error_tolerance {
            p.density_error_tolerance = t;
        }
        if let Some(w) = self.relaxation {
            p.relaxation = w;
        }
        if let Some(nu) = self.viscosity {
            p.viscosity = nu;
        }
        p
    }

    fn iterations(&self) -> usize {
        self.max_iterations.unwrap_or(DEFAULT_MAX_ITERATIONS)
    }

    fn min_iterations(&self) -> usize {
        self.min_iterations.unwrap_or(DEFAULT_MIN_ITERATIONS)
    }

    /// `max_iterations` against `min_iterations` as written (both named with their values).
    fn check_written(
        &self,
        key: &dyn Fn(&'static str) -> String,
    ) -> Result<(), (&'static str, String)> {
        let min = self.min_iterations();
        match self.max_iterations {
            Some(max) if min >= 1 && max < min => Err((
                "max_iterations",
                format!("must be >= {} = {min}, got {max}", key("min_iterations")),
            )),
            _ => Ok(()),
        }
    }
}

/// IISPH's `[solver]` settings for water (`kind = "iisph"`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaterSettings {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: CommonSettings,
    /// The pressure-solve settings.
    #[serde(flatten)]
    pub iisph: IisphSettings,
}

/// IISPH's `[solver]` settings for granular matter (`kind = "granular"`): those of
/// [`WaterSettings`] plus friction, drag and upscaling ([`GranularParams`], and
/// [`IisphParams::upscaling_factor`]); `None` = the default of
/// [`GranularParams::with_friction_angle`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularSettings {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: CommonSettings,
    /// The pressure-solve settings.
    #[serde(flatten)]
    pub iisph: IisphSettings,
    /// [`GranularParams::friction_angle_deg`] (degrees, required).
    pub friction_angle_deg: f64,
    /// [`GranularParams::cone_match`]: `"plane-strain"` (the default), `"simple-shear"` or
    /// `"plane-strain-associated"` ([`crate::cone_alpha`]).
    pub cone_match: Option<ConeMatch>,
    /// [`GranularParams::drag_coefficient`].
    pub drag_coefficient: Option<f64>,
    /// [`GranularParams::air_velocity`] (m/s).
    pub air_velocity: Option<[f64; 3]>,
    /// [`IisphParams::upscaling_factor`] (absent = no upscaling).
    pub upscaling_factor: Option<usize>,
    /// [`GranularParams::friction_max_iterations`].
    pub friction_max_iterations: Option<usize>,
    /// [`GranularParams::friction_tolerance`].
    pub friction_tolerance: Option<f64>,
    /// [`GranularParams::friction_relaxation`].
    pub friction_relaxation: Option<f64>,
}

/// The [`SolverSettings`] items both IISPH kinds share (same parameters, solver and
/// kernel).
macro_rules! iisph_kind {
    () => {
        type Params<R: Real> = IisphParams<R>;

        const DENSITY_KERNEL: KernelKind = IISPH_KERNEL;

        fn common(&self) -> &CommonSettings {
            &self.common
        }

        fn common_mut(&mut self) -> &mut CommonSettings {
            &mut self.common
        }

        fn iterations(&self) -> usize {
            self.iisph.iterations()
        }

        fn set_iterations(&mut self, n: usize) {
            self.iisph.max_iterations = Some(n);
        }

        fn min_iterations(&self) -> Option<usize> {
            Some(self.iisph.min_iterations())
        }

        fn check_written(
            &self,
            key: &dyn Fn(&'static str) -> String,
        ) -> Result<(), (&'static str, String)> {
            self.iisph.check_written(key)
        }

        fn build<R: Real>(
            params: IisphParams<R>,
            boundary: Box<dyn Boundary<R>>,
        ) -> Result<Box<dyn FluidSolver<R>>, SolverError> {
            Ok(Box::new(Iisph::with_boundary(params, boundary)?))
        }
    };
}

impl SolverSettings for WaterSettings {
    iisph_kind!();

    fn with_common(common: CommonSettings, _iterations: usize) -> Self {
        Self {
            common,
            iisph: IisphSettings::default(),
        }
    }

    fn params(&self, scene: &SceneValues) -> IisphParams<f64> {
        self.iisph.params(&self.common, scene)
    }
}

impl SolverSettings for GranularSettings {
    iisph_kind!();
    /// The name the IISPH scheme gives itself with friction ([`crate::IisphScheme`]).
    const LABEL: &'static str = "IISPH-granular";

    /// No friction (`friction_angle_deg = 0`), every other setting the default.
    fn with_common(common: CommonSettings, _iterations: usize) -> Self {
        Self {
            common,
            iisph: IisphSettings::default(),
            friction_angle_deg: 0.0,
            cone_match: None,
            drag_coefficient: None,
            air_velocity: None,
            upscaling_factor: None,
            friction_max_iterations: None,
            friction_tolerance: None,
            friction_relaxation: None,
        }
    }

    fn params(&self, scene: &SceneValues) -> IisphParams<f64> {
        let mut p = self.iisph.params(&self.common, scene);
        let mut g = GranularParams::with_friction_angle(self.friction_angle_deg);
        if let Some(m) = self.cone_match {
            g.cone_match = m;
        }
        if let Some(c) = self.drag_coefficient {
            g.drag_coefficient = c;
        }
        if let Some(v) = self.air_velocity {
            g.air_velocity = v.into();
        }
        if let Some(n) = self.friction_max_iterations {
            g.friction_max_iterations = n;
        }
        if let Some(t) = self.friction_tolerance {
            g.friction_tolerance = t;
        }
        if let Some(w) = self.friction_relaxation {
            g.friction_relaxation = w;
        }
        p.granular = Some(g);
        p.upscaling_factor = self.upscaling_factor;
        p
    }
}

impl<R: Real> IisphParams<R> {
    /// These parameters in precision `S`, each value rounded to nearest (an error names the
    /// first finite value that does not fit).
    pub fn try_convert<S: Real>(&self) -> Result<IisphParams<S>, SolverError> {
        Ok(IisphParams {
            common: self.common.try_convert(NAME)?,
            min_iterations: self.min_iterations,
            max_iterations: self.max_iterations,
            density_error_tolerance: convert(
                NAME,
                "density_error_tolerance",
                self.density_error_tolerance,
            )?,
            relaxation: convert(NAME, "relaxation", self.relaxation)?,
            viscosity: convert(NAME, "viscosity", self.viscosity)?,
            granular: self
                .granular
                .as_ref()
                .map(GranularParams::try_convert)
                .transpose()?,
            upscaling_factor: self.upscaling_factor,
        })
    }
}

impl<R: Real> GranularParams<R> {
    /// These parameters in precision `S`, each value rounded to nearest (an error names the
    /// first finite value that does not fit).
    pub fn try_convert<S: Real>(&self) -> Result<GranularParams<S>, SolverError> {
        Ok(GranularParams {
            friction_angle_deg: convert(NAME, "friction_angle_deg", self.friction_angle_deg)?,
            cone_match: self.cone_match,
            drag_coefficient: convert(NAME, "drag_coefficient", self.drag_coefficient)?,
            air_velocity: convert3(NAME, "air_velocity", &self.air_velocity)?,
            air_density: convert(NAME, "air_density", self.air_density)?,
            drag_cone_half_angle_deg: convert(
                NAME,
                "drag_cone_half_angle_deg",
                self.drag_cone_half_angle_deg,
            )?,
            friction_max_iterations: self.friction_max_iterations,
            friction_tolerance: convert(NAME, "friction_tolerance", self.friction_tolerance)?,
            friction_relaxation: convert(NAME, "friction_relaxation", self.friction_relaxation)?,
        })
    }
}
