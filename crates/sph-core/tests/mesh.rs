//! TriangleMesh: construction errors, transforms, closedness and the winding number.

mod common;

use common::cube;
use sph_core::{MeshError, TriangleMesh, Vec3};

#[test]
fn new_rejects_bad_input() {
    let v = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    assert!(TriangleMesh::new(v.clone(), vec![[0, 1, 2]]).is_ok());
    let e = TriangleMesh::new(v.clone(), vec![[0, 1, 3]]).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::IndexOutOfRange {
                triangle: 0,
                corner: 2,
                index: 3,
                ..
            }
        ),
        "{e}"
    );
    let e = TriangleMesh::new(v.clone(), vec![[0, 1, 1]]).unwrap_err();
    assert!(matches!(e, MeshError::DegenerateTriangle { .. }), "{e}");
    let e = TriangleMesh::<f64>::new(v.clone(), vec![]).unwrap_err();
    assert!(matches!(e, MeshError::Empty { .. }), "{e}");
    let mut bad = v.clone();
    bad[1].y = f64::NAN;
    let e = TriangleMesh::new(bad, vec![[0, 1, 2]]).unwrap_err();
    assert!(e.to_string().contains("vertex 1: coordinate y"), "{e}");
    let m = TriangleMesh::new(v, vec![[0, 1, 2]]).unwrap();
    assert!(m.transformed(-1.0, Vec3::zeros()).is_err());
    assert!(m.transformed(f64::INFINITY, Vec3::zeros()).is_err());
    let t = m.transformed(2.0, Vec3::new(1.0, 0.0, 0.0)).unwrap();
    assert_eq!(t.vertices()[1], Vec3::new(3.0, 0.0, 0.0));
    assert_eq!(t.bounds().max, Vec3::new(3.0, 2.0, 0.0));
}

#[test]
fn closedness_check_names_the_edge() {
    let (m, _) = cube();
    m.check_closed().unwrap();
    TriangleMesh::icosphere(Vec3::zeros(), 1.0f32, 3)
        .unwrap()
        .check_closed()
        .unwrap();
    // A hole: drop triangle 0 = [0, 4, 6].
    let open = TriangleMesh::new(m.vertices().to_vec(), m.triangles()[1..].to_vec()).unwrap();
    let e = open.check_closed().unwrap_err();
    assert!(matches!(e, MeshError::OpenEdge { count: 1, .. }), "{e}");
    assert!(e.to_string().contains("boundary edge"), "{e}");
    // A flipped triangle.
    let mut tris = m.triangles().to_vec();
    tris[3].swap(1, 2);
    let flipped = TriangleMesh::new(m.vertices().to_vec(), tris).unwrap();
    let e = flipped.check_closed().unwrap_err();
    assert!(
        matches!(e, MeshError::InconsistentOrientation { .. }),
        "{e}"
    );
    // A non-manifold edge: a duplicated triangle.
    let mut tris = m.triangles().to_vec();
    tris.push(tris[0]);
    let dup = TriangleMesh::new(m.vertices().to_vec(), tris).unwrap();
    let e = dup.check_closed().unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::OpenEdge {
                count: 3,
                a: 0,
                b: 4,
                triangle: 0,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn winding_number_of_closed_meshes() {
    let (m, _) = cube();
    assert!((m.winding_number(&Vec3::new(0.0, 0.0, 0.5)) - 1.0).abs() < 1e-12);
    assert!(m.winding_number(&Vec3::new(3.0, 0.0, 0.5)).abs() < 1e-12);
    let s = TriangleMesh::icosphere(Vec3::new(1.0, 2.0, 3.0), 0.5f64, 2).unwrap();
    assert!((s.winding_number(&Vec3::new(1.1, 2.0, 3.0)) - 1.0).abs() < 1e-12);
}
