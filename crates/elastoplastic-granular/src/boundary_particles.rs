//! Walls of fixed boundary (dummy) particles whose stress and velocity are extrapolated from
//! the granular particles around them: Adami, Hu & Adams (2012), "A generalized wall
//! boundary condition for smoothed particle hydrodynamics", *J. Comput. Phys.*
//! 231:7057–7075, with the pressure generalised to the stress tensor as in Bui et al.
//! (2008, rows of fixed boundary particles) and Project Chrono's CRM (Hu, Rakhsha, Yang,
//! Negrut et al. 2021, *CMAME* 385:114022, boundary condition enforcing markers).
//!
//! For a boundary particle `b` with unit normal `n_b` (pointing into the granular side),
//! over the granular neighbours `f` (Shepard weights `W_bf`, `r_bf = x_b − x_f`):
//!
//! ```text
//! σ̄_b = (Σ_f σ_f W_bf − I Σ_f ρ_f (g·r_bf) W_bf) / Σ_f W_bf     (Adami eq. 27, stress)
//! ṽ_b = Σ_f v_f W_bf / Σ_f W_bf
//! free-slip:  σ_b = P σ̄_b P,  v_b = P ṽ_b,   P = I − 2 n_b n_bᵀ (the mirror image)
//! no-slip:    σ_b = σ̄_b,      v_b = −ṽ_b                       (wall at rest)
//! Coulomb:    σ_b = σ̄_b − 2(1 − χ)(n t_tᵀ + t_t nᵀ),  v_b = −(ṽ·n) n + (1 − 2χ) ṽ_t
//! ```
//!
//! **Coulomb walls** (wall friction coefficient `μ_w`). Write the extrapolated traction on
//! the wall's plane as `σ̄ n = t_n n + t_t` (`t_n = nᵀσ̄n`, compressive when negative;
//! `t_t = (I − nnᵀ) σ̄ n` its tangential part) and the velocity as `ṽ = (ṽ·n) n + ṽ_t`. The
//! mirror is `P σ̄ P = σ̄ − 2(n t_tᵀ + t_t nᵀ)`: it keeps `t_n` and the in-plane block and
//! reverses `t_t`. A particle next to the wall and its boundary neighbours enter the
//! momentum sum through `σ_i/ρ_i² + σ_b/ρ_b²`, so the traction the wall carries is that of
//! the mean `(σ̄ + σ_b)/2`: its normal part is `t_n` for every model, its tangential part
//! `0` for free-slip (the mirror), `t_t` for no-slip, and `χ t_t` for
//! `σ_b = σ̄ − 2(1 − χ)(n t_tᵀ + t_t nᵀ)`. Coulomb's law, a tangential traction at most
//! `μ_w` times the compressive normal one, gives
//!
//! ```text
//! χ = min(1, μ_w max(−t_n, 0) / |t_t|)    (χ = 1 when t_t = 0; 0 ≤ χ ≤ 1)
//! ```
//!
//! so a wall below the limit acts as no-slip (`χ = 1`), a sliding one passes exactly
//! `μ_w |t_n|` in the direction of `t_t`, and a wall in tension (`t_n ≥ 0`, no contact)
//! is free-slip (`χ = 0`). The velocity follows the same blend between the mirror of the
//! tangential velocity (no-slip, `−ṽ_t`) and its copy (free-slip, `+ṽ_t`), so that the
//! velocity gradient at a wall that slides does not keep loading the shear the limit
//! removes. `μ_w = 0` is free-slip; a large `μ_w` is no-slip.
//!
//! Measured (`tests/walls.rs`, an elastic slab periodic along the slope at 20 mm, `μ_w` =
//! 0.4): it holds 5° below `atan μ_w` (0.02 mm in 0.6 s) and slides 5° above it, but it
//! slides faster than a Coulomb block, `g (sin θ − μ_w cos θ)` (0.69 m in 0.6 s against
//! 0.17 m): `μ_w |t_n|` caps the traction the wall takes, and the grains' own shear stress
//! next to a sliding wall, which the wall's share cannot exceed, stays below that cap.
//!
//! **Moving walls.** A boundary particle with a wall velocity `v_w` moves with it (`x_b +=
//! v_w Δt` each explicit step) and its model acts on the relative velocity: `v_b = v_w +
//! f(ṽ − v_w)` with `f` the fixed wall's rule above (`−u`, the mirror `P u`, or Coulomb's
//! blend). The wall's acceleration is taken as zero (Adami et al. 2012, eq. 27, has
//! `g − a_w`): a wall moves at constant velocity between the changes its owner makes.
//!
//! Their density is `ρ0` and their mass that of a particle; they enter every sum (velocity
//! gradient, continuity, momentum, artificial viscosity and stress) as neighbours. The
//! isotropic gravity term carries the hydrostatic gradient of the normal stress across the
//! wall (the part the wall must supply for a resting layer to carry its weight). A boundary
//! particle without granular neighbours carries no stress and no velocity.

