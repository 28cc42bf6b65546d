//! Volume maps: the boundary's share of the SPH density, precomputed per solid on a grid.
//!
//! J. Bender, T. Kugelstadt, M. Weiler, D. Koschier, "Volume Maps: An Implicit Boundary
//! Representation for SPH", Proc. ACM SIGGRAPH Conference on Motion, Interaction and Games
//! (MIG '19), <https://doi.org/10.1145/3359566.3360077>.
//!
//! # Equations
//!
//! Bender et al. write the density of particle `i` as `ρ_i = Σ_j m_j W_ij + Σ_b ρ0 V_b W_ib`
//! and represent the boundary term by the volume `V_b` of the solid inside the support,
//! placed as one virtual particle at the closest surface point. Here the boundary term is the
//! integral that this one-particle approximation stands for, the **kernel-weighted boundary
//! volume**
//!
//! `Ψ(x) = ∫_solid W(x − y) dy` (dimensionless), `ρ_B = ρ0 Ψ(x_i)`,
//! `Σ_b V_b W_ib ≡ Ψ(x_i)`, `Σ_b V_b ∇W_ib ≡ ∇Ψ(x_i)` (1/m, pointing into the solid),
//!
//! which is the density map of Koschier & Bender, "Density maps for improved SPH boundary
//! handling", SCA '17 (their `ρ̃(x)/ρ0`), with the kernel integral taken directly rather than
//! through a per-point volume. It is evaluated as
//!
//! `Ψ(x) = Ψ_plane(φ(x)) + C(x)`,
//!
//! with `φ` the solid's signed distance, `Ψ_plane(d) = 2π ∫_d^h W(r) r (r − d) dr` the exact
//! volume of the tangent half-space ([`half_space_volume`], tabulated with 4096 cubic Hermite
//! intervals, error < 1e-12), and `C` a correction that is exactly 0 wherever the solid inside
//! the support ball is that half-space (flat walls are exact), small and smooth near curved
//! surfaces, and non-zero near edges and corners. `C` is computed at grid nodes of spacing
//! `h / cells_per_support` over the solid's band by a spherical quadrature of the
//! **difference** between the solid and its tangent half-space, direction by direction (see
//! `quadrature::node_correction`), skipped where `|φ| ≥ h` or where 78 probes of the ball
//! agree with the tangent plane to `1e-9 h`.
//!
//! # Why not a trilinear `C`: second-order node models (default)
//!
//! A trilinear interpolation of `C(x) = Ψ_exact(x) − Ψ_plane(φ(x))` has an `O(cell)` error
//! wherever `φ` has a kink inside the band, i.e. on the medial axis of the distance field:
//! inside a tank, along the bisector planes of every edge and corner — exactly where fluid
//! particles sit. The jump of `∇C` there is `|Ψ_plane'(φ)| |n₁ − n₂|`, up to `1.7/h` for
//! Poly6; measured in a tank corner: 1.7e-2 of the bulk value. And even on a smooth sphere `C`
//! is not small: it reaches −0.08 for a radius of `1.5 h` and −0.03 for `4 h`, so its trilinear
//! error at `h/4` cells is ~2e-3. The default [`Interpolation::NodePlanes`] therefore stores at
//! each node `c` its own plane `(φ_c, n_c)` and the value, gradient and Hessian of
//! `D_c = Ψ_exact − Ψ_plane(φ_c + n_c·(x − x_c))` at `x_c` (all three from the same
//! spherical quadrature, planar parts cancelling direction by direction), and blends the
//! nodes' second-order models with the trilinear weights `w_c(x)`:
//!
//! `Ψ(x) = Σ_c w_c(x) [Ψ_plane(φ_c + n_c·Δ_c) + C_c + g_c·Δ_c + ½ Δ_cᵀ H_c Δ_c]`,
//! `Δ_c = x − x_c`.
//!
//! Each `D_c` is smooth (also across the medial axis of `φ`, since its plane is fixed), so the
//! blend errs by `O(cell³)`; it is exact for flat walls. `∇Ψ` is the exact gradient of this
//! interpolant (continuous inside cells, C⁰ across cell faces). Storage: 56 bytes (`f32`) per
//! node within `h + √3 cell` of the surface plus a 4-byte index per grid node.
//! [`Interpolation::TrilinearCorrection`] interpolates `C` trilinearly, kept for comparison.
//!
//! # Accuracy and cost (measured, tests `tests/volume_map.rs`; absolute, bulk value 1)
//!
//! | case | 16 × 32 directions (default) | 32 × 64 |
//! |---|---|---|
//! | half-space, tank wall away from edges | 1e-6 (f32 node storage) | same |
//! | sphere `a = 1.5 h`, `4 h` (Poly6) | 8.6e-3, 9.4e-3 | 1.8e-3, 2.1e-3 |
//! | tank corner (Poly6) | 3.4e-3 (trilinear `C`: 1.7e-2) | — |
//! | icosphere `GridSdf` (cell h/10) | — | 5.9e-3 |
//!
//! With 16 × 32 directions the error is that of the direction quadrature at the nodes (the
//! solid's ray integrals have kinks at grazing directions that the Gauss–Legendre rule in
//! `cos θ` does not resolve); 64 × 128 reaches ~3e-4 on the sphere.
//!
//! # Cost
//!
//! Every node costs one distance and one gradient; each band node 78 more distances (the
//! planarity probes); each quadrature node (near edges, corners and curved surfaces)
//! `polar × azimuth` rays. Along a ray, solids with closed-form ray intervals
//! ([`Sdf::ray_inside_intervals`]: planes, spheres, boxes and their complements) give the
//! inside stretches directly (exact up to `f64` rounding of the stored shape). Other solids
//! (meshes, user solids) are searched: a ray samples `φ` at `ray_samples` points, refines
//! each sign change by regula falsi to `|φ| ≤ 1e-10 h` and searches intervals whose end
//! values leave room for a thin sliver of solid (bisection down to `1e-6 h`). For solids with
//! a known Lipschitz bound ([`Sdf::lipschitz_bound`], 1 for exact distances) samples and
//! searches that the bound rules out are skipped: the crossings, and the brackets they are
//! refined from, are those of the full search, so the map is bit-identical (on the tank
//! below: 9.4 distance evaluations per ray instead of 19.3). For such solids the sliver
//! search is also skipped in the first interval of rays from nodes on the surface
//! (`|φ| ≤` rounding): it would bisect towards the surface the node lies on, down to
//! `1e-6 h`. This changes a map only where a solid sliver lies within `h / ray_samples` of
//! such a node (the property test `lipschitz_skips_are_bit_identical_to_the_full_search`
//! checks nodes on walls, edges and corners); closed-form intervals agree with the search to
//! its root tolerance (`closed_form_intervals_agree_with_the_search`). Nodes are built in
//! parallel by rows, each node on its own, so parallel and sequential builds are
//! bit-identical. SPlisHSPlasH's dam-break tank (4 × 3 × 1.5 m, cubic spline, `h = 0.05` m,
//! `f32`): 1.06e7 nodes, 2.3e6 in the band, 2.4e5 by quadrature, 2.9e6 stored (203 MB as a
//! cache file); dated timings against SPlisHSPlasH in `docs/performance.md`. 32 × 64
//! directions cost 4× the quadrature time.
//!
//! # Cache
//!
//! A map depends only on its [`VolumeMapKey`]: the solid's [`Sdf::fingerprint`], kernel,
//! support radius, domain, options, precision and the format and build versions
//! ([`FORMAT_VERSION`], [`BUILD_VERSION`]). [`VolumeMapBoundary::with_cache`] looks each map
//! up in a [`VolumeMapCache`] directory (file `<SHA-256 of the key>.vmap`), loads it when
//! the file passes every check (bit-identical to a cold build), and otherwise builds it and
//! writes the file atomically. [`VolumeMap::read_file`] documents the format and the
//! refusals ([`SolverError::MapFile`]): a corrupt, truncated, foreign or other-version file
//! is never half-loaded; the boundary then rebuilds, replaces the file and reports the
//! refusal in [`VolumeMapBoundary::cache_warnings`] for the caller to log. Solids that do
//! not describe themselves (the default of [`Sdf::fingerprint`]) are rebuilt every time.
//!
//! # Grid size
//!
//! A solid's grid may have at most [`VolumeMapOptions::max_nodes`] nodes (default 2²⁵), and
//! that limit at most 2²⁶ ([`SampledGrid::MAX_NODES`]), checked before any work.
//!
//! # Other deviations and limits
//!
//! - Overlapping solids double-count their overlap (each solid is integrated on its own).
//! - The viscosity kernel is rejected (its `W'' r²`, needed for the Hessians, diverges).
//! - Nodes equidistant to two surfaces (e.g. at `φ = h` from two tank walls) carry one of the
//!   planes; beyond `φ ≥ h` their correction is not computed, so within a cell of such
//!   nodes `Ψ` errs by up to `Ψ_plane(h − √3 cell)` (~1e-4 at `h/4` cells for Poly6).
//! - Root finding along rays assumes the distance is 2-Lipschitz (or the solid's
//!   [`Sdf::lipschitz_bound`]); solid slivers thinner than `1e-6 h` between ray samples are
//!   ignored, and for solids with a declared bound, slivers in the first `h / ray_samples`
//!   of rays from nodes on the surface.
//! - Outside the grid box `C = 0`: for bounded solids the box is the solid's bounds grown by
//!   `h` (intersected with the domain grown by `h`), for unbounded solids the domain grown by
//!   `h`.

