//! Solver parameters, with the paper's values where it gives them.

use sph_core::Real;
use sph_solver::{CommonParams, SolverError};

/// Name of the solver in errors and reports.
pub(crate) const NAME: &str = "PBF";

pub use sph_solver::DEFAULT_SUPPORT_OVER_SPACING;

/// CFM relaxation used by [`PbfParams::for_spacing`], relative to the constraint-gradient
/// denominator of a particle at rest in a full lattice ([`PbfParams::reference_denominator`]):
/// `ε = 1.0 · D_ref` (597 m⁻² at `s = 0.025 m`, `h = 0.05 m`). The paper gives no value for
/// `ε` (eq. 11); see the crate documentation for why it is this large.
pub const DEFAULT_RELATIVE_CFM: f64 = 1.0;

/// Most Jacobi iterations per time step ([`PbfParams::solver_iterations`]) accepted,
/// bounded by what can finish: the paper uses 2–10 (§8, Table 1), SPlisHSPlasH caps its
/// tolerance-driven count at 100; an iteration is two neighbour passes, so beyond 1000 a
/// frame takes minutes while the mean compression no longer changes.
pub const MAX_SOLVER_ITERATIONS: usize = 1000;

/// Parameters of [`crate::Pbf`]. Lengths are absolute, in metres; SI units throughout.
///
/// Build them with [`PbfParams::for_spacing`] (or [`Default`], which is `for_spacing(0.025)`),
/// change fields as needed, and let [`crate::Pbf::new`] check them with
/// [`PbfParams::validate`].
///
/// | field | default | source |
/// | --- | --- | --- |
/// | `common.rest_density` | 1000 kg/m³ | water; the paper works with unit masses and gives no value |
/// | `common.particle_spacing` | given (0.025 m for `Default`) | scene |
/// | `common.support_radius` | `2 s` | [`DEFAULT_SUPPORT_OVER_SPACING`]; not given in the paper |
/// | `common.dt` | 0.016 s | §8, Table 1: "a frame time of 16 ms is used in all cases" |
/// | `common.substeps` | 4 | Table 1: Dam Break and Bunny Drop, 4 steps/frame |
/// | `solver_iterations` | 4 | §8: "typically 2–4" (Table 1: 3 for the dam break, 10 for the bunny drop) |
/// | `mean_compression_tolerance` | `None` (fixed iteration count, as the paper) | not in the paper; SPlisHSPlasH's stopping rule (`maxError`, e.g. 0.001 = 0.1 %) |
/// | `min_solver_iterations` | 2 | SPlisHSPlasH's minimum (`minIterations`); only used with a tolerance |
/// | `cfm_epsilon` | `1.0 ·` [`PbfParams::reference_denominator`] (597 m⁻² at the default spacing) | eq. 11; value not given in the paper, [`DEFAULT_RELATIVE_CFM`] |
/// | `clamp_negative_constraint` | `false` | the paper (bilateral `C_i`, eq. 1); `true` is SPlisHSPlasH's unilateral `max(C_i, 0)` |
/// | `scorr_k` | 0.1 | §4, eq. 13: "k = 0.1" |
/// | `scorr_n` | 4 | §4, eq. 13: "n = 4" |
/// | `scorr_delta_q` | 0.2 (× h) | §4, eq. 13: "\|Δq\| = 0.1h … 0.3h" (middle of the range) |
/// | `vorticity_epsilon` | 0 m/s (off) | eq. 16; optional in the paper, no value given |
/// | `xsph_c` | 0.01 | §5, eq. 17: "typically chosen to be 0.01" |
/// | `common.gravity` | (0, −9.81, 0) m/s² | standard gravity along −y |
/// | `common.reorder_every` | 10 | not in the paper (locality of the CPU loops) |
/// | `common.neighbour_method` | `Method::CellStartGrid` | §8: "for neighbor finding we use the method of [Green 2008]"; also the workspace's fastest |
#[derive(Debug, Clone, PartialEq)]
pub struct PbfParams<R: Real> {
    /// The parameters every solver has: rest density `ρ0` (eq. 1), particle spacing `s`
    /// (mass `ρ0 s³`, particle radius `s / 2`), support radius `h` of the Poly6 and Spiky
    /// kernels, frame length `dt` (one [`crate::Pbf::step`] call: `substeps` steps of
    /// Algorithm 1, each of `Δt = dt / substeps`), gravity (`f_ext` of line 2), reordering
    /// and the neighbour method (found once per step at the predicted positions).
    pub common: CommonParams<R>,
    /// Jacobi iterations of the constraint solve per step (Algorithm 1 `solverIterations`,
    /// ≥ 1); the maximum when `mean_compression_tolerance` is set.
    pub solver_iterations: usize,
    /// Optional stopping rule (not in the paper, which iterates a fixed count; the rule of
    /// SPlisHSPlasH's PBF solver): `Some(η)` ends a step's Jacobi iterations after the first
    /// iteration, from the `min_solver_iterations`-th on, whose mean compression
    /// `(1/N) Σ_i max(ρ_i/ρ0 − 1, 0)`, measured at the positions that iteration starts from
    /// (eq. 2), is at most `η` (dimensionless: 0.001 = 0.1 %; finite and > 0). A step that
    /// reaches `solver_iterations` without it is counted in
    /// [`crate::StepStats::unconverged_substeps`], not an error. `None`: always
    /// `solver_iterations`.
    pub mean_compression_tolerance: Option<R>,
    /// Fewest Jacobi iterations per step when `mean_compression_tolerance` is set (≥ 1 and
    /// ≤ `solver_iterations`); ignored otherwise.
    pub min_solver_iterations: usize,
    /// Constraint force mixing relaxation `ε` of eq. 11, in the units of `Σ_k |∇_{p_k} C_i|²`,
    /// i.e. m⁻² (the masses are kept in the constraint gradients, see the crate docs). Must be
    /// finite and > 0 (it keeps `λ` finite for a particle without neighbours).
    pub cfm_epsilon: R,
    /// Unilateral density constraint: `C_i = max(ρ_i/ρ0 − 1, 0)` instead of eq. 1's
    /// `ρ_i/ρ0 − 1`, so that under-dense particles (free surface, walls) exert no pull (not in
    /// the paper, whose artificial pressure of eq. 13 counters the clustering instead; the
    /// choice of SPlisHSPlasH's PBF, which with it runs at a negligible `ε` = 10⁻⁶ m⁻²).
    ///
    /// With a small `ε`, start the fluid at or below the rest density: SPlisHSPlasH gives its
    /// particles the volume `0.8 (2r)³`. A simple cubic lattice with masses `ρ0 s³` has the
    /// Poly6 density `1.0098 ρ0` at `h = 2 s`; the Jacobi iterations then correct that 1 %
    /// in every particle at once and overshoot, and the block expands (measured on the
    /// 59,319-particle dam break at Δt = 2 ms, `ε` = 10⁻⁶ m⁻²: neighbour pairs −20 % after
    /// one step, mean `ρ/ρ0` 0.84 after 20).
    pub clamp_negative_constraint: bool,
    /// Artificial pressure strength `k` of eq. 13 (dimensionless, ≥ 0; 0 disables `s_corr`).
    /// `s_corr` enters eq. 14 in units of [`PbfParams::scorr_unit`] (see the crate docs).
    pub scorr_k: R,
    /// Artificial pressure exponent `n` of eq. 13 (≥ 1).
    pub scorr_n: u32,
    /// `|Δq|` of eq. 13 as a fraction of `h` (in (0, 1)).
    pub scorr_delta_q: R,
    /// Vorticity confinement strength `ε` of eq. 16 (m/s: the confinement acceleration is
    /// `ε N × ω` with `ω` in 1/s; 0 disables it). A negative value reverses the force
    /// (anti-confinement, which damps vortices): not a physical setting, but the negative
    /// control of the `pbf-vorticity` experiment; scene files accept only `ε ≥ 0`.
    pub vorticity_epsilon: R,
    /// XSPH viscosity `c` of eq. 17 (dimensionless, in [0, 1]; 0 disables it).
    pub xsph_c: R,
}

