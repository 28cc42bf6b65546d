//! The scene-facing settings of PBF (`[solver] kind = "pbf"`): each key is the name of the
//! [`PbfParams`] field it sets, defaults are [`PbfParams::for_spacing`]'s, the range checks
//! are [`PbfParams::validate`]'s.

use serde::Deserialize;
use sph_core::Real;
use sph_solver::settings::convert;
use sph_solver::{
    Boundary, CommonSettings, FluidSolver, KernelKind, SceneValues, SolverError, SolverSettings,
};

use crate::{Pbf, PbfParams, DEFAULT_RELATIVE_CFM, PBF_KERNEL};

/// PBF's `[solver]` settings (`kind = "pbf"`); `None` = the default of
/// [`PbfParams::for_spacing`]. Units and ranges as in [`PbfParams`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PbfSettings {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: CommonSettings,
    /// [`PbfParams::solver_iterations`] (required; formerly `iterations`).
    #[serde(alias = "iterations")]
    pub solver_iterations: usize,
    /// [`PbfParams::mean_compression_tolerance`].
    pub mean_compression_tolerance: Option<f64>,
    /// [`PbfParams::min_solver_iterations`], only with `mean_compression_tolerance`
    /// (formerly `min_iterations`).
    #[serde(alias = "min_iterations")]
    pub min_solver_iterations: Option<usize>,
    /// [`PbfParams::cfm_epsilon`] relative to the full-lattice denominator
    /// ([`PbfParams::reference_denominator`]): `ε = relative_cfm · D_ref` (default
    /// [`DEFAULT_RELATIVE_CFM`]). The one PBF setting stated relative to something else, so
    /// that a scene keeps its relaxation when its spacing changes; a refusal of
    /// `cfm_epsilon` is reported at this key.
    pub relative_cfm: Option<f64>,
    /// [`PbfParams::clamp_negative_constraint`].
    pub clamp_negative_constraint: Option<bool>,
    /// [`PbfParams::scorr_k`].
    pub scorr_k: Option<f64>,
    /// [`PbfParams::scorr_n`].
    pub scorr_n: Option<u32>,
    /// [`PbfParams::scorr_delta_q`].
    pub scorr_delta_q: Option<f64>,
    /// [`PbfParams::vorticity_epsilon`] (scene files: ≥ 0; the negative control of the
    /// vorticity experiment sets the parameter in code).
    pub vorticity_epsilon: Option<f64>,
    /// [`PbfParams::xsph_c`].
    pub xsph_c: Option<f64>,
}

/// The solver's name in errors.
use crate::params::NAME;

impl SolverSettings for PbfSettings {
    type Params<R: Real> = PbfParams<R>;

    const DENSITY_KERNEL: KernelKind = PBF_KERNEL;

