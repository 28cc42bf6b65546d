//! The scheme: explicit steps of Bui et al. (2008) sub-cycled inside each substep of the
//! frame shell, neighbour lists kept across steps while particles move less than half the
//! skin.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Matrix3;
use sph_core::{apply_permutation, ParticleSet, Real, Vec3};
use sph_kernels::{Kernel, KernelKind};
use sph_solver::boundary::{check_volume_kernel, VolumeMapBoundary};
use sph_solver::scene_boundary::{PeriodicAxis, Pour};
use sph_solver::state::{match_arrays, ArraySpec};
use sph_solver::step::{blow_up, check_divergence, FramePhases, StepAt};
use sph_solver::{Dimensions, FrameSolver, SchemeParts, SolverError, StepStats, SubstepScheme};

use sph_solver::boundary::wall_extrapolation::{extrapolate, Extrapolation};
use sph_solver::boundary::{BoundaryParticle, MAX_BOUNDARY_PARTICLES};

use crate::boundary_particles::{sample_moving_wall, sample_solids};
use crate::kernels::{Consts, SpaceConsts, ELASTOPLASTIC_KERNEL};
use crate::params::{ElastoplasticParams, InitialStress, WallModel};
use crate::passes::{
    boundary_pair_terms, max_displacement, momentum_pass, pair_gradients, reinitialise_density,
    stress_pass, StepInputs,
};
use crate::scratch::Scratch;
use crate::stress::artificial_stress;
use crate::walls::{SharedWalls, WallSampler};

pub(crate) use crate::name::NAME;

/// The phases [`Elastoplastic::step`](FrameSolver::step) times.
pub const ELASTOPLASTIC_PHASES: &[&str] = &[
    "begin",
    "create_hash_grid",
    "detect_neighbours",
    "stress",
    "momentum",
    "reorder",
];
const BEGIN: usize = 0;
const CREATE_HASH_GRID: usize = 1;
const DETECT_NEIGHBOURS: usize = 2;
const STRESS: usize = 3;
const MOMENTUM: usize = 4;
const REORDER: usize = 5;

/// What the solver carries between frames ([`SubstepScheme::save_arrays`]): the stress
/// (`6 n` values per particle in the order xx, yy, zz, xy, yz, zx) and the equivalent
/// plastic shear strain (`n` values). The density is the particles' own. Once a wall of
/// boundary particles has moved, also `boundary_motion`: each boundary particle's position
/// and wall velocity (6 values per boundary particle, m and m/s). With a pour
/// ([`crate::Pour`]), the frame shell adds `pour`
/// ([`sph_solver::frame::POUR_STATE_ARRAY`]): the layers placed so far and when the last
/// was.
pub const ELASTOPLASTIC_STATE_ARRAYS: &[&str] =
    &["stress", "plastic_strain", "boundary_motion", "pour"];

/// The elastic–plastic granular solver of Bui et al. (2008); see the crate documentation.
pub type Elastoplastic<R> = FrameSolver<R, ElastoplasticScheme<R>>;

/// The time step of [`Elastoplastic`] as a [`SubstepScheme`].
pub struct ElastoplasticScheme<R: Real> {
    params: ElastoplasticParams<R>,
    c: SpaceConsts<R>,
    parts: SchemeParts<R>,
    walls: WallSampler<R>,
    models: Vec<WallModel>,
    /// The fixed (or caller-moved) boundary particles, then the moving walls' of the
    /// parameters.
    boundary_particles: Vec<BoundaryParticle<R>>,
    /// How many of `boundary_particles` are not the parameters' moving walls'.
    fixed_boundary: usize,
    /// The fastest boundary particle's speed (m/s; zero: all fixed).
    boundary_speed: R,
    /// How far the boundary particles moved since the last neighbour search (m).
    boundary_shift: R,
    /// A boundary particle has moved: checkpoints carry their positions and velocities.
    boundary_moved: bool,
    /// The moving walls of the parameters still to stop: their particles and when.
    schedule: Vec<WallStop>,
    scratch: Scratch<R>,
    lists_valid: bool,
    explicit_steps: u64,
    searches: u64,
    /// The initial stress is still to be applied (at the first frame's start).
    initial_stress_pending: bool,
}

