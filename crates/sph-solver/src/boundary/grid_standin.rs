//! A minimal private stand-in for `sph_core::grid::SampledGrid<R>` (being written in
//! sph-core), with the same signatures: a dense regular grid of `f64` node values, sampled by
//! trilinear interpolation. When the sph-core type lands, `volume_map` switches to it by
//! changing one `use` line and this file is deleted.
#![allow(dead_code)]

use std::marker::PhantomData;

use rayon::prelude::*;
use sph_core::{Aabb, CoreError, Real, Vec3};

/// Largest node count [`SampledGrid::covering`] accepts.
const MAX_NODES: f64 = (1u64 << 31) as f64;

/// Dense regular grid of `f64` values with origin `origin`, spacing `cell` and `dims` nodes.
#[derive(Debug, Clone)]
pub struct SampledGrid<R> {
    origin: Vec3<f64>,
    cell: f64,
    dims: [usize; 3],
    values: Vec<f64>,
    _real: PhantomData<R>,
}

fn cell_error(cell: f64) -> CoreError {
    CoreError::InvalidParameter {
        name: "grid cell size",
        value: cell,
        reason: "must be finite and > 0",
    }
}

impl<R: Real> SampledGrid<R> {
    /// Node counts of a grid with spacing `cell` whose nodes cover `[min, max]`:
    /// `ceil((max − min)/cell) + 1` per axis (at least 2).
    pub fn covering(min: Vec3<f64>, max: Vec3<f64>, cell: f64) -> Result<[usize; 3], CoreError> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(cell_error(cell));
        }
        let mut dims = [0usize; 3];
        for a in 0..3 {
            let n = ((max[a] - min[a]) / cell).ceil() + 1.0;
            if !(min[a].is_finite() && max[a].is_finite() && n.is_finite() && n <= MAX_NODES) {
                return Err(CoreError::InvalidParameter {
                    name: "grid extent",
                    value: max[a] - min[a],
                    reason: "must be finite, >= 0 and hold fewer than 2^31 nodes per axis",
                });
            }
            dims[a] = (n.max(2.0)) as usize;
        }
        Ok(dims)
    }

    /// Evaluates `f(index, position)` at every node (in parallel, deterministic result).
    pub fn from_fn(
        origin: Vec3<f64>,
        cell: f64,
        dims: [usize; 3],
        f: impl Fn([usize; 3], Vec3<f64>) -> f64 + Sync,
    ) -> Result<Self, CoreError> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(cell_error(cell));
        }
        let total = dims[0] as f64 * dims[1] as f64 * dims[2] as f64;
        if dims.iter().any(|&n| n < 2) || total > MAX_NODES {
            return Err(CoreError::InvalidParameter {
                name: "grid node count",
                value: total,
                reason: "needs >= 2 nodes per axis and fewer than 2^31 in all",
            });
        }
        let [nx, ny, _] = dims;
        let values = (0..dims[0] * dims[1] * dims[2])
            .into_par_iter()
            .map(|l| {
                let idx = [l % nx, (l / nx) % ny, l / (nx * ny)];
                let p = origin + Vec3::new(idx[0] as f64, idx[1] as f64, idx[2] as f64) * cell;
                f(idx, p)
            })
            .collect();
        Ok(Self {
            origin,
            cell,
            dims,
            values,
            _real: PhantomData,
        })
    }

    /// Trilinear value and its gradient (per length) at `p`; `None` outside the grid box.
    pub fn sample(&self, p: &Vec3<R>) -> Option<(f64, Vec3<f64>)> {
        let q = Vec3::new(p.x.as_f64(), p.y.as_f64(), p.z.as_f64());
        let u = (q - self.origin) / self.cell;
        if (0..3).any(|a| !(u[a] >= 0.0 && u[a] <= (self.dims[a] - 1) as f64)) {
            return None;
        }
        Some(self.interpolate(u))
    }

    /// As [`SampledGrid::sample`], with `p` clamped into the grid box first.
    pub fn sample_clamped(&self, p: &Vec3<R>) -> (f64, Vec3<f64>) {
        let q = Vec3::new(p.x.as_f64(), p.y.as_f64(), p.z.as_f64());
        let mut u = (q - self.origin) / self.cell;
        for a in 0..3 {
            u[a] = if u[a].is_nan() {
                0.0
            } else {
                u[a].clamp(0.0, (self.dims[a] - 1) as f64)
            };
        }
        self.interpolate(u)
    }

    fn interpolate(&self, u: Vec3<f64>) -> (f64, Vec3<f64>) {
        let mut i = [0usize; 3];
        let mut f = [0.0; 3];
        for a in 0..3 {
            let c = (u[a].floor() as usize).min(self.dims[a] - 2);
            i[a] = c;
            f[a] = u[a] - c as f64;
        }
        let [nx, ny, _] = self.dims;
        let v = |di: usize, dj: usize, dk: usize| {
            self.values[(i[0] + di) + nx * ((i[1] + dj) + ny * (i[2] + dk))]
        };
        let (mut val, mut grad) = (0.0, Vec3::zeros());
        for dk in 0..2 {
            for dj in 0..2 {
                for di in 0..2 {
                    let w = [
                        if di == 1 { f[0] } else { 1.0 - f[0] },
                        if dj == 1 { f[1] } else { 1.0 - f[1] },
                        if dk == 1 { f[2] } else { 1.0 - f[2] },
                    ];
                    let s = [
                        if di == 1 { 1.0 } else { -1.0 },
                        if dj == 1 { 1.0 } else { -1.0 },
                        if dk == 1 { 1.0 } else { -1.0 },
                    ];
                    let value = v(di, dj, dk);
                    val += w[0] * w[1] * w[2] * value;
                    grad += Vec3::new(s[0] * w[1] * w[2], w[0] * s[1] * w[2], w[0] * w[1] * s[2])
                        * (value / self.cell);
                }
            }
        }
        (val, grad)
    }

    /// Node counts along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Node spacing (length).
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// The box spanned by the nodes.
    pub fn grid_box(&self) -> Aabb<f64> {
        let d = Vec3::new(
            (self.dims[0] - 1) as f64,
            (self.dims[1] - 1) as f64,
            (self.dims[2] - 1) as f64,
        );
        Aabb {
            min: self.origin,
            max: self.origin + d * self.cell,
        }
    }

    /// The value at node `idx` (`None` out of range).
    pub fn node_value(&self, idx: [usize; 3]) -> Option<f64> {
        let [nx, ny, nz] = self.dims;
        (idx[0] < nx && idx[1] < ny && idx[2] < nz)
            .then(|| self.values[idx[0] + nx * (idx[1] + ny * idx[2])])
    }

    /// Position of node `idx`.
    pub fn node_position(&self, idx: [usize; 3]) -> Vec3<f64> {
        self.origin + Vec3::new(idx[0] as f64, idx[1] as f64, idx[2] as f64) * self.cell
    }
}
