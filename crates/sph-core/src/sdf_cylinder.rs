//! The solid cylinder with a vertical axis, [`CylinderSdf`].

// NaN-rejecting checks (a NaN ray is outside) are written as `!(x < 0.0)` on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::sdf::{
    check_finite_vec, check_positive, push_clipped, push_fingerprint, quadratic_roots, v64,
};
use crate::{Aabb, CoreError, Real, Sdf, Vec3};

/// Solid cylinder with a vertical axis (along `y`): the points within `radius` of the axis
/// through `base_center`, between `base_center.y` and `base_center.y + height` (exact
/// Euclidean distance outside and inside).
///
/// With `ρ` the distance from the axis and `y_c` the height of the mid-plane, the distance is
/// that of the meridian half-plane point `(ρ, y)` to the rectangle `[0, r] × [y0, y0 + h]`:
/// `q = (ρ − r, |y − y_c| − h/2)`, `φ = |max(q, 0)| + min(max(q₀, q₁), 0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CylinderSdf<R: Real> {
    base_center: Vec3<R>,
    radius: R,
    height: R,
}

impl<R: Real> CylinderSdf<R> {
    /// A cylinder of `radius > 0` and `height > 0` standing on `base_center` (the centre of
    /// its lower disc), its axis along `+y`.
    pub fn new(base_center: Vec3<R>, radius: R, height: R) -> Result<Self, CoreError> {
        check_finite_vec("cylinder base center", &base_center)?;
        check_positive("cylinder radius", radius)?;
        check_positive("cylinder height", height)?;
        Ok(Self {
            base_center,
            radius,
            height,
        })
    }

    /// `(unit radial direction, ρ − r, |y − y_c| − h/2, sign of y − y_c)` at `p`.
    fn parts(&self, p: &Vec3<R>) -> (Vec3<R>, R, R, R) {
        let half = self.height * R::of_f64(0.5);
        let (dx, dz) = (p.x - self.base_center.x, p.z - self.base_center.z);
        let rho = (dx * dx + dz * dz).sqrt();
        let radial = if rho > R::zero() {
            Vec3::new(dx / rho, R::zero(), dz / rho)
        } else {
            // On the axis every horizontal direction is a subgradient.
            Vec3::new(R::one(), R::zero(), R::zero())
        };
        let dy = p.y - (self.base_center.y + half);
        let sign_y = if dy < R::zero() { -R::one() } else { R::one() };
        (radial, rho - self.radius, dy.abs() - half, sign_y)
    }
}

