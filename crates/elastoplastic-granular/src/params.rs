//! The parameters of [`Elastoplastic`](crate::Elastoplastic), their defaults and bounds.

use sph_core::{Aabb, Real, Vec3};
use sph_solver::scene_boundary::{PeriodicAxis, Pour};
use sph_solver::{CommonParams, Dimensions, SolverError};

use crate::name::NAME;
use crate::stress::{ConeMatch, DruckerPrager};

pub use sph_solver::scene_boundary::{MovingWall, WallModel, MAX_WALL_FRICTION, MAX_WALL_MOTION_S};

/// Largest Young's modulus accepted (Pa): 1 TPa, above any granular material's, so that the
/// explicit step count stays finite.
pub const MAX_YOUNGS_MODULUS_PA: f64 = 1e12;
/// Largest Poisson's ratio accepted: `K = E/(3(1 − 2ν))` diverges at 0.5.
pub const MAX_POISSON_RATIO: f64 = 0.49;
/// Largest friction (and dilatancy) angle accepted (degrees).
pub const MAX_FRICTION_ANGLE_DEG: f64 = 70.0;
/// Largest cohesion accepted (Pa).
pub const MAX_COHESION_PA: f64 = 1e9;
/// Largest fixed velocity scale of the artificial viscosity accepted (m/s).
pub const MAX_VISCOSITY_SPEED_M_S: f64 = 1e6;
/// Largest artificial viscosity coefficient (`α_Π`, `β_Π`) accepted.
pub const MAX_VISCOSITY_COEFFICIENT: f64 = 10.0;
/// Largest artificial stress exponent `n` accepted.
pub const MAX_ARTIFICIAL_STRESS_EXPONENT: f64 = 10.0;
/// Most explicit steps in one [`SubstepScheme::substep`](sph_solver::SubstepScheme) (one
/// `dt / substeps`): a run must be able to finish; raise `common.substeps` instead.
pub const MAX_EXPLICIT_STEPS_PER_SUBSTEP: usize = 100_000;
/// Longest density re-initialisation interval accepted (s).
pub const MAX_DENSITY_REINIT_INTERVAL_S: f64 = 1e6;
/// Most solids with their own wall model.
pub const MAX_WALL_MODELS: usize = 64;
/// Most moving walls ([`ElastoplasticParams::moving_walls`]).
pub const MAX_MOVING_WALLS: usize = 64;
/// Rows of boundary particles standing for a wall
/// ([`ElastoplasticParams::boundary_particle_region`]): three, so that a particle at the
/// wall sees a full support (2.4 spacings) of boundary particles behind it.
pub const BOUNDARY_PARTICLE_ROWS: f64 = 3.0;

