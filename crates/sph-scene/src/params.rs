//! From the `[solver]` settings to the solver's parameters ([`SolverParams`]): the solver's
//! defaults for the scene's particle spacing (`*Params::for_spacing`), then the scene's
//! frame length, gravity and substeps, then each setting the scene gives. The solver's own
//! range checks (`*Params::validate`) run on the result when the scene is checked, in the
//! scene's precision; an error is reported once, at the scene field the parameter comes
//! from, with its line.

use iisph_granular::{GranularParams, IisphParams};
use pbf::PbfParams;
use pcisph::PcisphParams;
use sph_core::{Real, Vec3};
use sph_solver::{CommonParams, SolverError};

use crate::error::Ctx;
use crate::{
    GranularSpec, IisphSettings, PbfSpec, PcisphSpec, Precision, Scene, SceneError, SolverSpec,
};

/// The parameters of the solver a scene asks for, in precision `R`.
#[derive(Debug, Clone, PartialEq)]
pub enum SolverParams<R: Real> {
    /// Position Based Fluids.
    Pbf(PbfParams<R>),
    /// PCISPH.
    Pcisph(PcisphParams<R>),
    /// IISPH, water or (with `granular` set) granular.
    Iisph(IisphParams<R>),
}

impl<R: Real> SolverParams<R> {
    /// The parameters every solver has.
    pub fn common(&self) -> &CommonParams<R> {
        match self {
            SolverParams::Pbf(p) => &p.common,
            SolverParams::Pcisph(p) => &p.common,
            SolverParams::Iisph(p) => &p.common,
        }
    }

    /// The solver's own range checks.
    pub fn validate(&self) -> Result<(), SolverError> {
        match self {
            SolverParams::Pbf(p) => p.validate(),
            SolverParams::Pcisph(p) => p.validate(),
            SolverParams::Iisph(p) => p.validate(),
        }
    }
}

fn r<R: Real>(x: f64) -> R {
    R::of_f64(x)
}

fn vec3<R: Real>(v: [f64; 3]) -> Vec3<R> {
    Vec3::new(r(v[0]), r(v[1]), r(v[2]))
}

impl Scene {
    /// The solver parameters the scene asks for, in precision `R`, checked by the solver
    /// (`validate`); an error names the scene field the refused parameter comes from
    /// ([`Scene::check`] runs this in the scene's precision).
    pub fn solver_params<R: Real>(&self) -> Result<SolverParams<R>, SceneError> {
        let p = self.solver_params_unchecked::<R>();
        let ctx = Ctx {
            lines: Some(&self.lines),
            ..Ctx::new(&self.source)
        };
        p.validate()
            .map_err(|e| self.param_error(&ctx, R::NAME, e))?;
        Ok(p)
    }

    /// The solver parameters the scene asks for, in precision `R`, without the solver's
    /// checks (the solver's constructor runs them).
    pub fn solver_params_unchecked<R: Real>(&self) -> SolverParams<R> {
        match &self.solver {
            SolverSpec::Pbf(s) => SolverParams::Pbf(self.pbf_params(s)),
            SolverSpec::Pcisph(s) => SolverParams::Pcisph(self.pcisph_params(s)),
            SolverSpec::Iisph(s) => SolverParams::Iisph(self.iisph_params(&s.iisph)),
            SolverSpec::Granular(s) => SolverParams::Iisph(self.granular_params(s)),
        }
    }

    /// The solver parameters in the scene's precision, checked: part of [`Scene::check`].
    pub(crate) fn check_solver_params(&self, ctx: &Ctx) -> Result<(), SceneError> {
        let checked = match self.precision {
            Precision::F32 => self.solver_params_unchecked::<f32>().validate(),
            Precision::F64 => self.solver_params_unchecked::<f64>().validate(),
        };
        let name = match self.precision {
            Precision::F32 => f32::NAME,
            Precision::F64 => f64::NAME,
        };
        checked.map_err(|e| self.param_error(ctx, name, e))
    }

