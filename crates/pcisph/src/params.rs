//! Parameters of the PCISPH solver.

use sph_core::Real;
use sph_solver::{CommonParams, SolverError};

/// Name of the solver in errors and reports.
pub(crate) const NAME: &str = "PCISPH";

/// Most prediction-correction iterations per time step ([`PcisphParams::pressure_iterations`])
/// accepted, bounded by what can finish: Macklin & Müller (2013, §8) run 4, SPlisHSPlasH
/// caps its PCISPH at 100; an iteration is two neighbour passes, so beyond 1000 a frame takes
/// minutes while the density error no longer changes.
pub const MAX_PRESSURE_ITERATIONS: usize = 1000;

/// Parameters of [`crate::Pcisph`]. Lengths are absolute, in metres; SI units throughout.
///
/// Build them with [`PcisphParams::for_spacing`] (or [`Default`], `for_spacing(0.025)`),
/// change fields as needed, and let [`crate::Pcisph::new`] check them with
/// [`PcisphParams::validate`].
///
/// | field | default | source |
/// | --- | --- | --- |
/// | `common.rest_density` | 1000 kg/m³ | water |
/// | `common.particle_spacing` | given (0.025 m for `Default`) | scene; also the prototype lattice of `δ` (S&P09 eq. 8) |
/// | `common.support_radius` | `2 s` | as PBF ([`sph_solver::DEFAULT_SUPPORT_OVER_SPACING`]), so both solvers see the same neighbourhoods |
/// | `common.dt` | 0.016 s | Macklin & Müller §8: a frame of 16 ms |
/// | `common.substeps` | 10 | Macklin & Müller §8: PCISPH "with 10 sub-steps" (Δt = 1.6 ms; "not stable with less than 10") |
/// | `common.gravity` | (0, −9.81, 0) m/s² | standard gravity along −y |
/// | `common.reorder_every` | 10 | locality of the CPU loops |
/// | `common.neighbour_method` | `Method::CellStartGrid` | as PBF |
/// | `pressure_iterations` | 4 | Macklin & Müller §8: "4 pressure iterations" |
/// | `density_error_tolerance` | `None` (no early stop) | S&P09's `η` (relative, e.g. 0.01 = 1 %), on the maximum compression |
/// | `clamp_negative_pressure` | `true` | SPlisHSPlasH's clamping of the density error to ≥ 0; S&P09 do not clamp (`false`) |
/// | `xsph_c` | 0.05 ([`DEFAULT_PCISPH_XSPH`]) | PBF's XSPH (Macklin & Müller eq. 17) standing in for S&P09's viscosity force; 0.01 (PBF's value) leaves a fluid at rest boiling (see the crate docs) |
#[derive(Debug, Clone, PartialEq)]
pub struct PcisphParams<R: Real> {
    /// The parameters every solver has (see the table).
    pub common: CommonParams<R>,
    /// Pressure (prediction-correction) iterations per time step (≥ 1); the maximum when
    /// `density_error_tolerance` is set.
    pub pressure_iterations: usize,
    /// Early stop: `Some(η)` ends a time step's iterations after the first one whose maximum
    /// predicted relative compression `max_i max(ρ*_i/ρ0 − 1, 0)` is at most `η`
    /// (dimensionless, e.g. 0.01 = 1 %; finite and > 0). `None`: always
    /// `pressure_iterations`.
    pub density_error_tolerance: Option<R>,
    /// Clamp the predicted density error to `≥ 0` before the pressure update (no negative
    /// pressures; SPlisHSPlasH). `false` is S&P09.
    pub clamp_negative_pressure: bool,
    /// XSPH viscosity `c` (dimensionless, in [0, 1]; 0 disables it).
    pub xsph_c: R,
}

/// Default XSPH `c` of PCISPH: the damping S&P09's viscosity force supplies. Measured on a
/// 20 × 32 × 20 block at rest in a closed tank twice its height (volume-map walls, 10
/// substeps × 4 iterations per 16 ms frame, `examples/rest_probe.rs`), the kinetic energy
/// per particle after 2 s is 1.3·10⁻² `m g H` with `c = 0.01`, 3.7·10⁻⁵ with `c = 0.05` and
/// 1.0·10⁻⁵ with `c = 0.1`.
pub const DEFAULT_PCISPH_XSPH: f64 = 0.05;

