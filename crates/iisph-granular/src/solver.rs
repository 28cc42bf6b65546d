//! The IISPH time step with the granular extension (see the crate documentation for the
//! equations).

use std::fmt;
use std::time::Instant;

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{apply_permutation, ParticleSet, Real, Vec3};
use sph_kernels::{CubicSpline, Kernel};
use sph_solver::boundary::check_volume_kernel;
use sph_solver::csr::par_csr_blocks;
use sph_solver::step::{
    begin_frame, check_divergence, density_at, end_frame, par_update_sum, CellReorder, FramePhases,
    StepAt, StepNeighbours, MIN_LEN, REDUCE_CHUNK,
};
use sph_solver::{Boundary, CollisionBoundary, Solids, SolverError, StepStats};

use crate::friction;
use crate::granular::{drag_force, occlusion, prototype_friction_coefficient, Sym3};
use crate::params::NAME;
use crate::upscale::Upscaler;
use crate::IisphParams;

/// The phases [`Iisph::step`] times ([`StepStats::phases`]).
pub const IISPH_PHASES: &[&str] = &[
    "integrate",
    "create_hash_grid",
    "detect_neighbours",
    "advection",
    "pressure_solve",
    "friction_solve",
    "forces",
    "upscaling",
    "reorder",
];
const INTEGRATE: usize = 0;
const CREATE_HASH_GRID: usize = 1;
const DETECT_NEIGHBOURS: usize = 2;
const ADVECTION: usize = 3;
const PRESSURE_SOLVE: usize = 4;
const FRICTION_SOLVE: usize = 5;
const FORCES: usize = 6;
const UPSCALING: usize = 7;
const REORDER: usize = 8;
const FRAME: FramePhases = FramePhases {
    checks: INTEGRATE,
    reorder: REORDER,
    statistics: INTEGRATE,
};

/// The density kernel (and the kernel of every gradient) of the solver.
pub const IISPH_KERNEL: &str = "cubic-spline";

/// Kernels and constants of the per-particle loops.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Consts<R: Real> {
    pub kernel: CubicSpline<R>,
    /// `W(0)`: the self term of the density sum.
    pub w0: R,
    pub rho0: R,
    pub dt: R,
    pub h: R,
    /// `(1/d)` of the prototype friction coefficient (granular only, else 0).
    pub inv_friction_d: R,
    /// Drucker–Prager `α = √2 sin θ` (0 for water).
    pub alpha: R,
    /// Coulomb coefficient `tan θ` of the contact response (0 for water).
    pub wall_friction: R,
    /// Drag: `C_D`, `ρ_a`, cross-section `π r²`, `cos` of the cone half-angle, air velocity.
    pub drag_coefficient: R,
    pub air_density: R,
    pub area: R,
    pub cos_cone: R,
    pub air_velocity: Vec3<R>,
    /// `10 ν` of the viscosity force (`2 (d + 2) ν`, `d = 3`).
    pub visc: R,
    pub granular: bool,
    pub drag: bool,
}

impl<R: Real> Consts<R> {
    pub(crate) fn new(p: &IisphParams<R>) -> Result<Self, SolverError> {
        let h = p.common.support_radius;
        let kernel = CubicSpline::new(h)?;
        let dt = p.substep_dt();
        let rho0 = p.common.rest_density;
        let g = p.granular.as_ref();
        let inv_friction_d = match g {
            Some(_) => {
                let d =
                    prototype_friction_coefficient(&kernel, p.common.particle_spacing, rho0, dt)
                        .ok_or(SolverError::InvalidParameter {
                            solver: NAME,
                            name: "support_radius",
                            value: h.as_f64(),
                            reason: "no finite prototype friction coefficient D (eq. 9)",
                        })?;
                R::one() / d
            }
            None => R::zero(),
        };
        let r = p.common.particle_radius();
        Ok(Self {
            kernel,
            w0: kernel.value(R::zero()),
            rho0,
            dt,
            h,
            inv_friction_d,
            alpha: g.map_or(R::zero(), |g| g.alpha()),
            wall_friction: g.map_or(R::zero(), |g| {
                R::of_f64(g.friction_angle_deg.as_f64().to_radians().tan())
            }),
            drag_coefficient: g.map_or(R::zero(), |g| g.drag_coefficient),
            air_density: g.map_or(R::zero(), |g| g.air_density),
            area: R::pi() * r * r,
            cos_cone: g.map_or(R::one(), |g| {
                R::of_f64(g.drag_cone_half_angle_deg.as_f64().to_radians().cos())
            }),
            air_velocity: g.map_or(Vec3::zeros(), |g| g.air_velocity),
            visc: R::of_f64(10.0) * p.viscosity,
            granular: g.is_some(),
            drag: g.is_some_and(|g| g.drag_coefficient > R::zero() && g.air_density > R::zero()),
        })
    }
}

