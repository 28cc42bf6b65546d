//! [`VolumeMapKey`] (everything a volume map depends on) and [`VolumeMapCache`] (a directory
//! of map files named by the SHA-256 of their key).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};
use sph_core::{push_fingerprint, Aabb, Real, Sdf};
use sph_kernels::KernelKind;

use super::options::{Interpolation, VolumeMapOptions};
use super::quadrature::TABLE_INTERVALS;
use crate::error::MapFileProblem;
use crate::SolverError;

/// The version of the volume-map file layout this build reads and writes (see
/// [`VolumeMap::read_file`](super::VolumeMap::read_file)).
pub const FORMAT_VERSION: u32 = 1;

/// Version of the map construction: bump it whenever a change of the build moves any stored
/// value (a quadrature, a tolerance, the node models), so that no cache serves maps of the
/// old construction. 2: closed-form ray intervals for analytic solids
/// ([`Sdf::ray_inside_intervals`](sph_core::Sdf::ray_inside_intervals)).
pub const BUILD_VERSION: u32 = 2;

/// Everything a [`VolumeMap`](super::VolumeMap) depends on, as bytes: the file format and
/// build versions, the precision `R`, the kernel and its support radius, the domain, every
/// [`VolumeMapOptions`] field, the kernel-table resolution and the solid's
/// [`Sdf::fingerprint`]. Two builds with equal keys give bit-identical maps (sequential and
/// parallel builds are bit-identical: each node is computed on its own).
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeMapKey {
    bytes: Vec<u8>,
    kernel: KernelKind,
    support_radius: f64,
}

impl VolumeMapKey {
    /// The key of the map of `solid` for `kernel` with support radius `support_radius` (m)
    /// over `domain` with `options`, or `None` when the solid does not describe itself
    /// ([`Sdf::fingerprint`] returns `false`: such maps are never cached).
    pub fn new<R: Real>(
        solid: &dyn Sdf<R>,
        kernel: KernelKind,
        support_radius: R,
        domain: &Aabb<R>,
        options: &VolumeMapOptions,
    ) -> Option<Self> {
        let mut b = Vec::with_capacity(256);
        push_fingerprint::<f64>(&mut b, "sph-solver volume map", &[]);
        let o = options;
        let interpolation = match o.interpolation {
            Interpolation::NodePlanes => 0.0,
            Interpolation::TrilinearCorrection => 1.0,
        };
        push_fingerprint(
            &mut b,
            "versions, table intervals",
            &[
                FORMAT_VERSION as f64,
                BUILD_VERSION as f64,
                TABLE_INTERVALS as f64,
            ],
        );
        push_fingerprint::<f64>(&mut b, R::NAME, &[]);
        push_fingerprint(&mut b, kernel.name(), &[support_radius]);
        let (lo, hi) = (domain.min, domain.max);
        push_fingerprint(&mut b, "domain", &[lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]);
        push_fingerprint(
            &mut b,
            "options",
            &[
                o.cells_per_support as f64,
                o.polar_directions as f64,
                o.azimuth_directions as f64,
                o.ray_samples as f64,
                o.max_nodes as f64,
                interpolation,
            ],
        );
        push_fingerprint::<f64>(&mut b, "solid", &[]);
        solid.fingerprint(&mut b).then_some(Self {
            bytes: b,
            kernel,
            support_radius: support_radius.as_f64(),
        })
    }

    /// The key's bytes (stored whole in every map file, so that a hash collision or a file
    /// for other inputs is detected).
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The kernel of the map.
    pub fn kernel(&self) -> KernelKind {
        self.kernel
    }

    /// The support radius (m) of the map's kernel.
    pub fn support_radius(&self) -> f64 {
        self.support_radius
    }

    /// The SHA-256 of the key in lowercase hex (64 characters): the cache's file name.
    pub fn digest_hex(&self) -> String {
        Sha256::digest(&self.bytes)
            .iter()
            .fold(String::with_capacity(64), |mut s, b| {
                let _ = write!(s, "{b:02x}");
                s
            })
    }

    #[cfg(test)]
    pub(crate) fn from_bytes_for_tests(bytes: Vec<u8>) -> Self {
        Self {
            bytes,
            kernel: KernelKind::Poly6,
            support_radius: 1.0,
        }
    }
}

/// A directory of volume-map files, as SPlisHSPlasH's cache folder: the map of a key is
/// `DIR/<sha256 of the key>.vmap` and holds the key whole (format in
/// [`VolumeMap::read_file`](super::VolumeMap::read_file)).
///
/// [`VolumeMapBoundary::with_cache`](super::VolumeMapBoundary::with_cache) loads a map
/// when its file exists and passes every check, and otherwise builds it and writes the file
/// (atomically: concurrent processes building the same map each write a complete file and
/// the last rename wins). A refused file (corrupt, truncated, foreign, other version) is not
/// an error of the build: the map is rebuilt, the file replaced, and the refusal reported in
/// [`VolumeMapBoundary::cache_warnings`](super::VolumeMapBoundary::cache_warnings) for the
/// caller to log. Nothing is ever deleted; clear the directory to reclaim space.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VolumeMapCache {
    dir: PathBuf,
}

impl VolumeMapCache {
    /// The cache in `dir`, created (with its parents) when missing.
    ///
    /// Errors: [`SolverError::MapFile`] with [`MapFileProblem::Io`] when the directory cannot
    /// be created.
    pub fn new(dir: impl Into<PathBuf>) -> Result<Self, SolverError> {
        let dir = dir.into();
        std::fs::create_dir_all(&dir).map_err(|e| SolverError::MapFile {
            path: dir.clone(),
            problem: MapFileProblem::Io {
                operation: "create directory",
                message: e.to_string(),
            },
        })?;
        Ok(Self { dir })
    }

    /// The cache directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file of the map of `key`.
    pub fn path(&self, key: &VolumeMapKey) -> PathBuf {
        self.dir.join(format!("{}.vmap", key.digest_hex()))
    }
}
