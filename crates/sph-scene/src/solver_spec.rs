//! The `[solver]` table as types: [`SolverSpec`], one variant per solver, each holding the
//! settings every solver has ([`SolverCommon`], flattened into the table) and its own; the
//! two IISPH kinds share [`IisphSettings`]. `None` = the solver's default. The values are
//! range-checked by [`Scene::check`](crate::Scene::check), and turned into the solvers'
//! parameters by [`Scene::solver_params`](crate::Scene::solver_params).

use iisph_granular::ConeMatch;
use serde::Deserialize;

/// Which solver a scene is meant for: the tag (`kind`) of the `[solver]` table, and
/// [`SolverSpec::kind`]. Kept next to [`SolverSpec`] so that code can name a solver without
/// its settings (e.g. to run one scene with both solvers, [`SolverSpec::with_kind`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverKind {
    /// Position Based Fluids (Macklin & Müller 2013).
    Pbf,
    /// Predictive-corrective incompressible SPH (Solenthaler & Pajarola 2009).
    Pcisph,
    /// Implicit incompressible SPH (Ihmsen et al. 2014), water.
    Iisph,
    /// IISPH with Drucker–Prager friction, drag and upscaling for granular matter (Neder
    /// 2024).
    Granular,
}

impl SolverKind {
    /// The name used in scene files: `"pbf"`, `"pcisph"`, `"iisph"` or `"granular"`.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Pbf => "pbf",
            SolverKind::Pcisph => "pcisph",
            SolverKind::Iisph => "iisph",
            SolverKind::Granular => "granular",
        }
    }
}

/// Solver settings: the `[solver]` table, one variant per solver, selected by `kind`; a
/// field of another solver is refused (unknown field). Units as in the crate documentation.
///
/// Deserializes as an internally tagged table (`kind = "pbf"` + the [`PbfSpec`] fields). The
/// scene parser reads `kind` first and then the variant from the same table, so that its
/// errors keep the field path and line (see `parse/solver.rs`); both accept the same tables.
///
/// Not `#[non_exhaustive]`: the workspace's matches on it should break when a solver is
/// added.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum SolverSpec {
    /// Position Based Fluids (`kind = "pbf"`).
    Pbf(PbfSpec),
    /// PCISPH (`kind = "pcisph"`).
    Pcisph(PcisphSpec),
    /// IISPH for water (`kind = "iisph"`).
    Iisph(IisphSpec),
    /// IISPH for granular matter (`kind = "granular"`).
    Granular(GranularSpec),
}

/// The settings every solver has (flattened into each variant's table).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct SolverCommon {
    /// Solver steps per frame (≥ 1).
    pub substeps: usize,
    /// Rest density (kg/m³, > 0).
    pub rest_density: Option<f64>,
    /// Support radius over particle spacing (> 1).
    pub support_over_spacing: Option<f64>,
    /// Reorder particles every this many frames (0 = never).
    pub reorder_every: Option<usize>,
}

/// PBF settings (`[solver] kind = "pbf"`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PbfSpec {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: SolverCommon,
    /// Constraint (Jacobi) iterations per step (≥ 1); the maximum with
    /// `mean_compression_tolerance`.
    pub iterations: usize,
    /// CFM relaxation relative to the full-lattice denominator (> 0).
    pub relative_cfm: Option<f64>,
    /// Artificial pressure strength `k` (≥ 0).
    pub scorr_k: Option<f64>,
    /// Artificial pressure exponent `n` (≥ 1).
    pub scorr_n: Option<u32>,
    /// Artificial pressure `|Δq|` as a fraction of `h`, in (0, 1).
    pub scorr_delta_q: Option<f64>,
    /// Vorticity confinement `ε` (m/s, ≥ 0).
    pub vorticity_epsilon: Option<f64>,
    /// XSPH viscosity `c`, in [0, 1].
    pub xsph_c: Option<f64>,
    /// Unilateral density constraint `max(ρ/ρ0 − 1, 0)`.
    pub clamp_negative_constraint: Option<bool>,
    /// Mean compression at which the Jacobi iterations stop (> 0; `iterations` is then the
    /// maximum).
    pub mean_compression_tolerance: Option<f64>,
    /// Fewest iterations per step with `mean_compression_tolerance` (≥ 1, ≤ `iterations`).
    pub min_iterations: Option<usize>,
}