/// Per-particle working arrays (structure of arrays), kept between steps.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch<R: Real> {
    /// `W'(r)/r` per neighbour pair (CSR order of the neighbour lists): `∇W_ij = (x_i − x_j)
    /// · grad_scale[k]`.
    pub grad_scale: Vec<R>,
    /// `ρ_i` at the step's start positions, boundary included (eq. 3 + eq. 29).
    pub density: Vec<R>,
    /// `∇Ψ(x_i)` of a volume boundary.
    pub bgrad: Vec<Vec3<R>>,
    /// `v_i^adv` (eq. 18).
    pub v_adv: Vec<Vec3<R>>,
    /// Source term `ρ0 − ρ_i^adv` (eq. 19) of the linear system.
    pub source: Vec<R>,
    /// Diagonal `a_ii` (eq. 24), Δt² included.
    pub aii: Vec<R>,
    /// Pressure `p_i` (Pa); kept between steps for the warm start.
    pub pressure: Vec<R>,
    /// `p_i / ρ_i²`.
    pub p_over_rho2: Vec<R>,
    /// Pressure acceleration `F^p_i / m_i` of the current iterate.
    pub accel: Vec<Vec3<R>>,
    /// Frictional stress `s_i` (Pa, deviatoric, inside the yield surface); kept between
    /// steps (the friction solve's warm start).
    pub stress: Vec<Sym3<R>>,
    /// `s_i / ρ_i²`.
    pub stress_over_rho2: Vec<Sym3<R>>,
    /// Friction acceleration `F^f_i / m_i` of the current stress.
    pub friction_accel: Vec<Vec3<R>>,
    /// Velocity at the step's end without friction, `v^adv + Δt (a^p − a^f_prev)`.
    pub v_base: Vec<Vec3<R>>,
    /// Velocity at the step's end with the current stress iterate.
    pub v_trial: Vec<Vec3<R>>,
    pub perm_sym: Vec<Sym3<R>>,
    pub x_new: Vec<Vec3<R>>,
    pub v_new: Vec<Vec3<R>>,
    pub density_new: Vec<R>,
    /// Partial sums of the density error per chunk of [`REDUCE_CHUNK`] particles.
    pub error_partials: Vec<f64>,
    pub partials: Vec<[f64; 3]>,
    pub perm_scalar: Vec<R>,
}

impl<R: Real> Scratch<R> {
    fn resize(&mut self, n: usize, granular: bool) {
        let z = Vec3::zeros();
        self.density.resize(n, R::zero());
        self.bgrad.resize(n, z);
        self.v_adv.resize(n, z);
        self.source.resize(n, R::zero());
        self.aii.resize(n, R::zero());
        self.pressure.resize(n, R::zero());
        self.p_over_rho2.resize(n, R::zero());
        self.accel.resize(n, z);
        let ng = if granular { n } else { 0 };
        self.stress.resize(ng, [R::zero(); 6]);
        self.stress_over_rho2.resize(ng, [R::zero(); 6]);
        self.friction_accel.resize(ng, z);
        self.v_base.resize(ng, z);
        self.v_trial.resize(ng, z);
        self.x_new.resize(n, z);
        self.v_new.resize(n, z);
        self.density_new.resize(n, R::zero());
        self.error_partials.resize(n.div_ceil(REDUCE_CHUNK), 0.0);
    }
}

/// `∇W_ij` from the cached `W'(r)/r` of the pair.
#[inline(always)]
pub(crate) fn grad<R: Real>(xi: &Vec3<R>, xj: &Vec3<R>, f: R) -> Vec3<R> {
    (xi - xj) * f
}

/// Implicit incompressible SPH (Ihmsen et al. 2014) for water and, with
/// [`crate::GranularParams`], granular matter (Neder 2024); see the crate documentation.
pub struct Iisph<R: Real> {
    params: IisphParams<R>,
    c: Consts<R>,
    boundary: Box<dyn Boundary<R>>,
    neighbours: StepNeighbours<R>,
    scratch: Scratch<R>,
    reorder: CellReorder<R>,
    upscaler: Option<Upscaler<R>>,
    steps: u64,
}

