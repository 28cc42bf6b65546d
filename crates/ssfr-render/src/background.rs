//! The scene behind the liquid, rendered first into colour and depth (the paper's "the whole
//! scene means the non-fluid rendered result (such as ground floor and background objects).
//! They should be rendered before the SSFR, and then can be used as a scene (2D) texture in
//! the final step"): a checkered ground plane, the tank's inner walls seen in cut-away (the
//! walls facing the camera are not drawn), box and sphere obstacles and a sky gradient.
//!
//! Every pixel casts one exact ray (analytic intersections), so the scene depth is exact:
//! the refraction experiment compares against it.

use rayon::prelude::*;

use crate::camera::CameraFrame;
use crate::error::{finite3, positive};
use crate::{SsfrError, V3};

/// A light at infinity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Direction towards the light (world; normalised when used).
    pub direction: [f32; 3],
    /// Colour (linear RGB, 1 = white).
    pub colour: [f32; 3],
    /// Ambient fraction in [0, 1] of the diffuse term.
    pub ambient: f32,
}

impl Default for Light {
    fn default() -> Self {
        Self {
            direction: [-0.4, 1.0, 0.6],
            colour: [1.0, 1.0, 1.0],
            ambient: 0.35,
        }
    }
}

impl Light {
    /// Unit direction towards the light (world); errors on a zero or non-finite direction.
    pub fn unit_direction(&self) -> Result<V3, SsfrError> {
        finite3("light.direction", self.direction)?;
        let d = V3::from(self.direction);
        if d.norm() == 0.0 {
            return Err(SsfrError::invalid("light.direction", "zero vector"));
        }
        Ok(d.normalize())
    }
}

/// The infinite ground plane `y = height_m`, checkered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// Height of the plane (m).
    pub height_m: f32,
    /// Side of one checker square (m, > 0).
    pub checker_m: f32,
    /// The two checker colours (linear RGB).
    pub colours: [[f32; 3]; 2],
}

/// The tank: the inside of an axis-aligned box, seen in cut-away (a ray shows the face where
/// it leaves the box: the floor and the far walls).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TankWalls {
    /// Lower corner (m).
    pub min: [f32; 3],
    /// Upper corner (m).
    pub max: [f32; 3],
    /// Wall colour (linear RGB); the floor is checkered with the ground's colours.
    pub colour: [f32; 3],
    /// Spacing of the grid lines drawn on walls and floor (m, > 0).
    pub grid_m: f32,
}

/// A solid obstacle drawn in the background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Obstacle {
    /// An axis-aligned box.
    Box {
        /// Lower corner (m).
        min: [f32; 3],
        /// Upper corner (m).
        max: [f32; 3],
        /// Colour (linear RGB).
        colour: [f32; 3],
    },
    /// A ball.
    Sphere {
        /// Centre (m).
        center: [f32; 3],
        /// Radius (m, > 0).
        radius: f32,
        /// Colour (linear RGB).
        colour: [f32; 3],
    },
}

/// The background scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Background {
    /// The ground plane, if any.
    pub ground: Option<Ground>,
    /// The tank, if any.
    pub tank: Option<TankWalls>,
    /// Obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Sky colour at the horizon (linear RGB).
    pub sky_horizon: [f32; 3],
    /// Sky colour straight up (linear RGB).
    pub sky_zenith: [f32; 3],
}

/// Default colours.
pub const CHECKER_LIGHT: [f32; 3] = [0.80, 0.78, 0.72];
/// Default colours.
pub const CHECKER_DARK: [f32; 3] = [0.30, 0.32, 0.36];