/// Young's modulus of the defaults (Pa): Bui et al. (2008)'s aluminium-bar test as
/// SPHinXsys's `test_2d_column_collapse` transcribes it (5.84 MPa).
pub const DEFAULT_YOUNGS_MODULUS_PA: f64 = 5.84e6;
/// Poisson's ratio of the defaults: 0.3, the same source.
pub const DEFAULT_POISSON_RATIO: f64 = 0.3;
/// Rest density of the defaults (kg/m³): 2040, the same source.
pub const DEFAULT_REST_DENSITY: f64 = 2040.0;
/// Monaghan's artificial viscosity `α_Π` of the defaults (Monaghan 1992's solid-body
/// value, the one Bui et al. 2008 use with it).
pub const DEFAULT_VISCOSITY_ALPHA: f64 = 0.1;
/// Monaghan's artificial viscosity `β_Π` of the defaults (0: no quadratic term).
pub const DEFAULT_VISCOSITY_BETA: f64 = 0.0;
/// Artificial stress `ε` of the defaults (Gray, Monaghan & Swift 2001, §5).
pub const DEFAULT_ARTIFICIAL_STRESS_EPSILON: f64 = 0.5;
/// Artificial stress exponent `n` of the defaults (Gray, Monaghan & Swift 2001, §5).
pub const DEFAULT_ARTIFICIAL_STRESS_EXPONENT: f64 = 2.55;
/// CFL number `C` of the defaults, in `Δt ≤ C h / c_p` with `c_p = √((K + 4G/3)/ρ0)` the
/// P-wave speed ([`ElastoplasticParams::p_wave_speed`]), the fastest elastic wave and so the
/// one a Courant condition must hold (Courant, Friedrichs & Lewy 1928).
///
/// Measured, not taken: with the defaults (ν = 0.3, the cubic B-spline, `h = 1.2 s`,
/// symplectic Euler, `α_Π` = 0.1) the quick Bui column (`scenes/granular_column_bui.toml`,
/// `E` = 5.84 MPa, 600 grains) and the quick 30° poured heap
/// (`scenes/granular_repose_poured_30.toml`, `E` = 0.584 MPa, 1,200 grains) are stable and
/// come to rest up to `C_p` = 1.16, the largest value tried (docs/performance.md, "The
/// Courant number from a stability measurement"). The column's deposit drifts with the step
/// (its front 0.8 spacing further at twice the earlier default's step, 1.6 at three times,
/// 1.9 at four; the earlier default itself 1.1 spacings from half its step); the default is
/// the largest value tried at which the front stays within a spacing of the earlier
/// default's, 2.5 times below the largest stable value tried, for the scenes not measured
/// (other Poisson ratios, walls, spacings). Bui et al. (2008) take `C` = 0.1–0.2 with
/// `√(E/ρ0)`, i.e. `C_p` = 0.12–0.23 at ν = 0.3 (`c_p = 1.160 √(E/ρ0)` there); this crate's
/// earlier default was `C` = 0.2 with `√(E/ρ0)` (`C_p` = 0.232).
pub const DEFAULT_CFL_NUMBER: f64 = 0.46;
/// The cone's match of the defaults: Bui et al. (2008)'s plane strain of an associated
/// material.
pub const DEFAULT_CONE_MATCH: ConeMatch = ConeMatch::PlaneStrainAssociated;
/// The density re-initialisation's interval a scene sets to turn it on (s): 2 ms, the
/// interval at which SPHinXsys's granular examples (its `test_2d_column_collapse`, a
/// `DensitySummationComplexFreeSurface` once per advection step of `Dt = 0.002 s`)
/// re-initialise theirs; see [`ElastoplasticParams::density_reinit_interval_s`]. The default
/// is off (0, Bui et al.'s continuity equation alone): on, the poured heaps of the shipped
/// scenes stand at other angles (one pour each at 20 mm: 45.5° instead of 38.6° at 40°,
/// simple-shear match), which only ensembles of pours can judge.
pub const DENSITY_REINIT_INTERVAL_S: f64 = 0.002;
/// Neighbour-list skin of the defaults, as a fraction of the particle spacing.
pub const DEFAULT_SKIN_OVER_SPACING: f64 = 0.3;
/// Support radius of the defaults over the particle spacing, Bui et al. (2008)'s: their
/// cubic B-spline with smoothing length `1.2 s` has support `2.4 s` (the other solvers'
/// default is [`sph_solver::DEFAULT_SUPPORT_OVER_SPACING`], 2).
pub const BUI_SUPPORT_OVER_SPACING: f64 = 2.4;

/// The stress the particles start from (in scene files `initial_stress = "geostatic"` or
/// `"none"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum InitialStress {
    /// Unstressed: the grains settle under gravity from zero stress (the default).
    #[default]
    None,
    /// At rest under gravity in each column (Jaky's `K0 = 1 − sin φ`, the earth pressure at
    /// rest of a normally consolidated granular soil: [`crate::initial`]): `σ_v = −ρ0 |g| d`
    /// along gravity, `K0 σ_v` across it, `d` the depth below the column's top particle plus
    /// half a spacing (columns one spacing wide across gravity), applied to the state the
    /// first frame starts from.
    Geostatic,
}