impl<R: Real> fmt::Debug for Iisph<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Iisph")
            .field("params", &self.params)
            .field("boundary", &self.boundary.name())
            .field("particles", &self.scratch.density.len())
            .field("steps", &self.steps)
            .finish()
    }
}

impl<R: Real> Iisph<R> {
    /// A solver with validated `params` and the solids as a [`CollisionBoundary`] at the
    /// particle radius `s/2` (no boundary density: walls only by the contact response).
    pub fn new(params: IisphParams<R>, solids: Solids<R>) -> Result<Self, SolverError> {
        let b = CollisionBoundary::new(solids, params.common.particle_radius())?;
        Self::with_boundary(params, Box::new(b))
    }

    /// A solver with validated `params` and any boundary. A boundary that takes part in the
    /// density must have been integrated with the solver's kernel ([`IISPH_KERNEL`], the
    /// cubic spline) at its support radius, otherwise [`SolverError::InvalidParameter`].
    pub fn with_boundary(
        params: IisphParams<R>,
        boundary: Box<dyn Boundary<R>>,
    ) -> Result<Self, SolverError> {
        params.validate()?;
        check_volume_kernel(&*boundary, NAME, IISPH_KERNEL, params.common.support_radius)?;
        let c = Consts::new(&params)?;
        Ok(Self {
            neighbours: StepNeighbours::new(params.common.neighbour_method),
            upscaler: params.upscaling_factor.map(Upscaler::new),
            params,
            c,
            boundary,
            scratch: Scratch::default(),
            reorder: CellReorder::default(),
            steps: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &IisphParams<R> {
        &self.params
    }

    /// The boundary.
    pub fn boundary(&self) -> &dyn Boundary<R> {
        &*self.boundary
    }

    /// The neighbour lists of the last time step (found at its start positions).
    pub fn neighbours(&self) -> &NeighbourLists {
        self.neighbours.lists()
    }

    /// The pressures `p_i` (Pa) of the last time step.
    pub fn pressure(&self) -> &[R] {
        &self.scratch.pressure
    }

    /// The frictional stresses `s_i` (Pa, symmetric `[xx, yy, zz, xy, xz, yz]`,
    /// deviatoric, `‖s_i‖ ≤ α p_i`) the last time step applied (empty for water).
    pub fn stress(&self) -> &[Sym3<R>] {
        &self.scratch.stress
    }

    /// Number of [`Iisph::step`] calls made (including failed ones).
    pub fn steps_done(&self) -> u64 {
        self.steps
    }

    /// The permutation of the last reordering (see `FluidSolver::last_permutation`).
    pub fn last_permutation(&self) -> Option<&[u32]> {
        self.reorder.last_permutation()
    }

    /// The passive high-resolution points (upscaling), once seeded by the first step.
    pub fn passive_points(&self) -> Option<&[Vec3<R>]> {
        self.upscaler
            .as_ref()
            .and_then(|u| u.seeded().then_some(u.points()))
    }

    /// Sets up the pressure system of one time step from `state` without advancing it:
    /// neighbours, densities, advection and the predicted density (Algorithm 1 lines 1–5),
    /// with a cold start `p⁰ = 0`. Afterwards [`Iisph::system_diagonal`],
    /// [`Iisph::system_source`], [`Iisph::apply_system`] and [`Iisph::solve_system`] inspect
    /// and solve it (for tests and studies of the solver; [`Iisph::step`] does the same
    /// internally). Errors as [`Iisph::step`].
    pub fn assemble_system(&mut self, state: &ParticleSet<R>) -> Result<(), SolverError> {
        sph_solver::step::check_state(state)?;
        let n = state.len();
        self.scratch.pressure.clear();
        self.scratch.resize(n, self.c.granular);
        let at = StepAt {
            solver: NAME,
            step: self.steps,
            substep: 0,
        };
        let h = self.params.common.support_radius;
        self.neighbours
            .find_in_step(&state.positions, h, at, "position")?;
        let nb = self.neighbours.lists();
        let volume = self.boundary.has_volume().then_some(&*self.boundary);
        let (x, v, m) = (
            &state.positions[..],
            &state.velocities[..],
            &state.masses[..],
        );
        let s = &mut self.scratch;
        density_pass(&self.c, x, m, nb, volume, s);
        advection_pass(&self.c, self.params.common.gravity, x, v, m, nb, s);
        predicted_density_pass(&self.c, x, m, nb, s);
        Ok(())
    }

    /// The diagonal `a_ii` (eq. 24, m³/kg·… in units of density per pressure, Δt² included)
    /// of the last assembled system.
    pub fn system_diagonal(&self) -> &[R] {
        &self.scratch.aii
    }

    /// The right-hand side `ρ0 − ρ_i^adv` (kg/m³) of the last assembled system.
    pub fn system_source(&self) -> &[R] {
        &self.scratch.source
    }

    /// The densities `ρ_i` (boundary included) of the last assembled system.
    pub fn system_density(&self) -> &[R] {
        &self.scratch.density
    }

    /// `out = A p` for the last assembled system (`state` must be the one given to
    /// [`Iisph::assemble_system`]): the density change `Σ_j m_j (Δt a^p_i − Δt a^p_j)·∇W_ij
    /// Δt + …` the pressures `p` cause (eqs. 20–22, `a_ii p_i + ψ_i`). Overwrites the
    /// solver's pressure scratch. Errors if the lengths differ from the system's.
    pub fn apply_system(
        &mut self,
        state: &ParticleSet<R>,
        p: &[R],
        out: &mut [R],
    ) -> Result<(), SolverError> {
        let n = self.scratch.density.len();
        if p.len() != n || out.len() != n || state.len() != n {
            return Err(SolverError::InvalidParameter {
                solver: NAME,
                name: "p",
                value: p.len() as f64,
                reason: "length differs from the assembled system's particle count",
            });
        }
        let nb = self.neighbours.lists();
        let (x, m) = (&state.positions[..], &state.masses[..]);
        let c = &self.c;
        let s = &mut self.scratch;
        for ((pi, &pr), &rho) in s.p_over_rho2.iter_mut().zip(p).zip(&s.density) {
            *pi = pr / (rho * rho);
        }
        let (offsets, indices) = (nb.offsets(), nb.indices());
        let (gs, pi, bgrad) = (&s.grad_scale[..], &s.p_over_rho2[..], &s.bgrad[..]);
        for i in 0..n {
            s.accel[i] = pressure_accel(c, x, m, offsets, indices, gs, pi, bgrad, i);
        }
        for (i, o) in out.iter_mut().enumerate() {
            *o = a_times_p(c, x, m, offsets, indices, gs, &s.accel, bgrad, i);
        }
        Ok(())
    }

    /// Runs the relaxed Jacobi solve (Algorithm 1 lines 6–13) on the last assembled system
    /// from `p = 0`; returns `(iterations, average compression, converged)`. The pressures
    /// are then [`Iisph::pressure`].
    pub fn solve_system(&mut self, state: &ParticleSet<R>) -> (usize, f64, bool) {
        let nb = self.neighbours.lists();
        let s = &mut self.scratch;
        s.pressure.iter_mut().for_each(|p| *p = R::zero());
        s.p_over_rho2.iter_mut().for_each(|p| *p = R::zero());
        s.accel.iter_mut().for_each(|a| *a = Vec3::zeros());
        pressure_solve(
            &self.c,
            &self.params,
            &state.positions,
            &state.masses,
            nb,
            s,
        )
    }

    /// Advances `state` by one frame of `substeps` IISPH time steps (see the crate docs).
    ///
    /// Checks the state first, reorders it by cell every `reorder_every` calls, and after
    /// each time step checks for divergence before writing its result
    /// ([`SolverError::BlowUp`]; the state then holds the last completed time step). Writes
    /// positions, velocities and densities (at the final positions). Does not allocate once
    /// its buffers have grown.
    pub fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, SolverError> {
        let step = self.steps;
        self.steps += 1;
        let mut stats = StepStats::new(IISPH_PHASES);
        begin_frame(
            state,
            &mut self.reorder,
            &self.params.common,
            step,
            FRAME,
            &mut stats,
        )?;
        let n = state.len();
        if self.scratch.pressure.len() != n {
            self.scratch.pressure.clear();
            self.scratch.stress.clear();
        } else if let Some(perm) = self.reorder.last_permutation() {
            let s = &mut self.scratch;
            apply_permutation(&mut s.pressure, perm, &mut s.perm_scalar);
            if s.stress.len() == n {
                apply_permutation(&mut s.stress, perm, &mut s.perm_sym);
            }
        }
        self.scratch.resize(n, self.c.granular);
        if let Some(u) = self.upscaler.as_mut() {
            if !u.seeded() {
                let t = Instant::now();
                u.seed(&state.positions, self.params.common.particle_spacing);
                stats.phases.add(UPSCALING, t.elapsed().as_secs_f64());
            }
        }
        let substeps = self.params.common.substeps;
        for sub in 0..substeps {
            let at = StepAt {
                solver: NAME,
                step,
                substep: sub,
            };
            self.substep(state, at, sub + 1 == substeps, &mut stats)?;
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
        last: bool,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        let h = self.params.common.support_radius;
        let search = self
            .neighbours
            .find_in_step(&state.positions, h, at, "position")?;
        stats.phases.add(CREATE_HASH_GRID, search.build_s());
        stats.phases.add(DETECT_NEIGHBOURS, search.detect_s());
        let nb = self.neighbours.lists();
        let c = self.c;
        let volume = self.boundary.has_volume().then_some(&*self.boundary);
        let (x, v, m) = (
            &state.positions[..],
            &state.velocities[..],
            &state.masses[..],
        );
        let s = &mut self.scratch;
        let p = &self.params;
        let g = p.common.gravity;

        // Algorithm 1, lines 2–5: density, drag, advection (with the friction of the kept
        // stress), predicted density, a_ii.
        let t = Instant::now();
        density_pass(&c, x, m, nb, volume, s);
        advection_pass(&c, g, x, v, m, nb, s);
        if c.granular {
            friction::predict(&c, x, m, nb, s);
        }
        predicted_density_pass(&c, x, m, nb, s);
        stats.phases.add(ADVECTION, t.elapsed().as_secs_f64());

        // Lines 6–13: relaxed Jacobi.
        let t = Instant::now();
        let (iterations, error, converged) = pressure_solve(&c, p, x, m, nb, s);
        stats.iterations += iterations;
        stats.last_solve_error = error;
        if !converged {
            stats.unconverged_substeps += 1;
        }
        stats.phases.add(PRESSURE_SOLVE, t.elapsed().as_secs_f64());

        // Lines 3 and 11 (stress and yield), solved after the pressure: see `friction`.
        if let Some(gp) = &p.granular {
            let t = Instant::now();
            let f = friction::solve(
                &c,
                gp.friction_max_iterations,
                gp.friction_tolerance.as_f64(),
                x,
                m,
                nb,
                s,
            );
            stats.friction_iterations += f.iterations;
            stats.last_friction_residual = f.residual;
            if !f.converged {
                stats.unconverged_friction_substeps += 1;
            }
            stats.phases.add(FRICTION_SOLVE, t.elapsed().as_secs_f64());
        }

        // Line 14: pressure and friction forces; line 15: integration.
        let t = Instant::now();
        forces_pass(&c, x, m, nb, &*self.boundary, s);
        stats.phases.add(FORCES, t.elapsed().as_secs_f64());

        let t = Instant::now();
        if last {
            let xn = &s.x_new[..];
            s.density_new
                .par_iter_mut()
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, rho)| *rho = density_at(&c.kernel, c.rho0, xn, m, nb, volume, i));
        }
        check_divergence(at, &s.x_new, &s.v_new, &*self.boundary, h)?;
        state.positions.copy_from_slice(&s.x_new);
        state.velocities.copy_from_slice(&s.v_new);
        if last {
            state.densities.copy_from_slice(&s.density_new);
        } else {
            state.densities.copy_from_slice(&s.density);
        }
        stats.phases.add(INTEGRATE, t.elapsed().as_secs_f64());
        stats.substeps += 1;
        stats.neighbour_pairs = nb.pair_count();

        // Line 16: advect the passive high-resolution points.
        if let Some(u) = self.upscaler.as_mut() {
            let t = Instant::now();
            u.advect(
                &state.positions,
                &state.velocities,
                &state.masses,
                &state.densities,
                &c.kernel,
                g,
                c.dt,
                &*self.boundary,
            );
            stats.phases.add(UPSCALING, t.elapsed().as_secs_f64());
        }
        Ok(())
    }
}

/// Eq. 3 + eq. 29: `ρ_i`, `∇Ψ_i`, `W'(r)/r` of every pair, and the diagonal `a_ii` of
/// eq. 24 (it needs only `x`, `m` and the particle's own density):
/// `a_ii = Σ_j m_j (d_ii − d_ji)·∇W_ij + ρ0 d_ii·∇Ψ_i
///       = −Δt²/ρ_i² (|Σ_j m_j ∇W_ij + ρ0 ∇Ψ_i|² + m_i Σ_j m_j |∇W_ij|²)`.
#[allow(clippy::needless_range_loop)] // k addresses the CSR pair arrays (indices, scales)
pub(crate) fn density_pass<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    volume: Option<&dyn Boundary<R>>,
    s: &mut Scratch<R>,
) {
    let offsets = nb.offsets();
    let indices = nb.indices();
    s.grad_scale.resize(indices.len(), R::zero());
    let dt2 = c.dt * c.dt;
    let outputs = (&mut s.density[..], &mut s.bgrad[..], &mut s.aii[..]);
    par_csr_blocks(
        offsets,
        outputs,
        &mut s.grad_scale[..],
        &|first, (rho_b, bg_b, aii_b): (&mut [R], &mut [Vec3<R>], &mut [R]), gs: &mut [R]| {
            let base = offsets[first];
            let block = rho_b.iter_mut().zip(bg_b.iter_mut()).zip(aii_b.iter_mut());
            for (l, ((rho, bg), aii)) in block.enumerate() {
                let i = first + l;
                let (xi, mi) = (x[i], m[i]);
                let mut sum = mi * c.w0;
                let mut sum_grad = Vec3::zeros();
                let mut sum_grad_sq = R::zero();
                for k in offsets[i]..offsets[i + 1] {
                    let j = indices[k] as usize;
                    let d = xi - x[j];
                    let r = d.norm();
                    sum += m[j] * c.kernel.value(r);
                    let f = if r > R::zero() {
                        c.kernel.derivative(r) / r
                    } else {
                        R::zero()
                    };
                    gs[k - base] = f;
                    let gw = d * f;
                    sum_grad += gw * m[j];
                    sum_grad_sq += m[j] * gw.norm_squared();
                }
                if let Some(b) = volume {
                    let smp = b.sample(&xi);
                    sum += c.rho0 * smp.volume;
                    *bg = smp.volume_gradient;
                } else {
                    *bg = Vec3::zeros();
                }
                *rho = sum;
                let gi = sum_grad + *bg * c.rho0;
                *aii = -dt2 / (sum * sum) * (gi.norm_squared() + mi * sum_grad_sq);
            }
            0.0
        },
    );
}

/// Eqs. 5–6 and 17–18: drag, viscosity, `v^adv`; the warm start `p⁰ = p(t − Δt) / 2` and
/// its `p/ρ²`.
pub(crate) fn advection_pass<R: Real>(
    c: &Consts<R>,
    g: Vec3<R>,
    x: &[Vec3<R>],
    v: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) {
    let offsets = nb.offsets();
    let indices = nb.indices();
    let (rho, gs) = (&s.density[..], &s.grad_scale[..]);
    let half = R::of_f64(0.5);
    let eps_h2 = R::of_f64(0.01) * c.h * c.h;
    let neighbour_terms = c.drag || c.visc > R::zero();
    // The body for particle i: writes v^adv, the warm start and p/ρ².
    let body = |i: usize, va: &mut Vec3<R>, pr: &mut R, pi: &mut R| {
        let (xi, vi, mi, rhoi) = (x[i], v[i], m[i], rho[i]);
        *pr *= half;
        *pi = *pr / (rhoi * rhoi);
        if !neighbour_terms {
            *va = vi + g * c.dt;
            return;
        }
        let mut visc = Vec3::zeros();
        let upstream = {
            let rel = c.air_velocity - vi;
            let len = rel.norm();
            if c.drag && len > R::zero() {
                -rel / len
            } else {
                Vec3::zeros()
            }
        };
        let mut occ = R::zero();
        for k in offsets[i]..offsets[i + 1] {
            let j = indices[k] as usize;
            let xj = x[j];
            if c.visc > R::zero() {
                let gw = grad(&xi, &xj, gs[k]);
                let vol_j = m[j] / rho[j];
                let xij = xi - xj;
                visc += gw * (vol_j * (vi - v[j]).dot(&xij) / (xij.norm_squared() + eps_h2));
            }
            if c.drag {
                occ = occ.max(occlusion(&upstream, &(xj - xi), c.cos_cone));
            }
        }
        let mut acc = g + visc * c.visc;
        if c.drag {
            let f = drag_force(
                c.air_velocity - vi,
                c.air_density,
                c.drag_coefficient,
                c.area,
                R::one() - occ,
            );
            acc += f / mi;
        }
        *va = vi + acc * c.dt;
    };
    s.v_adv
        .par_iter_mut()
        .zip(s.pressure.par_iter_mut())
        .zip(s.p_over_rho2.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, ((va, pr), pi))| body(i, va, pr, pi));
}

