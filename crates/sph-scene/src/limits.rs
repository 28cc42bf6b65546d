//! The bounds a scene is checked against: each says what can be built and run on one
//! machine, and every error that refuses a scene by one of them names it.

/// Largest total number of fluid particles a scene may produce (20 M).
pub const MAX_PARTICLES: usize = 20_000_000;

/// Largest number of passive points of granular upscaling (`upscaling_factor` times the
/// particles): 20 M, each carrying a position and a velocity (48 bytes in `f64`, about 1 GB
/// in all, written whole into every checkpoint); beyond it the factor is a typing mistake.
pub const MAX_PASSIVE_POINTS: usize = 20_000_000;

/// Most frames (`duration / frame_dt`) a scene may have: 10 million, 44 hours of 16 ms
/// frames; beyond it the frame length or the duration is a typing mistake.
pub const MAX_FRAMES: f64 = 1e7;

/// Largest number of nodes of a signed distance grid built for a mesh (16 M).
pub const MAX_SDF_NODES: usize = 16 << 20;

/// Largest scene file read (1 MiB): a scene is a page of TOML; a larger file is not one
/// (e.g. `/dev/zero` or a mesh given by mistake) and is refused before it is read.
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 20;

/// Largest OBJ mesh file read (64 MiB, about a million triangles): the mesh is read whole
/// and parsed, which takes several times its size in memory, and its signed distance grid
/// is bounded by [`MAX_SDF_NODES`] anyway. A larger file is refused before it is read.
pub const MAX_MESH_FILE_BYTES: u64 = 64 << 20;
