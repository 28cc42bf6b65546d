//! The PCISPH baseline of Solenthaler & Pajarola (2009): [`Pcisph`], [`PcisphParams`].

use std::fmt;
use std::time::Instant;

use neighbour_search::{HashedGrid, Method, NeighbourLists, NeighbourSearch};
use rayon::prelude::*;
use sph_core::{ParticleSet, Real, Sdf, Vec3};
use sph_kernels::{Kernel, Poly6, Spiky};

use crate::solver::{
    check_divergence, check_masses, check_predicted, collide, density_energy_stats,
    find_step_neighbours, CellReorder, MIN_LEN, REDUCE_CHUNK,
};
use crate::{PbfError, PbfParams, Solids, StepStats};

/// Parameters of [`Pcisph`]. Lengths are absolute, in metres; SI units throughout.
///
/// Build them with [`PcisphParams::for_spacing`] (or [`Default`], `for_spacing(0.025)`),
/// change fields as needed, and let [`Pcisph::new`] check them with
/// [`PcisphParams::validate`].
///
/// | field | default | source |
/// | --- | --- | --- |
/// | `rest_density` | 1000 kg/m³ | water (as [`PbfParams`]) |
/// | `particle_spacing` | given (0.025 m for `Default`) | scene; also the prototype lattice of `δ` (S&P09 eq. 8) |
/// | `support_radius` | `2 s` | as [`PbfParams`] ([`crate::DEFAULT_SUPPORT_OVER_SPACING`]), so both solvers see the same neighbourhoods |
/// | `dt` | 0.016 s | Macklin & Müller §8: a frame of 16 ms |
/// | `substeps` | 10 | Macklin & Müller §8: PCISPH "with 10 sub-steps" (Δt = 1.6 ms; "not stable with less than 10") |
/// | `pressure_iterations` | 4 | Macklin & Müller §8: "4 pressure iterations" |
/// | `density_error_tolerance` | `None` (no early stop) | S&P09's `η` (relative, e.g. 0.01 = 1 %), on the maximum compression |
/// | `clamp_negative_pressure` | `true` | SPlisHSPlasH's clamping of the density error to ≥ 0; S&P09 do not clamp (`false`), which makes SDF-bounded fluids collapse into clumps (see below) |
/// | `xsph_c` | 0.01 | PBF's XSPH (Macklin & Müller eq. 17), replacing S&P09's viscosity force |
/// | `gravity` | (0, −9.81, 0) m/s² | standard gravity along −y |
/// | `reorder_every` | 10 | as [`PbfParams`] (locality of the CPU loops) |
/// | `neighbour_method` | [`Method::CellStartGrid`] | as [`PbfParams`] |
#[derive(Debug, Clone, PartialEq)]
pub struct PcisphParams<R: Real> {
    /// Rest density `ρ0` (kg/m³).
    pub rest_density: R,
    /// Particle spacing `s` (m): the prototype lattice of `δ`, the particle mass `ρ0 s³`
    /// ([`PcisphParams::particle_mass`]) and the collision radius `s / 2`.
    pub particle_spacing: R,
    /// Support radius `h` (m) of the Poly6 and Spiky kernels. Must exceed `particle_spacing`.
    pub support_radius: R,
    /// Time advanced by one [`Pcisph::step`] call (s): `substeps` steps of `dt / substeps`.
    pub dt: R,
    /// Time steps per [`Pcisph::step`] call (≥ 1).
    pub substeps: usize,
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
    /// External acceleration (m/s²).
    pub gravity: Vec3<R>,
    /// Reorder the particles by cell at the start of every `reorder_every`-th
    /// [`Pcisph::step`] call, starting with the first; 0 never reorders.
    pub reorder_every: usize,
    /// Neighbour search method (found once per time step at the current positions).
    pub neighbour_method: Method,
}

impl<R: Real> Default for PcisphParams<R> {
    /// [`PcisphParams::for_spacing`] with `s = 0.025 m`.
    fn default() -> Self {
        Self::for_spacing(R::of_f64(0.025))
    }
}