mod boundary;
mod file;
mod key;
mod quadrature;

pub use boundary::VolumeMapBoundary;
pub use file::{FORMAT_VERSION, MAGIC};
pub use key::{VolumeMapCache, VolumeMapKey, BUILD_VERSION};
pub use quadrature::{half_space_volume, half_space_volume_derivative};

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;
use sph_core::{Aabb, Real, Sdf, Vec3};

use crate::SolverError;
use nalgebra::Matrix3;
use quadrature::{looks_planar, node_correction, Directions, KernelTables, NodeCorrection};
use sph_core::grid::SampledGrid;

/// How `Ψ` is interpolated between grid nodes (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// Trilinear blend of each node's tangent-plane model plus second-order correction
    /// (`O(cell³)` where the nodes' corrections are smooth, exact for flat walls). Stores
    /// 56 bytes per band node.
    #[default]
    NodePlanes,
    /// `Ψ = Ψ_plane(φ(x)) + C(x)` with `C` trilinear on a dense [`f64`] grid (`O(cell)` near
    /// medial axes of `φ`, e.g. near tank edges).
    TrilinearCorrection,
}

/// Build options of a volume map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeMapOptions {
    /// Grid cells per support radius (1..=64; default 4: spacing `h/4`).
    pub cells_per_support: usize,
    /// Gauss–Legendre points in `cos θ` about the node normal (1..=256; default 16).
    pub polar_directions: usize,
    /// Uniform azimuths (1..=1024; default 32).
    pub azimuth_directions: usize,
    /// Samples of `φ` along each ray before the sign-change search (1..=256; default 8).
    pub ray_samples: usize,
    /// Largest grid (nodes) a single solid may use (8..=2²⁶, the limit of
    /// [`SampledGrid::MAX_NODES`]; default 2²⁵ ≈ 3.4e7).
    pub max_nodes: usize,
    /// Interpolation scheme (default [`Interpolation::NodePlanes`]).
    pub interpolation: Interpolation,
}

