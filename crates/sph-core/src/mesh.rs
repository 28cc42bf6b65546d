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

use std::collections::HashMap;

use rayon::prelude::*;

use crate::{Aabb, Real, SampledGrid, Sdf, Vec3};

/// Errors of mesh construction, topology checks and [`GridSdf`] building.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The mesh has no triangles (or no vertices).
    #[error("mesh is empty: {vertices} vertices, {triangles} triangles")]
    Empty {
        /// Number of vertices.
        vertices: usize,
        /// Number of triangles.
        triangles: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle}: corner {corner} refers to vertex {index}, but there are only {vertex_count} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// Corner (0, 1 or 2).
        corner: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A triangle uses the same vertex twice.
    #[error("triangle {triangle} is degenerate: vertex {index} appears twice")]
    DegenerateTriangle {
        /// Triangle index.
        triangle: usize,
        /// The repeated vertex.
        index: u32,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {index}: coordinate {axis} is not finite ({value})")]
    NonFiniteVertex {
        /// Vertex index.
        index: usize,
        /// `'x'`, `'y'` or `'z'`.
        axis: char,
        /// The offending value.
        value: f64,
    },
    /// An undirected edge is not shared by exactly two triangles (1: a boundary edge, a hole;
    /// more than 2: a non-manifold edge).
    #[error("mesh is not closed: edge ({a}, {b}) of triangle {triangle} is shared by {count} triangle(s), a closed mesh needs exactly 2 ({kind})")]
    OpenEdge {
        /// First vertex of the edge (as it appears in `triangle`).
        a: u32,
        /// Second vertex of the edge.
        b: u32,
        /// First triangle (in index order) containing the edge.
        triangle: usize,
        /// Number of triangles containing the edge.
        count: usize,
        /// `"boundary edge"` or `"non-manifold edge"`.
        kind: &'static str,
    },
    /// An edge is shared by two triangles that traverse it in the same direction, i.e. the
    /// triangles are not consistently oriented.
    #[error("mesh is not closed: edge ({a}, {b}) is traversed in the same direction by triangles {first} and {second} (inconsistent orientation)")]
    InconsistentOrientation {
        /// First vertex of the edge.
        a: u32,
        /// Second vertex of the edge.
        b: u32,
        /// First triangle containing the edge.
        first: usize,
        /// Second triangle containing the edge.
        second: usize,
    },
    /// A scalar argument is out of range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Name of the argument.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// The requested grid would have too many nodes.
    #[error("signed distance grid of {nx} x {ny} x {nz} nodes exceeds the maximum of {max} nodes (cell size too small for the mesh)")]
    GridTooLarge {
        /// Nodes along x.
        nx: usize,
        /// Nodes along y.
        ny: usize,
        /// Nodes along z.
        nz: usize,
        /// [`GridSdf::MAX_NODES`].
        max: usize,
    },
}

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
            let (a, b, c) = (a - p, b - p, c - p);
            let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
            let num = a.dot(&b.cross(&c));
            let den = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
            sum += 2.0 * num.atan2(den);
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

