//! Step 1–2 of the paper (after van der Laan et al. 2009, §3.1 and §3.3): every particle is
//! drawn as a sphere (or, with anisotropy, an ellipsoid) into a **depth buffer** that keeps
//! the nearest surface and, additively, into a **thickness buffer**.
//!
//! Unlike a GPU point sprite, which writes `z_c − r √(1 − x² − y²)` of a screen-aligned
//! hemisphere, each pixel here intersects its own view ray with the particle's quadric
//! exactly: the depth is the view `z` of the entry point and the thickness the length of the
//! chord (m). For a sphere of centre `c` and radius `r` and the pixel ray `t d`
//! (`d = ((u − c_x)/f, (c_y − v)/f, 1)`), with `G = I/r`, and for an ellipsoid
//! `{c + M w : |w| ≤ 1}` with `G = M⁻¹` (view space): `q = G d`, `s = G c`,
//! `Δ = (q·s)² − |q|² (|s|² − 1)`; the ray hits when `Δ ≥ 0`, at depth
//! `z = (q·s − √Δ)/|q|²`, with chord `2 √Δ |d| / |q|²`.
//!
//! # Cost
//! Each particle touches the pixels of the screen box of its bounding box (the hull of the
//! projected corners, exact and conservative): for `N` spheres of radius `r` at depth `z`
//! seen with focal length `f` pixels, about `N (2 f r / z)²` pixel tests. The screen is cut
//! into bands of [`BAND_ROWS`] rows; particles are binned to the bands they overlap
//! (counting sort, `O(N)`), and the bands are drawn in parallel, each by one thread, in
//! particle order, so the result does not depend on the thread count. Particles whose box
//! reaches closer than [`NEAR_M`] to the camera plane are skipped.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use nalgebra::Matrix3;
use rayon::prelude::*;
use sph_core::{Real, Vec3};

use crate::camera::CameraFrame;
use crate::{SsfrError, V3};

/// Rows per band of the parallel splatting.
pub const BAND_ROWS: usize = 8;
/// Particles whose bounding box reaches closer than this to the camera plane (m) are not
/// drawn.
pub const NEAR_M: f32 = 1e-3;

/// The particles to draw: positions (m, any [`Real`]), a radius (m) for all or per particle,
/// and optionally one ellipsoid per particle.
#[derive(Debug, Clone, Copy)]
pub struct ParticleView<'a, R: Real> {
    /// Positions (m, world).
    pub positions: &'a [Vec3<R>],
    /// Radius of every particle (m, > 0), used where `radii` is `None`.
    pub radius: f32,
    /// Per-particle radii (m, > 0), overriding `radius`.
    pub radii: Option<&'a [R]>,
    /// Per-particle ellipsoids `{x_i + M_i w : |w| ≤ 1}` (world, m), overriding the radii:
    /// see [`crate::anisotropy`].
    pub ellipsoids: Option<&'a [Matrix3<f32>]>,
}

impl<'a, R: Real> ParticleView<'a, R> {
    /// Spheres of one radius.
    pub fn spheres(positions: &'a [Vec3<R>], radius: f32) -> Self {
        Self {
            positions,
            radius,
            radii: None,
            ellipsoids: None,
        }
    }