/// PCISPH settings (`[solver] kind = "pcisph"`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PcisphSpec {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: SolverCommon,
    /// Maximum pressure iterations per step (≥ 1).
    pub iterations: usize,
    /// XSPH viscosity `c`, in [0, 1].
    pub xsph_c: Option<f64>,
    /// Clamp negative pressures to zero.
    pub clamp_negative_pressure: Option<bool>,
    /// Relative density error at which the pressure iteration stops (> 0).
    pub density_error_tolerance: Option<f64>,
}

/// The settings both IISPH kinds have, besides [`SolverCommon`] (flattened into their
/// tables); see the `iisph-granular` crate.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct IisphSettings {
    /// Most relaxed-Jacobi iterations per step (≥ `min_iterations`; default
    /// [`DEFAULT_IISPH_MAX_ITERATIONS`]).
    pub max_iterations: Option<usize>,
    /// Fewest iterations per step (≥ 1; default [`DEFAULT_IISPH_MIN_ITERATIONS`]).
    pub min_iterations: Option<usize>,
    /// Average relative density error at which the iterations stop (> 0; default 0.001).
    pub density_error_tolerance: Option<f64>,
    /// Jacobi relaxation `ω`, in (0, 1] (default 0.5).
    pub relaxation: Option<f64>,
    /// Kinematic viscosity `ν` (m²/s, ≥ 0; default 0) of the explicit SPH viscosity force.
    pub viscosity: Option<f64>,
}

/// IISPH settings for water (`[solver] kind = "iisph"`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IisphSpec {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: SolverCommon,
    /// The IISPH settings.
    #[serde(flatten)]
    pub iisph: IisphSettings,
}

/// IISPH settings for granular matter (`[solver] kind = "granular"`): those of
/// [`IisphSpec`] plus friction, drag and upscaling.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularSpec {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: SolverCommon,
    /// The IISPH settings.
    #[serde(flatten)]
    pub iisph: IisphSettings,
    /// Friction angle `θ` (degrees, in [0, 90); required): Drucker–Prager `α = √2 sin θ`
    /// or `√2 tan θ`, by `cone_match`.
    pub friction_angle_deg: f64,
    /// How the yield cone is matched to `θ`: `"plane-strain"` (`α = √2 sin θ`, the thesis's
    /// eq. 14; the default) or `"simple-shear"` (`α = √2 tan θ`: `θ` is then the angle of
    /// repose). See [`ConeMatch`].
    pub cone_match: Option<ConeMatch>,
    /// Drag coefficient `C_D` (≥ 0; default 0 = no drag).
    pub drag_coefficient: Option<f64>,
    /// Uniform air velocity (m/s; default 0).
    pub air_velocity: Option<[f64; 3]>,
    /// Passive high-resolution points per simulation particle (≥ 1; absent = no upscaling).
    pub upscaling_factor: Option<usize>,
    /// Most friction-stress iterations per step (≥ 1; default 20).
    pub friction_max_iterations: Option<usize>,
    /// Mean unyielded strain per step at which the friction iterations stop (> 0; default
    /// 1e-4).
    pub friction_tolerance: Option<f64>,
    /// Relaxation `ω` of the friction-stress update, relative to the exact self-coupling
    /// (in (0, 1]; default 0.35, the update's stability bound on the prototype lattice; the
    /// thesis's eq. 9 implies ½, which lies outside it: see the `iisph-granular` docs).
    pub friction_relaxation: Option<f64>,
}

/// Default `max_iterations` of the IISPH kinds (SPlisHSPlasH's default cap).
pub const DEFAULT_IISPH_MAX_ITERATIONS: usize = 100;

/// Default `min_iterations` of the IISPH kinds (Ihmsen et al. 2014: at least two).
pub const DEFAULT_IISPH_MIN_ITERATIONS: usize = 2;

impl SolverSpec {
    /// Which solver.
    pub fn kind(&self) -> SolverKind {
        match self {
            SolverSpec::Pbf(_) => SolverKind::Pbf,
            SolverSpec::Pcisph(_) => SolverKind::Pcisph,
            SolverSpec::Iisph(_) => SolverKind::Iisph,
            SolverSpec::Granular(_) => SolverKind::Granular,
        }
    }