/// A moving wall ([`crate::MovingWall`]) to stop: its boundary particles and the time (s
/// from the run's start) its motion ends.
#[derive(Debug, Clone)]
struct WallStop {
    particles: std::ops::Range<usize>,
    stop_s: f64,
}

impl<R: Real> std::fmt::Debug for ElastoplasticScheme<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ElastoplasticScheme")
            .field("params", &self.params)
            .field("parts", &self.parts)
            .field("explicit_steps", &self.explicit_steps)
            .finish()
    }
}

impl<R: Real> ElastoplasticScheme<R> {
    fn build(
        params: ElastoplasticParams<R>,
        parts: SchemeParts<R>,
        walls: WallSampler<R>,
    ) -> Result<Self, SolverError> {
        let coulomb = std::iter::once(&params.default_wall)
            .chain(&params.wall_models)
            .any(|m| matches!(m, WallModel::Coulomb(_)));
        let particle_walls = params.boundary_particle_region.is_some();
        let planar_volume =
            matches!(walls, WallSampler::PerSolid(_)) || parts.boundary.has_volume();
        if params.dimensions == Dimensions::Two && planar_volume {
            return Err(SolverError::InvalidParameter {
                solver: NAME,
                name: "dimensions",
                value: 2.0,
                reason: "a planar run takes walls of boundary particles (boundary_particle_region), not volume maps, which are integrated in 3D",
            });
        }
        if coulomb && !particle_walls {
            return Err(SolverError::InvalidParameter {
                solver: NAME,
                name: "wall_models",
                value: params.wall_models.len() as f64,
                reason:
                    "Coulomb walls are walls of boundary particles: set boundary_particle_region",
            });
        }
        let models = match &walls {
            // Volume-map walls sampled into boundary particles as well would count twice;
            // contact-only ones (a moving wall's lattice) do not.
            WallSampler::PerSolid(w)
                if particle_walls
                    && (0..w.maps().len())
                        .any(|k| params.wall_model(k) != WallModel::ContactOnly) =>
            {
                return Err(SolverError::InvalidParameter {
                    solver: NAME,
                    name: "boundary_particle_region",
                    value: 0.0,
                    reason: "walls of boundary particles take a boundary without volume (e.g. a collision boundary), not volume-map walls (unless every solid is contact-only)",
                });
            }
            WallSampler::PerSolid(w) => (0..w.maps().len()).map(|k| params.wall_model(k)).collect(),
            WallSampler::Combined if particle_walls => {
                if parts.boundary.has_volume() {
                    return Err(SolverError::InvalidParameter {
                        solver: NAME,
                        name: "boundary_particle_region",
                        value: 0.0,
                        reason: "walls of boundary particles take a boundary without volume (e.g. a collision boundary): a volume map would count the walls twice",
                    });
                }
                Vec::new()
            }
            WallSampler::Combined => {
                if params.wall_models.iter().any(|&m| m != params.default_wall) {
                    return Err(SolverError::InvalidParameter {
                        solver: NAME,
                        name: "wall_models",
                        value: params.wall_models.len() as f64,
                        reason: "a wall model per solid needs the walls of `Elastoplastic::volume_map_walls` given to `ElastoplasticScheme::solver`, or boundary particles",
                    });
                }
                if parts.boundary.has_volume() {
                    vec![params.default_wall]
                } else {
                    Vec::new()
                }
            }
        };
        let fixed = sample_solids(parts.boundary.solids(), &params, MAX_BOUNDARY_PARTICLES)?;
        let mut moving: Vec<BoundaryParticle<R>> = Vec::new();
        let mut schedule = Vec::with_capacity(params.moving_walls.len());
        for wall in &params.moving_walls {
            let room = MAX_BOUNDARY_PARTICLES - fixed.len() - moving.len();
            let mut sampled = sample_moving_wall(wall, &params, room)?;
            if wall.duration_s == R::zero() {
                sampled.iter_mut().for_each(|b| b.velocity = Vec3::zeros());
            }
            let first = moving.len();
            moving.append(&mut sampled);
            schedule.push(WallStop {
                particles: first..moving.len(),
                stop_s: wall.duration_s.as_f64(),
            });
        }
        let mut scheme = Self {
            c: SpaceConsts::new(&params)?,
            initial_stress_pending: params.initial_stress == InitialStress::Geostatic,
            params,
            parts,
            walls,
            models,
            boundary_particles: moving,
            fixed_boundary: 0,
            boundary_speed: R::zero(),
            boundary_shift: R::zero(),
            boundary_moved: false,
            schedule,
            scratch: Scratch::default(),
            lists_valid: false,
            explicit_steps: 0,
            searches: 0,
        };
        if !(fixed.is_empty() && scheme.boundary_particles.is_empty()) {
            scheme.set_boundary_particles(fixed)?;
        }
        Ok(scheme)
    }

