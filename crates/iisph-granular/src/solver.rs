//! The IISPH time step with the granular extension (see the crate documentation for the
//! equations), one per [`SubstepScheme::substep`] of the frame shell, and what it carries
//! from one frame to the next (warm-started pressures, the frictional stress, the passive
//! points of the upscaling).

use std::time::Instant;

use sph_core::{apply_permutation, ParticleSet, Real, Vec3};
use sph_kernels::KernelKind;
use sph_solver::density_lanes::densities_at;
use sph_solver::state::match_arrays;
use sph_solver::step::{check_divergence_cleared, FramePhases, StepAt};
use sph_solver::{ArraySpec, FrameSolver, SchemeParts, SolverError, StepStats, SubstepScheme};

use crate::friction;
use crate::granular::Sym3;
use crate::kernels::{Consts, IISPH_KERNEL};
use crate::params::{IisphParams, NAME};
use crate::passes::{
    a_times_p, advection_pass, density_pass, forces_pass, predicted_density_pass, pressure_accel,
    pressure_solve,
};
use crate::scratch::Scratch;
use crate::upscale::Upscaler;

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

/// Names of the arrays IISPH carries between frames ([`sph_solver::SolverState::arrays`]):
/// the pressures of the warm start (1 per particle), the frictional stress (granular; 6 per
/// particle, `[xx, yy, zz, xy, xz, yz]`), its friction acceleration (granular; 3 per
/// particle, m/s², the next step's predicted friction), and the upscaling's passive points
/// and their velocities (3 per point).
pub const IISPH_STATE_ARRAYS: [&str; 5] = [
    "pressure",
    "stress",
    "friction_acceleration",
    "passive_positions",
    "passive_velocities",
];

/// Implicit incompressible SPH (Ihmsen et al. 2014) for water and, with
/// [`crate::GranularParams`], granular matter (Neder 2024); see the crate documentation.
pub type Iisph<R> = FrameSolver<R, IisphScheme<R>>;

/// The time step of [`Iisph`] as a [`SubstepScheme`] (its parameters, kernels, working
/// arrays, boundary, neighbour search and upscaling).
#[derive(Debug)]
pub struct IisphScheme<R: Real> {
    params: IisphParams<R>,
    c: Consts<R>,
    parts: SchemeParts<R>,
    scratch: Scratch<R>,
    upscaler: Option<Upscaler<R>>,
}