impl Default for VolumeMapOptions {
    fn default() -> Self {
        Self {
            cells_per_support: 4,
            polar_directions: 16,
            azimuth_directions: 32,
            ray_samples: 8,
            max_nodes: 1 << 25,
            interpolation: Interpolation::NodePlanes,
        }
    }
}

impl VolumeMapOptions {
    fn validate(&self) -> Result<(), SolverError> {
        let checks: [(&'static str, usize, usize, usize, &'static str); 5] = [
            (
                "cells_per_support",
                self.cells_per_support,
                1,
                64,
                "must be in 1..=64",
            ),
            (
                "polar_directions",
                self.polar_directions,
                1,
                256,
                "must be in 1..=256",
            ),
            (
                "azimuth_directions",
                self.azimuth_directions,
                1,
                1024,
                "must be in 1..=1024",
            ),
            (
                "ray_samples",
                self.ray_samples,
                1,
                256,
                "must be in 1..=256",
            ),
            (
                "max_nodes",
                self.max_nodes,
                8,
                SampledGrid::<f64>::MAX_NODES,
                "must be in 8..=2^26",
            ),
        ];
        for (name, v, lo, hi, reason) in checks {
            if v < lo || v > hi {
                return Err(invalid(name, v as f64, reason));
            }
        }
        Ok(())
    }
}