    /// Checks lengths, finiteness and radii.
    pub fn validate(&self) -> Result<(), SsfrError> {
        let n = self.positions.len();
        if let Some(r) = self.radii {
            if r.len() != n {
                return Err(SsfrError::LengthMismatch {
                    what: "radii",
                    found: r.len(),
                    expected: n,
                });
            }
            if let Some((index, x)) = r
                .iter()
                .enumerate()
                .find(|(_, x)| !(x.is_finite_value() && **x > R::zero()))
            {
                return Err(SsfrError::BadParticle {
                    index,
                    what: "radius",
                    value: x.as_f64(),
                });
            }
        } else if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(SsfrError::invalid(
                "particle_radius",
                format!("{}: must be finite and > 0", self.radius),
            ));
        }
        if let Some(e) = self.ellipsoids {
            if e.len() != n {
                return Err(SsfrError::LengthMismatch {
                    what: "ellipsoids",
                    found: e.len(),
                    expected: n,
                });
            }
            if let Some((index, m)) = e
                .iter()
                .enumerate()
                .find(|(_, m)| !m.iter().all(|x| x.is_finite()) || m.determinant() == 0.0)
            {
                return Err(SsfrError::BadParticle {
                    index,
                    what: "ellipsoid",
                    value: m.determinant() as f64,
                });
            }
        }
        for (index, p) in self.positions.iter().enumerate() {
            if let Some(k) = (0..3).find(|&k| !p[k].is_finite_value()) {
                return Err(SsfrError::BadParticle {
                    index,
                    what: "position",
                    value: p[k].as_f64(),
                });
            }
        }
        Ok(())
    }
}

/// One particle ready to draw: `s = G c`, `|s|² − 1` and its pixel box (an ellipsoid's `G`
/// is kept apart, [`Splatter`]'s `ellipsoid_g`, so that spheres move 36 bytes each).
#[derive(Debug, Clone, Copy)]
struct Prim {
    /// Ellipsoid: `G c`; sphere: the centre `c` (view).
    s: V3,
    /// Ellipsoid: `|G c|² − 1`; sphere: `|c|² − r²`.
    s2m1: f32,
    /// A sphere: the cheaper test `Δ = (d·c)² − |d|²(|c|² − r²)` applies.
    sphere: bool,
    /// Pixel box `[i0, i1) × [j0, j1)`; empty when not drawn.
    i0: u32,
    i1: u32,
    j0: u32,
    j1: u32,
}

/// The splat buffers: nearest depth (view `z`, m; `f32::INFINITY` where no particle) and
/// thickness (summed chord lengths, m), row major.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SplatBuffers {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// Nearest depth per pixel.
    pub depth: Vec<f32>,
    /// Thickness per pixel.
    pub thickness: Vec<f32>,
}

/// Per-pixel view rays `d = (a, b, 1)` of a camera, kept while the camera stays: `a` per
/// column, `b` per row, `|d|²` and `|d|` per pixel.
#[derive(Debug, Default)]
struct RayTables {
    camera: Option<CameraFrame>,
    a: Vec<f32>,
    b: Vec<f32>,
    dd: Vec<f32>,
    norm: Vec<f32>,
}

impl RayTables {
    fn update(&mut self, camera: &CameraFrame) {
        if self.camera.as_ref() == Some(camera) {
            return;
        }
        let (w, h) = (camera.width, camera.height);
        let inv_f = 1.0 / camera.focal_px;
        self.a.clear();
        self.a
            .extend((0..w).map(|i| (i as f32 + 0.5 - camera.cx) * inv_f));
        self.b.clear();
        self.b
            .extend((0..h).map(|j| (camera.cy - (j as f32 + 0.5)) * inv_f));
        self.dd.resize(w * h, 0.0);
        self.norm.resize(w * h, 0.0);
        let a = &self.a;
        let b = &self.b;
        self.dd
            .par_chunks_mut(w)
            .zip(self.norm.par_chunks_mut(w))
            .enumerate()
            .for_each(|(j, (dd, norm))| {
                let bb = b[j] * b[j] + 1.0;
                for ((dd, norm), a) in dd.iter_mut().zip(norm.iter_mut()).zip(a) {
                    *dd = a * a + bb;
                    *norm = dd.sqrt();
                }
            });
        self.camera = Some(*camera);
    }
}

