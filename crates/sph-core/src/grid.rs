//! [`SampledGrid`]: a scalar field sampled on a regular grid of nodes and interpolated
//! trilinearly (value and analytic gradient). The node storage behind
//! [`GridSdf`](crate::GridSdf), reusable for any field given by a function or by node values.

use rayon::prelude::*;

use crate::{Aabb, CoreError, Real, Vec3};

/// A scalar field sampled on the nodes of a regular grid and interpolated trilinearly.
///
/// Conventions:
///
/// * Node `(i, j, k)` lies at `origin + (i, j, k) · cell` (length unit of the scene); there are
///   `dims = [nx, ny, nz]` nodes along x, y, z, at least 2 along each axis, at most
///   [`SampledGrid::MAX_NODES`] in all.
/// * Node values are stored in precision `R`, x fastest, then y, then z: node `(i, j, k)` is
///   `values[i + nx · (j + ny · k)]` ([`SampledGrid::values`]). They are not checked: a NaN
///   node value makes the samples of its cells NaN.
/// * Sampling is done in `f64`: the trilinear interpolant of the 8 nodes of the cell holding
///   the point and its analytic gradient, per length unit (on a face shared by two cells the
///   cell above is used, except at the upper end of the grid).
/// * The grid box ([`SampledGrid::grid_box`]) is the closed box spanned by the nodes;
///   [`SampledGrid::sample`] is `None` outside it, [`SampledGrid::sample_clamped`] samples
///   the nearest point of the box and returns the offset to it.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledGrid<R: Real> {
    origin: Vec3<f64>,
    cell: f64,
    dims: [usize; 3],
    values: Vec<R>,
}

fn check_cell(cell: f64) -> Result<(), CoreError> {
    if cell.is_finite() && cell > 0.0 {
        Ok(())
    } else {
        Err(CoreError::InvalidParameter {
            name: "grid cell size",
            value: cell,
            reason: "must be finite and > 0",
        })
    }
}

fn check_point(name: &'static str, p: &Vec3<f64>) -> Result<(), CoreError> {
    match (0..3).find(|&a| !p[a].is_finite()) {
        Some(a) => Err(CoreError::InvalidParameter {
            name,
            value: p[a],
            reason: "components must be finite",
        }),
        None => Ok(()),
    }
}

impl<R: Real> SampledGrid<R> {
    /// Largest number of nodes a grid may have (64 Mi nodes, 256 MiB of `f32` values).
    pub const MAX_NODES: usize = 1 << 26;

    /// Node counts `[nx, ny, nz]` (each ≥ 2) of the grid with origin `min` and node spacing
    /// `cell` (length, finite and > 0) whose nodes cover the box `[min, max]`: the smallest
    /// counts with `min + (n − 1) · cell ≥ max` on every axis (as computed in `f64`).
    ///
    /// Errors: [`CoreError::InvalidParameter`] for a non-finite or non-positive `cell`, a
    /// non-finite corner or `max < min` on an axis; [`CoreError::GridTooLarge`] for more than
    /// [`SampledGrid::MAX_NODES`] nodes.
    pub fn covering(min: Vec3<f64>, max: Vec3<f64>, cell: f64) -> Result<[usize; 3], CoreError> {
        check_cell(cell)?;
        check_point("grid min", &min)?;
        check_point("grid max", &max)?;
        let mut counts = [0f64; 3];
        for a in 0..3 {
            if max[a] < min[a] {
                return Err(CoreError::InvalidParameter {
                    name: ["grid max x", "grid max y", "grid max z"][a],
                    value: max[a],
                    reason: "must be >= the grid min on the same axis",
                });
            }
            let mut n = ((max[a] - min[a]) / cell).ceil() + 1.0;
            // Rounding of the quotient may leave the last node just short of `max`.
            if n.is_finite() && n <= Self::MAX_NODES as f64 && min[a] + (n - 1.0) * cell < max[a] {
                n += 1.0;
            }
            counts[a] = n.max(2.0);
        }
        let total = counts[0] * counts[1] * counts[2];
        // `as usize` saturates: counts beyond usize are reported as usize::MAX.
        let dims = counts.map(|n| n as usize);
        if total > Self::MAX_NODES as f64 {
            return Err(CoreError::GridTooLarge {
                nx: dims[0],
                ny: dims[1],
                nz: dims[2],
                max: Self::MAX_NODES,
            });
        }
        Ok(dims)
    }