    const RENAMED: &'static [(&'static str, &'static str)] = &[
        ("iterations", "solver_iterations"),
        ("min_iterations", "min_solver_iterations"),
    ];

    fn with_common(common: CommonSettings, iterations: usize) -> Self {
        Self {
            common,
            solver_iterations: iterations,
            mean_compression_tolerance: None,
            min_solver_iterations: None,
            relative_cfm: None,
            clamp_negative_constraint: None,
            scorr_k: None,
            scorr_n: None,
            scorr_delta_q: None,
            vorticity_epsilon: None,
            xsph_c: None,
        }
    }

    fn common(&self) -> &CommonSettings {
        &self.common
    }

    fn common_mut(&mut self) -> &mut CommonSettings {
        &mut self.common
    }

    fn iterations(&self) -> usize {
        self.solver_iterations
    }

    fn set_iterations(&mut self, n: usize) {
        self.solver_iterations = n;
    }

    fn min_iterations(&self) -> Option<usize> {
        self.min_solver_iterations
    }

    fn params(&self, scene: &SceneValues) -> PbfParams<f64> {
        let mut p = PbfParams::for_spacing(scene.particle_spacing);
        self.common.apply(scene, &mut p.common);
        if let Some(d_ref) = p.reference_denominator() {
            p.cfm_epsilon = d_ref * self.relative_cfm.unwrap_or(DEFAULT_RELATIVE_CFM);
        }
        p.solver_iterations = self.solver_iterations;
        if let Some(k) = self.scorr_k {
            p.scorr_k = k;
        }
        if let Some(n) = self.scorr_n {
            p.scorr_n = n;
        }
        if let Some(dq) = self.scorr_delta_q {
            p.scorr_delta_q = dq;
        }
        if let Some(e) = self.vorticity_epsilon {
            p.vorticity_epsilon = e;
        }
        if let Some(c) = self.xsph_c {
            p.xsph_c = c;
        }
        if let Some(c) = self.clamp_negative_constraint {
            p.clamp_negative_constraint = c;
        }
        if let Some(t) = self.mean_compression_tolerance {
            p.mean_compression_tolerance = Some(t);
            p.min_solver_iterations = self
                .min_solver_iterations
                .unwrap_or(p.min_solver_iterations.min(self.solver_iterations));
        }
        p
    }

    fn check_written(
        &self,
        key: &dyn Fn(&'static str) -> String,
    ) -> Result<(), (&'static str, String)> {
        if let Some(k) = self.min_solver_iterations {
            if self.mean_compression_tolerance.is_none() {
                return Err((
                    "min_solver_iterations",
                    format!("only applies with {}", key("mean_compression_tolerance")),
                ));
            }
            if k == 0 || k > self.solver_iterations {
                return Err((
                    "min_solver_iterations",
                    format!(
                        "must be >= 1 and <= {} = {}, got {k}",
                        key("solver_iterations"),
                        self.solver_iterations
                    ),
                ));
            }
        }
        match self.vorticity_epsilon {
            Some(e) if !(e.is_finite() && e >= 0.0) => Err((
                "vorticity_epsilon",
                format!("must be finite and >= 0, got {e}"),
            )),
            _ => Ok(()),
        }
    }

    fn key_of(params: &PbfParams<f64>, name: &str, value: f64) -> Option<(&'static str, f64)> {
        let d_ref = params.reference_denominator()?;
        (name == "cfm_epsilon").then(|| ("relative_cfm", value / d_ref))
    }

    fn build<R: Real>(
        params: PbfParams<R>,
        boundary: Box<dyn Boundary<R>>,
    ) -> Result<Box<dyn FluidSolver<R>>, SolverError> {
        Ok(Box::new(Pbf::with_boundary(params, boundary)?))
    }
}

impl<R: Real> PbfParams<R> {
    /// These parameters in precision `S`, each value rounded to nearest (an error names the
    /// first finite value that does not fit). `cfm_epsilon` is converted relative to its
    /// scale, the full-lattice denominator `D_ref` ([`PbfParams::reference_denominator`],
    /// computed again in `S` from the converted spacing and support radius): `ε/D_ref` is
    /// kept, as when the parameters are made in `S` from a relative CFM. In the same
    /// precision every value is kept as it is.
    pub fn try_convert<S: Real>(&self) -> Result<PbfParams<S>, SolverError> {
        let common = self.common.try_convert::<S>(NAME)?;
        let d_ref = (self.reference_denominator(), common.reference_denominator());
        let cfm_epsilon = match d_ref {
            (Some(d), Some(d_s)) if S::NAME != R::NAME => {
                let relative = self.cfm_epsilon.as_f64() / d.as_f64();
                d_s * convert::<f64, S>(NAME, "cfm_epsilon", relative)?
            }
            _ => convert(NAME, "cfm_epsilon", self.cfm_epsilon)?,
        };
        Ok(PbfParams {
            common,
            solver_iterations: self.solver_iterations,
            mean_compression_tolerance: self
                .mean_compression_tolerance
                .map(|t| convert(NAME, "mean_compression_tolerance", t))
                .transpose()?,
            min_solver_iterations: self.min_solver_iterations,
            cfm_epsilon,
            clamp_negative_constraint: self.clamp_negative_constraint,
            scorr_k: convert(NAME, "scorr_k", self.scorr_k)?,
            scorr_n: self.scorr_n,
            scorr_delta_q: convert(NAME, "scorr_delta_q", self.scorr_delta_q)?,
            vorticity_epsilon: convert(NAME, "vorticity_epsilon", self.vorticity_epsilon)?,
            xsph_c: convert(NAME, "xsph_c", self.xsph_c)?,
        })
    }
}