/// Eq. 19 (with the boundary term): the source `ρ0 − ρ_i^adv`; fused with the pressure
/// accelerations of the warm start `p⁰` (the first half of the first Jacobi iteration,
/// which reads the same neighbour data).
pub(crate) fn predicted_density_pass<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) {
    let offsets = nb.offsets();
    let indices = nb.indices();
    let (rho, gs, bgrad, va, pi) = (
        &s.density[..],
        &s.grad_scale[..],
        &s.bgrad[..],
        &s.v_adv[..],
        &s.p_over_rho2[..],
    );
    s.source
        .par_iter_mut()
        .zip(s.accel.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (src, acc))| {
            let (xi, vai, p_i) = (x[i], va[i], pi[i]);
            let mut div = R::zero();
            let mut a = Vec3::zeros();
            for k in offsets[i]..offsets[i + 1] {
                let j = indices[k] as usize;
                let gw = grad(&xi, &x[j], gs[k]);
                div += m[j] * (vai - va[j]).dot(&gw);
                a -= gw * (m[j] * (p_i + pi[j]));
            }
            div += c.rho0 * vai.dot(&bgrad[i]);
            let rho_adv = rho[i] + c.dt * div;
            *src = c.rho0 - rho_adv;
            *acc = a - bgrad[i] * (c.rho0 * p_i);
        });
}