    /// Checks the arguments shared by the constructors; returns the number of nodes.
    fn check_layout(origin: &Vec3<f64>, cell: f64, dims: [usize; 3]) -> Result<usize, CoreError> {
        check_cell(cell)?;
        check_point("grid origin", origin)?;
        for (a, &n) in dims.iter().enumerate() {
            if n < 2 {
                return Err(CoreError::InvalidParameter {
                    name: [
                        "grid nodes along x",
                        "grid nodes along y",
                        "grid nodes along z",
                    ][a],
                    value: n as f64,
                    reason: "a grid needs at least 2 nodes along each axis",
                });
            }
        }
        let total = dims[0]
            .checked_mul(dims[1])
            .and_then(|t| t.checked_mul(dims[2]))
            .filter(|&t| t <= Self::MAX_NODES);
        let Some(total) = total else {
            return Err(CoreError::GridTooLarge {
                nx: dims[0],
                ny: dims[1],
                nz: dims[2],
                max: Self::MAX_NODES,
            });
        };
        let last = Vec3::new(
            (dims[0] - 1) as f64,
            (dims[1] - 1) as f64,
            (dims[2] - 1) as f64,
        );
        check_point(
            "grid far corner (origin + (dims - 1) · cell)",
            &(origin + last * cell),
        )?;
        Ok(total)
    }

    /// A grid whose value at node `(i, j, k)` is `f([i, j, k], position)`, rounded to `R`
    /// ([`Real::of_f64`]). The nodes are evaluated in parallel (rayon) in no particular order;
    /// the result is deterministic as long as each value depends only on its arguments.
    ///
    /// Errors: [`CoreError::InvalidParameter`] for a non-finite origin, a non-finite or
    /// non-positive `cell`, fewer than 2 nodes along an axis or a non-finite last node;
    /// [`CoreError::GridTooLarge`] for more than [`SampledGrid::MAX_NODES`] nodes (checked
    /// before `f` is called).
    pub fn from_fn(
        origin: Vec3<f64>,
        cell: f64,
        dims: [usize; 3],
        f: impl Fn([usize; 3], Vec3<f64>) -> f64 + Sync,
    ) -> Result<Self, CoreError> {
        let total = Self::check_layout(&origin, cell, dims)?;
        let [nx, ny, _] = dims;
        let mut grid = Self {
            origin,
            cell,
            dims,
            values: vec![R::zero(); total],
        };
        let node =
            |i: usize, j: usize, k: usize| origin + Vec3::new(i as f64, j as f64, k as f64) * cell;
        grid.values
            .par_chunks_mut(nx)
            .enumerate()
            .for_each(|(row, out)| {
                let (j, k) = (row % ny, row / ny);
                for (i, v) in out.iter_mut().enumerate() {
                    *v = R::of_f64(f([i, j, k], node(i, j, k)));
                }
            });
        Ok(grid)
    }

    /// A grid from its node values (layout as in [`SampledGrid::values`]).
    ///
    /// Errors: those of [`SampledGrid::from_fn`], and [`CoreError::LengthMismatch`] when
    /// `values.len()` is not `nx · ny · nz`.
    pub fn from_values(
        origin: Vec3<f64>,
        cell: f64,
        dims: [usize; 3],
        values: Vec<R>,
    ) -> Result<Self, CoreError> {
        let total = Self::check_layout(&origin, cell, dims)?;
        if values.len() != total {
            return Err(CoreError::LengthMismatch {
                what: "grid node values",
                found: values.len(),
                expected: total,
            });
        }
        Ok(Self {
            origin,
            cell,
            dims,
            values,
        })
    }

    /// A grid from parts already checked by the caller (`dims ≥ 2`, `cell > 0`, lengths).
    pub(crate) fn from_checked_parts(
        origin: Vec3<f64>,
        cell: f64,
        dims: [usize; 3],
        values: Vec<R>,
    ) -> Self {
        debug_assert!(dims.iter().all(|&n| n >= 2));
        debug_assert_eq!(values.len(), dims[0] * dims[1] * dims[2]);
        Self {
            origin,
            cell,
            dims,
            values,
        }
    }

    /// Node spacing (length).
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// Number of nodes along x, y, z (each ≥ 2).
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Position of node `(0, 0, 0)`, the lower corner of the grid box.
    pub fn origin(&self) -> Vec3<f64> {
        self.origin
    }

    /// The closed box spanned by the nodes, from the origin to node `dims − 1`, rounded to `R`.
    pub fn grid_box(&self) -> Aabb<R> {
        let hi = self.origin
            + Vec3::new(
                (self.dims[0] - 1) as f64,
                (self.dims[1] - 1) as f64,
                (self.dims[2] - 1) as f64,
            ) * self.cell;
        Aabb {
            min: Vec3::new(
                R::of_f64(self.origin.x),
                R::of_f64(self.origin.y),
                R::of_f64(self.origin.z),
            ),
            max: Vec3::new(R::of_f64(hi.x), R::of_f64(hi.y), R::of_f64(hi.z)),
        }
    }

    /// Stored value at node `(i, j, k)` (`None` out of range).
    pub fn node_value(&self, i: usize, j: usize, k: usize) -> Option<R> {
        let [nx, ny, nz] = self.dims;
        (i < nx && j < ny && k < nz).then(|| self.values[i + nx * (j + ny * k)])
    }

