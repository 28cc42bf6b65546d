#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Position Based Fluids: the solver core of
//!
//! > Miles Macklin and Matthias Müller, "Position Based Fluids", *ACM Transactions on
//! > Graphics* 32(4), Article 104, 2013 (SIGGRAPH 2013), doi:10.1145/2461912.2461984.
//!
//! [`Pbf::step`] runs the paper's Algorithm 1 on a structure-of-arrays
//! [`sph_core::ParticleSet`] (positions, velocities, masses, densities), generic over
//! [`sph_core::Real`] (`f32` or `f64`), with rayon-parallel loops over the particles.
//!
//! [`Pbf`] implements `sph_solver::FluidSolver`, so a scene runner can hold a
//! `Box<dyn FluidSolver<R>>` beside the other solvers of the workspace (the PCISPH baseline
//! the paper compares against is the `pcisph` crate). Its walls are a
//! [`sph_solver::Boundary`]: [`Pbf::new`] takes solids and projects particles out of them
//! (the paper's collision handling); [`Pbf::with_boundary`] takes any model, e.g. volume
//! maps, whose walls take part in the density. Scenes and experiments are not part of this
//! crate.
//!
//! ```
//! use pbf::{ParticleSet, Pbf, PbfParams, Solids, Vec3};
//! use sph_core::{sampling::cubic_lattice, Aabb, BoxSdf, Inverted};
//!
//! let params = PbfParams::<f32>::default(); // s = 0.025 m, h = 0.05 m, 16 ms frames
//! let s = params.common.particle_spacing;
//! let block = Aabb::new(Vec3::zeros(), Vec3::new(4.0, 4.0, 4.0) * s).unwrap();
//! let tank = Aabb::new(Vec3::zeros(), Vec3::new(12.0, 8.0, 4.0) * s).unwrap();
//! let positions = cubic_lattice(&block, s, 1 << 20).unwrap();
//! let (m, rho0) = (params.particle_mass(), params.common.rest_density);
//! let mut state = ParticleSet::from_positions(positions, m, rho0);
//! let solids: Solids<f32> = vec![Box::new(Inverted(BoxSdf::new(tank).unwrap()))];
//! let mut solver = Pbf::new(params, solids).unwrap();
//! // The solver reorders the particles by grid cell every `reorder_every` calls (10 by
//! // default, starting with the first): `ids[k]` is the original index of the particle
//! // stored at `k` now.
//! let mut ids: Vec<u32> = (0..state.len() as u32).collect();
//! for _ in 0..10 {
//!     // One call advances a whole 16 ms frame of `substeps` steps.
//!     let stats = solver.step(&mut state).unwrap();
//!     assert!(stats.max_density_ratio < 1.5);
//!     if let Some(perm) = solver.last_permutation() {
//!         // The call began by moving the particle at `perm[k]` to `k`.
//!         ids = perm.iter().map(|&old| ids[old as usize]).collect();
//!     }
//! }
//! // Particle 0 started at the block's lower corner, half a spacing above the floor, and
//! // is still on the floor.
//! let k = ids.iter().position(|&id| id == 0).unwrap();
//! assert!(state.positions[k].y < s);
//! ```
//!
//! # Shape of the crate
//!
//! Like every solver of the workspace (`sph_solver`'s "Adding a solver"): `params.rs`
//! ([`PbfParams`], with [`MAX_SOLVER_ITERATIONS`]), `kernels.rs` (Poly6 and Spiky; the
//! density kernel [`PBF_KERNEL`]), `scratch.rs` ([`PbfScratch`]), `passes.rs` (the two
//! passes of a Jacobi iteration; `scorr.rs`, eq. 13) and `solver.rs` ([`PbfScheme`], the
//! [`SubstepScheme`] of one time step). [`Pbf`] is `FrameSolver<R, PbfScheme<R>>`: the
//! workspace's one frame shell runs the frame (checks, reordering, substeps, statistics)
//! and implements [`FluidSolver`]; the scheme's own methods ([`PbfScheme::scratch`],
//! [`PbfScheme::evaluate_constraints`], …) are methods of [`Pbf`] through `Deref`. PBF
//! carries nothing from one frame to the next besides the particles and the frame count
//! ([`FluidSolver::save_state`]).
//!
//! | paper | here |
//! | --- | --- |
//! | Algorithm 1 lines 1–4 (gravity, prediction) | [`Pbf::step`], phase `integrate` of [`StepStats`] ([`PBF_PHASES`]) |
//! | lines 5–7 (neighbours once per step, at `x*`; Green 2008) | `neighbour_search::CellStartGrid`, phases `create_hash_grid`, `detect_neighbours` |
//! | eqs. 1–2 (constraint, density, Poly6) | `lambda_pass` (private), [`PbfScratch::density`] |
//! | eqs. 7–8 (constraint gradients, Spiky) and 9–11 (`λ_i` with CFM `ε`) | `lambda_pass`, [`PbfScratch::lambda`] |
//! | eqs. 12–14 (`Δp_i` with `s_corr`) | `delta_pass` (private), [`ArtificialPressure`] (eq. 13), [`PbfScratch::delta_p`] |
//! | line 14 (collision detection and response, inside the loop) | [`sph_solver::Boundary::project`] (collision or volume-map model) |
//! | lines 20–24, eq. 15 (vorticity), eq. 16 (confinement), eq. 17 (XSPH) | [`Pbf::step`], phase `velocity_update` |
//! | Table 2 (time per phase) | [`StepStats`] |
//! | §8, Table 1 (frame of 16 ms, 4 substeps, 2–4 iterations) | [`PbfParams`] defaults |
//!
//! # Conventions and deviations from the paper
//!
//! - **Masses are kept.** The paper treats all particles as having equal mass and drops `m`
//!   from eq. 2 on ("we will drop this term from subsequent equations"). Here, in SI units,
//!   `ρ_i = Σ_j m_j W(p_i − p_j)` (self term included), `∇_{p_j} C_i = −(m_j/ρ0) ∇W_ij`,
//!   `∇_{p_i} C_i = (1/ρ0) Σ_j m_j ∇W_ij` (eq. 8 with the mass), `λ_i = −C_i / (Σ_k |∇_{p_k}
//!   C_i|² + ε)` (eq. 11) and
//!   `Δp_i = (1/ρ0) Σ_j (λ_i m_j + λ_j m_i + s_corr u (m_i + m_j)/2) ∇W_ij`, i.e.
//!   `λ_i ∇_{p_i} C_i + Σ_j λ_j ∇_{p_i} C_j` plus the artificial pressure. For equal masses
//!   `m` this is exactly eq. 14 times `m`: the paper's formulas in its density unit `m`
//!   (`ρ0 → ρ0/m`). Consequently `ε` is in m⁻² and `λ` in m². Unequal masses are allowed
//!   (the generalisation above); the paper's case is equal masses.
//! - **CFM `ε` (eq. 11).** The paper gives no value. The scale is the denominator of a
//!   particle at rest in a full lattice, `D_ref = Σ_k |∇_{p_k} C_i|²`
//!   ([`PbfParams::reference_denominator`]; `0.37339/s²` at `h = 2 s`, 597 m⁻² at
//!   `s = 0.025 m`), and the default is `ε = D_ref` ([`DEFAULT_RELATIVE_CFM`]). It must be
//!   that large because each particle receives the corrections of all ~27 constraints it
//!   takes part in at once (Jacobi, §6): the paper's `ε` is the only under-relaxation of
//!   Algorithm 1. Measured on a 1000-particle block resting in a tank (4 substeps × 4
//!   iterations per 16 ms frame, 120 frames): kinetic energy at the end 3·10⁻³ J with
//!   `ε = D_ref`, but 0.13 J with `0.5 D_ref`, 1.5 J with `0.3 D_ref` and ~800 J (boiling)
//!   with `0.05 D_ref`.
//! - **Unit of `s_corr` (eqs. 13–14).** Eq. 14 adds the dimensionless `s_corr` to
//!   `λ_i + λ_j`, which has units (length²), so the paper's `k = 0.1` is tied to its unit of
//!   length (§9 notes that the term "is dependent on the spatial resolution"). Taken
//!   literally in SI at `s = 0.025 m` it moves a corner particle of a resting block by 1.4 `s`
//!   per iteration and the block explodes. Here `s_corr` is added in units of
//!   `u = 1/D_ref` ([`PbfParams::scorr_unit`]), the `λ` that corrects a unit density error in
//!   a full neighbourhood: `s_corr` then acts like a density offset of `|s_corr|` (0.5 % at the
//!   nearest-neighbour distance `h/2` with `k = 0.1`, `n = 4`, `|Δq| = 0.2 h`), which is the
//!   paper's described effect ("keeps particle density slightly lower than the rest
//!   density"), at any resolution.
//! - **Volumes in eqs. 15–17.** The paper writes the vorticity (eq. 15) and XSPH (eq. 17)
//!   sums without particle volumes (unit masses again). In SI they need the volume
//!   `V_j = m_j/ρ0` (Monaghan 1992's estimators, whose XSPH has `m_j/ρ̄_ij`; the rest density
//!   is used so that one neighbour pass gives both), so that `ω` is the curl in 1/s and XSPH's
//!   `c` is dimensionless (`c = 0.01` blends 1 % of the neighbourhood's relative velocity):
//!   `ω_i = Σ_j V_j v_ij × ∇_{p_j} W_ij`, `v_i ← v_i + c Σ_j V_j v_ij W_ij` (Poly6 `W`).
//! - **Vorticity confinement** (eq. 16): `η_i = Σ_j V_j (|ω_j| − |ω_i|) ∇W_ij` (SPH gradient
//!   of `|ω|` in difference form, Spiky), `N = η/|η|` (no force where `η = 0`), and the
//!   "force" is applied as an acceleration: `v_i ← v_i + Δt ε (N × ω_i)`, `ε` in m/s. Both
//!   confinement and XSPH are computed from the velocities of line 21 (neither sees the
//!   other's change). Default `ε = 0` (the paper uses it "optionally" and gives no value).
//! - **Collision response** (line 14, Algorithm 1; the [`sph_solver::CollisionBoundary`]
//!   that [`Pbf::new`] builds): each iteration, the corrected position
//!   `x*_i + Δp_i` is tested against every solid in turn; where the signed distance `d` is
//!   below the particle radius `r = s/2`, it is moved along the solid's SDF gradient
//!   (normalised; analytic for the `sph_core` shapes, central differences otherwise) by
//!   `r − d`, i.e. onto the surface offset by `r`. No friction or restitution: the velocity
//!   follows from line 21. The paper gives no details beyond "collision detection against
//!   solids as part of the constraint solving loop" with SDFs.
//! - **No clamping** of `C_i` by default (the paper does not clamp; particles with deficient
//!   neighbourhoods get `C_i < 0` and attract, limited by `s_corr` and `ε`).
//!   [`PbfParams::clamp_negative_constraint`] gives SPlisHSPlasH's unilateral
//!   `max(C_i, 0)` instead.
//! - **Fixed iteration count** by default, as in the paper;
//!   [`PbfParams::mean_compression_tolerance`] stops earlier (SPlisHSPlasH's rule), and a step
//!   that reaches the maximum without meeting it is counted in
//!   [`StepStats::unconverged_substeps`].
//! - **Neighbour lists** are found once per step at the predicted positions and reused by
//!   every iteration and the velocity update (as in the paper, §6).
//!
//! # Robustness
//!
//! [`PbfParams::validate`] rejects nonsense parameters by name. [`Pbf::step`] rejects
//! non-finite positions or velocities and non-positive masses on entry (naming the particle),
//! and reports divergence as [`SolverError::BlowUp`] instead of writing it: a non-finite
//! predicted position, final position or velocity, or a particle more than `h` inside any
//! solid after the solve (e.g. outside the tank). The state then holds the last completed
//! substep.
//!
//! # Performance and determinism
//!
//! No allocation happens inside [`Pbf::step`] once the buffers have grown (they are resized
//! only when the particle count changes; the neighbour lists grow with the pair count).
//! Every parallel loop writes one particle's values from a fixed-order sum over its
//! neighbour list, and the statistics are summed over fixed chunks, so results are bitwise
//! identical for any number of threads. Every `reorder_every` calls the particles are
//! reordered by cell ([`Pbf::last_permutation`] gives the permutation) for locality; this
//! changes the particle order of the state.
//!
//! Each Jacobi iteration makes two passes over the neighbour pairs. The first (densities,
//! `λ`) stores per pair the Spiky gradient factor `dW/dr / r` and `s_corr` in CSR order (each
//! rayon task owns its particles' contiguous range), and the second (`Δp`) reuses them at the
//! same positions, so it needs no square root, division or kernel evaluation.
//!
//! # Performance
//!
//! Measured side by side with SPlisHSPlasH 2.19's PBF on its `DamBreakModel` scene (59,319
//! fluid particles, Δt = 2 ms, 0.1 % mean density error) by
//! `RAYON_NUM_THREADS=T cargo run --release -p benches --example pbf_dambreak -- 250
//! tol=0.001 pbf unilateral [volume-map]`: the figures, dates and commands are in the
//! workspace's `docs/performance.md`. The accuracy-matched comparison uses SPlisHSPlasH's
//! stopping rule and tolerance ([`PbfParams::mean_compression_tolerance`] = 0.001, 2–100
//! iterations) and its form of the constraint ([`PbfParams::clamp_negative_constraint`],
//! `ε` = 10⁻⁶ m⁻², no `s_corr`). With the paper's form (bilateral `C_i`, `ε = D_ref`,
//! `s_corr`) the Jacobi iterations converge far more slowly to a given tolerance; at a fixed
//! iteration count (the paper's way of running) the cost per step is the same.
//!
//! With volume-map walls the boundary's `Ψ` is sampled at every Jacobi iteration only for
//! the particles within `1.5 h` of a solid; a particle farther than `h` skips the map, and a
//! map cell whose eight nodes lie on one flat wall takes the half-space volume directly.
//! The contact response runs only where it can act: each particle's distance to the solids
//! is evaluated once a step and carried through the iterations as a lower bound
//! (`sph_solver::ContactGuard`), and `project` and the divergence check evaluate the solids
//! only for the particles the bound does not clear (the same bits). In `f32` with AVX-512 the
//! pair passes take sixteen pairs per instruction with no gather: positions with `m` or `λ`
//! packed four `f32` per particle, `m_j` from the pair cache without `s_corr`, the final
//! density's velocities packed `[v, 0]`.
//!
//! **Bound.** Per iteration both passes stream the neighbour indices (2 × 4 B per pair), the
//! pair cache is written and read (2 × 8 B per pair), and about 64 B per particle of particle
//! arrays: 47 MB per iteration for the anchor scene's 1.81 M pairs, i.e. 0.08 µs per
//! particle-iteration at 10 GB/s of single-thread copy bandwidth
//! (`cargo run --release -p benches --example bandwidth`). The loops run several times above
//! that bound: they are compute-bound (about 28 cycles per pair evaluation), the positions of
//! the neighbours being L2 hits after the cell reorder.