use nalgebra::Matrix3;
use rayon::prelude::*;
use sph_core::sampling::cubic_lattice;
use sph_core::{Aabb, BoxSdf, Real, Sdf, Vec3};
use sph_kernels::Kernel;
use sph_solver::step::MIN_LEN;
use sph_solver::{NeighbourLists, SolverError};

use crate::kernels::Consts;
use crate::params::{ElastoplasticParams, MovingWall, WallModel, BOUNDARY_PARTICLE_ROWS};
use crate::periodic::{Images, PeriodicAxis};
use crate::stress::artificial_stress;

/// One fixed boundary particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundaryParticle<R: Real> {
    /// Position (m).
    pub position: Vec3<R>,
    /// Unit normal of the wall it stands for, pointing into the granular side.
    pub normal: Vec3<R>,
    /// Free-slip (mirrored), no-slip (opposite velocity) or Coulomb (module docs).
    pub model: WallModel,
    /// The wall's velocity (m/s; zero for a fixed wall): the particle moves with it, and
    /// the models act on the grains' velocity relative to it (module docs).
    pub velocity: Vec3<R>,
}

/// Boundary particles on the cubic lattice of spacing `spacing` filling `region` (half a
/// spacing from its faces, as the granular particles are placed), all with `normal` and
/// `model`. Errors: those of the lattice, or a normal that is not finite and non-zero.
pub fn boundary_block<R: Real>(
    region: &Aabb<R>,
    spacing: R,
    normal: Vec3<R>,
    model: WallModel,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    let len = normal.norm();
    if !(len.is_finite() && len > R::zero()) {
        return Err(SolverError::InvalidParameter {
            solver: crate::name::NAME,
            name: "normal",
            value: len.as_f64(),
            reason: "a boundary block's normal must be finite and non-zero (value: its length)",
        });
    }
    let normal = normal / len;
    Ok(cubic_lattice(region, spacing, max_count)?
        .into_iter()
        .map(|position| BoundaryParticle {
            position,
            normal,
            model,
            velocity: Vec3::zeros(),
        })
        .collect())
}

/// The stress and velocity of a Coulomb boundary particle with unit normal `n` and wall
/// friction coefficient `mu` from the extrapolated `s_bar`, `v_bar` (module docs).
pub fn coulomb<R: Real>(
    s_bar: &Matrix3<R>,
    v_bar: &Vec3<R>,
    n: &Vec3<R>,
    mu: R,
) -> (Matrix3<R>, Vec3<R>) {
    let t = s_bar * n;
    let t_n = n.dot(&t);
    let t_t = t - n * t_n;
    let tau = t_t.norm();
    let limit = mu * (-t_n).max(R::zero());
    let chi = if tau > limit { limit / tau } else { R::one() };
    let two = R::of_f64(2.0);
    let s_b = s_bar - (n * t_t.transpose() + t_t * n.transpose()) * (two * (R::one() - chi));
    let v_n = n.dot(v_bar);
    let v_t = v_bar - n * v_n;
    (s_b, v_t * (R::one() - two * chi) - n * v_n)
}

