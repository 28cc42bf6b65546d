//! Signed distance fields for solid boundaries.
//!
//! Convention (as in SPlisHSPlasH's volume maps and the PBF paper's "SDF stored as volume
//! textures"): the distance is **negative inside the solid** and positive in the free space
//! where particles live; [`Sdf::gradient`] is the unit outward normal of the solid.

use crate::{Aabb, CoreError, Real, Vec3};

/// A solid described by its signed distance (length unit of the scene).
pub trait Sdf<R: Real>: Send + Sync {
    /// Signed distance from `p` to the solid's surface: `< 0` inside the solid.
    fn signed_distance(&self, p: &Vec3<R>) -> R;

    /// Gradient of the signed distance (unit outward normal where the field is smooth).
    ///
    /// The default uses central differences with a step of `1e-4` times the local distance
    /// scale; analytic shapes override it.
    fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
        let scale = p.norm().max(R::one());
        let eps = R::of_f64(1e-4) * scale;
        let mut g = Vec3::zeros();
        for a in 0..3 {
            let mut e = Vec3::zeros();
            e[a] = eps;
            g[a] = (self.signed_distance(&(p + e)) - self.signed_distance(&(p - e))) / (eps + eps);
        }
        g
    }

    /// A box holding the solid's surface, when it is bounded.
    fn bounds(&self) -> Option<Aabb<R>> {
        None
    }

    /// Appends to `out` a stable, complete description of this solid (a type tag and every
    /// parameter the distance depends on, as little-endian bytes) and returns `true`; two
    /// solids with equal descriptions must have bit-identical distances and gradients. Caches
    /// of data derived from a solid (the volume maps of `sph-solver`) key on it.
    ///
    /// The default appends nothing and returns `false`: "not cacheable" (a user solid that
    /// does not describe itself is rebuilt every time rather than confused with another).
    fn fingerprint(&self, out: &mut Vec<u8>) -> bool {
        let _ = out;
        false
    }

    /// A Lipschitz constant `L` of [`Sdf::signed_distance`] as evaluated
    /// (`|φ(p) − φ(q)| ≤ L |p − q|` up to the rounding of the precision), when one is known:
    /// `Some(1.0)` for exact Euclidean distances. Searches along rays (the volume maps'
    /// quadrature) use it to skip stretches that cannot hold a surface crossing. The default,
    /// `None`, makes no claim (interpolated fields such as [`GridSdf`](crate::GridSdf)).
    fn lipschitz_bound(&self) -> Option<f64> {
        None
    }

    /// The parts of the segment `x + t ω`, `0 ≤ t ≤ t_max`, inside the solid (`φ < 0`), in
    /// closed form: appends them to `out` as disjoint intervals `(t_in, t_out)` in increasing
    /// order (`0 ≤ t_in < t_out ≤ t_max`) and returns `true`. Computed in `f64` from the
    /// shape's parameters (the surface of the stored shape, exactly up to `f64` rounding).
    /// `ω` need not be unit. Integrals along rays (the volume maps' quadrature) use it instead
    /// of searching the distance for sign changes.
    ///
    /// The default appends nothing and returns `false`: no closed form (meshes, user solids);
    /// callers then sample [`Sdf::signed_distance`].
    fn ray_inside_intervals(
        &self,
        x: &Vec3<f64>,
        dir: &Vec3<f64>,
        t_max: f64,
        out: &mut Vec<(f64, f64)>,
    ) -> bool {
        let _ = (x, dir, t_max, out);
        false
    }
}

/// Appends `(a, b) ∩ [0, t_max]` to `out` when it is not empty.
pub(crate) fn push_clipped(a: f64, b: f64, t_max: f64, out: &mut Vec<(f64, f64)>) {
    let (a, b) = (a.max(0.0), b.min(t_max));
    if a < b {
        out.push((a, b));
    }
}