pub(crate) fn invalid(name: &'static str, value: f64, reason: &'static str) -> SolverError {
    SolverError::InvalidParameter {
        solver: "volume map",
        name,
        value,
        reason,
    }
}

/// Build statistics of one [`VolumeMap`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VolumeMapStats {
    /// Grid nodes along x, y, z (`[0, 0, 0]` when the solid's band misses the domain).
    pub dims: [usize; 3],
    /// All grid nodes.
    pub nodes: usize,
    /// Nodes within `h` of the surface (`|φ| < h`).
    pub band_nodes: usize,
    /// Band nodes whose correction came from the spherical quadrature.
    pub quadrature_nodes: usize,
    /// Nodes stored with a model (node-planes scheme: `|φ| < h + √3 cell`).
    pub stored_nodes: usize,
    /// Wall-clock time of the cold build (for a map loaded from a cache: of the build that
    /// wrote the file).
    pub build_time: Duration,
    /// Wall-clock time of reading the map from a cache file (zero for a built map).
    pub load_time: Duration,
    /// How the map came about with respect to a [`VolumeMapCache`].
    pub cache: CacheUse,
}

/// What a [`VolumeMapCache`] did for one map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum CacheUse {
    /// Built; no cache was given.
    #[default]
    NoCache,
    /// Built; the solid does not describe itself ([`Sdf::fingerprint`]), so it is not cached.
    Uncacheable,
    /// Loaded from the cache.
    Hit,
    /// Built (no file yet) and written to the cache.
    Stored,
    /// A cache file existed but was refused (see
    /// [`VolumeMapBoundary::cache_warnings`]); rebuilt and the file replaced.
    Replaced,
    /// Built; writing the cache file failed (see [`VolumeMapBoundary::cache_warnings`]).
    WriteFailed,
}

/// One node's model (node-planes scheme), in `f32` (relative error 6e-8 of values ≤ 1 and
/// distances ≤ 2h: far below the quadrature error). A model with `|Δ| ≤ √3 cell` may
/// extrapolate slightly below 0 near `φ = h` (measured −1.7e-4 on a sphere); not clamped, to
/// keep `∇Ψ` the gradient of `Ψ`.
#[derive(Debug, Clone, Copy)]
struct NodeModel {
    phi: f32,
    n: [f32; 3],
    c: f32,
    g: [f32; 3],
    /// `∇∇D` as `[xx, yy, zz, xy, xz, yz]`.
    hess: [f32; 6],
}

const FAR: u32 = u32::MAX;
const DEEP: u32 = u32::MAX - 1;
/// Flag of a stored node whose correction is exactly zero (the solid within its ball is its
/// tangent half-space): where every corner of a cell is such a node (or [`FAR`]), `Ψ` is the
/// half-space volume of the solid's own distance, with no node model to read.
const PLANE_BIT: u32 = 1 << 30;

#[derive(Debug, Clone)]
enum Storage<R: Real> {
    /// No grid (the band misses the domain).
    Empty,
    NodePlanes {
        /// Per dense node: index into `models`, or [`FAR`] (Ψ = 0 nearby) / [`DEEP`] (Ψ = 1).
        index: Vec<u32>,
        models: Vec<NodeModel>,
        /// One bit per cell: set where all eight corners are flat-wall nodes or [`FAR`],
        /// so that `Ψ` is the half-space volume of the solid's own distance. A bit grid is
        /// 1/32 of the index, small enough to stay in cache where the index is not.
        flat_cells: Vec<u64>,
    },
    Trilinear(SampledGrid<R>),
}

/// The volume map of one solid: `Ψ` and `∇Ψ` for one kernel (see the module docs).
#[derive(Debug, Clone)]
pub struct VolumeMap<R: Real> {
    tables: Arc<KernelTables>,
    origin: Vec3<f64>,
    cell: f64,
    dims: [usize; 3],
    bounded: bool,
    storage: Storage<R>,
    stats: VolumeMapStats,
}

fn v64<R: Real>(v: &Vec3<R>) -> Vec3<f64> {
    Vec3::new(v.x.as_f64(), v.y.as_f64(), v.z.as_f64())
}