/// Parameters of [`Elastoplastic`](crate::Elastoplastic).
///
/// | field | default | source |
/// |---|---|---|
/// | `common.rest_density` | 2040 kg/m³ | [`DEFAULT_REST_DENSITY`] |
/// | `common.support_radius` | `2.4 s` | [`BUI_SUPPORT_OVER_SPACING`] |
/// | `common.substeps` | 1 (the explicit steps are sub-cycled inside it) | |
/// | `youngs_modulus` | 5.84 MPa | [`DEFAULT_YOUNGS_MODULUS_PA`] |
/// | `poisson_ratio` | 0.3 | [`DEFAULT_POISSON_RATIO`] |
/// | `friction_angle_deg` | given | |
/// | `cone_match` | plane strain, associated (Bui et al. 2008) | [`ConeMatch`] |
/// | `dilatancy_angle_deg` | 0 (sand, Bui et al. 2008) | |
/// | `cohesion` | 0 Pa (cohesionless) | |
/// | `viscosity_alpha`, `viscosity_beta` | 0.1, 0 | [`DEFAULT_VISCOSITY_ALPHA`] |
/// | `viscosity_speed_m_s` | `None` (the speed of sound) | Monaghan 1992 |
/// | `artificial_stress_epsilon`, `_exponent` | 0.5, 2.55 | Gray et al. 2001 |
/// | `cfl_number` | 0.46 (with the P-wave speed) | [`DEFAULT_CFL_NUMBER`] |
/// | `skin` | `0.3 s` | [`DEFAULT_SKIN_OVER_SPACING`] |
/// | `density_reinit_interval_s` | 0 (off; [`DENSITY_REINIT_INTERVAL_S`] to turn it on) | Bui et al. 2008 |
/// | `default_wall`, `wall_models` | no-slip, none | |
/// | `periodic` | none | |
/// | `boundary_particle_region` | none (walls from the boundary) | |
/// | `moving_walls` | none | |
/// | `pour` | none | |
/// | `initial_stress` | none | |
/// | `dimensions` | 3 | |
#[derive(Debug, Clone, PartialEq)]
pub struct ElastoplasticParams<R: Real> {
    /// The parameters every solver has.
    pub common: CommonParams<R>,
    /// Young's modulus `E` (Pa).
    pub youngs_modulus: R,
    /// Poisson's ratio `ν`.
    pub poisson_ratio: R,
    /// Friction angle `φ` (degrees).
    pub friction_angle_deg: R,
    /// How the friction angle (and dilatancy angle, cohesion) fix the cone: under
    /// [`ConeMatch::SimpleShear`] a heap comes to rest at `friction_angle_deg`.
    pub cone_match: ConeMatch,
    /// Dilatancy angle `ψ` (degrees, `0 ≤ ψ ≤ φ`).
    pub dilatancy_angle_deg: R,
    /// Cohesion `c` (Pa).
    pub cohesion: R,
    /// Monaghan's artificial viscosity, linear coefficient `α_Π`.
    pub viscosity_alpha: R,
    /// Monaghan's artificial viscosity, quadratic coefficient `β_Π`.
    pub viscosity_beta: R,
    /// The velocity scale of the viscosity's linear term (m/s): `None` uses the speed of
    /// sound `c = √(E/ρ0)` (Monaghan 1992); `Some(u)` a fixed scale, so that the damping
    /// does not grow with the modulus (its shear viscosity is of order `α_Π u h / 10`
    /// whatever `E`). See [`ElastoplasticParams::viscosity_speed`].
    pub viscosity_speed_m_s: Option<R>,
    /// Gray et al. (2001)'s artificial stress coefficient `ε` (0 disables it).
    pub artificial_stress_epsilon: R,
    /// Gray et al. (2001)'s artificial stress exponent `n`.
    pub artificial_stress_exponent: R,
    /// CFL number `C` of the explicit step `Δt ≤ C h / c_p`, `h` the smoothing length (half
    /// the support radius) and `c_p` the P-wave speed ([`Self::p_wave_speed`]).
    pub cfl_number: R,
    /// Neighbour-list skin (m): lists are built with radius `support + skin` and kept while
    /// no particle has moved more than `skin / 2` since.
    pub skin: R,
    /// How often the density is re-initialised (s; 0: never, the continuity equation alone
    /// as Bui et al. 2008 publish it). Between re-initialisations the density follows the
    /// continuity equation; at each, every grain takes the kernel summation's density with
    /// the free-surface floor, `ρ_i = max(ρ0 Σ_j m_j W_ij / (m0 σ0), ρ0)` (`σ0 = Σ_k W(|k| s)`
    /// the number density of the full cubic lattice of spacing `s`, `m0 = ρ0 s³`; grains
    /// and boundary particles summed), as SPHinXsys's free-surface density summation does:
    /// a grain that separates from the bulk, or lies at its surface, keeps `ρ0` instead of
    /// the continuity equation's ever lower density, whose `m/ρ` and `σ/ρ²` otherwise grow
    /// without bound and feed energy into the grain's next contact. The re-initialisation
    /// falls on the first of every `max(1, round(interval/Δt))` explicit steps of a substep,
    /// so a run resumed from a checkpoint repeats the uninterrupted one.
    pub density_reinit_interval_s: R,
    /// The wall model of solids past the end of `wall_models`.
    pub default_wall: WallModel,
    /// The wall model of each solid, by index in the boundary's solids.
    pub wall_models: Vec<WallModel>,
    /// Periodic axes (at most one entry per axis; each period at least `support_radius +
    /// skin`, so that one image on each side covers every neighbour).
    pub periodic: Vec<PeriodicAxis<R>>,
    /// `Some(region)`: the solids of the solver's boundary become walls of fixed boundary
    /// particles ([`crate::boundary_particles::sample_solids`]): the nodes of the particle
    /// lattice over `region` (the fluid's lattice: half a spacing from its faces), extended
    /// by [`BOUNDARY_PARTICLE_ROWS`] spacings, that lie inside a solid within that many
    /// spacings of its surface, each with its solid's model (`wall_models`); the solids
    /// then only keep the particles out. `None`: the boundary's volume (if any) is the wall.
    pub boundary_particle_region: Option<Aabb<R>>,
    /// Walls of boundary particles that move for a while and then stand still (a trapdoor
    /// lowered under a bed, a gate lifted), sampled on the same lattice as the solids'
    /// walls (they need `boundary_particle_region`); see [`MovingWall`].
    pub moving_walls: Vec<MovingWall<R>>,
    /// Grains poured during the run, a layer at a time where the heap grows (the funnel
    /// method of forming a heap; see [`Pour`]).
    pub pour: Option<Pour<R>>,
    /// The stress the particles start from.
    pub initial_stress: InitialStress,
    /// Three dimensions, or the plane `z = 0` ([`Dimensions::Two`]: a plane-strain run, as
    /// Bui et al. (2008) compute theirs). In the plane every particle lies at `z = 0`, the
    /// kernel is the cubic B-spline normalised in 2D over the thickness of one spacing
    /// (grains keep the mass `ρ0 s³`), walls are boundary particles in the plane (no volume
    /// maps), gravity lies in the plane and no axis but `x` and `y` is periodic. The velocity
    /// gradient then has no `z` row or column, so the stress update is the plane-strain one
    /// (`ε̇_zz = 0`, `σ_zz` from the constitutive law).
    pub dimensions: Dimensions,
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> SolverError {
    SolverError::invalid(NAME, name, value, reason)
}

fn check_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    reason: &'static str,
) -> Result<(), SolverError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(invalid(name, value, reason))
    }
}