/// The two distinct real roots `t1 < t2` of `a t² + 2 b t + c = 0` (`a > 0`), in the stable
/// form that avoids cancelling `b` against the discriminant; `None` without two distinct
/// roots (or with `a ≤ 0`, or a NaN).
pub(crate) fn quadratic_roots(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - a * c;
    if !(a > 0.0 && disc > 0.0) {
        return None;
    }
    let q = -(b + b.signum() * disc.sqrt());
    let (t1, t2) = (q / a, c / q);
    Some((t1.min(t2), t1.max(t2)))
}

pub(crate) fn v64<R: Real>(v: &Vec3<R>) -> Vec3<f64> {
    Vec3::new(v.x.as_f64(), v.y.as_f64(), v.z.as_f64())
}

/// Appends a type tag (length-prefixed) and the `f64` bit patterns of `values` (exact for
/// `f32` and `f64` scalars) to a [`Sdf::fingerprint`] description.
pub fn push_fingerprint<R: Real>(out: &mut Vec<u8>, tag: &str, values: &[R]) {
    out.extend_from_slice(&(tag.len() as u64).to_le_bytes());
    out.extend_from_slice(tag.as_bytes());
    out.extend_from_slice(&(values.len() as u64).to_le_bytes());
    for v in values {
        out.extend_from_slice(&v.as_f64().to_bits().to_le_bytes());
    }
}

pub(crate) fn check_positive<R: Real>(name: &'static str, value: R) -> Result<(), CoreError> {
    if !(value.is_finite_value() && value > R::zero()) {
        return Err(CoreError::InvalidParameter {
            name,
            value: value.as_f64(),
            reason: "must be finite and > 0",
        });
    }
    Ok(())
}

pub(crate) fn check_finite_vec<R: Real>(name: &'static str, v: &Vec3<R>) -> Result<(), CoreError> {
    if let Some(a) = (0..3).find(|&a| !v[a].is_finite_value()) {
        return Err(CoreError::InvalidParameter {
            name,
            value: v[a].as_f64(),
            reason: "components must be finite",
        });
    }
    Ok(())
}

/// Half-space solid `{p : n·(p − point) < 0}`: the free side is the one the normal points to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane<R: Real> {
    normal: Vec3<R>,
    offset: R,
}

impl<R: Real> Plane<R> {
    /// A plane through `point` whose unit `normal` (normalised here) points into free space.
    pub fn new(point: Vec3<R>, normal: Vec3<R>) -> Result<Self, CoreError> {
        check_finite_vec("plane point", &point)?;
        check_finite_vec("plane normal", &normal)?;
        check_positive("plane normal length", normal.norm())?;
        let normal = normal.normalize();
        Ok(Self {
            offset: normal.dot(&point),
            normal,
        })
    }

    /// Unit normal pointing into free space.
    pub fn normal(&self) -> Vec3<R> {
        self.normal
    }
}

impl<R: Real> Sdf<R> for Plane<R> {
    fn signed_distance(&self, p: &Vec3<R>) -> R {
        self.normal.dot(p) - self.offset
    }
    fn gradient(&self, _p: &Vec3<R>) -> Vec3<R> {
        self.normal
    }
    fn fingerprint(&self, out: &mut Vec<u8>) -> bool {
        let n = self.normal;
        push_fingerprint(out, "plane", &[n.x, n.y, n.z, self.offset]);
        true
    }
    fn lipschitz_bound(&self) -> Option<f64> {
        Some(1.0)
    }
    /// `φ(t) = n·x − offset + t n·ω < 0`.
    fn ray_inside_intervals(
        &self,
        x: &Vec3<f64>,
        dir: &Vec3<f64>,
        t_max: f64,
        out: &mut Vec<(f64, f64)>,
    ) -> bool {
        let n = v64(&self.normal);
        let (phi0, slope) = (n.dot(x) - self.offset.as_f64(), n.dot(dir));
        if slope == 0.0 {
            if phi0 < 0.0 {
                push_clipped(0.0, t_max, t_max, out);
            }
        } else {
            let root = -phi0 / slope;
            if slope > 0.0 {
                push_clipped(f64::NEG_INFINITY, root, t_max, out);
            } else {
                push_clipped(root, f64::INFINITY, t_max, out);
            }
        }
        true
    }
}