fn vr<R: Real>(v: &Vec3<f64>) -> Vec3<R> {
    Vec3::new(R::of_f64(v.x), R::of_f64(v.y), R::of_f64(v.z))
}

/// The flat-cell bits of a node index (see `Storage::NodePlanes::flat_cells`).
fn flat_cells(index: &[u32], dims: [usize; 3]) -> Vec<u64> {
    let [nx, ny, nz] = dims;
    let cells = (nx - 1) * (ny - 1) * (nz - 1);
    let mut bits = vec![0u64; cells.div_ceil(64)];
    let flat = |v: u32| v == FAR || (v < DEEP && v & PLANE_BIT != 0);
    let mut cell = 0;
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let all = (0..8).all(|c| {
                    let (a, b, d) = (c & 1, (c >> 1) & 1, c >> 2);
                    flat(index[(i + a) + nx * ((j + b) + ny * (k + d))])
                });
                if all {
                    bits[cell / 64] |= 1 << (cell % 64);
                }
                cell += 1;
            }
        }
    }
    bits
}

fn unit_normal<R: Real>(sdf: &dyn Sdf<R>, p: &Vec3<R>) -> Vec3<f64> {
    let g = v64(&sdf.gradient(p));
    let len = g.norm();
    if len > 0.0 && len.is_finite() {
        g / len
    } else {
        Vec3::z()
    }
}

