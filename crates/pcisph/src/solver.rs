//! The PCISPH time step (see the crate documentation for the equations).

use std::fmt;
use std::time::Instant;

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{ParticleSet, Real, Sdf, Vec3};
use sph_kernels::{Kernel, Poly6, Spiky};
use sph_solver::boundary::check_volume_kernel;
use sph_solver::step::{
    begin_frame, check_divergence, check_predicted, density_at, end_frame, CellReorder,
    FramePhases, StepAt, StepNeighbours, MIN_LEN,
};
use sph_solver::{Boundary, CollisionBoundary, Solids, SolverError, StepStats};

use crate::PcisphParams;

/// The phases [`Pcisph::step`] times ([`StepStats::phases`]).
pub const PCISPH_PHASES: &[&str] = &[
    "integrate",
    "create_hash_grid",
    "detect_neighbours",
    "pressure_solve",
    "velocity_update",
    "reorder",
];
const INTEGRATE: usize = 0;
const CREATE_HASH_GRID: usize = 1;
const DETECT_NEIGHBOURS: usize = 2;
const PRESSURE_SOLVE: usize = 3;
const VELOCITY_UPDATE: usize = 4;
const REORDER: usize = 5;
const FRAME: FramePhases = FramePhases {
    checks: INTEGRATE,
    reorder: REORDER,
    statistics: VELOCITY_UPDATE,
};

const NAME: &str = "PCISPH";

/// Kernels and constants of the per-particle loops.
#[derive(Debug, Clone, Copy)]
struct Consts<R: Real> {
    poly6: Poly6<R>,
    spiky: Spiky<R>,
    rho0: R,
    inv_rho0: R,
    /// `1/ρ0²` of the pressure force.
    inv_rho0_sq: R,
    delta: R,
}

impl<R: Real> Consts<R> {
    fn new(p: &PcisphParams<R>) -> Result<Self, SolverError> {
        let h = p.common.support_radius;
        let poly6 = Poly6::new(h)?;
        let rho0 = p.common.rest_density;
        let inv_rho0 = R::one() / rho0;
        Ok(Self {
            poly6,
            spiky: Spiky::new(h)?,
            rho0,
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
    /// Predicted positions `x*` (after the contact response); at the end, the final
    /// positions.
    predicted: Vec<Vec3<R>>,
    pressure: Vec<R>,
    /// Pressure acceleration `F^p_i / m_i`.
    accel: Vec<Vec3<R>>,
    /// `∇Ψ` of a volume boundary at `x(t)` (zero otherwise).
    boundary_grad: Vec<Vec3<R>>,
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
        self.boundary_grad.resize(n, z);
        self.density.resize(n, R::zero());
        self.velocity_new.resize(n, z);
    }
}

/// The PCISPH solver of Solenthaler & Pajarola (2009); see the crate documentation.
pub struct Pcisph<R: Real> {
    params: PcisphParams<R>,
    c: Consts<R>,
    boundary: Box<dyn Boundary<R>>,
    neighbours: StepNeighbours<R>,
    scratch: Scratch<R>,
    reorder: CellReorder<R>,
    steps: u64,
}

impl<R: Real> fmt::Debug for Pcisph<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Pcisph")
            .field("params", &self.params)
            .field("delta", &self.c.delta)
            .field("boundary", &self.boundary.name())
            .field("solids", &self.boundary.solids().len())
            .field("particles", &self.scratch.predicted.len())
            .field("steps", &self.steps)
            .finish()
    }
}

/// Symplectic Euler with total acceleration `a`: `v* = v + Δt a` and the position
/// `x + Δt v*` before the contact response.
#[inline]
fn advance<R: Real>(x: Vec3<R>, v: Vec3<R>, a: Vec3<R>, dt: R) -> (Vec3<R>, Vec3<R>) {
    let v_star = v + a * dt;
    (v_star, x + v_star * dt)
}

impl<R: Real> Pcisph<R> {
    /// A solver with validated `params` and the given solids as a [`CollisionBoundary`]
    /// with the particle radius `s / 2` as contact distance. Computes `δ`.
    pub fn new(params: PcisphParams<R>, solids: Solids<R>) -> Result<Self, SolverError> {
        let boundary = CollisionBoundary::new(solids, params.particle_radius())?;
        Self::with_boundary(params, Box::new(boundary))
    }

    /// A solver with validated `params` and any boundary model. A boundary that takes part
    /// in the density must have been integrated with Poly6 of this solver's support radius,
    /// otherwise [`SolverError::InvalidParameter`].
    pub fn with_boundary(
        params: PcisphParams<R>,
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

    /// The boundary.
    pub fn boundary(&self) -> &dyn Boundary<R> {
        &*self.boundary
    }

    /// The solids, in the order contacts are resolved.
    pub fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        self.boundary.solids()
    }

