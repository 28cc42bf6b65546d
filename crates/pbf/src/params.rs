//! Solver parameters, with the paper's values where it gives them.

use neighbour_search::Method;
use sph_core::{Real, Vec3};
use sph_kernels::{Kernel, Spiky};

use crate::PbfError;

/// Ratio `h / s` of the support radius to the particle spacing used by
/// [`PbfParams::for_spacing`]: `h = 2 s` (26 neighbours on a simple cubic lattice; the value of
/// the workspace's SPlisHSPlasH anchor scene, `s = 0.025 m`, `h = 0.05 m`). The paper gives no
/// ratio; it notes that with the artificial pressure term a particle does not need the
/// "30–40 neighbours" of the SPH rule of thumb (§4).
pub const DEFAULT_SUPPORT_OVER_SPACING: f64 = 2.0;

/// CFM relaxation used by [`PbfParams::for_spacing`], relative to the constraint-gradient
/// denominator of a particle at rest in a full lattice ([`PbfParams::reference_denominator`]):
/// `ε = 1.0 · D_ref` (597 m⁻² at `s = 0.025 m`, `h = 0.05 m`). The paper gives no value for
/// `ε` (eq. 11); see the crate documentation for why it is this large.
pub const DEFAULT_RELATIVE_CFM: f64 = 1.0;

/// Parameters of [`crate::Pbf`]. Lengths are absolute, in metres; SI units throughout.
///
/// Build them with [`PbfParams::for_spacing`] (or [`Default`], which is `for_spacing(0.025)`),
/// change fields as needed, and let [`crate::Pbf::new`] check them with
/// [`PbfParams::validate`].
///
/// | field | default | source |
/// | --- | --- | --- |
/// | `rest_density` | 1000 kg/m³ | water; the paper works with unit masses and gives no value |
/// | `particle_spacing` | given (0.025 m for `Default`) | scene |
/// | `support_radius` | `2 s` | [`DEFAULT_SUPPORT_OVER_SPACING`]; not given in the paper |
/// | `dt` | 0.016 s | §8, Table 1: "a frame time of 16 ms is used in all cases" |
/// | `substeps` | 4 | Table 1: Dam Break and Bunny Drop, 4 steps/frame |
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
/// | `gravity` | (0, −9.81, 0) m/s² | standard gravity along −y |
/// | `reorder_every` | 10 | not in the paper (locality of the CPU loops) |
/// | `neighbour_method` | [`Method::CellStartGrid`] | §8: "for neighbor finding we use the method of [Green 2008]"; also the workspace's fastest |
#[derive(Debug, Clone, PartialEq)]
pub struct PbfParams<R: Real> {
    /// Rest density `ρ0` (kg/m³), eq. 1.
    pub rest_density: R,
    /// Particle spacing `s` (m) of the fluid's initial lattice: the particle mass is
    /// `ρ0 s³` ([`PbfParams::particle_mass`], used by scenes to fill [`sph_core::ParticleSet`])
    /// and the collision radius is `s / 2` ([`PbfParams::particle_radius`]).
    pub particle_spacing: R,
    /// Support radius `h` (m, absolute) of the Poly6 and Spiky kernels: `W = 0` for `r >= h`.
    /// Must exceed `particle_spacing`.
    pub support_radius: R,
    /// Time advanced by one [`crate::Pbf::step`] call (s): a frame of `substeps` steps of
    /// Algorithm 1, each of `Δt = dt / substeps`.
    pub dt: R,
    /// Steps of Algorithm 1 per [`crate::Pbf::step`] call (≥ 1).
    pub substeps: usize,
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
    /// `ε N × ω` with `ω` in 1/s; ≥ 0, 0 disables it).
    pub vorticity_epsilon: R,
    /// XSPH viscosity `c` of eq. 17 (dimensionless, in [0, 1]; 0 disables it).
    pub xsph_c: R,
    /// External acceleration `f_ext` of Algorithm 1 line 2 (m/s²).
    pub gravity: Vec3<R>,
    /// Reorder the particles by cell (neighbour-search [`neighbour_search::CellSorter`],
    /// lexicographic order) at the start of every `reorder_every`-th [`crate::Pbf::step`]
    /// call, starting with the first; 0 never reorders.
    pub reorder_every: usize,
    /// Neighbour search method (found once per step at the predicted positions).
    pub neighbour_method: Method,
}