    /// The solver's name in scene files (`"pbf"`, …).
    pub fn kind_name(&self) -> &'static str {
        self.kind().name()
    }

    /// The settings every solver has.
    pub fn common(&self) -> &SolverCommon {
        match self {
            SolverSpec::Pbf(s) => &s.common,
            SolverSpec::Pcisph(s) => &s.common,
            SolverSpec::Iisph(s) => &s.common,
            SolverSpec::Granular(s) => &s.common,
        }
    }

    /// The settings every solver has, to edit (check the scene again after, with
    /// [`Scene::check`](crate::Scene::check)).
    pub fn common_mut(&mut self) -> &mut SolverCommon {
        match self {
            SolverSpec::Pbf(s) => &mut s.common,
            SolverSpec::Pcisph(s) => &mut s.common,
            SolverSpec::Iisph(s) => &mut s.common,
            SolverSpec::Granular(s) => &mut s.common,
        }
    }

    /// The IISPH settings of the two IISPH kinds.
    pub fn iisph(&self) -> Option<&IisphSettings> {
        match self {
            SolverSpec::Iisph(s) => Some(&s.iisph),
            SolverSpec::Granular(s) => Some(&s.iisph),
            _ => None,
        }
    }

    /// Solver steps per frame.
    pub fn substeps(&self) -> usize {
        self.common().substeps
    }

    /// PBF: constraint iterations per step; PCISPH: maximum pressure iterations per step;
    /// IISPH and granular: `max_iterations` (default [`DEFAULT_IISPH_MAX_ITERATIONS`]).
    pub fn iterations(&self) -> usize {
        match self {
            SolverSpec::Pbf(s) => s.iterations,
            SolverSpec::Pcisph(s) => s.iterations,
            SolverSpec::Iisph(IisphSpec { iisph, .. })
            | SolverSpec::Granular(GranularSpec { iisph, .. }) => {
                iisph.max_iterations.unwrap_or(DEFAULT_IISPH_MAX_ITERATIONS)
            }
        }
    }

    /// Sets the iterations per step (`iterations`, or `max_iterations` of the IISPH kinds);
    /// not range-checked ([`Scene::check`](crate::Scene::check) does).
    pub fn set_iterations(&mut self, n: usize) {
        match self {
            SolverSpec::Pbf(s) => s.iterations = n,
            SolverSpec::Pcisph(s) => s.iterations = n,
            SolverSpec::Iisph(IisphSpec { iisph, .. })
            | SolverSpec::Granular(GranularSpec { iisph, .. }) => iisph.max_iterations = Some(n),
        }
    }

    /// These settings for solver `kind`: a copy when `kind` is this solver's; otherwise the
    /// settings every solver has ([`SolverCommon`]) carried over, with the iteration count and
    /// XSPH `c` between PBF and PCISPH and the [`IisphSettings`] between `iisph` and
    /// `granular`, and the rest left to the other solver's defaults (a `granular` made from
    /// another kind gets `friction_angle_deg = 0`, i.e. no friction).
    pub fn with_kind(&self, kind: SolverKind) -> SolverSpec {
        if self.kind() == kind {
            return self.clone();
        }
        let common = self.common().clone();
        let xsph_c = match self {
            SolverSpec::Pbf(s) => s.xsph_c,
            SolverSpec::Pcisph(s) => s.xsph_c,
            _ => None,
        };
        let iisph = self.iisph().cloned().unwrap_or_default();
        match kind {
            SolverKind::Pbf => SolverSpec::Pbf(PbfSpec {
                common,
                iterations: self.iterations(),
                relative_cfm: None,
                scorr_k: None,
                scorr_n: None,
                scorr_delta_q: None,
                vorticity_epsilon: None,
                xsph_c,
                clamp_negative_constraint: None,
                mean_compression_tolerance: None,
                min_iterations: None,
            }),
            SolverKind::Pcisph => SolverSpec::Pcisph(PcisphSpec {
                common,
                iterations: self.iterations(),
                xsph_c,
                clamp_negative_pressure: None,
                density_error_tolerance: None,
            }),
            SolverKind::Iisph => SolverSpec::Iisph(IisphSpec { common, iisph }),
            SolverKind::Granular => SolverSpec::Granular(GranularSpec {
                common,
                iisph,
                friction_angle_deg: 0.0,
                cone_match: None,
                drag_coefficient: None,
                air_velocity: None,
                upscaling_factor: None,
                friction_max_iterations: None,
                friction_tolerance: None,
                friction_relaxation: None,
            }),
        }
    }
}
