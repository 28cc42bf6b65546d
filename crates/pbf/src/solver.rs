//! The solver: Algorithm 1 of Macklin & Müller (2013).

use std::fmt;
use std::time::Instant;

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{validate_finite_positions, CoreError, ParticleSet, Real, Sdf, Vec3};
use sph_kernels::Kernel;
use sph_solver::boundary::check_volume_kernel;
use sph_solver::step::{
    begin_frame, check_divergence, check_masses, check_predicted, end_frame, CellReorder,
    FramePhases, StepAt, StepNeighbours, MIN_LEN,
};
use sph_solver::{Boundary, CollisionBoundary, Solids, SolverError, StepStats};

use crate::passes::{
    delta_pass, lambda_pass, near_boundary, Consts, LambdaOut, PairCache, PassInput,
};
use crate::PbfParams;

/// The Position Based Fluids solver of
///
/// > Miles Macklin and Matthias Müller, "Position Based Fluids", *ACM Transactions on
/// > Graphics* 32(4), Article 104, 2013 (SIGGRAPH 2013),
///
/// Algorithm 1, one call of [`Pbf::step`] advancing one whole frame of `substeps` steps of
/// `Δt = dt / substeps`:
///
/// 1. apply gravity and predict `x* = x + Δt (v + Δt g)` (lines 1–4);
/// 2. find the neighbours within `h` **once**, at the predicted positions (lines 5–7);
/// 3. `solver_iterations` Jacobi iterations (lines 8–19), each:
///    `ρ_i` (eq. 2, Poly6), `λ_i` (eqs. 1, 8, 11, Spiky gradients, CFM `ε`) for all `i`;
///    then `Δp_i` (eq. 14 with `s_corr` of eq. 13) and the boundary's contact response
///    ([`Boundary::project`]) for all `i`; then `x* ← x* + Δp` for all `i`. A volume-map
///    boundary also adds its density `ρ0 Ψ(x_i)` to `ρ_i` and `∇Ψ` to `∇_{p_i} C_i` (and
///    `λ_i ∇Ψ_i` to `Δp_i`), as the PBF implementations after the paper do with boundary
///    particles (Akinci et al. 2012; SPlisHSPlasH). With
///    [`PbfParams::mean_compression_tolerance`] (not in the paper; SPlisHSPlasH's rule) the
///    count is adaptive: between `min_solver_iterations` and `solver_iterations`, stopping
///    after the first iteration whose mean compression at its start is within the tolerance;
///    [`PbfParams::clamp_negative_constraint`] makes `C_i` unilateral;
/// 4. `v = (x* − x)/Δt` (line 21); vorticity `ω_i` (eq. 15) and the confinement
///    acceleration `ε N × ω` (eq. 16), XSPH (eq. 17), both from the line-21 velocities;
///    `x ← x*` (line 23).
///
/// See the crate documentation for the mass convention, the collision response, the blow-up
/// checks and the deviations from the paper.
pub struct Pbf<R: Real> {
    params: PbfParams<R>,
    c: Consts<R>,
    boundary: Box<dyn Boundary<R>>,
    neighbours: StepNeighbours<R>,
    scratch: PbfScratch<R>,
    reorder: CellReorder<R>,
    steps: u64,
}

/// The phases [`Pbf::step`] times ([`StepStats::phases`]), named after the rows of the
/// paper's Table 2, plus the reordering by cell.
pub const PBF_PHASES: &[&str] = &[
    "integrate",
    "create_hash_grid",
    "detect_neighbours",
    "constraint_solve",
    "velocity_update",
    "reorder",
];
const INTEGRATE: usize = 0;
const CREATE_HASH_GRID: usize = 1;
const DETECT_NEIGHBOURS: usize = 2;
const CONSTRAINT_SOLVE: usize = 3;
const VELOCITY_UPDATE: usize = 4;
const REORDER: usize = 5;
const FRAME: FramePhases = FramePhases {
    checks: INTEGRATE,
    reorder: REORDER,
    statistics: VELOCITY_UPDATE,
};

const NAME: &str = "PBF";

impl<R: Real> fmt::Debug for Pbf<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Pbf")
            .field("params", &self.params)
            .field("boundary", &self.boundary.name())
            .field("solids", &self.boundary.solids().len())
            .field("particles", &self.scratch.predicted.len())
            .field("steps", &self.steps)
            .finish()
    }
}

