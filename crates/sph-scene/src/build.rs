//! Building from a validated scene: the initial fluid particles (lattice sampling of
//! blocks and meshes), the boundary signed distance fields, and the particle-level checks
//! the parser runs on them.

// NaN-rejecting checks are written as `!(x > 0.0)` on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::sync::Arc;

use sph_core::{
    sampling::cubic_lattice, Aabb, BoxSdf, CylinderSdf, GridSdf, Inverted, Plane, Real, Sdf,
    Sphere, TriangleMesh, Vec3,
};

use crate::error::Ctx;
use crate::geom::{cast3, fmt3, v3, AXES};
use crate::limits::{MAX_PARTICLES, MAX_PASSIVE_POINTS, MAX_SDF_NODES};
use crate::sample_cache::{FluidKey, FluidSample, SampleKey};
use crate::{FluidSpec, Scene, SceneError, SolidSpec};

/// The initial fluid particles of a scene ([`Scene::fluid_particles`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FluidParticles<R: Real> {
    /// Positions (m), fluid by fluid in file order.
    pub positions: Vec<Vec3<R>>,
    /// Velocities (m/s), one per position.
    pub velocities: Vec<Vec3<R>>,
}

/// How far the tank reaches past each end of a periodic axis, in tank extents (at least
/// 1 m): the particles are wrapped into the period at each neighbour search and move less
/// than the support radius between searches, far less than this.
pub const OPEN_TANK_REACH: f64 = 100.0;

impl Scene {
    /// Initial fluid particle positions (m), fluid by fluid in file order (see the crate
    /// documentation for the sampling rules).
    pub fn fluid_positions<R: Real>(&self) -> Result<Vec<Vec3<R>>, SceneError> {
        Ok(self.fluid_particles::<R>()?.positions)
    }

    /// Initial velocities (m/s), one per particle of [`Scene::fluid_positions`] (same order).
    pub fn fluid_velocities<R: Real>(&self) -> Result<Vec<Vec3<R>>, SceneError> {
        Ok(self.fluid_particles::<R>()?.velocities)
    }

    /// The initial fluid particles from one sampling: positions (m) and velocities (m/s),
    /// fluid by fluid in file order.
    pub fn fluid_particles<R: Real>(&self) -> Result<FluidParticles<R>, SceneError> {
        let ctx = Ctx::new(&self.source);
        let samples = self.fluid_samples(&ctx)?;
        let (mut positions, mut velocities) = (Vec::new(), Vec::new());
        for (f, pts) in self.fluids.iter().zip(samples.iter()) {
            velocities.extend(std::iter::repeat_n(
                cast3::<R>(&v3(f.velocity())),
                pts.len(),
            ));
            positions.extend(pts.iter().map(cast3::<R>));
        }
        Ok(FluidParticles {
            positions,
            velocities,
        })
    }

    /// Upper bound of the particle count of fluid `i` (lattice points over its box).
    fn lattice_estimate(&self, i: usize) -> f64 {
        let s = self.particle_spacing;
        let e = self.block_to_fill(self.fluids[i].bounds()).extent();
        (0..3)
            .map(|a| ((e[a] / s) + 1e-9).floor().max(1.0))
            .product()
    }

    /// Every fluid's sample (f64, file order), from the scene's cache when the particle
    /// checks already sampled this spacing and these fluids.
    fn fluid_samples(&self, ctx: &Ctx) -> Result<FluidSample, SceneError> {
        let key = SampleKey {
            spacing: self.particle_spacing,
            fluids: self
                .fluids
                .iter()
                .map(|f| match f {
                    FluidSpec::Block { min, max, .. } => FluidKey::Block {
                        min: *min,
                        max: *max,
                    },
                    FluidSpec::Mesh { mesh, .. } => FluidKey::Mesh(Arc::clone(&mesh.mesh)),
                    FluidSpec::Cylinder {
                        base_center,
                        radius,
                        height,
                        ..
                    } => FluidKey::Cylinder {
                        base_center: *base_center,
                        radius_height: [*radius, *height],
                    },
                })
                .collect(),
        };
        self.fluid_samples.get_or_sample(key, || {
            (0..self.fluids.len())
                .map(|i| self.sample_fluid(ctx, i))
                .collect()
        })
    }