/// Solid ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere<R: Real> {
    center: Vec3<R>,
    radius: R,
}

impl<R: Real> Sphere<R> {
    /// A ball of absolute `radius > 0` around `center`.
    pub fn new(center: Vec3<R>, radius: R) -> Result<Self, CoreError> {
        check_finite_vec("sphere center", &center)?;
        check_positive("sphere radius", radius)?;
        Ok(Self { center, radius })
    }
}

impl<R: Real> Sdf<R> for Sphere<R> {
    fn signed_distance(&self, p: &Vec3<R>) -> R {
        (p - self.center).norm() - self.radius
    }
    fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
        let d = p - self.center;
        let n = d.norm();
        if n > R::zero() {
            d / n
        } else {
            // The centre has no direction; any unit vector is a valid subgradient.
            Vec3::new(R::zero(), R::one(), R::zero())
        }
    }
    fn bounds(&self) -> Option<Aabb<R>> {
        let r = Vec3::repeat(self.radius);
        Some(Aabb {
            min: self.center - r,
            max: self.center + r,
        })
    }
    fn fingerprint(&self, out: &mut Vec<u8>) -> bool {
        let c = self.center;
        push_fingerprint(out, "sphere", &[c.x, c.y, c.z, self.radius]);
        true
    }
    fn lipschitz_bound(&self) -> Option<f64> {
        Some(1.0)
    }
    /// `|x + t ω − c|² < r²`: between the roots of the quadratic (the stable form that
    /// avoids cancelling `b` against the discriminant).
    fn ray_inside_intervals(
        &self,
        x: &Vec3<f64>,
        dir: &Vec3<f64>,
        t_max: f64,
        out: &mut Vec<(f64, f64)>,
    ) -> bool {
        let d = x - v64(&self.center);
        let r = self.radius.as_f64();
        let (a, b, c) = (dir.norm_squared(), d.dot(dir), d.norm_squared() - r * r);
        if let Some((t1, t2)) = quadratic_roots(a, b, c) {
            push_clipped(t1, t2, t_max, out);
        }
        true
    }
}

/// Solid axis-aligned box (exact Euclidean distance outside and inside).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxSdf<R: Real> {
    center: Vec3<R>,
    half_extents: Vec3<R>,
}

impl<R: Real> BoxSdf<R> {
    /// A solid box covering `aabb`; every edge must be longer than zero.
    pub fn new(aabb: Aabb<R>) -> Result<Self, CoreError> {
        let half = aabb.extent() * R::of_f64(0.5);
        for a in 0..3 {
            check_positive("box edge length", half[a] + half[a])?;
        }
        Ok(Self {
            center: aabb.center(),
            half_extents: half,
        })
    }

    /// The box as an [`Aabb`].
    pub fn aabb(&self) -> Aabb<R> {
        Aabb {
            min: self.center - self.half_extents,
            max: self.center + self.half_extents,
        }
    }
}

