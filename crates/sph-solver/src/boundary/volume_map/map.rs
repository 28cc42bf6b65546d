//! A volume map: its grid of node models, its construction and its sampling.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;
use sph_core::{Aabb, Real, Sdf, Vec3};

use super::options::{Interpolation, VolumeMapOptions};
use super::quadrature::{looks_planar, node_correction, Directions, KernelTables, NodeCorrection};
use crate::SolverError;
use nalgebra::Matrix3;
use sph_core::grid::SampledGrid;

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
    /// How the map came about with respect to a [`VolumeMapCache`](super::VolumeMapCache).
    pub cache: CacheUse,
}

/// What a [`VolumeMapCache`](super::VolumeMapCache) did for one map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum CacheUse {
    /// Built; no cache was given.
    #[default]
    NoCache,
    /// Built; the solid does not describe itself ([`Sdf::fingerprint`](sph_core::Sdf::fingerprint)), so it is not cached.
    Uncacheable,
    /// Loaded from the cache.
    Hit,
    /// Built (no file yet) and written to the cache.
    Stored,
    /// A cache file existed but was refused (see
    /// [`VolumeMapBoundary::cache_warnings`](super::VolumeMapBoundary::cache_warnings)); rebuilt and the file replaced.
    Replaced,
    /// Built; writing the cache file failed (see [`VolumeMapBoundary::cache_warnings`](super::VolumeMapBoundary::cache_warnings)).
    WriteFailed,
}

/// One node's model (node-planes scheme), in `f32` (relative error 6e-8 of values ≤ 1 and
/// distances ≤ 2h: far below the quadrature error). A model with `|Δ| ≤ √3 cell` may
/// extrapolate slightly below 0 near `φ = h` (measured −1.7e-4 on a sphere); not clamped, to
/// keep `∇Ψ` the gradient of `Ψ`.
#[derive(Debug, Clone, Copy)]
pub(super) struct NodeModel {
    pub(super) phi: f32,
    pub(super) n: [f32; 3],
    pub(super) c: f32,
    pub(super) g: [f32; 3],
    /// `∇∇D` as `[xx, yy, zz, xy, xz, yz]`.
    pub(super) hess: [f32; 6],
}

pub(super) const FAR: u32 = u32::MAX;
pub(super) const DEEP: u32 = u32::MAX - 1;
/// Flag of a stored node whose correction is exactly zero (the solid within its ball is its
/// tangent half-space): where every corner of a cell is such a node (or [`FAR`]), `Ψ` is the
/// half-space volume of the solid's own distance, with no node model to read.
pub(super) const PLANE_BIT: u32 = 1 << 30;

#[derive(Debug, Clone)]
pub(super) enum Storage<R: Real> {
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
    pub(super) tables: Arc<KernelTables>,
    pub(super) origin: Vec3<f64>,
    pub(super) cell: f64,
    pub(super) dims: [usize; 3],
    pub(super) bounded: bool,
    pub(super) storage: Storage<R>,
    pub(super) stats: VolumeMapStats,
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
    /// Builds the map of `solid`; `cancel`, when given, is checked once per row of nodes
    /// (a slab of `nx` cells): once it is set the remaining rows are skipped and the build
    /// returns [`SolverError::Cancelled`].
    pub(crate) fn build(
        solid: &dyn Sdf<R>,
        tables: Arc<KernelTables>,
        domain: &Aabb<R>,
        options: &VolumeMapOptions,
        cancel: Option<&AtomicBool>,
    ) -> Result<Self, SolverError> {
        let cancelled = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
        let refuse = || SolverError::Cancelled {
            what: "volume map".into(),
        };
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
            // Checked per node here (the grid fills itself): a skipped node's value is
            // never kept.
            Interpolation::TrilinearCorrection => Storage::Trilinear(
                SampledGrid::from_fn(origin, cell, dims, |_, p| {
                    if cancelled() {
                        0.0
                    } else {
                        node(p).2.c
                    }
                })
                .map_err(|e| SolverError::Boundary(format!("volume map grid: {e}")))?,
            ),
            Interpolation::NodePlanes => {
                let [nx, ny, nz] = dims;
                // Rows of nodes in parallel (fine enough that the quadrature nodes, which
                // gather near edges, spread over the threads), each node on its own.
                let slabs: Vec<(Vec<u32>, Vec<NodeModel>)> = (0..nz * ny)
                    .into_par_iter()
                    .map(|row| {
                        if cancelled() {
                            return (Vec::new(), Vec::new());
                        }
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
                if cancelled() {
                    return Err(refuse());
                }
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
        if cancelled() {
            return Err(refuse());
        }
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
