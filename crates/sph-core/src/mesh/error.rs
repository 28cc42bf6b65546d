//! [`MeshError`], the errors of the mesh module.

/// Errors of mesh construction, topology checks and [`GridSdf`](super::GridSdf) building.
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
        /// [`GridSdf::MAX_NODES`](super::GridSdf::MAX_NODES).
        max: usize,
    },
}