impl<R: Real> VolumeMap<R> {
    pub(crate) fn build(
        solid: &dyn Sdf<R>,
        tables: Arc<KernelTables>,
        domain: &Aabb<R>,
        options: &VolumeMapOptions,
    ) -> Result<Self, SolverError> {
        let start = Instant::now();
        let h = tables.h;
        let cell = h / options.cells_per_support as f64;
        let dom = Aabb {
            min: v64(&domain.min),
            max: v64(&domain.max),
        }
        .expanded(h);
        let bounds = solid.bounds();
        let region = match bounds {
            Some(b) => {
                let b = Aabb {
                    min: v64(&b.min),
                    max: v64(&b.max),
                }
                .expanded(h);
                let r = Aabb {
                    min: b.min.sup(&dom.min),
                    max: b.max.inf(&dom.max),
                };
                (0..3)
                    .all(|a| r.min[a].is_finite() && r.max[a].is_finite() && r.min[a] <= r.max[a])
                    .then_some(r)
            }
            None => Some(dom),
        };
        let empty = |stats| Self {
            tables: tables.clone(),
            origin: Vec3::zeros(),
            cell,
            dims: [0; 3],
            bounded: bounds.is_some(),
            storage: Storage::Empty,
            stats,
        };
        let Some(region) = region else {
            return Ok(empty(VolumeMapStats {
                build_time: start.elapsed(),
                ..Default::default()
            }));
        };
        let dims = SampledGrid::<R>::covering(region.min, region.max, cell)
            .map_err(|e| SolverError::Boundary(format!("volume map grid: {e}")))?;
        let total = dims[0] as f64 * dims[1] as f64 * dims[2] as f64;
        if total > options.max_nodes as f64 {
            return Err(SolverError::Boundary(format!(
                "volume map grid of {} x {} x {} = {total} nodes (cell {cell} m) exceeds \
                 max_nodes = {}",
                dims[0], dims[1], dims[2], options.max_nodes
            )));
        }
        let origin = region.min;
        let dirs = Directions::new(
            options.polar_directions,
            options.azimuth_directions,
            options.ray_samples,
        );
        let band = AtomicUsize::new(0);
        let quad = AtomicUsize::new(0);
        let eps = R::MACHINE_EPSILON.as_f64();
        // One node: (φ, n, correction); the correction is 0 outside the band and where planar.
        let zero = NodeCorrection {
            c: 0.0,
            grad: Vec3::zeros(),
            hess: Matrix3::zeros(),
        };
        let node = |p: Vec3<f64>| {
            let pr = vr::<R>(&p);
            let phi = solid.signed_distance(&pr).as_f64();
            let n = unit_normal(solid, &pr);
            if phi.is_nan() || phi.abs() >= h {
                return (phi, n, zero);
            }
            band.fetch_add(1, Ordering::Relaxed);
            // 1e-9 h, or the rounding of the solid's own precision.
            let tol = 1e-9 * h + 16.0 * eps * (p.amax() + h);
            if looks_planar(solid, p, phi, n, h, tol) {
                return (phi, n, zero);
            }
            quad.fetch_add(1, Ordering::Relaxed);
            (phi, n, node_correction(solid, p, phi, n, &tables, &dirs))
        };
        let reach = h + 3f64.sqrt() * cell;
        let storage = match options.interpolation {
            Interpolation::TrilinearCorrection => Storage::Trilinear(
                SampledGrid::from_fn(origin, cell, dims, |_, p| node(p).2.c)
                    .map_err(|e| SolverError::Boundary(format!("volume map grid: {e}")))?,
            ),
            Interpolation::NodePlanes => {
                let [nx, ny, nz] = dims;
                // Rows of nodes in parallel (fine enough that the quadrature nodes, which
                // gather near edges, spread over the threads), each node on its own.
                let slabs: Vec<(Vec<u32>, Vec<NodeModel>)> = (0..nz * ny)
                    .into_par_iter()
                    .map(|row| {
                        let (j, k) = (row % ny, row / ny);
                        let mut index = Vec::with_capacity(nx);
                        let mut models = Vec::new();
                        for i in 0..nx {
                            let p = origin + Vec3::new(i as f64, j as f64, k as f64) * cell;
                            let (
                                phi,
                                n,
                                NodeCorrection {
                                    c,
                                    grad: g,
                                    hess: hs,
                                },
                            ) = node(p);
                            if phi >= reach {
                                index.push(FAR);
                            } else if phi <= -reach {
                                index.push(DEEP);
                            } else {
                                let pure = c == 0.0 && g == Vec3::zeros() && hs == Matrix3::zeros();
                                index.push(models.len() as u32 | if pure { PLANE_BIT } else { 0 });
                                models.push(NodeModel {
                                    phi: phi as f32,
                                    n: [n.x as f32, n.y as f32, n.z as f32],
                                    c: c as f32,
                                    g: [g.x as f32, g.y as f32, g.z as f32],
                                    hess: [
                                        hs[(0, 0)] as f32,
                                        hs[(1, 1)] as f32,
                                        hs[(2, 2)] as f32,
                                        hs[(0, 1)] as f32,
                                        hs[(0, 2)] as f32,
                                        hs[(1, 2)] as f32,
                                    ],
                                });
                            }
                        }
                        (index, models)
                    })
                    .collect();
                let stored: usize = slabs.iter().map(|s| s.1.len()).sum();
                if stored >= PLANE_BIT as usize {
                    return Err(SolverError::Boundary(format!(
                        "volume map: {stored} band nodes exceed the u32 index"
                    )));
                }
                let mut index = Vec::with_capacity(nx * ny * nz);
                let mut models = Vec::with_capacity(stored);
                for (idx, m) in slabs {
                    let off = models.len() as u32;
                    index.extend(idx.into_iter().map(|v| if v >= DEEP { v } else { v + off }));
                    models.extend(m);
                }
                let flat_cells = flat_cells(&index, dims);
                Storage::NodePlanes {
                    index,
                    models,
                    flat_cells,
                }
            }
        };
        let stored_nodes = match &storage {
            Storage::NodePlanes { models, .. } => models.len(),
            _ => 0,
        };
        Ok(Self {
            tables: tables.clone(),
            origin,
            cell,
            dims,
            bounded: bounds.is_some(),
            storage,
            stats: VolumeMapStats {
                dims,
                nodes: dims[0] * dims[1] * dims[2],
                band_nodes: band.into_inner(),
                quadrature_nodes: quad.into_inner(),
                stored_nodes,
                build_time: start.elapsed(),
                ..VolumeMapStats::default()
            },
        })
    }

    /// Writes this map, built for `key`, to `path`, atomically (a temporary file beside
    /// `path`, `fsync`, rename): a reader never sees a partial file.
    ///
    /// Errors: [`SolverError::MapFile`] with [`MapFileProblem::Io`](crate::MapFileProblem::Io).
    pub fn write_file(&self, path: &Path, key: &VolumeMapKey) -> Result<(), SolverError> {
        file::write_map(path, self, key)
    }