/// One row of a sphere's box: `d = (a, b, 1)`, `Δ = (d·c)² − |d|²(|c|² − r²)`; where
/// `Δ ≥ 0`, the depth `z = (d·c − √Δ)/|d|²` enters the nearest-depth test and the chord
/// `2√Δ/|d|` is added to the thickness. Branch-free over the row (the compiler vectorises
/// it); the arithmetic per pixel is that of a per-pixel loop, so the result is too.
#[inline]
fn sphere_row(
    p: &Prim,
    b: f32,
    a: &[f32],
    dd: &[f32],
    norm: &[f32],
    depth: &mut [f32],
    thick: &mut [f32],
) {
    let c = p.s;
    let bc = b * c.y + c.z;
    let s2m1 = p.s2m1;
    let n = a.len();
    let (dd, norm, depth, thick) = (&dd[..n], &norm[..n], &mut depth[..n], &mut thick[..n]);
    for k in 0..n {
        let dc = a[k] * c.x + bc;
        let disc = dc * dc - dd[k] * s2m1;
        let hit = disc >= 0.0;
        let sq = if hit { disc } else { 0.0 }.sqrt();
        let z = (dc - sq) / dd[k];
        let zd = depth[k];
        depth[k] = if hit && z < zd { z } else { zd };
        thick[k] += if hit { 2.0 * sq / norm[k] } else { 0.0 };
    }
}

/// `⌈x⌉` clamped to `[0, hi]` (0 for NaN), by integer truncation: `f32::ceil` is a libm
/// call on the x86-64 baseline.
#[inline]
fn ceil_in(x: f32, hi: usize) -> u32 {
    let x = x.clamp(0.0, hi as f32);
    let t = x as u32;
    if (t as f32) < x {
        t + 1
    } else {
        t
    }
}

/// `⌊x⌋ + 1` clamped to `[0, hi]` (0 for NaN), by integer truncation.
#[inline]
fn floor_plus_one_in(x: f32, hi: usize) -> u32 {
    if x.is_nan() || x < 0.0 {
        0
    } else {
        (x.min(hi as f32) as u32 + 1).min(hi as u32)
    }
}