    /// A solver's refusal of a parameter, at the scene field it comes from.
    fn param_error(&self, ctx: &Ctx, precision: &str, e: SolverError) -> SceneError {
        let field = match &e {
            SolverError::InvalidParameter { name, .. } => self.field_of_parameter(name),
            _ => "solver".to_string(),
        };
        ctx.invalid(
            field,
            format!("{e} (in {precision}, the precision the solver runs in)"),
        )
    }

    /// The scene field a solver parameter comes from: of the fields written in `[solver]`
    /// and `[simulation]`, the longest whose words (split at `_`) are all words of the
    /// parameter's name (`min_solver_iterations` → `solver.min_iterations`,
    /// `pressure_iterations` → `solver.iterations`); `solver` when none is.
    fn field_of_parameter(&self, name: &str) -> String {
        let words: Vec<&str> = name.split('_').collect();
        ["solver", "simulation"]
            .iter()
            .flat_map(|t| self.lines.fields_under(t).map(move |f| (*t, f)))
            .filter(|(_, f)| f.split('_').all(|w| words.contains(&w)))
            .max_by_key(|(_, f)| (f.len(), *f))
            .map_or_else(|| "solver".to_string(), |(t, f)| format!("{t}.{f}"))
    }

    /// The parameters every solver takes from the scene: spacing, support radius, rest
    /// density, frame length, gravity, substeps, reordering.
    fn common_params<R: Real>(&self, mut c: CommonParams<R>) -> CommonParams<R> {
        let s = self.solver.common();
        if let Some(ratio) = s.support_over_spacing {
            c.support_radius = r::<R>(self.particle_spacing * ratio);
        }
        if let Some(rho0) = s.rest_density {
            c.rest_density = r(rho0);
        }
        if let Some(k) = s.reorder_every {
            c.reorder_every = k;
        }
        c.dt = r(self.frame_dt_s);
        c.gravity = vec3(self.gravity);
        c.substeps = s.substeps;
        c
    }

    /// PBF: `PbfParams::for_spacing`, then the settings `s`.
    fn pbf_params<R: Real>(&self, s: &PbfSpec) -> PbfParams<R> {
        let mut p = PbfParams::<R>::for_spacing(r(self.particle_spacing));
        p.common = self.common_params(p.common);
        let relative_cfm = s.relative_cfm.unwrap_or(pbf::DEFAULT_RELATIVE_CFM);
        if let Some(d_ref) = p.reference_denominator() {
            p.cfm_epsilon = d_ref * r::<R>(relative_cfm);
        }
        p.solver_iterations = s.iterations;
        if let Some(k) = s.scorr_k {
            p.scorr_k = r(k);
        }
        if let Some(n) = s.scorr_n {
            p.scorr_n = n;
        }
        if let Some(dq) = s.scorr_delta_q {
            p.scorr_delta_q = r(dq);
        }
        if let Some(e) = s.vorticity_epsilon {
            p.vorticity_epsilon = r(e);
        }
        if let Some(c) = s.xsph_c {
            p.xsph_c = r(c);
        }
        if let Some(c) = s.clamp_negative_constraint {
            p.clamp_negative_constraint = c;
        }
        if let Some(t) = s.mean_compression_tolerance {
            p.mean_compression_tolerance = Some(r(t));
            p.min_solver_iterations = s
                .min_iterations
                .unwrap_or(p.min_solver_iterations.min(s.iterations));
        }
        p
    }

    /// PCISPH: `PcisphParams::for_spacing`, then the settings `s`.
    fn pcisph_params<R: Real>(&self, s: &PcisphSpec) -> PcisphParams<R> {
        let mut p = PcisphParams::<R>::for_spacing(r(self.particle_spacing));
        p.common = self.common_params(p.common);
        p.pressure_iterations = s.iterations;
        if let Some(c) = s.xsph_c {
            p.xsph_c = r(c);
        }
        if let Some(c) = s.clamp_negative_pressure {
            p.clamp_negative_pressure = c;
        }
        if let Some(t) = s.density_error_tolerance {
            p.density_error_tolerance = Some(r(t));
        }
        p
    }