    /// Reads the map of `key` (whose solid must be the one passed to [`VolumeMap::sample`])
    /// from `path`, written by [`VolumeMap::write_file`].
    ///
    /// File layout (integers little-endian): 8 bytes [`MAGIC`], 4 bytes [`FORMAT_VERSION`],
    /// 8 bytes total file length, the key (8-byte length, bytes: [`VolumeMapKey::as_bytes`]),
    /// the payload (8-byte length, bytes: grid, node models, statistics), and the SHA-256 of
    /// all bytes before it. The reader checks, in this order, magic, version, length,
    /// checksum, key and the payload's consistency, and refuses the file at the first
    /// failure, loading nothing of it.
    ///
    /// Errors: [`SolverError::MapFile`] naming `path` and the
    /// [`MapFileProblem`](crate::MapFileProblem): `Io`, `BadMagic`,
    /// `UnsupportedVersion`, `Truncated`, `TrailingBytes`, `ChecksumMismatch`, `ForeignKey`
    /// (a map of other inputs), `Malformed`; [`SolverError::Kernel`] for a key whose kernel
    /// cannot be built.
    pub fn read_file(path: &Path, key: &VolumeMapKey) -> Result<Self, SolverError> {
        let kernel = key.kernel().build(key.support_radius())?;
        let tables = Arc::new(KernelTables::new(&kernel));
        Self::read_with_tables(path, key, tables)
    }

    pub(crate) fn read_with_tables(
        path: &Path,
        key: &VolumeMapKey,
        tables: Arc<KernelTables>,
    ) -> Result<Self, SolverError> {
        let start = Instant::now();
        let mut map = file::read_map(path, key, tables)?;
        map.stats.load_time = start.elapsed();
        map.stats.cache = CacheUse::Hit;
        Ok(map)
    }

    /// Build statistics (node counts and build time).
    pub fn stats(&self) -> VolumeMapStats {
        self.stats
    }

    /// Support radius `h` (m) of the kernel the map was integrated with.
    pub fn support_radius(&self) -> f64 {
        self.tables.h
    }

    /// Grid node spacing (m).
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// `Ψ` (dimensionless) and `∇Ψ` (1/m) of this map's solid at `x`; `solid` must be the
    /// solid the map was built for (its distance is evaluated only where the grid does not
    /// reach, and everywhere by the trilinear scheme). Zero where `φ ≥ h`.
    pub fn sample(&self, solid: &dyn Sdf<R>, x: &Vec3<R>) -> (R, Vec3<R>) {
        let (psi, grad) = self.sample_f64(solid, x);
        (R::of_f64(psi), vr(&grad))
    }

    fn grid_coords(&self, p: &Vec3<f64>) -> Option<Vec3<f64>> {
        if self.dims[0] < 2 {
            return None;
        }
        let u = (p - self.origin) / self.cell;
        (0..3)
            .all(|a| u[a] >= 0.0 && u[a] <= (self.dims[a] - 1) as f64)
            .then_some(u)
    }

    fn plane_only(&self, solid: &dyn Sdf<R>, x: &Vec3<R>) -> (f64, Vec3<f64>) {
        let phi = solid.signed_distance(x).as_f64();
        if phi.is_nan() || phi >= self.tables.h {
            return (0.0, Vec3::zeros());
        }
        let n = unit_normal(solid, x);
        (
            self.tables.psi_plane(phi),
            n * self.tables.psi_plane_derivative(phi),
        )
    }

    fn sample_f64(&self, solid: &dyn Sdf<R>, x: &Vec3<R>) -> (f64, Vec3<f64>) {
        let p = v64(x);
        let u = self.grid_coords(&p);
        match (&self.storage, u) {
            (
                Storage::NodePlanes {
                    index,
                    models,
                    flat_cells,
                },
                Some(u),
            ) => {
                // Beyond the support of the solid Ψ is exactly 0: one evaluation of the
                // signed distance (a few flops for analytic solids) instead of eight
                // scattered node reads (the dense node index of a tank is tens of MB).
                let phi = solid.signed_distance(x).as_f64();
                if phi >= self.tables.h {
                    return (0.0, Vec3::zeros());
                }
                let cell = self.cell_of(&u);
                let flat = (flat_cells[cell / 64] >> (cell % 64)) & 1 == 1;
                let blended = if flat {
                    None
                } else {
                    self.blend(index, models, &p, &u)
                };
                blended.unwrap_or_else(|| {
                    // Flat wall around the whole cell: exact half-space volume.
                    let n = unit_normal(solid, x);
                    let (pv, pd) = self.tables.psi_plane_with_derivative(phi);
                    (pv, n * pd)
                })
            }
            (Storage::Trilinear(grid), _) => {
                let (psi, grad) = self.plane_only(solid, x);
                if psi == 0.0 && grad == Vec3::zeros() {
                    return (0.0, Vec3::zeros());
                }
                let (c, gc) = grid.sample(x).unwrap_or((0.0, Vec3::zeros()));
                (psi + c, grad + gc)
            }
            _ if self.bounded && self.dims[0] >= 2 => (0.0, Vec3::zeros()),
            _ => self.plane_only(solid, x),
        }
    }