impl<R: Real> Default for PbfParams<R> {
    /// [`PbfParams::for_spacing`] with `s = 0.025 m`.
    fn default() -> Self {
        Self::for_spacing(R::of_f64(0.025))
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> SolverError {
    SolverError::invalid(NAME, name, value, reason)
}

fn non_negative<R: Real>(name: &'static str, v: R) -> Result<(), SolverError> {
    SolverError::non_negative(NAME, name, v)
}

impl<R: Real> PbfParams<R> {
    /// The defaults of the table above for particle spacing `s` (m): `h = 2 s`, `ε` from the
    /// full-lattice denominator. Not validated here (a bad `s` is reported by
    /// [`PbfParams::validate`]).
    pub fn for_spacing(s: R) -> Self {
        let mut common = CommonParams::for_spacing(s);
        common.substeps = 4;
        let mut p = Self {
            common,
            solver_iterations: 4,
            mean_compression_tolerance: None,
            min_solver_iterations: 2,
            cfm_epsilon: R::one(),
            clamp_negative_constraint: false,
            scorr_k: R::of_f64(0.1),
            scorr_n: 4,
            scorr_delta_q: R::of_f64(0.2),
            vorticity_epsilon: R::zero(),
            xsph_c: R::of_f64(0.01),
        };
        if let Some(d) = p.reference_denominator() {
            p.cfm_epsilon = d * R::of_f64(DEFAULT_RELATIVE_CFM);
        }
        p
    }

    /// Particle mass `ρ0 s³` (kg) of a fluid sampled on a simple cubic lattice of spacing `s`.
    pub fn particle_mass(&self) -> R {
        self.common.particle_mass()
    }

    /// Collision radius `s / 2` (m): particles are kept at least this far from every solid
    /// by the collision boundary.
    pub fn particle_radius(&self) -> R {
        self.common.particle_radius()
    }

    /// Length of one step of Algorithm 1, `Δt = dt / substeps` (s).
    pub fn substep_dt(&self) -> R {
        self.common.substep_dt()
    }

    /// The denominator `Σ_k |∇_{p_k} C_i|²` of eq. 9 (m⁻²) for a particle at rest inside a
    /// simple cubic lattice of spacing `s` with masses `ρ0 s³` (eq. 8 with Spiky gradients),
    /// the scale against which `cfm_epsilon` is chosen
    /// ([`CommonParams::reference_denominator`]). `None` if `s` or `h` are invalid. For
    /// `h = 2 s` it is `0.37339 / s²`.
    pub fn reference_denominator(&self) -> Option<R> {
        self.common.reference_denominator()
    }

    /// The unit (m²) in which the dimensionless `s_corr` of eq. 13 is added to `λ_i + λ_j`
    /// in eq. 14: `1 / D_ref` with `D_ref` = [`PbfParams::reference_denominator`], i.e. the
    /// `λ` that corrects a unit density error of a particle in a full neighbourhood (see the
    /// crate documentation). Errors when `s` or `h` are invalid.
    pub fn scorr_unit(&self) -> Result<R, SolverError> {
        match self.reference_denominator() {
            Some(d) if d.is_finite_value() && d > R::zero() && (R::one() / d).is_finite_value() => {
                Ok(R::one() / d)
            }
            _ => Err(invalid(
                "support_radius",
                self.common.support_radius.as_f64(),
                "no finite reference denominator for this spacing and support radius",
            )),
        }
    }

    /// Checks every field; the error names the first invalid one.
    pub fn validate(&self) -> Result<(), SolverError> {
        self.common.validate(NAME)?;
        self.common.check_iteration_count(
            NAME,
            "solver_iterations",
            self.solver_iterations,
            MAX_SOLVER_ITERATIONS,
            "must be at most 1000 per time step (MAX_SOLVER_ITERATIONS: a run must be able to finish)",
        )?;
        if let Some(tol) = self.mean_compression_tolerance {
            if !(tol.is_finite_value() && tol > R::zero()) {
                return Err(invalid(
                    "mean_compression_tolerance",
                    tol.as_f64(),
                    "must be finite and > 0 (none given = a fixed iteration count)",
                ));
            }
            if self.min_solver_iterations == 0
                || self.min_solver_iterations > self.solver_iterations
            {
                return Err(invalid(
                    "min_solver_iterations",
                    self.min_solver_iterations as f64,
                    "must be >= 1 and <= solver_iterations",
                ));
            }
        }
        if !(self.cfm_epsilon.is_finite_value() && self.cfm_epsilon > R::zero()) {
            return Err(invalid(
                "cfm_epsilon",
                self.cfm_epsilon.as_f64(),
                "must be finite and > 0",
            ));
        }
        non_negative("scorr_k", self.scorr_k)?;
        if self.scorr_n == 0 {
            return Err(invalid("scorr_n", 0.0, "must be >= 1"));
        }
        if !(self.scorr_delta_q.is_finite_value()
            && self.scorr_delta_q > R::zero()
            && self.scorr_delta_q < R::one())
        {
            return Err(invalid(
                "scorr_delta_q",
                self.scorr_delta_q.as_f64(),
                "must be a fraction of h in (0, 1)",
            ));
        }
        if !self.vorticity_epsilon.is_finite_value() {
            return Err(invalid(
                "vorticity_epsilon",
                self.vorticity_epsilon.as_f64(),
                "must be finite",
            ));
        }
        if !(self.xsph_c.is_finite_value() && self.xsph_c >= R::zero() && self.xsph_c <= R::one()) {
            return Err(invalid("xsph_c", self.xsph_c.as_f64(), "must be in [0, 1]"));
        }
        self.scorr_unit()?;
        Ok(())
    }
}

sph_solver::solver_parameters!(PbfParams, NAME);
