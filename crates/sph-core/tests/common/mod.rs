//! Fixtures shared by the mesh test files.

use sph_core::{Aabb, BoxSdf, TriangleMesh, Vec3};

/// A closed box mesh and the analytic distance of the same box.
pub fn cube() -> (TriangleMesh<f64>, BoxSdf<f64>) {
    let b = Aabb::new(Vec3::new(-0.5, -0.25, 0.1), Vec3::new(0.7, 0.45, 0.9)).unwrap();
    (TriangleMesh::cuboid(&b).unwrap(), BoxSdf::new(b).unwrap())
}
