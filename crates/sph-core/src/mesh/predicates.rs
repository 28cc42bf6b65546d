//! Geometric predicates on triangles, in `f64`: point–triangle distance, the signed solid
//! angle behind the winding number, and SDFGen's robust 2D orientation and point-in-triangle
//! tests used for ray-crossing parity.

use crate::Vec3;

/// Signed solid angle of the triangle with corners `a`, `b`, `c` (relative to the viewpoint)
/// seen from the origin, in steradians (van Oosterom & Strackee 1983): positive when the
/// corners run counter-clockwise seen from the origin.
#[inline]
pub(super) fn solid_angle(a: &Vec3<f64>, b: &Vec3<f64>, c: &Vec3<f64>) -> f64 {
    let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
    let num = a.dot(&b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * num.atan2(den)
}

/// Squared distance from `p` to the triangle `t` (Ericson, *Real-Time Collision Detection*,
/// §5.1.5, closest point by Voronoi regions).
pub(super) fn point_triangle_distance_sq(p: &Vec3<f64>, t: &[Vec3<f64>; 3]) -> f64 {
    let (a, b, c) = (t[0], t[1], t[2]);
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm_squared();
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (ap - ab * v).norm_squared();
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (ap - ac * w).norm_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (bp - (c - b) * w).norm_squared();
    }
    let denom = 1.0 / (va + vb + vc);
    if !denom.is_finite() {
        // Degenerate (zero-area) triangle: the nearest of its three edges.
        let seg = |s: Vec3<f64>, e: Vec3<f64>| {
            let d = e - s;
            let l = d.norm_squared();
            let u = if l > 0.0 {
                ((p - s).dot(&d) / l).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - (s + d * u)).norm_squared()
        };
        return seg(a, b).min(seg(b, c)).min(seg(c, a));
    }
    let v = vb * denom;
    let w = vc * denom;
    (ap - ab * v - ac * w).norm_squared()
}

/// Twice the signed area of the 2D triangle `(0,0)–(x1,y1)–(x2,y2)` and its sign, with
/// SDFGen's simulation-of-simplicity tie break for exact zeros, so that the sign is
/// antisymmetric under swapping the two points and only 0 when they coincide.
#[inline]
fn orientation(x1: f64, y1: f64, x2: f64, y2: f64) -> (i32, f64) {
    let area = y1 * x2 - x1 * y2;
    let s = if area > 0.0 {
        1
    } else if area < 0.0 {
        -1
    } else if y2 > y1 {
        1
    } else if y2 < y1 {
        -1
    } else if x1 > x2 {
        1
    } else if x1 < x2 {
        -1
    } else {
        0
    };
    (s, area)
}

/// Robust test of `(x0,y0)` in the 2D triangle `(x1,y1),(x2,y2),(x3,y3)` (SDFGen's
/// `point_in_triangle_2d`); on success the barycentric coordinates of the point.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(super) fn point_in_triangle_2d(
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    x2: f64,
    y2: f64,
    x3: f64,
    y3: f64,
) -> Option<[f64; 3]> {
    let (x1, x2, x3) = (x1 - x0, x2 - x0, x3 - x0);
    let (y1, y2, y3) = (y1 - y0, y2 - y0, y3 - y0);
    let (sa, a) = orientation(x2, y2, x3, y3);
    if sa == 0 {
        return None;
    }
    let (sb, b) = orientation(x3, y3, x1, y1);
    if sb != sa {
        return None;
    }
    let (sc, c) = orientation(x1, y1, x2, y2);
    if sc != sa {
        return None;
    }
    let sum = a + b + c;
    if sum == 0.0 {
        // All three areas are exact zeros with matching tie-break signs: the projected
        // triangle is degenerate; count the crossing at its first vertex.
        return Some([1.0, 0.0, 0.0]);
    }
    Some([a / sum, b / sum, c / sum])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [Vec3<f64>; 3] {
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ]
    }

    #[test]
    fn point_triangle_distance_in_every_region() {
        let t = tri();
        let d = |x: f64, y: f64, z: f64| point_triangle_distance_sq(&Vec3::new(x, y, z), &t);
        assert_eq!(d(0.5, 0.5, 3.0), 9.0); // face
        assert_eq!(d(-1.0, -1.0, 0.0), 2.0); // vertex a
        assert_eq!(d(3.0, 0.0, 1.0), 2.0); // vertex b
        assert_eq!(d(0.0, 4.0, 0.0), 4.0); // vertex c
        assert_eq!(d(1.0, -2.0, 0.0), 4.0); // edge ab
        assert_eq!(d(-3.0, 1.0, 0.0), 9.0); // edge ca
        assert!((d(2.0, 2.0, 0.0) - 2.0).abs() < 1e-15); // edge bc
                                                         // A degenerate (collinear) triangle: the distance to its segment.
        let flat = [t[0], t[1], Vec3::new(1.0, 0.0, 0.0)];
        assert_eq!(
            point_triangle_distance_sq(&Vec3::new(1.5, 1.0, 0.0), &flat),
            1.0
        );
    }

    #[test]
    fn solid_angle_of_a_face_seen_from_a_cube_centre() {
        // One of the 12 triangles of a cube around the origin subtends 4π/12 (by symmetry,
        // two triangles per face of 4π/6).
        let a = Vec3::new(-1.0, -1.0, 1.0);
        let b = Vec3::new(1.0, -1.0, 1.0);
        let c = Vec3::new(1.0, 1.0, 1.0);
        let w = solid_angle(&a, &b, &c);
        assert!((w - 4.0 * std::f64::consts::PI / 12.0).abs() < 1e-12, "{w}");
        assert!((solid_angle(&a, &c, &b) + w).abs() < 1e-15);
    }

    #[test]
    fn orientation_is_antisymmetric_with_ties_broken() {
        for (x1, y1, x2, y2) in [
            (1.0, 0.0, 0.0, 1.0),
            (1.0, 1.0, 2.0, 2.0),
            (0.0, 0.0, 3.0, 0.0),
        ] {
            let (s, a) = orientation(x1, y1, x2, y2);
            let (t, b) = orientation(x2, y2, x1, y1);
            assert_eq!((s, a), (-t, -b));
            assert_ne!(s, 0);
        }
        assert_eq!(orientation(1.0, 2.0, 1.0, 2.0).0, 0);
    }

    #[test]
    fn a_point_on_a_shared_edge_or_vertex_is_in_exactly_one_triangle() {
        // The square [0, 2]² as a counter-clockwise fan of four triangles around (1, 1):
        // points on the shared edges and on the shared centre vertex are counted once.
        let fan = [
            [(0.0, 0.0), (2.0, 0.0)],
            [(2.0, 0.0), (2.0, 2.0)],
            [(2.0, 2.0), (0.0, 2.0)],
            [(0.0, 2.0), (0.0, 0.0)],
        ];
        for (x, y) in [
            (1.0, 1.0),
            (0.5, 0.5),
            (1.5, 0.5),
            (1.5, 1.5),
            (0.25, 1.75),
            (1.0, 0.5),
        ] {
            let n = fan
                .iter()
                .filter(|[(x1, y1), (x2, y2)]| {
                    point_in_triangle_2d(x, y, *x1, *y1, *x2, *y2, 1.0, 1.0).is_some()
                })
                .count();
            assert_eq!(n, 1, "({x}, {y})");
        }
        let first = |x: f64, y: f64| point_in_triangle_2d(x, y, 0.0, 0.0, 2.0, 0.0, 2.0, 2.0);
        let w = first(1.5, 0.5).unwrap();
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!(first(-1.0, 0.5).is_none());
    }
}
