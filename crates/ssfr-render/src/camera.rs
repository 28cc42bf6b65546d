//! The pinhole camera: a look-at frame and a vertical field of view.
//!
//! View space: the camera at the origin, `x` to the right, `y` up, `z` the distance along the
//! viewing direction (positive in front of the camera; "depth" everywhere in this crate is
//! this `z`, in metres). Pixel `(i, j)` (column, row; row 0 at the top) has its centre at
//! `(i + ½, j + ½)`; a view point `(x, y, z)` projects to `u = cx + f x / z`,
//! `v = cy − f y / z` with the focal length in pixels `f = (H/2) / tan(fov_y/2)`.

use crate::error::{finite3, positive};
use crate::{SsfrError, V3};

/// A perspective camera looking from `eye` at `target` (metres), with `up` fixing the roll.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Camera position (m, world).
    pub eye: [f32; 3],
    /// Point looked at (m, world).
    pub target: [f32; 3],
    /// Up direction (world; need not be normalised, must not be parallel to the view).
    pub up: [f32; 3],
    /// Vertical field of view (degrees, in (0, 180)).
    pub fov_y_deg: f32,
    /// Image width (pixels).
    pub width: usize,
    /// Image height (pixels).
    pub height: usize,
}

/// A [`Camera`] with its frame computed: the transforms used per pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFrame {
    /// Camera position (world).
    pub eye: V3,
    /// Unit right vector (world).
    pub right: V3,
    /// Unit up vector (world).
    pub up: V3,
    /// Unit viewing direction (world).
    pub forward: V3,
    /// Focal length (pixels).
    pub focal_px: f32,
    /// Principal point, x (pixels).
    pub cx: f32,
    /// Principal point, y (pixels).
    pub cy: f32,
    /// Image width (pixels).
    pub width: usize,
    /// Image height (pixels).
    pub height: usize,
}

impl Camera {
    /// Checks the parameters and computes the frame. Errors: non-finite vectors, `eye ==
    /// target`, `up` parallel to the view, a field of view outside (0°, 180°), a zero-size
    /// image ([`SsfrError::ImageSize`]).
    pub fn frame(&self) -> Result<CameraFrame, SsfrError> {
        crate::check_image_size(self.width, self.height)?;
        // The field of view first: a default eye is derived from it, and a bad one must
        // be blamed, not the eye the caller never gave.
        positive("camera.fov_deg", self.fov_y_deg)?;
        if self.fov_y_deg >= 179.0 {
            return Err(SsfrError::invalid(
                "camera.fov_deg",
                format!("{}: must be < 179", self.fov_y_deg),
            ));
        }
        finite3("camera.eye", self.eye)?;
        finite3("camera.target", self.target)?;
        finite3("camera.up", self.up)?;
        let eye = V3::from(self.eye);
        let d = V3::from(self.target) - eye;
        if d.norm() <= 0.0 {
            return Err(SsfrError::invalid(
                "camera.target",
                "equals camera.eye (no viewing direction)",
            ));
        }
        let forward = d.normalize();
        let right = forward.cross(&V3::from(self.up));
        if right.norm() < 1e-6 * V3::from(self.up).norm().max(1e-30) || right.norm() == 0.0 {
            return Err(SsfrError::invalid(
                "camera.up",
                "parallel to the viewing direction (or zero)",
            ));
        }
        let right = right.normalize();
        let up = right.cross(&forward);
        let focal_px = 0.5 * self.height as f32 / (0.5 * self.fov_y_deg.to_radians()).tan();
        Ok(CameraFrame {
            eye,
            right,
            up,
            forward,
            focal_px,
            cx: 0.5 * self.width as f32,
            cy: 0.5 * self.height as f32,
            width: self.width,
            height: self.height,
        })
    }
}

impl CameraFrame {
    /// World point to view space.
    #[inline]
    pub fn to_view(&self, p: &V3) -> V3 {
        let d = p - self.eye;
        V3::new(d.dot(&self.right), d.dot(&self.up), d.dot(&self.forward))
    }

    /// View direction to world direction.
    #[inline]
    pub fn dir_to_world(&self, d: &V3) -> V3 {
        self.right * d.x + self.up * d.y + self.forward * d.z
    }

    /// World direction to view direction.
    #[inline]
    pub fn dir_to_view(&self, d: &V3) -> V3 {
        V3::new(d.dot(&self.right), d.dot(&self.up), d.dot(&self.forward))
    }

    /// Pixel coordinates `(u, v)` of a view point with `z > 0`.
    #[inline]
    pub fn project(&self, v: &V3) -> (f32, f32) {
        (
            self.cx + self.focal_px * v.x / v.z,
            self.cy - self.focal_px * v.y / v.z,
        )
    }

    /// The view-space ray direction through pixel coordinates `(u, v)`, scaled so that its
    /// `z` is 1 (a point at depth `z` on the ray is `z · ray`).
    #[inline]
    pub fn ray(&self, u: f32, v: f32) -> V3 {
        V3::new(
            (u - self.cx) / self.focal_px,
            (self.cy - v) / self.focal_px,
            1.0,
        )
    }

    /// The view point at depth `z` seen through the centre of pixel `(i, j)`.
    #[inline]
    pub fn unproject_pixel(&self, i: usize, j: usize, z: f32) -> V3 {
        self.ray(i as f32 + 0.5, j as f32 + 0.5) * z
    }

    /// Width in metres of one pixel at depth `z`.
    #[inline]
    pub fn pixel_size_at(&self, z: f32) -> f32 {
        z / self.focal_px
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn cam() -> Camera {
        Camera {
            eye: [0.3, 1.2, 3.0],
            target: [0.5, 0.2, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 50.0,
            width: 320,
            height: 200,
        }
    }

    #[test]
    fn target_projects_to_the_centre_and_round_trips() {
        let f = cam().frame().unwrap();
        let t = f.to_view(&V3::new(0.5, 0.2, 0.0));
        let (u, v) = f.project(&t);
        assert_relative_eq!(u, 160.0, epsilon = 1e-3);
        assert_relative_eq!(v, 100.0, epsilon = 1e-3);
        let p = V3::new(0.9, -0.1, 0.4);
        let pv = f.to_view(&p);
        let (u, v) = f.project(&pv);
        let back = f.ray(u, v) * pv.z;
        assert_relative_eq!(back, pv, epsilon = 1e-4);
        // Up in the world is up in the image.
        let above = f.to_view(&V3::new(0.5, 0.4, 0.0));
        assert!(f.project(&above).1 < 100.0);
    }

    #[test]
    fn degenerate_cameras_are_named() {
        let mut c = cam();
        c.width = 0;
        assert!(matches!(c.frame(), Err(SsfrError::ImageSize { .. })));
        let mut c = cam();
        c.up = [0.2, -1.0, -3.0];
        assert!(c.frame().unwrap_err().to_string().contains("camera.up"));
        let mut c = cam();
        c.target = c.eye;
        assert!(c.frame().unwrap_err().to_string().contains("camera.target"));
        let mut c = cam();
        c.fov_y_deg = f32::NAN;
        assert!(c.frame().is_err());
    }
}