/// What [`extrapolate`] reads.
pub(crate) struct Extrapolation<'a, R: Real> {
    pub c: Consts<R>,
    pub images: &'a Images<R>,
    /// Positions of the particles then the boundary particles.
    pub x: &'a [Vec3<R>],
    /// Densities of the particles (the boundary's are `ρ0`).
    pub rho: &'a [R],
    pub particles: &'a [BoundaryParticle<R>],
    pub gravity: Vec3<R>,
}

/// The grain neighbours of each boundary particle (from the neighbour lists, in their
/// order: the extrapolation's sums add in the same order as over the whole lists, whose
/// other entries are boundary particles), rebuilt at each neighbour search, and their
/// Shepard weights `W_bf` and gravity terms `ρ_f (g·r_bf) W_bf`, computed once per step for
/// both extrapolations of the step.
#[derive(Debug, Clone, Default)]
pub(crate) struct BoundaryLists<R: Real> {
    /// CSR offsets: boundary particle `k`'s entries are `start[k]..start[k + 1]`.
    start: Vec<usize>,
    /// The lists' entry (a particle or an image of one).
    entry: Vec<u32>,
    /// The grain it resolves to.
    grain: Vec<u32>,
    /// The boundary particle (`0..`) whose entry it is.
    owner: Vec<u32>,
    weight: Vec<R>,
    weighted_gravity: Vec<R>,
}

impl<R: Real> BoundaryLists<R> {
    /// Keeps, for each of the `count` boundary particles `n..n + count` of `nb`, the entries
    /// that resolve to a grain (`< n`). Grows its arrays to the pair count (reusing them).
    pub(crate) fn rebuild(
        &mut self,
        nb: &NeighbourLists,
        images: &Images<R>,
        x: &[Vec3<R>],
        n: usize,
        count: usize,
    ) {
        self.start.clear();
        self.entry.clear();
        self.grain.clear();
        self.owner.clear();
        self.start.push(0);
        for k in 0..count {
            for &j in nb.neighbours(n + k) {
                let (f, _) = images.resolve(j as usize, x);
                if f < n {
                    self.entry.push(j);
                    self.grain.push(f as u32);
                    self.owner.push(k as u32);
                }
            }
            self.start.push(self.entry.len());
        }
        let len = self.entry.len();
        self.weight.resize(len, R::zero());
        self.weighted_gravity.resize(len, R::zero());
    }

    /// The weights and gravity terms at the positions `e.x` (boundary particles from `n =
    /// e.x.len() − e.particles.len()` on).
    pub(crate) fn weigh(&mut self, e: &Extrapolation<'_, R>) {
        let n = e.x.len() - e.particles.len();
        let (entry, owner) = (&self.entry, &self.owner);
        self.weight
            .par_iter_mut()
            .zip(self.weighted_gravity.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(m, (w, wg))| {
                let (j, xj) = e.images.resolve(entry[m] as usize, e.x);
                let r = e.x[n + owner[m] as usize] - xj;
                *w = e.c.kernel.value(r.norm());
                *wg = e.rho[j] * e.gravity.dot(&r) * *w;
            });
    }
}