impl<R: Real> ElastoplasticParams<R> {
    /// The defaults of the table above for spacing `s` (m) and friction angle `φ` (degrees).
    /// Not validated here.
    pub fn for_spacing(s: R, friction_angle_deg: R) -> Self {
        let mut common = CommonParams::for_spacing(s);
        common.rest_density = R::of_f64(DEFAULT_REST_DENSITY);
        common.support_radius = s * R::of_f64(BUI_SUPPORT_OVER_SPACING);
        Self {
            common,
            youngs_modulus: R::of_f64(DEFAULT_YOUNGS_MODULUS_PA),
            poisson_ratio: R::of_f64(DEFAULT_POISSON_RATIO),
            friction_angle_deg,
            cone_match: DEFAULT_CONE_MATCH,
            dilatancy_angle_deg: R::zero(),
            cohesion: R::zero(),
            viscosity_alpha: R::of_f64(DEFAULT_VISCOSITY_ALPHA),
            viscosity_beta: R::of_f64(DEFAULT_VISCOSITY_BETA),
            viscosity_speed_m_s: None,
            artificial_stress_epsilon: R::of_f64(DEFAULT_ARTIFICIAL_STRESS_EPSILON),
            artificial_stress_exponent: R::of_f64(DEFAULT_ARTIFICIAL_STRESS_EXPONENT),
            cfl_number: R::of_f64(DEFAULT_CFL_NUMBER),
            skin: s * R::of_f64(DEFAULT_SKIN_OVER_SPACING),
            density_reinit_interval_s: R::zero(),
            default_wall: WallModel::NoSlip,
            wall_models: Vec::new(),
            periodic: Vec::new(),
            boundary_particle_region: None,
            moving_walls: Vec::new(),
            pour: None,
            initial_stress: InitialStress::None,
            dimensions: Dimensions::Three,
        }
    }