/// Squared distance from `p` to the triangle `t` (Ericson, *Real-Time Collision Detection*,
/// §5.1.5, closest point by Voronoi regions).
fn point_triangle_distance_sq(p: &Vec3<f64>, t: &[Vec3<f64>; 3]) -> f64 {
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
fn point_in_triangle_2d(
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

/// Signed distance of a closed [`TriangleMesh`] sampled on a regular grid of nodes and
/// interpolated trilinearly: the "signed distance fields stored as volume textures" of the PBF
/// paper (§8, after Bridson et al. 2006), built as Bridson's SDFGen (`makelevelset3`) does
/// (see the [module documentation](self)).
///
/// * The grid covers the mesh bounds grown by `margin` on every side; nodes are `cell` apart,
///   the first at the lower corner.
/// * [`Sdf::signed_distance`] inside the grid box: trilinear interpolation of the node values.
///   For node values equal to the exact distance, the interpolation error of a 1-Lipschitz
///   function is at most `Σ_c w_c |p − c| ≤ (Σ_c w_c |p − c|²)^{1/2} ≤ (√3/2)·cell`; node
///   values away from the narrow band come from sweeping and are distances to *a* triangle,
///   i.e. never below the exact value (exact along straight sweep paths, see the tests for
///   measured errors).
/// * Outside the grid box: the distance from `p` to the box plus the interpolated value at
///   the nearest point `q` of the box, `|p − q| + φ(q)`. By the triangle inequality this is an
///   upper bound of the true distance, exact when the nearest surface point lies along the
///   outward direction, and positive (with a margin > 0 the boundary values are positive).
/// * [`Sdf::gradient`]: the analytic gradient of the trilinear interpolant (plus the unit
///   direction `(p − q)/|p − q|` outside the box), normalised; `(0, 1, 0)` where it vanishes.
///
/// The sign comes from ray-crossing parity, which assumes a closed mesh
/// ([`TriangleMesh::check_closed`]); with holes, rows of nodes whose ray passes through a hole
/// get wrong signs. [`Inverted`](crate::Inverted)`<GridSdf>` turns the solid into a container.
#[derive(Debug, Clone)]
pub struct GridSdf<R: Real> {
    grid: SampledGrid<R>,
    surface_bounds: Aabb<R>,
}

const NO_TRI: u32 = u32::MAX;
/// Rounds of the 26-neighbour relaxation after the sweeps of [`build_grid`].
const RELAX_ROUNDS: usize = 2;

impl<R: Real> GridSdf<R> {
    /// Largest number of grid nodes [`GridSdf::new`] accepts (64 Mi nodes,
    /// [`SampledGrid::MAX_NODES`]).
    pub const MAX_NODES: usize = SampledGrid::<R>::MAX_NODES;
    /// Half-width, in cells, of the band around each triangle's bounding box where node
    /// distances are computed exactly (SDFGen's `exact_band`, 1 there).
    pub const EXACT_BAND: usize = 1;

    /// Samples the signed distance of `mesh` with node spacing `cell` (> 0) over the mesh
    /// bounds grown by `margin` (≥ 0; use at least a cell or two so that the field outside the
    /// mesh is represented) on every side. Errors for invalid arguments and for grids of more
    /// than [`GridSdf::MAX_NODES`] nodes.
    pub fn new(mesh: &TriangleMesh<R>, cell: R, margin: R) -> Result<Self, MeshError> {
        let dx = cell.as_f64();
        positive("grid cell size", dx)?;
        let margin = margin.as_f64();
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(MeshError::InvalidParameter {
                name: "grid margin",
                value: margin,
                reason: "must be finite and >= 0",
            });
        }
        let b = mesh.bounds();
        let (lo, hi) = (v64(&b.min), v64(&b.max));
        let origin = lo - Vec3::repeat(margin);
        let mut dims = [0usize; 3];
        for a in 0..3 {
            let n = ((hi[a] - lo[a] + 2.0 * margin) / dx).ceil() + 1.0;
            if !(n.is_finite() && n <= Self::MAX_NODES as f64) {
                return Err(MeshError::GridTooLarge {
                    nx: if a == 0 { usize::MAX } else { dims[0] },
                    ny: if a == 1 { usize::MAX } else { dims[1] },
                    nz: if a == 2 { usize::MAX } else { dims[2] },
                    max: Self::MAX_NODES,
                });
            }
            dims[a] = (n as usize).max(2);
        }
        let total = dims[0] as f64 * dims[1] as f64 * dims[2] as f64;
        if total > Self::MAX_NODES as f64 {
            return Err(MeshError::GridTooLarge {
                nx: dims[0],
                ny: dims[1],
                nz: dims[2],
                max: Self::MAX_NODES,
            });
        }
        let (phi, _) = build_grid(mesh, origin, dx, dims);
        let values = phi.into_iter().map(R::of_f64).collect();
        Ok(Self {
            grid: SampledGrid::from_checked_parts(origin, dx, dims, values),
            surface_bounds: b,
        })
    }

    /// The sampled grid of node values (signed distances) behind this field.
    pub fn grid(&self) -> &SampledGrid<R> {
        &self.grid
    }

    /// Node spacing (length).
    pub fn cell_size(&self) -> R {
        R::of_f64(self.grid.cell_size())
    }

    /// Number of nodes along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.grid.dims()
    }

    /// The box spanned by the grid nodes.
    pub fn grid_box(&self) -> Aabb<R> {
        self.grid.grid_box()
    }

    /// Stored signed distance at node `(i, j, k)` (`None` out of range).
    pub fn node_value(&self, i: usize, j: usize, k: usize) -> Option<R> {
        self.grid.node_value(i, j, k)
    }

    /// Position of node `(i, j, k)`.
    pub fn node_position(&self, i: usize, j: usize, k: usize) -> Vec3<R> {
        let p = self.grid.node_position(i, j, k);
        Vec3::new(R::of_f64(p.x), R::of_f64(p.y), R::of_f64(p.z))
    }
}