impl<R: Real> Default for PcisphParams<R> {
    /// [`PcisphParams::for_spacing`] with `s = 0.025 m`.
    fn default() -> Self {
        Self::for_spacing(R::of_f64(0.025))
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> SolverError {
    SolverError::invalid(NAME, name, value, reason)
}

impl<R: Real> PcisphParams<R> {
    /// The defaults of the table above for particle spacing `s` (m). Not validated here.
    pub fn for_spacing(s: R) -> Self {
        let mut common = CommonParams::for_spacing(s);
        common.substeps = 10;
        Self {
            common,
            pressure_iterations: 4,
            density_error_tolerance: None,
            clamp_negative_pressure: true,
            xsph_c: R::of_f64(DEFAULT_PCISPH_XSPH),
        }
    }

    /// Particle mass `ρ0 s³` (kg) of a fluid sampled on a simple cubic lattice of spacing `s`
    /// (the prototype mass of `δ`).
    pub fn particle_mass(&self) -> R {
        self.common.particle_mass()
    }

    /// Particle radius `s / 2` (m).
    pub fn particle_radius(&self) -> R {
        self.common.particle_radius()
    }

    /// Length of one time step, `Δt = dt / substeps` (s).
    pub fn substep_dt(&self) -> R {
        self.common.substep_dt()
    }

    /// The scaling factor `δ` of S&P09 eq. 8 (m²/s², i.e. Pa per kg/m³ of density error):
    /// `δ = −1 / (β (−Σ_j ∇W_ij · Σ_j ∇W_ij − Σ_j ∇W_ij · ∇W_ij))`, `β = Δt² m² 2/ρ0²`, for a
    /// prototype particle in a full simple cubic lattice of spacing `s` (Spiky gradients,
    /// every lattice point within `h`), `m = ρ0 s³` and `Δt` = [`PcisphParams::substep_dt`].
    /// Errors (naming `support_radius`) when `s`, `h` or the result are not usable.
    pub fn scaling_factor(&self) -> Result<R, SolverError> {
        let h = self.common.support_radius.as_f64();
        // D_ref = (m/ρ0)² (Σ_j ∇W_ij · Σ_j ∇W_ij + Σ_j ∇W_ij · ∇W_ij).
        let d_ref = self.common.reference_denominator().ok_or_else(|| {
            invalid(
                "support_radius",
                h,
                "no prototype lattice for this spacing and support radius",
            )
        })?;
        let (m, rho0, dt) = (
            self.particle_mass(),
            self.common.rest_density,
            self.substep_dt(),
        );
        let vol = m / rho0;
        let sums = d_ref / (vol * vol);
        let two = R::of_f64(2.0);
        let beta = dt * dt * m * m * two / (rho0 * rho0);
        let delta = -R::one() / (beta * -sums);
        if delta.is_finite_value() && delta > R::zero() {
            Ok(delta)
        } else {
            Err(invalid(
                "support_radius",
                h,
                "the scaling factor δ (eq. 8) is not finite and positive",
            ))
        }
    }

    /// Checks every field; the error ([`SolverError::InvalidParameter`]) names the first
    /// invalid one.
    pub fn validate(&self) -> Result<(), SolverError> {
        self.common.validate(NAME)?;
        self.common.check_iteration_count(
            NAME,
            "pressure_iterations",
            self.pressure_iterations,
            MAX_PRESSURE_ITERATIONS,
            "must be at most 1000 per time step (MAX_PRESSURE_ITERATIONS: a run must be able to finish)",
        )?;
        if let Some(t) = self.density_error_tolerance {
            if !(t.is_finite_value() && t > R::zero()) {
                return Err(invalid(
                    "density_error_tolerance",
                    t.as_f64(),
                    "must be finite and > 0 (none given = no early stop)",
                ));
            }
        }
        if !(self.xsph_c.is_finite_value() && self.xsph_c >= R::zero() && self.xsph_c <= R::one()) {
            return Err(invalid("xsph_c", self.xsph_c.as_f64(), "must be in [0, 1]"));
        }
        self.scaling_factor()?;
        Ok(())
    }
}

sph_solver::solver_parameters!(PcisphParams, NAME);