    /// The neighbour lists of the last time step (found at its start positions).
    pub fn neighbours(&self) -> &NeighbourLists {
        self.neighbours.lists()
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

    /// Advances `state` by one whole frame, `common.dt` (16 ms by default), made of
    /// `common.substeps` PCISPH time steps (see the crate documentation): one call is a
    /// frame, not one time step.
    ///
    /// **Particle order.** Every `common.reorder_every` calls (the first call included), the
    /// call begins by reordering the particles of `state` by grid cell: afterwards
    /// [`Pcisph::last_permutation`] returns `perm` with `new[k] = old[perm[k]]` (`None` when
    /// the call did not reorder). To follow particles, keep an index map `ids` (initially
    /// `0..n`) and compose it after each call, `ids = perm.iter().map(|&o| ids[o as
    /// usize]).collect()`, so `ids[k]` is the original index of the particle now at `k`
    /// (the `pbf` and `sph-scene` crate examples show it); `reorder_every = 0` keeps the
    /// input order.
    ///
    /// Checks the state first ([`SolverError::InvalidState`], [`SolverError::InvalidMass`]),
    /// reorders it by cell every `reorder_every` calls, and after each time step checks for
    /// divergence before writing its result into `state` ([`SolverError::BlowUp`]; `state`
    /// then holds the last completed time step, never a non-finite value). Writes positions,
    /// velocities and densities (at the final positions). Does not allocate once its buffers
    /// have grown.
    pub fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, SolverError> {
        let step = self.steps;
        self.steps += 1;
        let mut stats = StepStats::new(PCISPH_PHASES);
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
        let boundary = &*self.boundary;
        let p = &self.params;
        let c = self.c;
        let dt = p.substep_dt();
        let inv_dt = R::one() / dt;
        let g = p.common.gravity;
        let h = p.common.support_radius;
        let rho0 = p.common.rest_density;
        let s = &mut self.scratch;
        let (x, v, m) = (
            &state.positions[..],
            &state.velocities[..],
            &state.masses[..],
        );

        // Step 1: neighbours once, at the current positions.
        let search_stats = self.neighbours.find_in_step(x, h, at, "position")?;
        stats.phases.add(CREATE_HASH_GRID, search_stats.build_s());
        stats.phases.add(DETECT_NEIGHBOURS, search_stats.detect_s());
        let nb = self.neighbours.lists();

        // Step 2: non-pressure forces (XSPH, gravity), p = 0, first prediction; the
        // boundary's ∇Ψ at x(t) for the pressure force.
        let t = Instant::now();
        let xsph_c = p.xsph_c;
        s.velocity
            .par_iter_mut()
            .zip(s.predicted.par_iter_mut())
            .zip(s.pressure.par_iter_mut())
            .zip(s.accel.par_iter_mut())
            .zip(s.boundary_grad.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, ((((vel, xp), pr), acc), bg))| {
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
                if let Some(b) = volume {
                    *bg = b.sample(&xi).volume_gradient;
                }
                *xp = boundary.project(advance(xi, vn, g, dt).1);
            });
        check_predicted(at, &s.predicted)?;
        stats.phases.add(INTEGRATE, t.elapsed().as_secs_f64());

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
                    let r = density_at(&c.poly6, c.rho0, xp, m, nb, volume, i);
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
            let (vel, bgrad) = (&s.velocity[..], &s.boundary_grad[..]);
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
                    if volume.is_some() {
                        // −Σ_b ρ0 V_b (p_i/ρ0²) ∇W_ib = −(p_i/ρ0) ∇Ψ.
                        a -= bgrad[i] * (pi * c.inv_rho0);
                    }
                    *acc = a;
                    *xn = boundary.project(advance(xi, vel[i], g + a, dt).1);
                });
            if converged {
                break;
            }
        }
        stats.phases.add(PRESSURE_SOLVE, t.elapsed().as_secs_f64());

        // Step 4: final velocities (with the contact displacement), densities.
        let t = Instant::now();
        let (xp, vel, acc) = (&s.predicted[..], &s.velocity[..], &s.accel[..]);
        s.density
            .par_iter_mut()
            .zip(s.velocity_new.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, (rho, vn))| {
                // xp[i] is project(y): the last prediction used the same acceleration.
                let (v_star, y) = advance(x[i], vel[i], g + acc[i], dt);
                *vn = v_star + (xp[i] - y) * inv_dt;
                *rho = density_at(&c.poly6, c.rho0, xp, m, nb, volume, i);
            });
        check_divergence(at, xp, &s.velocity_new, boundary, h)?;
        state.positions.copy_from_slice(xp);
        state.velocities.copy_from_slice(&s.velocity_new);
        state.densities.copy_from_slice(&s.density);
        stats.phases.add(VELOCITY_UPDATE, t.elapsed().as_secs_f64());
        stats.substeps += 1;
        stats.neighbour_pairs = nb.pair_count();
        Ok(())
    }
}
