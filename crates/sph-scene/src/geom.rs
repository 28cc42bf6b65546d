//! Small helpers shared by the modules: vectors from arrays, precision casts, axis names and
//! number formatting for messages.

use sph_core::{Real, Vec3};

/// Axis names, for messages.
pub(crate) const AXES: [char; 3] = ['x', 'y', 'z'];

/// `[x, y, z]` as a vector.
pub(crate) fn v3(a: [f64; 3]) -> Vec3<f64> {
    Vec3::new(a[0], a[1], a[2])
}

/// `v` in precision `R`.
pub(crate) fn cast3<R: Real>(v: &Vec3<f64>) -> Vec3<R> {
    Vec3::new(R::of_f64(v.x), R::of_f64(v.y), R::of_f64(v.z))
}

/// `v` for a message.
pub(crate) fn fmt3(v: &Vec3<f64>) -> String {
    format!("({:.6}, {:.6}, {:.6})", v.x, v.y, v.z)
}