/// Per-particle working arrays of the solver (structure of arrays, one `Vec` per quantity),
/// kept between steps so that a step does not allocate. After a [`Pbf::step`] they hold the
/// values of its last substep, in the state's current particle order.
#[derive(Debug, Clone, Default)]
pub struct PbfScratch<R: Real> {
    predicted: Vec<Vec3<R>>,
    next: Vec<Vec3<R>>,
    lambda: Vec<R>,
    delta_p: Vec<Vec3<R>>,
    density: Vec<R>,
    boundary_grad: Vec<Vec3<R>>,
    near_boundary: Vec<bool>,
    velocity: Vec<Vec3<R>>,
    velocity_new: Vec<Vec3<R>>,
    vorticity: Vec<Vec3<R>>,
    vorticity_norm: Vec<R>,
    partials: Vec<[f64; 3]>,
    pairs: PairCache<R>,
}

impl<R: Real> PbfScratch<R> {
    fn resize(&mut self, n: usize) {
        if self.predicted.len() == n {
            return;
        }
        let z = Vec3::zeros();
        self.predicted.resize(n, z);
        self.next.resize(n, z);
        self.lambda.resize(n, R::zero());
        self.delta_p.resize(n, z);
        self.density.resize(n, R::zero());
        self.boundary_grad.resize(n, z);
        self.near_boundary.resize(n, false);
        self.velocity.resize(n, z);
        self.velocity_new.resize(n, z);
        self.vorticity.resize(n, z);
        self.vorticity_norm.resize(n, R::zero());
    }

    /// Predicted positions `x*` (m): after a step, the final positions of its last substep.
    pub fn predicted(&self) -> &[Vec3<R>] {
        &self.predicted
    }
    /// `λ_i` of the last iteration (eq. 11; m², see the crate docs for units).
    pub fn lambda(&self) -> &[R] {
        &self.lambda
    }
    /// `Δp_i` of the last iteration (eq. 14, before the contact response; m).
    pub fn delta_p(&self) -> &[Vec3<R>] {
        &self.delta_p
    }
    /// Densities `ρ_i` (eq. 2 plus the boundary's `ρ0 Ψ`, kg/m³): after a step, at the final
    /// positions; after [`Pbf::evaluate_constraints`], at the given positions.
    pub fn density(&self) -> &[R] {
        &self.density
    }
    /// Velocities `(x* − x)/Δt` of Algorithm 1 line 21 (m/s), before vorticity confinement
    /// and XSPH.
    pub fn velocity(&self) -> &[Vec3<R>] {
        &self.velocity
    }
    /// Vorticity `ω_i` of eq. 15 (1/s); zero when vorticity confinement is off.
    pub fn vorticity(&self) -> &[Vec3<R>] {
        &self.vorticity
    }
}

/// What [`Pbf::evaluate_constraints`] computed, borrowed from the solver.
#[derive(Debug, Clone, Copy)]
pub struct ConstraintEval<'a, R: Real> {
    /// `ρ_i` (eq. 2 plus the boundary's `ρ0 Ψ`, kg/m³).
    pub density: &'a [R],
    /// `λ_i` (eq. 11).
    pub lambda: &'a [R],
    /// `Δp_i` (eq. 14, with `s_corr`, without the contact response; m).
    pub delta_p: &'a [Vec3<R>],
    /// The neighbour lists used (within `h`, excluding the particle itself).
    pub neighbours: &'a NeighbourLists,
}

impl<R: Real> Pbf<R> {
    /// A solver with validated `params` and the given solids as a [`CollisionBoundary`]
    /// with the particle radius `s / 2` as contact distance (the paper's collision handling).
    pub fn new(params: PbfParams<R>, solids: Solids<R>) -> Result<Self, SolverError> {
        let boundary = CollisionBoundary::new(solids, params.particle_radius())?;
        Self::with_boundary(params, Box::new(boundary))
    }

