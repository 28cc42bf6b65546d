#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Bui, H. H., Fukagawa, R., Sako, K. & Ohno, S. (2008). "Lagrangian meshfree particles
//! method (SPH) for large deformation and failure flows of geomaterial using
//! elastic–plastic soil constitutive model". *International Journal for Numerical and
//! Analytical Methods in Geomechanics* 32(12):1537–1570. With the artificial stress of
//! Gray, J. P., Monaghan, J. J. & Swift, R. P. (2001), "SPH elastic dynamics", *Computer
//! Methods in Applied Mechanics and Engineering* 190:6641–6662, and the artificial viscosity
//! of Monaghan, J. J. (1992), "Smoothed particle hydrodynamics", *Annual Review of Astronomy
//! and Astrophysics* 30:543–574.
//!
//! The whole stress, its mean part included, is a state carried by each particle from step
//! to step and frame to frame: an elastic response capped by the Drucker–Prager cone. A heap
//! can therefore stand: a slope below the cone is held by the elastic stress it built up
//! while settling.
//!
//! # Equations
//!
//! Tension positive; `σ` the Cauchy stress, `L = ∇v`, `ε̇ = (L + Lᵀ)/2`, `ω = (L − Lᵀ)/2`,
//! `I1 = tr σ`, `s = σ − I1/3 I`, `J2 = s:s/2`, `K = E/(3(1 − 2ν))`, `G = E/(2(1 + ν))`.
//!
//! ```text
//! ρ̇_i  = Σ_j m_j (v_i − v_j)·∇_i W_ij                                   (continuity)
//! ρ_i  ← max(ρ0 Σ_j m_j W_ij / (m0 σ0), ρ0)   every 2 ms, if set        (re-initialisation)
//! L_i  = Σ_j (m_j/ρ_j) (v_j − v_i) ⊗ ∇_i W_ij                            (velocity gradient)
//! σ̇    = σ ωᵀ + ω σ + 2G ė + K tr(ε̇) I − λ̇ [3 α_ψ K I + (G/√J2) s]      (Jaumann rate)
//! λ̇    = (3 α_φ K tr ε̇ + (G/√J2) s:ε̇) / (9 α_φ α_ψ K + G)   on the cone, if > 0
//! f    = √J2 + α_φ I1 − k_c,  α_φ, α_ψ, k_c from φ, ψ, c by the cone's match (below)
//! dv_i/dt = Σ_j m_j (σ_i/ρ_i² + σ_j/ρ_j² − Π_ij I + (R_i + R_j) f_ij^n)·∇_i W_ij + g
//! Π_ij = (−α_Π c φ_ij + β_Π φ_ij²)/ρ̄_ij if v_ij·x_ij < 0,  φ_ij = h v_ij·x_ij/(|x_ij|² + 0.01 h²)
//! R_i  = Σ_a R^a e_a e_aᵀ,  R^a = −ε σ^a/ρ_i² for σ^a > 0;  f_ij = W(r_ij)/W(s)
//! ```
//!
//! After each stress step, Bui's return: tension cracking (if `−α_φ I1 + k_c < 0` the mean
//! stress moves back to the apex), then the deviator scaled by `r = (−α_φ I1 + k_c)/√J2` when
//! `r < 1` ([`DruckerPrager::return_to_cone`]).
//!
//! # The cone's match and the angle of repose
//!
//! [`ConeMatch`] says in which state of stress the cone meets Mohr–Coulomb:
//! `PlaneStrainAssociated` (Bui et al. 2008's `α_φ = tan φ/√(9 + 12 tan²φ)`,
//! `k_c = 3c/√(9 + 12 tan²φ)`, the default), `PlaneStrain` (`α_φ = sin φ/3`, `k_c = c cos φ`)
//! or `SimpleShear` (`α_φ = tan φ/3`, `k_c = c`). With `ψ = 0` a flank that formed by
//! flowing comes to rest at `tan β = 3 α_φ` (steady shear parallel to the slope, stress
//! coaxial with the plastic flow: [`ConeMatch::predicted_repose_angle_deg`]), so under
//! `SimpleShear` the friction angle is the angle of repose; a settled wedge that has not
//! flowed holds up to `sin β = 3 α_φ` ([`ConeMatch::max_stable_slope_deg`]; Davis 1968's
//! reduced strength). The workspace's `docs/elastoplastic-granular.md` derives both and
//! records the runs that measure them.
//!
//! One explicit step (symplectic Euler): `L`, `ρ̇` and the stress update from `(x, v, σ, ρ)`,
//! then the acceleration from the new `σ`, `ρ`; `v ← v + Δt a`, `x ← x + Δt v`, projected out
//! of the solids. `Δt = (dt/substeps)/n` with the smallest `n` such that `Δt ≤ C h / c_p`,
//! `c_p = √((K + 4G/3)/ρ0)` the P-wave speed (the fastest elastic wave; `1.160 √(E/ρ0)` at
//! ν = 0.3), `h` the smoothing length (half the support radius), `C` measured on the shipped
//! scenes ([`DEFAULT_CFL_NUMBER`]). The steps are
//! sub-cycled inside each substep of the frame shell; the neighbour lists are built with
//! radius `support + skin` and kept while no particle has moved more than `skin/2` (and no
//! grain and moving wall together more than `skin`).
//!
//! Walls are rows of boundary particles, fixed or moving at a velocity
//! ([`ElastoplasticScheme::set_boundary_velocity`]) ([`boundary_particles`]; from a scene's solids
//! with [`ElastoplasticParams::boundary_particle_region`], [`sample_solids`]) or volume maps
//! sampled solid by solid, each solid with its [`WallModel`] (free-slip, no-slip, or, for
//! boundary particles, Coulomb with a wall friction coefficient; see [`boundary_particles`]
//! and [`walls`] for the terms). In scene files the solver is `[solver] kind =
//! "elastoplastic"` ([`ElastoplasticSettings`]) with `[boundary] model = "particles"`.
//!
//! A particle faster than `c` stops the run with a blow-up error naming the step and the
//! particle: the explicit step's Courant bound holds only below it.
//!
//! # Deviations
//!
//! - Walls: Bui et al. use rows of boundary particles. Here either such rows
//!   ([`boundary_particles`], stress and velocity extrapolated as Adami et al. 2012 do for
//!   the pressure; the only walls with which a layer rests, see the docs page), or volume
//!   maps: the walls' share of each sum is the volume map's `∇Ψ`, the wall's stress
//!   mirrors the particle's and its velocity is zero (free-slip: normal components only).
//!   Particles are also projected out of the solids to the contact distance, as in the
//!   workspace's other solvers.
//! - Periodic axes by images of the particles near the ends
//!   (`sph_solver::scene_boundary::PeriodicImages`).
//! - Time integration: symplectic Euler instead of Bui's leap-frog.
//! - Optionally ([`ElastoplasticParams::density_reinit_interval_s`], off by default as in
//!   Bui et al.), the density is re-initialised every 2 ms ([`DENSITY_REINIT_INTERVAL_S`])
//!   by the kernel sum with the free-surface floor `ρ0`, as SPHinXsys's granular examples
//!   re-initialise theirs: a grain that separates keeps `ρ0` instead of a continuity density
//!   falling without bound (the frictionless pour's blow-up).
//! - The geostatic start ([`InitialStress::Geostatic`]) takes Jaky's `K0 = 1 − sin φ`
//!   ([`initial`]): the elastic `ν/(1 − ν)` lies outside the matched cones.
//! - A particle without any granular neighbour inside the kernel support (a grain out of
//!   contact) carries no stress; otherwise its zero velocity gradient would keep the last
//!   stress, which acts as a spring against walls.
//! - The plastic rate applies when the stress lies within [`stress::YIELD_TOLERANCE`] of the
//!   cone (Bui: exactly on it).
//! - The equivalent plastic shear strain (the output) is this crate's measure:
//!   `Σ √(2 Δe^p:Δe^p)` over the flow rule's and the return's deviatoric plastic strain.
//! - Material defaults follow SPHinXsys's transcription of Bui's aluminium-bar test
//!   (`E` = 5.84 MPa, `ν` = 0.3, `ρ0` = 2040 kg/m³), not checked against the paper here; the
//!   speed of sound is `√(E/ρ0)` as in Bui (SPHinXsys uses `√(K/ρ0)`), but the explicit
//!   step's Courant bound takes the P-wave speed `√((K + 4G/3)/ρ0)`, the fastest wave.