impl<R: Real> Default for PbfParams<R> {
    /// [`PbfParams::for_spacing`] with `s = 0.025 m`.
    fn default() -> Self {
        Self::for_spacing(R::of_f64(0.025))
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> PbfError {
    PbfError::InvalidParameter {
        name,
        value,
        reason,
    }
}

fn positive<R: Real>(name: &'static str, v: R) -> Result<(), PbfError> {
    if v.is_finite_value() && v > R::zero() {
        Ok(())
    } else {
        Err(invalid(name, v.as_f64(), "must be finite and > 0"))
    }
}

fn non_negative<R: Real>(name: &'static str, v: R) -> Result<(), PbfError> {
    if v.is_finite_value() && v >= R::zero() {
        Ok(())
    } else {
        Err(invalid(name, v.as_f64(), "must be finite and >= 0"))
    }
}

impl<R: Real> PbfParams<R> {
    /// The defaults of the table above for particle spacing `s` (m): `h = 2 s`, `ε` from the
    /// full-lattice denominator. Not validated here (a bad `s` is reported by
    /// [`PbfParams::validate`]).
    pub fn for_spacing(s: R) -> Self {
        let h = s * R::of_f64(DEFAULT_SUPPORT_OVER_SPACING);
        let mut p = Self {
            rest_density: R::of_f64(1000.0),
            particle_spacing: s,
            support_radius: h,
            dt: R::of_f64(0.016),
            substeps: 4,
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
            gravity: Vec3::new(R::zero(), R::of_f64(-9.81), R::zero()),
            reorder_every: 10,
            neighbour_method: Method::CellStartGrid,
        };
        if let Some(d) = p.reference_denominator() {
            p.cfm_epsilon = d * R::of_f64(DEFAULT_RELATIVE_CFM);
        }
        p
    }

    /// Particle mass `ρ0 s³` (kg) of a fluid sampled on a simple cubic lattice of spacing `s`.
    pub fn particle_mass(&self) -> R {
        let s = self.particle_spacing;
        self.rest_density * s * s * s
    }

    /// Collision radius `s / 2` (m): particles are kept at least this far from every solid.
    pub fn particle_radius(&self) -> R {
        self.particle_spacing * R::of_f64(0.5)
    }

    /// Length of one step of Algorithm 1, `Δt = dt / substeps` (s).
    pub fn substep_dt(&self) -> R {
        self.dt / R::of_f64(self.substeps.max(1) as f64)
    }

    /// The denominator `Σ_k |∇_{p_k} C_i|²` of eq. 9 (m⁻²) for a particle at rest inside a
    /// simple cubic lattice of spacing `s` with masses `ρ0 s³` (eq. 8 with Spiky gradients),
    /// the scale against which `cfm_epsilon` is chosen. `None` if `s` or `h` are invalid.
    /// For `h = 2 s` it is `0.37339 / s²`.
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
        // m / ρ0 = s³.
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
        Some(sum + grad_i.norm_squared())
    }

    /// The unit (m²) in which the dimensionless `s_corr` of eq. 13 is added to `λ_i + λ_j`
    /// in eq. 14: `1 / D_ref` with `D_ref` = [`PbfParams::reference_denominator`], i.e. the
    /// `λ` that corrects a unit density error of a particle in a full neighbourhood (see the
    /// crate documentation). Errors when `s` or `h` are invalid.
    pub fn scorr_unit(&self) -> Result<R, PbfError> {
        match self.reference_denominator() {
            Some(d) if d.is_finite_value() && d > R::zero() && (R::one() / d).is_finite_value() => {
                Ok(R::one() / d)
            }
            _ => Err(invalid(
                "support_radius",
                self.support_radius.as_f64(),
                "no finite reference denominator for this spacing and support radius",
            )),
        }
    }

    /// Checks every field; the error names the first invalid one.
    pub fn validate(&self) -> Result<(), PbfError> {
        positive("rest_density", self.rest_density)?;
        positive("particle_spacing", self.particle_spacing)?;
        positive("support_radius", self.support_radius)?;
        if self.support_radius <= self.particle_spacing {
            return Err(invalid(
                "support_radius",
                self.support_radius.as_f64(),
                "must exceed particle_spacing (no neighbours otherwise)",
            ));
        }
        positive("dt", self.dt)?;
        if self.substeps == 0 {
            return Err(invalid("substeps", 0.0, "must be >= 1"));
        }
        if self.solver_iterations == 0 {
            return Err(invalid("solver_iterations", 0.0, "must be >= 1"));
        }
        if let Some(tol) = self.mean_compression_tolerance {
            if !(tol.is_finite_value() && tol > R::zero()) {
                return Err(invalid(
                    "mean_compression_tolerance",
                    tol.as_f64(),
                    "must be finite and > 0 (or None for a fixed iteration count)",
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
        positive("cfm_epsilon", self.cfm_epsilon)?;
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
        non_negative("vorticity_epsilon", self.vorticity_epsilon)?;
        if !(self.xsph_c.is_finite_value() && self.xsph_c >= R::zero() && self.xsph_c <= R::one()) {
            return Err(invalid("xsph_c", self.xsph_c.as_f64(), "must be in [0, 1]"));
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
        if (self.support_radius / self.particle_spacing).as_f64() > 64.0 {
            return Err(invalid(
                "support_radius",
                self.support_radius.as_f64(),
                "must be at most 64 particle spacings",
            ));
        }
        self.scorr_unit()?;
        Ok(())
    }
}