    /// The solver with `params` and volume-map `walls` (from
    /// [`FrameSolver::volume_map_walls`]), each solid taking its wall model
    /// ([`ElastoplasticParams::wall_model`]). Errors: invalid parameters, or walls
    /// integrated with another kernel or support radius.
    pub fn solver(
        params: ElastoplasticParams<R>,
        walls: VolumeMapBoundary<R>,
    ) -> Result<Elastoplastic<R>, SolverError> {
        params.validate()?;
        check_volume_kernel(
            &walls,
            NAME,
            ELASTOPLASTIC_KERNEL,
            params.common.support_radius,
        )?;
        let walls = Arc::new(walls);
        let parts = SchemeParts::new(
            Box::new(SharedWalls(Arc::clone(&walls))),
            params.common.neighbour_method,
        );
        let scheme = Self::build(params, parts, WallSampler::PerSolid(walls))?;
        Ok(FrameSolver::from_scheme(scheme))
    }

    /// The stress `σ_i` of each particle (Pa, tension positive) after the last step.
    pub fn stress(&self) -> &[Matrix3<R>] {
        &self.scratch.stress[..self.scratch.plastic_strain.len()]
    }

    /// The equivalent plastic shear strain accumulated by each particle
    /// ([`StressUpdate::plastic_strain`](crate::StressUpdate::plastic_strain) summed).
    pub fn plastic_strain(&self) -> &[R] {
        &self.scratch.plastic_strain
    }

    /// Sets the stress of each particle (Pa, tension positive; one per particle of the state
    /// the next [`FrameSolver::step`] takes), e.g. a geostatic initial stress; it replaces
    /// the parameters' `initial_stress`. Errors: a
    /// non-finite or asymmetric stress, named by its index.
    pub fn set_stress(&mut self, stress: &[Matrix3<R>]) -> Result<(), SolverError> {
        for (i, m) in stress.iter().enumerate() {
            if m.iter().any(|v| !v.is_finite()) || *m != m.transpose() {
                return Err(SolverError::InvalidParameter {
                    solver: NAME,
                    name: "stress",
                    value: i as f64,
                    reason: "each stress must be finite and symmetric (value: the first particle whose stress is not)",
                });
            }
        }
        self.resize(stress.len());
        self.scratch.stress[..stress.len()].copy_from_slice(stress);
        self.initial_stress_pending = false;
        Ok(())
    }

