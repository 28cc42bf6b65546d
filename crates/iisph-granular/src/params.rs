//! Parameters of the IISPH solver (water) and of its granular extension.

use sph_core::{Real, Vec3};
use sph_solver::{CommonParams, SolverError};

/// Name of the solver in errors and reports.
pub(crate) const NAME: &str = "IISPH";

/// Density of air at 20 °C and 1 atm (kg/m³), the default surrounding medium of the drag
/// force (Neder 2024 eq. 6's `ρ_a`).
pub const AIR_DENSITY: f64 = 1.2041;

/// Default half-angle (degrees) of the occlusion cone of the drag force (Neder 2024 §5.6 "a
/// cone … defined by the direction of the relative velocity difference and a set angle"; the
/// thesis gives no value, 30° is our choice).
pub const DEFAULT_DRAG_CONE_HALF_ANGLE_DEG: f64 = 30.0;

/// Default cap of the friction-stress iterations per time step.
pub const DEFAULT_FRICTION_MAX_ITERATIONS: usize = 20;

/// Default tolerance of the friction solve: mean strain per time step of the unyielded
/// particles (dimensionless).
pub const DEFAULT_FRICTION_TOLERANCE: f64 = 1e-4;

/// Default relaxation `ω` of the friction-stress Jacobi update, relative to the exact
/// self-coupling `D/2` of a particle's stress with its own strain rate: `s ← s − 2ω D⁻¹ε`.
/// The update is stable only for `ω < 2 / λ_max`, `λ_max` the largest eigenvalue of the
/// strain-from-stress operator relative to its diagonal. On the prototype lattice (a full
/// simple cubic lattice, cubic spline, `h = 2 s`) the operator is a convolution, its symbol
/// at wave vector `k` is `c (2/3) |g(k)|²` for the deviatoric mode along `g` (and
/// `c |g(k)|²/2` for the shear modes) with `g(k) = Σ_r sin(k·r) ∇W(r)`, against the diagonal
/// `c Σ_r |∇W(r)|² / 3`; its maximum, at `k ≈ 0.33 π/s (1, 1, 1)`, is `λ_max = 5.64`, so
/// `ω < 0.355` (the friction module's docs and `tests::friction_symbol_bound` give the
/// derivation and check it). 0.35 is just inside; the thesis's factor 2 in eq. 9 (`ω = ½`)
/// is outside, and there the iteration amplifies those modes until the yield cone stops
/// them.
pub const DEFAULT_FRICTION_RELAXATION: f64 = 0.35;

/// Default [`IisphParams::min_iterations`]: Ihmsen et al. 2014 §4 ("at least two
/// iterations"); Neder 2024 Alg. 1 line 7.
pub const DEFAULT_MIN_ITERATIONS: usize = 2;

/// Default [`IisphParams::max_iterations`]: SPlisHSPlasH's default cap.
pub const DEFAULT_MAX_ITERATIONS: usize = 100;

/// Most relaxed-Jacobi pressure iterations per time step ([`IisphParams::max_iterations`],
/// and so [`IisphParams::min_iterations`]) accepted, bounded by what can finish. The count
/// is a cap: a solve stops at the tolerance, after 2–20 iterations at the default 0.1 %
/// (Ihmsen et al. 2014; SPlisHSPlasH's default cap is 100). Studies of the solve converge
/// to far tighter tolerances (the direct-solve comparison: 10⁻⁹ within a cap of 20 000),
/// so the cap is 100 000, and `substeps` × the cap is bounded by
/// [`sph_solver::MAX_ITERATIONS_PER_FRAME`].
pub const MAX_PRESSURE_ITERATIONS: usize = 100_000;

/// Most friction-stress iterations per time step ([`GranularParams::friction_max_iterations`])
/// accepted, bounded by what can finish: the crate's study of the cap went to 400 (the angle
/// of repose no longer changes beyond 50); an iteration is two neighbour passes.
pub const MAX_FRICTION_ITERATIONS: usize = 1000;

/// The cone's match of [`GranularParams::with_friction_angle`] and of scenes that name none:
/// plane strain, the thesis's eq. 14, so that its experiments run as printed.
pub const DEFAULT_CONE_MATCH: ConeMatch = ConeMatch::PlaneStrain;

/// How the Drucker–Prager cone is matched to Mohr–Coulomb (`sph_solver::cone_match`, the
/// vocabulary the granular solvers share; [`GranularParams::cone_match`]).
pub use sph_solver::ConeMatch;

