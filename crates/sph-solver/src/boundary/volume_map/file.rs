//! The volume-map file format: one [`VolumeMap`] with the full key it was built for.
//!
//! Layout (all integers little-endian):
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `b"SPHVMAP\x1a"` |
//! | 4 | format version ([`FORMAT_VERSION`]) |
//! | 8 | total file length (bytes) |
//! | 8 + k | key length `k`, the key ([`VolumeMapKey::as_bytes`]) |
//! | 8 + p | payload length `p`, the payload (grid, node models, statistics) |
//! | 32 | SHA-256 of every byte before it |
//!
//! A reader checks, in this order, the magic, the version, the length, the checksum, the key
//! and the payload's internal consistency, and returns a [`SolverError::MapFile`] naming the
//! path and the first [`MapFileProblem`] found; nothing is kept of a refused file. Writers
//! write a temporary file beside the target, `fsync` it and rename it over the target, so a
//! reader sees either the old file, the new file or none, also when two processes write the
//! same map at once (both write identical bytes; the last rename wins).

use atomic_write_file::AtomicWriteFile;
use std::fs;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use sha2::{Digest, Sha256};
use sph_core::{Real, SampledGrid, Vec3};

use super::key::{VolumeMapKey, FORMAT_VERSION};
use super::map::{CacheUse, NodeModel, Storage, VolumeMap, VolumeMapStats, DEEP, PLANE_BIT};
use super::quadrature::KernelTables;
use crate::error::MapFileProblem;
use crate::SolverError;

/// The magic bytes that open every volume-map file.
pub const MAGIC: [u8; 8] = *b"SPHVMAP\x1a";
/// Magic, version and total length.
const HEADER: usize = 8 + 4 + 8;
const CHECKSUM: usize = 32;

fn refuse(path: &Path, problem: MapFileProblem) -> SolverError {
    SolverError::MapFile {
        path: path.to_path_buf(),
        problem,
    }
}

fn io(path: &Path, operation: &'static str, e: std::io::Error) -> SolverError {
    refuse(
        path,
        MapFileProblem::Io {
            operation,
            message: e.to_string(),
        },
    )
}

/// Little-endian writer of the payload.
#[derive(Default)]
struct Out(Vec<u8>);

impl Out {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
}

/// Little-endian reader of the payload; every short read is [`MapFileProblem::Malformed`].
struct In<'a>(&'a [u8]);

const SHORT: MapFileProblem = MapFileProblem::Malformed("payload shorter than its contents");

impl<'a> In<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], MapFileProblem> {
        if self.0.len() < n {
            return Err(SHORT);
        }
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        Ok(a)
    }
    fn u8(&mut self) -> Result<u8, MapFileProblem> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, MapFileProblem> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self) -> Result<u64, MapFileProblem> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f64(&mut self) -> Result<f64, MapFileProblem> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn f32(&mut self) -> Result<f32, MapFileProblem> {
        Ok(f32::from_bits(self.u32()?))
    }
    /// A length prefix that the remaining bytes can hold at `size` bytes per element.
    fn len(&mut self, size: usize) -> Result<usize, MapFileProblem> {
        let n = self.u64()?;
        if n > (self.0.len() / size) as u64 {
            return Err(SHORT);
        }
        Ok(n as usize)
    }
}

const EMPTY: u8 = 0;
const NODE_PLANES: u8 = 1;
const TRILINEAR: u8 = 2;

fn encode<R: Real>(map: &VolumeMap<R>) -> Vec<u8> {
    let mut o = Out::default();
    for a in 0..3 {
        o.f64(map.origin[a]);
    }
    o.f64(map.cell);
    for d in map.dims {
        o.u64(d as u64);
    }
    o.u8(map.bounded as u8);
    let s = &map.stats;
    for v in [s.nodes, s.band_nodes, s.quadrature_nodes, s.stored_nodes] {
        o.u64(v as u64);
    }
    o.u64(s.build_time.as_nanos().min(u64::MAX as u128) as u64);
    match &map.storage {
        Storage::Empty => o.u8(EMPTY),
        Storage::NodePlanes {
            index,
            models,
            flat_cells,
        } => {
            o.u8(NODE_PLANES);
            o.u64(index.len() as u64);
            index.iter().for_each(|&v| o.u32(v));
            o.u64(models.len() as u64);
            for m in models {
                o.f32(m.phi);
                m.n.iter()
                    .chain(&[m.c])
                    .chain(&m.g)
                    .chain(&m.hess)
                    .for_each(|&v| o.f32(v));
            }
            o.u64(flat_cells.len() as u64);
            flat_cells.iter().for_each(|&v| o.u64(v));
        }
        Storage::Trilinear(grid) => {
            o.u8(TRILINEAR);
            let origin = grid.origin();
            for a in 0..3 {
                o.f64(origin[a]);
            }
            o.f64(grid.cell_size());
            for d in grid.dims() {
                o.u64(d as u64);
            }
            o.u64(grid.values().len() as u64);
            // `as_f64` is exact for `f32` and `f64`.
            grid.values().iter().for_each(|v| o.f64(v.as_f64()));
        }
    }
    o.0
}