impl<R: Real> PcisphParams<R> {
    /// The defaults of the table above for particle spacing `s` (m). Not validated here.
    pub fn for_spacing(s: R) -> Self {
        Self {
            rest_density: R::of_f64(1000.0),
            particle_spacing: s,
            support_radius: s * R::of_f64(crate::DEFAULT_SUPPORT_OVER_SPACING),
            dt: R::of_f64(0.016),
            substeps: 10,
            pressure_iterations: 4,
            density_error_tolerance: None,
            clamp_negative_pressure: true,
            xsph_c: R::of_f64(0.01),
            gravity: Vec3::new(R::zero(), R::of_f64(-9.81), R::zero()),
            reorder_every: 10,
            neighbour_method: Method::CellStartGrid,
        }
    }

    /// The [`PbfParams`] with the same shared fields (PBF-only fields neutral), whose
    /// validation and lattice sums are reused.
    fn shared(&self) -> PbfParams<R> {
        PbfParams {
            rest_density: self.rest_density,
            particle_spacing: self.particle_spacing,
            support_radius: self.support_radius,
            dt: self.dt,
            substeps: self.substeps,
            solver_iterations: 1,
            mean_compression_tolerance: None,
            min_solver_iterations: 1,
            cfm_epsilon: R::one(),
            clamp_negative_constraint: false,
            scorr_k: R::zero(),
            scorr_n: 1,
            scorr_delta_q: R::of_f64(0.5),
            vorticity_epsilon: R::zero(),
            xsph_c: self.xsph_c,
            gravity: self.gravity,
            reorder_every: self.reorder_every,
            neighbour_method: self.neighbour_method,
        }
    }

    /// Particle mass `ρ0 s³` (kg) of a fluid sampled on a simple cubic lattice of spacing `s`
    /// (the prototype mass of `δ`).
    pub fn particle_mass(&self) -> R {
        self.shared().particle_mass()
    }

    /// Collision radius `s / 2` (m).
    pub fn particle_radius(&self) -> R {
        self.shared().particle_radius()
    }

    /// Length of one time step, `Δt = dt / substeps` (s).
    pub fn substep_dt(&self) -> R {
        self.shared().substep_dt()
    }

    /// The scaling factor `δ` of S&P09 eq. 8 (m²/s², i.e. Pa per kg/m³ of density error):
    /// `δ = −1 / (β (−Σ_j ∇W_ij · Σ_j ∇W_ij − Σ_j ∇W_ij · ∇W_ij))`, `β = Δt² m² 2/ρ0²`, for a
    /// prototype particle in a full simple cubic lattice of spacing `s` (Spiky gradients,
    /// every lattice point within `h`), `m = ρ0 s³` and `Δt` = [`PcisphParams::substep_dt`].
    /// Errors (naming `support_radius`) when `s`, `h` or the result are not usable.
    pub fn scaling_factor(&self) -> Result<R, PbfError> {
        let bad = |reason| PbfError::InvalidParameter {
            name: "support_radius",
            value: self.support_radius.as_f64(),
            reason,
        };
        // D_ref = (m/ρ0)² (Σ_j ∇W_ij · Σ_j ∇W_ij + Σ_j ∇W_ij · ∇W_ij).
        let d_ref = self
            .shared()
            .reference_denominator()
            .ok_or_else(|| bad("no prototype lattice for this spacing and support radius"))?;
        let (m, rho0, dt) = (self.particle_mass(), self.rest_density, self.substep_dt());
        let vol = m / rho0;
        let sums = d_ref / (vol * vol);
        let two = R::of_f64(2.0);
        let beta = dt * dt * m * m * two / (rho0 * rho0);
        let delta = -R::one() / (beta * -sums);
        if delta.is_finite_value() && delta > R::zero() {
            Ok(delta)
        } else {
            Err(bad(
                "the scaling factor δ (eq. 8) is not finite and positive",
            ))
        }
    }

