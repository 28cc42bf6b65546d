//! The screen-space march of the improved refraction ([`crate::RefractDistance::SceneDepth`]):
//! where the refracted view ray first passes behind the scene buffer's depth.
//!
//! The scene depth is a height field of constant value over each pixel (the value
//! [`SceneBuffer::depth_at`] reads). The ray `q(s) = P + s R` (view space) is clipped to the
//! image, to `z > `[`NEAR_Z_M`] and to the scene's largest finite depth; its two ends are
//! projected, and between them the screen point moves linearly in a parameter `α ∈ [0, 1]`
//! along which `1/z` is linear too (perspective-correct interpolation). The pixels the
//! screen segment crosses are visited in order (Amanatides & Woo's grid traversal); in a
//! pixel of depth `D` the ray's depth is monotonic, so the first `α` with `z(α) ≥ D` is
//! either where the ray enters the pixel or the root of `1/z(α) = 1/D`, in closed form. The
//! result is the first crossing of the ray with the depth height field, exactly (up to f32
//! rounding): a fixed-step march with bisection converges to it as its step shrinks, and
//! misses scene features thinner than its step, which this traversal does not.
//!
//! To skip the stretches where the ray is plainly in front of the scene, [`DepthTiles`]
//! keeps a pyramid of the nearest depth over squares of 1, 4, 16, 64, 256 pixels
//! ([`TILE_FACTOR`]); the traversal walks the coarsest squares and descends into a square
//! only where the ray's largest depth inside it reaches the square's nearest depth
//! (hierarchical-Z tracing).
//!
//! Cost per liquid pixel: the coarse squares its refracted ray's screen path crosses plus
//! `2 × `[`TILE_FACTOR`] cells per level inside each square the ray comes close to the scene
//! in, down to the pixels around the crossing: `O(L / 256 + 8 log₄ L)` cells for a path of
//! `L` pixels over a smooth scene (a fixed-step march takes `L / step` samples, each a
//! projection and a depth read). Building the pyramid is one pass over the pixels, once per
//! background.
//!
//! Grid traversal: J. Amanatides and A. Woo, *A fast voxel traversal algorithm for ray
//! tracing*, Eurographics '87, pp. 3–10, 1987.

use crate::background::SceneBuffer;
use crate::camera::CameraFrame;
use crate::V3;

/// Side ratio of two levels of the [`DepthTiles`] pyramid.
pub const TILE_FACTOR: usize = 4;

/// Levels of the [`DepthTiles`] pyramid (pixels, then squares of 4, 16, 64, 256 pixels).
const LEVELS: usize = 5;

/// The nearest view depth the march follows a ray to (m); closer, the ray has left the
/// view frustum towards the camera.
pub const NEAR_Z_M: f32 = 1e-4;

/// One level of the pyramid: squares of `cell_px` pixels, `1 / (nearest depth)` in each
/// (0 for sky).
#[derive(Debug, Clone, Default, PartialEq)]
struct Level {
    cell_px: usize,
    nx: usize,
    ny: usize,
    inv_depth: Vec<f32>,
}

/// The scene depth as a pyramid of nearest depths (stored as `1/z`) over squares of 1, 4,
/// 16, 64 and 256 pixels, and the largest finite depth of the scene: what the march needs.
/// Built from a [`SceneBuffer`] by [`DepthTiles::build`] (the [`crate::Renderer`] does it
/// each time it renders the background).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DepthTiles {
    width: usize,
    height: usize,
    levels: Vec<Level>,
    max_depth: f32,
}

impl DepthTiles {
    /// Fills `self` (buffers reused) from `scene`'s depth. Cost: one pass over the pixels
    /// and `1/16` of that per coarser level.
    pub fn build(&mut self, scene: &SceneBuffer) {
        let (w, h) = (scene.width, scene.height);
        self.width = w;
        self.height = h;
        self.levels.resize(LEVELS, Level::default());
        let base = &mut self.levels[0];
        base.cell_px = 1;
        base.nx = w;
        base.ny = h;
        base.inv_depth.clear();
        base.inv_depth.extend(scene.depth.iter().map(|&z| 1.0 / z));
        self.max_depth = scene
            .depth
            .iter()
            .copied()
            .filter(|z| z.is_finite())
            .fold(0.0, f32::max);
        for l in 1..LEVELS {
            let (fine, coarse) = self.levels.split_at_mut(l);
            let (fine, coarse) = (&fine[l - 1], &mut coarse[0]);
            coarse.cell_px = fine.cell_px * TILE_FACTOR;
            coarse.nx = fine.nx.div_ceil(TILE_FACTOR);
            coarse.ny = fine.ny.div_ceil(TILE_FACTOR);
            coarse.inv_depth.clear();
            coarse.inv_depth.resize(coarse.nx * coarse.ny, 0.0);
            for (j, row) in fine.inv_depth.chunks(fine.nx.max(1)).enumerate() {
                let out = &mut coarse.inv_depth[(j / TILE_FACTOR) * coarse.nx..];
                for (i, &x) in row.iter().enumerate() {
                    let c = &mut out[i / TILE_FACTOR];
                    *c = c.max(x);
                }
            }
        }
    }