/// Writes the boundary particles' stress into `stress[n..]` from the particles' `stress[..n]`
/// (module docs), their artificial stress into `art[n..]` if given, and their velocity into
/// `v[n..]` if given (from `v[..n]`), with the weights of the last [`BoundaryLists::weigh`].
pub(crate) fn extrapolate<R: Real>(
    e: &Extrapolation<'_, R>,
    lists: &BoundaryLists<R>,
    stress: &mut [Matrix3<R>],
    v: Option<&mut [Vec3<R>]>,
    art: Option<&mut [Matrix3<R>]>,
) {
    let n = e.x.len() - e.particles.len();
    let (s_head, s_tail) = stress.split_at_mut(n);
    let (v_head, v_tail) = match v {
        Some(v) => {
            let (h, t) = v.split_at_mut(n);
            (Some(&*h), Some(t))
        }
        None => (None, None),
    };
    let art_tail = art.map(|a| &mut a[n..]);
    let two = R::of_f64(2.0);
    let work =
        |k: usize, sig: &mut Matrix3<R>, vel: Option<&mut Vec3<R>>, a: Option<&mut Matrix3<R>>| {
            let mut sum_s = Matrix3::zeros();
            let mut sum_g = R::zero();
            let mut sum_v = Vec3::zeros();
            let mut sum_w = R::zero();
            for m in lists.start[k]..lists.start[k + 1] {
                let j = lists.grain[m] as usize;
                let w = lists.weight[m];
                sum_s += s_head[j] * w;
                sum_g += lists.weighted_gravity[m];
                if let Some(vh) = v_head {
                    sum_v += vh[j] * w;
                }
                sum_w += w;
            }
            let p = &e.particles[k];
            let mirror = Matrix3::identity() - p.normal * p.normal.transpose() * two;
            let (s_bar, v_bar) = if sum_w > R::zero() {
                ((sum_s - Matrix3::identity() * sum_g) / sum_w, sum_v / sum_w)
            } else {
                (Matrix3::zeros(), Vec3::zeros())
            };
            // A moving wall: its models act on the velocity relative to it.
            let moving = p.velocity != Vec3::zeros();
            let v_rel = if moving { v_bar - p.velocity } else { v_bar };
            let (s_b, v_b) = match p.model {
                WallModel::NoSlip => (s_bar, -v_rel),
                WallModel::Coulomb(mu) => coulomb(&s_bar, &v_rel, &p.normal, R::of_f64(mu)),
                _ => (mirror * s_bar * mirror, mirror * v_rel),
            };
            let v_b = if moving { v_b + p.velocity } else { v_b };
            *sig = s_b;
            if let Some(vel) = vel {
                *vel = v_b;
            }
            if let Some(a) = a {
                *a = artificial_stress(&s_b, e.c.rho0, e.c.eps_stress);
            }
        };
    match (v_tail, art_tail) {
        (Some(vt), None) => s_tail
            .par_iter_mut()
            .zip(vt.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(k, (sig, vel))| work(k, sig, Some(vel), None)),
        (None, Some(at)) => s_tail
            .par_iter_mut()
            .zip(at.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(k, (sig, a))| work(k, sig, None, Some(a))),
        _ => s_tail
            .par_iter_mut()
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(k, sig)| work(k, sig, None, None)),
    }
}

/// Most boundary particles [`sample_solids`] makes (4 M, 200 MB of solver arrays in
/// `f64`): a wall three rows thick around a box of a few million grains.
pub const MAX_BOUNDARY_PARTICLES: usize = 1 << 22;
/// Most lattice nodes [`sample_solids`] visits (256 M, each a signed distance per solid):
/// the region's lattice extended by the wall rows; beyond it the spacing is far too fine for
/// the region.
pub const MAX_BOUNDARY_LATTICE_NODES: f64 = (1u64 << 28) as f64;

fn sampling_error(name: &'static str, value: f64, reason: &'static str) -> SolverError {
    SolverError::InvalidParameter {
        solver: crate::name::NAME,
        name,
        value,
        reason,
    }
}