    /// Sets the boundary particles (see [`crate::boundary_particles`]); they take part in
    /// every sum from the next step on, and those with a velocity move with it until
    /// [`ElastoplasticScheme::set_boundary_velocity`] stops them. They replace those the
    /// solver sampled from the solids; the parameters' moving walls ([`crate::MovingWall`])
    /// stay, after them in [`ElastoplasticScheme::boundary_particles`]. Solids whose share
    /// they replace should have the model [`WallModel::ContactOnly`]. Errors: a non-finite
    /// position, normal or velocity, named by its index.
    pub fn set_boundary_particles(
        &mut self,
        particles: Vec<BoundaryParticle<R>>,
    ) -> Result<(), SolverError> {
        for (k, b) in particles.iter().enumerate() {
            let ok = b
                .position
                .iter()
                .chain(b.normal.iter())
                .chain(b.velocity.iter())
                .all(|v| v.is_finite())
                && b.normal.norm() > R::zero();
            if !ok {
                return Err(SolverError::InvalidParameter {
                    solver: NAME,
                    name: "boundary_particles",
                    value: k as f64,
                    reason: "each boundary particle needs a finite position and velocity and a finite non-zero normal (value: the first that has not)",
                });
            }
        }
        let n = self.scratch.plastic_strain.len();
        let moving = self.boundary_particles.split_off(self.fixed_boundary);
        let fixed = particles.len();
        self.boundary_particles = particles
            .into_iter()
            .map(|b| BoundaryParticle {
                normal: b.normal / b.normal.norm(),
                ..b
            })
            .chain(moving)
            .collect();
        for w in &mut self.schedule {
            w.particles = w.particles.start - self.fixed_boundary + fixed
                ..w.particles.end - self.fixed_boundary + fixed;
        }
        self.fixed_boundary = fixed;
        self.boundary_speed = self.fastest_boundary();
        self.resize(n);
        self.lists_valid = false;
        Ok(())
    }

