//! The parameters every particle solver has.

use neighbour_search::Method;
use sph_core::{Real, Vec3};
use sph_kernels::{Kernel, Spiky};

use crate::error::SolverError;

/// Ratio `h / s` of the support radius to the particle spacing used by
/// [`CommonParams::for_spacing`]: `h = 2 s` (26 neighbours on a simple cubic lattice; the
/// value of SPlisHSPlasH's dam-break scene, `s = 0.025 m`, `h = 0.05 m`).
pub const DEFAULT_SUPPORT_OVER_SPACING: f64 = 2.0;

/// Contact distance of volume-map walls as a fraction of the particle radius `s/2`
/// ([`CommonParams::volume_map_contact_distance`]): particles are projected out of a solid
/// only when closer than `s/4` to it (a safety net against tunnelling in fast impacts); at
/// rest the boundary density keeps them near `s/2`. The shipped scenes use it.
pub const VOLUME_MAP_CONTACT_FRACTION: f64 = 0.5;

/// Most substeps per frame a solver accepts, bounded by what can finish: 100 000 substeps
/// took 40 minutes for 3 frames of a quick scene (2026-11), so 10 000 is at most a few
/// minutes per quick frame; a frame of 16 ms in 10 000 substeps is a 1.6 µs step, far below
/// any CFL limit of the workspace's scenes (they use 2–32). A shorter frame (`dt`) gives
/// shorter steps.
pub const MAX_SUBSTEPS: usize = 10_000;

/// Most solver iterations per frame (`substeps` × the maximum iteration count per time
/// step of any iterative solve) a solver accepts, bounded by what can finish: an iteration
/// is one or two neighbour passes (≈ 1–2 ms for a quick scene of 10⁴ particles), so
/// 200 000 is at most a few minutes per quick frame. The shipped scenes use at most
/// 32 × 100; the IISPH direct-solve comparison (`iisph-granular/tests/pressure_system.rs`)
/// caps one solve at 20 000 iterations with 8 substeps.
pub const MAX_ITERATIONS_PER_FRAME: usize = 200_000;

/// Parameters shared by the particle solvers (embedded as `common` in each solver's own
/// parameters). Lengths absolute, in metres; SI units.
///
/// | field | default ([`CommonParams::for_spacing`]) |
/// | --- | --- |
/// | `rest_density` | 1000 kg/m³ (water) |
/// | `particle_spacing` | given |
/// | `support_radius` | `2 s` ([`DEFAULT_SUPPORT_OVER_SPACING`]) |
/// | `dt` | 0.016 s (a frame of 16 ms, Macklin & Müller 2013 §8) |
/// | `substeps` | 1 (each solver sets its own default) |
/// | `gravity` | (0, −9.81, 0) m/s² |
/// | `reorder_every` | 10 |
/// | `neighbour_method` | [`Method::CellStartGrid`] (Green 2008) |
#[derive(Debug, Clone, PartialEq)]
pub struct CommonParams<R: Real> {
    /// Rest density `ρ0` (kg/m³).
    pub rest_density: R,
    /// Particle spacing `s` (m) of the fluid's initial lattice: particle mass `ρ0 s³`
    /// ([`CommonParams::particle_mass`]), particle radius `s / 2`.
    pub particle_spacing: R,
    /// Support radius `h` (m, absolute) of the kernels. Must exceed `particle_spacing`.
    pub support_radius: R,
    /// Time advanced by one `step` call (s): a frame of `substeps` time steps of
    /// `dt / substeps`.
    pub dt: R,
    /// Time steps per `step` call (1 ..= [`MAX_SUBSTEPS`]).
    pub substeps: usize,
    /// External acceleration (m/s²).
    pub gravity: Vec3<R>,
    /// Reorder the particles by cell at the start of every `reorder_every`-th `step` call,
    /// starting with the first; 0 never reorders.
    pub reorder_every: usize,
    /// Neighbour search method.
    pub neighbour_method: Method,
}

impl<R: Real> Default for CommonParams<R> {
    /// [`CommonParams::for_spacing`] with `s = 0.025 m`.
    fn default() -> Self {
        Self::for_spacing(R::of_f64(0.025))
    }
}

impl<R: Real> CommonParams<R> {
    /// The defaults of the table above for particle spacing `s` (m). Not validated here.
    pub fn for_spacing(s: R) -> Self {
        Self {
            rest_density: R::of_f64(1000.0),
            particle_spacing: s,
            support_radius: s * R::of_f64(DEFAULT_SUPPORT_OVER_SPACING),
            dt: R::of_f64(0.016),
            substeps: 1,
            gravity: Vec3::new(R::zero(), R::of_f64(-9.81), R::zero()),
            reorder_every: 10,
            neighbour_method: Method::CellStartGrid,
        }
    }