/// The Drucker–Prager coefficient `α` of this solver's cone `‖s‖_F ≤ α p` for friction
/// angle `θ` (degrees) under the match `cone`: what a match means here.
///
/// The cone `√J2 + α_φ I1 ≤ k_c` of the shared vocabulary is, with `p = −I1/3` and
/// `‖s‖_F = √(2 J2)`, the cone `‖s‖_F ≤ 3√2 α_φ p`: `α = 3√2 α_φ`. The two matches of the
/// thesis's experiments are written in closed form (derivation in the crate docs, "The
/// yield cone's matching and the angle of repose"; a slope that flowed and stopped rests
/// at `tan β = α / √2`):
///
/// | match | `α` | slope at rest `β` | θ = 20°, 30°, 40° |
/// | --- | --- | --- | --- |
/// | [`ConeMatch::PlaneStrain`] (the thesis's eq. 14) | `√2 sin θ` | `atan(sin θ)` | 18.9°, 26.6°, 32.7° |
/// | [`ConeMatch::SimpleShear`] | `√2 tan θ` | `θ` | 20°, 30°, 40° |
/// | [`ConeMatch::PlaneStrainAssociated`] (Bui et al. 2008) | `3√2 tan θ/√(9 + 12 tan² θ)` | `atan(3 tan θ/√(9 + 12 tan² θ))` | 18.5°, 25.7°, 31.1° |
pub fn cone_alpha(cone: ConeMatch, friction_angle_deg: f64) -> f64 {
    let t = friction_angle_deg.to_radians();
    let r2 = std::f64::consts::SQRT_2;
    match cone {
        ConeMatch::PlaneStrain => r2 * t.sin(),
        ConeMatch::SimpleShear => r2 * t.tan(),
        other => 3.0 * r2 * other.alpha_phi(friction_angle_deg),
    }
}

/// Parameters of [`crate::Iisph`]. Lengths absolute, in metres; SI units throughout.
///
/// | field | default ([`IisphParams::for_spacing`]) | source |
/// | --- | --- | --- |
/// | `common` | [`CommonParams::for_spacing`] with 8 substeps per 16 ms frame (Δt = 2 ms) | Δt of the SPlisHSPlasH dam-break comparison |
/// | `min_iterations` | 2 | Ihmsen et al. 2014 §4 ("at least two iterations"); Neder 2024 Alg. 1 line 7 |
/// | `max_iterations` | 100 | cap (SPlisHSPlasH's default); hitting it is counted in `StepStats::unconverged_substeps` |
/// | `density_error_tolerance` | 0.001 (0.1 %) | Ihmsen et al. 2014 §5 (`η` = 0.1 % average density error) |
/// | `relaxation` | 0.5 | Ihmsen et al. 2014 eq. 14 / Neder 2024 eq. 20 (`ω = 0.5`) |
/// | `viscosity` | 0 m²/s | kinematic viscosity of an explicit SPH viscosity force (not in the thesis; see the crate docs) |
/// | `granular` | `None` (water) | Neder 2024 §§5.6–5.9 |
/// | `upscaling_factor` | `None` (off) | passive points per particle, Neder 2024 §5.12 |
#[derive(Debug, Clone, PartialEq)]
pub struct IisphParams<R: Real> {
    /// The parameters every solver has.
    pub common: CommonParams<R>,
    /// Fewest relaxed-Jacobi iterations per time step (≥ 1; 2 in the paper).
    pub min_iterations: usize,
    /// Most relaxed-Jacobi iterations per time step (≥ `min_iterations`).
    pub max_iterations: usize,
    /// `η`: the iterations stop once the average predicted compression
    /// `mean_i max(ρ_i^l − ρ0, 0) / ρ0` is below it (relative, > 0).
    pub density_error_tolerance: R,
    /// Relaxation `ω` of the Jacobi update, in (0, 1].
    pub relaxation: R,
    /// Kinematic viscosity `ν` (m²/s, ≥ 0) of the explicit viscosity force; 0 = off.
    pub viscosity: R,
    /// Friction, drag (granular matter); `None` for water.
    pub granular: Option<GranularParams<R>>,
    /// Passive high-resolution points per simulation particle (≥ 1), advected by the SPH
    /// velocity field; `None` = no upscaling.
    pub upscaling_factor: Option<usize>,
}