    /// Sets the wall velocity (m/s) of the boundary particles `range` (indices into
    /// [`ElastoplasticScheme::boundary_particles`]), e.g. to start or stop a wall: they
    /// move with it from the next step on. Errors: a range past the boundary particles or
    /// a non-finite velocity.
    pub fn set_boundary_velocity(
        &mut self,
        range: std::ops::Range<usize>,
        velocity: Vec3<R>,
    ) -> Result<(), SolverError> {
        let error = |value: f64, reason: &'static str| SolverError::InvalidParameter {
            solver: NAME,
            name: "boundary_velocity",
            value,
            reason,
        };
        if range.end > self.boundary_particles.len() || range.start > range.end {
            return Err(error(
                range.end as f64,
                "the range must lie within the boundary particles (value: its end)",
            ));
        }
        if !velocity.iter().all(|v| v.is_finite()) {
            return Err(error(
                velocity.norm().as_f64(),
                "a wall velocity must be finite (value: its norm)",
            ));
        }
        for b in &mut self.boundary_particles[range] {
            b.velocity = velocity;
        }
        self.boundary_speed = self.fastest_boundary();
        Ok(())
    }

    fn fastest_boundary(&self) -> R {
        self.boundary_particles
            .iter()
            .map(|b| b.velocity.norm())
            .fold(R::zero(), |a, b| if b > a { b } else { a })
    }

    /// Stops the moving walls whose motion has ended by `time_s` (s from the run's start;
    /// the step from `time_s` to `time_s + dt` is the first they do not move in if it
    /// starts past their end less half a step): the explicit step nearest the end is the
    /// last one that moves them.
    fn stop_walls(&mut self, time_s: f64, dt: f64) {
        let mut stopped = false;
        for w in &self.schedule {
            if time_s + 0.5 * dt >= w.stop_s {
                let still = &mut self.boundary_particles[w.particles.clone()];
                still.iter_mut().for_each(|b| b.velocity = Vec3::zeros());
                stopped = true;
            }
        }
        if stopped {
            self.schedule.retain(|w| time_s + 0.5 * dt < w.stop_s);
            self.boundary_speed = self.fastest_boundary();
        }
    }

    /// Moves the boundary particles that have a velocity by `dt` (their positions, and the
    /// scratch's of this step and the next).
    fn move_boundary(&mut self, n: usize, dt: R) {
        let s = &mut self.scratch;
        for (k, b) in self.boundary_particles.iter_mut().enumerate() {
            if b.velocity != Vec3::zeros() {
                b.position += b.velocity * dt;
                s.x[n + k] = b.position;
                s.x_new[n + k] = b.position;
            }
        }
        self.boundary_shift += self.boundary_speed * dt;
        self.boundary_moved = true;
    }

    /// The parameters' initial stress of the particles at `positions` (sized for them), if
    /// it is still to be applied. The geostatic stress is a function of each particle's
    /// position, so applying it before or after a reordering gives each particle the same.
    fn apply_initial_stress(&mut self, positions: &[Vec3<R>]) -> Result<(), SolverError> {
        if self.initial_stress_pending {
            let stress = crate::initial::geostatic(&self.params, positions)?;
            self.scratch.stress[..positions.len()].copy_from_slice(&stress);
            self.initial_stress_pending = false;
        }
        Ok(())
    }

    /// The per-particle arrays: stress (`xx, yy, zz, xy, yz, zx`) and plastic strain.
    fn particle_arrays(&self, arrays: &mut Vec<(String, Vec<R>)>) {
        let s = &self.scratch;
        arrays.push((
            "stress".into(),
            s.stress[..s.plastic_strain.len()]
                .iter()
                .flat_map(|m| {
                    [
                        m[(0, 0)],
                        m[(1, 1)],
                        m[(2, 2)],
                        m[(0, 1)],
                        m[(1, 2)],
                        m[(2, 0)],
                    ]
                })
                .collect(),
        ));
        arrays.push(("plastic_strain".into(), s.plastic_strain.clone()));
    }

    /// The boundary particles.
    pub fn boundary_particles(&self) -> &[BoundaryParticle<R>] {
        &self.boundary_particles
    }

    fn resize(&mut self, n: usize) {
        self.scratch.resize(
            n,
            &self.boundary_particles,
            self.params.common.rest_density,
            self.params.common.particle_mass(),
            self.models.len(),
        );
    }

    /// Explicit steps taken so far, and neighbour searches made for them.
    pub fn counts(&self) -> (u64, u64) {
        (self.explicit_steps, self.searches)
    }

    /// The wall model each wall gradient of the scheme takes (one per solid with per-solid
    /// walls, one for a combined boundary with volume, none otherwise).
    pub fn wall_models(&self) -> &[WallModel] {
        &self.models
    }

    /// One explicit step (number `k` of the substep, `Δt = dt`) of the `n` particles of
    /// `state` with the kernel and constants `c`: the density re-initialisation when due,
    /// the boundary particles' extrapolations, the stress and momentum passes, the swap.
    fn explicit_step<K: Kernel<R>>(
        &mut self,
        c: Consts<R, K>,
        state: &ParticleSet<R>,
        n: usize,
        k: usize,
        dt: R,
        stats: &mut StepStats,
    ) {
        let reinit = self.params.density_reinit_steps();
        let boundary_mass = self.params.common.particle_mass();
        let s = &mut self.scratch;
        let inputs = StepInputs {
            c,
            masses: &state.masses,
            nb: self.parts.neighbours.lists(),
            boundary: &*self.parts.boundary,
            walls: &self.walls,
            models: &self.models,
            gravity: self.params.common.gravity,
            dt,
            boundary_mass,
        };
        let t = Instant::now();
        if reinit.is_some_and(|every| k.is_multiple_of(every)) {
            reinitialise_density(s, &inputs);
        }
        let bp = &self.boundary_particles;
        if !bp.is_empty() {
            let e = Extrapolation {
                kernel: c.kernel,
                images: &s.images,
                x: &s.x,
                rho: &s.rho,
                particles: bp,
                gravity: self.params.common.gravity,
            };
            s.boundary_lists.weigh(&e);
            extrapolate(&e, &s.boundary_lists, &mut s.stress, Some(&mut s.v), None);
        }
        pair_gradients(s, &inputs);
        stress_pass(s, &inputs);
        if !bp.is_empty() {
            let e = Extrapolation {
                kernel: c.kernel,
                images: &s.images,
                x: &s.x,
                rho: &s.rho,
                particles: bp,
                gravity: self.params.common.gravity,
            };
            let (rho0, eps) = (c.rho0, c.eps_stress);
            let art = |s_b: &Matrix3<R>| artificial_stress(s_b, rho0, eps);
            extrapolate(
                &e,
                &s.boundary_lists,
                &mut s.stress_new,
                None,
                Some((&mut s.art, &art)),
            );
            boundary_pair_terms(s, n);
        }
        stats.phases.add(STRESS, t.elapsed().as_secs_f64());
        let t = Instant::now();
        momentum_pass(s, &inputs);
        stats.phases.add(MOMENTUM, t.elapsed().as_secs_f64());
        std::mem::swap(&mut s.x, &mut s.x_new);
        std::mem::swap(&mut s.v, &mut s.v_new);
        std::mem::swap(&mut s.rho, &mut s.rho_new);
        std::mem::swap(&mut s.stress, &mut s.stress_new);
        std::mem::swap(&mut s.plastic_strain, &mut s.plastic_new);
        self.explicit_steps += 1;
        stats.iterations += 1;
    }

    fn time_step(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        let (steps, dt) = self.params.explicit_steps();
        let h = self.params.common.support_radius;
        let skin = self.params.skin;
        let half = R::of_f64(0.5);
        let n = state.len();
        self.scratch.x[..n].copy_from_slice(&state.positions);
        self.scratch.v[..n].copy_from_slice(&state.velocities);
        self.scratch.rho[..n].copy_from_slice(&state.densities);
        if self.params.dimensions == Dimensions::Two {
            check_in_plane(&state.positions)?;
        }
        // The clock of the moving walls: the frame count (checkpointed) and the substep.
        let substeps = self.params.common.substeps as f64;
        let substep_start_s = (at.step as f64 * substeps + at.substep as f64)
            * self.params.common.substep_dt().as_f64();
        for k in 0..steps {
            if !self.schedule.is_empty() {
                let dt = dt.as_f64();
                self.stop_walls(substep_start_s + k as f64 * dt, dt);
            }
            if self.boundary_speed > R::zero() {
                self.move_boundary(n, dt);
            }
            let s = &mut self.scratch;
            let moved = max_displacement(s, n);
            // A pair stays within the lists' reach `h + skin` while the two together moved
            // less than the skin: grains `2 × moved`, a grain and a wall `moved + shift`.
            if !self.lists_valid || moved > skin * half || moved + self.boundary_shift > skin {
                let axes = &self.params.periodic;
                // The boundary particles (after the grains) list only grains: no sum reads
                // a boundary–boundary pair. With periodic axes the images of both kinds
                // follow them, and every pair is listed.
                let search = if axes.is_empty() {
                    self.parts
                        .neighbours
                        .find_active_in_step(&s.x, n, h + skin, at, "position")?
                } else {
                    s.images.rebuild(&mut s.x, axes, h + skin, &mut s.x_ext);
                    self.parts
                        .neighbours
                        .find_in_step(&s.x_ext, h + skin, at, "position")?
                };
                stats.phases.add(CREATE_HASH_GRID, search.build_s());
                stats.phases.add(DETECT_NEIGHBOURS, search.detect_s());
                s.anchor.copy_from_slice(&s.x);
                s.images.owners(s.x.len(), &mut s.owner);
                s.boundary_lists.rebuild(
                    self.parts.neighbours.lists(),
                    &s.images,
                    &s.x,
                    n,
                    self.boundary_particles.len(),
                );
                if self.boundary_speed > R::zero() {
                    // The search wrapped the positions into the periods.
                    for (k, b) in self.boundary_particles.iter_mut().enumerate() {
                        b.position = s.x[n + k];
                    }
                }
                self.lists_valid = true;
                self.boundary_shift = R::zero();
                self.searches += 1;
            }
            match self.c {
                SpaceConsts::Three(c) => self.explicit_step(c, state, n, k, dt, stats),
                SpaceConsts::Two(c) => self.explicit_step(c, state, n, k, dt, stats),
            }
        }
        let s = &self.scratch;
        check_divergence(at, &s.x[..n], &s.v[..n], &*self.parts.boundary, h)?;
        check_sound_barrier(at, &s.v[..n], self.params.sound_speed())?;
        state.positions.copy_from_slice(&s.x[..n]);
        state.velocities.copy_from_slice(&s.v[..n]);
        state.densities.copy_from_slice(&s.rho[..n]);
        stats.substeps += 1;
        stats.neighbour_pairs = self.parts.neighbours.lists().pair_count();
        Ok(())
    }
}