    /// The material's moduli and cone.
    pub fn material(&self) -> DruckerPrager<R> {
        DruckerPrager::matched(
            self.youngs_modulus.as_f64(),
            self.poisson_ratio.as_f64(),
            self.friction_angle_deg.as_f64(),
            self.dilatancy_angle_deg.as_f64(),
            self.cohesion.as_f64(),
            self.cone_match,
        )
    }

    /// The wall model of solid `k`.
    pub fn wall_model(&self, k: usize) -> WallModel {
        self.wall_models
            .get(k)
            .copied()
            .unwrap_or(self.default_wall)
    }

    /// The speed of sound `c = √(E/ρ0)` (m/s) of the viscosity and the blow-up bound.
    pub fn sound_speed(&self) -> R {
        (self.youngs_modulus / self.common.rest_density).sqrt()
    }

    /// The P-wave (longitudinal) speed `c_p = √((K + 4G/3)/ρ0) = √(E (1 − ν) / ((1 + ν)
    /// (1 − 2ν) ρ0))` (m/s) of the explicit step (Landau & Lifshitz, *Theory of Elasticity*,
    /// §22): the fastest elastic wave, `1.160 √(E/ρ0)` at ν = 0.3.
    pub fn p_wave_speed(&self) -> R {
        let nu = self.poisson_ratio;
        let one = R::one();
        let stiffening = (one - nu) / ((one + nu) * (one - nu - nu));
        (self.youngs_modulus * stiffening / self.common.rest_density).sqrt()
    }

    /// The velocity scale of the artificial viscosity's linear term (m/s):
    /// [`Self::viscosity_speed_m_s`] if set, else the speed of sound.
    pub fn viscosity_speed(&self) -> R {
        self.viscosity_speed_m_s
            .unwrap_or_else(|| self.sound_speed())
    }

    /// The smoothing length `h` (m): half the support radius (cubic B-spline).
    pub fn smoothing_length(&self) -> R {
        self.common.support_radius * R::of_f64(0.5)
    }

    /// The explicit steps of one substep and their length (s): `n = ⌈(dt/substeps) / (C h/c_p)⌉`
    /// steps of `(dt/substeps)/n`, `c_p` the P-wave speed ([`Self::p_wave_speed`]).
    pub fn explicit_steps(&self) -> (usize, R) {
        let limit = self.cfl_number * self.smoothing_length() / self.p_wave_speed();
        let sub = self.common.substep_dt();
        let n = (sub / limit).as_f64().ceil().max(1.0);
        let n = if n.is_finite() && n < usize::MAX as f64 {
            n as usize
        } else {
            usize::MAX
        };
        (n, sub / R::of_f64(n as f64))
    }

    /// The explicit steps between two density re-initialisations (`None`: never): the
    /// interval over the explicit step, rounded, at least one.
    pub fn density_reinit_steps(&self) -> Option<usize> {
        if self.density_reinit_interval_s <= R::zero() {
            return None;
        }
        let (_, dt) = self.explicit_steps();
        let k = (self.density_reinit_interval_s / dt).as_f64().round();
        Some(if k >= 1.0 && k < usize::MAX as f64 {
            k as usize
        } else {
            1
        })
    }