impl<R: Real> Sdf<R> for CylinderSdf<R> {
    fn signed_distance(&self, p: &Vec3<R>) -> R {
        let (_, q0, q1, _) = self.parts(p);
        let (a, b) = (q0.max(R::zero()), q1.max(R::zero()));
        (a * a + b * b).sqrt() + q0.max(q1).min(R::zero())
    }
    fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
        let (radial, q0, q1, sign_y) = self.parts(p);
        let up = Vec3::new(R::zero(), sign_y, R::zero());
        let (a, b) = (q0.max(R::zero()), q1.max(R::zero()));
        let n = (a * a + b * b).sqrt();
        if n > R::zero() {
            (radial * a + up * b) / n
        } else if q0 >= q1 {
            // Inside: the nearer of the side and the cap.
            radial
        } else {
            up
        }
    }
    fn bounds(&self) -> Option<Aabb<R>> {
        let (c, r, h) = (self.base_center, self.radius, self.height);
        Some(Aabb {
            min: Vec3::new(c.x - r, c.y, c.z - r),
            max: Vec3::new(c.x + r, c.y + h, c.z + r),
        })
    }
    fn fingerprint(&self, out: &mut Vec<u8>) -> bool {
        let c = self.base_center;
        push_fingerprint(
            out,
            "cylinder-y",
            &[c.x, c.y, c.z, self.radius, self.height],
        );
        true
    }
    fn lipschitz_bound(&self) -> Option<f64> {
        Some(1.0)
    }
    /// The open cylinder is the intersection of the slab `y0 < y < y0 + h` and the infinite
    /// cylinder `ρ < r`, whose crossings are the roots of a quadratic in `t` (the stable form
    /// that avoids cancelling `b` against the discriminant).
    fn ray_inside_intervals(
        &self,
        x: &Vec3<f64>,
        dir: &Vec3<f64>,
        t_max: f64,
        out: &mut Vec<(f64, f64)>,
    ) -> bool {
        let c = v64(&self.base_center);
        let (r, h) = (self.radius.as_f64(), self.height.as_f64());
        let (y0, y1) = (c.y, c.y + h);
        let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
        if dir.y == 0.0 {
            if !(x.y > y0 && x.y < y1) {
                return true;
            }
        } else {
            let (p, q) = ((y0 - x.y) / dir.y, (y1 - x.y) / dir.y);
            t_in = p.min(q);
            t_out = p.max(q);
        }
        let (dx, dz) = (x.x - c.x, x.z - c.z);
        let a = dir.x * dir.x + dir.z * dir.z;
        let b = dx * dir.x + dz * dir.z;
        let cc = dx * dx + dz * dz - r * r;
        if a == 0.0 {
            // Parallel to the axis: inside the whole way or not at all.
            if !(cc < 0.0) {
                return true;
            }
        } else {
            let Some((t1, t2)) = quadratic_roots(a, b, cc) else {
                return true;
            };
            t_in = t_in.max(t1);
            t_out = t_out.min(t2);
        }
        push_clipped(t_in, t_out, t_max, out);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The naive oracle of the distance: the nearest of `n` points sampled along each side of
    /// the meridian rectangle (the top and bottom caps `ρ ∈ [0, r]`, the side `y ∈ [y0, y1]`),
    /// the sign from the membership test; off by at most half a sample step.
    fn brute_distance(c: Vec3<f64>, r: f64, h: f64, p: &Vec3<f64>, n: usize) -> (f64, f64) {
        let rho = (p.x - c.x).hypot(p.z - c.z);
        let y = p.y;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            let f = i as f64 / n as f64;
            for (sr, sy) in [(f * r, c.y), (f * r, c.y + h), (r, c.y + f * h)] {
                best = best.min((rho - sr).hypot(y - sy));
            }
        }
        let inside = rho < r && y > c.y && y < c.y + h;
        let step = r.max(h) / n as f64;
        (if inside { -best } else { best }, 0.5 * step)
    }

    fn inside(c: Vec3<f64>, r: f64, h: f64, p: &Vec3<f64>) -> bool {
        (p.x - c.x).hypot(p.z - c.z) < r && p.y > c.y && p.y < c.y + h
    }

    proptest! {
        #[test]
        fn distance_matches_the_brute_force_oracle(
            c in prop::array::uniform3(-1.0..1.0f64),
            r in 0.1..2.0f64,
            h in 0.1..2.0f64,
            p in prop::array::uniform3(-3.0..3.0f64),
        ) {
            let (c, p) = (Vec3::from(c), Vec3::from(p));
            let s = CylinderSdf::new(c, r, h).unwrap();
            let (oracle, tol) = brute_distance(c, r, h, &p, 4000);
            let d = s.signed_distance(&p);
            prop_assert!((d - oracle).abs() <= tol + 1e-12, "{d} against {oracle}");
        }

        /// The gradient is the distance's central difference where the field is smooth
        /// (away from the edges, the axis and the medial surface: the difference of two
        /// one-sided steps is then that of one plane).
        #[test]
        fn gradient_matches_finite_differences(
            c in prop::array::uniform3(-1.0..1.0f64),
            r in 0.3..2.0f64,
            h in 0.3..2.0f64,
            p in prop::array::uniform3(-3.0..3.0f64),
        ) {
            let (c, p) = (Vec3::from(c), Vec3::from(p));
            let s = CylinderSdf::new(c, r, h).unwrap();
            let eps = 1e-6;
            let g = s.gradient(&p);
            let mut fd = Vec3::zeros();
            for a in 0..3 {
                let mut e = Vec3::zeros();
                e[a] = eps;
                fd[a] = (s.signed_distance(&(p + e)) - s.signed_distance(&(p - e))) / (2.0 * eps);
            }
            let smooth = (fd.norm() - 1.0).abs() < 1e-6
                && (fd - g).norm() < 1e-3 || {
                    // a kink within eps: the one-sided differences disagree
                    let mut kink = false;
                    for a in 0..3 {
                        let mut e = Vec3::zeros();
                        e[a] = eps;
                        let d0 = s.signed_distance(&p);
                        let fwd = (s.signed_distance(&(p + e)) - d0) / eps;
                        let bwd = (d0 - s.signed_distance(&(p - e))) / eps;
                        kink |= (fwd - bwd).abs() > 1e-4;
                    }
                    kink
                };
            prop_assert!(smooth, "gradient {g:?} against {fd:?}");
            prop_assert!((g.norm() - 1.0).abs() < 1e-12);
        }

        /// The closed-form intervals against dense sampling of the membership test along
        /// the segment: every sample inside lies in an interval and every sample outside in
        /// none, except within one sample step of an interval's end.
        #[test]
        fn ray_intervals_match_dense_sampling(
            c in prop::array::uniform3(-1.0..1.0f64),
            r in 0.1..2.0f64,
            h in 0.1..2.0f64,
            x in prop::array::uniform3(-3.0..3.0f64),
            dir in prop::array::uniform3(-2.0..2.0f64),
            axis_parallel in any::<bool>(),
            horizontal in any::<bool>(),
            t_max in 0.1..4.0f64,
        ) {
            let (c, x) = (Vec3::from(c), Vec3::from(x));
            let mut dir = Vec3::from(dir);
            if axis_parallel { dir.x = 0.0; dir.z = 0.0; }
            if horizontal { dir.y = 0.0; }
            prop_assume!(dir.norm() > 1e-3);
            let s = CylinderSdf::new(c, r, h).unwrap();
            let mut out = Vec::new();
            prop_assert!(s.ray_inside_intervals(&x, &dir, t_max, &mut out));
            prop_assert!(out.len() <= 1);
            for &(a, b) in &out {
                prop_assert!(0.0 <= a && a < b && b <= t_max);
            }
            let n = 4000;
            let dt = t_max / n as f64;
            for i in 0..=n {
                let t = i as f64 * dt;
                let near_end = out.iter().any(|&(a, b)| (t - a).abs() <= dt || (t - b).abs() <= dt);
                if near_end { continue; }
                let listed = out.iter().any(|&(a, b)| t > a && t < b);
                prop_assert_eq!(listed, inside(c, r, h, &(x + dir * t)), "t = {}", t);
            }
        }
    }

    #[test]
    fn analytic_values_and_bad_shapes() {
        let s = CylinderSdf::new(Vec3::new(1.0, 0.0, 1.0), 2.0, 4.0).unwrap();
        assert_eq!(s.signed_distance(&Vec3::new(1.0, 2.0, 1.0)), -2.0);
        assert_eq!(s.signed_distance(&Vec3::new(6.0, 2.0, 1.0)), 3.0);
        assert_eq!(s.signed_distance(&Vec3::new(1.0, 5.0, 1.0)), 1.0);
        assert_eq!(s.signed_distance(&Vec3::new(6.0, 8.0, 1.0)), 5.0);
        assert_eq!(
            s.gradient(&Vec3::new(1.0, -1.0, 1.0)),
            Vec3::new(0.0, -1.0, 0.0)
        );
        let e = CylinderSdf::new(Vec3::<f64>::zeros(), 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("cylinder radius"), "{e}");
        let e = CylinderSdf::new(Vec3::<f32>::zeros(), 1.0, f32::NAN).unwrap_err();
        assert!(e.to_string().contains("cylinder height"), "{e}");
        let e = CylinderSdf::new(Vec3::new(f64::INFINITY, 0.0, 0.0), 1.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("cylinder base center"), "{e}");
    }
}