    fn sample_fluid(&self, ctx: &Ctx, i: usize) -> Result<Vec<Vec3<f64>>, SceneError> {
        let s = self.particle_spacing;
        let field = format!("fluid[{i}]");
        let lattice_err = |e: sph_core::CoreError| {
            ctx.invalid(
                field.clone(),
                format!("sampling at particle_spacing {s} m: {e}"),
            )
        };
        match &self.fluids[i] {
            FluidSpec::Block { min, max, .. } => {
                let b = self.block_to_fill(Aabb {
                    min: v3(*min),
                    max: v3(*max),
                });
                cubic_lattice(&b, s, MAX_PARTICLES).map_err(lattice_err)
            }
            FluidSpec::Mesh { mesh, .. } => {
                let b = mesh.mesh.bounds();
                let grid = build_grid(ctx, &field, &mesh.mesh, s, 2.0 * s)?;
                let pts = cubic_lattice(&b, s, MAX_PARTICLES).map_err(lattice_err)?;
                Ok(pts
                    .into_iter()
                    .filter(|p| grid.signed_distance(p) < 0.0)
                    .collect())
            }
            FluidSpec::Cylinder {
                base_center,
                radius,
                height,
                ..
            } => cylinder_lattice(v3(*base_center), *radius, *height, s, MAX_PARTICLES)
                .map_err(lattice_err),
        }
    }

    fn solid_sdf<R: Real>(&self, ctx: &Ctx, j: usize) -> Result<Box<dyn Sdf<R>>, SceneError> {
        let field = format!("solid[{j}]");
        let core = |sub: &str, e: sph_core::CoreError| {
            ctx.invalid(format!("{field}.{sub}"), format!("in {}: {e}", R::NAME))
        };
        Ok(match &self.solids[j] {
            SolidSpec::Sphere { center, radius } => Box::new(
                Sphere::new(cast3::<R>(&v3(*center)), R::of_f64(*radius))
                    .map_err(|e| core("radius", e))?,
            ),
            SolidSpec::Box { min, max } => {
                let b = Aabb::new(cast3::<R>(&v3(*min)), cast3::<R>(&v3(*max)))
                    .map_err(|e| core("min", e))?;
                Box::new(BoxSdf::new(b).map_err(|e| core("min", e))?)
            }
            SolidSpec::Plane { point, normal } => Box::new(
                Plane::new(cast3::<R>(&v3(*point)), cast3::<R>(&v3(*normal)))
                    .map_err(|e| core("normal", e))?,
            ),
            SolidSpec::Cylinder {
                base_center,
                radius,
                height,
            } => Box::new(
                CylinderSdf::new(
                    cast3::<R>(&v3(*base_center)),
                    R::of_f64(*radius),
                    R::of_f64(*height),
                )
                .map_err(|e| core("radius", e))?,
            ),
            SolidSpec::Mesh { mesh, sdf_cell } => {
                let cell = sdf_cell.unwrap_or(self.particle_spacing * 0.5);
                let m = &mesh.mesh;
                let verts: Vec<Vec3<R>> = m.vertices().iter().map(cast3::<R>).collect();
                let mr = TriangleMesh::new(verts, m.triangles().to_vec()).map_err(|e| {
                    ctx.invalid(format!("{field}.path"), format!("in {}: {e}", R::NAME))
                })?;
                let margin = 2.0 * self.particle_spacing + 2.0 * cell;
                Box::new(build_grid(ctx, &field, &mr, cell, margin)?)
            }
        })
    }