    /// Whether these tiles were built for an image of `width` × `height`.
    pub fn fits(&self, width: usize, height: usize) -> bool {
        self.width == width
            && self.height == height
            && self.levels.len() == LEVELS
            && self.levels[0].inv_depth.len() == width * height
    }

    /// Largest finite depth of the scene (m; 0 when the scene is all sky).
    pub fn max_depth(&self) -> f32 {
        self.max_depth
    }
}

/// The largest `s ≥ 0` with `g0 + s g1 ≥ 0` for all constraints, capped by `s_max`; `None`
/// when `s = 0` already violates one.
fn clip(constraints: &[(f32, f32)], s_max: f32) -> Option<f32> {
    let mut s = s_max;
    for &(g0, g1) in constraints {
        if g0.is_nan() || g0 < 0.0 {
            return None;
        }
        if g1 < 0.0 {
            s = s.min(-g0 / g1);
        }
    }
    Some(s)
}

/// Pixel coordinates where the view ray `p + s r` (`s ≥ 0`) first passes behind the scene
/// depth (`z ≥` the pixel's depth), or, when it never does, where it leaves the image, the
/// near plane or the scene's depth range; `p` projected when it starts outside them. See
/// the module docs.
pub fn march(camera: &CameraFrame, tiles: &DepthTiles, p: &V3, r: &V3) -> (f32, f32) {
    let (w, h) = (camera.width as f32, camera.height as f32);
    let (f, cx, cy) = (camera.focal_px, camera.cx, camera.cy);
    let start = camera.project(p);
    // Constraints g0 + s g1 ≥ 0: near plane, depth range, and u ∈ [0, w], v ∈ [0, h]
    // multiplied by z > 0 (linear in the point, so g1 is the same form of r).
    let image = |q: &V3| {
        [
            f * q.x + cx * q.z,
            (w - cx) * q.z - f * q.x,
            cy * q.z - f * q.y,
            f * q.y + (h - cy) * q.z,
        ]
    };
    let (gp, gr) = (image(p), image(r));
    let constraints = [
        (p.z - NEAR_Z_M, r.z),
        (tiles.max_depth - p.z, -r.z),
        (gp[0], gr[0]),
        (gp[1], gr[1]),
        (gp[2], gr[2]),
        (gp[3], gr[3]),
    ];
    // Any ray leaves the frustum within a few times the depth range (its screen speed
    // is at least its lateral speed over the far depth); the cap only guards rounding.
    let Some(s_end) = clip(&constraints, 1e3 * (tiles.max_depth + p.z.abs() + 1.0)) else {
        return start;
    };
    let q1 = p + r * s_end;
    if s_end.is_nan() || s_end <= 0.0 || q1.z < NEAR_Z_M {
        return start;
    }
    let end = camera.project(&q1);
    let delta = (end.0 - start.0, end.1 - start.1);
    let ray = ScreenRay {
        start,
        delta,
        inv_delta: (1.0 / delta.0, 1.0 / delta.1),
        iz0: 1.0 / p.z,
        iz1: 1.0 / q1.z,
    };
    let top = LEVELS - 1;
    let lv = &tiles.levels[top];
    let hit = ray.traverse(
        (0.0, 1.0),
        lv.cell_px,
        (0, 0),
        (lv.nx - 1, lv.ny - 1),
        |i, j, a, b| ray.visit(tiles, top, i, j, a, b),
    );
    hit.unwrap_or(end)
}

/// Margin (pixels) that keeps a crossing inside its pixel, see [`in_pixel`].
const PIXEL_MARGIN: f32 = 1.0 / 256.0;

