//! Independent f64 formulas for the solvers' oracle tests: 3-vectors as arrays and the Müller et al. (2003)
//! kernels written out from their closed forms (not through `sph-kernels`).

use std::f64::consts::PI;

use sph_core::Vec3;

/// A 3-vector of the oracles.
pub type V = [f64; 3];

/// `a − b`.
pub fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// `a + b`.
pub fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// `k a`.
pub fn scale(a: V, k: f64) -> V {
    [a[0] * k, a[1] * k, a[2] * k]
}
/// `a · b`.
pub fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// `a × b`.
pub fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// `|a|`.
pub fn norm(a: V) -> f64 {
    dot(a, a).sqrt()
}
/// The components of `p`.
pub fn to_v(p: &Vec3<f64>) -> V {
    [p.x, p.y, p.z]
}

/// Poly6, `315/(64π h⁹)(h² − r²)³` for `r < h`.
pub fn poly6(r: V, h: f64) -> f64 {
    let r2 = dot(r, r);
    if r2 >= h * h {
        0.0
    } else {
        315.0 / (64.0 * PI * h.powi(9)) * (h * h - r2).powi(3)
    }
}

/// Spiky gradient, `−45/(π h⁶)(h − r)² r̂` (zero at r = 0 and r >= h).
pub fn spiky_grad(r: V, h: f64) -> V {
    let l = norm(r);
    if l == 0.0 || l >= h {
        [0.0; 3]
    } else {
        scale(r, -45.0 / (PI * h.powi(6)) * (h - l).powi(2) / l)
    }
}
