#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! The PCISPH solver ([`Pcisph`]), the baseline of
//!
//! > Barbara Solenthaler and Renato Pajarola, "Predictive-Corrective Incompressible SPH",
//! > *ACM Transactions on Graphics* 28(3), Article 40, 2009 (SIGGRAPH 2009),
//! > doi:10.1145/1531326.1531346,
//!
//! as Macklin & Müller (2013, "Position Based Fluids", ACM TOG 32(4), §8) use it for comparison: PCISPH with 10 substeps and 4
//! pressure iterations per 16 ms frame against PBF with 4 substeps and 10 iterations ("so
//! that each performs 40 pressure iterations per-frame in total").
//!
//! # What is implemented
//!
//! One [`Pcisph::step`] call is one frame of `substeps` time steps of `Δt = dt / substeps`;
//! each time step is the paper's predictive-corrective loop:
//!
//! 1. neighbours within `h` found **once**, at the current positions `x(t)`
//!    (`neighbour_search::CellStartGrid`, the same search as the `pbf` crate);
//! 2. non-pressure forces: gravity, and the XSPH velocity filter of PBF (see deviations);
//!    pressure `p_i = 0` and pressure acceleration `a^p_i = 0`;
//! 3. `pressure_iterations` times (or fewer with `density_error_tolerance`):
//!    - predict `v*_i = v_i + Δt (g + a^p_i)`, `x*_i = x_i + Δt v*_i`, then the boundary's
//!      contact response ([`sph_solver::Boundary::project`]) applied to `x*_i`;
//!    - predict the density `ρ*_i = Σ_j m_j W(x*_i − x*_j) + ρ0 Ψ(x*_i)` (Poly6, self term
//!      included, over the neighbours of step 1; `Ψ` the boundary volume of a volume-map
//!      boundary, 0 for the collision model) and the density error `ρ*_err,i = ρ*_i − ρ0`;
//!    - update the pressure `p_i ← p_i + δ ρ*_err,i` with the precomputed scaling factor `δ`
//!      of **eq. 8**;
//!    - compute the pressure force (the symmetric form of **eqs. 5–6**, with `ρ0`, see below)
//!      at the current positions `x(t)`: `a^p_i = F^p_i / m_i = −Σ_j m_j (p_i/ρ0² + p_j/ρ0²)
//!      ∇W_ij − (p_i/ρ0) ∇Ψ(x_i(t))` (Spiky gradient, `∇W_ij = ∇W(x_i(t) − x_j(t))`; the
//!      boundary term is Akinci et al. 2012's `−m_i Σ_b ρ0 V_b (p_i/ρ0²) ∇W_ib` with
//!      `Σ_b V_b ∇W_ib = ∇Ψ`, the form of Neder 2024 eq. 31 and Bender et al. 2019);
//! 4. `v_i(t+Δt) = v_i + Δt (g + a^p_i)`, `x_i(t+Δt) = x_i + Δt v_i(t+Δt)` with the last
//!    pressure force, followed by the same collision response, the velocity taking the
//!    displacement of the response (`v += (x_collided − x_uncollided) / Δt`: PBF's line 21
//!    for a projected particle, the unchanged velocity otherwise).
//!
//! **Shape of the crate.** Like every solver of the workspace (`sph_solver`'s "Adding a
//! solver"): `params.rs` ([`PcisphParams`], with [`MAX_PRESSURE_ITERATIONS`]), `kernels.rs`
//! (Poly6, Spiky, `δ`; the density kernel [`PCISPH_KERNEL`]), `scratch.rs` and `solver.rs`
//! ([`PcisphScheme`], the [`SubstepScheme`] of one time step, whose passes are short enough
//! to stay in it). [`Pcisph`] is `FrameSolver<R, PcisphScheme<R>>`: the workspace's one
//! frame shell runs the frame and implements [`FluidSolver`]; [`PcisphScheme::delta`] and
//! [`PcisphScheme::pressure`] are methods of [`Pcisph`] through `Deref`. PCISPH starts every
//! time step from `p = 0`, so it carries nothing between frames besides the particles and
//! the frame count ([`FluidSolver::save_state`]).
//!
//! //! **Scaling factor (eq. 8).** `δ = −1 / (β (−Σ_j ∇W_ij · Σ_j ∇W_ij − Σ_j ∇W_ij · ∇W_ij))`
//! with `β = Δt² m² 2/ρ0²`, evaluated once, in [`PcisphParams::scaling_factor`], for a
//! prototype particle at the origin of a full simple cubic lattice of spacing
//! `particle_spacing` (all lattice points within `h`) with the prototype mass
//! `m = ρ0 s³` ([`PcisphParams::particle_mass`]) and the substep `Δt`. (The two sums are
//! `D_ref / (m/ρ0)²` with [`sph_solver::CommonParams::reference_denominator`] `D_ref`, which is how
//! they are computed, so that `δ = 1 / (2 Δt² D_ref)`.) `δ` is in Pa·m³/kg = m²/s²; it is
//! 327 m²/s² at `s = 0.025 m`, `h = 0.05 m`, `Δt = 1.6 ms`.
//!
//! **Pressure force.** `F^p_i = −m_i Σ_j m_j (p_i/ρ0² + p_j/ρ0²) ∇W_ij`: the symmetric
//! (momentum-conserving) SPH pressure force with the rest density in place of `ρ_i`, `ρ_j` in
//! the denominators. This is the form of the paper's derivation of `δ` (eq. 5 with `p_i = p_j
//! = p̃_i` and `ρ_i = ρ_j = ρ0`: `F^p_i = −m² Σ_j (2 p̃_i/ρ0²) ∇W_ij`), so that the linear model
//! behind `δ` is exact for the prototype, and it is what SPlisHSPlasH's `TimeStepPCISPH` does.
//! Using the (predicted) densities `ρ_i²` instead would change the effective stiffness by
//! `(ρ0/ρ_i)²` and blow up for isolated particles.
//!
//! **Phases** reported in [`sph_solver::StepStats::phases`] ([`PCISPH_PHASES`]):
//!
//! | field | PCISPH meaning |
//! | --- | --- |
//! | `integrate` | input checks, XSPH, gravity and the first prediction (steps 2 and 3's first prediction) |
//! | `create_hash_grid`, `detect_neighbours` | the neighbour search of step 1 (build, query) |
//! | `pressure_solve` | the pressure iterations (step 3: density prediction, pressure update, pressure force, prediction with collisions) |
//! | `velocity_update` | step 4: final velocities, densities at the final positions, blow-up checks, writing the state, statistics |
//! | `reorder` (and `reordered`) | as for PBF |
//! | `substeps` | time steps done |
//! | `iterations` | pressure iterations done in total (`substeps × pressure_iterations` without early stop) |
//! | `neighbour_pairs` | ordered pairs of the last substep's neighbour lists |
//! | `max_density_ratio`, `mean_density_ratio` | `ρ_i/ρ0` at the final positions (with the last substep's neighbour lists) |
//! | `kinetic_energy` | `Σ m_i \|v_i\|² / 2` at the end (J) |
//!
//! # Deviations from Solenthaler & Pajarola (2009)
//!
//! - **Viscosity.** S&P09 include an SPH viscosity force in the non-pressure forces `F^v`.
//!   Here the viscosity is PBF's XSPH filter (Macklin & Müller eq. 17, `c = 0.05` by default,
//!   see below; volumes
//!   `m_j/ρ0`, Poly6), `v_i ← v_i + c Σ_j (m_j/ρ0) (v_j − v_i) W(x_i − x_j)`, applied as a
//!   non-pressure velocity change at the start of each time step (at `x(t)`, with the
//!   neighbours of step 1), so that the comparison with PBF isolates the pressure solver.
//! - **Boundaries.** S&P09 handle boundaries with their own collision handling; here the
//!   walls are a [`sph_solver::Boundary`]: [`Pcisph::new`] projects particles out of SDF
//!   solids to the particle radius `s/2` (PBF's response, no friction or restitution),
//!   [`Pcisph::with_boundary`] takes volume maps, whose walls also take part in the density
//!   and the pressure force; the contact response is applied to the predicted positions
//!   inside each iteration and to the final positions.
//! - **Iteration count.** The paper iterates until the density error is below `η` (with a
//!   minimum number of iterations; SPlisHSPlasH uses at least 3). Here `pressure_iterations`
//!   is a fixed count by default (the PBF paper's comparison: 4), and
//!   `density_error_tolerance = Some(η)` stops early after the first iteration whose
//!   **maximum** predicted relative compression `max_i max(ρ*_i/ρ0 − 1, 0)` is at most `η`
//!   (the pressure and force of that iteration are still applied; no minimum count).
//!   Particles below the rest density (free surface) do not count, otherwise a free surface
//!   would never satisfy any tolerance. (SPlisHSPlasH checks the *mean* clamped error.)
//! - **Negative pressures are clamped by default** (`clamp_negative_pressure = true`): the
//!   density error is clamped to `≥ 0` before the pressure update, as SPlisHSPlasH does
//!   (`densityAdv = max(densityAdv, 1)`), so pressures are never negative. S&P09 do not
//!   clamp; `false` gives their form, with which a fluid bounded by SDF walls collapses into
//!   clumps (measured below), so it is not a usable default for the comparison.
//! - **Masses.** Densities and forces use the particles' own masses; `δ` uses the prototype
//!   mass `ρ0 s³` (the paper's particles all have the same mass `m`).
//! - **Neighbours** for the predicted densities are those of `x(t)` (the paper's "once per
//!   time step"), so a pair that only comes within `h` at the predicted positions is missed.
//!
//! # Measured behaviour (1000-particle block at rest in a tank, SDF walls, XSPH `c` 0.01)
//!
//! 10 × 10 × 10 particles at `s = 0.025 m` filling the bottom of a tank of 10 × 20 × 10
//! spacings, 10 substeps × 4 iterations per 16 ms frame (`tests/pcisph.rs`):
//!
//! - **Unclamped (`clamp_negative_pressure = false`, S&P09):** the block collapses into clumps within two frames
//!   (mean `ρ/ρ0` 2.4 after 2 frames, 3.3 after 4; pressures down to −1.05·10⁶ Pa; kinetic
//!   energy 5·10⁵ J). The wall and free-surface particles lack neighbours (the SDF walls
//!   contribute no density), so their density error is negative every iteration and their
//!   accumulated pressure pulls their neighbours in: the particle-deficiency problem the PBF
//!   paper mentions (§8: "each iteration makes its pressure increasingly negative").
//!   No NaN and no error results; the state is just meaningless.
//! - **Clamped** (`clamp_negative_pressure = true`, the default): the compression is held (max `ρ/ρ0`
//!   1.016 at t = 1 s and at most 1.023 over the run in f64; 1.006 and 1.052 in f32), but
//!   with XSPH `c = 0.01` as the only damping the block does not come to rest: the kinetic
//!   energy grows to 5–8 J and the fluid splashes up the tank. With `c = 0.1` it settles (kinetic energy 0.02 J at t = 1 s, max
//!   `ρ/ρ0` 1.002, mean 0.995), the free surface ending near 8.4 `s` instead of 10 `s`
//!   because particles stack along the walls. S&P09's SPH viscosity force, replaced here by
//!   XSPH, supplies damping the scheme needs; their boundary handling, replaced by SDFs,
//!   supplies wall density.
//!
//! # Why a fluid at rest kept boiling, and the fix (measured)
//!
//! A block of 20 × 32 × 20 particles (`s = 0.025 m`, 12,800 particles) resting on the floor
//! of a closed tank twice its height, 10 × 4 per 16 ms frame, 2 s, kinetic energy per
//! particle in units of `m g H` (`H` the block height), split into the particles within `h`
//! of a wall, the top two layers and the bulk (`cargo run --release -p pcisph --example
//! rest_probe -- SUBSTEPS ITERATIONS XSPH [volume-map] [unclamped]`, f64):
//!
//! | walls | XSPH `c` | iterations | KE at 2 s | where |
//! | --- | --- | --- | --- | --- |
//! | collision | 0.01 | 4 | 6.1·10⁻² | walls 8.7·10⁻², bulk 4.0·10⁻²; splashes to 56 `s` (block 32 `s`) |
//! | collision | 0.01 | 1 | 1.7·10⁻² | |
//! | collision | 0.01 | 20 | 9.3·10⁻² | |
//! | collision | 0 | 4 | 2.2·10⁻¹ | |
//! | volume map | 0.01 | 4 | 1.3·10⁻² | bulk 1.5·10⁻², walls 1.1·10⁻²; no splash |
//! | volume map | 0.01 | 1 | 7.2·10⁻⁴ | (max `ρ/ρ0` 1.07: under-resolved pressure) |
//! | volume map | 0.01 | 20 | 2.8·10⁻² | |
//! | volume map | 0.05 | 4 | **3.7·10⁻⁵** | the default |
//! | volume map | 0.1 | 4 | 1.0·10⁻⁵ | |
//! | collision | 0.1 | 4 | 1.8·10⁻⁴ | surface 29.8 `s` (particles stacked at the walls) |
//!
//! Two causes, each measured: (1) with collision walls the wall particles lack the wall's
//! share of their density, so the energy concentrates at the walls (twice the bulk's) and
//! the fluid splashes; volume maps remove that (5× less energy, no splash). (2) What
//! remains grows with the number of pressure iterations (1 → 4 → 20: 7·10⁻⁴ → 1.3·10⁻² →
//! 2.8·10⁻²), in the bulk: each iteration makes the correction of the per-step density
//! fluctuations more complete, and the correction enters the velocity; S&P09 dissipate that
//! with their viscosity force, for which PBF's XSPH with `c = 0.01` is far too weak. Tried
//! and rejected by measurement: under-relaxing the pressure update (`ω = 0.5` at 20
//! iterations: 2.5·10⁻², i.e. not a diverging Jacobi iteration), clamping the accumulated
//! pressure instead of the density error (6.7·10⁻² with collision walls), and particle
//! masses calibrated to the Poly6 lattice density (1.5·10⁻² with volume maps: the kernel's
//! +0.98 % lattice bias is not the cause). Hence the defaults: volume-map walls (the scene
//! default, `sph_scene::BoundaryModel`) and `c = 0.05` ([`DEFAULT_PCISPH_XSPH`]). The
//! `boundary-rest` experiment checks the result on a smaller column (PCISPH 4.5·10⁻⁵ with
//! volume maps against 7·10⁻³ with collision walls).

