//! Liquid bodies with a known surface: lattice particles filling a sphere or a box, and the
//! exact ray intersection with that surface (what the renderer's depth should be).

use sph_core::Vec3;
use ssfr_render::{CameraFrame, V3};

/// A body of liquid with an analytic surface.
#[derive(Debug, Clone, Copy)]
pub enum Shape {
    /// A ball.
    Sphere {
        /// Centre (m).
        centre: [f32; 3],
        /// Radius of the liquid's surface (m).
        radius: f32,
    },
    /// An axis-aligned box (a resting block, or a wide thin slab).
    Box {
        /// Lower corner (m).
        min: [f32; 3],
        /// Upper corner (m).
        max: [f32; 3],
    },
}

impl Shape {
    /// Particles of spacing `s` filling the shape: a cubic lattice whose points lie half a
    /// spacing inside the surface, so that spheres of radius `s/2` reach it (the scene
    /// files' sampling of blocks).
    pub fn particles(&self, s: f32) -> Vec<Vec3<f32>> {
        let (lo, hi) = match *self {
            Shape::Sphere { centre, radius } => (
                [centre[0] - radius, centre[1] - radius, centre[2] - radius],
                [centre[0] + radius, centre[1] + radius, centre[2] + radius],
            ),
            Shape::Box { min, max } => (min, max),
        };
        let n: Vec<usize> = (0..3)
            .map(|k| ((hi[k] - lo[k]) / s).round() as usize)
            .collect();
        let mut out = Vec::new();
        for i in 0..n[0] {
            for j in 0..n[1] {
                for k in 0..n[2] {
                    let p = Vec3::new(
                        lo[0] + (i as f32 + 0.5) * s,
                        lo[1] + (j as f32 + 0.5) * s,
                        lo[2] + (k as f32 + 0.5) * s,
                    );
                    let inside = match *self {
                        Shape::Sphere { centre, radius } => {
                            (p - V3::from(centre)).norm() <= radius - 0.5 * s
                        }
                        Shape::Box { .. } => true,
                    };
                    if inside {
                        out.push(p);
                    }
                }
            }
        }
        out
    }

    /// The exact first hit of the pixel `(i, j)`'s ray: `(depth m, unit normal (view), face
    /// id)`.
    pub fn hit(&self, cam: &CameraFrame, i: usize, j: usize) -> Option<(f32, V3, usize)> {
        let d = cam.dir_to_world(&cam.ray(i as f32 + 0.5, j as f32 + 0.5)); // view z = 1
        let e = cam.eye;
        match *self {
            Shape::Sphere { centre, radius } => {
                let oc = e - V3::from(centre);
                let a = d.norm_squared();
                let b = oc.dot(&d);
                let disc = b * b - a * (oc.norm_squared() - radius * radius);
                if disc < 0.0 {
                    return None;
                }
                let t = (-b - disc.sqrt()) / a;
                let n = (e + d * t - V3::from(centre)) / radius;
                (t > 0.0).then(|| (t, cam.dir_to_view(&n), 0))
            }
            Shape::Box { min, max } => {
                let (t0, t1, axis, _) =
                    ssfr_render::ray_box(&e, &d, &V3::from(min), &V3::from(max))?;
                if t0 > t1 || t0 <= 0.0 {
                    return None;
                }
                let mut n = V3::zeros();
                n[axis] = -d[axis].signum();
                let face = 2 * axis + usize::from(d[axis] < 0.0);
                Some((t0, cam.dir_to_view(&n), face))
            }
        }
    }
}
