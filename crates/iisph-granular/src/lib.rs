#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Implicit incompressible SPH for water and granular matter ([`Iisph`]), implementing
//!
//! > André Neder, *Real-time Simulation of Granular Matter using Smoothed Particle
//! > Hydrodynamics*, Master's thesis, Universität Koblenz, Institut für Computervisualistik,
//! > January 2024 (Algorithm 1 and §§5.2–5.12),
//!
//! with the parts the thesis leaves open ("…") taken from the works it cites:
//!
//! - IISPH: Markus Ihmsen, Jens Cornelis, Barbara Solenthaler, Christopher Horvath and
//!   Matthias Teschner, "Implicit Incompressible SPH", *IEEE Transactions on Visualization
//!   and Computer Graphics* 20(3):426–435, 2014, doi:10.1109/TVCG.2013.105;
//! - friction: Iván Alduán and Miguel A. Otaduy, "SPH Granular Flow with Friction and
//!   Cohesion", *SCA '11*, pp. 25–32, 2011, doi:10.1145/2019406.2019410;
//! - upscaling: Markus Ihmsen, Arthur Wahl and Matthias Teschner, "High-Resolution
//!   Simulation of Granular Material with SPH", *VRIPHYS '12*, pp. 53–60, 2012,
//!   doi:10.2312/PE/vriphys/vriphys12/053-060;
//! - boundaries: Jan Bender, Tassilo Kugelstadt, Marcel Weiler and Dan Koschier, "Volume
//!   Maps: An Implicit Boundary Representation for SPH", *MIG '19*, 2019,
//!   doi:10.1145/3359566.3360077 (the workspace's `sph_solver::VolumeMapBoundary`);
//! - drag: Christoph Gissler, Stefan Band, Andreas Peer, Markus Ihmsen and Matthias
//!   Teschner, "Generalized Drag Force for Particle-Based Simulations", *Computers &
//!   Graphics* 69:1–11, 2017, doi:10.1016/j.cag.2017.09.002 (in the thesis' simplified form).
//!
//! Water is the same solver without [`GranularParams`] (no friction, no drag).
//!
//! # Shape of the crate
//!
//! Like every solver of the workspace (`sph_solver`'s "Adding a solver"), split by concern
//! with no two files importing each other: `params.rs` ([`IisphParams`],
//! [`GranularParams`], the maxima [`MAX_PRESSURE_ITERATIONS`] and
//! [`MAX_FRICTION_ITERATIONS`]), `kernels.rs` (the cubic spline, [`IISPH_KERNEL`], and the
//! constants of the loops), `scratch.rs` (the per-particle arrays), `passes.rs` (density,
//! advection, predicted density, the pressure solve, forces), `friction.rs` (the
//! friction-stress solve, on top of `passes.rs`), `granular.rs` (stress algebra, drag),
//! `upscale.rs` (passive points) and `solver.rs` ([`IisphScheme`], the
//! [`SubstepScheme`] of one time step, and what it carries between frames). [`Iisph`] is
//! `FrameSolver<R, IisphScheme<R>>`: the workspace's one frame shell runs the frame and
//! implements [`FluidSolver`]; [`IisphScheme::pressure`], [`IisphScheme::stress`] and the
//! pressure-system diagnostics are methods of [`Iisph`] through `Deref`. Between frames it
//! carries the warm-started pressures, the frictional stress and the passive points with
//! their velocities ([`IISPH_STATE_ARRAYS`], [`FluidSolver::save_state`]).
//!
//! # One time step (Algorithm 1)
//!
//! `Δt = dt / substeps`; `∇W_ij = ∇_i W(x_i − x_j)` of the cubic spline (the kernel of the
//! density, of every gradient and of the volume maps, [`IISPH_KERNEL`]); `Ψ_i = Ψ(x_i)` and
//! `∇Ψ_i` from the boundary (`Σ_b V_b W_ib` and `Σ_b V_b ∇W_ib` of eqs. 29–31, 0 for
//! collision walls).
//!
//! 1. **Neighbours** within `h` at `x(t)` (`sph_solver::step::StepNeighbours`).
//! 2. **Density** `ρ_i = Σ_j m_j W_ij + ρ0 Ψ_i` (eqs. 3 and 29, self term included).
//!    **Drag** (eqs. 5–6): `F^drag_i = ½ ρ_a |v_rel|² C_D ω_i A v_rel/|v_rel|` with
//!    `v_rel = v_a − v_i`, `A = π (s/2)²` and `ω_i = 1 − max_j o_ij`, where `o_ij` rises
//!    linearly in `cos φ` from 0 at the cone's edge (half-angle 30° by default) to 1 on its
//!    axis, `φ` being the angle between `x_j − x_i` and the upstream direction `−v_rel`
//!    ([`granular::occlusion`]).
//! 3. **Stress, predicted** (granular): the stress `s_i` is kept from the last step (see
//!    7.) with the friction acceleration `a^f_i = −Σ_j m_j (s_i/ρ_i² + s_j/ρ_j²) ∇W_ij −
//!    ρ0 (s_i/ρ_i²) ∇Ψ_i` (eqs. 26, 31) its solve ended with (at the last step's positions
//!    and densities; permuted with the particles and saved with the state); that `a^f`
//!    enters the advection, so the pressure solve sees the friction that holds the
//!    material. Recomputing it at this step's positions would cost a neighbour pass; step 7
//!    subtracts the same `a^f` for `v^base` and recomputes the friction of the stress, so
//!    the approximation moves only the friction the pressure solve predicts.
//! 4. **Advection** (eqs. 17–18): `v^adv_i = v_i + Δt (g + a^visc_i + F^drag_i/m_i +
//!    a^f_i)`.
//! 5. **Predicted density** (eq. 19 with the boundary term): `ρ^adv_i = ρ_i + Δt Σ_j m_j
//!    (v^adv_i − v^adv_j)·∇W_ij + Δt ρ0 v^adv_i·∇Ψ_i`, and the diagonal (eq. 24 with the
//!    boundary): `a_ii = Σ_j m_j (d_ii − d_ji)·∇W_ij + ρ0 d_ii·∇Ψ_i` with `d_ii = −Δt²/ρ_i²
//!    (Σ_j m_j ∇W_ij + ρ0 ∇Ψ_i)` and `d_ji = −Δt² m_i/ρ_i² ∇W_ji`, evaluated in the closed
//!    form `a_ii = −Δt²/ρ_i² (|Σ_j m_j ∇W_ij + ρ0 ∇Ψ_i|² + m_i Σ_j m_j |∇W_ij|²)`.
//! 6. **Relaxed Jacobi** (eqs. 20–23) from the warm start `p⁰ = p(t − Δt)/2` (Ihmsen et al.
//!    2014 §4): `p^{l+1}_i = max(0, p^l_i + ω (ρ0 − ρ^adv_i − (A p^l)_i) / a_ii)`, `ω = 0.5`,
//!    where `(A p)_i = a_ii p_i + ψ_i` (eqs. 20–22) is evaluated matrix-free through the
//!    pressure accelerations `a^p_i = −Σ_j m_j (p_i/ρ_i² + p_j/ρ_j²) ∇W_ij − ρ0 (p_i/ρ_i²) ∇Ψ_i`
//!    (eqs. 25, 31): `(A p)_i = Δt² (Σ_j m_j (a^p_i − a^p_j)·∇W_ij + ρ0 a^p_i·∇Ψ_i)`, which
//!    expands to exactly `Σ_j m_j (d_ii p_i + Σ_j d_ij p_j − d_jj p_j − Σ_k d_jk p_k)·∇W_ij +
//!    ρ0 (…)·∇Ψ_i` (Ihmsen et al. eq. 12; the tests check the expansion against a literal
//!    dense evaluation of eqs. 20–24). `max(0, ·)` is the unilateral condition of eq. 4 (a
//!    projected Jacobi iteration). The predicted density of the iterate is `ρ^l_i = ρ^adv_i
//!    + (A p^l)_i`; the iterations stop after at least `min_iterations` (2) once the
//!    **average compression** `Σ_i max(ρ^l_i − ρ0, 0) / (N ρ0)` is at most `η` (0.1 %), or
//!    at `max_iterations` (a statistic, [`sph_solver::StepStats::unconverged_substeps`]).
//!    Particles with `a_ii = 0` (no neighbour, no wall) get `p = 0`.
//! 7. **Friction stress and yield** (eqs. 7–14, granular; the `friction` module), after the
//!    pressure solve: `v^base_i = v^adv_i + Δt (a^p_i − a^f_i)` is the velocity without
//!    friction; each iteration takes the strain rate of `v = v^base + Δt a^f(s)`,
//!    `∇u_i = Σ_j V_j (u_j − u_i) ⊗ ∇W_ij − u_i ⊗ ∇Ψ_i` (`V_j = m_j/ρ_j`, walls no-slip),
//!    `ε_i = (∇u_i + ∇u_iᵀ)/2`, corrects the stress `s_i ← Y_i(dev(s_i − 2ω D⁻¹ ε_i))` with the
//!    prototype `D = d I` of eq. 9 and the relaxation `ω = 0.35`
//!    ([`GranularParams::friction_relaxation`]; the thesis's update is `ω = ½`, see the
//!    deviations), the deviatoric part `dev s = s − (Tr s/3) I` and the
//!    Drucker–Prager radial return `Y_i(s) = s · min(1, α p_i / ‖s‖)`, `α = √2 sin θ`
//!    (eqs. 13–14, with this step's pressure; `√2 tan θ` with [`ConeMatch::SimpleShear`],
//!    see below), and recomputes `a^f(s)`. It stops once the
//!    mean strain per step of the particles inside the yield surface, `Σ_i ‖dev ε_i‖ Δt / N`,
//!    is at most `friction_tolerance` (10⁻⁴), or after `friction_max_iterations` (20; a
//!    statistic, `StepStats::unconverged_friction_substeps`).
//! 8. **Forces and integration** (eqs. 25–28, 30–31): `v_i(t+Δt) = v^adv_i + Δt a^p_i`
//!    (water) or `v^base_i + Δt a^f_i(s)` (granular), `x_i(t+Δt) = x_i + Δt v_i(t+Δt)`
//!    (symplectic Euler), then the boundary's contact response (a volume-map boundary
//!    projects only particles closer than its contact distance to a wall, a safety net; the
//!    velocity takes the displacement); for granular matter the contact also applies
//!    Coulomb friction `μ = tan θ` to the tangential velocity (see deviations).
//! 9. **Upscaling** (§5.12, see [`upscale`]): the passive points move with the interpolated
//!    velocity field ([`Iisph::passive_points`], `FluidSolver::passive_points`).
//!
//! # The yield cone's matching and the angle of repose
//!
//! The cone `‖s‖_F ≤ α p` (eq. 14) has one coefficient; a friction angle `θ` fixes it only
//! once one says in which state of stress the cone must agree with Mohr–Coulomb's
//! `|τ| ≤ tan θ · σ_n`. [`GranularParams::cone_match`] ([`ConeMatch`]) names the choice.
//!
//! - **Plane strain** ([`ConeMatch::PlaneStrain`], the default and the thesis's eq. 14,
//!   after Alduán & Otaduy 2011): `α = √2 sin θ`. In plane strain with zero dilatancy the
//!   out-of-plane stress is the mean of the in-plane ones, the Mohr circle's radius is
//!   `‖s‖_F / √2` and its centre `p`, and Mohr–Coulomb (`radius ≤ p sin θ`) is exactly this
//!   cone. Other codes match the same cone differently, which moves the slope it holds
//!   (the `β` below, for θ = 20°, 30°, 40°): the SPH Drucker–Prager model of H. H. Bui,
//!   R. Fukagawa, K. Sako and S. Ohno, "Lagrangian meshfree particles method (SPH) for large
//!   deformation and failure flows of geomaterial using elastic–plastic soil constitutive
//!   model", *Int. J. Numer. Anal. Meth. Geomech.* 32:1537–1570 (2008), doi:10.1002/nag.688,
//!   uses the plane-strain match of an *associated* material, `√J₂ ≤ α_φ I₁` with
//!   `α_φ = tan φ / √(9 + 12 tan² φ)`, i.e. `α = √2 tan θ / √(1 + 4/3 tan² θ)` here
//!   (β = 18.5°, 25.7°, 31.1°); the sand MPM of G. Klár, T. Gast, A. Pradhana, C. Fu,
//!   C. Schroeder, C. Jiang and J. Teran, "Drucker–Prager Elastoplasticity for Sand
//!   Animation", *ACM Trans. Graph.* 35(4):103 (SIGGRAPH 2016), doi:10.1145/2897824.2925906,
//!   uses `α_K = √(2/3) · 2 sin φ / (3 − sin φ)` on `‖ε̂‖_F + α_K tr ε` of the Hencky strain,
//!   the cone through Mohr–Coulomb's triaxial-compression corners, `α = 2√6 sin θ /
//!   (3 − sin θ)` here (β = 24.0°, 34.7°, 43.4°, steeper than `θ`).
//! - **Simple shear** ([`ConeMatch::SimpleShear`]): `α = √2 tan θ`. In simple shear with
//!   equal normal stresses, `s` has only the shear component `τ` (twice, `s_xy = s_yx`), so
//!   `‖s‖_F = √2 |τ|` and the cone reads `|τ| ≤ (α/√2) p = tan θ · p`: Coulomb's law on the
//!   shear plane (β = 20°, 30°, 40°). It is the convention of μ(I)-type continuum codes,
//!   e.g. Project Chrono's CRM (continuous representation model), which bounds
//!   `√(½ s:s) ≤ μ_s p` with `μ_s = tan θ`.
//!
//! **What each predicts for a slope at rest.** A layer at the surface of a heap that has
//! flowed and stopped is sheared parallel to the slope: its stress is close to simple shear
//! on planes parallel to the surface, `‖s‖_F ≈ √2 |τ|`, and with the normal stresses nearly
//! equal `p ≈ σ_n`. The layer holds while `|τ| ≤ (α/√2) σ_n`, and an infinite slope of angle
//! `β` carries `τ/σ_n = tan β`, so it comes to rest at `tan β = α/√2`:
//!
//! - plane strain: `tan β = sin θ`, **β = atan(sin θ)** = 18.9°, 26.6°, 32.7° for θ = 20°,
//!   30°, 40° — the relation of E. H. Davis, "Theories of plasticity and the failure of soil
//!   masses", in I. K. Lee (ed.), *Soil Mechanics: Selected Topics*, Butterworths, London,
//!   1968, pp. 341–380, for a non-associated material with zero dilatancy
//!   (`tan φ* = sin φ cos ψ / (1 − sin φ sin ψ)` at `ψ = 0`), which incompressible IISPH
//!   imposes;
//! - simple shear: `tan β = tan θ`, **β = θ**: the friction angle is the angle of repose.
//!
//! [`ConeMatch::predicted_repose_angle_deg`] returns `atan(α/√2)` (`= atan(3 α_φ)`, [`cone_alpha`]). The Coulomb friction at
//! walls (see the deviations) uses `μ = tan θ` under either match. The thesis's match is the
//! default so that its experiments run as printed; the workspace's repose scenes
//! (`scenes/granular_repose_thesis_*.toml`) choose `cone_match = "simple-shear"`, so that
//! `friction_angle_deg` is the angle a heap stands at, and the `granular-repose` experiment
//! measures both matches against these predictions.
//!
//! # Deviations and choices where the thesis is silent
//!
//! - **Sign of the stress.** The thesis writes `s = D⁻¹ε` (eq. 10). With the force of
//!   eq. 26 (`F^f = −m Σ m_j (s_i/ρ_i² + s_j/ρ_j²)∇W_ij ≈ −(m/ρ) ∇·s`) a stress along `+ε`
//!   would accelerate the deformation; the stress that cancels the strain rate within one
//!   step, as Alduán & Otaduy (2011, §4.1) intend, is `s = −D⁻¹ε`: a stress `s_i` changes
//!   the velocity gradient by `≈ (Δt m²/ρ²) Σ_j (1/ρ_j) ∇W_ij ∇W_ijᵀ s_i = (D/2) s_i`, the
//!   factor 2 of eq. 9 counting the symmetric `s_j` term, so `Δε = D s`, and `Δε = −ε`
//!   requires `s = −D⁻¹ε`.
//! - **Velocity gradient** (eq. 7 prints `Σ_j V_j ∇W_ij u_jᵀ`): we use the difference form
//!   `Σ_j V_j (u_j − u_i) ⊗ ∇W_ij`, zero for a uniform flow also at a free surface, and in
//!   the orientation `(∇u)_ab = ∂u_a/∂x_b` (the strain is its symmetric part either way).
//! - **Prototype `D`** (eq. 9): evaluated once for a particle in a full simple cubic lattice
//!   of spacing `s` with `ρ_i = ρ_j = ρ0`, `m = ρ0 s³`; on that lattice `D` is exactly
//!   isotropic, `D = d I`, so `D⁻¹ε = ε/d` ([`granular::prototype_friction_coefficient`]).
//! - **Deviatoric part**: `Tr s / 3` (3D) instead of the thesis' `Tr s / 2`.
//! - **The stress is solved implicitly, not computed once.** Algorithm 1 computes `s = D⁻¹ε`
//!   once per step from the velocities at the step's start (line 3) and clamps it in the
//!   pressure loop (line 11). Implemented literally (as this crate first did), that stress
//!   only cancels the strain rate of the previous step: the pressure and gravity of every
//!   step shear the material anew, so it behaves like a strong viscosity and creeps. A
//!   column of aspect ratio 2.7 at θ = 40° kept spreading at about 1 `L0` per 0.1 s, and
//!   slumped heaps settled at 6.6°, 10.6° and 10.5° for θ = 20°, 30° and 40° (quick
//!   `granular-repose` scenes, 2026-11-23). Alduán & Otaduy (2011) treat friction as a
//!   rigidity constraint solved iteratively alongside the pressure; we follow them. The
//!   stress is a state of the particle (kept between steps, permuted with them), its
//!   friction enters the pressure solve's advection, and after the pressure solve it is
//!   corrected by relaxed Jacobi iterations of the thesis' own update `s ← s − D⁻¹ε`, with
//!   the yield criterion applied in every iteration (step 7 above), relaxed (next item).
//!   With it the same column stops (front 2.03 `L0` at 0.8 s, 2.05 at 1.2 s, `tests/solver.rs`) and the heaps
//!   stand at 15.3°, 22.5° and 27.6° (15.0°, 24.0° and 31.1° when the scenes also start
//!   uncompressed at the walls, `initial_masses = "calibrated"`; these figures are of the
//!   thesis's relaxation ½).
//!   Solving the friction before the pressure instead (with the last step's pressure in
//!   the yield bound and in the predicted velocity, nearer Algorithm 1's line order, and
//!   then incompressible as a water step) cut the 100k pile's pressure iterations from 15
//!   to 9.4 per step and its step time by 10 %, but let the `a = 4` column run into the
//!   far wall (runout 8.1 `L0` against 6.75) and lowered the 40° heap to 25.7° (quick
//!   experiments, 2026-11-23); we keep the order after the pressure solve.
//! - **Relaxation of the stress update** ([`GranularParams::friction_relaxation`], `ω =
//!   0.35`, [`DEFAULT_FRICTION_RELAXATION`]). A stress `s_i` changes its own strain rate by
//!   `(D/2) s_i` (see the sign above), so the thesis's `s ← s − D⁻¹ε` is a Jacobi step
//!   relaxed by ½ on that self-coupling, and `s ← s − 2ω D⁻¹ε` relaxes it by `ω`. A relaxed
//!   Jacobi iteration converges only if `ω λ < 2` for every eigenvalue `λ` of the operator
//!   (strain rate from stress) relative to its diagonal. On the prototype lattice (a full
//!   simple cubic lattice, uniform density, so `Σ_j ∇W_ij = 0`) the operator is a
//!   convolution: a stress wave `S e^{ik·x}` causes the strain rate `c sym(S g gᵀ)` with `c
//!   = V Δt m/ρ0²` and `g(k) = Σ_r sin(k·r) ∇W(r)` (`r` the lattice offsets), whose
//!   eigenvalues on deviatoric `S` are `(2/3) c |g|²` (the mode along `g`), `c |g|²/2`
//!   (twice) and 0 (twice); the diagonal is `c Σ_r |∇W(r)|²/3`, the symbol's mean (Parseval).
//!   For the cubic spline at `h = 2 s` the largest ratio is `λ_max = 5.64`, at `k ≈ 0.33 π/s
//!   (1, 1, 1)` (the checkerboard `k = π/s` is in the wide stencil's null space), so the
//!   update is stable for `ω < 2/5.64 = 0.355`; 0.35 is just inside, near the optimum
//!   `2/(λ_min + λ_max)` for smooth modes (`λ_min → 0`). At the thesis's ½ (`ω λ_max = 2.8`)
//!   those modes grow by 1.8 per iteration until the yield cone clips them: that is the
//!   residual that stalled at 2–3·10⁻⁴ per step with the solve at its cap, and the clipped
//!   stress pattern raises the density (dam break, 100 steps: max `ρ/ρ0` 1.144 at ½, 1.034
//!   at 0.35, 1.029 at 0.25); a larger `ω` (0.75, 1.0) meets the tolerance in fewer
//!   iterations only because it drives more particles onto the cone (max `ρ/ρ0` 1.118,
//!   1.094). `friction::tests::friction_symbol_bound` recomputes `λ_max` and the Parseval
//!   check. Other kernels or ratios `h/s` have another bound.
//! - **Yield criterion**: radial return to the Drucker–Prager cone in the Frobenius norm
//!   (Alduán & Otaduy 2011); the thesis' per-component approximation is not used.
//! - **Coulomb friction at contacts** (not in the thesis). A particle with `p = 0` (an
//!   under-dense free-surface grain) has no Drucker–Prager friction at all, so single
//!   grains thrown ahead slid along the floor to the tank's end walls. Where the boundary's
//!   contact response pushes a granular particle out of a wall, its tangential velocity
//!   loses up to `tan θ` times the normal velocity change (Coulomb's law with the
//!   material's friction angle). With it (and lattice masses) the heaps no longer reached
//!   the end walls except for θ = 20°, and the column-collapse runouts for `a ≤ 2` moved
//!   into Lube et al.'s band; with calibrated initial masses as well, all five aspect
//!   ratios are in it.
//! - **Integration** (eq. 27 names only `F^p`): the friction force of line 14 is added.
//! - **Viscosity.** The thesis has none. `viscosity` (kinematic, m²/s, default 0) adds the
//!   explicit SPH viscosity of Monaghan (1992)/Morris et al. as used by SPlisHSPlasH's
//!   "standard" viscosity, `a^visc_i = 2 (d+2) ν Σ_j (m_j/ρ_j) (v_ij·x_ij)/(|x_ij|² + 0.01 h²)
//!   ∇W_ij` (`d = 3`), to the advection forces.
//! - **Drag**: the thesis' occlusion "smallest angle … subtracted from 1" is made
//!   dimensionless as above; the air density is 1.2041 kg/m³; a uniform air velocity.
//! - **Stopping rule**: the average of the clamped compression (surface particles with
//!   `p = 0` below `ρ0` are not errors; eq. 23's absolute value would count them).
//! - **Kernel**: the cubic spline (as SPlisHSPlasH's IISPH), support `h = 2 s` by default;
//!   the thesis does not name its kernel.
//!
//! # Measured behaviour (tests in `tests/solver.rs`, f64, `s = 0.025 m`, Δt = 2 ms)
//!
//! - **Water at rest**: a 10³ block filling the bottom of a tank (volume-map walls) settles
//!   with 2–3 iterations per step, max `ρ/ρ0` ≤ 1.007, the surface still within 0.1 `s`
//!   over the last 20 frames, kinetic energy 2.8·10⁻³ `m g H` after 1 s (no viscosity:
//!   nothing damps the sloshing the settling starts).
//! - **Initial compression at walls.** A lattice of masses `ρ0 s³` with its outer layers
//!   `s/2` from volume-map walls starts 3.8 % above `ρ0` next to one wall and 7.5 % in a
//!   corner (the map integrates the wall continuously; the fluid is a lattice sum). IISPH
//!   removes that within one time step, which throws such a block up (kinetic energy 12 J
//!   for 15.6 kg in the first frame). SPlisHSPlasH starts its fluids under-dense (particle
//!   volume `0.8 (2r)³`) for the same reason; the tests scale the masses so that no
//!   particle starts compressed, and scene files choose `[boundary] initial_masses =
//!   "calibrated"` (`sph_solver::initial::calibrate_masses`), as the IISPH and granular
//!   scenes do.
//! - **Friction.** A column of aspect ratio 2.7 with θ = 40° spreads 1.6 `L0` in 0.4 s
//!   against 5.3 `L0` for water and then stops (2.03 `L0` at 0.8 s, 2.05 at 1.2 s). The
//!   released blocks of the earlier repose scenes (collapse deposits, 2 s, plane-strain
//!   cone) stood at 15.0°, 24.0°, 31.1° for θ = 20°, 30°, 40°, their steepest 5 cm at
//!   17.3–18.1°, 25.6–26.4°, 33.7–35.6°, near `atan(sin θ)`. Fixed-base heaps
//!   (`granular-repose`, quick, 3-particle slab) stand 3.7–5.7° above the prediction of
//!   either match (23.7°, 34.8°, 43.7° simple shear; 22.7°, 32.3°, 38.4° plane strain, at
//!   4 s, with the friction relaxation 0.35; 23.7°, 34.9°, 43.9° and 22.4°, 31.6°, 38.2°
//!   at ½, the heaps 2–4 % lower): see that experiment's deviations. Planar column collapses of aspect ratio 0.5–7 run out 0.56, 1.12, 2.11,
//!   3.86 and 5.73 `L0`, within ±30 % of Lube et al.'s (2005) law
//!   (`granular-column-collapse`). At the thesis's relaxation ½ the friction solve often
//!   stopped at its 20-iteration cap with a mean unyielded strain of 2–3·10⁻⁴ per step
//!   (400 iterations left that residual and the angle, 19.2° against 19.8° at 50 on a flat
//!   0.6 m × 0.15 m block at θ = 30°, unchanged; 10 iterations gave 21.7°): the unstable
//!   modes of the deviations above. At `ω = 0.35` the dam break's solve (59,319 particles,
//!   100 steps) meets the tolerance in 1–4 iterations (1.92 per step, none at the cap,
//!   against 2.35 per step and 2 at the cap at ½).
//!
//! # Performance: method and bound
//!
//! Per time step: one neighbour search; a density pass computes `ρ_i`, `∇Ψ_i`, `a_ii` and
//! caches `W'(r)/r` of every pair in the CSR order of the neighbour lists (one square root
//! per pair per step), so the later passes recompute `∇W_ij = (x_i − x_j) W'(r)/r` from
//! positions without a square root; the advection needs no neighbour loop for water
//! (gravity only); the predicted density pass also computes the pressure accelerations of
//! the warm start (the first half of iteration 0). Each Jacobi iteration is then two
//! neighbour passes (one for the first): (1) `a^p_i` reads per pair the neighbour index
//! (4 B), the cached scale (`size_of::<R>()`), `x_j` (3R), `m_j` and `p_j/ρ_j²` (2R); (2)
//! `(A p)_i` and the update read the index, the scale, `x_j`, `m_j` and `a^p_j` (3R). The
//! per-particle arrays (`x`, `m`, `p/ρ²`, `a^p`: 8R = 32 B in f32) of 10⁵ particles fit in
//! the last-level cache, so the memory traffic per iteration is the streamed index and
//! scale arrays, `2 × (4 + size_of::<R>())` = 16 B (f32) or 24 B (f64) per neighbour pair
//! (≈ 30 MB per iteration for the 59k-particle dam break's 1.9 M pairs in f32), plus
//! 2 × 32 B per particle; a pass does about 20 flops per pair, so on one core it is bound
//! by the arithmetic, not by memory bandwidth. A water step with `k` iterations is
//! `2k + 3` neighbour passes (density, predicted density, `2k − 1` iteration passes, forces,
//! and the density at the end positions of the frame's last substep); the granular model
//! adds the base velocity (one pass) and two passes per friction iteration (strain rate
//! and stress update; friction acceleration with the trial velocities), each reading a
//! 6-component stress or a velocity per pair: `2k_f + 1` passes for `k_f` friction
//! iterations, so with the default cap of 20 a granular step can cost several water
//! steps. What the granular step adds beyond that is folded into passes that run anyway:
//! the drag's occlusion is taken in the density pass (it needs the pair's offset and
//! distance), the kept stress's friction is carried from the last step (step 3),
//! `V_j = m_j/ρ_j` is computed once per step, and the friction acceleration reads
//! `m_j s_j/ρ_j²` and the density pass's `G_i = Σ_j m_j ∇W_ij + ρ0 ∇Ψ_i`
//! (`a^f_i = −(s_i/ρ_i²) G_i − Σ_j (m_j s_j/ρ_j²) ∇W_ij`, one symmetric product per pair).
//! Every parallel loop writes one particle's values and reduces in fixed chunks, so results
//! are bitwise identical for any number of threads.
//!
//! In `f32` on a processor with AVX-512 (detected at run time), the density pass
//! (`sph_solver::pair_lanes`) and the pressure passes (the predicted density with the warm
//! start's accelerations, both halves of each Jacobi iteration, the forces) take sixteen
//! pairs of one particle per instruction, every neighbour value loaded from arrays packed
//! four `f32` per particle (`[x, y, z, m]`, `[x, y, z, m p/ρ²]`, `[a^p, m]`, `[v^adv, m]`,
//! refilled where their values change, one pass over the particles each) and transposed,
//! never gathered; the pressure sum is taken as `(p_i/ρ_i²) Σ_j m_j ∇W_ij + Σ_j (m_j p_j/ρ_j²)
//! ∇W_ij`, the first sum from the density pass. The sums differ from the scalar loops' by
//! their order only (and the pressure sum by that split), within the bound the lanes' tests
//! check; `f64` and processors without AVX-512 take the scalar loops. The granular model's
//! friction passes stay scalar.
//!
//! The contact response and the divergence check evaluate the solids only for the particles
//! a carried distance bound does not clear (`sph_solver::ContactGuard`, from the distances
//! evaluated with the end-of-step volume samples, which are skipped beyond the map's
//! support): the same bits.