//! # Robustness, performance, determinism
//!
//! Exactly as for the `pbf` crate's solver (both use `sph_solver::step`): invalid input is rejected naming the particle; divergence (a
//! non-finite predicted or final position or velocity, or a particle more than `h` inside a
//! solid) is [`sph_solver::SolverError::BlowUp`] and the state keeps the last completed substep; no
//! allocation in a step once the buffers have grown; every loop writes one particle's values
//! from fixed-order sums over its neighbour list and the statistics are summed over fixed
//! chunks, so the results are bitwise identical for any number of threads; the particles are
//! reordered by cell every `reorder_every` calls ([`Pcisph::last_permutation`]).

mod kernels;
mod params;
mod scratch;
mod settings;
mod solver;

pub use kernels::PCISPH_KERNEL;
pub use params::{PcisphParams, DEFAULT_PCISPH_XSPH, MAX_PRESSURE_ITERATIONS};
pub use settings::PcisphSettings;
pub use solver::{Pcisph, PcisphScheme, PCISPH_PHASES};

pub use sph_core::{sampling::cubic_lattice, Aabb, BoxSdf, Inverted, Plane, Sphere};
pub use sph_core::{ParticleSet, Real, Vec3};
pub use sph_solver::boundary::{VolumeMapBoundary, VolumeMapCache, VolumeMapOptions};
pub use sph_solver::initial::{calibrate_masses, density_ratios, MassCalibration};
pub use sph_solver::VOLUME_MAP_CONTACT_FRACTION;
pub use sph_solver::{
    Boundary, CollisionBoundary, CommonParams, FluidSolver, FrameSolver, KernelKind, Solids,
    SolverError, SolverState, StepStats, SubstepScheme,
};