/// The pressure acceleration `F^p_i/m_i = −Σ_j m_j (p_i/ρ_i² + p_j/ρ_j²) ∇W_ij − ρ0 (p_i/ρ_i²)
/// ∇Ψ_i` (eqs. 25 and 31) from `p/ρ²`.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn pressure_accel<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    offsets: &[usize],
    indices: &[u32],
    gs: &[R],
    pi: &[R],
    bgrad: &[Vec3<R>],
    i: usize,
) -> Vec3<R> {
    let (xi, p_i) = (x[i], pi[i]);
    let mut a = Vec3::zeros();
    for k in offsets[i]..offsets[i + 1] {
        let j = indices[k] as usize;
        a -= grad(&xi, &x[j], gs[k]) * (m[j] * (p_i + pi[j]));
    }
    a - bgrad[i] * (c.rho0 * p_i)
}

/// `(A p)_i = Δt² (Σ_j m_j (a_i − a_j)·∇W_ij + ρ0 a_i·∇Ψ_i)` from the pressure accelerations
/// `a` of `p`: the predicted density change due to pressure, `ρ_i^{l} − ρ_i^adv`, i.e. the
/// left side of Ihmsen et al.'s eq. 12 / Neder 2024 eqs. 20–23 (`a_ii p_i + ψ_i`).
#[inline]
#[allow(clippy::too_many_arguments)]
fn a_times_p<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    offsets: &[usize],
    indices: &[u32],
    gs: &[R],
    a: &[Vec3<R>],
    bgrad: &[Vec3<R>],
    i: usize,
) -> R {
    let (xi, ai) = (x[i], a[i]);
    let mut sum = R::zero();
    for k in offsets[i]..offsets[i + 1] {
        let j = indices[k] as usize;
        sum += m[j] * (ai - a[j]).dot(&grad(&xi, &x[j], gs[k]));
    }
    sum += c.rho0 * ai.dot(&bgrad[i]);
    c.dt * c.dt * sum
}