/// Coordinate `x` moved inside pixel `i`, [`PIXEL_MARGIN`] from its edges: a crossing where
/// the ray enters a pixel behind a depth step lies on the pixel's edge, and rounding must
/// not hand the sample (and the depth read there) to the neighbour it came from.
#[inline]
fn in_pixel(x: f32, i: usize) -> f32 {
    x.clamp(i as f32 + PIXEL_MARGIN, (i + 1) as f32 - PIXEL_MARGIN)
}

/// The clipped ray on the screen: `start + α delta`, `1/z` from `iz0` to `iz1`.
struct ScreenRay {
    start: (f32, f32),
    delta: (f32, f32),
    /// `1 / delta` per axis (infinite for 0).
    inv_delta: (f32, f32),
    iz0: f32,
    iz1: f32,
}

impl ScreenRay {
    /// Visits, in order, the cells of side `cell_px` (a power of 2, so that dividing by
    /// it is exact as a product) that the segment crosses for `α ∈ [a0, a1]`, with the `α`
    /// interval inside each; the cell indices are clamped to `[lo, hi]` (inclusive, per
    /// axis). Stops at the first `Some` of `visit` and returns it.
    #[inline]
    fn traverse<T>(
        &self,
        (a0, a1): (f32, f32),
        cell_px: usize,
        lo: (usize, usize),
        hi: (usize, usize),
        mut visit: impl FnMut(usize, usize, f32, f32) -> Option<T>,
    ) -> Option<T> {
        let ((u0, v0), (du, dv)) = (self.start, self.delta);
        let (cell, inv_cell) = (cell_px as f32, 1.0 / cell_px as f32);
        // Truncation is the floor for x ≥ 0 (a float-to-int cast, not a libm call).
        let cell_of =
            |x: f32, lo: usize, hi: usize| ((x * inv_cell).max(0.0) as usize).clamp(lo, hi);
        let mut ci = cell_of(u0 + a0 * du, lo.0, hi.0);
        let mut cj = cell_of(v0 + a0 * dv, lo.1, hi.1);
        // α where the segment leaves cell `c` along an axis.
        let exit = |c: usize, x0: f32, d: f32, inv_d: f32| {
            if d > 0.0 {
                ((c + 1) as f32 * cell - x0) * inv_d
            } else if d < 0.0 {
                (c as f32 * cell - x0) * inv_d
            } else {
                f32::INFINITY
            }
        };
        let mut a = a0;
        loop {
            let ei = exit(ci, u0, du, self.inv_delta.0);
            let ej = exit(cj, v0, dv, self.inv_delta.1);
            let b = ei.min(ej).min(a1).max(a);
            if let Some(x) = visit(ci, cj, a, b) {
                return Some(x);
            }
            if b >= a1 {
                return None;
            }
            if ei <= ej {
                if du > 0.0 && ci < hi.0 {
                    ci += 1;
                } else if du < 0.0 && ci > lo.0 {
                    ci -= 1;
                } else {
                    return None;
                }
            } else if dv > 0.0 && cj < hi.1 {
                cj += 1;
            } else if dv < 0.0 && cj > lo.1 {
                cj -= 1;
            } else {
                return None;
            }
            a = b;
        }
    }

    /// The first `α` in `[a, b]` where `1/z(α) ≤ inv_depth` (the ray at or behind depth
    /// `1/inv_depth`), if any; `1/z` is linear in `α`, so its smallest value on `[a, b]`
    /// is at an end.
    #[inline]
    fn crossing(&self, inv_depth: f32, a: f32, b: f32) -> Option<f32> {
        let d = self.iz1 - self.iz0;
        if self.iz0 + a * d <= inv_depth {
            Some(a)
        } else if self.iz0 + b * d <= inv_depth {
            Some(((self.iz0 - inv_depth) / (self.iz0 - self.iz1)).clamp(a, b))
        } else {
            None
        }
    }

    /// The first crossing inside cell `(i, j)` of `level`, where the ray spends `[a, b]`.
    fn visit(
        &self,
        tiles: &DepthTiles,
        level: usize,
        i: usize,
        j: usize,
        a: f32,
        b: f32,
    ) -> Option<(f32, f32)> {
        let lv = &tiles.levels[level];
        let first = self.crossing(lv.inv_depth[j * lv.nx + i], a, b)?;
        if level == 0 {
            let (u, v) = (
                self.start.0 + first * self.delta.0,
                self.start.1 + first * self.delta.1,
            );
            return Some((in_pixel(u, i), in_pixel(v, j)));
        }
        let fine = &tiles.levels[level - 1];
        let lo = (i * TILE_FACTOR, j * TILE_FACTOR);
        let hi = (
            (lo.0 + TILE_FACTOR).min(fine.nx) - 1,
            (lo.1 + TILE_FACTOR).min(fine.ny) - 1,
        );
        // The ray is in front of every cell of this one before `first`.
        self.traverse((first, b), fine.cell_px, lo, hi, |i, j, a, b| {
            self.visit(tiles, level - 1, i, j, a, b)
        })
    }
}

