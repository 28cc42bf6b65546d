//! The solver: Algorithm 1 of Macklin & Müller (2013), one time step per
//! [`SubstepScheme::substep`] of the frame shell.

use std::time::Instant;

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{validate_finite_positions, CoreError, ParticleSet, Real, Vec3};
use sph_kernels::{Kernel, KernelKind};
use sph_solver::boundary::check_volume_kernel;
use sph_solver::step::{
    check_divergence_cleared, check_masses, check_predicted, FramePhases, StepAt, MIN_LEN,
};
use sph_solver::{Boundary, FrameSolver, SchemeParts, SolverError, StepStats, SubstepScheme};

use crate::kernels::{Consts, PBF_KERNEL};
use crate::lanes::{self, LaneConsts};
use crate::params::PbfParams;
use crate::passes::{delta_pass, lambda_pass, near_boundary, LambdaOut, PassInput};
use crate::scratch::PbfScratch;

/// The Position Based Fluids solver of
///
/// > Miles Macklin and Matthias Müller, "Position Based Fluids", *ACM Transactions on
/// > Graphics* 32(4), Article 104, 2013 (SIGGRAPH 2013),
///
/// Algorithm 1, one call of [`FrameSolver::step`] advancing one whole frame of `substeps` steps of
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
pub type Pbf<R> = FrameSolver<R, PbfScheme<R>>;

/// The time step of [`Pbf`]: Algorithm 1 of Macklin & Müller (2013) as a [`SubstepScheme`]
/// (its parameters, kernels, working arrays, boundary and neighbour search). PBF carries
/// nothing from one frame to the next besides the particles.
#[derive(Debug)]
pub struct PbfScheme<R: Real> {
    params: PbfParams<R>,
    c: Consts<R>,
    parts: SchemeParts<R>,
    scratch: PbfScratch<R>,
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

use crate::params::NAME;

/// What [`PbfScheme::evaluate_constraints`] computed, borrowed from the solver.
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

impl<R: Real> SubstepScheme<R> for PbfScheme<R> {
    type Params = PbfParams<R>;
    const PHASES: &'static [&'static str] = PBF_PHASES;
    const FRAME_PHASES: FramePhases = FramePhases {
        checks: INTEGRATE,
        reorder: REORDER,
        statistics: VELOCITY_UPDATE,
    };
    const DENSITY_KERNEL: KernelKind = PBF_KERNEL;