    /// Position `origin + (i, j, k) · cell` of node `(i, j, k)` (not range-checked: indices
    /// past the last node extend the lattice).
    pub fn node_position(&self, i: usize, j: usize, k: usize) -> Vec3<f64> {
        self.origin + Vec3::new(i as f64, j as f64, k as f64) * self.cell
    }

    /// All node values, x fastest, then y, then z (node `(i, j, k)` at
    /// `i + nx · (j + ny · k)`).
    pub fn values(&self) -> &[R] {
        &self.values
    }

    /// The trilinear value and gradient (per length) at `p` clamped into the grid box, and the
    /// offset `p − q` from the clamped point `q` to `p` (exactly zero on axes where `p` is
    /// inside the box). Along clamped axes the gradient is that of the interpolant at `q`.
    /// A NaN component is treated as the lower face of the box on that axis (zero offset);
    /// an infinite one gives an infinite offset.
    #[inline]
    pub fn sample_clamped(&self, p: &Vec3<R>) -> (f64, Vec3<f64>, Vec3<f64>) {
        let (u, off) = self.locate(p);
        let (v, g) = self.trilinear(u);
        (v, g, off)
    }

    /// The trilinear value and gradient (per length) at `p`, or `None` when `p` is outside
    /// the closed grid box `[origin, origin + (dims − 1) · cell]` (evaluated in `f64`) or has
    /// a non-finite component.
    #[inline]
    pub fn sample(&self, p: &Vec3<R>) -> Option<(f64, Vec3<f64>)> {
        let mut u = [0.0; 3];
        for a in 0..3 {
            let x = p[a].as_f64();
            let top = (self.dims[a] - 1) as f64;
            // The same bounds as `grid_box` (in f64), so its corners are inside.
            if !(x >= self.origin[a] && x <= self.origin[a] + top * self.cell) {
                return None;
            }
            u[a] = ((x - self.origin[a]) / self.cell).clamp(0.0, top);
        }
        Some(self.trilinear(u))
    }

    /// Clamps `p` into the grid box: returns grid coordinates (in cells) of the clamped
    /// point and the offset `p − q` in length units.
    #[inline]
    fn locate(&self, p: &Vec3<R>) -> ([f64; 3], Vec3<f64>) {
        let mut u = [0.0; 3];
        let mut off = Vec3::zeros();
        for a in 0..3 {
            let x = p[a].as_f64();
            let g = (x - self.origin[a]) / self.cell;
            let max = (self.dims[a] - 1) as f64;
            // Offsets only on clamped axes (exactly 0 inside the box, whatever the rounding).
            if g < 0.0 {
                off[a] = x - self.origin[a];
                u[a] = 0.0;
            } else if g > max {
                off[a] = x - (self.origin[a] + max * self.cell);
                u[a] = max;
            } else if g.is_nan() {
                u[a] = 0.0;
            } else {
                u[a] = g;
            }
        }
        (u, off)
    }

    /// Trilinear value and gradient (per length) at grid coordinates `u` (inside the box).
    #[inline]
    fn trilinear(&self, u: [f64; 3]) -> (f64, Vec3<f64>) {
        let [nx, ny, _] = self.dims;
        let mut base = [0usize; 3];
        let mut f = [0.0; 3];
        for a in 0..3 {
            let i = (u[a].floor() as usize).min(self.dims[a] - 2);
            base[a] = i;
            f[a] = u[a] - i as f64;
        }
        let idx = |i: usize, j: usize, k: usize| {
            self.values[(base[0] + i) + nx * ((base[1] + j) + ny * (base[2] + k))].as_f64()
        };
        let c000 = idx(0, 0, 0);
        let c100 = idx(1, 0, 0);
        let c010 = idx(0, 1, 0);
        let c110 = idx(1, 1, 0);
        let c001 = idx(0, 0, 1);
        let c101 = idx(1, 0, 1);
        let c011 = idx(0, 1, 1);
        let c111 = idx(1, 1, 1);
        let [fx, fy, fz] = f;
        let c00 = c000 + (c100 - c000) * fx;
        let c10 = c010 + (c110 - c010) * fx;
        let c01 = c001 + (c101 - c001) * fx;
        let c11 = c011 + (c111 - c011) * fx;
        let c0 = c00 + (c10 - c00) * fy;
        let c1 = c01 + (c11 - c01) * fy;
        let value = c0 + (c1 - c0) * fz;
        // d/dfx
        let dx0 = (c100 - c000) + ((c110 - c010) - (c100 - c000)) * fy;
        let dx1 = (c101 - c001) + ((c111 - c011) - (c101 - c001)) * fy;
        let gx = dx0 + (dx1 - dx0) * fz;
        let gy = (c10 - c00) + ((c11 - c01) - (c10 - c00)) * fz;
        let gz = c1 - c0;
        (value, Vec3::new(gx, gy, gz) / self.cell)
    }
}