/// A planar run's particles all lie in the plane `z = 0`; an error names the first that
/// does not (its index, and its `z` in the reason).
fn check_in_plane<R: Real>(positions: &[Vec3<R>]) -> Result<(), SolverError> {
    match positions.iter().position(|p| p.z != R::zero()) {
        None => Ok(()),
        Some(i) => Err(SolverError::InvalidSolverState {
            solver: NAME.to_owned(),
            reason: format!(
                "a planar run (dimensions = 2) keeps every particle in the plane z = 0; particle {i} is at z = {} m",
                positions[i].z.as_f64()
            ),
        }),
    }
}

impl<R: Real> SubstepScheme<R> for ElastoplasticScheme<R> {
    type Params = ElastoplasticParams<R>;
    const PHASES: &'static [&'static str] = ELASTOPLASTIC_PHASES;
    const FRAME_PHASES: FramePhases = FramePhases {
        checks: BEGIN,
        reorder: REORDER,
        statistics: MOMENTUM,
    };
    const DENSITY_KERNEL: KernelKind = ELASTOPLASTIC_KERNEL;

    /// Any boundary: its summed `∇Ψ` (if it has volume) takes `default_wall`; per-solid
    /// models need [`ElastoplasticScheme::solver`].
    fn new(params: ElastoplasticParams<R>, parts: SchemeParts<R>) -> Result<Self, SolverError> {
        Self::build(params, parts, WallSampler::Combined)
    }
    fn params(&self) -> &ElastoplasticParams<R> {
        &self.params
    }
    fn parts(&self) -> &SchemeParts<R> {
        &self.parts
    }
    fn begin_frame(
        &mut self,
        state: &mut ParticleSet<R>,
        permutation: Option<&[u32]>,
        _stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        let n = state.len();
        self.resize(n);
        if let Some(p) = permutation {
            let s = &mut self.scratch;
            apply_permutation(&mut s.stress, p, &mut s.permute_m);
            apply_permutation(&mut s.plastic_strain, p, &mut s.permute_r);
            self.resize(n);
        }
        self.apply_initial_stress(&state.positions)?;
        // Every frame starts from fresh lists, so that a run resumed from a checkpoint
        // repeats the uninterrupted one bit for bit.
        self.lists_valid = false;
        Ok(())
    }
    fn prepare(&mut self, state: &ParticleSet<R>) -> Result<(), SolverError> {
        self.resize(state.len());
        self.apply_initial_stress(&state.positions)
    }
    fn pour(&self) -> Option<&Pour<R>> {
        self.params.pour.as_ref()
    }
    fn periodic_axes(&self) -> &[PeriodicAxis<R>] {
        &self.params.periodic
    }
    /// Poured grains start unstressed, with no plastic strain, and the neighbour lists are
    /// rebuilt.
    fn init_emitted(&mut self, state: &ParticleSet<R>, first: usize) -> Result<(), SolverError> {
        let n = state.len();
        self.resize(n);
        self.scratch.stress[first..n].fill(Matrix3::zeros());
        self.scratch.plastic_strain[first..n].fill(R::zero());
        self.lists_valid = false;
        Ok(())
    }
    fn substep(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        _last: bool,
        stats: &mut StepStats,
    ) -> Result<(), SolverError> {
        // The substep's explicit steps run on a worker of the thread pool: each of their
        // parallel loops then starts on the calling worker instead of waking the pool and
        // sleeping until it is done (two context switches per loop, about a dozen loops
        // per explicit step).
        rayon::scope(|_| self.time_step(state, at, stats))
    }
    /// The stress (Pa, `xx, yy, zz, xy, yz, zx`) and the equivalent plastic shear strain:
    /// the arrays a checkpoint carries.
    fn particle_fields(&self, fields: &mut Vec<(String, Vec<R>)>) {
        self.particle_arrays(fields);
    }
    fn save_arrays(&self, arrays: &mut Vec<(String, Vec<R>)>) {
        self.particle_arrays(arrays);
        if self.boundary_moved {
            arrays.push((
                "boundary_motion".into(),
                self.boundary_particles
                    .iter()
                    .flat_map(|b| {
                        let (x, v) = (b.position, b.velocity);
                        [x.x, x.y, x.z, v.x, v.y, v.z]
                    })
                    .collect(),
            ));
        }
    }
    fn restore_arrays(
        &mut self,
        arrays: &[(String, Vec<R>)],
        particles: usize,
    ) -> Result<(), SolverError> {
        let n = particles;
        let found = match_arrays(
            NAME,
            arrays,
            &[
                ArraySpec {
                    name: "stress",
                    len: 6 * n,
                },
                ArraySpec {
                    name: "plastic_strain",
                    len: n,
                },
                ArraySpec {
                    name: "boundary_motion",
                    len: 6 * self.boundary_particles.len(),
                },
            ],
        )?;
        if let Some(v) = found[2] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(SolverError::InvalidSolverState {
                    solver: NAME.to_owned(),
                    reason: "the boundary particles' positions and velocities must be finite"
                        .into(),
                });
            }
            for (b, c) in self.boundary_particles.iter_mut().zip(v.chunks_exact(6)) {
                b.position = Vec3::new(c[0], c[1], c[2]);
                b.velocity = Vec3::new(c[3], c[4], c[5]);
            }
            self.boundary_speed = self.fastest_boundary();
            self.boundary_moved = true;
        }
        self.resize(n);
        let s = &mut self.scratch;
        match found[0] {
            Some(v) => {
                for (m, c) in s.stress[..n].iter_mut().zip(v.chunks_exact(6)) {
                    *m = Matrix3::new(c[0], c[3], c[5], c[3], c[1], c[4], c[5], c[4], c[2]);
                }
            }
            None => s.stress[..n].fill(Matrix3::zeros()),
        }
        match found[1] {
            Some(v) => s.plastic_strain.copy_from_slice(v),
            None => s.plastic_strain.fill(R::zero()),
        }
        self.lists_valid = false;
        self.initial_stress_pending = false;
        Ok(())
    }
}

/// A blow-up when a particle moves faster than the sound speed `c = √(E/ρ0)`: the explicit
/// step `Δt ≤ C h / c_p` (`c_p ≥ c` the P-wave speed) keeps the elastic waves within the
/// Courant condition only while the particles themselves are slower than the waves, so a
/// faster particle means the scheme has left its stability bound. Needs no closed domain
/// (an open or periodic set-up has no solid to find a runaway particle in). Errors: the first
/// such particle, with its speed and `c`.
fn check_sound_barrier<R: Real>(at: StepAt, v: &[Vec3<R>], c: R) -> Result<(), SolverError> {
    let c2 = c * c;
    match v.iter().position(|u| u.norm_squared() > c2) {
        None => Ok(()),
        Some(i) => Err(blow_up(
            at.solver,
            at.step,
            i,
            format!(
                "substep {}: speed {:.3e} m/s above the sound speed {:.3e} m/s (the explicit step's stability bound)",
                at.substep,
                v[i].norm().as_f64(),
                c.as_f64()
            ),
        )),
    }
}