    /// Checks every field; the error ([`SolverError::InvalidParameter`]) names the first
    /// invalid one.
    pub fn validate(&self) -> Result<(), SolverError> {
        self.common.validate(NAME)?;
        let f = |v: R| v.as_f64();
        check_range(
            "youngs_modulus",
            f(self.youngs_modulus),
            f64::MIN_POSITIVE,
            MAX_YOUNGS_MODULUS_PA,
            "must be > 0 and at most MAX_YOUNGS_MODULUS_PA (1e12 Pa)",
        )?;
        check_range(
            "poisson_ratio",
            f(self.poisson_ratio),
            0.0,
            MAX_POISSON_RATIO,
            "must be in [0, MAX_POISSON_RATIO = 0.49]",
        )?;
        check_range(
            "friction_angle_deg",
            f(self.friction_angle_deg),
            0.0,
            MAX_FRICTION_ANGLE_DEG,
            "must be in [0, MAX_FRICTION_ANGLE_DEG = 70] degrees",
        )?;
        check_range(
            "dilatancy_angle_deg",
            f(self.dilatancy_angle_deg),
            0.0,
            f(self.friction_angle_deg),
            "must be in [0, friction_angle_deg] degrees",
        )?;
        check_range(
            "cohesion",
            f(self.cohesion),
            0.0,
            MAX_COHESION_PA,
            "must be in [0, MAX_COHESION_PA = 1e9] Pa",
        )?;
        for (name, v) in [
            ("viscosity_alpha", self.viscosity_alpha),
            ("viscosity_beta", self.viscosity_beta),
        ] {
            check_range(
                name,
                f(v),
                0.0,
                MAX_VISCOSITY_COEFFICIENT,
                "must be in [0, MAX_VISCOSITY_COEFFICIENT = 10]",
            )?;
        }
        if let Some(u) = self.viscosity_speed_m_s {
            check_range(
                "viscosity_speed_m_s",
                f(u),
                f64::MIN_POSITIVE,
                MAX_VISCOSITY_SPEED_M_S,
                "must be > 0 and at most MAX_VISCOSITY_SPEED_M_S (1e6 m/s) when set",
            )?;
        }
        check_range(
            "artificial_stress_epsilon",
            f(self.artificial_stress_epsilon),
            0.0,
            1.0,
            "must be in [0, 1]",
        )?;
        check_range(
            "artificial_stress_exponent",
            f(self.artificial_stress_exponent),
            1.0,
            MAX_ARTIFICIAL_STRESS_EXPONENT,
            "must be in [1, MAX_ARTIFICIAL_STRESS_EXPONENT = 10]",
        )?;
        check_range(
            "cfl_number",
            f(self.cfl_number),
            f64::MIN_POSITIVE,
            1.0,
            "must be in (0, 1]",
        )?;
        check_range(
            "skin",
            f(self.skin),
            0.0,
            f(self.common.support_radius),
            "must be in [0, support_radius] m",
        )?;
        check_range(
            "density_reinit_interval_s",
            f(self.density_reinit_interval_s),
            0.0,
            MAX_DENSITY_REINIT_INTERVAL_S,
            "must be in [0, 1e6] s (0: never)",
        )?;
        if self.wall_models.len() > MAX_WALL_MODELS {
            return Err(invalid(
                "wall_models",
                self.wall_models.len() as f64,
                "at most MAX_WALL_MODELS = 64 solids have their own model",
            ));
        }
        for m in std::iter::once(&self.default_wall).chain(&self.wall_models) {
            if let WallModel::Coulomb(mu) = *m {
                check_range(
                    "wall_friction",
                    mu,
                    0.0,
                    MAX_WALL_FRICTION,
                    "a Coulomb wall's friction coefficient must be in [0, MAX_WALL_FRICTION = 10]",
                )?;
            }
        }
        self.validate_moving_walls()?;
        if let Some(p) = &self.pour {
            p.validate(NAME, f(self.common.particle_spacing), self.common.gravity)?;
        }
        let reach = f(self.common.support_radius + self.skin);
        for (k, a) in self.periodic.iter().enumerate() {
            if a.axis > 2 || self.periodic[..k].iter().any(|b| b.axis == a.axis) {
                return Err(invalid(
                    "periodic",
                    a.axis as f64,
                    "each periodic axis must be 0, 1 or 2 and appear once (value: the axis)",
                ));
            }
            check_range(
                "periodic",
                f(a.period()),
                reach,
                f64::MAX,
                "a period (hi − lo, m; the value) must be finite and at least support_radius + skin",
            )?;
            if !f(a.lo).is_finite() {
                return Err(invalid("periodic", f(a.lo), "the lower end must be finite"));
            }
        }
        if self.dimensions == Dimensions::Two {
            if self.common.gravity.z != R::zero() {
                return Err(invalid(
                    "gravity",
                    f(self.common.gravity.z),
                    "a planar run (dimensions = 2) needs gravity in the plane z = 0 (value: its z component)",
                ));
            }
            if self.periodic.iter().any(|a| a.axis == 2) {
                return Err(invalid(
                    "periodic",
                    2.0,
                    "a planar run (dimensions = 2) has no periodic z axis: the plane is its section",
                ));
            }
        }
        let (n, _) = self.explicit_steps();
        if n > MAX_EXPLICIT_STEPS_PER_SUBSTEP {
            return Err(invalid(
                "cfl_number",
                n as f64,
                "the substep needs more than MAX_EXPLICIT_STEPS_PER_SUBSTEP = 100000 explicit steps (value: their count); raise common.substeps",
            ));
        }
        Ok(())
    }
}