    /// The boundary signed distance fields in precision `R`: the tank first (as
    /// `Inverted<BoxSdf>`, when there is one; open along the periodic axes
    /// ([`Scene::periodic_axes`]): its box reaches
    /// [`OPEN_TANK_REACH`] times its extent (at least 1 m) past each end there, so that
    /// particles crossing a periodic end, which the solver wraps, meet no wall), then the
    /// solids that stand still in file order ([`Scene::standing_solids`]; meshes as
    /// [`GridSdf`] with cell `sdf_cell`, default `particle_spacing / 2`, and margin
    /// `2 · particle_spacing + 2 · cell`). A moving solid (`motion`) is not among them: it
    /// is a wall of boundary particles the solver moves ([`crate::SolidMotion`]). Errors
    /// only when a value does not fit in `R` (e.g. a box too thin for `f32`).
    pub fn build_solids<R: Real>(&self) -> Result<Vec<Box<dyn Sdf<R>>>, SceneError> {
        let ctx = Ctx::new(&self.source);
        let mut out: Vec<Box<dyn Sdf<R>>> = Vec::with_capacity(self.solids.len() + 1);
        if let Some(t) = &self.tank {
            let (mut lo, mut hi) = (t.min, t.max);
            // In the plane the tank is open along z, as along a periodic axis.
            let planar_z = self.is_planar().then_some((2, 0.0, 0.0));
            for (axis, _, _) in self.periodic_axes().into_iter().chain(planar_z) {
                if axis < 3 {
                    let reach = OPEN_TANK_REACH * (hi[axis] - lo[axis]).max(1.0);
                    lo[axis] -= reach;
                    hi[axis] += reach;
                }
            }
            let b = Aabb::new(cast3::<R>(&lo), cast3::<R>(&hi))
                .and_then(BoxSdf::new)
                .map_err(|e| ctx.invalid("tank.min", format!("in {}: {e}", R::NAME)))?;
            out.push(Box::new(Inverted(b)));
        }
        for j in self.standing_solids() {
            out.push(self.solid_sdf::<R>(&ctx, j)?);
        }
        Ok(out)
    }