    /// Linear index of the cell holding grid coordinates `u` (cells along x fastest).
    #[inline]
    fn cell_of(&self, u: &Vec3<f64>) -> usize {
        let [nx, ny, _] = self.dims;
        let c = |a: usize| (u[a].floor() as usize).min(self.dims[a] - 2);
        c(0) + (nx - 1) * (c(1) + (ny - 1) * c(2))
    }

    fn blend(
        &self,
        index: &[u32],
        models: &[NodeModel],
        p: &Vec3<f64>,
        u: &Vec3<f64>,
    ) -> Option<(f64, Vec3<f64>)> {
        let mut i = [0usize; 3];
        let mut f = [0.0; 3];
        for a in 0..3 {
            let c = (u[a].floor() as usize).min(self.dims[a] - 2);
            i[a] = c;
            f[a] = u[a] - c as f64;
        }
        let [nx, ny, _] = self.dims;
        let corner_index = |corner: usize| {
            let d = [corner & 1, (corner >> 1) & 1, corner >> 2];
            index[(i[0] + d[0]) + nx * ((i[1] + d[1]) + ny * (i[2] + d[2]))]
        };
        if (0..8).all(|k| {
            let v = corner_index(k);
            v == FAR || (v < DEEP && v & PLANE_BIT != 0)
        }) {
            return None;
        }
        let t = &self.tables;
        let (mut psi, mut grad) = (0.0, Vec3::zeros());
        for corner in 0..8 {
            let d = [corner & 1, (corner >> 1) & 1, corner >> 2];
            let idx = (i[0] + d[0]) + nx * ((i[1] + d[1]) + ny * (i[2] + d[2]));
            let wa = |a: usize| if d[a] == 1 { f[a] } else { 1.0 - f[a] };
            let sa = |a: usize| (if d[a] == 1 { 1.0 } else { -1.0 }) / self.cell;
            let w = wa(0) * wa(1) * wa(2);
            let dw = Vec3::new(
                sa(0) * wa(1) * wa(2),
                wa(0) * sa(1) * wa(2),
                wa(0) * wa(1) * sa(2),
            );
            let (value, slope) = match index[idx] {
                FAR => (0.0, Vec3::zeros()),
                DEEP => (1.0, Vec3::zeros()),
                m => {
                    let m = &models[(m & !PLANE_BIT) as usize];
                    let xc = self.origin
                        + Vec3::new(
                            (i[0] + d[0]) as f64,
                            (i[1] + d[1]) as f64,
                            (i[2] + d[2]) as f64,
                        ) * self.cell;
                    let dx = p - xc;
                    let n = Vec3::new(m.n[0] as f64, m.n[1] as f64, m.n[2] as f64);
                    let g = Vec3::new(m.g[0] as f64, m.g[1] as f64, m.g[2] as f64);
                    let hs = m.hess.map(|v| v as f64);
                    let hdx = Vec3::new(
                        hs[0] * dx.x + hs[3] * dx.y + hs[4] * dx.z,
                        hs[3] * dx.x + hs[1] * dx.y + hs[5] * dx.z,
                        hs[4] * dx.x + hs[5] * dx.y + hs[2] * dx.z,
                    );
                    let arg = m.phi as f64 + n.dot(&dx);
                    let (pv, pd) = t.psi_plane_with_derivative(arg);
                    (
                        pv + m.c as f64 + g.dot(&dx) + 0.5 * dx.dot(&hdx),
                        n * pd + g + hdx,
                    )
                }
            };
            psi += w * value;
            grad += dw * value + slope * w;
        }
        Some((psi, grad))
    }
}