impl<R: Real> Sdf<R> for BoxSdf<R> {
    fn signed_distance(&self, p: &Vec3<R>) -> R {
        let q = (p - self.center).abs() - self.half_extents;
        let outside = q.sup(&Vec3::zeros()).norm();
        let inside = q.x.max(q.y.max(q.z)).min(R::zero());
        outside + inside
    }
    fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
        let d = p - self.center;
        let q = d.abs() - self.half_extents;
        let sign = |a: usize| {
            if d[a] < R::zero() {
                -R::one()
            } else {
                R::one()
            }
        };
        let outside = q.sup(&Vec3::zeros());
        let n = outside.norm();
        if n > R::zero() {
            Vec3::new(
                outside.x * sign(0),
                outside.y * sign(1),
                outside.z * sign(2),
            ) / n
        } else {
            // Inside: the nearest face is the axis of largest q.
            let a = if q.x >= q.y && q.x >= q.z {
                0
            } else if q.y >= q.z {
                1
            } else {
                2
            };
            let mut g = Vec3::zeros();
            g[a] = sign(a);
            g
        }
    }
    fn bounds(&self) -> Option<Aabb<R>> {
        Some(self.aabb())
    }
    fn fingerprint(&self, out: &mut Vec<u8>) -> bool {
        let (c, e) = (self.center, self.half_extents);
        push_fingerprint(out, "box", &[c.x, c.y, c.z, e.x, e.y, e.z]);
        true
    }
    fn lipschitz_bound(&self) -> Option<f64> {
        Some(1.0)
    }
    /// The slab test: the open box is the intersection of three open slabs.
    fn ray_inside_intervals(
        &self,
        x: &Vec3<f64>,
        dir: &Vec3<f64>,
        t_max: f64,
        out: &mut Vec<(f64, f64)>,
    ) -> bool {
        let b = self.aabb();
        let (lo, hi) = (v64(&b.min), v64(&b.max));
        let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
        for a in 0..3 {
            if dir[a] == 0.0 {
                if !(x[a] > lo[a] && x[a] < hi[a]) {
                    return true;
                }
            } else {
                let (p, q) = ((lo[a] - x[a]) / dir[a], (hi[a] - x[a]) / dir[a]);
                t_in = t_in.max(p.min(q));
                t_out = t_out.min(p.max(q));
            }
        }
        push_clipped(t_in, t_out, t_max, out);
        true
    }
}

/// Complement of a solid: what was inside becomes free space. A tank is `Inverted<BoxSdf>`:
/// particles live inside the box and the walls are everything outside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inverted<S>(pub S);