    /// The indices (in file order) of the solids without a `motion`: those
    /// [`Scene::build_solids`] builds.
    pub fn standing_solids(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.solids.len()).filter(|&j| self.motions.get(j).is_none_or(Option::is_none))
    }

    /// When the last moving solid stops (s from the start; 0 without one).
    pub fn motion_end_s(&self) -> f64 {
        self.motions
            .iter()
            .flatten()
            .map(|m| m.duration_s)
            .fold(0.0, f64::max)
    }

    /// The grains the scene's pour adds during the run, at its spacing (0 without a pour;
    /// [`sph_solver::Pour::grains`]).
    pub fn poured_grains(&self) -> usize {
        self.pour
            .map_or(0, |p| self.pour_of(&p).grains(self.particle_spacing))
    }

    /// Particle-level checks: count limit, non-empty fluids, inside the tank, outside solids.
    pub(crate) fn validate_particles(&self, ctx: &Ctx) -> Result<(), SceneError> {
        let mut total = 0.0;
        for i in 0..self.fluids.len() {
            total += self.lattice_estimate(i);
            if !(total <= MAX_PARTICLES as f64) {
                return Err(ctx.invalid(
                    format!("fluid[{i}]"),
                    format!(
                        "the fluids up to this one need about {total:.3e} particles at particle_spacing {} m, more than the maximum of {MAX_PARTICLES}",
                        self.particle_spacing
                    ),
                ));
            }
        }
        if let Some(p) = &self.pour {
            // Checked before the run adds them: the pour's volume over spacing³.
            total += (self.pour_of(p).volume_m3 / self.particle_spacing.powi(3)).max(0.0);
            if !(total <= MAX_PARTICLES as f64) {
                return Err(ctx.invalid(
                    "pour.volume",
                    format!(
                        "the fluids and the pour need about {total:.3e} particles at particle_spacing {} m, more than the maximum of {MAX_PARTICLES}",
                        self.particle_spacing
                    ),
                ));
            }
        }
        if let Some(k) = self.solver.upscaling_factor() {
            // Checked here, before the solver allocates them in its first step.
            let points = total * k as f64;
            if !(points <= MAX_PASSIVE_POINTS as f64) {
                return Err(ctx.invalid(
                    "solver.upscaling_factor",
                    format!(
                        "{k} passive points per particle for about {total:.3e} particles make about {points:.3e} points, more than the maximum of {MAX_PASSIVE_POINTS} (MAX_PASSIVE_POINTS)"
                    ),
                ));
            }
        }
        let solids: Vec<Box<dyn Sdf<f64>>> = (0..self.solids.len())
            .map(|j| self.solid_sdf::<f64>(ctx, j))
            .collect::<Result<_, _>>()?;
        for i in 0..self.fluids.len() {
            let field = format!("fluid[{i}]");
            if let FluidSpec::Block { min, max, .. } = &self.fluids[i] {
                // The lattice puts at least one layer per axis, half a spacing inside the
                // lower corner: in a block thinner than a spacing that layer lies outside it.
                let s = self.particle_spacing;
                if let Some(a) = self
                    .spanned_axes()
                    .find(|&a| max[a] - min[a] < s * (1.0 - 1e-9))
                {
                    return Err(ctx.invalid(
                        format!("{field}.max"),
                        format!(
                            "the block is {} m thick along {}, less than one particle_spacing ({s} m): it cannot hold a layer of particles",
                            max[a] - min[a],
                            AXES[a]
                        ),
                    ));
                }
            }
            if let FluidSpec::Cylinder { height, .. } = &self.fluids[i] {
                // The first layer sits half a spacing above the base (as in a block).
                let s = self.particle_spacing;
                if *height < s * (1.0 - 1e-9) {
                    return Err(ctx.invalid(
                        format!("{field}.height"),
                        format!(
                            "the cylinder is {height} m high, less than one particle_spacing ({s} m): it cannot hold a layer of particles"
                        ),
                    ));
                }
            }
        }
        let samples = self.fluid_samples(ctx)?;
        for (i, pts) in samples.iter().enumerate() {
            let field = format!("fluid[{i}]");
            if pts.is_empty() {
                return Err(ctx.invalid(
                    field,
                    format!(
                        "contains no particle at particle_spacing {} m (smaller than a spacing?)",
                        self.particle_spacing
                    ),
                ));
            }
            if let Some(t) = &self.tank {
                if let Some(p) = pts.iter().find(|p| {
                    !self
                        .spanned_axes()
                        .all(|a| p[a] > t.min[a] && p[a] < t.max[a])
                }) {
                    return Err(ctx.invalid(
                        field,
                        format!("particle at {} is not strictly inside the tank", fmt3(p)),
                    ));
                }
            }
            for (j, sdf) in solids.iter().enumerate() {
                if let Some(p) = pts.iter().find(|p| !(sdf.signed_distance(p) > 0.0)) {
                    return Err(ctx.invalid(
                        field,
                        format!(
                            "overlaps solid[{j}]: particle at {} has signed distance {:.6} m to it (fluids must lie outside solids)",
                            fmt3(p),
                            sdf.signed_distance(p)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A [`GridSdf`] for a scene mesh, with the node count checked against [`MAX_SDF_NODES`]
/// first.
fn build_grid<R: Real>(
    ctx: &Ctx,
    field: &str,
    mesh: &TriangleMesh<R>,
    cell: f64,
    margin: f64,
) -> Result<GridSdf<R>, SceneError> {
    let e = mesh.bounds().extent();
    let nodes: f64 = (0..3)
        .map(|a| ((e[a].as_f64() + 2.0 * margin) / cell).ceil() + 1.0)
        .product();
    if !(nodes <= MAX_SDF_NODES as f64) {
        return Err(ctx.invalid(
            field,
            format!(
                "the mesh's signed distance grid at cell {cell} m would have {nodes:.3e} nodes, more than the maximum of {MAX_SDF_NODES} (use a larger sdf_cell/particle_spacing or a smaller mesh)"
            ),
        ));
    }
    GridSdf::new(mesh, R::of_f64(cell), R::of_f64(margin))
        .map_err(|e| ctx.invalid(field, format!("building the signed distance grid: {e}")))
}

/// The points of a cubic lattice of spacing `s` inside the vertical cylinder of radius
/// `radius` and height `height` on the base centre `c` (see the crate documentation): the
/// lattice is centred on the axis (the axis passes through the corners of four lattice cells,
/// so the points sit at `c + ((i + ½) s, (j + ½) s, (k + ½) s)`), its first layer half a
/// spacing above the base, `⌊height / s⌋` layers (at least one), and a point is kept when
/// its horizontal distance to the axis is **< `radius`**, so that `N s³` approximates the
/// volume `π r² H` without bias.
pub(crate) fn cylinder_lattice(
    c: Vec3<f64>,
    radius: f64,
    height: f64,
    s: f64,
    max_points: usize,
) -> Result<Vec<Vec3<f64>>, sph_core::CoreError> {
    if !(s.is_finite() && s > 0.0) {
        return Err(sph_core::CoreError::InvalidParameter {
            name: "lattice spacing",
            value: s,
            reason: "must be finite and > 0",
        });
    }
    let n = (radius / s).ceil().max(1.0);
    let layers = (height / s + 1e-9).floor().max(1.0);
    let estimate = 4.0 * n * n * layers;
    if !(estimate <= max_points as f64) {
        return Err(sph_core::CoreError::InvalidParameter {
            name: "lattice point count",
            value: estimate,
            reason: "exceeds the allowed maximum",
        });
    }
    let (n, layers) = (n as i64, layers as i64);
    let mut out = Vec::new();
    for i in -n..n {
        let dx = (i as f64 + 0.5) * s;
        for k in -n..n {
            let dz = (k as f64 + 0.5) * s;
            if dx.hypot(dz) >= radius {
                continue;
            }
            for j in 0..layers {
                out.push(Vec3::new(c.x + dx, c.y + (j as f64 + 0.5) * s, c.z + dz));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Against the shape itself (not the lattice rule): every point lies inside the
        /// cylinder, the set is mirror-symmetric about the axis in x and z, the layers are
        /// `⌊H/s⌋`, and the count per layer matches the disc area to within the band of cells
        /// the circle crosses (`|N s² − π r²| ≤ 2π r · √2 s`, the area of cells within half a
        /// cell diagonal of the circle).
        #[test]
        fn cylinder_lattice_fills_the_cylinder(
            cx in -1.0..1.0f64, cy in -1.0..1.0f64, cz in -1.0..1.0f64,
            r_over_s in 0.8..12.0f64, h_over_s in 1.0..8.0f64, s in 0.01..0.1f64,
        ) {
            let (r, h) = (r_over_s * s, h_over_s * s);
            let c = Vec3::new(cx, cy, cz);
            let pts = cylinder_lattice(c, r, h, s, 1 << 20).unwrap();
            let tol = 1e-9;
            for p in &pts {
                prop_assert!((p.x - cx).hypot(p.z - cz) < r + tol);
                prop_assert!(p.y > cy && p.y < cy + h + tol);
            }
            let layers = (h / s + 1e-9).floor() as usize;
            prop_assert_eq!(pts.len() % layers, 0);
            let per_layer = (pts.len() / layers) as f64;
            let area = std::f64::consts::PI * r * r;
            let band = 2.0 * std::f64::consts::PI * r * std::f64::consts::SQRT_2 * s;
            prop_assert!((per_layer * s * s - area).abs() <= band,
                "{per_layer} points of {s}² against π r² = {area}");
            // mirror symmetry about the axis
            let key = |x: f64, y: f64, z: f64| {
                let half = |d: f64| (2.0 * d / s).round() as i64;
                (half(x - cx), half(y - cy), half(z - cz))
            };
            let set: std::collections::HashSet<_> =
                pts.iter().map(|p| key(p.x, p.y, p.z)).collect();
            for p in &pts {
                prop_assert!(set.contains(&key(2.0 * cx - p.x, p.y, p.z)));
                prop_assert!(set.contains(&key(p.x, p.y, 2.0 * cz - p.z)));
            }
        }
    }

    #[test]
    fn cylinder_lattice_refuses_too_many_points() {
        let e = cylinder_lattice(Vec3::zeros(), 1.0, 1.0, 0.001, 1000).unwrap_err();
        assert!(e.to_string().contains("lattice point count"), "{e}");
    }
}