    /// Checks every field; the error ([`PbfError::InvalidParameter`]) names the first invalid
    /// one.
    pub fn validate(&self) -> Result<(), PbfError> {
        if self.pressure_iterations == 0 {
            return Err(PbfError::InvalidParameter {
                name: "pressure_iterations",
                value: 0.0,
                reason: "must be >= 1",
            });
        }
        if let Some(t) = self.density_error_tolerance {
            if !(t.is_finite_value() && t > R::zero()) {
                return Err(PbfError::InvalidParameter {
                    name: "density_error_tolerance",
                    value: t.as_f64(),
                    reason: "must be finite and > 0 (or None for no early stop)",
                });
            }
        }
        // The shared fields, checked (and named) as PBF checks them.
        self.shared().validate()?;
        self.scaling_factor()?;
        Ok(())
    }
}

/// Kernels and constants of the per-particle loops.
#[derive(Debug, Clone, Copy)]
struct Consts<R: Real> {
    poly6: Poly6<R>,
    spiky: Spiky<R>,
    /// `W(0)` of Poly6: the self term of the density sum.
    w0: R,
    inv_rho0: R,
    /// `1/ρ0²` of the pressure force.
    inv_rho0_sq: R,
    delta: R,
}

impl<R: Real> Consts<R> {
    fn new(p: &PcisphParams<R>) -> Result<Self, PbfError> {
        let h = p.support_radius;
        let poly6 = Poly6::new(h)?;
        let inv_rho0 = R::one() / p.rest_density;
        Ok(Self {
            poly6,
            spiky: Spiky::new(h)?,
            w0: poly6.value_r2(R::zero()),
            inv_rho0,
            inv_rho0_sq: inv_rho0 * inv_rho0,
            delta: p.scaling_factor()?,
        })
    }
}

/// Per-particle working arrays (structure of arrays), kept between steps.
#[derive(Debug, Clone, Default)]
struct Scratch<R: Real> {
    /// Velocity after the non-pressure velocity change (XSPH), `v_i` of the loop.
    velocity: Vec<Vec3<R>>,
    /// Predicted positions `x*` (after collision response); at the end, the final positions.
    predicted: Vec<Vec3<R>>,
    pressure: Vec<R>,
    /// Pressure acceleration `F^p_i / m_i`.
    accel: Vec<Vec3<R>>,
    density: Vec<R>,
    velocity_new: Vec<Vec3<R>>,
    partials: Vec<[f64; 3]>,
}

impl<R: Real> Scratch<R> {
    fn resize(&mut self, n: usize) {
        if self.predicted.len() == n {
            return;
        }
        let z = Vec3::zeros();
        self.velocity.resize(n, z);
        self.predicted.resize(n, z);
        self.pressure.resize(n, R::zero());
        self.accel.resize(n, z);
        self.density.resize(n, R::zero());
        self.velocity_new.resize(n, z);
        self.partials.resize(n.div_ceil(REDUCE_CHUNK), [0.0; 3]);
    }
}