/// Relaxed Jacobi (Ihmsen et al. 2014 eq. 14, Neder 2024 eq. 20) with the unilateral
/// projection `p ≥ 0` (eq. 4): at least `min_iterations`, then until the average predicted
/// compression is below `η`, at most `max_iterations`. Expects `accel` to hold the pressure
/// accelerations of the starting pressures. Returns `(iterations, last average error,
/// converged)`.
pub(crate) fn pressure_solve<R: Real>(
    c: &Consts<R>,
    p: &IisphParams<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    s: &mut Scratch<R>,
) -> (usize, f64, bool) {
    let n = x.len();
    if n == 0 {
        return (0, 0.0, true);
    }
    let offsets = nb.offsets();
    let indices = nb.indices();
    let omega = p.relaxation;
    let eta = p.density_error_tolerance.as_f64();
    let inv_rho0 = 1.0 / c.rho0.as_f64();
    let mut error = 0.0;
    for l in 0..p.max_iterations {
        // Pressure accelerations of the iterate p^l (for l = 0 computed by
        // `predicted_density_pass`).
        if l > 0 {
            let (gs, pi, bgrad) = (&s.grad_scale[..], &s.p_over_rho2[..], &s.bgrad[..]);
            s.accel
                .par_iter_mut()
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, a)| {
                    *a = pressure_accel(c, x, m, offsets, indices, gs, pi, bgrad, i);
                });
        }
        // A p^l, the density error of p^l, and the update p^{l+1}.
        {
            let (gs, acc, bgrad, src, aii, rho) = (
                &s.grad_scale[..],
                &s.accel[..],
                &s.bgrad[..],
                &s.source[..],
                &s.aii[..],
                &s.density[..],
            );
            let update = |i: usize, pr: &mut R, pi: &mut R| -> f64 {
                let ap = a_times_p(c, x, m, offsets, indices, gs, acc, bgrad, i);
                let a = aii[i];
                let next = if a < R::zero() {
                    let q = *pr + omega * (src[i] - ap) / a;
                    if q > R::zero() {
                        q
                    } else {
                        R::zero()
                    }
                } else {
                    R::zero()
                };
                *pr = next;
                *pi = next / (rho[i] * rho[i]);
                // ρ_i^l − ρ0 = (A p)_i − (ρ0 − ρ_i^adv), counted where positive.
                (ap - src[i]).as_f64().max(0.0)
            };
            let total = par_update_sum(
                &mut s.pressure,
                &mut s.p_over_rho2,
                &mut s.error_partials,
                update,
            );
            error = total / n as f64 * inv_rho0;
        }
        if l + 1 >= p.min_iterations && error <= eta {
            return (l + 1, error, true);
        }
    }
    (p.max_iterations, error, false)
}