/// The granular part of [`IisphParams`] (Neder 2024 §§5.6–5.9).
///
/// | field | default ([`GranularParams::with_friction_angle`]) | source |
/// | --- | --- | --- |
/// | `friction_angle_deg` | given | `θ` of eq. 14 (degrees, in [0, 90)) |
/// | `cone_match` | [`ConeMatch::PlaneStrain`] (`α = √2 sin θ`) | eq. 14; [`ConeMatch::SimpleShear`] makes `θ` the angle of repose |
/// | `drag_coefficient` | 0 (off) | `C_D` of eq. 6 (dimensionless) |
/// | `air_velocity` | 0 m/s | `v_a` of eq. 5 (a uniform field) |
/// | `air_density` | 1.2041 kg/m³ ([`AIR_DENSITY`]) | `ρ_a` of eq. 6 |
/// | `drag_cone_half_angle_deg` | 30° ([`DEFAULT_DRAG_CONE_HALF_ANGLE_DEG`]) | the occlusion cone of §5.6 (no value given) |
/// | `friction_max_iterations` | [`DEFAULT_FRICTION_MAX_ITERATIONS`] | cap of the friction-stress solve (our choice; hitting it is counted in `StepStats::unconverged_friction_substeps`) |
/// | `friction_tolerance` | [`DEFAULT_FRICTION_TOLERANCE`] | mean unyielded strain per step at which the friction solve stops (our choice, see the crate docs) |
/// | `friction_relaxation` | [`DEFAULT_FRICTION_RELAXATION`] (0.35) | `ω` of the stress update relative to the exact self-coupling; the stability bound of the prototype lattice (the thesis's eq. 9 implies ½) |
#[derive(Debug, Clone, PartialEq)]
pub struct GranularParams<R: Real> {
    /// Friction angle `θ` (degrees, in [0, 90)): the Drucker–Prager coefficient is
    /// `α = √2 sin θ` or `√2 tan θ`, by [`GranularParams::cone_match`].
    pub friction_angle_deg: R,
    /// How the cone is matched to `θ` (see [`ConeMatch`]).
    pub cone_match: ConeMatch,
    /// Drag coefficient `C_D` (dimensionless, ≥ 0); 0 switches the drag off.
    pub drag_coefficient: R,
    /// Velocity of the surrounding air (m/s), uniform.
    pub air_velocity: Vec3<R>,
    /// Density of the surrounding air `ρ_a` (kg/m³, ≥ 0).
    pub air_density: R,
    /// Half-angle of the occlusion cone (degrees, in (0, 90]).
    pub drag_cone_half_angle_deg: R,
    /// Most iterations of the friction-stress solve per time step (≥ 1).
    pub friction_max_iterations: usize,
    /// The friction solve stops once the mean strain per time step of the particles inside
    /// the yield surface, `Σ_i ‖dev ε_i‖ Δt / N` (dimensionless), is at most this (> 0).
    pub friction_tolerance: R,
    /// Relaxation `ω` (in (0, 1]) of the stress update `s ← Y(dev(s − 2ω D⁻¹ ε))`, relative
    /// to the exact self-coupling `D/2` (Neder 2024's eq. 9, with its factor 2, is `ω = ½`);
    /// see [`DEFAULT_FRICTION_RELAXATION`] for the stability bound `ω < 0.355`.
    pub friction_relaxation: R,
}

impl<R: Real> GranularParams<R> {
    /// Friction angle `θ` (degrees), no drag, still air.
    pub fn with_friction_angle(friction_angle_deg: R) -> Self {
        Self {
            friction_angle_deg,
            cone_match: DEFAULT_CONE_MATCH,
            drag_coefficient: R::zero(),
            air_velocity: Vec3::zeros(),
            air_density: R::of_f64(AIR_DENSITY),
            drag_cone_half_angle_deg: R::of_f64(DEFAULT_DRAG_CONE_HALF_ANGLE_DEG),
            friction_max_iterations: DEFAULT_FRICTION_MAX_ITERATIONS,
            friction_tolerance: R::of_f64(DEFAULT_FRICTION_TOLERANCE),
            friction_relaxation: R::of_f64(DEFAULT_FRICTION_RELAXATION),
        }
    }

    /// The same with the cone matched by `cone_match`.
    pub fn with_cone_match(self, cone_match: ConeMatch) -> Self {
        Self { cone_match, ..self }
    }

    /// The Drucker–Prager friction coefficient `α` ([`cone_alpha`]): `√2 sin θ`
    /// (Neder 2024 eq. 14) or `√2 tan θ`.
    pub fn alpha(&self) -> R {
        R::of_f64(cone_alpha(
            self.cone_match,
            self.friction_angle_deg.as_f64(),
        ))
    }