    /// These parameters in precision `S`, each value rounded to nearest
    /// ([`crate::settings::convert`]: an error names the first finite value that does not
    /// fit, as a parameter of `solver`).
    pub fn try_convert<S: Real>(
        &self,
        solver: &'static str,
    ) -> Result<CommonParams<S>, SolverError> {
        use crate::settings::{convert, convert3};
        Ok(CommonParams {
            rest_density: convert(solver, "rest_density", self.rest_density)?,
            particle_spacing: convert(solver, "particle_spacing", self.particle_spacing)?,
            support_radius: convert(solver, "support_radius", self.support_radius)?,
            dt: convert(solver, "dt", self.dt)?,
            substeps: self.substeps,
            gravity: convert3(solver, "gravity", &self.gravity)?,
            reorder_every: self.reorder_every,
            neighbour_method: self.neighbour_method,
        })
    }

    /// Particle mass `ρ0 s³` (kg) of a fluid sampled on a simple cubic lattice of spacing `s`.
    pub fn particle_mass(&self) -> R {
        let s = self.particle_spacing;
        self.rest_density * s * s * s
    }

    /// Particle radius `s / 2` (m).
    pub fn particle_radius(&self) -> R {
        self.particle_spacing * R::of_f64(0.5)
    }

    /// The recommended contact distance of volume-map walls (m):
    /// [`VOLUME_MAP_CONTACT_FRACTION`] of the particle radius, the `contact_distance` of
    /// [`VolumeMapBoundary::new`](crate::VolumeMapBoundary::new) in the shipped scenes.
    pub fn volume_map_contact_distance(&self) -> R {
        self.particle_radius() * R::of_f64(VOLUME_MAP_CONTACT_FRACTION)
    }

    /// Length of one time step, `Δt = dt / substeps` (s).
    pub fn substep_dt(&self) -> R {
        self.dt / R::of_f64(self.substeps.max(1) as f64)
    }

    /// `D_ref = Σ_k |∇_{x_k} C_i|²` (m⁻²) of a particle at rest inside a full simple cubic
    /// lattice of spacing `s` with masses `ρ0 s³`, for the density constraint
    /// `C_i = ρ_i/ρ0 − 1` with Spiky gradients: `(s³)² (Σ_j |∇W_ij|² + |Σ_j ∇W_ij|²)`. PBF's
    /// CFM scale (Macklin & Müller 2013, eq. 11) and, through `δ = 1 / (2 Δt² D_ref)`,
    /// PCISPH's scaling factor (Solenthaler & Pajarola 2009, eq. 8). `None` if `s` or `h` are
    /// invalid or `h > 64 s`. For `h = 2 s` it is `0.37339 / s²`.
    pub fn reference_denominator(&self) -> Option<R> {
        let (s, h) = (self.particle_spacing, self.support_radius);
        if !(s.is_finite_value() && s > R::zero() && h.is_finite_value() && h > R::zero()) {
            return None;
        }
        let spiky = Spiky::new(h).ok()?;
        let reach = (h / s).as_f64().ceil();
        if reach > 64.0 {
            return None;
        }
        let reach = reach as i64;
        let vol = s * s * s;
        let mut sum = R::zero();
        let mut grad_i = Vec3::<R>::zeros();
        for a in -reach..=reach {
            for b in -reach..=reach {
                for c in -reach..=reach {
                    if (a, b, c) == (0, 0, 0) {
                        continue;
                    }
                    let r = Vec3::new(
                        R::of_f64(a as f64),
                        R::of_f64(b as f64),
                        R::of_f64(c as f64),
                    ) * s;
                    let g = spiky.gradient(&r) * vol;
                    sum += g.norm_squared();
                    grad_i += g;
                }
            }
        }
        let d = sum + grad_i.norm_squared();
        (d.is_finite_value() && d > R::zero()).then_some(d)
    }