/// Line 14 (pressure and friction forces, eqs. 25–26 and 30–31) and line 15 (symplectic
/// Euler, eqs. 27–28), with the boundary's contact response on the new positions. A
/// granular step takes the velocity the friction solve left in `v_trial` (which holds both
/// forces); water adds the pressure acceleration to `v^adv`.
pub(crate) fn forces_pass<R: Real>(
    c: &Consts<R>,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    boundary: &dyn Boundary<R>,
    s: &mut Scratch<R>,
) {
    let offsets = nb.offsets();
    let indices = nb.indices();
    let (gs, pi, bgrad, va, vt) = (
        &s.grad_scale[..],
        &s.p_over_rho2[..],
        &s.bgrad[..],
        &s.v_adv[..],
        &s.v_trial[..],
    );
    let inv_dt = R::one() / c.dt;
    s.x_new
        .par_iter_mut()
        .zip(s.v_new.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (xn, vn))| {
            let v_new = if c.granular {
                vt[i]
            } else {
                va[i] + pressure_accel(c, x, m, offsets, indices, gs, pi, bgrad, i) * c.dt
            };
            let y = x[i] + v_new * c.dt;
            let projected = boundary.project(y);
            let push = projected - y;
            let mut v_out = v_new + push * inv_dt;
            if c.granular {
                v_out = coulomb_contact(v_out, push * inv_dt, c.wall_friction);
            }
            *vn = v_out;
            *xn = projected;
        });
}

