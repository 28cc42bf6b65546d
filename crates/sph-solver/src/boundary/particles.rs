//! Walls of fixed boundary (dummy) particles, placed on the particle lattice: the layout
//! half of the boundary-particle wall of Adami, Hu & Adams (2012), "A generalized wall
//! boundary condition for smoothed particle hydrodynamics", *J. Comput. Phys.*
//! 231:7057–7075 (rows of fixed boundary particles, as Bui et al. 2008 place them). The
//! values they carry are extrapolated from the particles around them
//! ([`super::wall_extrapolation`]).
//!
//! A [`WallLattice`] is the fluid's lattice (spacing `s`, half a spacing from the faces of a
//! region) extended by a number of rows on each non-periodic axis; the solids' walls are the
//! nodes inside a solid no deeper than the rows ([`WallLattice::sample_solids`]), a moving
//! wall the nodes inside its box ([`WallLattice::sample_moving_wall`]), and a block of
//! boundary particles any box filled on the same lattice ([`boundary_block`]).
//!
//! **Moving walls.** A boundary particle with a wall velocity `v_w` moves with it (`x_b +=
//! v_w Δt` each explicit step, the solver's part) and its wall model acts on the velocity
//! relative to it ([`super::wall_extrapolation`]).

use sph_core::sampling::cubic_lattice;
use sph_core::{Aabb, BoxSdf, Real, Sdf, Vec3};

use crate::error::SolverError;
use crate::scene_boundary::{image_offsets, MovingWall, PeriodicAxis, WallModel};

/// One fixed boundary particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundaryParticle<R: Real> {
    /// Position (m).
    pub position: Vec3<R>,
    /// Unit normal of the wall it stands for, pointing into the particles' side.
    pub normal: Vec3<R>,
    /// Free-slip (mirrored), no-slip (opposite velocity) or Coulomb
    /// ([`super::wall_extrapolation`]).
    pub model: WallModel,
    /// The wall's velocity (m/s; zero for a fixed wall): the particle moves with it, and
    /// the models act on the particles' velocity relative to it.
    pub velocity: Vec3<R>,
}