impl<R: Real> SubstepScheme<R> for IisphScheme<R> {
    type Params = IisphParams<R>;
    const PHASES: &'static [&'static str] = IISPH_PHASES;
    const FRAME_PHASES: FramePhases = FramePhases {
        checks: INTEGRATE,
        reorder: REORDER,
        statistics: INTEGRATE,
    };
    const DENSITY_KERNEL: KernelKind = IISPH_KERNEL;

    fn new(params: IisphParams<R>, parts: SchemeParts<R>) -> Result<Self, SolverError> {
        Ok(Self {
            c: Consts::new(&params)?,
            upscaler: params.upscaling_factor.map(Upscaler::new),
            params,
            parts,
            scratch: Scratch::default(),
        })
    }
    fn params(&self) -> &IisphParams<R> {
        &self.params
    }
    fn parts(&self) -> &SchemeParts<R> {
        &self.parts
    }
    fn name(&self) -> &'static str {
        if self.params.granular.is_some() {
            "IISPH-granular"
        } else {
            "IISPH"
        }
    }

    /// Keeps the pressures (and stresses) of the last frame for the warm start, in the new
    /// particle order; seeds the passive points on the first frame.
    fn begin_frame(
        &mut self,
        state: &mut ParticleSet<R>,
        permutation: Option<&[u32]>,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        let n = state.len();
        if self.scratch.pressure.len() != n {
            let s = &mut self.scratch;
            s.pressure.clear();
            s.stress.clear();
            // A zero stress has zero friction.
            s.friction_accel.clear();
            s.friction_accel_current = true;
        } else if let Some(perm) = permutation {
            let s = &mut self.scratch;
            apply_permutation(&mut s.pressure, perm, &mut s.perm_scalar);
            if s.stress.len() == n {
                apply_permutation(&mut s.stress, perm, &mut s.perm_sym);
            }
            if s.friction_accel.len() == n {
                apply_permutation(&mut s.friction_accel, perm, &mut s.perm_vec);
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
        Ok(())
    }

    fn substep(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        last: bool,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        self.time_step(state, at, last, stats)
    }

    /// `pressure` and (granular) `stress` and `friction_acceleration` once a frame has run;
    /// the passive points and their velocities once seeded.
    fn save_arrays(&self, arrays: &mut Vec<(String, Vec<R>)>) {
        let s = &self.scratch;
        if !s.pressure.is_empty() {
            arrays.push(("pressure".into(), s.pressure.clone()));
        }
        if !s.stress.is_empty() {
            arrays.push((
                "stress".into(),
                s.stress.iter().flatten().copied().collect(),
            ));
            if s.friction_accel_current && s.friction_accel.len() == s.stress.len() {
                let a = &s.friction_accel;
                arrays.push((
                    "friction_acceleration".into(),
                    a.iter().flat_map(|v| [v.x, v.y, v.z]).collect(),
                ));
            }
        }
        if let Some(u) = self.upscaler.as_ref().filter(|u| u.seeded()) {
            let flat = |v: &[Vec3<R>]| v.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
            arrays.push(("passive_positions".into(), flat(u.points())));
            arrays.push(("passive_velocities".into(), flat(u.velocities())));
        }
    }

    /// Accepts the arrays of [`IISPH_STATE_ARRAYS`] that fit: `pressure` (`n` values),
    /// `stress` (granular only, `6 n`), `friction_acceleration` (granular only, `3 n`), and
    /// both or neither of the passive arrays (upscaling only, `3 k n` each for `k` points
    /// per particle). An absent `pressure` or `stress` is the cold start of a fresh solver;
    /// an absent `friction_acceleration` is recomputed from the stress by the next step
    /// (bitwise resumption needs it); absent passive arrays are seeded by the next frame.
    fn restore_arrays(
        &mut self,
        arrays: &[(String, Vec<R>)],
        particles: usize,
    ) -> Result<(), SolverError> {
        let n = particles;
        let granular = self.c.granular;
        let points = self.params.upscaling_factor.map_or(0, |k| k * n);
        let mut accepted = vec![ArraySpec {
            name: "pressure",
            len: n,
        }];
        if granular {
            accepted.push(ArraySpec {
                name: "stress",
                len: 6 * n,
            });
            accepted.push(ArraySpec {
                name: "friction_acceleration",
                len: 3 * n,
            });
        }
        if self.upscaler.is_some() {
            for name in ["passive_positions", "passive_velocities"] {
                accepted.push(ArraySpec {
                    name,
                    len: 3 * points,
                });
            }
        }
        let found = match_arrays(self.name(), arrays, &accepted)?;
        let k = if granular { 3 } else { 1 };
        let passive = (
            found.get(k).copied().flatten(),
            found.get(k + 1).copied().flatten(),
        );
        if passive.0.is_some() != passive.1.is_some() {
            return Err(SolverError::InvalidSolverState {
                solver: self.name().to_owned(),
                reason: "the passive points need both `passive_positions` and `passive_velocities`"
                    .into(),
            });
        }
        let vec3 = |f: &[R]| {
            f.chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect::<Vec<_>>()
        };
        let s = &mut self.scratch;
        s.pressure.clear();
        s.stress.clear();
        s.friction_accel.clear();
        if let Some(p) = found[0] {
            s.pressure.extend_from_slice(p);
        }
        let stress = found.get(1).copied().flatten().filter(|_| granular);
        let accel = found.get(2).copied().flatten().filter(|_| granular);
        if let Some(st) = stress {
            s.stress
                .extend(st.chunks_exact(6).map(|c| std::array::from_fn(|e| c[e])));
        }
        // Without a stress the friction is zero; with one, its acceleration is restored or
        // recomputed by the next step.
        s.friction_accel_current = stress.is_none() || accel.is_some();
        if let (Some(a), Some(_)) = (accel, stress) {
            s.friction_accel = vec3(a);
        }
        if let (Some(u), (Some(x), Some(v))) = (self.upscaler.as_mut(), passive) {
            u.restore(vec3(x), vec3(v));
        }
        Ok(())
    }

    fn passive_points(&self) -> Option<&[Vec3<R>]> {
        self.upscaler
            .as_ref()
            .and_then(|u| u.seeded().then_some(u.points()))
    }
}

impl<R: Real> IisphScheme<R> {
    /// The pressures `p_i` (Pa) of the last time step.
    pub fn pressure(&self) -> &[R] {
        &self.scratch.pressure
    }

    /// The frictional stresses `s_i` (Pa, symmetric `[xx, yy, zz, xy, xz, yz]`,
    /// deviatoric, `‖s_i‖ ≤ α p_i`) the last time step applied (empty for water).
    pub fn stress(&self) -> &[Sym3<R>] {
        &self.scratch.stress
    }

    /// Sets up the pressure system of one time step from `state` without advancing it:
    /// neighbours, densities, advection and the predicted density (Algorithm 1 lines 1–5),
    /// with a cold start `p⁰ = 0`. Afterwards [`IisphScheme::system_diagonal`],
    /// [`IisphScheme::system_source`], [`IisphScheme::apply_system`] and [`IisphScheme::solve_system`] inspect
    /// and solve it (for tests and studies of the solver; [`Iisph::step`] does the same
    /// internally). Errors as [`Iisph::step`].
    pub fn assemble_system(&mut self, state: &ParticleSet<R>) -> Result<(), SolverError> {
        sph_solver::step::check_state(state)?;
        let n = state.len();
        self.scratch.pressure.clear();
        self.scratch.resize(n, self.c.granular);
        let at = StepAt {
            solver: NAME,
            step: 0,
            substep: 0,
        };
        let h = self.params.common.support_radius;
        self.parts
            .neighbours
            .find_in_step(&state.positions, h, at, "position")?;
        let nb = self.parts.neighbours.lists();
        let volume = self
            .parts
            .boundary
            .has_volume()
            .then_some(&*self.parts.boundary);
        let (x, v, m) = (
            &state.positions[..],
            &state.velocities[..],
            &state.masses[..],
        );
        let s = &mut self.scratch;
        density_pass(&self.c, x, v, m, nb, volume, s);
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
    /// [`IisphScheme::assemble_system`]): the density change `Σ_j m_j (Δt a^p_i − Δt a^p_j)·∇W_ij
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
        let nb = self.parts.neighbours.lists();
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
    /// are then [`IisphScheme::pressure`].
    pub fn solve_system(&mut self, state: &ParticleSet<R>) -> (usize, f64, bool) {
        let nb = self.parts.neighbours.lists();
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

    fn time_step(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        last: bool,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        let h = self.params.common.support_radius;
        let search = self
            .parts
            .neighbours
            .find_in_step(&state.positions, h, at, "position")?;
        stats.phases.add(CREATE_HASH_GRID, search.build_s());
        stats.phases.add(DETECT_NEIGHBOURS, search.detect_s());
        let nb = self.parts.neighbours.lists();
        let c = self.c;
        let volume = self
            .parts
            .boundary
            .has_volume()
            .then_some(&*self.parts.boundary);
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
        density_pass(&c, x, v, m, nb, volume, s);
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
        forces_pass(&c, x, m, nb, &*self.parts.boundary, s);
        stats.phases.add(FORCES, t.elapsed().as_secs_f64());

        let t = Instant::now();
        if last {
            densities_at(
                &c.kernel,
                c.rho0,
                &s.x_new,
                m,
                nb,
                None,
                &mut s.packed,
                &mut s.density_new,
            );
            // The boundary's term, sampled once: the next step's density pass reuses the
            // samples at these positions.
            match volume {
                Some(b) => {
                    s.end_samples.fill(&s.x_new, b);
                    let samples = s.end_samples.samples();
                    for (rho, smp) in s.density_new.iter_mut().zip(samples) {
                        *rho += c.rho0 * smp.volume;
                    }
                }
                None => s.end_samples.clear(),
            }
        }
        let boundary = &*self.parts.boundary;
        let bounds = boundary.contact_guard().map(|_| &s.clearance[..]);
        check_divergence_cleared(at, &s.x_new, &s.v_new, boundary, h, bounds)?;
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
                &*self.parts.boundary,
            );
            stats.phases.add(UPSCALING, t.elapsed().as_secs_f64());
        }
        Ok(())
    }
}