mod friction;
pub mod granular;
mod kernels;
mod lanes;
mod params;
mod passes;
mod scratch;
mod settings;
mod solver;
pub mod upscale;

pub use kernels::IISPH_KERNEL;
pub use params::{
    cone_alpha, ConeMatch, GranularParams, IisphParams, AIR_DENSITY, DEFAULT_CONE_MATCH,
    DEFAULT_DRAG_CONE_HALF_ANGLE_DEG, DEFAULT_FRICTION_MAX_ITERATIONS, DEFAULT_FRICTION_RELAXATION,
    DEFAULT_FRICTION_TOLERANCE, DEFAULT_MAX_ITERATIONS, DEFAULT_MIN_ITERATIONS,
    MAX_FRICTION_ITERATIONS, MAX_PRESSURE_ITERATIONS,
};
pub use settings::{GranularSettings, IisphSettings, WaterSettings};
pub use solver::{Iisph, IisphScheme, IISPH_PHASES, IISPH_STATE_ARRAYS};

pub use sph_core::{
    sampling::cubic_lattice, Aabb, BoxSdf, Inverted, ParticleSet, Plane, Real, Sdf, Sphere, Vec3,
};
pub use sph_solver::boundary::{VolumeMapBoundary, VolumeMapCache, VolumeMapOptions};
pub use sph_solver::initial::{calibrate_masses, density_ratios, MassCalibration};
pub use sph_solver::{
    Boundary, CollisionBoundary, CommonParams, FluidSolver, FrameSolver, KernelKind, Solids,
    SolverError, SolverState, StepStats, SubstepScheme, VOLUME_MAP_CONTACT_FRACTION,
};