/// Scratch of the splatting (kept between frames: no allocation once grown).
#[derive(Debug, Default)]
pub struct Splatter {
    rays: RayTables,
    prims: Vec<Prim>,
    /// Per particle, an ellipsoid's `G = M⁻¹` (view space); empty for spheres.
    ellipsoid_g: Vec<Matrix3<f32>>,
    band_start: Vec<usize>,
    band_items: Vec<u32>,
    band_fill: Vec<usize>,
    /// Pixel tests done by the last call (the cost measure).
    pub pixel_tests: u64,
    /// Particles drawn by the last call (inside the view).
    pub drawn: usize,
    /// When set, [`Splatter::splat`] stops with [`SsfrError::Cancelled`] (checked per band
    /// of rows).
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Splatter {
    /// Draws `particles` seen by `camera` into `out` (resized and cleared). Returns the
    /// number of particles whose box meets the image; the caller decides whether none is an
    /// error ([`SsfrError::NothingVisible`] in [`crate::Renderer`]).
    pub fn splat<R: Real>(
        &mut self,
        camera: &CameraFrame,
        particles: &ParticleView<'_, R>,
        out: &mut SplatBuffers,
    ) -> Result<usize, SsfrError> {
        particles.validate()?;
        let (w, h) = (camera.width, camera.height);
        out.width = w;
        out.height = h;
        out.depth.clear();
        out.depth.resize(w * h, f32::INFINITY);
        out.thickness.clear();
        out.thickness.resize(w * h, 0.0);
        let rot = Matrix3::from_rows(&[
            camera.right.transpose(),
            camera.up.transpose(),
            camera.forward.transpose(),
        ]);
        let n = particles.positions.len();
        self.prims.clear();
        self.prims.resize(
            n,
            Prim {
                s: V3::zeros(),
                s2m1: 0.0,
                sphere: false,
                i0: 0,
                i1: 0,
                j0: 0,
                j1: 0,
            },
        );
        self.ellipsoid_g.clear();
        if let Some(e) = particles.ellipsoids {
            self.ellipsoid_g.resize(n, Matrix3::zeros());
            self.ellipsoid_g
                .par_iter_mut()
                .zip(e.par_iter())
                .for_each(|(g, m)| *g = (rot * m).try_inverse().unwrap_or_else(Matrix3::zeros));
        }
        let ellipsoid_g = &self.ellipsoid_g;
        self.prims.par_iter_mut().enumerate().for_each(|(k, prim)| {
            let p = &particles.positions[k];
            let pw = V3::new(
                p.x.as_f64() as f32,
                p.y.as_f64() as f32,
                p.z.as_f64() as f32,
            );
            let c = camera.to_view(&pw);
            let (ext, radius) = match particles.ellipsoids {
                Some(e) => {
                    let mv = rot * e[k];
                    let ext = V3::new(mv.row(0).norm(), mv.row(1).norm(), mv.row(2).norm());
                    (ext, None)
                }
                None => {
                    let r = particles
                        .radii
                        .map_or(particles.radius, |r| r[k].as_f64() as f32);
                    (V3::repeat(r), Some(r))
                }
            };
            let (s, s2m1) = match radius {
                Some(r) => (c, c.norm_squared() - r * r),
                None => {
                    let s = ellipsoid_g[k] * c;
                    (s, s.norm_squared() - 1.0)
                }
            };
            *prim = Prim {
                s,
                s2m1,
                sphere: radius.is_some(),
                i0: 0,
                i1: 0,
                j0: 0,
                j1: 0,
            };
            let z0 = c.z - ext.z;
            if z0 <= NEAR_M {
                return;
            }
            let z1 = c.z + ext.z;
            let f = camera.focal_px;
            let mut umin = f32::INFINITY;
            let mut umax = f32::NEG_INFINITY;
            let mut vmin = f32::INFINITY;
            let mut vmax = f32::NEG_INFINITY;
            for z in [z0, z1] {
                for sx in [-1.0, 1.0] {
                    let u = camera.cx + f * (c.x + sx * ext.x) / z;
                    umin = umin.min(u);
                    umax = umax.max(u);
                }
                for sy in [-1.0, 1.0] {
                    let v = camera.cy - f * (c.y + sy * ext.y) / z;
                    vmin = vmin.min(v);
                    vmax = vmax.max(v);
                }
            }
            // Pixel centres i + 1/2 in [umin, umax].
            let i0 = ceil_in(umin - 0.5, w);
            let i1 = floor_plus_one_in(umax - 0.5, w);
            let j0 = ceil_in(vmin - 0.5, h);
            let j1 = floor_plus_one_in(vmax - 0.5, h);
            if i0 < i1 && j0 < j1 {
                prim.i0 = i0;
                prim.i1 = i1;
                prim.j0 = j0;
                prim.j1 = j1;
            }
        });
        // Bin by band (counting sort, in particle order).
        let bands = h.div_ceil(BAND_ROWS);
        self.band_start.clear();
        self.band_start.resize(bands + 1, 0);
        let mut drawn = 0;
        for p in &self.prims {
            if p.j0 < p.j1 {
                drawn += 1;
                for b in p.j0 as usize / BAND_ROWS..=(p.j1 as usize - 1) / BAND_ROWS {
                    self.band_start[b + 1] += 1;
                }
            }
        }
        for b in 0..bands {
            self.band_start[b + 1] += self.band_start[b];
        }
        self.band_items.clear();
        self.band_items.resize(self.band_start[bands], 0);
        self.band_fill.clear();
        self.band_fill.extend_from_slice(&self.band_start);
        for (k, p) in self.prims.iter().enumerate() {
            if p.j0 < p.j1 {
                let bands = p.j0 as usize / BAND_ROWS..=(p.j1 as usize - 1) / BAND_ROWS;
                for slot in &mut self.band_fill[bands] {
                    self.band_items[*slot] = k as u32;
                    *slot += 1;
                }
            }
        }
        let prims = &self.prims;
        let band_start = &self.band_start;
        let band_items = &self.band_items;
        self.rays.update(camera);
        let rays = &self.rays;
        let cancel = self.cancel.as_deref();
        let cancelled = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
        let tests: u64 = out
            .depth
            .par_chunks_mut(w * BAND_ROWS)
            .zip(out.thickness.par_chunks_mut(w * BAND_ROWS))
            .enumerate()
            .map(|(b, (depth, thick))| {
                if cancelled() {
                    return 0;
                }
                let row0 = b * BAND_ROWS;
                let rows = depth.len() / w;
                let mut tests = 0u64;
                for &k in &band_items[band_start[b]..band_start[b + 1]] {
                    let p = &prims[k as usize];
                    let j0 = (p.j0 as usize).max(row0);
                    let j1 = (p.j1 as usize).min(row0 + rows);
                    tests += ((j1 - j0) * (p.i1 - p.i0) as usize) as u64;
                    if p.sphere {
                        let (i0, i1) = (p.i0 as usize, p.i1 as usize);
                        for j in j0..j1 {
                            let off = (j - row0) * w;
                            let ray_off = j * w;
                            sphere_row(
                                p,
                                rays.b[j],
                                &rays.a[i0..i1],
                                &rays.dd[ray_off + i0..ray_off + i1],
                                &rays.norm[ray_off + i0..ray_off + i1],
                                &mut depth[off + i0..off + i1],
                                &mut thick[off + i0..off + i1],
                            );
                        }
                        continue;
                    }
                    let g = &ellipsoid_g[k as usize];
                    let (g0, g1, g2) = (g.column(0), g.column(1), g.column(2));
                    for j in j0..j1 {
                        let bv = (camera.cy - (j as f32 + 0.5)) / camera.focal_px;
                        let qrow = g1 * bv + g2;
                        let off = (j - row0) * w;
                        for i in p.i0 as usize..p.i1 as usize {
                            let a = (i as f32 + 0.5 - camera.cx) / camera.focal_px;
                            let q = g0 * a + qrow;
                            let qs = q.dot(&p.s);
                            let qq = q.norm_squared();
                            let disc = qs * qs - qq * p.s2m1;
                            if disc >= 0.0 {
                                let sq = disc.sqrt();
                                let z = (qs - sq) / qq;
                                let px = off + i;
                                if z < depth[px] {
                                    depth[px] = z;
                                }
                                thick[px] += 2.0 * sq * (a * a + bv * bv + 1.0).sqrt() / qq;
                            }
                        }
                    }
                }
                tests
            })
            .sum();
        if cancelled() {
            return Err(SsfrError::Cancelled);
        }
        self.pixel_tests = tests;
        self.drawn = drawn;
        Ok(drawn)
    }
}

/// The naive oracle of [`Splatter::splat`] for spheres: every pixel against every particle,
/// in f64 (tests and benchmarks only).
pub fn splat_spheres_naive(
    camera: &CameraFrame,
    centres: &[V3],
    radius: f32,
) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (camera.width, camera.height);
    let mut depth = vec![f32::INFINITY; w * h];
    let mut thick = vec![0.0f32; w * h];
    for p in centres {
        let c = camera.to_view(p).cast::<f64>();
        if c.z - radius as f64 <= NEAR_M as f64 {
            continue;
        }
        for j in 0..h {
            for i in 0..w {
                let d = camera.ray(i as f32 + 0.5, j as f32 + 0.5).cast::<f64>();
                let r = radius as f64;
                let dc = d.dot(&c);
                let dd = d.norm_squared();
                let disc = dc * dc - dd * (c.norm_squared() - r * r);
                if disc >= 0.0 {
                    let z = ((dc - disc.sqrt()) / dd) as f32;
                    let k = j * w + i;
                    depth[k] = depth[k].min(z);
                    thick[k] += (2.0 * disc.sqrt() / dd.sqrt()) as f32;
                }
            }
        }
    }
    (depth, thick)
}