    /// Checks an iteration count `count` of field `name` of `solver`: at least 1, at most
    /// `max` per time step (the solver's named maximum; `max_reason` states it, e.g. "must be
    /// at most 1000 per time step (MAX_SOLVER_ITERATIONS)") and at most
    /// [`MAX_ITERATIONS_PER_FRAME`] over the frame's `substeps`.
    pub fn check_iteration_count(
        &self,
        solver: &'static str,
        name: &'static str,
        count: usize,
        max: usize,
        max_reason: &'static str,
    ) -> Result<(), SolverError> {
        let invalid = |reason| SolverError::InvalidParameter {
            solver,
            name,
            value: count as f64,
            reason,
        };
        if count == 0 {
            return Err(invalid("must be >= 1"));
        }
        if count > max {
            return Err(invalid(max_reason));
        }
        if count.saturating_mul(self.substeps) > MAX_ITERATIONS_PER_FRAME {
            return Err(invalid(
                "times substeps must be at most 200000 iterations per frame (MAX_ITERATIONS_PER_FRAME: a run must be able to finish)",
            ));
        }
        Ok(())
    }

    /// Checks every field; the error names `solver` and the first invalid field.
    pub fn validate(&self, solver: &'static str) -> Result<(), SolverError> {
        let invalid = |name, value: f64, reason| SolverError::InvalidParameter {
            solver,
            name,
            value,
            reason,
        };
        let positive = |name, v: R| {
            if v.is_finite_value() && v > R::zero() {
                Ok(())
            } else {
                Err(invalid(name, v.as_f64(), "must be finite and > 0"))
            }
        };
        positive("rest_density", self.rest_density)?;
        positive("particle_spacing", self.particle_spacing)?;
        positive("support_radius", self.support_radius)?;
        if self.support_radius <= self.particle_spacing {
            return Err(invalid(
                "support_radius",
                self.support_radius.as_f64(),
                "must be > 1 particle_spacing (no neighbours otherwise)",
            ));
        }
        if (self.support_radius / self.particle_spacing).as_f64() > 64.0 {
            return Err(invalid(
                "support_radius",
                self.support_radius.as_f64(),
                "must be at most 64 particle spacings",
            ));
        }
        positive("dt", self.dt)?;
        if self.substeps == 0 {
            return Err(invalid("substeps", 0.0, "must be >= 1"));
        }
        if self.substeps > MAX_SUBSTEPS {
            return Err(invalid(
                "substeps",
                self.substeps as f64,
                "must be at most 10000 per frame (MAX_SUBSTEPS: a run must be able to finish)",
            ));
        }
        if let Some(a) = (0..3).find(|&a| !self.gravity[a].is_finite_value()) {
            return Err(invalid(
                "gravity",
                self.gravity[a].as_f64(),
                "components must be finite",
            ));
        }
        let dt_sub = self.substep_dt();
        if !(dt_sub.is_finite_value() && dt_sub > R::zero()) {
            return Err(invalid(
                "substeps",
                self.substeps as f64,
                "dt / substeps underflows to zero",
            ));
        }
        let m = self.particle_mass();
        if !(m.is_finite_value() && m > R::zero()) {
            return Err(invalid(
                "particle_spacing",
                self.particle_spacing.as_f64(),
                "particle mass rest_density * spacing^3 is not representable",
            ));
        }
        if self.reference_denominator().is_none() {
            return Err(invalid(
                "support_radius",
                self.support_radius.as_f64(),
                "no finite reference denominator for this spacing and support radius",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{CommonParams, MAX_ITERATIONS_PER_FRAME, MAX_SUBSTEPS};
    use crate::SolverError;

    fn reason(e: SolverError) -> &'static str {
        match e {
            SolverError::InvalidParameter { reason, .. } => reason,
            other => panic!("{other:?}"),
        }
    }

    /// The bounds are checked and their messages state the constants' values.
    #[test]
    fn counts_are_bounded_and_the_messages_state_the_bounds() {
        let mut p = CommonParams::<f64> {
            substeps: MAX_SUBSTEPS,
            ..Default::default()
        };
        p.validate("test").unwrap();
        p.substeps = MAX_SUBSTEPS + 1;
        let r = reason(p.validate("test").unwrap_err());
        assert!(r.contains(&MAX_SUBSTEPS.to_string()), "{r}");
        p.substeps = 10;
        let max = MAX_ITERATIONS_PER_FRAME / 10;
        p.check_iteration_count("test", "it", max, usize::MAX, "x")
            .unwrap();
        let r = reason(
            p.check_iteration_count("test", "it", max + 1, usize::MAX, "x")
                .unwrap_err(),
        );
        assert!(r.contains(&MAX_ITERATIONS_PER_FRAME.to_string()), "{r}");
        assert_eq!(
            reason(
                p.check_iteration_count("test", "it", 11, 10, "cap")
                    .unwrap_err()
            ),
            "cap"
        );
        assert!(p.check_iteration_count("test", "it", 0, 10, "cap").is_err());
    }
}