    /// A solver with validated `params` and any boundary model. A boundary that takes part
    /// in the density must have been integrated with this solver's density kernel (Poly6 of
    /// support radius `h`), otherwise [`SolverError::InvalidParameter`].
    pub fn with_boundary(
        params: PbfParams<R>,
        boundary: Box<dyn Boundary<R>>,
    ) -> Result<Self, SolverError> {
        params.validate()?;
        check_volume_kernel(&*boundary, NAME, "poly6", params.common.support_radius)?;
        let c = Consts::new(&params)?;
        Ok(Self {
            neighbours: StepNeighbours::new(params.common.neighbour_method),
            params,
            c,
            boundary,
            scratch: PbfScratch::default(),
            reorder: CellReorder::default(),
            steps: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PbfParams<R> {
        &self.params
    }

    /// Replaces the parameters (validated; the kernels are rebuilt, the buffers kept). The
    /// support radius must stay that of a volume boundary's kernel.
    pub fn set_params(&mut self, params: PbfParams<R>) -> Result<(), SolverError> {
        params.validate()?;
        check_volume_kernel(&*self.boundary, NAME, "poly6", params.common.support_radius)?;
        self.c = Consts::new(&params)?;
        self.neighbours.set_method(params.common.neighbour_method);
        self.params = params;
        Ok(())
    }

    /// The boundary.
    pub fn boundary(&self) -> &dyn Boundary<R> {
        &*self.boundary
    }

    /// The solids, in the order contacts are resolved.
    pub fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        self.boundary.solids()
    }

    /// The neighbour lists of the last substep (or of [`Pbf::evaluate_constraints`]).
    pub fn neighbours(&self) -> &NeighbourLists {
        self.neighbours.lists()
    }

    /// The working arrays (values of the last substep).
    pub fn scratch(&self) -> &PbfScratch<R> {
        &self.scratch
    }

    /// Number of [`Pbf::step`] calls made (including failed ones).
    pub fn steps_done(&self) -> u64 {
        self.steps
    }

    /// The permutation applied to the particles at the start of the last [`Pbf::step`]
    /// call (`new[k] = old[perm[k]]`), or `None` if that call did not reorder. Apply it to any
    /// per-particle data kept beside the [`ParticleSet`] (`sph_core::apply_permutation`).
    pub fn last_permutation(&self) -> Option<&[u32]> {
        self.reorder.last_permutation()
    }

    /// Computes, at the given positions and without moving anything, the neighbours, the
    /// densities (eq. 2), `λ_i` (eq. 11) and `Δp_i` (eq. 14, before the contact response)
    /// that one Jacobi iteration of [`Pbf::step`] computes (the same code). For tests and
    /// diagnostics.
    pub fn evaluate_constraints(
        &mut self,
        positions: &[Vec3<R>],
        masses: &[R],
    ) -> Result<ConstraintEval<'_, R>, SolverError> {
        validate_finite_positions(positions)?;
        if masses.len() != positions.len() {
            return Err(CoreError::LengthMismatch {
                what: "masses",
                found: masses.len(),
                expected: positions.len(),
            }
            .into());
        }
        check_masses(masses)?;
        let n = positions.len();
        self.scratch.resize(n);
        let volume = self.boundary.has_volume().then_some(&*self.boundary);
        let s = &mut self.scratch;
        s.predicted.copy_from_slice(positions);
        self.neighbours
            .find(&s.predicted, self.params.common.support_radius)?;
        if let Some(b) = volume {
            near_boundary(
                b,
                &s.predicted,
                self.params.common.support_radius,
                &mut s.near_boundary,
            );
        }
        let volume = volume.map(|b| (b, &s.near_boundary[..]));
        let input = PassInput {
            c: &self.c,
            x: &s.predicted,
            m: masses,
            nb: self.neighbours.lists(),
            volume,
        };
        let out = LambdaOut {
            density: &mut s.density,
            lambda: &mut s.lambda,
            boundary_grad: &mut s.boundary_grad,
        };
        let _ = lambda_pass(input, out, &mut s.pairs);
        delta_pass(
            input,
            &s.lambda,
            &s.boundary_grad,
            &s.pairs,
            &*self.boundary,
            &mut s.delta_p,
            &mut s.next,
        );
        Ok(ConstraintEval {
            density: &s.density,
            lambda: &s.lambda,
            delta_p: &s.delta_p,
            neighbours: self.neighbours.lists(),
        })
    }

    /// Advances `state` by one whole frame, `common.dt` (16 ms by default), made of
    /// `common.substeps` time steps of Algorithm 1 (see [`Pbf`]): one call is a frame, not
    /// one solver step.
    ///
    /// **Particle order.** Every `common.reorder_every` calls (the first call included), the
    /// call begins by reordering the particles of `state` by grid cell for memory locality:
    /// afterwards [`Pbf::last_permutation`] returns `perm` with `new[k] = old[perm[k]]`
    /// (`None` when the call did not reorder). To follow particles across a run, keep an
    /// index map `ids` (initially `0..n`) and compose it after each call,
    /// `ids = perm.iter().map(|&o| ids[o as usize]).collect()`, so `ids[k]` is the original
    /// index of the particle now at `k`; apply the same permutation to any per-particle data
    /// kept beside the state (`sph_core::apply_permutation`). `reorder_every = 0` keeps the
    /// input order. The crate-level example shows it.
    ///
    /// Checks the state first (array lengths, finite positions and velocities, positive
    /// masses: [`SolverError::InvalidState`], [`SolverError::InvalidMass`]), reorders it by
    /// cell every `reorder_every` calls, and after each substep checks for divergence before
    /// writing the substep's result into `state` ([`SolverError::BlowUp`]; `state` then holds
    /// the last completed substep, never a non-finite value). Writes positions, velocities
    /// and densities (at the final positions).
    ///
    /// Does not allocate once its buffers have grown to the particle count (and the neighbour
    /// lists to the pair count).
    pub fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, SolverError> {
        let step = self.steps;
        self.steps += 1;
        let mut stats = StepStats::new(PBF_PHASES);
        let common = &self.params.common;
        begin_frame(state, &mut self.reorder, common, step, FRAME, &mut stats)?;
        self.scratch.resize(state.len());

        for sub in 0..self.params.common.substeps {
            let at = StepAt {
                solver: NAME,
                step,
                substep: sub,
            };
            self.substep(state, at, &mut stats)?;
        }

        end_frame(
            state,
            self.params.common.rest_density,
            &mut self.scratch.partials,
            FRAME,
            &mut stats,
        );
        Ok(stats)
    }

    fn substep(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        let volume = self.boundary.has_volume().then_some(&*self.boundary);
        let p = &self.params;
        let c = self.c;
        let dt = p.substep_dt();
        let g = p.common.gravity;
        let h = p.common.support_radius;
        let s = &mut self.scratch;
        let boundary = &*self.boundary;

        // Lines 1–4: apply forces, predict positions.
        let t = Instant::now();
        {
            let (x, v) = (&state.positions[..], &state.velocities[..]);
            s.predicted
                .par_iter_mut()
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, xp)| {
                    let vi = v[i] + g * dt;
                    *xp = x[i] + vi * dt;
                });
        }
        check_predicted(at, &s.predicted)?;
        stats.phases.add(INTEGRATE, t.elapsed().as_secs_f64());