/// The solids' walls as boundary particles: the nodes of the particle lattice (spacing
/// `s = params.common.particle_spacing`, half a spacing from the faces of
/// `params.boundary_particle_region`, the fluid's lattice) over that region extended by
/// [`BOUNDARY_PARTICLE_ROWS`] spacings on each side (not along a periodic axis, whose
/// period the region spans), kept where they lie inside a solid no deeper than
/// `BOUNDARY_PARTICLE_ROWS · s` (the deepest solid that holds the node, from its signed
/// distance). Each takes the solid whose surface is nearest among those holding it: its
/// unit outward normal (the gradient of its signed distance) and its model
/// ([`ElastoplasticParams::wall_model`]; a solid with [`WallModel::ContactOnly`] gives
/// none). In lattice order. No region: none.
///
/// Errors: more than `min(max_count, MAX_BOUNDARY_PARTICLES)` particles, a lattice of
/// more than [`MAX_BOUNDARY_LATTICE_NODES`] nodes, an allocation that fails, or a solid
/// whose gradient is not a finite non-zero vector at a node (each named, with the count or
/// the node's index as value).
pub fn sample_solids<R: Real>(
    solids: &[Box<dyn Sdf<R>>],
    params: &ElastoplasticParams<R>,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    let Some(lattice) = WallLattice::of(params)? else {
        return Ok(Vec::new());
    };
    let mut out = Particles::new(max_count);
    for (node, x) in lattice.nodes().enumerate() {
        let mut deepest = R::zero();
        let mut nearest: Option<(usize, R)> = None;
        for (m, solid) in solids.iter().enumerate() {
            let d = solid.signed_distance(&x);
            if d < R::zero() {
                deepest = deepest.max(-d);
                if nearest.is_none_or(|(_, b)| -d < b) {
                    nearest = Some((m, -d));
                }
            }
        }
        let Some((m, _)) = nearest else { continue };
        let model = params.wall_model(m);
        if deepest > lattice.depth_limit || model == WallModel::ContactOnly {
            continue;
        }
        let normal = unit_gradient(&*solids[m], &x, node)?;
        out.push(BoundaryParticle {
            position: x,
            normal,
            model,
            velocity: Vec3::zeros(),
        })?;
    }
    Ok(out.0)
}

/// The particles of the moving wall `wall` ([`MovingWall`]) on the lattice of
/// [`sample_solids`] (that of `params.boundary_particle_region`): the nodes inside its box no
/// deeper than [`BOUNDARY_PARTICLE_ROWS`] spacings, a node taking the periodic image of
/// itself that lies deepest in the box (so that a box across a periodic axis's ends gives
/// particles on both sides of the seam), each with the wall's model and velocity and the
/// outward normal of the box's nearest face. In lattice order; no region: none.
///
/// Errors: those of [`sample_solids`] (counts against `max_count` and
/// [`MAX_BOUNDARY_PARTICLES`], the lattice's size, an allocation).
pub fn sample_moving_wall<R: Real>(
    wall: &MovingWall<R>,
    params: &ElastoplasticParams<R>,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    let Some(lattice) = WallLattice::of(params)? else {
        return Ok(Vec::new());
    };
    let solid = BoxSdf::new(wall.region)?;
    let images = periodic_images(&params.periodic);
    let mut out = Particles::new(max_count);
    for (node, x) in lattice.nodes().enumerate() {
        let deepest = images
            .iter()
            .map(|o| (x + o, solid.signed_distance(&(x + o))))
            .fold(None, |best: Option<(Vec3<R>, R)>, (y, d)| match best {
                Some((_, b)) if b <= d => best,
                _ => Some((y, d)),
            });
        let Some((y, d)) = deepest else { continue };
        if d >= R::zero() || -d > lattice.depth_limit {
            continue;
        }
        out.push(BoundaryParticle {
            position: x,
            normal: unit_gradient(&solid, &y, node)?,
            model: wall.model,
            velocity: wall.velocity,
        })?;
    }
    Ok(out.0)
}

/// The offsets of a point's periodic images: zero and `±period` along each periodic axis
/// and their combinations (1, 3, 9 or 27 offsets).
fn periodic_images<R: Real>(axes: &[PeriodicAxis<R>]) -> Vec<Vec3<R>> {
    let mut out = vec![Vec3::zeros()];
    for a in axes {
        let shift = |sign: R| {
            let mut e: Vec3<R> = Vec3::zeros();
            e[a.axis] = sign * a.period();
            e
        };
        let ends = [shift(R::one()), shift(-R::one())];
        let more: Vec<Vec3<R>> = out.iter().flat_map(|o| ends.map(|e| o + e)).collect();
        out.extend(more);
    }
    out
}