fn decode<R: Real>(
    payload: &[u8],
    tables: Arc<KernelTables>,
) -> Result<VolumeMap<R>, MapFileProblem> {
    let mut r = In(payload);
    let origin = Vec3::new(r.f64()?, r.f64()?, r.f64()?);
    let cell = r.f64()?;
    let mut dims = [0usize; 3];
    for d in &mut dims {
        *d = usize::try_from(r.u64()?).map_err(|_| MapFileProblem::Malformed("grid size"))?;
    }
    let bounded = r.u8()? != 0;
    let mut counts = [0usize; 4];
    for c in &mut counts {
        *c = r.u64()? as usize;
    }
    let build_time = Duration::from_nanos(r.u64()?);
    let nodes = dims
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or(MapFileProblem::Malformed("grid size"))?;
    let storage = match r.u8()? {
        EMPTY => Storage::Empty,
        NODE_PLANES => {
            let n = r.len(4)?;
            let index: Vec<u32> = (0..n).map(|_| r.u32()).collect::<Result<_, _>>()?;
            let n = r.len(14 * 4)?;
            let models: Vec<NodeModel> = (0..n)
                .map(|_| {
                    let mut v = [0f32; 14];
                    for x in &mut v {
                        *x = r.f32()?;
                    }
                    Ok(NodeModel {
                        phi: v[0],
                        n: [v[1], v[2], v[3]],
                        c: v[4],
                        g: [v[5], v[6], v[7]],
                        hess: [v[8], v[9], v[10], v[11], v[12], v[13]],
                    })
                })
                .collect::<Result<_, MapFileProblem>>()?;
            let n = r.len(8)?;
            let flat_cells: Vec<u64> = (0..n).map(|_| r.u64()).collect::<Result<_, _>>()?;
            if index.len() != nodes || dims.iter().any(|&d| d < 2) {
                return Err(MapFileProblem::Malformed(
                    "node index does not match the grid",
                ));
            }
            let cells = (dims[0] - 1) * (dims[1] - 1) * (dims[2] - 1);
            if flat_cells.len() != cells.div_ceil(64) {
                return Err(MapFileProblem::Malformed("cell bits do not match the grid"));
            }
            let bad = |&v: &u32| v < DEEP && (v & !PLANE_BIT) as usize >= models.len();
            if index.iter().any(bad) {
                return Err(MapFileProblem::Malformed(
                    "node index points past the models",
                ));
            }
            Storage::NodePlanes {
                index,
                models,
                flat_cells,
            }
        }
        TRILINEAR => {
            let o = Vec3::new(r.f64()?, r.f64()?, r.f64()?);
            let c = r.f64()?;
            let mut d = [0usize; 3];
            for x in &mut d {
                *x = r.u64()? as usize;
            }
            let n = r.len(8)?;
            let values: Vec<R> = (0..n)
                .map(|_| r.f64().map(R::of_f64))
                .collect::<Result<_, _>>()?;
            Storage::Trilinear(
                SampledGrid::from_values(o, c, d, values)
                    .map_err(|_| MapFileProblem::Malformed("correction grid"))?,
            )
        }
        _ => return Err(MapFileProblem::Malformed("unknown storage scheme")),
    };
    if !r.0.is_empty() {
        return Err(MapFileProblem::Malformed("bytes after the map"));
    }
    if !(cell.is_finite() && cell > 0.0) || (0..3).any(|a| !origin[a].is_finite()) {
        return Err(MapFileProblem::Malformed("grid origin or spacing"));
    }
    Ok(VolumeMap {
        tables,
        origin,
        cell,
        dims,
        bounded,
        storage,
        stats: VolumeMapStats {
            dims,
            nodes: counts[0],
            band_nodes: counts[1],
            quadrature_nodes: counts[2],
            stored_nodes: counts[3],
            build_time,
            ..VolumeMapStats::default()
        },
    })
}

/// The whole file for `map` built for `key`.
fn file_bytes<R: Real>(map: &VolumeMap<R>, key: &VolumeMapKey) -> Vec<u8> {
    let payload = encode(map);
    let key = key.as_bytes();
    let total = HEADER + 8 + key.len() + 8 + payload.len() + CHECKSUM;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(total as u64).to_le_bytes());
    out.extend_from_slice(&(key.len() as u64).to_le_bytes());
    out.extend_from_slice(key);
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&payload);
    let sum = Sha256::digest(&out);
    out.extend_from_slice(&sum);
    debug_assert_eq!(out.len(), total);
    out
}

