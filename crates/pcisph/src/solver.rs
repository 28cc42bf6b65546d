//! The PCISPH time step (see the crate documentation for the equations), one per
//! [`SubstepScheme::substep`] of the frame shell.

use std::time::Instant;

use rayon::prelude::*;
use sph_core::{ParticleSet, Real, Vec3};
use sph_kernels::{Kernel, KernelKind};
use sph_solver::step::{
    check_divergence, check_predicted, density_at, FramePhases, StepAt, MIN_LEN,
};
use sph_solver::{FrameSolver, SchemeParts, SolverError, StepStats, SubstepScheme};

use crate::kernels::{Consts, PCISPH_KERNEL};
use crate::params::PcisphParams;
use crate::scratch::Scratch;

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

/// The PCISPH solver of Solenthaler & Pajarola (2009); see the crate documentation.
pub type Pcisph<R> = FrameSolver<R, PcisphScheme<R>>;

/// The time step of [`Pcisph`] as a [`SubstepScheme`] (its parameters, kernels and `δ`,
/// working arrays, boundary and neighbour search). PCISPH starts every time step from
/// `p = 0`, so it carries nothing from one frame to the next besides the particles.
#[derive(Debug)]
pub struct PcisphScheme<R: Real> {
    params: PcisphParams<R>,
    c: Consts<R>,
    parts: SchemeParts<R>,
    scratch: Scratch<R>,
}

/// Symplectic Euler with total acceleration `a`: `v* = v + Δt a` and the position
/// `x + Δt v*` before the contact response.
#[inline]
fn advance<R: Real>(x: Vec3<R>, v: Vec3<R>, a: Vec3<R>, dt: R) -> (Vec3<R>, Vec3<R>) {
    let v_star = v + a * dt;
    (v_star, x + v_star * dt)
}

impl<R: Real> SubstepScheme<R> for PcisphScheme<R> {
    type Params = PcisphParams<R>;
    const PHASES: &'static [&'static str] = PCISPH_PHASES;
    const FRAME_PHASES: FramePhases = FramePhases {
        checks: INTEGRATE,
        reorder: REORDER,
        statistics: VELOCITY_UPDATE,
    };
    const DENSITY_KERNEL: KernelKind = PCISPH_KERNEL;

    fn new(params: PcisphParams<R>, parts: SchemeParts<R>) -> Result<Self, SolverError> {
        Ok(Self {
            c: Consts::new(&params)?,
            params,
            parts,
            scratch: Scratch::default(),
        })
    }
    fn params(&self) -> &PcisphParams<R> {
        &self.params
    }
    fn parts(&self) -> &SchemeParts<R> {
        &self.parts
    }
    fn begin_frame(
        &mut self,
        state: &mut ParticleSet<R>,
        _permutation: Option<&[u32]>,
        _stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        self.scratch.resize(state.len());
        Ok(())
    }
    fn substep(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        _last: bool,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        self.time_step(state, at, stats)
    }
}

impl<R: Real> PcisphScheme<R> {
    /// The scaling factor `δ` of S&P09 eq. 8 (m²/s²), computed once by [`Pcisph::new`]
    /// ([`PcisphParams::scaling_factor`]).
    pub fn delta(&self) -> R {
        self.c.delta
    }

    /// The pressures `p_i` (Pa) at the end of the last time step's iterations.
    pub fn pressure(&self) -> &[R] {
        &self.scratch.pressure
    }

    fn time_step(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        let volume = self
            .parts
            .boundary
            .has_volume()
            .then_some(&*self.parts.boundary);
        let boundary = &*self.parts.boundary;
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
        let search_stats = self.parts.neighbours.find_in_step(x, h, at, "position")?;
        stats.phases.add(CREATE_HASH_GRID, search_stats.build_s());
        stats.phases.add(DETECT_NEIGHBOURS, search_stats.detect_s());
        let nb = self.parts.neighbours.lists();

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
