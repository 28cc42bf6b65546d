//! Triangle meshes and their signed distance: an exact (brute-force) evaluation and a
//! [`GridSdf`] sampled on a regular grid.
//!
//! The PBF paper (Macklin & Müller 2013, §8) represents solid boundaries by "signed distance
//! fields stored as volume textures"; [`GridSdf`] is that representation, built the way
//! Bridson's SDFGen / `makelevelset3` does it (Bridson, Marino & Fedkiw 2006 lecture notes
//! *Fluid Simulation*, SIGGRAPH course; C. Batty's and R. Bridson's `SDFGen`):
//!
//! 1. exact point–triangle distances on the grid nodes of each triangle's bounding box grown
//!    by [`GridSdf::EXACT_BAND`] cells (the narrow band), remembering the closest triangle,
//! 2. propagation of the closest triangle to the remaining nodes by sweeping (each node
//!    tries the closest triangle of its already-visited neighbour and keeps it when nearer),
//!    then two rounds in which every node tries the closest triangles of its 26 neighbours
//!    (not in SDFGen, whose sweeps run along the 8 diagonal octants; here the sweeps run
//!    along the axes, which alone left nodes deep inside curved surfaces with a distant
//!    triangle: on an 81,920-triangle icosphere the largest node error falls from 0.77 to
//!    0.45 cells, at 4× the build time, 0.23 → 0.94 s for 10⁶ nodes on 2 threads),
//! 3. the sign from the parity of ray crossings along +x through each row of nodes, with
//!    the robust 2D point-in-triangle test of SDFGen (exact orientation signs with a
//!    simulation-of-simplicity tie break, so a ray through a shared edge or vertex is counted
//!    exactly once).
//!
//! Sign convention as everywhere in the workspace: negative **inside** the solid.

mod error;
mod grid_sdf;
mod predicates;

use std::collections::HashMap;

use crate::{Aabb, Real, Vec3};
use predicates::{point_triangle_distance_sq, solid_angle};

pub use error::MeshError;
pub use grid_sdf::GridSdf;

/// An indexed triangle mesh (length unit of the scene).
///
/// Invariants checked by [`TriangleMesh::new`]: at least one triangle, every index in range,
/// no triangle repeating a vertex, every coordinate finite. Closedness is a separate check,
/// [`TriangleMesh::check_closed`], since loaders may want to report it differently. Triangles
/// of a closed mesh are expected counter-clockwise seen from outside (outward normals), but
/// neither [`TriangleMesh::signed_distance_exact`] nor [`GridSdf`] depends on the orientation.
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh<R: Real> {
    vertices: Vec<Vec3<R>>,
    triangles: Vec<[u32; 3]>,
}

#[inline]
fn v64<R: Real>(v: &Vec3<R>) -> Vec3<f64> {
    Vec3::new(v.x.as_f64(), v.y.as_f64(), v.z.as_f64())
}

fn positive(name: &'static str, v: f64) -> Result<(), MeshError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(MeshError::InvalidParameter {
            name,
            value: v,
            reason: "must be finite and > 0",
        })
    }
}

impl<R: Real> TriangleMesh<R> {
    /// A mesh from vertex positions and triangles (indices into `vertices`); see the type's
    /// invariants.
    pub fn new(vertices: Vec<Vec3<R>>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if vertices.is_empty() || triangles.is_empty() {
            return Err(MeshError::Empty {
                vertices: vertices.len(),
                triangles: triangles.len(),
            });
        }
        for (index, v) in vertices.iter().enumerate() {
            if let Some(a) = (0..3).find(|&a| !v[a].is_finite_value()) {
                return Err(MeshError::NonFiniteVertex {
                    index,
                    axis: ['x', 'y', 'z'][a],
                    value: v[a].as_f64(),
                });
            }
        }
        let n = vertices.len();
        for (t, tri) in triangles.iter().enumerate() {
            for (corner, &index) in tri.iter().enumerate() {
                if index as usize >= n {
                    return Err(MeshError::IndexOutOfRange {
                        triangle: t,
                        corner,
                        index,
                        vertex_count: n,
                    });
                }
            }
            if tri[0] == tri[1] || tri[0] == tri[2] {
                return Err(MeshError::DegenerateTriangle {
                    triangle: t,
                    index: tri[0],
                });
            }
            if tri[1] == tri[2] {
                return Err(MeshError::DegenerateTriangle {
                    triangle: t,
                    index: tri[1],
                });
            }
        }
        Ok(Self {
            vertices,
            triangles,
        })
    }