        // Lines 5–7: neighbours at the predicted positions, once per step.
        let search_stats =
            self.neighbours
                .find_in_step(&s.predicted, h, at, "predicted position")?;
        stats.phases.add(CREATE_HASH_GRID, search_stats.build_s());
        stats.phases.add(DETECT_NEIGHBOURS, search_stats.detect_s());
        let nb = self.neighbours.lists();
        let m = &state.masses[..];

        // Lines 8–19: Jacobi iterations with the contact response.
        let t = Instant::now();
        if let Some(b) = volume {
            near_boundary(b, &s.predicted, h, &mut s.near_boundary);
        }
        let reach = volume.map(|b| (b, &s.near_boundary[..]));
        let inv_n = 1.0 / (state.len().max(1) as f64);
        let mut done = 0;
        loop {
            let input = PassInput {
                c: &c,
                x: &s.predicted,
                m,
                nb,
                volume: reach,
            };
            let out = LambdaOut {
                density: &mut s.density,
                lambda: &mut s.lambda,
                boundary_grad: &mut s.boundary_grad,
            };
            let compression = lambda_pass(input, out, &mut s.pairs) * inv_n;
            delta_pass(
                input,
                &s.lambda,
                &s.boundary_grad,
                &s.pairs,
                boundary,
                &mut s.delta_p,
                &mut s.next,
            );
            std::mem::swap(&mut s.predicted, &mut s.next);
            done += 1;
            // The stopping rule of `mean_compression_tolerance` (fixed count without it).
            let Some(tol) = p.mean_compression_tolerance else {
                if done == p.solver_iterations {
                    break;
                }
                continue;
            };
            stats.last_solve_error = compression;
            let met = compression <= tol.as_f64();
            if done >= p.solver_iterations || (met && done >= p.min_solver_iterations) {
                if !met {
                    stats.unconverged_substeps += 1;
                }
                break;
            }
        }
        stats
            .phases
            .add(CONSTRAINT_SOLVE, t.elapsed().as_secs_f64());
        stats.iterations += done;

        // Lines 20–24: velocity update, vorticity confinement, XSPH, position update.
        let t = Instant::now();
        velocity_update(
            VelocityInput {
                c: &c,
                p,
                x_old: &state.positions,
                m,
                nb,
                volume,
            },
            s,
        );
        let x = &s.predicted[..];