/// Checks a whole file's bytes against `key` and returns its payload.
fn verified_payload<'a>(bytes: &'a [u8], key: &VolumeMapKey) -> Result<&'a [u8], MapFileProblem> {
    let found = bytes.len() as u64;
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        // A prefix of the magic is an interrupted write, anything else a foreign file.
        return Err(if !bytes.is_empty() && MAGIC.starts_with(bytes) {
            MapFileProblem::Truncated {
                expected: HEADER as u64,
                found,
            }
        } else {
            MapFileProblem::BadMagic
        });
    }
    if bytes.len() < HEADER {
        return Err(MapFileProblem::Truncated {
            expected: HEADER as u64,
            found,
        });
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(MapFileProblem::UnsupportedVersion {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let expected = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    if found < expected {
        return Err(MapFileProblem::Truncated { expected, found });
    }
    if found > expected {
        return Err(MapFileProblem::TrailingBytes { expected, found });
    }
    if bytes.len() < HEADER + 16 + CHECKSUM {
        return Err(MapFileProblem::Malformed("shorter than an empty map file"));
    }
    let (body, sum) = bytes.split_at(bytes.len() - CHECKSUM);
    if Sha256::digest(body).as_slice() != sum {
        return Err(MapFileProblem::ChecksumMismatch);
    }
    let mut r = In(&body[HEADER..]);
    let k = r.len(1)?;
    let stored_key = r.take(k)?;
    let p = r.len(1)?;
    let payload = r.take(p)?;
    if !r.0.is_empty() {
        return Err(MapFileProblem::Malformed("bytes after the payload"));
    }
    if stored_key != key.as_bytes() {
        return Err(MapFileProblem::ForeignKey);
    }
    Ok(payload)
}

/// Reads the map of `key` from `path` with the kernel tables `tables` (those of the key's
/// kernel and support radius).
pub(crate) fn read_map<R: Real>(
    path: &Path,
    key: &VolumeMapKey,
    tables: Arc<KernelTables>,
) -> Result<VolumeMap<R>, SolverError> {
    let bytes = fs::read(path).map_err(|e| io(path, "read", e))?;
    let payload = verified_payload(&bytes, key).map_err(|p| refuse(path, p))?;
    decode(payload, tables).map_err(|p| refuse(path, p))
}

/// Writes the map of `key` to `path` atomically (temporary file in the same directory,
/// `fsync`, rename; then a best-effort `fsync` of the directory).
pub(crate) fn write_map<R: Real>(
    path: &Path,
    map: &VolumeMap<R>,
    key: &VolumeMapKey,
) -> Result<(), SolverError> {
    let bytes = file_bytes(map, key);
    let mut f = AtomicWriteFile::open(path).map_err(|e| io(path, "create", e))?;
    f.write_all(&bytes).map_err(|e| io(path, "write", e))?;
    f.commit().map_err(|e| io(path, "commit", e))
}

impl<R: Real> VolumeMap<R> {
    /// Writes this map, built for `key`, to `path`, atomically (a temporary file beside
    /// `path`, `fsync`, rename): a reader never sees a partial file.
    ///
    /// Errors: [`SolverError::MapFile`] with [`MapFileProblem::Io`](crate::MapFileProblem::Io).
    pub fn write_file(&self, path: &Path, key: &VolumeMapKey) -> Result<(), SolverError> {
        write_map(path, self, key)
    }

    /// Reads the map of `key` (whose solid must be the one passed to [`VolumeMap::sample`])
    /// from `path`, written by [`VolumeMap::write_file`].
    ///
    /// File layout (integers little-endian): 8 bytes [`MAGIC`], 4 bytes [`FORMAT_VERSION`],
    /// 8 bytes total file length, the key (8-byte length, bytes: [`VolumeMapKey::as_bytes`]),
    /// the payload (8-byte length, bytes: grid, node models, statistics), and the SHA-256 of
    /// all bytes before it. The reader checks, in this order, magic, version, length,
    /// checksum, key and the payload's consistency, and refuses the file at the first
    /// failure, loading nothing of it.
    ///
    /// Errors: [`SolverError::MapFile`] naming `path` and the
    /// [`MapFileProblem`](crate::MapFileProblem): `Io`, `BadMagic`,
    /// `UnsupportedVersion`, `Truncated`, `TrailingBytes`, `ChecksumMismatch`, `ForeignKey`
    /// (a map of other inputs), `Malformed`; [`SolverError::Kernel`] for a key whose kernel
    /// cannot be built.
    pub fn read_file(path: &Path, key: &VolumeMapKey) -> Result<Self, SolverError> {
        let kernel = key.kernel().build(key.support_radius())?;
        let tables = Arc::new(KernelTables::new(&kernel));
        Self::read_with_tables(path, key, tables)
    }

    pub(crate) fn read_with_tables(
        path: &Path,
        key: &VolumeMapKey,
        tables: Arc<KernelTables>,
    ) -> Result<Self, SolverError> {
        let start = Instant::now();
        let mut map = read_map(path, key, tables)?;
        map.stats.load_time = start.elapsed();
        map.stats.cache = CacheUse::Hit;
        Ok(map)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magic_prefix_is_truncation_other_bytes_are_foreign() {
        let key = VolumeMapKey::from_bytes_for_tests(b"k".to_vec());
        let p = verified_payload(b"SPHV", &key).unwrap_err();
        assert!(matches!(p, MapFileProblem::Truncated { .. }), "{p:?}");
        let p = verified_payload(b"PK\x03\x04 zip file", &key).unwrap_err();
        assert_eq!(p, MapFileProblem::BadMagic);
        let p = verified_payload(b"", &key).unwrap_err();
        assert_eq!(p, MapFileProblem::BadMagic);
    }
}