/// The naive oracle of [`march`] (tests only): in f64, the ray clipped as in [`march`], then
/// every pixel of the image intersected with its screen segment (slabs) and the earliest
/// crossing over all of them kept. Cost: one pass over the pixels per ray.
pub fn march_naive(camera: &CameraFrame, scene: &SceneBuffer, p: &V3, r: &V3) -> (f32, f32) {
    let (p, r) = (p.cast::<f64>(), r.cast::<f64>());
    let (w, h) = (camera.width as f64, camera.height as f64);
    let (f, cx, cy) = (camera.focal_px as f64, camera.cx as f64, camera.cy as f64);
    let project = |q: &nalgebra::Vector3<f64>| (cx + f * q.x / q.z, cy - f * q.y / q.z);
    let max_depth = scene
        .depth
        .iter()
        .filter(|z| z.is_finite())
        .fold(0.0f64, |m, &z| m.max(z as f64));
    let start = project(&p);
    let out = |(u, v): (f64, f64)| (u as f32, v as f32);
    // The frustum and depth range as half-spaces n·q + c ≥ 0.
    let planes: [(nalgebra::Vector3<f64>, f64); 6] = [
        (nalgebra::Vector3::z(), -(NEAR_Z_M as f64)),
        (-nalgebra::Vector3::z(), max_depth),
        (nalgebra::Vector3::new(f, 0.0, cx), 0.0),
        (nalgebra::Vector3::new(-f, 0.0, w - cx), 0.0),
        (nalgebra::Vector3::new(0.0, -f, cy), 0.0),
        (nalgebra::Vector3::new(0.0, f, h - cy), 0.0),
    ];
    let mut s_end = 1e3 * (max_depth + p.z.abs() + 1.0);
    for (n, c) in planes {
        let (g0, g1) = (n.dot(&p) + c, n.dot(&r));
        if g0 < 0.0 {
            return out(start);
        }
        if g1 < 0.0 {
            s_end = s_end.min(-g0 / g1);
        }
    }
    let q1 = p + r * s_end;
    if s_end <= 0.0 || q1.z < NEAR_Z_M as f64 {
        return out(start);
    }
    let end = project(&q1);
    let (du, dv) = (end.0 - start.0, end.1 - start.1);
    let (iz0, iz1) = (1.0 / p.z, 1.0 / q1.z);
    // α interval of the segment inside [x0, x0 + 1) along one axis.
    let slab = |x: f64, d: f64, x0: f64| -> (f64, f64) {
        if d == 0.0 {
            if x >= x0 && x <= x0 + 1.0 {
                (0.0, 1.0)
            } else {
                (1.0, 0.0)
            }
        } else {
            let (a, b) = ((x0 - x) / d, (x0 + 1.0 - x) / d);
            (a.min(b).max(0.0), a.max(b).min(1.0))
        }
    };
    let mut best = f64::INFINITY;
    let mut best_px = (0, 0);
    for j in 0..scene.height {
        let (ja, jb) = slab(start.1, dv, j as f64);
        if ja > jb {
            continue;
        }
        for i in 0..scene.width {
            let (ia, ib) = slab(start.0, du, i as f64);
            let (a, b) = (ia.max(ja), ib.min(jb));
            let depth = scene.depth[j * scene.width + i] as f64;
            if a > b || a >= best || !depth.is_finite() {
                continue;
            }
            let id = 1.0 / depth;
            let iz = |t: f64| iz0 + t * (iz1 - iz0);
            let hit = if iz(a) <= id {
                a
            } else if iz(b) <= id {
                (iz0 - id) / (iz0 - iz1)
            } else {
                continue;
            };
            if hit < best {
                best = hit;
                best_px = (i, j);
            }
        }
    }
    if best.is_finite() {
        let (u, v) = out((start.0 + best * du, start.1 + best * dv));
        (in_pixel(u, best_px.0), in_pixel(v, best_px.1))
    } else {
        out(end)
    }
}