impl<R: Real> ElastoplasticParams<R> {
    /// The moving walls' checks: at most [`MAX_MOVING_WALLS`], each a proper box with a
    /// finite velocity, a duration in `[0, MAX_WALL_MOTION_S]`, a model that makes particles,
    /// and a lattice to sample it on (`boundary_particle_region`).
    fn validate_moving_walls(&self) -> Result<(), SolverError> {
        let walls = &self.moving_walls;
        if walls.is_empty() {
            return Ok(());
        }
        if walls.len() > MAX_MOVING_WALLS {
            return Err(invalid(
                "moving_walls",
                walls.len() as f64,
                "at most MAX_MOVING_WALLS = 64 moving walls",
            ));
        }
        if self.boundary_particle_region.is_none() {
            return Err(invalid(
                "moving_walls",
                walls.len() as f64,
                "moving walls are walls of boundary particles: set boundary_particle_region (the lattice they are sampled on)",
            ));
        }
        for (k, w) in walls.iter().enumerate() {
            let finite = |v: &Vec3<R>| v.iter().all(|x| x.is_finite());
            let proper = finite(&w.region.min)
                && finite(&w.region.max)
                && (0..3).all(|a| w.region.min[a] < w.region.max[a]);
            if !proper {
                return Err(invalid(
                    "moving_walls",
                    k as f64,
                    "each moving wall's box needs finite corners with min < max on every axis (value: the wall's index)",
                ));
            }
            if !finite(&w.velocity) {
                return Err(invalid(
                    "moving_walls",
                    k as f64,
                    "each moving wall's velocity must be finite (value: the wall's index)",
                ));
            }
            check_range(
                "moving_walls",
                w.duration_s.as_f64(),
                0.0,
                MAX_WALL_MOTION_S,
                "a moving wall's duration (s; the value) must be in [0, MAX_WALL_MOTION_S = 3.2e7]",
            )?;
            match w.model {
                WallModel::ContactOnly => {
                    return Err(invalid(
                        "moving_walls",
                        k as f64,
                        "a moving wall is made of boundary particles: its model cannot be contact-only (value: the wall's index)",
                    ))
                }
                WallModel::Coulomb(mu) => check_range(
                    "wall_friction",
                    mu,
                    0.0,
                    MAX_WALL_FRICTION,
                    "a Coulomb wall's friction coefficient must be in [0, MAX_WALL_FRICTION = 10]",
                )?,
                _ => {}
            }
        }
        Ok(())
    }
}

sph_solver::solver_parameters!(ElastoplasticParams, NAME);