pub mod boundary_particles;
pub mod initial;
mod kernels;
mod lanes;
mod name;
mod params;
mod passes;
pub mod pour;
mod scratch;
mod settings;
mod solver;
pub mod stress;
pub mod walls;

pub use boundary_particles::{
    boundary_block, sample_solids, BoundaryParticle, MAX_BOUNDARY_LATTICE_NODES,
    MAX_BOUNDARY_PARTICLES,
};
pub use kernels::ELASTOPLASTIC_KERNEL;
pub use params::{
    ElastoplasticParams, InitialStress, MovingWall, WallModel, BOUNDARY_PARTICLE_ROWS,
    BUI_SUPPORT_OVER_SPACING, DEFAULT_ARTIFICIAL_STRESS_EPSILON,
    DEFAULT_ARTIFICIAL_STRESS_EXPONENT, DEFAULT_CFL_NUMBER, DEFAULT_CONE_MATCH,
    DEFAULT_POISSON_RATIO, DEFAULT_REST_DENSITY, DEFAULT_SKIN_OVER_SPACING,
    DEFAULT_VISCOSITY_ALPHA, DEFAULT_VISCOSITY_BETA, DEFAULT_YOUNGS_MODULUS_PA,
    DENSITY_REINIT_INTERVAL_S, MAX_ARTIFICIAL_STRESS_EXPONENT, MAX_COHESION_PA,
    MAX_DENSITY_REINIT_INTERVAL_S, MAX_EXPLICIT_STEPS_PER_SUBSTEP, MAX_FRICTION_ANGLE_DEG,
    MAX_MOVING_WALLS, MAX_POISSON_RATIO, MAX_VISCOSITY_COEFFICIENT, MAX_WALL_FRICTION,
    MAX_WALL_MODELS, MAX_WALL_MOTION_S, MAX_YOUNGS_MODULUS_PA,
};
pub use pour::{Pour, FALL_OVER_LANDING_TIME, MAX_POURED_GRAINS};
pub use settings::{ElastoplasticSettings, WITH_COMMON_FRICTION_ANGLE_DEG};
pub use solver::{
    Elastoplastic, ElastoplasticScheme, ELASTOPLASTIC_PHASES, ELASTOPLASTIC_STATE_ARRAYS,
};
pub use sph_solver::scene_boundary::PeriodicAxis;
pub use sph_solver::scene_boundary::{Axis, PeriodicSetting, SceneBoundary};
pub use stress::{ConeMatch, DruckerPrager, StressUpdate};

pub use sph_core::sampling::cubic_lattice;
pub use sph_core::{Aabb, BoxSdf, Inverted, ParticleSet, Plane, Vec3};
pub use sph_solver::{Solids, SolverError};