    /// The closed surface of a box, 12 triangles with outward (counter-clockwise) orientation.
    pub fn cuboid(aabb: &Aabb<R>) -> Result<Self, MeshError> {
        let (lo, hi) = (aabb.min, aabb.max);
        for a in 0..3 {
            positive("cuboid edge length", (hi[a] - lo[a]).as_f64())?;
        }
        let vertices = (0..8)
            .map(|c| {
                Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        // Corner c = x + 2y + 4z; each face as two counter-clockwise triangles seen from outside.
        let quads: [[u32; 4]; 6] = [
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Self::new(vertices, triangles)
    }

    /// A closed, outward-oriented icosphere: an icosahedron inscribed in the sphere of
    /// `radius` around `center`, each triangle split into four `subdivisions` times with the
    /// new vertices projected onto the sphere (`20 · 4^subdivisions` triangles, at most 7
    /// subdivisions).
    pub fn icosphere(center: Vec3<R>, radius: R, subdivisions: u32) -> Result<Self, MeshError> {
        positive("icosphere radius", radius.as_f64())?;
        if subdivisions > 7 {
            return Err(MeshError::InvalidParameter {
                name: "icosphere subdivisions",
                value: subdivisions as f64,
                reason: "must be <= 7",
            });
        }
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let mut verts: Vec<Vec3<f64>> = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .iter()
        .map(|v| Vec3::new(v[0], v[1], v[2]).normalize())
        .collect();
        let mut tris: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut midpoint = |a: u32, b: u32, verts: &mut Vec<Vec3<f64>>| -> u32 {
                let key = (a.min(b), a.max(b));
                *mid.entry(key).or_insert_with(|| {
                    let m = (verts[a as usize] + verts[b as usize]).normalize();
                    verts.push(m);
                    (verts.len() - 1) as u32
                })
            };
            let mut next = Vec::with_capacity(tris.len() * 4);
            for &[a, b, c] in &tris {
                let ab = midpoint(a, b, &mut verts);
                let bc = midpoint(b, c, &mut verts);
                let ca = midpoint(c, a, &mut verts);
                next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            tris = next;
        }
        let r = radius.as_f64();
        let c = v64(&center);
        let vertices = verts
            .iter()
            .map(|v| {
                let p = c + v * r;
                Vec3::new(R::of_f64(p.x), R::of_f64(p.y), R::of_f64(p.z))
            })
            .collect();
        Self::new(vertices, tris)
    }

    /// Vertex positions.
    pub fn vertices(&self) -> &[Vec3<R>] {
        &self.vertices
    }

    /// Triangles as vertex-index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Checks that the mesh is closed: every undirected edge is shared by exactly two
    /// triangles which traverse it in opposite directions (a closed, consistently oriented
    /// 2-manifold along its edges). The error names the first offending edge in triangle
    /// order.
    pub fn check_closed(&self) -> Result<(), MeshError> {
        #[derive(Clone, Copy)]
        struct EdgeInfo {
            count: u32,
            first: u32,
            second: u32,
            first_forward: bool,
            second_forward: bool,
        }
        let key = |a: u32, b: u32| ((a.min(b) as u64) << 32) | a.max(b) as u64;
        let mut edges: HashMap<u64, EdgeInfo> = HashMap::with_capacity(self.triangles.len() * 2);
        for (t, tri) in self.triangles.iter().enumerate() {
            for c in 0..3 {
                let (a, b) = (tri[c], tri[(c + 1) % 3]);
                let fwd = a < b;
                edges
                    .entry(key(a, b))
                    .and_modify(|e| {
                        if e.count == 1 {
                            e.second = t as u32;
                            e.second_forward = fwd;
                        }
                        e.count += 1;
                    })
                    .or_insert(EdgeInfo {
                        count: 1,
                        first: t as u32,
                        second: u32::MAX,
                        first_forward: fwd,
                        second_forward: fwd,
                    });
            }
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            for c in 0..3 {
                let (a, b) = (tri[c], tri[(c + 1) % 3]);
                let e = edges[&key(a, b)];
                if e.count != 2 {
                    return Err(MeshError::OpenEdge {
                        a,
                        b,
                        triangle: t,
                        count: e.count as usize,
                        kind: if e.count < 2 {
                            "boundary edge"
                        } else {
                            "non-manifold edge"
                        },
                    });
                }
                if e.first_forward == e.second_forward {
                    return Err(MeshError::InconsistentOrientation {
                        a,
                        b,
                        first: e.first as usize,
                        second: e.second as usize,
                    });
                }
            }
        }
        Ok(())
    }

    /// The box holding every vertex.
    pub fn bounds(&self) -> Aabb<R> {
        let mut min = self.vertices[0];
        let mut max = self.vertices[0];
        for v in &self.vertices[1..] {
            min = min.inf(v);
            max = max.sup(v);
        }
        Aabb { min, max }
    }

    /// The mesh scaled uniformly by `scale` about the origin, then translated by
    /// `translation` (`p ↦ scale · p + translation`). The scale must be finite and > 0 (a
    /// negative scale would turn the mesh inside out); the result must stay finite.
    pub fn transformed(&self, scale: R, translation: Vec3<R>) -> Result<Self, MeshError> {
        positive("mesh scale", scale.as_f64())?;
        let vertices = self
            .vertices
            .iter()
            .map(|v| v * scale + translation)
            .collect();
        Self::new(vertices, self.triangles.clone())
    }

    fn triangle64(&self, t: usize) -> [Vec3<f64>; 3] {
        let [a, b, c] = self.triangles[t];
        [
            v64(&self.vertices[a as usize]),
            v64(&self.vertices[b as usize]),
            v64(&self.vertices[c as usize]),
        ]
    }

    /// Generalised winding number of the surface around `p` (Jacobson, Kavan & Sorkine-Hornung
    /// 2013): the sum of the signed solid angles of the triangles seen from `p` over `4π`
    /// (van Oosterom & Strackee 1983 formula). For a closed mesh it is the integer number of
    /// times the surface wraps around `p` (±1 inside, 0 outside); for meshes with small holes
    /// it degrades gracefully. Computed in `f64`, `O(triangles)`.
    pub fn winding_number(&self, p: &Vec3<R>) -> f64 {
        let p = v64(p);
        let mut sum = 0.0;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.triangle64(t);
            sum += solid_angle(&(a - p), &(b - p), &(c - p));
        }
        sum / (4.0 * std::f64::consts::PI)
    }

    /// Exact signed distance from `p` to the surface (brute force over all triangles, in
    /// `f64`, `O(triangles)`; the oracle for [`GridSdf`]). The magnitude is the distance to the
    /// nearest triangle; the sign is negative where the absolute generalised
    /// [winding number](TriangleMesh::winding_number) exceeds ½ (inside), so it does not
    /// depend on the orientation of the triangles. Points on the surface give 0.
    pub fn signed_distance_exact(&self, p: &Vec3<R>) -> R {
        let q = v64(p);
        let mut best = f64::INFINITY;
        for t in 0..self.triangles.len() {
            let tri = self.triangle64(t);
            best = best.min(point_triangle_distance_sq(&q, &tri));
        }
        let d = best.sqrt();
        let inside = self.winding_number(p).abs() > 0.5;
        R::of_f64(if inside { -d } else { d })
    }
}
