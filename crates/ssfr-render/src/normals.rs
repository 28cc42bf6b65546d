//! Step 5 of the paper (van der Laan et al. 2009, §3.1): the view-space normal of each
//! liquid pixel from the smoothed depth. The pixel's view position is
//! `P(i, j) = z(i, j) · ((i + ½ − c_x)/f, (c_y − j − ½)/f, 1)`; along each image axis the
//! forward and the backward difference of `P` are formed and the one with the smaller
//! `|Δz|` is kept (so that a silhouette does not bend the normals of the pixels beside it;
//! a missing neighbour means the other side), and `n = ∂P/∂x × ∂P/∂y`, normalised and turned
//! towards the camera. A pixel with no neighbour on either side along an axis gets the
//! normal facing the camera. Cost: one pass over the pixels.

use rayon::prelude::*;

use crate::camera::CameraFrame;
use crate::V3;

/// Fills `normals` (resized; row major, view space, unit; zero where `depth` is not finite).
pub fn normals_from_depth(camera: &CameraFrame, depth: &[f32], normals: &mut Vec<[f32; 3]>) {
    let (w, h) = (camera.width, camera.height);
    normals.clear();
    normals.resize(w * h, [0.0; 3]);
    normals.par_chunks_mut(w).enumerate().for_each(|(j, row)| {
        for (i, out) in row.iter_mut().enumerate() {
            let z = depth[j * w + i];
            if !z.is_finite() {
                continue;
            }
            let p = camera.unproject_pixel(i, j, z);
            let at = |ii: usize, jj: usize| {
                let zz = depth[jj * w + ii];
                zz.is_finite().then(|| camera.unproject_pixel(ii, jj, zz))
            };
            let pick = |fwd: Option<V3>, bwd: Option<V3>| -> Option<V3> {
                match (fwd.map(|f| f - p), bwd.map(|b| p - b)) {
                    (Some(f), Some(b)) => Some(if f.z.abs() <= b.z.abs() { f } else { b }),
                    (Some(f), None) => Some(f),
                    (None, Some(b)) => Some(b),
                    (None, None) => None,
                }
            };
            let dx = pick(
                (i + 1 < w).then(|| at(i + 1, j)).flatten(),
                (i > 0).then(|| at(i - 1, j)).flatten(),
            );
            // Rows grow downwards: the "up" tangent is the backward row difference.
            let dy = pick(
                (j > 0).then(|| at(i, j - 1)).flatten(),
                (j + 1 < h).then(|| at(i, j + 1)).flatten(),
            );
            let n = match (dx, dy) {
                (Some(a), Some(b)) => {
                    let c = a.cross(&b);
                    if c.norm() > 0.0 {
                        c.normalize()
                    } else {
                        -p.normalize()
                    }
                }
                _ => -p.normalize(),
            };
            let n = if n.dot(&p) > 0.0 { -n } else { n };
            *out = [n.x, n.y, n.z];
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;

    #[test]
    fn plane_normals_are_exact() {
        let cam = Camera {
            eye: [0.0, 1.0, 2.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            width: 40,
            height: 30,
        }
        .frame()
        .unwrap();
        // Depth of the plane y = 0.
        let mut depth = vec![f32::INFINITY; 40 * 30];
        for j in 0..30 {
            for i in 0..40 {
                let d = cam.dir_to_world(&cam.ray(i as f32 + 0.5, j as f32 + 0.5));
                if d.y < 0.0 {
                    depth[j * 40 + i] = -cam.eye.y / d.y;
                }
            }
        }
        let mut n = Vec::new();
        normals_from_depth(&cam, &depth, &mut n);
        let up_view = cam.dir_to_view(&V3::y());
        for k in 0..40 * 30 {
            if depth[k].is_finite() {
                let nk = V3::from(n[k]);
                assert!((nk - up_view).norm() < 2e-3, "{k}: {nk:?} vs {up_view:?}");
            }
        }
    }
}