    /// The angle (degrees) at which a slope of this material comes to rest
    /// ([`ConeMatch::predicted_repose_angle_deg`]).
    pub fn predicted_repose_angle_deg(&self) -> f64 {
        self.cone_match
            .predicted_repose_angle_deg(self.friction_angle_deg.as_f64())
    }

    fn validate(&self, common: &CommonParams<R>) -> Result<(), SolverError> {
        let th = self.friction_angle_deg;
        if !(th.is_finite_value() && th >= R::zero() && th < R::of_f64(90.0)) {
            return Err(invalid(
                "friction_angle_deg",
                th.as_f64(),
                "must be in [0, 90) degrees",
            ));
        }
        non_negative("drag_coefficient", self.drag_coefficient)?;
        non_negative("air_density", self.air_density)?;
        if let Some(a) = (0..3).find(|&a| !self.air_velocity[a].is_finite_value()) {
            return Err(invalid(
                "air_velocity",
                self.air_velocity[a].as_f64(),
                "has a component that is not finite",
            ));
        }
        let cone = self.drag_cone_half_angle_deg;
        if !(cone.is_finite_value() && cone > R::zero() && cone <= R::of_f64(90.0)) {
            return Err(invalid(
                "drag_cone_half_angle_deg",
                cone.as_f64(),
                "must be in (0, 90] degrees",
            ));
        }
        common.check_iteration_count(
            NAME,
            "friction_max_iterations",
            self.friction_max_iterations,
            MAX_FRICTION_ITERATIONS,
            "must be at most 1000 per time step (MAX_FRICTION_ITERATIONS: a run must be able to finish)",
        )?;
        let tol = self.friction_tolerance;
        if !(tol.is_finite_value() && tol > R::zero()) {
            return Err(invalid(
                "friction_tolerance",
                tol.as_f64(),
                "must be finite and > 0",
            ));
        }
        let w = self.friction_relaxation;
        if !(w.is_finite_value() && w > R::zero() && w <= R::one()) {
            return Err(invalid(
                "friction_relaxation",
                w.as_f64(),
                "must be in (0, 1]",
            ));
        }
        Ok(())
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> SolverError {
    SolverError::invalid(NAME, name, value, reason)
}

fn non_negative<R: Real>(name: &'static str, v: R) -> Result<(), SolverError> {
    SolverError::non_negative(NAME, name, v)
}

impl<R: Real> Default for IisphParams<R> {
    /// [`IisphParams::for_spacing`] with `s = 0.025 m`.
    fn default() -> Self {
        Self::for_spacing(R::of_f64(0.025))
    }
}

impl<R: Real> IisphParams<R> {
    /// The water defaults of the table above for particle spacing `s` (m). Not validated.
    pub fn for_spacing(s: R) -> Self {
        let mut common = CommonParams::for_spacing(s);
        common.substeps = 8;
        Self {
            common,
            min_iterations: DEFAULT_MIN_ITERATIONS,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            density_error_tolerance: R::of_f64(0.001),
            relaxation: R::of_f64(0.5),
            viscosity: R::zero(),
            granular: None,
            upscaling_factor: None,
        }
    }

    /// The same with granular friction at angle `θ` (degrees) and no drag.
    pub fn granular(s: R, friction_angle_deg: R) -> Self {
        Self {
            granular: Some(GranularParams::with_friction_angle(friction_angle_deg)),
            ..Self::for_spacing(s)
        }
    }

    /// Length of one time step, `Δt = dt / substeps` (s).
    pub fn substep_dt(&self) -> R {
        self.common.substep_dt()
    }

    /// Checks every field; the error ([`SolverError::InvalidParameter`]) names the first
    /// invalid one.
    pub fn validate(&self) -> Result<(), SolverError> {
        self.common.validate(NAME)?;
        if self.min_iterations == 0 {
            return Err(invalid("min_iterations", 0.0, "must be >= 1"));
        }
        if self.min_iterations > MAX_PRESSURE_ITERATIONS {
            return Err(invalid(
                "min_iterations",
                self.min_iterations as f64,
                "must be at most 100000 per time step (MAX_PRESSURE_ITERATIONS: a run must be able to finish)",
            ));
        }
        if self.max_iterations < self.min_iterations {
            return Err(invalid(
                "max_iterations",
                self.max_iterations as f64,
                "must be >= min_iterations",
            ));
        }
        self.common.check_iteration_count(
            NAME,
            "max_iterations",
            self.max_iterations,
            MAX_PRESSURE_ITERATIONS,
            "must be at most 100000 per time step (MAX_PRESSURE_ITERATIONS: a run must be able to finish)",
        )?;
        let eta = self.density_error_tolerance;
        if !(eta.is_finite_value() && eta > R::zero()) {
            return Err(invalid(
                "density_error_tolerance",
                eta.as_f64(),
                "must be finite and > 0",
            ));
        }
        let w = self.relaxation;
        if !(w.is_finite_value() && w > R::zero() && w <= R::one()) {
            return Err(invalid("relaxation", w.as_f64(), "must be in (0, 1]"));
        }
        non_negative("viscosity", self.viscosity)?;
        if let Some(g) = &self.granular {
            g.validate(&self.common)?;
        }
        if self.upscaling_factor == Some(0) {
            return Err(invalid(
                "upscaling_factor",
                0.0,
                "must be >= 1 passive point per particle (none given = no upscaling)",
            ));
        }
        if self.upscaling_factor.is_some_and(|k| k > 4096) {
            return Err(invalid(
                "upscaling_factor",
                self.upscaling_factor.unwrap_or(0) as f64,
                "must be at most 4096 passive points per particle",
            ));
        }
        Ok(())
    }
}

sph_solver::solver_parameters!(IisphParams, NAME);

#[cfg(test)]
mod tests {
    use super::{cone_alpha, ConeMatch, GranularParams};

    /// `α` of both matches against values computed by hand (sin 30° = 1/2, tan 45° = 1,
    /// tan 30° = 1/√3) and against the closed forms at 20° and 40°.
    #[test]
    fn cone_alpha_values() {
        let r2 = std::f64::consts::SQRT_2;
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(cone_alpha(ConeMatch::PlaneStrain, 30.0), r2 / 2.0));
        assert!(close(
            cone_alpha(ConeMatch::SimpleShear, 30.0),
            r2 / 3f64.sqrt()
        ));
        assert!(close(cone_alpha(ConeMatch::SimpleShear, 45.0), r2));
        assert!(close(cone_alpha(ConeMatch::PlaneStrain, 0.0), 0.0));
        assert!(close(cone_alpha(ConeMatch::SimpleShear, 0.0), 0.0));
        for t in [20.0f64, 40.0] {
            assert!(close(
                cone_alpha(ConeMatch::PlaneStrain, t),
                r2 * t.to_radians().sin()
            ));
            assert!(close(
                cone_alpha(ConeMatch::SimpleShear, t),
                r2 * t.to_radians().tan()
            ));
            // The simple-shear cone is the wider one for every θ in (0, 90).
            assert!(cone_alpha(ConeMatch::SimpleShear, t) > cone_alpha(ConeMatch::PlaneStrain, t));
            // Every match is the shared vocabulary's cone: `α = 3√2 α_φ`.
            for m in ConeMatch::ALL {
                assert!(close(cone_alpha(m, t), 3.0 * r2 * m.alpha_phi(t)), "{m:?}");
            }
        }
    }

    /// The slope each match holds: `atan(sin θ)` = 18.9°, 26.6°, 32.7° (plane strain)
    /// and `θ` (simple shear).
    #[test]
    fn predicted_repose_angles() {
        let ps: Vec<f64> = [20.0, 30.0, 40.0]
            .iter()
            .map(|&t| ConeMatch::PlaneStrain.predicted_repose_angle_deg(t))
            .collect();
        for (got, want) in ps.iter().zip([18.88, 26.57, 32.73]) {
            assert!((got - want).abs() < 0.01, "{got} vs {want}");
        }
        for t in [0.0, 20.0, 30.0, 40.0, 89.0] {
            let b = ConeMatch::SimpleShear.predicted_repose_angle_deg(t);
            assert!((b - t).abs() < 1e-9, "{b} vs {t}");
        }
    }

    /// The default is the thesis's match, and `alpha()` follows the field.
    #[test]
    fn params_follow_the_match() {
        let g = GranularParams::<f64>::with_friction_angle(30.0);
        assert_eq!(g.cone_match, ConeMatch::PlaneStrain);
        assert!((g.alpha() - std::f64::consts::SQRT_2 * 0.5).abs() < 1e-12);
        let g = g.with_cone_match(ConeMatch::SimpleShear);
        assert!((g.alpha() - cone_alpha(ConeMatch::SimpleShear, 30.0)).abs() < 1e-12);
        assert!((g.predicted_repose_angle_deg() - 30.0).abs() < 1e-9);
    }
}