/// Coulomb friction of the contact response (granular only): a particle the boundary pushed
/// out with the velocity change `dv_n` (along the wall normal) loses up to `μ |dv_n|` of
/// its tangential velocity, `μ = tan θ`. It acts only where the contact safety net acts
/// (particles the volume map's pressure did not hold off the wall, which have no
/// confining pressure and so no Drucker–Prager friction).
#[inline]
fn coulomb_contact<R: Real>(v: Vec3<R>, dv_n: Vec3<R>, mu: R) -> Vec3<R> {
    let push = dv_n.norm();
    if push <= R::zero() || mu <= R::zero() {
        return v;
    }
    let n = dv_n / push;
    let vn = n * v.dot(&n);
    let vt = v - vn;
    let speed_t = vt.norm();
    let loss = mu * push;
    if speed_t <= loss {
        vn
    } else {
        vn + vt * ((speed_t - loss) / speed_t)
    }
}

#[cfg(test)]
mod tests {
    use super::coulomb_contact;
    use sph_core::Vec3;

    /// Coulomb's law at a contact: the tangential speed drops by `μ |Δv_n|` (to zero at
    /// most), the normal velocity is kept, and without a push nothing changes.
    #[test]
    fn coulomb_contact_follows_coulombs_law() {
        let v = Vec3::new(2.0, 0.5, 0.0);
        let push = Vec3::new(0.0, 1.0, 0.0);
        let out = coulomb_contact(v, push, 0.5);
        assert!((out - Vec3::new(1.5, 0.5, 0.0)).norm() < 1e-12, "{out}");
        let stopped = coulomb_contact(v, push * 10.0, 0.5);
        assert!(
            (stopped - Vec3::new(0.0, 0.5, 0.0)).norm() < 1e-12,
            "{stopped}"
        );
        assert_eq!(coulomb_contact(v, Vec3::zeros(), 0.5), v);
        assert_eq!(coulomb_contact(v, push, 0.0), v);
    }
}