    /// IISPH (water): `IisphParams::for_spacing`, then the settings `s`.
    fn iisph_params<R: Real>(&self, s: &IisphSettings) -> IisphParams<R> {
        let mut p = IisphParams::<R>::for_spacing(r(self.particle_spacing));
        p.common = self.common_params(p.common);
        if let Some(k) = s.max_iterations {
            p.max_iterations = k;
        }
        if let Some(k) = s.min_iterations {
            p.min_iterations = k;
        }
        if let Some(t) = s.density_error_tolerance {
            p.density_error_tolerance = r(t);
        }
        if let Some(w) = s.relaxation {
            p.relaxation = r(w);
        }
        if let Some(nu) = s.viscosity {
            p.viscosity = r(nu);
        }
        p
    }

    /// Granular IISPH: `iisph_params`, then friction, drag and upscaling.
    fn granular_params<R: Real>(&self, s: &GranularSpec) -> IisphParams<R> {
        let mut p = self.iisph_params::<R>(&s.iisph);
        let mut g = GranularParams::with_friction_angle(r(s.friction_angle_deg));
        if let Some(m) = s.cone_match {
            g.cone_match = m;
        }
        if let Some(c) = s.drag_coefficient {
            g.drag_coefficient = r(c);
        }
        if let Some(v) = s.air_velocity {
            g.air_velocity = vec3(v);
        }
        if let Some(n) = s.friction_max_iterations {
            g.friction_max_iterations = n;
        }
        if let Some(t) = s.friction_tolerance {
            g.friction_tolerance = r(t);
        }
        if let Some(w) = s.friction_relaxation {
            g.friction_relaxation = r(w);
        }
        p.granular = Some(g);
        p.upscaling_factor = s.upscaling_factor;
        p
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::Scene;

    const TEXT: &str = r#"
name = "mapping"
[simulation]
particle_spacing = 0.05
duration = 0.1
frame_dt = 0.02
[solver]
kind = "pbf"
substeps = 2
iterations = 3
mean_compression_tolerance = 0.01
min_iterations = 2
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.2, 0.2, 0.2]
"#;

    /// `friction_relaxation` reaches the granular parameters, absent gives the crate's
    /// default, and a value the solver refuses is named by its scene field.
    #[test]
    fn friction_relaxation_reaches_the_granular_parameters() {
        let text = |extra: &str| {
            format!(
                "name = \"relax\"\n[simulation]\nparticle_spacing = 0.05\nduration = 0.1\nframe_dt = 0.02\n[solver]\nkind = \"granular\"\nsubsteps = 1\nfriction_angle_deg = 30.0\n{extra}\n[[fluid]]\nkind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.2, 0.2]\n"
            )
        };
        let relaxation = |extra: &str| {
            let scene = Scene::parse_str(&text(extra), Path::new("relax.toml")).unwrap();
            let crate::SolverSpec::Granular(g) = &scene.solver else {
                panic!("not granular")
            };
            scene
                .granular_params::<f64>(g)
                .granular
                .expect("granular parameters")
                .friction_relaxation
        };
        assert_eq!(relaxation("friction_relaxation = 0.3"), 0.3);
        assert_eq!(relaxation(""), iisph_granular::DEFAULT_FRICTION_RELAXATION);
        let error = Scene::parse_str(&text("friction_relaxation = 1.5"), Path::new("relax.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("solver.friction_relaxation") && error.contains("(0, 1]"),
            "{error}"
        );
    }

    /// A parameter a solver refuses is named by the scene field it comes from (generic: by
    /// the words of its name, not a list of fields).
    #[test]
    fn solver_parameters_map_to_scene_fields() {
        let scene = Scene::parse_str(TEXT, Path::new("mapping.toml")).unwrap();
        for (param, field) in [
            ("solver_iterations", "solver.iterations"),
            ("pressure_iterations", "solver.iterations"),
            ("min_solver_iterations", "solver.min_iterations"),
            (
                "mean_compression_tolerance",
                "solver.mean_compression_tolerance",
            ),
            ("substeps", "solver.substeps"),
            ("support_radius", "solver"),
        ] {
            assert_eq!(scene.field_of_parameter(param), field, "{param}");
        }
    }
}