        // Divergence checks before anything is written to the state.
        check_divergence(at, x, &s.velocity_new, boundary, h)?;
        state.positions.copy_from_slice(x);
        state.velocities.copy_from_slice(&s.velocity_new);
        state.densities.copy_from_slice(&s.density);
        stats.phases.add(VELOCITY_UPDATE, t.elapsed().as_secs_f64());
        stats.substeps += 1;
        stats.neighbour_pairs = nb.pair_count();
        Ok(())
    }
}

/// What [`velocity_update`] reads besides the scratch arrays.
struct VelocityInput<'a, R: Real> {
    c: &'a Consts<R>,
    p: &'a PbfParams<R>,
    x_old: &'a [Vec3<R>],
    m: &'a [R],
    nb: &'a NeighbourLists,
    volume: Option<&'a dyn Boundary<R>>,
}

/// Algorithm 1 lines 20–22: `v = (x* − x)/Δt`, the densities at the final positions (for
/// the statistics and the state), vorticity (eq. 15) and confinement (eq. 16), XSPH
/// (eq. 17); the new velocities go to `s.velocity_new`.
fn velocity_update<R: Real>(input: VelocityInput<'_, R>, s: &mut PbfScratch<R>) {
    let VelocityInput {
        c,
        p,
        x_old,
        m,
        nb,
        volume,
    } = input;
    let dt = p.substep_dt();
    let inv_dt = R::one() / dt;
    let x = &s.predicted[..];
    s.velocity
        .par_iter_mut()
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, v)| *v = (x[i] - x_old[i]) * inv_dt);
    let vort_on = p.vorticity_epsilon != R::zero();
    let xsph_on = p.xsph_c > R::zero();
    let v = &s.velocity[..];
    // Densities at the final positions and eq. 15; without vorticity confinement, XSPH
    // (eq. 17) in the same pass (it needs the same Poly6 values and nothing else of this
    // pass).
    let (eps_v, xsph_c) = (p.vorticity_epsilon, p.xsph_c);
    s.density
        .par_iter_mut()
        .zip(s.vorticity.par_iter_mut())
        .zip(s.vorticity_norm.par_iter_mut())
        .zip(s.velocity_new.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (((rho, w), wn), vn))| {
            let (xi, vi) = (x[i], v[i]);
            let mut sum_w = m[i] * c.w0;
            let mut omega = Vec3::zeros();
            let mut xsph = Vec3::zeros();
            for &j in nb.neighbours(i) {
                let j = j as usize;
                let r = xi - x[j];
                let wij = c.poly6.value_r2(r.norm_squared());
                sum_w += m[j] * wij;
                if vort_on {
                    // v_ij × ∇_{p_j} W(p_i − p_j) = ∇W(p_i − p_j) × v_ij, volume m_j/ρ0.
                    omega += c.spiky.gradient(&r).cross(&(v[j] - vi)) * (m[j] * c.inv_rho0);
                } else if xsph_on {
                    xsph += (v[j] - vi) * (m[j] * c.inv_rho0 * wij);
                }
            }
            if let Some(bd) = volume {
                sum_w += c.rho0 * bd.sample(&xi).volume;
            }
            *rho = sum_w;
            *w = omega;
            *wn = omega.norm();
            if !vort_on {
                *vn = vi + xsph * xsph_c;
            }
        });
    if vort_on {
        let (omega, omega_norm) = (&s.vorticity[..], &s.vorticity_norm[..]);
        s.velocity_new
            .par_iter_mut()
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, vn)| {
                let (xi, vi) = (x[i], v[i]);
                let mut eta = Vec3::zeros();
                let mut xsph = Vec3::zeros();
                for &j in nb.neighbours(i) {
                    let j = j as usize;
                    let r = xi - x[j];
                    let vol = m[j] * c.inv_rho0;
                    // η = ∇|ω| (SPH gradient, difference form).
                    eta += c.spiky.gradient(&r) * (vol * (omega_norm[j] - omega_norm[i]));
                    if xsph_on {
                        xsph += (v[j] - vi) * (vol * c.poly6.value_r2(r.norm_squared()));
                    }
                }
                let mut out = vi + xsph * xsph_c;
                let len = eta.norm();
                if len > R::zero() {
                    out += (eta / len).cross(&omega[i]) * (eps_v * dt);
                }
                *vn = out;
            });
    }
}