    fn new(params: PbfParams<R>, parts: SchemeParts<R>) -> Result<Self, SolverError> {
        Ok(Self {
            c: Consts::new(&params)?,
            params,
            parts,
            scratch: PbfScratch::default(),
        })
    }
    fn params(&self) -> &PbfParams<R> {
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

impl<R: Real> PbfScheme<R> {
    /// Replaces the parameters (validated; the kernels are rebuilt, the buffers kept). The
    /// support radius must stay that of a volume boundary's kernel.
    pub fn set_params(&mut self, params: PbfParams<R>) -> Result<(), SolverError> {
        params.validate()?;
        check_volume_kernel(
            &*self.parts.boundary,
            NAME,
            PBF_KERNEL,
            params.common.support_radius,
        )?;
        self.c = Consts::new(&params)?;
        self.parts
            .neighbours
            .set_method(params.common.neighbour_method);
        self.params = params;
        Ok(())
    }

    /// The working arrays (values of the last substep).
    pub fn scratch(&self) -> &PbfScratch<R> {
        &self.scratch
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
        let volume = self
            .parts
            .boundary
            .has_volume()
            .then_some(&*self.parts.boundary);
        let s = &mut self.scratch;
        s.predicted.copy_from_slice(positions);
        self.parts
            .neighbours
            .find(&s.predicted, self.params.common.support_radius)?;
        if let Some(b) = volume {
            near_boundary(
                b,
                &s.predicted,
                self.params.common.support_radius,
                &mut s.clearance,
                &mut s.near_boundary,
            );
        }
        let volume = volume.map(|b| (b, &s.near_boundary[..]));
        let nb = self.parts.neighbours.lists();
        let input = PassInput {
            c: &self.c,
            x: &s.predicted,
            m: masses,
            nb,
            volume,
            lanes: LaneConsts::new(&self.c, n, nb),
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
            &*self.parts.boundary,
            (None, &mut s.clearance),
            &mut s.delta_p,
            &mut s.next,
        );
        Ok(ConstraintEval {
            density: &s.density,
            lambda: &s.lambda,
            delta_p: &s.delta_p,
            neighbours: self.parts.neighbours.lists(),
        })
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
        let p = &self.params;
        let c = self.c;
        let dt = p.substep_dt();
        let g = p.common.gravity;
        let h = p.common.support_radius;
        let s = &mut self.scratch;
        let boundary = &*self.parts.boundary;

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
            self.parts
                .neighbours
                .find_in_step(&s.predicted, h, at, "predicted position")?;
        stats.phases.add(CREATE_HASH_GRID, search_stats.build_s());
        stats.phases.add(DETECT_NEIGHBOURS, search_stats.detect_s());
        let nb = self.parts.neighbours.lists();
        let m = &state.masses[..];

        // Lines 8–19: Jacobi iterations with the contact response.
        let t = Instant::now();
        // Distances at the predicted positions: the volume's reach and the contact guard's
        // bounds (the contact response and the divergence check then evaluate the solids
        // only for the particles near them).
        let guard = boundary.contact_guard();
        if volume.is_some() || guard.is_some() {
            near_boundary(
                boundary,
                &s.predicted,
                h,
                &mut s.clearance,
                &mut s.near_boundary,
            );
        }
        let reach = volume.map(|b| (b, &s.near_boundary[..]));
        let lanes = LaneConsts::new(&c, state.len(), nb);
        let inv_n = 1.0 / (state.len().max(1) as f64);
        let mut done = 0;
        loop {
            let input = PassInput {
                c: &c,
                x: &s.predicted,
                m,
                nb,
                volume: reach,
                lanes,
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
                (guard, &mut s.clearance),
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
                lanes,
            },
            s,
        );
        let x = &s.predicted[..];

        // Divergence checks before anything is written to the state.
        let bounds = guard.map(|_| &s.clearance[..]);
        check_divergence_cleared(at, x, &s.velocity_new, boundary, h, bounds)?;
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
    lanes: Option<LaneConsts>,
}

/// Algorithm 1 lines 20–22: `v = (x* − x)/Δt`, the densities at the final positions (for
/// the statistics and the state), vorticity (eq. 15) and confinement (eq. 16), XSPH
/// (eq. 17); the new velocities go to `s.velocity_new`. A volume boundary's `ρ0 Ψ` is
/// sampled only for the particles the Jacobi iterations sampled (`s.near_boundary`, from
/// [`near_boundary`] at this step's predicted positions): the others have `Ψ = 0` by the
/// argument of [`near_boundary`], and adding `ρ0 · 0` changes no density.
fn velocity_update<R: Real>(input: VelocityInput<'_, R>, s: &mut PbfScratch<R>) {
    let VelocityInput {
        c,
        p,
        x_old,
        m,
        nb,
        volume,
        lanes,
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
    let near = &s.near_boundary[..];
    if lanes.is_some() && !vort_on {
        s.pairs.packed.fill(x, m);
        lanes::pack_velocities(&mut s.pairs.packed_v, v);
    }
    let packed = (&s.pairs.packed, &s.pairs.packed_v);
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
            let lanes = lanes.filter(|_| !vort_on);
            if let Some(l) = &lanes {
                let (pair_w, pair_xsph) = lanes::density_xsph(l, packed, v, nb, i);
                sum_w += pair_w;
                if xsph_on {
                    xsph = pair_xsph;
                }
            }
            // The scalar loop runs only without the lanes.
            let scalar_list = if lanes.is_some() {
                &[][..]
            } else {
                nb.neighbours(i)
            };
            for &j in scalar_list {
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
            if let Some(bd) = volume.filter(|_| near[i]) {
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