/// The unit outward normal of `solid` at the wall lattice's node `x` (number `node`).
fn unit_gradient<R: Real>(
    solid: &dyn Sdf<R>,
    x: &Vec3<R>,
    node: usize,
) -> Result<Vec3<R>, SolverError> {
    let g = solid.gradient(x);
    let len = g.norm();
    if len.is_finite() && len > R::zero() {
        Ok(g / len)
    } else {
        Err(sampling_error(
            "boundary_particles",
            node as f64,
            "a solid's signed distance has no finite non-zero gradient at a wall node (value: the node's index in the wall lattice)",
        ))
    }
}

/// The wall lattice of [`sample_solids`]: the fluid's lattice over the region, extended by
/// the wall rows on each non-periodic axis.
struct WallLattice<R: Real> {
    lo: Vec3<R>,
    counts: [usize; 3],
    spacing: R,
    depth_limit: R,
}

impl<R: Real> WallLattice<R> {
    /// The lattice of `params` (`None` without a region). Errors: more than
    /// [`MAX_BOUNDARY_LATTICE_NODES`] nodes.
    fn of(params: &ElastoplasticParams<R>) -> Result<Option<Self>, SolverError> {
        let Some(region) = &params.boundary_particle_region else {
            return Ok(None);
        };
        let s = params.common.particle_spacing;
        let depth_limit = R::of_f64(BOUNDARY_PARTICLE_ROWS) * s;
        let mut lo: Vec3<R> = Vec3::zeros();
        let mut counts = [0usize; 3];
        for a in 0..3 {
            let periodic = params.periodic.iter().any(|p| p.axis == a);
            let pad = if periodic { R::zero() } else { depth_limit };
            lo[a] = region.min[a] - pad;
            let c: f64 = ((region.max[a] - region.min[a] + pad + pad) / s).as_f64();
            counts[a] = (c + 1e-9_f64).floor().max(1.0) as usize;
        }
        let total: f64 = counts.iter().map(|&c| c as f64).product();
        if total > MAX_BOUNDARY_LATTICE_NODES {
            return Err(sampling_error(
                "boundary_particle_region",
                total,
                "the wall lattice would have more than MAX_BOUNDARY_LATTICE_NODES = 2^28 nodes (value: their count); coarsen the spacing or shrink the region",
            ));
        }
        Ok(Some(Self {
            lo,
            counts,
            spacing: s,
            depth_limit,
        }))
    }

    /// The nodes in lattice order (`x` slowest, `z` fastest).
    fn nodes(&self) -> impl Iterator<Item = Vec3<R>> + '_ {
        let [nx, ny, nz] = self.counts;
        let half = R::of_f64(0.5);
        (0..nx).flat_map(move |i| {
            (0..ny).flat_map(move |j| {
                (0..nz).map(move |k| {
                    let idx: Vec3<R> = Vec3::new(
                        R::of_f64(i as f64),
                        R::of_f64(j as f64),
                        R::of_f64(k as f64),
                    );
                    self.lo + (idx + Vec3::repeat(half)) * self.spacing
                })
            })
        })
    }
}

/// Boundary particles collected up to a limit, with fallible growth.
struct Particles<R: Real>(Vec<BoundaryParticle<R>>, usize);

impl<R: Real> Particles<R> {
    fn new(max_count: usize) -> Self {
        Self(Vec::new(), max_count.min(MAX_BOUNDARY_PARTICLES))
    }

    fn push(&mut self, b: BoundaryParticle<R>) -> Result<(), SolverError> {
        let (out, max) = (&mut self.0, self.1);
        if out.len() >= max {
            return Err(sampling_error(
                "boundary_particles",
                max as f64,
                "the walls need more than this many boundary particles (MAX_BOUNDARY_PARTICLES = 2^22, or the caller's limit); coarsen the spacing",
            ));
        }
        if out.len() == out.capacity() {
            let more = out.capacity().max(1024).min(max - out.len());
            out.try_reserve(more).map_err(|_| {
                sampling_error(
                    "boundary_particles",
                    (out.len() + more) as f64,
                    "could not allocate the boundary particles (value: their count)",
                )
            })?;
        }
        out.push(b);
        Ok(())
    }
}