mod kernels;
mod lanes;
mod params;
mod passes;
mod scorr;
mod scratch;
mod settings;
mod solver;

pub use kernels::PBF_KERNEL;
pub use params::{
    PbfParams, DEFAULT_RELATIVE_CFM, DEFAULT_SUPPORT_OVER_SPACING, MAX_SOLVER_ITERATIONS,
};
pub use scorr::ArtificialPressure;
pub use scratch::PbfScratch;
pub use settings::PbfSettings;
pub use solver::{ConstraintEval, Pbf, PbfScheme, PBF_PHASES};

pub use neighbour_search::Method;
pub use sph_core::{sampling::cubic_lattice, Aabb, BoxSdf, Inverted, Plane, Sphere};
pub use sph_core::{ParticleSet, Real, Sdf, Vec3};
pub use sph_solver::boundary::{VolumeMapBoundary, VolumeMapCache, VolumeMapOptions};
pub use sph_solver::initial::{calibrate_masses, density_ratios, MassCalibration};
pub use sph_solver::VOLUME_MAP_CONTACT_FRACTION;
pub use sph_solver::{
    Boundary, CollisionBoundary, CommonParams, FluidSolver, FrameSolver, KernelKind, Solids,
    SolverError, SolverState, StepStats, SubstepScheme,
};