/// Boundary particles on the cubic lattice of spacing `spacing` filling `region` (half a
/// spacing from its faces, as the particles are placed), all with `normal` and `model`.
/// Errors (naming `solver`): those of the lattice, or a normal that is not finite and
/// non-zero.
pub fn boundary_block<R: Real>(
    solver: &'static str,
    region: &Aabb<R>,
    spacing: R,
    normal: Vec3<R>,
    model: WallModel,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    let len = normal.norm();
    if !(len.is_finite() && len > R::zero()) {
        return Err(SolverError::InvalidParameter {
            solver,
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

/// Most boundary particles a [`WallLattice`] samples (4 M, 200 MB of solver arrays in
/// `f64`): a wall three rows thick around a box of a few million particles.
pub const MAX_BOUNDARY_PARTICLES: usize = 1 << 22;
/// Most lattice nodes a [`WallLattice`] has (256 M, each a signed distance per solid): the
/// region's lattice extended by the wall rows; beyond it the spacing is far too fine for
/// the region.
pub const MAX_BOUNDARY_LATTICE_NODES: f64 = (1u64 << 28) as f64;

/// The lattice on which walls become boundary particles: the fluid's lattice (spacing `s`,
/// half a spacing from the faces of a region) over the region extended by `rows` spacings
/// on each side (not along a periodic axis, whose period the region spans).
#[derive(Debug, Clone)]
pub struct WallLattice<R: Real> {
    solver: &'static str,
    lo: Vec3<R>,
    counts: [usize; 3],
    spacing: R,
    depth_limit: R,
    periodic: Vec<PeriodicAxis<R>>,
}

impl<R: Real> WallLattice<R> {
    /// The lattice of spacing `spacing` over `region` extended by `rows` spacings, with the
    /// periodic axes `periodic`, for `solver` (named in errors). Errors: more than
    /// [`MAX_BOUNDARY_LATTICE_NODES`] nodes.
    pub fn new(
        solver: &'static str,
        region: &Aabb<R>,
        spacing: R,
        rows: f64,
        periodic: &[PeriodicAxis<R>],
    ) -> Result<Self, SolverError> {
        let s = spacing;
        let depth_limit = R::of_f64(rows) * s;
        let mut lo: Vec3<R> = Vec3::zeros();
        let mut counts = [0usize; 3];
        for a in 0..3 {
            let is_periodic = periodic.iter().any(|p| p.axis == a);
            let pad = if is_periodic { R::zero() } else { depth_limit };
            lo[a] = region.min[a] - pad;
            let c: f64 = ((region.max[a] - region.min[a] + pad + pad) / s).as_f64();
            counts[a] = (c + 1e-9_f64).floor().max(1.0) as usize;
        }
        let total: f64 = counts.iter().map(|&c| c as f64).product();
        if total > MAX_BOUNDARY_LATTICE_NODES {
            return Err(sampling_error(
                solver,
                "boundary_particle_region",
                total,
                "the wall lattice would have more than MAX_BOUNDARY_LATTICE_NODES = 2^28 nodes (value: their count); coarsen the spacing or shrink the region",
            ));
        }
        Ok(Self {
            solver,
            lo,
            counts,
            spacing: s,
            depth_limit,
            periodic: periodic.to_vec(),
        })
    }

    /// The lattice cut to the single layer of nodes at `at` (m) along `axis` (0, 1 or 2):
    /// the walls of a planar (2D) run, whose particles all lie in that plane. Errors:
    /// an axis past 2 or a non-finite `at`.
    pub fn in_plane(mut self, axis: usize, at: R) -> Result<Self, SolverError> {
        if axis > 2 || !at.is_finite_value() {
            return Err(sampling_error(
                self.solver,
                "plane",
                axis as f64,
                "a planar wall lattice needs an axis 0, 1 or 2 and a finite position (value: the axis)",
            ));
        }
        self.lo[axis] = at - self.spacing * R::of_f64(0.5);
        self.counts[axis] = 1;
        Ok(self)
    }

    /// The solids' walls as boundary particles: the nodes that lie inside a solid no deeper
    /// than the rows (the deepest solid that holds the node, from its signed distance).
    /// Each takes the solid whose surface is nearest among those holding it: its unit
    /// outward normal (the gradient of its signed distance) and its model `wall_model(k)`
    /// for solid `k` (a solid with [`WallModel::ContactOnly`] gives none). In lattice
    /// order.
    ///
    /// Errors: more than `min(max_count, MAX_BOUNDARY_PARTICLES)` particles, an allocation
    /// that fails, or a solid whose gradient is not a finite non-zero vector at a node (each
    /// named, with the count or the node's index as value).
    pub fn sample_solids(
        &self,
        solids: &[Box<dyn Sdf<R>>],
        wall_model: impl Fn(usize) -> WallModel,
        max_count: usize,
    ) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
        let mut out = Particles::new(self.solver, max_count);
        for (node, x) in self.nodes().enumerate() {
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
            let model = wall_model(m);
            if deepest > self.depth_limit || model == WallModel::ContactOnly {
                continue;
            }
            let normal = self.unit_gradient(&*solids[m], &x, node)?;
            out.push(BoundaryParticle {
                position: x,
                normal,
                model,
                velocity: Vec3::zeros(),
            })?;
        }
        Ok(out.0)
    }

    /// The particles of the moving wall `wall` ([`MovingWall`]): the nodes inside its box
    /// no deeper than the rows, a node taking the periodic image of itself that lies
    /// deepest in the box (so that a box across a periodic axis's ends gives particles on
    /// both sides of the seam), each with the wall's model and velocity and the outward
    /// normal of the box's nearest face. In lattice order.
    ///
    /// Errors: those of [`WallLattice::sample_solids`] and of the box.
    pub fn sample_moving_wall(
        &self,
        wall: &MovingWall<R>,
        max_count: usize,
    ) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
        let solid = BoxSdf::new(wall.region)?;
        let images = image_offsets(&self.periodic);
        let mut out = Particles::new(self.solver, max_count);
        for (node, x) in self.nodes().enumerate() {
            let deepest = images
                .iter()
                .map(|o| (x + o, solid.signed_distance(&(x + o))))
                .fold(None, |best: Option<(Vec3<R>, R)>, (y, d)| match best {
                    Some((_, b)) if b <= d => best,
                    _ => Some((y, d)),
                });
            let Some((y, d)) = deepest else { continue };
            if d >= R::zero() || -d > self.depth_limit {
                continue;
            }
            out.push(BoundaryParticle {
                position: x,
                normal: self.unit_gradient(&solid, &y, node)?,
                model: wall.model,
                velocity: wall.velocity,
            })?;
        }
        Ok(out.0)
    }

    /// The unit outward normal of `solid` at the node `x` (number `node`).
    fn unit_gradient(
        &self,
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
                self.solver,
                "boundary_particles",
                node as f64,
                "a solid's signed distance has no finite non-zero gradient at a wall node (value: the node's index in the wall lattice)",
            ))
        }
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

fn sampling_error(
    solver: &'static str,
    name: &'static str,
    value: f64,
    reason: &'static str,
) -> SolverError {
    SolverError::InvalidParameter {
        solver,
        name,
        value,
        reason,
    }
}

/// Boundary particles collected up to a limit, with fallible growth.
struct Particles<R: Real>(Vec<BoundaryParticle<R>>, usize, &'static str);

impl<R: Real> Particles<R> {
    fn new(solver: &'static str, max_count: usize) -> Self {
        Self(Vec::new(), max_count.min(MAX_BOUNDARY_PARTICLES), solver)
    }

    fn push(&mut self, b: BoundaryParticle<R>) -> Result<(), SolverError> {
        let (out, max, solver) = (&mut self.0, self.1, self.2);
        if out.len() >= max {
            return Err(sampling_error(
                solver,
                "boundary_particles",
                max as f64,
                "the walls need more than this many boundary particles (MAX_BOUNDARY_PARTICLES = 2^22, or the caller's limit); coarsen the spacing",
            ));
        }
        if out.len() == out.capacity() {
            let more = out.capacity().max(1024).min(max - out.len());
            out.try_reserve(more).map_err(|_| {
                sampling_error(
                    solver,
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