impl<R: Real> Sdf<R> for GridSdf<R> {
    fn signed_distance(&self, p: &Vec3<R>) -> R {
        let (v, _, off) = self.grid.sample_clamped(p);
        R::of_f64(v + off.norm())
    }

    fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
        let (_, mut g, off) = self.grid.sample_clamped(p);
        let n = off.norm();
        if n > 0.0 {
            for a in 0..3 {
                if off[a] != 0.0 {
                    // Clamped axis: the trilinear field does not vary along it; the distance
                    // to the box does.
                    g[a] = 0.0;
                }
            }
            g += off / n;
        }
        let len = g.norm();
        if len > 0.0 && len.is_finite() {
            g /= len;
            Vec3::new(R::of_f64(g.x), R::of_f64(g.y), R::of_f64(g.z))
        } else {
            Vec3::new(R::zero(), R::one(), R::zero())
        }
    }

    fn bounds(&self) -> Option<Aabb<R>> {
        Some(self.surface_bounds)
    }
}

/// The SDFGen construction on nodes `origin + (i, j, k) · dx`: returns the signed node values
/// and the closest triangle of each node.
fn build_grid<R: Real>(
    mesh: &TriangleMesh<R>,
    origin: Vec3<f64>,
    dx: f64,
    dims: [usize; 3],
) -> (Vec<f64>, Vec<u32>) {
    let [nx, ny, nz] = dims;
    let plane = nx * ny;
    let ntri = mesh.triangles.len();
    // Triangle vertices in grid coordinates (cells) and in length units.
    let tris: Vec<[Vec3<f64>; 3]> = (0..ntri).map(|t| mesh.triangle64(t)).collect();
    let grid_tris: Vec<[Vec3<f64>; 3]> =
        tris.iter().map(|t| t.map(|v| (v - origin) / dx)).collect();
    let node = |i: usize, j: usize, k: usize| {
        origin + Vec3::new(i as f64 * dx, j as f64 * dx, k as f64 * dx)
    };

    // Bin triangles by the k-planes of their (band-grown) bounding boxes, for plane-parallel
    // work without write conflicts.
    let band = GridSdf::<R>::EXACT_BAND as f64;
    let range = |lo: f64, hi: f64, n: usize, grow: f64| -> Option<(usize, usize)> {
        let a = (lo - grow).ceil().max(0.0);
        let b = (hi + grow).floor().min((n - 1) as f64);
        (a <= b).then_some((a as usize, b as usize))
    };
    let mut per_plane: Vec<Vec<u32>> = vec![Vec::new(); nz];
    for (t, g) in grid_tris.iter().enumerate() {
        let lo = g[0].z.min(g[1].z).min(g[2].z);
        let hi = g[0].z.max(g[1].z).max(g[2].z);
        if let Some((k0, k1)) = range(lo, hi, nz, band) {
            for list in &mut per_plane[k0..=k1] {
                list.push(t as u32);
            }
        }
    }

    let far = (nx + ny + nz) as f64 * dx;
    let mut phi = vec![far; plane * nz];
    let mut closest = vec![NO_TRI; plane * nz];
    let mut crossings = vec![0u32; plane * nz];

    // 1. Exact distances in the narrow band, and 3. ray-crossing counts along +x (both
    //    per k-plane).
    phi.par_chunks_mut(plane)
        .zip(closest.par_chunks_mut(plane))
        .zip(crossings.par_chunks_mut(plane))
        .enumerate()
        .for_each(|(k, ((phi_k, cl_k), cross_k))| {
            for &t in &per_plane[k] {
                let g = &grid_tris[t as usize];
                let lo = g[0].inf(&g[1]).inf(&g[2]);
                let hi = g[0].sup(&g[1]).sup(&g[2]);
                let (Some((i0, i1)), Some((j0, j1))) =
                    (range(lo.x, hi.x, nx, band), range(lo.y, hi.y, ny, band))
                else {
                    continue;
                };
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        let d =
                            point_triangle_distance_sq(&node(i, j, k), &tris[t as usize]).sqrt();
                        let n = i + nx * j;
                        if d < phi_k[n] || (d == phi_k[n] && t < cl_k[n]) {
                            phi_k[n] = d;
                            cl_k[n] = t;
                        }
                    }
                }
                // Ray crossings: only triangles whose z-range (without band) holds k.
                let kf = k as f64;
                if kf < lo.z || kf > hi.z {
                    continue;
                }
                let Some((j0, j1)) = range(lo.y, hi.y, ny, 0.0) else {
                    continue;
                };
                for j in j0..=j1 {
                    if let Some([a, b, c]) = point_in_triangle_2d(
                        j as f64, kf, g[0].y, g[0].z, g[1].y, g[1].z, g[2].y, g[2].z,
                    ) {
                        let fi = a * g[0].x + b * g[1].x + c * g[2].x;
                        // The crossing lies in (i_interval − 1, i_interval]: it flips the
                        // parity of nodes i >= i_interval.
                        let iv = fi.ceil();
                        if iv < 0.0 {
                            cross_k[nx * j] += 1;
                        } else if iv < nx as f64 {
                            cross_k[iv as usize + nx * j] += 1;
                        }
                    }
                }
            }
        });

    // 2. Propagate closest triangles by axis-wise sweeps (two rounds, both directions along
    //    each axis; each node tries the closest triangle of the neighbour behind it).
    let try_tri = |phi: &mut f64, cl: &mut u32, cand: u32, p: Vec3<f64>| {
        if cand != NO_TRI && cand != *cl {
            let d = point_triangle_distance_sq(&p, &tris[cand as usize]).sqrt();
            if d < *phi {
                *phi = d;
                *cl = cand;
            }
        }
    };
    for _round in 0..2 {
        // x: rows are contiguous.
        phi.par_chunks_mut(nx)
            .zip(closest.par_chunks_mut(nx))
            .enumerate()
            .for_each(|(row, (ph, cl))| {
                let (j, k) = (row % ny, row / ny);
                for i in 1..nx {
                    let cand = cl[i - 1];
                    try_tri(&mut ph[i], &mut cl[i], cand, node(i, j, k));
                }
                for i in (0..nx - 1).rev() {
                    let cand = cl[i + 1];
                    try_tri(&mut ph[i], &mut cl[i], cand, node(i, j, k));
                }
            });
        // y: within each k-plane.
        phi.par_chunks_mut(plane)
            .zip(closest.par_chunks_mut(plane))
            .enumerate()
            .for_each(|(k, (ph, cl))| {
                for j in 1..ny {
                    for i in 0..nx {
                        let cand = cl[i + nx * (j - 1)];
                        let n = i + nx * j;
                        try_tri(&mut ph[n], &mut cl[n], cand, node(i, j, k));
                    }
                }
                for j in (0..ny - 1).rev() {
                    for i in 0..nx {
                        let cand = cl[i + nx * (j + 1)];
                        let n = i + nx * j;
                        try_tri(&mut ph[n], &mut cl[n], cand, node(i, j, k));
                    }
                }
            });
        // z: columns gathered per j-slab, swept, written back.
        let slabs: Vec<(Vec<f64>, Vec<u32>)> = (0..ny)
            .into_par_iter()
            .map(|j| {
                let mut ph = vec![0.0; nx * nz];
                let mut cl = vec![NO_TRI; nx * nz];
                for k in 0..nz {
                    let src = nx * j + plane * k;
                    ph[nx * k..nx * (k + 1)].copy_from_slice(&phi[src..src + nx]);
                    cl[nx * k..nx * (k + 1)].copy_from_slice(&closest[src..src + nx]);
                }
                for k in 1..nz {
                    for i in 0..nx {
                        let cand = cl[i + nx * (k - 1)];
                        let n = i + nx * k;
                        try_tri(&mut ph[n], &mut cl[n], cand, node(i, j, k));
                    }
                }
                for k in (0..nz - 1).rev() {
                    for i in 0..nx {
                        let cand = cl[i + nx * (k + 1)];
                        let n = i + nx * k;
                        try_tri(&mut ph[n], &mut cl[n], cand, node(i, j, k));
                    }
                }
                (ph, cl)
            })
            .collect();
        for (j, (ph, cl)) in slabs.into_iter().enumerate() {
            for k in 0..nz {
                let dst = nx * j + plane * k;
                phi[dst..dst + nx].copy_from_slice(&ph[nx * k..nx * (k + 1)]);
                closest[dst..dst + nx].copy_from_slice(&cl[nx * k..nx * (k + 1)]);
            }
        }
    }

    // 2b. Relaxation: the axis-wise sweeps carry triangles along the axes only, which leaves
    //    nodes deep inside curved surfaces with a triangle that is not the closest (measured
    //    on an icosphere: gradient directions 20–35° off the radius 3–14 cells inside). Each
    //    node also tries the closest triangles of its 26 neighbours, from the previous
    //    round's assignment (Jacobi, so the result does not depend on the thread count).
    for _round in 0..RELAX_ROUNDS {
        let prev = closest.clone();
        phi.par_chunks_mut(nx)
            .zip(closest.par_chunks_mut(nx))
            .enumerate()
            .for_each(|(row, (ph, cl))| {
                let (j, k) = (row % ny, row / ny);
                let (j0, j1) = (j.saturating_sub(1), (j + 1).min(ny - 1));
                let (k0, k1) = (k.saturating_sub(1), (k + 1).min(nz - 1));
                for i in 0..nx {
                    let p = node(i, j, k);
                    let (i0, i1) = (i.saturating_sub(1), (i + 1).min(nx - 1));
                    for kk in k0..=k1 {
                        for jj in j0..=j1 {
                            let base = plane * kk + nx * jj;
                            for &cand in &prev[base + i0..=base + i1] {
                                try_tri(&mut ph[i], &mut cl[i], cand, p);
                            }
                        }
                    }
                }
            });
    }

    // 3. (continued) Parity along each row: odd = inside = negative.
    phi.par_chunks_mut(nx)
        .zip(crossings.par_chunks(nx))
        .for_each(|(ph, cr)| {
            let mut total = 0u32;
            for i in 0..nx {
                total += cr[i];
                if total % 2 == 1 {
                    ph[i] = -ph[i];
                }
            }
        });
    (phi, closest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BoxSdf, Inverted, Sphere};
    use proptest::prelude::*;
    use std::sync::OnceLock;

    fn cube() -> (TriangleMesh<f64>, BoxSdf<f64>) {
        let b = Aabb::new(Vec3::new(-0.5, -0.25, 0.1), Vec3::new(0.7, 0.45, 0.9)).unwrap();
        (TriangleMesh::cuboid(&b).unwrap(), BoxSdf::new(b).unwrap())
    }

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

    /// Icosphere of radius r with 4 subdivisions: the facets lie between the inscribed
    /// radius r·cos θ and r; the largest edge angle is below 0.08 rad, so the distance to the
    /// mesh differs from the sphere's by at most r(1 − cos 0.08) < 0.0032 r.
    const SPHERE_CENTER: Vec3<f64> = Vec3::new(0.2, -0.1, 0.3);

    fn sphere_mesh() -> &'static (TriangleMesh<f64>, Sphere<f64>) {
        static S: OnceLock<(TriangleMesh<f64>, Sphere<f64>)> = OnceLock::new();
        S.get_or_init(|| {
            let c = SPHERE_CENTER;
            (
                TriangleMesh::icosphere(c, 0.6, 4).unwrap(),
                Sphere::new(c, 0.6).unwrap(),
            )
        })
    }

    fn cube_grid() -> &'static GridSdf<f64> {
        static G: OnceLock<GridSdf<f64>> = OnceLock::new();
        G.get_or_init(|| GridSdf::new(&cube().0, 0.05, 0.2).unwrap())
    }

    fn sphere_grid() -> &'static GridSdf<f64> {
        static G: OnceLock<GridSdf<f64>> = OnceLock::new();
        G.get_or_init(|| GridSdf::new(&sphere_mesh().0, 0.04, 0.16).unwrap())
    }

    #[test]
    fn grid_nodes_have_correct_signs_and_bounded_errors() {
        // Node values against the exact oracle, on every node of the cube grid.
        let (m, b) = cube();
        let g = cube_grid();
        let [nx, ny, nz] = g.dims();
        let mut max_err: f64 = 0.0;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = g.node_position(i, j, k);
                    let v = g.node_value(i, j, k).unwrap();
                    let exact = b.signed_distance(&p);
                    assert!((m.signed_distance_exact(&p) - exact).abs() < 1e-12);
                    if exact.abs() > 1e-12 {
                        assert_eq!(v < 0.0, exact < 0.0, "node {i},{j},{k}: {v} vs {exact}");
                    }
                    max_err = max_err.max((v - exact).abs());
                }
            }
        }
        // The box's closest features are few; sweeping finds them exactly.
        assert!(max_err < 1e-12, "cube grid node error {max_err}");
    }

    #[test]
    fn inverted_grid_is_a_container() {
        let g = Inverted(cube_grid().clone());
        let inside = Vec3::new(0.0, 0.0, 0.5);
        assert!(g.signed_distance(&inside) > 0.2);
        let n = g.gradient(&Vec3::new(0.6, 0.0, 0.5));
        assert!((n - Vec3::new(-1.0, 0.0, 0.0)).norm() < 1e-9, "{n:?}");
        assert!(g.signed_distance(&Vec3::new(5.0, 0.0, 0.5)) < -4.0);
    }

    #[test]
    fn outside_the_grid_box_is_an_upper_bound_with_the_right_sign() {
        let (_, b) = cube();
        let g = cube_grid();
        for p in [
            Vec3::new(3.0, 0.1, 0.5),
            Vec3::new(-2.0, 4.0, -3.0),
            Vec3::new(0.1, 0.1, 7.0),
        ] {
            let (v, e) = (g.signed_distance(&p), b.signed_distance(&p));
            assert!(v >= e - 1e-9 && v <= e * 1.5, "{v} vs {e}");
            let n = g.gradient(&p);
            assert!((n.norm() - 1.0).abs() < 1e-12);
            assert!(n.dot(&b.gradient(&p)) > 0.8, "{n:?}");
        }
        // Along the outward axis the value is exact.
        let p = Vec3::new(3.0, 0.1, 0.5);
        assert!((g.signed_distance(&p) - b.signed_distance(&p)).abs() < 1e-9);
    }

    #[test]
    fn grid_parameters_are_checked() {
        let (m, _) = cube();
        assert!(GridSdf::new(&m, 0.0, 0.1).is_err());
        assert!(GridSdf::new(&m, f64::NAN, 0.1).is_err());
        assert!(GridSdf::new(&m, 0.1, -0.1).is_err());
        let e = GridSdf::new(&m, 1e-5, 0.1).unwrap_err();
        assert!(matches!(e, MeshError::GridTooLarge { .. }), "{e}");
    }

    #[test]
    fn f32_grid_matches_f64() {
        let m32 = TriangleMesh::icosphere(Vec3::new(0.0f32, 0.0, 0.0), 1.0, 2).unwrap();
        let m64 = TriangleMesh::icosphere(Vec3::new(0.0f64, 0.0, 0.0), 1.0, 2).unwrap();
        let g32 = GridSdf::new(&m32, 0.1, 0.3).unwrap();
        let g64 = GridSdf::new(&m64, 0.1, 0.3).unwrap();
        for p in [[0.3, 0.2, -0.1], [1.2, 0.0, 0.5], [-0.7, 0.7, 0.1]] {
            let a = g32.signed_distance(&Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32));
            let b = g64.signed_distance(&Vec3::new(p[0], p[1], p[2]));
            assert!((a as f64 - b).abs() < 1e-5, "{a} vs {b}");
        }
    }

    /// A 81 920-triangle icosphere on a 100³-node grid: build time (printed; asserted under a
    /// generous 10 s for a loaded 2-core machine, ~0.1–0.3 s in release when idle) and the
    /// maximum error against the exact oracle at 300 pseudo-random points of the grid box.
    #[test]
    fn large_mesh_build_time_and_error() {
        let c = Vec3::new(0.0, 0.0, 0.0);
        let m = TriangleMesh::icosphere(c, 1.0f64, 6).unwrap();
        assert_eq!(m.triangles().len(), 81_920);
        let cell = 2.2 / 99.0;
        let t0 = std::time::Instant::now();
        let g = GridSdf::new(&m, cell, 0.1).unwrap();
        let build = t0.elapsed().as_secs_f64();
        let gb = g.grid_box();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut max_err, mut max_band_err) = (0.0f64, 0.0f64);
        for _ in 0..300 {
            let p = Vec3::new(next(), next(), next());
            let p = gb.min + p.component_mul(&gb.extent());
            let exact = m.signed_distance_exact(&p);
            let v = g.signed_distance(&p);
            max_err = max_err.max((v - exact).abs());
            if exact.abs() < 2.0 * cell {
                max_band_err = max_band_err.max((v - exact).abs());
            }
            if exact.abs() > cell {
                assert_eq!(v < 0.0, exact < 0.0, "{p:?}");
            }
        }
        println!(
            "icosphere(6): {} triangles, grid {:?}, build {build:.3} s, max |grid - exact| = {max_err:.2e} = {:.3} cells (within 2 cells of the surface: {:.3} cells)",
            m.triangles().len(),
            g.dims(),
            max_err / cell,
            max_band_err / cell
        );
        assert!(max_err <= (0.75f64.sqrt() + 0.1) * cell);
        assert!(build < 10.0, "build took {build} s");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Exact mesh distance equals the analytic box distance; the grid stays within the
        /// trilinear bound (√3/2)·cell of the exact value (plus nothing: the cube's node
        /// values are exact) and has the right sign farther than one cell from the surface.
        #[test]
        fn cube_grid_vs_exact(x in -0.65..0.85f64, y in -0.4..0.6f64, z in -0.05..1.05f64) {
            let (m, b) = cube();
            let g = cube_grid();
            let p = Vec3::new(x, y, z);
            let exact = m.signed_distance_exact(&p);
            prop_assert!((exact - b.signed_distance(&p)).abs() < 1e-12);
            let v = g.signed_distance(&p);
            let tol = 0.75f64.sqrt() * 0.05;
            prop_assert!((v - exact).abs() <= tol, "grid {v} exact {exact}");
            if exact.abs() > 0.05 {
                prop_assert_eq!(v < 0.0, exact < 0.0);
                let n = g.gradient(&p);
                prop_assert!((n.norm() - 1.0).abs() < 1e-9);
            }
        }

        /// Icosphere: exact mesh distance within the facet sagitta (0.0032 r) of the sphere;
        /// grid within (√3/2)·cell + 0.1·cell of the exact value (the extra tenth of a cell
        /// covers swept node values, which are distances to a nearby but not always the
        /// nearest facet), sign right beyond one cell; the gradient points along the radius
        /// (within 18°) except within 6 cells of the centre: the distance is not
        /// differentiable at the centre (the sphere's medial axis), and where the level sets'
        /// radius of curvature ρ is a few cells the trilinear gradient's direction error,
        /// of order cell/ρ, exceeds that angle (measured: 41° at 0–1 cell, 33° at 1–2).
        #[test]
        fn sphere_grid_vs_exact(x in -0.55..0.95f64, y in -0.85..0.65f64, z in -0.45..1.05f64) {
            let (m, s) = sphere_mesh();
            let g = sphere_grid();
            let p = Vec3::new(x, y, z);
            let exact = m.signed_distance_exact(&p);
            prop_assert!((exact - s.signed_distance(&p)).abs() < 0.0032 * 0.6, "{exact}");
            let v = g.signed_distance(&p);
            let cell = 0.04;
            prop_assert!((v - exact).abs() <= (0.75f64.sqrt() + 0.1) * cell, "grid {v} exact {exact}");
            if exact.abs() > cell {
                prop_assert_eq!(v < 0.0, exact < 0.0);
                if (p - SPHERE_CENTER).norm() >= 6.0 * cell {
                    let n = g.gradient(&p);
                    prop_assert!(n.dot(&s.gradient(&p)) > 0.95, "{n:?}");
                }
            }
        }
    }
}