impl Background {
    /// A ground plane at `ground_y` (checkers of `checker_m`) and a sky, nothing else.
    pub fn ground_only(ground_y: f32, checker_m: f32) -> Self {
        Self {
            ground: Some(Ground {
                height_m: ground_y,
                checker_m,
                colours: [CHECKER_LIGHT, CHECKER_DARK],
            }),
            tank: None,
            obstacles: Vec::new(),
            sky_horizon: [0.85, 0.90, 0.95],
            sky_zenith: [0.35, 0.55, 0.85],
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SsfrError> {
        if let Some(g) = &self.ground {
            positive("background.ground.checker_m", g.checker_m)?;
            if !g.height_m.is_finite() {
                return Err(SsfrError::invalid(
                    "background.ground.height_m",
                    "not finite",
                ));
            }
        }
        if let Some(t) = &self.tank {
            finite3("background.tank.min", t.min)?;
            finite3("background.tank.max", t.max)?;
            positive("background.tank.grid_m", t.grid_m)?;
            if (0..3).any(|k| t.min[k] >= t.max[k]) {
                return Err(SsfrError::invalid("background.tank", "min must be < max"));
            }
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            match o {
                Obstacle::Box { min, max, .. } => {
                    finite3(&format!("background.obstacles[{i}].min"), *min)?;
                    finite3(&format!("background.obstacles[{i}].max"), *max)?;
                }
                Obstacle::Sphere { center, radius, .. } => {
                    finite3(&format!("background.obstacles[{i}].center"), *center)?;
                    positive(&format!("background.obstacles[{i}].radius"), *radius)?;
                }
            }
        }
        Ok(())
    }

    /// The sky seen in world direction `dir` (also the environment reflected by the liquid).
    #[inline]
    pub fn sky(&self, dir: &V3) -> V3 {
        let t = (dir.y / dir.norm().max(1e-30)).clamp(0.0, 1.0).sqrt();
        V3::from(self.sky_horizon) * (1.0 - t) + V3::from(self.sky_zenith) * t
    }

    /// The nearest hit of the ray `eye + t dir` with `t > 0`: `(t, colour, normal)`.
    fn trace(&self, eye: &V3, dir: &V3) -> Option<(f32, V3, V3)> {
        let mut best: Option<(f32, V3, V3)> = None;
        let mut consider = |t: f32, c: V3, n: V3| {
            if t > 0.0 && best.is_none_or(|b| t < b.0) {
                best = Some((t, c, n));
            }
        };
        if let Some(g) = &self.ground {
            if dir.y != 0.0 {
                let t = (g.height_m - eye.y) / dir.y;
                let p = eye + dir * t;
                let k = ((p.x / g.checker_m).floor() + (p.z / g.checker_m).floor()) as i64;
                let n = if eye.y >= g.height_m {
                    V3::y()
                } else {
                    -V3::y()
                };
                consider(t, V3::from(g.colours[k.rem_euclid(2) as usize]), n);
            }
        }
        if let Some(tk) = &self.tank {
            let (lo, hi) = (V3::from(tk.min), V3::from(tk.max));
            if let Some((t0, t1, _, exit_axis)) = ray_box(eye, dir, &lo, &hi) {
                if t1 > t0.max(0.0) {
                    let p = eye + dir * t1;
                    let mut n = V3::zeros();
                    n[exit_axis] = -dir[exit_axis].signum();
                    let grid = |a: f32| {
                        let f = (a / tk.grid_m).rem_euclid(1.0);
                        f.min(1.0 - f) < 0.03
                    };
                    let (a, b) = match exit_axis {
                        0 => (p.y, p.z),
                        1 => (p.x, p.z),
                        _ => (p.x, p.y),
                    };
                    let c = if exit_axis == 1 && dir.y < 0.0 {
                        let k = ((p.x / tk.grid_m).floor() + (p.z / tk.grid_m).floor()) as i64;
                        let base = self
                            .ground
                            .map_or([CHECKER_LIGHT, CHECKER_DARK], |g| g.colours);
                        V3::from(base[k.rem_euclid(2) as usize])
                    } else if grid(a) || grid(b) {
                        V3::from(tk.colour) * 0.6
                    } else {
                        V3::from(tk.colour)
                    };
                    consider(t1, c, n);
                }
            }
        }
        for o in &self.obstacles {
            match *o {
                Obstacle::Box { min, max, colour } => {
                    if let Some((t0, t1, entry_axis, _)) =
                        ray_box(eye, dir, &V3::from(min), &V3::from(max))
                    {
                        if t1 >= t0 && t0 > 0.0 {
                            let mut n = V3::zeros();
                            n[entry_axis] = -dir[entry_axis].signum();
                            consider(t0, V3::from(colour), n);
                        }
                    }
                }
                Obstacle::Sphere {
                    center,
                    radius,
                    colour,
                } => {
                    let c = V3::from(center);
                    let oc = eye - c;
                    let a = dir.norm_squared();
                    let b = oc.dot(dir);
                    let disc = b * b - a * (oc.norm_squared() - radius * radius);
                    if disc >= 0.0 {
                        let t = (-b - disc.sqrt()) / a;
                        let n = (eye + dir * t - c) / radius;
                        consider(t, V3::from(colour), n);
                    }
                }
            }
        }
        best
    }

    /// Renders the background seen by `camera` into `out` (resized): the colour lit by
    /// `light` (Lambert with an ambient term) and the exact depth of every pixel
    /// (`f32::INFINITY` where only sky is seen).
    pub fn render(
        &self,
        camera: &CameraFrame,
        light: &Light,
        out: &mut SceneBuffer,
    ) -> Result<(), SsfrError> {
        self.validate()?;
        let l = light.unit_direction()?;
        let lc = V3::from(light.colour);
        let amb = light.ambient.clamp(0.0, 1.0);
        let (w, h) = (camera.width, camera.height);
        out.width = w;
        out.height = h;
        out.colour.resize(w * h, [0.0; 3]);
        out.depth.resize(w * h, f32::INFINITY);
        out.colour
            .par_chunks_mut(w)
            .zip(out.depth.par_chunks_mut(w))
            .enumerate()
            .for_each(|(j, (crow, drow))| {
                for i in 0..w {
                    let dir = camera.dir_to_world(&camera.ray(i as f32 + 0.5, j as f32 + 0.5));
                    match self.trace(&camera.eye, &dir) {
                        Some((t, c, n)) => {
                            let diffuse = amb + (1.0 - amb) * n.dot(&l).max(0.0);
                            let col = c.component_mul(&lc) * diffuse;
                            crow[i] = [col.x, col.y, col.z];
                            drow[i] = t; // dir has unit view z, so t is the depth
                        }
                        None => {
                            let s = self.sky(&dir);
                            crow[i] = [s.x, s.y, s.z];
                            drow[i] = f32::INFINITY;
                        }
                    }
                }
            });
        Ok(())
    }
}

/// Ray–box intersection by slabs for the ray `eye + t dir`: `(t_near, t_far, entry axis,
/// exit axis)` (the ray meets the box when `t_near ≤ t_far`), `None` for a ray parallel to
/// and outside a slab.
pub fn ray_box(eye: &V3, dir: &V3, lo: &V3, hi: &V3) -> Option<(f32, f32, usize, usize)> {
    let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
    let (mut a0, mut a1) = (0, 0);
    for k in 0..3 {
        if dir[k] == 0.0 {
            if eye[k] < lo[k] || eye[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (mut n, mut f) = ((lo[k] - eye[k]) / dir[k], (hi[k] - eye[k]) / dir[k]);
        if n > f {
            std::mem::swap(&mut n, &mut f);
        }
        if n > t0 {
            t0 = n;
            a0 = k;
        }
        if f < t1 {
            t1 = f;
            a1 = k;
        }
    }
    Some((t0, t1, a0, a1))
}

/// The background as rendered: linear RGB colour and depth (view `z`, m) per pixel, row
/// major, row 0 at the top. The texture the refraction samples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneBuffer {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// Colour per pixel (linear RGB).
    pub colour: Vec<[f32; 3]>,
    /// Depth per pixel (m; `f32::INFINITY` for the sky).
    pub depth: Vec<f32>,
}

impl SceneBuffer {
    /// Bilinear colour at pixel coordinates `(u, v)` (clamped to the image).
    #[inline]
    pub fn sample(&self, u: f32, v: f32) -> V3 {
        let (w, h) = (self.width, self.height);
        let x = (u - 0.5).clamp(0.0, (w - 1) as f32);
        let y = (v - 0.5).clamp(0.0, (h - 1) as f32);
        let (i0, j0) = (x as usize, y as usize);
        let (i1, j1) = ((i0 + 1).min(w - 1), (j0 + 1).min(h - 1));
        let (fx, fy) = (x - i0 as f32, y - j0 as f32);
        let c = |i: usize, j: usize| V3::from(self.colour[j * w + i]);
        (c(i0, j0) * (1.0 - fx) + c(i1, j0) * fx) * (1.0 - fy)
            + (c(i0, j1) * (1.0 - fx) + c(i1, j1) * fx) * fy
    }

    /// Depth at the pixel containing `(u, v)` (clamped to the image).
    #[inline]
    pub fn depth_at(&self, u: f32, v: f32) -> f32 {
        let i = (u.max(0.0) as usize).min(self.width - 1);
        let j = (v.max(0.0) as usize).min(self.height - 1);
        self.depth[j * self.width + i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;

    #[test]
    fn ground_depth_is_exact() {
        let cam = Camera {
            eye: [0.0, 1.0, 2.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            width: 64,
            height: 48,
        }
        .frame()
        .unwrap();
        let bg = Background::ground_only(0.0, 0.1);
        let mut buf = SceneBuffer::default();
        bg.render(&cam, &Light::default(), &mut buf).unwrap();
        for j in 0..48 {
            for i in 0..64 {
                let z = buf.depth[j * 64 + i];
                if z.is_finite() {
                    let p = cam.eye + cam.dir_to_world(&cam.unproject_pixel(i, j, z));
                    assert!(p.y.abs() < 1e-4, "pixel {i},{j}: y = {}", p.y);
                }
            }
        }
        // The pixel below and right of the image centre looks half a pixel (0.012 rad) past
        // the origin, on a plane seen at 26.6°: depth ≈ √5 − √5 · 0.012 / tan 26.6° ≈ 2.18.
        let z = buf.depth[24 * 64 + 32];
        assert!((z - 2.18).abs() < 0.01, "{z}");
        // The top row sees sky.
        assert!(buf.depth[0].is_infinite());
    }
}