impl<R: Real, S: Sdf<R>> Sdf<R> for Inverted<S> {
    fn signed_distance(&self, p: &Vec3<R>) -> R {
        -self.0.signed_distance(p)
    }
    fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
        -self.0.gradient(p)
    }
    fn bounds(&self) -> Option<Aabb<R>> {
        self.0.bounds()
    }
    fn fingerprint(&self, out: &mut Vec<u8>) -> bool {
        push_fingerprint::<R>(out, "inverted", &[]);
        self.0.fingerprint(out)
    }
    fn lipschitz_bound(&self) -> Option<f64> {
        self.0.lipschitz_bound()
    }
    /// The gaps of the inner solid's intervals in `[0, t_max]`.
    fn ray_inside_intervals(
        &self,
        x: &Vec3<f64>,
        dir: &Vec3<f64>,
        t_max: f64,
        out: &mut Vec<(f64, f64)>,
    ) -> bool {
        let start = out.len();
        if !self.0.ray_inside_intervals(x, dir, t_max, out) {
            out.truncate(start);
            return false;
        }
        // The gaps overwrite the inner intervals in place: the gap before interval `k` is
        // written at or before `k`, after `k` is read; the last gap is pushed.
        let end = out.len();
        let (mut from, mut written) = (0.0, start);
        for k in start..end {
            let (a, b) = out[k];
            if from < a.min(t_max) {
                out[written] = (from, a.min(t_max));
                written += 1;
            }
            from = b;
        }
        out.truncate(written);
        push_clipped(from, t_max, t_max, out);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    fn unit_box() -> BoxSdf<f64> {
        BoxSdf::new(Aabb::new(Vec3::new(-1.0, -2.0, -3.0), Vec3::new(1.0, 2.0, 3.0)).unwrap())
            .unwrap()
    }

    #[test]
    fn analytic_values() {
        let s = Sphere::new(Vec3::new(1.0, 0.0, 0.0), 2.0).unwrap();
        assert_relative_eq!(s.signed_distance(&Vec3::new(4.0, 0.0, 0.0)), 1.0);
        assert_relative_eq!(s.signed_distance(&Vec3::new(1.0, 0.0, 0.0)), -2.0);
        let b = unit_box();
        assert_relative_eq!(b.signed_distance(&Vec3::new(0.0, 0.0, 0.0)), -1.0);
        assert_relative_eq!(b.signed_distance(&Vec3::new(2.0, 3.0, 0.0)), 2f64.sqrt());
        assert_relative_eq!(b.signed_distance(&Vec3::new(0.0, 0.0, 3.5)), 0.5);
        let tank = Inverted(b);
        assert_relative_eq!(tank.signed_distance(&Vec3::new(0.0, 1.5, 0.0)), 0.5);
        let p = Plane::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 2.0, 0.0)).unwrap();
        assert_relative_eq!(p.signed_distance(&Vec3::new(5.0, 3.0, -1.0)), 2.0);
    }

    #[test]
    fn invalid_shapes_are_named() {
        let e = Sphere::new(Vec3::<f32>::zeros(), 0.0).unwrap_err();
        assert!(e.to_string().contains("sphere radius"), "{e}");
        let e = Plane::new(Vec3::<f64>::zeros(), Vec3::zeros()).unwrap_err();
        assert!(e.to_string().contains("plane normal"), "{e}");
        let flat = Aabb::new(Vec3::<f64>::zeros(), Vec3::new(1.0, 0.0, 1.0)).unwrap();
        assert!(BoxSdf::new(flat).is_err());
    }

    proptest! {
        /// Shapes that declare a Lipschitz bound keep it (exact distances: 1), which the
        /// volume maps rely on to skip ray samples; and their fingerprints tell them apart.
        #[test]
        fn declared_lipschitz_bounds_hold(
            p in prop::array::uniform3(-5.0..5.0f64),
            q in prop::array::uniform3(-5.0..5.0f64),
        ) {
            let (p, q) = (Vec3::from(p), Vec3::from(q));
            let shapes: Vec<Box<dyn Sdf<f64>>> = vec![
                Box::new(unit_box()),
                Box::new(Inverted(unit_box())),
                Box::new(Sphere::new(Vec3::new(0.5, -0.5, 0.2), 1.5).unwrap()),
                Box::new(Plane::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 2.0, -0.5)).unwrap()),
                Box::new(crate::CylinderSdf::new(Vec3::new(0.3, -1.0, 0.1), 1.2, 2.5).unwrap()),
            ];
            let mut prints = Vec::new();
            for s in &shapes {
                let l = s.lipschitz_bound().expect("exact distance");
                let (a, b) = (s.signed_distance(&p), s.signed_distance(&q));
                // Rounding of two f64 distances of magnitude < 20: 1e-13.
                prop_assert!((a - b).abs() <= l * (p - q).norm() + 1e-13);
                let mut f = Vec::new();
                prop_assert!(s.fingerprint(&mut f));
                prop_assert!(!prints.contains(&f));
                prints.push(f);
            }
        }

        /// Closed-form ray intervals against the sampled distance (the naive oracle): the
        /// distance is negative at every interval's midpoint and non-negative at every
        /// gap's, and vanishes at every interior end point.
        #[test]
        fn ray_intervals_match_the_distance(
            x in prop::array::uniform3(-4.0..4.0f64),
            dir in prop::array::uniform3(-1.0..1.0f64),
            t_max in 0.1..8.0f64,
        ) {
            let (x, dir) = (Vec3::from(x), Vec3::from(dir));
            prop_assume!(dir.norm() > 1e-3);
            let shapes: Vec<Box<dyn Sdf<f64>>> = vec![
                Box::new(unit_box()),
                Box::new(Inverted(unit_box())),
                Box::new(Sphere::new(Vec3::new(0.5, -0.5, 0.2), 1.5).unwrap()),
                Box::new(Inverted(Sphere::new(Vec3::new(0.5, -0.5, 0.2), 1.5).unwrap())),
                Box::new(Plane::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 2.0, -0.5)).unwrap()),
                Box::new(Inverted(Inverted(unit_box()))),
            ];
            for (k, s) in shapes.iter().enumerate() {
                let mut iv = vec![(-1.0, -1.0)]; // appended after what is there
                prop_assert!(s.ray_inside_intervals(&x, &dir, t_max, &mut iv));
                prop_assert_eq!(iv[0], (-1.0, -1.0));
                let iv = &iv[1..];
                let phi = |t: f64| s.signed_distance(&(x + dir * t));
                // Rounding of f64 distances and roots of magnitude < 20: 1e-12 (m).
                let tol = 1e-12 * (1.0 + t_max) * (1.0 + dir.norm());
                let mut from = 0.0;
                for &(a, b) in iv {
                    prop_assert!(0.0 <= a && a < b && b <= t_max && a >= from, "shape {}: {:?}", k, iv);
                    for t in [a, b] {
                        if t > 0.0 && t < t_max {
                            prop_assert!(phi(t).abs() < 1e-9, "shape {}: end {} phi {}", k, t, phi(t));
                        }
                    }
                    from = b;
                }
                // The sign of the distance at 401 points along the segment: negative exactly
                // where an interval says inside.
                for i in 0..=400 {
                    let t = if i == 400 { t_max } else { t_max * i as f64 / 400.0 };
                    let inside = iv.iter().any(|&(a, b)| t >= a && t <= b);
                    let (f, near_end) = (phi(t), iv.iter().any(|&(a, b)| (t - a).abs().min((t - b).abs()) < 1e-9));
                    if !near_end {
                        prop_assert_eq!(f < 0.0, inside, "shape {}: t {} phi {} in {:?}", k, t, f, iv);
                    }
                    let consistent = if inside { f < tol } else { f > -tol };
                    prop_assert!(consistent, "shape {}: t {} phi {}", k, t, f);
                }
            }
        }

        /// Analytic gradients agree with central differences of the distance away from
        /// the medial axis (where the gradient is discontinuous), and have unit length.
        #[test]
        fn gradients_match_finite_differences(x in -5.0..5.0f64, y in -5.0..5.0f64, z in -5.0..5.0f64) {
            let p = Vec3::new(x, y, z);
            let shapes: Vec<Box<dyn Sdf<f64>>> = vec![
                Box::new(unit_box()),
                Box::new(Inverted(unit_box())),
                Box::new(Sphere::new(Vec3::new(0.5, -0.5, 0.2), 1.5).unwrap()),
                Box::new(Plane::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 2.0, -0.5)).unwrap()),
                Box::new(crate::CylinderSdf::new(Vec3::new(0.3, -1.0, 0.1), 1.2, 2.5).unwrap()),
            ];
            for s in &shapes {
                let g = s.gradient(&p);
                prop_assert!((g.norm() - 1.0).abs() < 1e-12);
                // Finite differences only where a ball of radius 1e-3 around p stays on one
                // side of the medial axis: check that the field is locally linear.
                let h = 1e-6;
                let mut fd = Vec3::zeros();
                for a in 0..3 {
                    let mut e = Vec3::zeros();
                    e[a] = h;
                    fd[a] = (s.signed_distance(&(p + e)) - s.signed_distance(&(p - e))) / (2.0 * h);
                }
                let lin = (s.signed_distance(&(p + g * 1e-3)) - s.signed_distance(&p) - 1e-3).abs();
                if lin < 1e-12 && (fd.norm() - 1.0).abs() < 1e-6 {
                    prop_assert!((fd - g).norm() < 1e-5, "fd {fd:?} vs {g:?} at {p:?}");
                }
            }
        }
    }
}