/// The PCISPH solver, the baseline of
///
/// > Barbara Solenthaler and Renato Pajarola, "Predictive-Corrective Incompressible SPH",
/// > *ACM Transactions on Graphics* 28(3), Article 40, 2009 (SIGGRAPH 2009),
///
/// as Macklin & Müller (2013, §8) use it for comparison: PCISPH with 10 substeps and 4
/// pressure iterations per 16 ms frame against PBF with 4 substeps and 10 iterations ("so
/// that each performs 40 pressure iterations per-frame in total").
///
/// # What is implemented
///
/// One [`Pcisph::step`] call is one frame of `substeps` time steps of `Δt = dt / substeps`;
/// each time step is the paper's predictive-corrective loop:
///
/// 1. neighbours within `h` found **once**, at the current positions `x(t)`
///    (`neighbour_search::CellStartGrid`, the same search as [`crate::Pbf`]);
/// 2. non-pressure forces: gravity, and the XSPH velocity filter of PBF (see deviations);
///    pressure `p_i = 0` and pressure acceleration `a^p_i = 0`;
/// 3. `pressure_iterations` times (or fewer with `density_error_tolerance`):
///    - predict `v*_i = v_i + Δt (g + a^p_i)`, `x*_i = x_i + Δt v*_i`, then the collision
///      response of PBF (`collide`, Algorithm 1 line 14 of Macklin & Müller) applied to `x*_i`;
///    - predict the density `ρ*_i = Σ_j m_j W(x*_i − x*_j)` (Poly6, self term included, over
///      the neighbours of step 1) and the density error `ρ*_err,i = ρ*_i − ρ0`;
///    - update the pressure `p_i ← p_i + δ ρ*_err,i` with the precomputed scaling factor `δ`
///      of **eq. 8**;
///    - compute the pressure force (the symmetric form of **eqs. 5–6**, with `ρ0`, see below)
///      at the current positions `x(t)`: `a^p_i = F^p_i / m_i = −Σ_j m_j (p_i/ρ0² + p_j/ρ0²)
///      ∇W_ij` (Spiky gradient, `∇W_ij = ∇W(x_i(t) − x_j(t))`);
/// 4. `v_i(t+Δt) = v_i + Δt (g + a^p_i)`, `x_i(t+Δt) = x_i + Δt v_i(t+Δt)` with the last
///    pressure force, followed by the same collision response, the velocity taking the
///    displacement of the response (`v += (x_collided − x_uncollided) / Δt`: PBF's line 21
///    for a projected particle, the unchanged velocity otherwise).
///
/// **Scaling factor (eq. 8).** `δ = −1 / (β (−Σ_j ∇W_ij · Σ_j ∇W_ij − Σ_j ∇W_ij · ∇W_ij))`
/// with `β = Δt² m² 2/ρ0²`, evaluated once, in [`PcisphParams::scaling_factor`], for a
/// prototype particle at the origin of a full simple cubic lattice of spacing
/// `particle_spacing` (all lattice points within `h`) with the prototype mass
/// `m = ρ0 s³` ([`PcisphParams::particle_mass`]) and the substep `Δt`. (The two sums are
/// `D_ref / (m/ρ0)²` with PBF's [`PbfParams::reference_denominator`] `D_ref`, which is how
/// they are computed, so that `δ = 1 / (2 Δt² D_ref)`.) `δ` is in Pa·m³/kg = m²/s²; it is
/// 327 m²/s² at `s = 0.025 m`, `h = 0.05 m`, `Δt = 1.6 ms`.
///
/// **Pressure force.** `F^p_i = −m_i Σ_j m_j (p_i/ρ0² + p_j/ρ0²) ∇W_ij`: the symmetric
/// (momentum-conserving) SPH pressure force with the rest density in place of `ρ_i`, `ρ_j` in
/// the denominators. This is the form of the paper's derivation of `δ` (eq. 5 with `p_i = p_j
/// = p̃_i` and `ρ_i = ρ_j = ρ0`: `F^p_i = −m² Σ_j (2 p̃_i/ρ0²) ∇W_ij`), so that the linear model
/// behind `δ` is exact for the prototype, and it is what SPlisHSPlasH's `TimeStepPCISPH` does.
/// Using the (predicted) densities `ρ_i²` instead would change the effective stiffness by
/// `(ρ0/ρ_i)²` and blow up for isolated particles.
///
/// **Table of the mapping onto [`StepStats`]** (the PBF type is reused so a scene runner can
/// treat both solvers alike):
///
/// | field | PCISPH meaning |
/// | --- | --- |
/// | `integrate_s` | input checks, XSPH, gravity and the first prediction (steps 2 and 3's first prediction) |
/// | `create_hash_grid_s`, `detect_neighbours_s` | the neighbour search of step 1 (build, query) |
/// | `constraint_solve_s` | the pressure iterations (step 3: density prediction, pressure update, pressure force, prediction with collisions) |
/// | `velocity_update_s` | step 4: final velocities, densities at the final positions, blow-up checks, writing the state, statistics |
/// | `reorder_s`, `reordered` | as for PBF |
/// | `substeps` | time steps done |
/// | `iterations` | pressure iterations done in total (`substeps × pressure_iterations` without early stop) |
/// | `neighbour_pairs` | ordered pairs of the last substep's neighbour lists |
/// | `max_density_ratio`, `mean_density_ratio` | `ρ_i/ρ0` at the final positions (with the last substep's neighbour lists) |
/// | `kinetic_energy` | `Σ m_i \|v_i\|² / 2` at the end (J) |
///
/// # Deviations from Solenthaler & Pajarola (2009)
///
/// - **Viscosity.** S&P09 include an SPH viscosity force in the non-pressure forces `F^v`.
///   Here the viscosity is PBF's XSPH filter (Macklin & Müller eq. 17, `c = 0.01`, volumes
///   `m_j/ρ0`, Poly6), `v_i ← v_i + c Σ_j (m_j/ρ0) (v_j − v_i) W(x_i − x_j)`, applied as a
///   non-pressure velocity change at the start of each time step (at `x(t)`, with the
///   neighbours of step 1), so that the comparison with PBF isolates the pressure solver.
/// - **Boundaries.** S&P09 handle boundaries with their own collision handling; here the
///   solids are signed distance fields with exactly PBF's response (projection to the
///   particle radius `s/2` along the SDF gradient, no friction or restitution), applied to
///   the predicted positions inside each iteration and to the final positions.
/// - **Iteration count.** The paper iterates until the density error is below `η` (with a
///   minimum number of iterations; SPlisHSPlasH uses at least 3). Here `pressure_iterations`
///   is a fixed count by default (the PBF paper's comparison: 4), and
///   `density_error_tolerance = Some(η)` stops early after the first iteration whose
///   **maximum** predicted relative compression `max_i max(ρ*_i/ρ0 − 1, 0)` is at most `η`
///   (the pressure and force of that iteration are still applied; no minimum count).
///   Particles below the rest density (free surface) do not count, otherwise a free surface
///   would never satisfy any tolerance. (SPlisHSPlasH checks the *mean* clamped error.)
/// - **Negative pressures are clamped by default** (`clamp_negative_pressure = true`): the
///   density error is clamped to `≥ 0` before the pressure update, as SPlisHSPlasH does
///   (`densityAdv = max(densityAdv, 1)`), so pressures are never negative. S&P09 do not
///   clamp; `false` gives their form, with which a fluid bounded by SDF walls collapses into
///   clumps (measured below), so it is not a usable default for the comparison.
/// - **Masses.** Densities and forces use the particles' own masses; `δ` uses the prototype
///   mass `ρ0 s³` (the paper's particles all have the same mass `m`).
/// - **Neighbours** for the predicted densities are those of `x(t)` (the paper's "once per
///   time step"), so a pair that only comes within `h` at the predicted positions is missed.
///
/// # Measured behaviour (1000-particle block at rest in a tank, SDF walls)
///
/// 10 × 10 × 10 particles at `s = 0.025 m` filling the bottom of a tank of 10 × 20 × 10
/// spacings, 10 substeps × 4 iterations per 16 ms frame (`tests/pcisph.rs`):
///
/// - **Unclamped (`clamp_negative_pressure = false`, S&P09):** the block collapses into clumps within two frames
///   (mean `ρ/ρ0` 2.4 after 2 frames, 3.3 after 4; pressures down to −1.05·10⁶ Pa; kinetic
///   energy 5·10⁵ J). The wall and free-surface particles lack neighbours (the SDF walls
///   contribute no density), so their density error is negative every iteration and their
///   accumulated pressure pulls their neighbours in: the particle-deficiency problem the PBF
///   paper mentions (§8: "each iteration makes its pressure increasingly negative").
///   No NaN and no error results; the state is just meaningless.
/// - **Clamped** (`clamp_negative_pressure = true`, the default): the compression is held (max `ρ/ρ0`
///   1.016 at t = 1 s and at most 1.023 over the run in f64; 1.006 and 1.052 in f32), but
///   with XSPH `c = 0.01` as the only damping the block does not come to rest: the kinetic
///   energy grows to 5–8 J and the fluid splashes up the tank. With `c = 0.1` it settles (kinetic energy 0.02 J at t = 1 s, max
///   `ρ/ρ0` 1.002, mean 0.995), the free surface ending near 8.4 `s` instead of 10 `s`
///   because particles stack along the walls. S&P09's SPH viscosity force, replaced here by
///   XSPH, supplies damping the scheme needs; their boundary handling, replaced by SDFs,
///   supplies wall density.
///
/// Time per frame (10 × 4, 1000 particles, release build, 2 cores shared with other work):
/// 28–41 ms, i.e. 3–4 ms per substep of 4 iterations.
///
/// # Robustness, performance, determinism
///
/// Exactly as for [`crate::Pbf`]: invalid input is rejected naming the particle; divergence (a
/// non-finite predicted or final position or velocity, or a particle more than `h` inside a
/// solid) is [`PbfError::BlowUp`] and the state keeps the last completed substep; no
/// allocation in a step once the buffers have grown; every loop writes one particle's values
/// from fixed-order sums over its neighbour list and the statistics are summed over fixed
/// chunks, so the results are bitwise identical for any number of threads; the particles are
/// reordered by cell every `reorder_every` calls ([`Pcisph::last_permutation`]).
pub struct Pcisph<R: Real> {
    params: PcisphParams<R>,
    c: Consts<R>,
    solids: Solids<R>,
    search: Box<dyn NeighbourSearch<R>>,
    fallback: Option<HashedGrid<R>>,
    neighbours: NeighbourLists,
    scratch: Scratch<R>,
    reorder: CellReorder<R>,
    steps: u64,
}

