//! The kernels and constants of the per-particle loops, built once from the parameters.

use sph_core::{Real, Vec3};
use sph_kernels::{CubicSpline, Kernel, KernelKind};
use sph_solver::SolverError;

use crate::granular::prototype_friction_coefficient;
use crate::params::{IisphParams, NAME};

/// The density kernel (and the kernel of every gradient) of the solver: the cubic spline
/// (Neder 2024 §2; Ihmsen et al. 2014). A volume-map boundary must have been integrated with
/// it.
pub const IISPH_KERNEL: KernelKind = KernelKind::CubicSpline;

/// Kernels and constants of the per-particle loops.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Consts<R: Real> {
    pub kernel: CubicSpline<R>,
    /// `W(0)`: the self term of the density sum.
    pub w0: R,
    pub rho0: R,
    pub dt: R,
    pub h: R,
    /// `2ω/d`: the step of the stress update `s ← s − (2ω/d) ε` for the prototype friction
    /// coefficient `d` and the relaxation `ω` (granular only, else 0).
    pub stress_step: R,
    /// Drucker–Prager `α = √2 sin θ` (0 for water).
    pub alpha: R,
    /// Coulomb coefficient `tan θ` of the contact response (0 for water).
    pub wall_friction: R,
    /// Drag: `C_D`, `ρ_a`, cross-section `π r²`, `cos` of the cone half-angle, air velocity.
    pub drag_coefficient: R,
    pub air_density: R,
    pub area: R,
    pub cos_cone: R,
    pub air_velocity: Vec3<R>,
    /// `10 ν` of the viscosity force (`2 (d + 2) ν`, `d = 3`).
    pub visc: R,
    pub granular: bool,
    pub drag: bool,
}

impl<R: Real> Consts<R> {
    pub(crate) fn new(p: &IisphParams<R>) -> Result<Self, SolverError> {
        let h = p.common.support_radius;
        let kernel = CubicSpline::new(h)?;
        let dt = p.substep_dt();
        let rho0 = p.common.rest_density;
        let g = p.granular.as_ref();
        let stress_step = match g {
            Some(g) => {
                let d =
                    prototype_friction_coefficient(&kernel, p.common.particle_spacing, rho0, dt)
                        .ok_or(SolverError::InvalidParameter {
                            solver: NAME,
                            name: "support_radius",
                            value: h.as_f64(),
                            reason: "no finite prototype friction coefficient D (eq. 9)",
                        })?;
                R::of_f64(2.0) * g.friction_relaxation / d
            }
            None => R::zero(),
        };
        let r = p.common.particle_radius();
        Ok(Self {
            kernel,
            w0: kernel.value(R::zero()),
            rho0,
            dt,
            h,
            stress_step,
            alpha: g.map_or(R::zero(), |g| g.alpha()),
            wall_friction: g.map_or(R::zero(), |g| {
                R::of_f64(g.friction_angle_deg.as_f64().to_radians().tan())
            }),
            drag_coefficient: g.map_or(R::zero(), |g| g.drag_coefficient),
            air_density: g.map_or(R::zero(), |g| g.air_density),
            area: R::pi() * r * r,
            cos_cone: g.map_or(R::one(), |g| {
                R::of_f64(g.drag_cone_half_angle_deg.as_f64().to_radians().cos())
            }),
            air_velocity: g.map_or(Vec3::zeros(), |g| g.air_velocity),
            visc: R::of_f64(10.0) * p.viscosity,
            granular: g.is_some(),
            drag: g.is_some_and(|g| g.drag_coefficient > R::zero() && g.air_density > R::zero()),
        })
    }
}