impl<R: Real> fmt::Debug for Pcisph<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Pcisph")
            .field("params", &self.params)
            .field("delta", &self.c.delta)
            .field("solids", &self.solids.len())
            .field("search", &self.search.name())
            .field("particles", &self.scratch.predicted.len())
            .field("steps", &self.steps)
            .finish()
    }
}

/// Symplectic Euler with total acceleration `a`: `v* = v + Δt a` and the uncollided
/// position `x + Δt v*`.
#[inline]
fn advance<R: Real>(x: Vec3<R>, v: Vec3<R>, a: Vec3<R>, dt: R) -> (Vec3<R>, Vec3<R>) {
    let v_star = v + a * dt;
    (v_star, x + v_star * dt)
}

/// Poly6 density `Σ_j m_j W(x_i − x_j)` (self term included) at positions `x`.
#[inline]
fn density_at<R: Real>(c: &Consts<R>, x: &[Vec3<R>], m: &[R], nb: &NeighbourLists, i: usize) -> R {
    let xi = x[i];
    let mut sum = m[i] * c.w0;
    for &j in nb.neighbours(i) {
        let j = j as usize;
        sum += m[j] * c.poly6.value_r2((xi - x[j]).norm_squared());
    }
    sum
}

impl<R: Real> Pcisph<R> {
    /// A solver with validated `params` and the given solids (signed distance fields,
    /// negative inside the solid; a tank is `sph_core::Inverted<BoxSdf>`). Computes `δ`.
    pub fn new(params: PcisphParams<R>, solids: Solids<R>) -> Result<Self, PbfError> {
        params.validate()?;
        let c = Consts::new(&params)?;
        Ok(Self {
            search: params.neighbour_method.build::<R>(),
            params,
            c,
            solids,
            fallback: None,
            neighbours: NeighbourLists::new(),
            scratch: Scratch::default(),
            reorder: CellReorder::default(),
            steps: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PcisphParams<R> {
        &self.params
    }

    /// The scaling factor `δ` of S&P09 eq. 8 (m²/s²), computed once by [`Pcisph::new`]
    /// ([`PcisphParams::scaling_factor`]).
    pub fn delta(&self) -> R {
        self.c.delta
    }

    /// The solids, in the order collisions are resolved.
    pub fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        &self.solids
    }

    /// The neighbour lists of the last time step (found at its start positions).
    pub fn neighbours(&self) -> &NeighbourLists {
        &self.neighbours
    }

    /// The pressures `p_i` (Pa) at the end of the last time step's iterations.
    pub fn pressure(&self) -> &[R] {
        &self.scratch.pressure
    }

    /// Number of [`Pcisph::step`] calls made (including failed ones).
    pub fn steps_done(&self) -> u64 {
        self.steps
    }

    /// The permutation applied to the particles at the start of the last [`Pcisph::step`]
    /// call (`new[k] = old[perm[k]]`), or `None` if that call did not reorder.
    pub fn last_permutation(&self) -> Option<&[u32]> {
        self.reorder.last_permutation()
    }

    /// Advances `state` by `dt`: `substeps` PCISPH time steps (see [`Pcisph`]).
    ///
    /// Checks the state first ([`PbfError::InvalidState`], [`PbfError::InvalidMass`]),
    /// reorders it by cell every `reorder_every` calls, and after each time step checks for
    /// divergence before writing its result into `state` ([`PbfError::BlowUp`]; `state` then
    /// holds the last completed time step, never a non-finite value). Writes positions,
    /// velocities and densities (at the final positions). See [`Pcisph`] for the meaning
    /// of the [`StepStats`] fields. Does not allocate once its buffers have grown.
    pub fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, PbfError> {
        let step = self.steps;
        self.steps += 1;
        let mut stats = StepStats::default();
        let t = Instant::now();
        state.validate()?;
        check_masses(&state.masses)?;
        self.scratch.resize(state.len());
        stats.integrate_s += t.elapsed().as_secs_f64();

        self.reorder.at_step(
            state,
            self.params.support_radius,
            step,
            self.params.reorder_every,
            &mut stats,
        )?;

        for sub in 0..self.params.substeps {
            self.substep(state, step, sub, &mut stats)?;
        }

        let t = Instant::now();
        density_energy_stats(
            state,
            self.params.rest_density,
            &mut self.scratch.partials,
            &mut stats,
        );
        stats.velocity_update_s += t.elapsed().as_secs_f64();
        Ok(stats)
    }

    fn substep(
        &mut self,
        state: &mut ParticleSet<R>,
        step: u64,
        sub: usize,
        stats: &mut StepStats,
    ) -> Result<(), PbfError> {
        let p = &self.params;
        let c = self.c;
        let dt = p.substep_dt();
        let inv_dt = R::one() / dt;
        let g = p.gravity;
        let h = p.support_radius;
        let radius = p.particle_radius();
        let rho0 = p.rest_density;
        let s = &mut self.scratch;
        let solids = &self.solids[..];
        let (x, v, m) = (
            &state.positions[..],
            &state.velocities[..],
            &state.masses[..],
        );

        // Step 1: neighbours once, at the current positions.
        let search_stats = find_step_neighbours(
            &mut *self.search,
            &mut self.fallback,
            x,
            h,
            &mut self.neighbours,
            step,
            sub,
            "position",
        )?;
        stats.create_hash_grid_s += search_stats.build_s();
        stats.detect_neighbours_s += search_stats.detect_s();
        let nb = &self.neighbours;

        // Step 2: non-pressure forces (XSPH, gravity), p = 0, first prediction.
        let t = Instant::now();
        let xsph_c = p.xsph_c;
        s.velocity
            .par_iter_mut()
            .zip(s.predicted.par_iter_mut())
            .zip(s.pressure.par_iter_mut())
            .zip(s.accel.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, (((vel, xp), pr), acc))| {
                let (xi, vi) = (x[i], v[i]);
                let mut vn = vi;
                if xsph_c > R::zero() {
                    let mut sum = Vec3::zeros();
                    for &j in nb.neighbours(i) {
                        let j = j as usize;
                        let w = c.poly6.value_r2((xi - x[j]).norm_squared());
                        sum += (v[j] - vi) * (m[j] * c.inv_rho0 * w);
                    }
                    vn += sum * xsph_c;
                }
                *vel = vn;
                *pr = R::zero();
                *acc = Vec3::zeros();
                *xp = collide(solids, advance(xi, vn, g, dt).1, radius);
            });
        check_predicted(step, sub, &s.predicted)?;
        stats.integrate_s += t.elapsed().as_secs_f64();

        // Step 3: prediction-correction iterations.
        let t = Instant::now();
        let clamp = p.clamp_negative_pressure;
        for it in 0..p.pressure_iterations {
            // Predicted density, density error, pressure update (eq. 8's δ).
            let xp = &s.predicted[..];
            s.density
                .par_iter_mut()
                .zip(s.pressure.par_iter_mut())
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, (rho, pr))| {
                    let r = density_at(&c, xp, m, nb, i);
                    let mut err = r - rho0;
                    if clamp && err < R::zero() {
                        err = R::zero();
                    }
                    *rho = r;
                    *pr += c.delta * err;
                });
            stats.iterations += 1;
            // Early stop on the maximum compression (a max is exact in any order).
            let converged = p.density_error_tolerance.is_some_and(|tol| {
                let max = s
                    .density
                    .par_iter()
                    .with_min_len(MIN_LEN)
                    .map(|r| r.as_f64())
                    .reduce(|| f64::NEG_INFINITY, f64::max);
                let error = (max / rho0.as_f64() - 1.0).max(0.0);
                stats.last_solve_error = error;
                let met = error <= tol.as_f64();
                if !met && it + 1 == p.pressure_iterations {
                    stats.unconverged_substeps += 1;
                }
                met
            });
            // Pressure force at x(t) and the next prediction.
            let pr = &s.pressure[..];
            let vel = &s.velocity[..];
            s.accel
                .par_iter_mut()
                .zip(s.predicted.par_iter_mut())
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, (acc, xn))| {
                    let (xi, pi) = (x[i], pr[i]);
                    let mut a = Vec3::zeros();
                    for &j in nb.neighbours(i) {
                        let j = j as usize;
                        // F^p_i / m_i = −Σ_j m_j (p_i/ρ0² + p_j/ρ0²) ∇W_ij.
                        a -= c.spiky.gradient(&(xi - x[j])) * (m[j] * (pi + pr[j]) * c.inv_rho0_sq);
                    }
                    *acc = a;
                    *xn = collide(solids, advance(xi, vel[i], g + a, dt).1, radius);
                });
            if converged {
                break;
            }
        }
        stats.constraint_solve_s += t.elapsed().as_secs_f64();

        // Step 4: final velocities (with the collision displacement), densities.
        let t = Instant::now();
        let (xp, vel, acc) = (&s.predicted[..], &s.velocity[..], &s.accel[..]);
        s.density
            .par_iter_mut()
            .zip(s.velocity_new.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, (rho, vn))| {
                // xp[i] is collide(y): the last prediction used the same acceleration.
                let (v_star, y) = advance(x[i], vel[i], g + acc[i], dt);
                *vn = v_star + (xp[i] - y) * inv_dt;
                *rho = density_at(&c, xp, m, nb, i);
            });
        check_divergence(step, sub, xp, &s.velocity_new, solids, h)?;
        state.positions.copy_from_slice(xp);
        state.velocities.copy_from_slice(&s.velocity_new);
        state.densities.copy_from_slice(&s.density);
        stats.velocity_update_s += t.elapsed().as_secs_f64();
        stats.substeps += 1;
        stats.neighbour_pairs = nb.pair_count();
        Ok(())
    }
}
